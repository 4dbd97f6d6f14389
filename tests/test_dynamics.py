"""One dynamics settings object (rp.Dynamics) for every propagating function: the same
bits as the keywords it replaces, a clear error when both are given, and the deprecated
``method=`` of propagate/monte_carlo."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp


@pytest.fixture
def setup(paper_state, paper_craft, benchmark_atmosphere):
    return paper_state, paper_craft, benchmark_atmosphere


def test_dynamics_gives_the_bits_of_the_keywords(setup):
    state, craft, model = setup
    dyn = rp.Dynamics(zonal_degree=4, floor_altitude=110e3, integrator="rk8", step=120.0)
    a = rp.propagate(state, craft, model, 86400.0, dynamics=dyn)
    b = rp.propagate(
        state,
        craft,
        model,
        86400.0,
        dynamics=rp.Dynamics(zonal_degree=4, floor_altitude=110e3, integrator="rk8", step=120.0),
    )
    np.testing.assert_array_equal(a.positions, b.positions)
    mc = rp.monte_carlo(state, craft, model, 86400.0, n=8, dynamics=dyn, progress=False)
    mk = rp.monte_carlo(
        state,
        craft,
        model,
        86400.0,
        n=8,
        dynamics=rp.Dynamics(zonal_degree=4, floor_altitude=110e3, integrator="rk8", step=120.0),
        progress=False,
    )
    np.testing.assert_array_equal(mc.positions, mk.positions)
    c1 = rp.ccsp(state, craft, model, 86400.0, dynamics=rp.Dynamics(zonal_degree=4))
    c2 = rp.ccsp(
        state,
        craft,
        model,
        86400.0,
        dynamics=rp.Dynamics(zonal_degree=4),
    )
    np.testing.assert_array_equal(c1.covariance, c2.covariance)


def test_dynamics_and_keywords_together_is_an_error(setup):
    state, craft, model = setup
    with (
        pytest.warns(DeprecationWarning, match=r"propagate\(zonal_degree=\) is deprecated"),
        pytest.raises(TypeError, match=r"propagate\(\) got dynamics= and zonal_degree="),
    ):
        rp.propagate(state, craft, model, 3600.0, dynamics=rp.Dynamics(), zonal_degree=3)
    with pytest.raises(TypeError, match=r"dynamics must be a rhoprop\.Dynamics"):
        rp.ccsp(state, craft, model, 3600.0, dynamics={"zonal_degree": 3})
    with pytest.raises(ValueError, match="integrator must be one of"):
        rp.Dynamics(integrator="euler")
    with pytest.raises(ValueError, match="zonal_degree = 9 is invalid"):
        rp.Dynamics(zonal_degree=9)
    with pytest.raises(ValueError, match="the CCSP integrates with RK8"):
        rp.ccsp(state, craft, model, 3600.0, dynamics=rp.Dynamics(integrator="rk4"))


def test_method_of_propagate_is_deprecated_for_integrator(setup):
    state, craft, model = setup
    with pytest.warns(DeprecationWarning, match=r"integrator="):
        old = rp.propagate(state, craft, model, 3600.0, method="rk8")
    new = rp.propagate(
        state,
        craft,
        model,
        3600.0,
        dynamics=rp.Dynamics(integrator="rk8"),
    )
    np.testing.assert_array_equal(old.positions, new.positions)
    with (
        pytest.warns(DeprecationWarning),
        pytest.raises(TypeError, match=r"both method= and integrator="),
    ):
        rp.propagate(state, craft, model, 3600.0, method="rk8", integrator="rk4")


def test_errors_has_one_spelling(tmp_path):
    # "record" everywhere (the run goes on and records each failure); load's and screen's
    # old "skip" still works with a warning.
    from test_catalog import SAMPLE

    bad = tmp_path / "bad.tle"
    bad.write_text(SAMPLE.read_text() + "1 garbage\n2 garbage\n")
    cat = rp.catalog.load(bad, errors="record")
    assert cat.skipped and len(cat) == len(rp.catalog.load(SAMPLE))
    with pytest.warns(DeprecationWarning, match=r'errors="record"'):
        old = rp.catalog.load(bad, errors="skip")
    assert len(old) == len(cat)
    with pytest.raises(ValueError, match="errors must be 'raise' or 'record'"):
        rp.catalog.load(bad, errors="ignore")


def test_progress_is_a_bool_or_a_callable_everywhere():
    from test_catalog import END, SAMPLE

    seen = []
    rp.catalog.propagate_catalog(
        rp.catalog.load(SAMPLE),
        rp.scenarios.benchmark_exponential(0.2),
        END,
        output_step=1800.0,
        execution=rp.Execution(progress=seen.append),
    )
    assert seen and seen[-1] == len(rp.catalog.load(SAMPLE))


def test_catalog_runs_honour_the_integration_settings():
    # propagate_catalog once read only the floor and zonal degree of a Dynamics: its
    # integrator and step were silently dropped. The step is now every object's fixed
    # step: the object-default step given explicitly is the default run bit for bit, and a
    # different step changes the result (each object's CCSP is the ccsp() of that step).
    from test_catalog import END, SAMPLE

    from rhoprop import catalog
    from rhoprop.catalog.objects import catalog_step, update_schedule

    cat = catalog.load(SAMPLE)
    model = rp.scenarios.benchmark_exponential(0.2)

    def run(**kw):
        return catalog.propagate_catalog(
            cat,
            model,
            END,
            output_step=1800.0,
            initial=rp.catalog.Initial(covariance=None),
            execution=rp.Execution(progress=False),
            **kw,
        )

    default = run()
    steps = {catalog_step(o.state) for o in cat}
    assert steps == {180.0}  # every object of the sample is in LEO
    same = run(dynamics=rp.Dynamics(zonal_degree=4, integrator="rk8", step=180.0))
    np.testing.assert_array_equal(same.covariance, default.covariance)
    fine = run(dynamics=rp.Dynamics(zonal_degree=4, step=60.0))
    assert not np.array_equal(fine.mean, default.mean)
    obj = cat[1]
    offsets = rp.time.to_seconds(fine.epochs, obj.state.epoch)
    updates, outputs = update_schedule(obj.state, offsets, 3600.0)
    alone = rp.ccsp(
        obj.state,
        rp.Spacecraft(1.0, obj.drag_parameter),
        model,
        update_times=updates,
        output_times=outputs,
        drag_sigma=0.15,  # "auto" without a fit
        dynamics=rp.Dynamics(zonal_degree=4, step=60.0),
    )
    at = np.searchsorted(alone.times, offsets)
    np.testing.assert_array_equal(fine.mean[1], alone.mean[at])
    # 60-s steps against 180-s ones: far more than the rounding, still under a metre.
    moved = np.abs(fine.mean[:, :, :3] - default.mean[:, :, :3]).max()
    assert 1e-4 < moved < 1.0, moved
    # The Monte Carlo takes the integrator too (RK4 at 10 s against RK8 at 180 s: the
    # same orbit within metres over 6 h, not the same bits).
    mc = dict(method=rp.MonteCarlo(n=8, seed=1))
    rk8 = run(**mc)
    rk4 = run(**mc, dynamics=rp.Dynamics(zonal_degree=4, integrator="rk4", step=10.0))
    assert not np.array_equal(rk4.mean, rk8.mean)
    np.testing.assert_allclose(rk4.mean[:, :, :3], rk8.mean[:, :, :3], rtol=0, atol=5.0)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        ("catalog_dop853", r"propagate_catalog\(\) integrates with rk8, not .*'dop853'"),
        ("catalog_rtol", r"propagate_catalog\(\) integrates with a fixed step .*rtol"),
        ("catalog_mc_dop853", r"integrates with rk8 or rk4 or abm, not"),
        ("reentry_rtol", r"reentry\(\) integrates with a fixed step"),
        ("monte_carlo_rtol", r"monte_carlo\(\) integrates with a fixed step"),
        ("ccsp_rtol", r"ccsp\(\) integrates with a fixed step"),
        ("screen_all_rk4_pc", r"screen_all\(\)'s Pc stage integrates with rk8"),
    ],
)
def test_a_setting_a_function_cannot_use_is_refused(setup, call, message):
    from test_catalog import END, SAMPLE

    from rhoprop import catalog
    from rhoprop.conjunction import screen_all

    state, craft, model = setup
    cat = catalog.load(SAMPLE)
    bench = rp.scenarios.benchmark_exponential(0.2)
    calls = {
        "catalog_dop853": lambda: catalog.propagate_catalog(
            cat, bench, END, dynamics=rp.Dynamics(zonal_degree=4, integrator="dop853")
        ),
        "catalog_rtol": lambda: catalog.propagate_catalog(
            cat, bench, END, dynamics=rp.Dynamics(zonal_degree=4, rtol=1e-9)
        ),
        "catalog_mc_dop853": lambda: catalog.propagate_catalog(
            cat, bench, END, method=rp.MonteCarlo(n=100), dynamics=rp.Dynamics(integrator="dop853")
        ),
        "reentry_rtol": lambda: catalog.reentry(cat, bench, dynamics=rp.Dynamics(rtol=1e-9)),
        "monte_carlo_rtol": lambda: rp.monte_carlo(
            state, craft, model, 3600.0, n=4, dynamics=rp.Dynamics(rtol=1e-9), progress=False
        ),
        "ccsp_rtol": lambda: rp.ccsp(state, craft, model, 3600.0, dynamics=rp.Dynamics(rtol=1e-9)),
        "screen_all_rk4_pc": lambda: screen_all(
            cat,
            bench,
            start="2002-09-07T00:00",
            end=END,
            distance=5e3,
            dynamics=rp.Dynamics(zonal_degree=4, integrator="rk4"),
            execution=rp.Execution(progress=False),
        ),
    }
    with pytest.raises(ValueError, match=message):
        calls[call]()


def test_screens_and_closest_approach_propagate_with_the_integration_settings(monkeypatch):
    # The tracks of screen and screen_all and closest_approach's refinement go through
    # rp.propagate with the Dynamics' integrator, step and rtol (they used to be dropped).
    # A recorder around the real propagate (the physics still runs) sees what each call
    # was given; the encounter is still found where the brute force puts it.
    from test_screening import CRAFT, MODEL, T, brute_force_tca, encounter

    from rhoprop.conjunction import kernel, screen, screen_all

    seen = []
    real = kernel.propagate  # every track and refinement of the searches goes through it

    def recording(*args, **kwargs):
        seen.append(kwargs["dynamics"].integration)
        return real(*args, **kwargs)

    monkeypatch.setattr(kernel, "propagate", recording)
    s1, s2 = encounter()
    window = dict(start=rp.time.add_seconds(T, -3 * 3600.0), end=rp.time.add_seconds(T, 3 * 3600.0))
    dyn = rp.Dynamics(integrator="rk8", step=20.0)
    res = screen(
        (s1, CRAFT, "a"),
        [(s2, CRAFT, "b")],
        MODEL,
        distance=1e3,
        execution=rp.Execution(progress=False),
        dynamics=dyn,
        **window,
    )
    assert seen and set(seen) == {("rk8", 20.0, None)}
    ref_tca, ref_miss = brute_force_tca(s1, s2, T)
    (event,) = res.events
    assert abs((event.tca - ref_tca) / np.timedelta64(1, "ns")) * 1e-9 < 1e-3
    assert abs(event.miss_distance - ref_miss) < 1.0
    seen.clear()
    screen_all(
        [(s1, CRAFT, "a"), (s2, CRAFT, "b")],
        MODEL,
        distance=1e3,
        pc=False,
        execution=rp.Execution(progress=False),
        dynamics=rp.Dynamics(zonal_degree=2, rtol=1e-8),
        **window,
    )
    assert seen and set(seen) == {(None, None, 1e-8)}
    seen.clear()
    ta = rp.propagate(s1, CRAFT, MODEL, 6 * 3600.0, output_step=600.0)
    tb = rp.propagate(s2, CRAFT, MODEL, 6 * 3600.0, output_step=600.0)
    rp.conjunction.closest_approach(
        ta, tb, model=MODEL, spacecraft=CRAFT, dynamics=rp.Dynamics(rtol=1e-11)
    )
    assert seen and set(seen) == {(None, None, 1e-11)}


def test_closest_approach_takes_its_dynamics_whole_and_the_loose_keywords_warn():
    # floor_altitude= and zonal_degree= beside dynamics= were a second path to the same
    # settings; they are folded into dynamics with a DeprecationWarning, same numbers.
    from test_screening import CRAFT, MODEL, encounter

    from rhoprop.conjunction import closest_approach

    s1, s2 = encounter()
    dur = 2 * 3600.0
    tr1 = rp.propagate(
        s1,
        CRAFT,
        MODEL,
        dur,
        output_step=60.0,
        dynamics=rp.Dynamics(zonal_degree=4),
    )
    tr2 = rp.propagate(
        s2,
        CRAFT,
        MODEL,
        dur,
        output_step=60.0,
        dynamics=rp.Dynamics(zonal_degree=4),
    )
    kw = dict(model=MODEL, spacecraft=CRAFT)
    new = closest_approach(tr1, tr2, dynamics=rp.Dynamics(zonal_degree=4), **kw)
    with pytest.warns(DeprecationWarning, match=r"closest_approach\(zonal_degree=\)"):
        old = closest_approach(tr1, tr2, zonal_degree=4, **kw)
    assert [e.tca for e in old] == [e.tca for e in new] and len(new) >= 1
    assert [e.miss_distance for e in old] == [e.miss_distance for e in new]
    with pytest.raises(TypeError, match="unexpected keyword argument 'zonal'"):
        closest_approach(tr1, tr2, zonal=4, **kw)
    with pytest.raises(TypeError, match="got dynamics= and zonal_degree="):
        with pytest.warns(DeprecationWarning):
            closest_approach(tr1, tr2, dynamics=rp.Dynamics(), zonal_degree=4, **kw)
