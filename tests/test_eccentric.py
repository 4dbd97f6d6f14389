"""Eccentric orbits in catalog runs: the initial covariance of a TLE-derived state keeps
the orbit's energy (element model), and the CCSP re-draws sigma points once per
revolution, at apogee, so that its covariance follows a Monte Carlo of the same initial
covariance (the independent reference: samples propagated one by one with DOP853)."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.catalog import CatalogObject, propagate_catalog
from rhoprop.catalog.covariance import element_covariance, tle_accuracy, tle_covariance
from rhoprop.constants import MU, R_EARTH
from rhoprop.frames import rtn_basis
from rhoprop.propagation.ccsp import update_schedule

EPOCH = np.datetime64("2023-11-14T00:00:00", "ns")


def kepler_state(a: float, e: float, true_anomaly: float, inc: float = 1.1) -> rp.OrbitState:
    """Inertial state (m, m/s) at ``true_anomaly`` (rad) of an orbit with perigee on x."""
    p = a * (1 - e * e)
    r = p / (1 + e * np.cos(true_anomaly))
    pos = r * np.array([np.cos(true_anomaly), np.sin(true_anomaly), 0.0])
    vel = np.sqrt(MU / p) * np.array([-np.sin(true_anomaly), e + np.cos(true_anomaly), 0.0])
    rot = np.array([[1, 0, 0], [0, np.cos(inc), -np.sin(inc)], [0, np.sin(inc), np.cos(inc)]])
    return rp.OrbitState(EPOCH, rot @ pos, rot @ vel)


def semi_major_axis_sigma(state: rp.OrbitState, cov: np.ndarray) -> float:
    """1-sigma of the semi-major axis (m) by the analytic gradient of vis-viva."""
    r, v = state.position, state.velocity
    rn = np.linalg.norm(r)
    a = 1 / (2 / rn - v @ v / MU)
    grad = a * a * np.concatenate([2 * r / rn**3, 2 * v / MU])
    return float(np.sqrt(grad @ cov @ grad))


@pytest.mark.parametrize("true_anomaly", [0.0, 0.4, 1.5, 2.8, np.pi, -2.0])
def test_element_covariance_keeps_the_regimes_drift(true_anomaly):
    # A Molniya orbit (12 h, e = 0.7, perigee 1,600 km) at six phases. The drift rate
    # (3 km/day, read as the orbit's mean along-track rate) fixes sigma_a = 2/3 drift / n:
    # the near-circular model with the local angular rate gave hundreds of km at perigee.
    a, e = 26_600e3, 0.7
    state = kepler_state(a, e, true_anomaly)
    acc = tle_accuracy(state)
    assert acc.regime == "eccentric"
    cov = tle_covariance(state)
    np.testing.assert_array_equal(cov, element_covariance(state, acc))
    n = np.sqrt(MU / a**3)
    drift_sigma_a = 2 / 3 * acc.drift_rate / n
    sigma_a = semi_major_axis_sigma(state, cov)
    # The drift takes at most half of the radial or along-track variance at epoch.
    assert sigma_a <= drift_sigma_a * (1 + 1e-3)
    if true_anomaly in (0.0, np.pi):
        assert sigma_a == pytest.approx(drift_sigma_a, rel=1e-3)
    # The regime's errors across the velocity (in the plane), along it and cross-track
    # (R, T, N on a circular orbit).
    along = state.velocity / np.linalg.norm(state.velocity)
    normal = np.cross(state.position, state.velocity)
    normal /= np.linalg.norm(normal)
    basis = np.array([np.cross(along, normal), along, normal])
    sig = np.sqrt(np.diag(basis @ cov[:3, :3] @ basis.T))
    np.testing.assert_allclose(sig, [acc.radial, acc.along_track, acc.cross_track], rtol=1e-6)
    sd = np.sqrt(np.diag(cov))
    assert np.linalg.eigvalsh(cov / np.outer(sd, sd)).min() > 1e-6


def test_near_circular_orbits_keep_the_clohessy_wiltshire_model():
    state = kepler_state(R_EARTH + 500e3, 0.001, 0.3)
    cov = tle_covariance(state)
    basis = rtn_basis(state.position, state.velocity)
    acc = tle_accuracy(state)
    sig = np.sqrt(np.diag(basis @ cov[:3, :3] @ basis.T))
    np.testing.assert_allclose(sig, [acc.radial, acc.along_track, acc.cross_track], rtol=1e-9)


def test_eccentric_catalog_run_follows_a_monte_carlo_of_its_initial_covariance():
    # A Molniya orbit with its epoch at perigee, 3 days (6 revolutions) through the
    # benchmark atmosphere (drag negligible at 1,600 km): the CCSP's along-track sigma at
    # the end against 300 samples of the initial covariance propagated one by one. The
    # sample standard deviation is good to 1/sqrt(2 x 300) = 4 %; 20 % allows for that
    # and the unscented transform's own error. Hourly re-drawing (the near-circular rule)
    # made it 3-10 times too large on such orbits and brought sigma points down.
    state = kepler_state(26_600e3, 0.7, 0.0)
    cov = tle_covariance(state)
    obj = CatalogObject("MOLNIYA-LIKE", 99001, state, 0.01, 0.0, "test", cov, "element model")
    atm = rp.scenarios.benchmark_exponential(0.2)
    end = EPOCH + np.timedelta64(3 * 86400, "s")
    res = propagate_catalog(
        [obj],
        atm,
        end,
        dynamics=rp.Dynamics(zonal_degree=4),
        execution=rp.Execution(progress=False),
    )
    assert list(res.status) == ["propagated"]
    mean = res.mean[0, -1]
    basis = rtn_basis(mean[:3], mean[3:])
    ccsp_sigma = np.sqrt(np.diag(basis @ res.covariance[0, -1, :3, :3] @ basis.T))

    rng = np.random.default_rng(7)
    chol = np.linalg.cholesky(cov)
    finals = []
    for _ in range(300):
        dx = chol @ rng.standard_normal(6)
        sample = rp.OrbitState(EPOCH, state.position + dx[:3], state.velocity + dx[3:])
        tr = rp.propagate(
            sample,
            rp.Spacecraft(1.0, 0.01),
            atm,
            3 * 86400.0,
            dynamics=rp.Dynamics(zonal_degree=4),
        )
        finals.append(tr.positions[-1])
    d = (np.array(finals) - np.mean(finals, axis=0)) @ basis.T
    mc_sigma = d.std(axis=0, ddof=1)
    np.testing.assert_allclose(ccsp_sigma[1], mc_sigma[1], rtol=0.2)
    np.testing.assert_allclose(ccsp_sigma[0], mc_sigma[0], rtol=0.2)


def test_covariances_between_updates_are_positive_definite():
    # A GTO-like orbit (600 x 39,000 km) from perigee, 5 days, Cd*A/m sigma 0.1: outputs
    # between updates are the moments of the points in flight, with a negative centre
    # weight; 1-4 a run had eigenvalues down to -1.2e-4 m^2 and failed a Cholesky
    # factorisation before they were lifted to positive definite.
    a = (2 * R_EARTH + 600e3 + 39_000e3) / 2
    state = kepler_state(a, (39_000e3 - 600e3) / (2 * a), 0.0)
    offsets = np.arange(3600.0, 5 * 86400.0 + 1.0, 3600.0)
    updates, outputs = update_schedule(state, offsets, 3600.0)
    assert outputs is not None and len(updates) < 12  # once per revolution (10.7 h)
    run = rp.ccsp(
        state,
        rp.Spacecraft(1.0, 0.01),
        rp.scenarios.benchmark_exponential(0.2),
        update_times=updates,
        output_times=outputs,
        initial_covariance=tle_covariance(state),
        drag_sigma=0.1,
    )
    assert np.isin(offsets, run.times).all()
    for cov in run.covariance:
        np.linalg.cholesky(cov)


def test_update_times_at_edges_and_unbound_states():
    # An apogee a rounding away from an output is that output (no two outputs 4e-12 s
    # apart); an object with one output runs; an unbound state keeps the near-circular
    # covariance and the hourly updates.
    a, e = 26_600e3, 0.7
    state = kepler_state(a, e, 0.0)
    period = 2 * np.pi * np.sqrt(a**3 / MU)
    updates, outputs = update_schedule(state, np.array([period / 2, period, 1.5 * period]), 3600.0)
    assert np.diff(np.union1d(updates, outputs)).min() > 1.0
    cov = tle_covariance(state)
    obj = CatalogObject("MOLNIYA-LIKE", 99001, state, 0.01, 0.0, "test", cov, "element model")
    atm = rp.scenarios.benchmark_exponential(0.2)
    res = propagate_catalog(
        [obj],
        atm,
        EPOCH + np.timedelta64(7200, "s"),
        output_step=86400.0,
        execution=rp.Execution(progress=False),
    )
    assert list(res.status) == ["propagated"]
    r = 7e6
    unbound = rp.OrbitState(EPOCH, [r, 0.0, 0.0], [0.0, 1.45 * np.sqrt(MU / r), 0.0])
    assert np.isfinite(tle_covariance(unbound)).all()
    updates, outputs = update_schedule(unbound, np.array([3600.0, 7200.0]), 3600.0)
    assert outputs is None and list(updates) == [3600.0, 7200.0]


def test_ccsp_default_schedule_updates_eccentric_orbits_at_apogee():
    # rp.ccsp with no update_interval: the same run as the catalog's schedule passed
    # explicitly (bit for bit), outputs every hour and at the apogees (this Molniya orbit
    # has a 1,600 km perigee; the Monte Carlo of the catalog test above is within 20 % of
    # the apogee schedule's). TEME, a catalog's frame: the schedule is computed in the
    # axes the run integrates in, bit for bit the same as update_schedule of this state.
    k = kepler_state(26_600e3, 0.7, 0.0)
    state = rp.OrbitState(k.epoch, k.position, k.velocity, "TEME")
    craft = rp.Spacecraft(1.0, 0.01)
    atm = rp.scenarios.benchmark_exponential(0.2)
    cov = tle_covariance(state)
    day = 3 * 86400.0
    default = rp.ccsp(state, craft, atm, day, initial_covariance=cov)
    updates, outputs = update_schedule(state, np.arange(3600.0, day + 1.0, 3600.0), 3600.0)
    assert outputs is not None and len(updates) == 7  # an apogee every 12 h from 6 h, the end
    explicit = rp.ccsp(
        state, craft, atm, update_times=updates, output_times=outputs, initial_covariance=cov
    )
    assert np.isin(np.arange(3600.0, day + 1.0, 3600.0), default.times).all()
    np.testing.assert_array_equal(default.times, explicit.times)
    np.testing.assert_array_equal(default.covariance, explicit.covariance)
    # Re-drawn hourly in equinoctial elements (the default) the points stay on their
    # orbits and the spread is the apogee schedule's (18.1 km both); in Cartesian
    # coordinates it grows 3.4x (61.7 km, measured 2026-12-04).
    hourly = rp.ccsp(state, craft, atm, day, update_interval=3600.0, initial_covariance=cov)
    assert hourly.along_track_std[-1] == pytest.approx(default.along_track_std[-1], rel=0.05)
    flat = rp.ccsp(
        state,
        craft,
        atm,
        day,
        update_interval=3600.0,
        initial_covariance=cov,
        coordinates="cartesian",
    )
    assert flat.along_track_std[-1] > 3 * default.along_track_std[-1]


def test_ccsp_default_schedule_is_hourly_on_near_circular_orbits():
    state = kepler_state(R_EARTH + 500e3, 0.001, 0.3)
    craft = rp.Spacecraft(1.0, 0.01)
    atm = rp.scenarios.benchmark_exponential(0.2)
    default = rp.ccsp(state, craft, atm, 5000.0)
    hourly = rp.ccsp(state, craft, atm, 5000.0, update_interval=3600.0)
    np.testing.assert_array_equal(default.times, [0.0, 3600.0, 5000.0])
    np.testing.assert_array_equal(default.covariance, hourly.covariance)


def test_ccsp_default_schedule_names_update_interval_when_too_long():
    state = kepler_state(R_EARTH + 500e3, 0.001, 0.3)
    with pytest.raises(ValueError, match="update_interval = 3600 s gives"):
        rp.ccsp(state, rp.Spacecraft(1.0, 0.01), rp.scenarios.benchmark_exponential(0.2), 1e12)
