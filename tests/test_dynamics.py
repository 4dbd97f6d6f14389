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
        integrator="rk8",
        step=120.0,
        zonal_degree=4,
        floor_altitude=110e3,
    )
    np.testing.assert_array_equal(a.positions, b.positions)
    mc = rp.monte_carlo(state, craft, model, 86400.0, n=8, dynamics=dyn, progress=False)
    mk = rp.monte_carlo(
        state,
        craft,
        model,
        86400.0,
        n=8,
        integrator="rk8",
        step=120.0,
        zonal_degree=4,
        floor_altitude=110e3,
        progress=False,
    )
    np.testing.assert_array_equal(mc.positions, mk.positions)
    c1 = rp.ccsp(state, craft, model, 86400.0, dynamics=rp.Dynamics(zonal_degree=4))
    c2 = rp.ccsp(state, craft, model, 86400.0, zonal_degree=4)
    np.testing.assert_array_equal(c1.covariance, c2.covariance)


def test_dynamics_and_keywords_together_is_an_error(setup):
    state, craft, model = setup
    with pytest.raises(TypeError, match=r"propagate\(\) got dynamics= and zonal_degree="):
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
    new = rp.propagate(state, craft, model, 3600.0, integrator="rk8")
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
        progress=seen.append,
    )
    assert seen and seen[-1] == len(rp.catalog.load(SAMPLE))
