"""The uncertainty methods as objects (rp.MonteCarlo, rp.Ccsp): one run equals the
function it stands for bit for bit, many runs equal each run alone, settings are checked
when the object is made, the old strings and keywords still work with a warning and give
the same numbers, and a setting a catalog cannot use is refused."""

from __future__ import annotations

import dataclasses
import importlib
import warnings
from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import catalog
from rhoprop.propagation import Request

PAPER = rp.scenarios.paper_state()
CRAFT = rp.scenarios.paper_spacecraft()
MODEL = rp.scenarios.benchmark_exponential(0.2)
SAMPLE = Path(__file__).parent / "data" / "sample.tle"
END = "2002-09-07T06:00:00"


def test_a_monte_carlo_object_runs_what_monte_carlo_runs():
    method = rp.MonteCarlo(n=16, seed=5, kappa=rp.kappa.GaussMarkov(1080.0), progress=False)
    got = method.run(PAPER, CRAFT, MODEL, 7200.0)
    want = rp.monte_carlo(
        PAPER,
        CRAFT,
        MODEL,
        7200.0,
        n=16,
        seed=5,
        kappa=rp.kappa.GaussMarkov(1080.0),
        progress=False,
    )
    np.testing.assert_array_equal(got.positions, want.positions)
    assert isinstance(method, rp.propagation.UncertaintyPropagation)


def test_a_ccsp_object_runs_what_ccsp_runs():
    method = rp.Ccsp(update_interval=1800.0, drag_sigma=0.1)
    got = method.run(PAPER, CRAFT, MODEL, 7200.0, dynamics=rp.Dynamics(zonal_degree=4))
    want = rp.ccsp(
        PAPER,
        CRAFT,
        MODEL,
        7200.0,
        update_interval=1800.0,
        drag_sigma=0.1,
        dynamics=rp.Dynamics(zonal_degree=4),
    )
    np.testing.assert_array_equal(got.covariance, want.covariance)
    assert isinstance(method, rp.propagation.UncertaintyPropagation)


def test_many_runs_equal_each_run_alone():
    other = rp.OrbitState(PAPER.epoch, PAPER.position * 1.01, PAPER.velocity / np.sqrt(1.01))
    requests = [Request(PAPER, CRAFT, 7200.0), Request(other, CRAFT, 5400.0)]
    ccsp = rp.Ccsp(update_interval=1800.0)
    for req, got in zip(requests, ccsp.run_many(requests, MODEL), strict=True):
        alone = ccsp.run(req.state, req.spacecraft, MODEL, req.duration)
        assert not isinstance(got, Exception)
        np.testing.assert_array_equal(got.covariance, alone.covariance)
    # Object i of a Monte Carlo runs with seed + i, as in a catalog.
    mc = rp.MonteCarlo(n=8, seed=2, output_step=None, progress=False)
    second = mc.run_many(requests, MODEL)[1]
    alone = rp.MonteCarlo(n=8, seed=3, output_step=None, progress=False).run(
        other, CRAFT, MODEL, 5400.0
    )
    assert not isinstance(second, Exception)
    np.testing.assert_array_equal(second.positions, alone.positions)
    # A request that fails gives its error in its place, the others still run.
    bad = [Request(PAPER, CRAFT, -1.0), requests[0]]
    out = ccsp.run_many(bad, MODEL)
    assert isinstance(out[0], ValueError) and not isinstance(out[1], Exception)


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda: rp.MonteCarlo(n=1), ValueError, "n must be an integer >= 2"),
        (lambda: rp.MonteCarlo(seed=-1), ValueError, "seed"),
        (lambda: rp.MonteCarlo(kappa="gauss"), TypeError, "kappa must be a rhoprop.kappa"),
        (lambda: rp.MonteCarlo(perturbation="log"), ValueError, "perturbation must be"),
        (lambda: rp.MonteCarlo(drag_sigma=5.0), ValueError, "drag_sigma must be from 0 to 3"),
        (lambda: rp.MonteCarlo(threads=0), ValueError, "threads must be a positive"),
        (lambda: rp.MonteCarlo(output_step=-60.0), ValueError, "output_step"),
        (lambda: rp.Ccsp(update_interval=0.0), ValueError, "update_interval"),
        (lambda: rp.Ccsp(scaling=(3.0,)), ValueError, "scaling must be two numbers"),
        (
            lambda: rp.Ccsp(scaling=(3.0, 3.0), kappa=rp.kappa.GaussMarkov()),
            ValueError,
            "give kappa or scaling, not both",
        ),
        (lambda: rp.Ccsp(coordinates="polar"), ValueError, "coordinates"),
    ],
)
def test_settings_are_checked_when_the_method_is_made(make, error, match):
    with pytest.raises(error, match=match):
        make()


def test_the_old_strings_and_keywords_warn_and_give_the_same_numbers():
    models = {"a": MODEL, "b": rp.scenarios.benchmark_exponential(0.1)}
    new = rp.ensemble(
        PAPER, CRAFT, models, "a", duration=3600.0, method=rp.MonteCarlo(n=8, progress=False)
    )
    with pytest.warns(DeprecationWarning, match=r"ensemble\(n=, progress=\) is deprecated"):
        old = rp.ensemble(PAPER, CRAFT, models, "a", duration=3600.0, n=8, progress=False)
    np.testing.assert_array_equal(old.component_covariances, new.component_covariances)
    with pytest.warns(DeprecationWarning, match=r"ensemble\(method='ccsp'\) is deprecated"):
        old = rp.ensemble(PAPER, CRAFT, models, "a", duration=3600.0, method="ccsp")
    new = rp.ensemble(PAPER, CRAFT, models, "a", duration=3600.0, method=rp.Ccsp())
    np.testing.assert_array_equal(old.component_covariances, new.component_covariances)
    with pytest.raises(TypeError, match=r"update_interval is not a setting of rp\.MonteCarlo"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            rp.ensemble(PAPER, CRAFT, models, "a", duration=3600.0, update_interval=60.0)
    with pytest.raises(ValueError, match="unknown method 'sigma'"):
        rp.ensemble(PAPER, CRAFT, models, "a", method="sigma")
    with pytest.raises(TypeError, match=r"method must be rp\.MonteCarlo"):
        rp.ensemble(PAPER, CRAFT, models, "a", method=3)


def test_a_catalog_takes_its_method_whole():
    cat = catalog.load(SAMPLE)
    mc = rp.MonteCarlo(n=16, seed=3)
    new = catalog.propagate_catalog(
        cat,
        MODEL,
        END,
        method=mc,
        execution=rp.Execution(progress=False),
    )
    with pytest.warns(DeprecationWarning, match="propagate_catalog"):
        old = catalog.propagate_catalog(
            cat, MODEL, END, method="monte_carlo", n=16, seed=3, progress=False
        )
    np.testing.assert_array_equal(old.covariance, new.covariance)
    assert new.method == "monte_carlo"
    # The CCSP's kappa reaches every object now (it was dropped before: the filter ran
    # the default process whatever was given).
    plain = catalog.propagate_catalog(
        cat,
        MODEL,
        END,
        execution=rp.Execution(progress=False),
    )
    fast = catalog.propagate_catalog(
        cat,
        MODEL,
        END,
        method=rp.Ccsp(kappa=rp.kappa.GaussMarkov(1080.0)),
        execution=rp.Execution(progress=False),
    )
    assert plain.method == "ccsp" and not np.array_equal(plain.covariance, fast.covariance)


@pytest.mark.parametrize(
    ("method", "match"),
    [
        (rp.Ccsp(drag_sigma=0.1), r"does not use rp.Ccsp's drag_sigma"),
        (rp.Ccsp(scaling=(3.0, 3.0)), r"does not use rp.Ccsp's scaling"),
        (rp.MonteCarlo(output_step=60.0), r"does not use rp.MonteCarlo's output_step"),
        (rp.MonteCarlo(record_density=True), r"does not use rp.MonteCarlo's record_density"),
    ],
)
def test_a_catalog_refuses_a_method_setting_it_cannot_use(method, match):
    with pytest.raises(ValueError, match=match):
        catalog.propagate_catalog(
            catalog.load(SAMPLE),
            MODEL,
            END,
            method=method,
            execution=rp.Execution(progress=False),
        )


def test_the_functions_keywords_are_the_method_objects_fields():
    # monte_carlo(**settings) and ccsp(**settings) spell the object's fields loose: the
    # two lists cannot drift apart, and the defaults are the object's.
    for cls, name in ((rp.MonteCarlo, "montecarlo"), (rp.Ccsp, "ccsp")):
        module = importlib.import_module(f"rhoprop.propagation.{name}")
        assert set(module.SETTINGS) == {f.name for f in dataclasses.fields(cls)}
    default = rp.monte_carlo(PAPER, CRAFT, MODEL, 7200.0, n=4, progress=False)
    same = rp.MonteCarlo(n=4, progress=False).run(PAPER, CRAFT, MODEL, 7200.0)
    np.testing.assert_array_equal(default.positions, same.positions)
    assert len(default.times) == len(same.times) == 3  # output_step 3600 s, both
    with pytest.raises(TypeError, match="unexpected keyword argument 'members'"):
        rp.monte_carlo(PAPER, CRAFT, MODEL, 7200.0, members=4)
    with pytest.raises(TypeError, match="unexpected keyword argument 'seed'"):
        rp.ccsp(PAPER, CRAFT, MODEL, 7200.0, seed=4)


def test_loose_dynamics_keywords_warn_and_give_the_same_numbers():
    dyn = rp.Dynamics(zonal_degree=4, integrator="rk4", step=30.0)
    new = rp.monte_carlo(PAPER, CRAFT, MODEL, 3600.0, n=4, progress=False, dynamics=dyn)
    with pytest.warns(DeprecationWarning, match=r"monte_carlo\(zonal_degree=, integrator="):
        old = rp.monte_carlo(
            PAPER, CRAFT, MODEL, 3600.0, n=4, progress=False, zonal_degree=4,
            integrator="rk4", step=30.0,
        )  # fmt: skip
    np.testing.assert_array_equal(old.positions, new.positions)
    new = rp.ccsp(PAPER, CRAFT, MODEL, 3600.0, dynamics=rp.Dynamics(floor_altitude=100e3))
    with pytest.warns(DeprecationWarning, match=r"ccsp\(floor_altitude=\)"):
        old = rp.ccsp(PAPER, CRAFT, MODEL, 3600.0, floor_altitude=100e3)
    np.testing.assert_array_equal(old.covariance, new.covariance)
    with pytest.raises(TypeError, match="unexpected keyword argument 'rtol'"):
        rp.ccsp(PAPER, CRAFT, MODEL, 3600.0, rtol=1e-9)  # the filter never took it


def test_reentry_takes_its_monte_carlo_whole():
    state = rp.OrbitState("2002-09-07T00:00:00", [6378137.0 + 200e3, 0.0, 0.0], [0.0, 7784.0, 0.0])
    obj = catalog.CatalogObject("LOW 1", 1, state, 0.02, 1e-3, "test")
    air = rp.scenarios.benchmark_exponential(0.2)
    new = catalog.reentry(
        [obj], air, method=rp.MonteCarlo(n=8, seed=3), duration=10 * 86400.0, groups=2, fit=False
    )
    with pytest.warns(DeprecationWarning, match=r"reentry\(n=, seed=\) is deprecated"):
        old = catalog.reentry([obj], air, n=8, seed=3, duration=10 * 86400.0, groups=2, fit=False)
    np.testing.assert_array_equal(old.decay_times, new.decay_times)
    assert np.isfinite(new.decay_times).all()  # every member came down: a real check
    with pytest.raises(TypeError, match=r"method must be rp\.MonteCarlo"):
        catalog.reentry([obj], air, method=rp.Ccsp())
    with pytest.raises(ValueError, match=r"does not use rp\.MonteCarlo's drag_sigma"):
        catalog.reentry([obj], air, method=rp.MonteCarlo(drag_sigma=0.1))
