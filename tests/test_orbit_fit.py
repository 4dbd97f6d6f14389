"""``rp.fit_positions``: it recovers the state and Cr that made a set of positions, starts
from positions alone, and refuses what it cannot fit. (On real precise orbits:
``tests/test_precise_srp.py``.)"""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp

MODEL = rp.scenarios.benchmark_exponential(0.0)
EPOCH = np.datetime64("2024-06-16T00:00", "ns")


def _positions(state, craft, hours, step, dynamics):
    run = rp.propagate(state, craft, MODEL, hours * 3600.0, output_step=step, dynamics=dynamics)
    return run.epochs, run.positions


def test_a_meo_orbit_and_its_cr_are_recovered_from_its_positions():
    # A GPS-like orbit pushed by light (Cr 1.3, A/m 0.02), every 15 min for a day; the fit
    # starts from the positions alone (its first velocity differenced) and Cr 1.5.
    truth = rp.OrbitState(EPOCH, [26_560e3, 0.0, 0.0], [0.0, 1_937.0, 3_354.0])
    craft = rp.Spacecraft(1.0, 0.02, cr=1.3)
    epochs, r = _positions(truth, craft, 24, 900.0, rp.Dynamics.precise())
    fit = rp.fit_positions(epochs, r, rp.Spacecraft(1.0, 0.02), MODEL, fit_cr=True)
    assert fit.spacecraft.cr == pytest.approx(1.3, abs=1e-6)
    np.testing.assert_allclose(fit.state.position, truth.position, atol=1e-3)
    np.testing.assert_allclose(fit.state.velocity, truth.velocity, atol=1e-6)
    assert fit.rms < 1e-3 and fit.residuals.shape == r.shape
    assert fit.covariance.shape == (7, 7) and fit.state.epoch == EPOCH
    # Without Cr the same positions leave residuals of tens of metres: the light's push is
    # not a state error.
    bare = rp.fit_positions(epochs, r, rp.Spacecraft(1.0, 0.02), MODEL)
    assert bare.spacecraft.cr is None and bare.covariance.shape == (6, 6)
    assert 1.0 < bare.rms < 1000.0, bare.rms


def test_a_noisy_leo_arc_fits_to_its_noise():
    # 400 km, an hour and a half every 30 s with 1-m noise, through drag: the fit's RMS is
    # the noise's (sqrt(3) m per position), the state as its covariance says.
    truth = rp.OrbitState(EPOCH, [6_778e3, 0.0, 0.0], [0.0, 4_753.0, 6_018.0], frame="TEME")
    craft = rp.Spacecraft(2.2, 0.01)
    dyn = rp.Dynamics(zonal_degree=4)
    epochs, r = _positions(truth, craft, 1.5, 30.0, dyn)
    noisy = r + np.random.default_rng(3).normal(0.0, 1.0, r.shape)
    fit = rp.fit_positions(epochs, noisy, craft, MODEL, frame="TEME", dynamics=dyn)
    assert fit.state.frame == "TEME"
    # 181 positions, 6 parameters: RMS within 10 % of sqrt(3) m (its spread: 3 %).
    assert abs(fit.rms - np.sqrt(3.0)) < 0.1 * np.sqrt(3.0), fit.rms
    # The position error as the fit's covariance says (measured 0.28 m against sigmas of
    # 0.09-0.17 m): inside the chi-square(3) 99.9 % bound, 16.27.
    err = fit.state.position - truth.position
    assert err @ np.linalg.solve(fit.covariance[:3, :3], err) < 16.27
    assert np.linalg.norm(err) < 1.0


def test_bad_input_is_refused():
    epochs = EPOCH + np.arange(6) * np.timedelta64(60, "s")
    r = np.tile([7e6, 0.0, 0.0], (6, 1))
    craft = rp.Spacecraft(2.2, 0.01)
    with pytest.raises(ValueError, match="at least 5 positions"):
        rp.fit_positions(epochs[:4], r[:4], craft, MODEL)
    with pytest.raises(ValueError, match=r"positions must be \(6, 3\)"):
        rp.fit_positions(epochs, r[:, :2], craft, MODEL)
    with pytest.raises(ValueError, match="increasing"):
        rp.fit_positions(epochs[::-1], r, craft, MODEL)
    with pytest.raises(ValueError, match="finite"):
        rp.fit_positions(epochs, np.where(r == 0, np.nan, r), craft, MODEL)
    with pytest.raises(TypeError, match="spacecraft must be a Spacecraft"):
        rp.fit_positions(epochs, r, 2.2, MODEL)
    with pytest.raises(TypeError, match=r"dynamics must be a rhoprop\.Dynamics"):
        rp.fit_positions(epochs, r, craft, MODEL, dynamics="precise")


def test_cr_the_positions_do_not_support_ends_on_its_bound_with_a_warning():
    # Positions without radiation pressure, 2 m of noise: Cr goes to 0, where it is held
    # (the state's step taken with it there), the fit as good as the one without Cr
    # (measured 3.1366069 m both), and a warning says so.
    truth = rp.OrbitState(EPOCH, [26_560e3, 0.0, 0.0], [0.0, 1_937.0, 3_354.0])
    craft = rp.Spacecraft(1.0, 0.02)
    epochs, r = _positions(truth, craft, 24, 900.0, rp.Dynamics.precise())
    r = r + np.random.default_rng(1).normal(0.0, 2.0, r.shape)
    with pytest.warns(RuntimeWarning, match="Cr ended at its bound 0"):
        fit = rp.fit_positions(epochs, r, craft, MODEL, fit_cr=True)
    assert fit.spacecraft.cr == 0.0
    bare = rp.fit_positions(epochs, r, craft, MODEL)
    assert fit.rms <= bare.rms * (1 + 1e-6), (fit.rms, bare.rms)
