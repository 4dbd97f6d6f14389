"""Drag-coefficient debiasing recovers known density ratios."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp


def paper_teme() -> rp.OrbitState:
    """The paper's state labelled TEME, the axes the dynamics are written in (J2 about
    z), as the independent reference integrates it."""
    s = rp.scenarios.paper_state()
    return rp.OrbitState(s.epoch, s.position, s.velocity, "TEME")


def test_constant_ratio_is_recovered_exactly():
    state, craft = paper_teme(), rp.scenarios.paper_spacecraft()
    ref = rp.density.Exponential(3.725e-12, 400e3, 58.515e3)
    denser = rp.density.Exponential(1.3 * 3.725e-12, 400e3, 58.515e3)
    cd = rp.debias_drag_coefficient(state, craft, ref, denser)
    assert cd == pytest.approx(3.0912 / 1.3, rel=1e-12)


def test_altitude_dependent_ratio_is_the_mean_along_the_backward_orbit():
    # Different scale heights: the ratio varies with altitude; compare with the mean of the
    # ratio along an independent backward propagation (scipy, tests/reference.py).
    from scipy.integrate import solve_ivp

    from reference import exponential_rhs

    state, craft = paper_teme(), rp.scenarios.paper_spacecraft()
    ref = rp.density.Exponential(3.725e-12, 400e3, 58.515e3)
    other = rp.density.Exponential(3.725e-12, 400e3, 50e3)
    cd = rp.debias_drag_coefficient(state, craft, ref, other, window=8 * 3600.0)
    t = -np.arange(0.0, 8 * 3600.0 + 30.0, 60.0)
    sol = solve_ivp(
        exponential_rhs(3.725e-12, 400e3, 58.515e3, craft.drag_parameter),
        (0.0, t[-1]),
        state.state,
        method="DOP853",
        t_eval=t,
        rtol=1e-12,
        atol=1e-6,
    )
    h = np.linalg.norm(sol.y[:3].T, axis=1) - 6378137.0 - 400e3
    expect = 3.0912 * np.mean(np.exp(-h / 58.515e3) / np.exp(-h / 50e3))
    assert cd == pytest.approx(expect, rel=1e-6)
    assert cd != pytest.approx(3.0912, rel=1e-3)


def test_msis_00_vs_21_debias_is_plausible():
    # NRLMSISE-00 is ~20 % denser than NRLMSIS 2.1 around 400 km in Case I, so its Cd is
    # lower by about that much.
    state, craft = paper_teme(), rp.scenarios.paper_spacecraft()
    sw = rp.SpaceWeather()
    cd = rp.debias_drag_coefficient(
        state,
        craft,
        rp.density.Msis("2.1", space_weather=sw),
        rp.density.Msis("00", space_weather=sw),
    )
    assert 0.7 * 3.0912 < cd < 0.95 * 3.0912


def test_bad_window():
    state, craft = paper_teme(), rp.scenarios.paper_spacecraft()
    ref = rp.scenarios.benchmark_exponential()
    with pytest.raises(ValueError, match="window must be > 0"):
        rp.debias_drag_coefficient(state, craft, ref, ref, window=0.0)
