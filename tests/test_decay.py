"""Decay end to end: decayed Monte Carlo members leave every statistic
(NaN after their decay, survivors counted per output), a Monte Carlo whose mean orbit
decays still runs, the CCSP stops cleanly with the epoch reported, and an object that
comes down through a sampled field is reported as decayed, never a DensityFieldError.
The ensemble and the catalog build on the same survivors' statistics."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import catalog

DAY = 86400.0
#: At 1e-9 kg/m^3 (400 km) the paper's orbit decays after 2.64 days; with a 50 % density
#: bias held for the whole run (Constant kappa) the denser members come down earlier.
DENSE = rp.density.Exponential(1e-9, 400e3, 58.515e3, rel_sigma=0.5)


@pytest.fixture(scope="module")
def setup():
    return rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()


def dense_function():
    """The same dense atmosphere as a sampled model (geodetic altitude): the core
    interpolates it in a field that covers 50 km below perigee only."""

    def fn(t, lat, lon, alt):
        mean = 1e-9 * np.exp(-(alt - 400e3) / 58.515e3)
        return mean, 0.5 * mean

    return rp.density.FromFunction(fn, name="dense")


@pytest.fixture(scope="module")
def decaying(setup):
    # 200 members over 1.8 days: 38 (19 %) come down, the mean orbit does not.
    state, craft = setup
    return rp.monte_carlo(
        state,
        craft,
        DENSE,
        1.8 * DAY,
        n=200,
        kappa=rp.kappa.Constant(),
        output_step=3600.0,
        progress=False,
        seed=0,
    )


def test_decayed_members_are_excluded_from_every_statistic(decaying):
    r = decaying
    assert r.mean_orbit.decayed_at is None
    assert 0.1 < r.decayed.mean() < 0.3
    assert np.all(r.decay_times[r.decayed] < 1.8 * DAY)
    # Survivors per output: members whose decay time is after it.
    expected = (r.decay_times[:, None] > r.times[None, :]).sum(axis=0)
    np.testing.assert_array_equal(r.survivors, expected)
    assert r.survivors[0] == 200 and r.survivors[-1] == 200 - r.decayed.sum()
    # After its decay a member is NaN everywhere (no frozen state), before it finite.
    for arr in (r.positions, r.velocities, r.rtn_errors):
        assert np.isnan(arr[~r.alive]).all() and np.isfinite(arr[r.alive]).all()
    # Statistics of the survivors only, computed here from the surviving members.
    keep = ~r.decayed  # the members that never came down
    stats = r.stats()
    np.testing.assert_allclose(stats.std[-1], r.rtn_errors[keep, -1].std(axis=0, ddof=1))
    np.testing.assert_allclose(stats.mean[-1], r.rtn_errors[keep, -1].mean(axis=0))
    np.testing.assert_array_equal(stats.count, r.survivors)
    m = r.moments()
    states = np.concatenate([r.positions[keep, -1], r.velocities[keep, -1]], axis=1)
    np.testing.assert_allclose(m.mean[-1], states.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(m.covariance[-1], np.cov(states.T), rtol=1e-9)
    np.testing.assert_array_equal(m.count, r.survivors)
    # The original symptom: the frozen members inflated the spread. Measured: along-track
    # std 3544 km with them averaged in (radial 2989 km), 3250 km over the 162 survivors
    # (radial 1034 km); the radial spread of the survivors is far below the frozen one.
    assert stats.std[-1, 0] < 0.5 * 2989e3


def test_a_decaying_mean_orbit_still_runs(setup):
    # 3 days: the mean orbit comes down after ~2.64 days. The reference is the mean orbit
    # until then and the survivors' mean state after it.
    state, craft = setup
    r = rp.monte_carlo(
        state,
        craft,
        DENSE,
        3 * DAY,
        n=200,
        kappa=rp.kappa.Constant(),
        output_step=3600.0,
        progress=False,
        seed=0,
    )
    k = len(r.mean_orbit.times)
    assert r.mean_orbit.decayed_at is not None and k < len(r.times)
    assert r.times[k - 1] < r.mean_orbit.decayed_at <= r.times[k]
    np.testing.assert_array_equal(r.reference_positions[:k], r.mean_orbit.positions)
    after = r.alive[:, k:]
    assert (after.sum(axis=0) >= 2).all()
    mean_after = np.nanmean(np.where(after[..., None], r.positions[:, k:], np.nan), axis=0)
    np.testing.assert_allclose(r.reference_positions[k:], mean_after, rtol=1e-12)
    # Relative to the survivors' own mean the mean error vanishes; the spread does not.
    stats = r.stats()
    assert np.abs(stats.mean[k:]).max() < 1e-6 * stats.std[k:].max()
    assert (stats.std[k:, 1] > 0).all()
    # Before the mean orbit's decay the errors are relative to it.
    ref = rp.frames.to_rtn(r.positions[r.alive[:, 1], 1], *r.mean_orbit.states[1].reshape(2, 3))
    np.testing.assert_allclose(r.rtn_errors[r.alive[:, 1], 1], ref, atol=1e-6)


def test_ccsp_stops_cleanly_at_decay(setup):
    state, craft = setup
    c = rp.ccsp(state, craft, DENSE, 3 * DAY)
    assert c.decayed_at is not None and 0 < c.decayed_at < 3 * DAY
    assert len(c.times) < 73 and c.times[-1] <= c.decayed_at
    assert np.isfinite(c.covariance).all() and np.isfinite(c.along_track_std).all()
    far = rp.ccsp(state, craft, rp.scenarios.benchmark_exponential(0.2), DAY)
    assert far.decayed_at is None and far.times[-1] == DAY


def test_coming_down_through_a_sampled_field_is_decay_not_an_error(setup):
    # The field covers 50 km below perigee; the first run leaves it downwards, the
    # retry widens it to 50 km below the floor, and decay is reported.
    state, craft = setup
    model = dense_function()
    c = rp.ccsp(state, craft, model, 3 * DAY)
    assert c.decayed_at is not None and np.isfinite(c.covariance).all()
    r = rp.monte_carlo(
        state, craft, model, 1.8 * DAY, n=50, kappa=rp.kappa.Constant(), progress=False
    )
    assert r.decayed.any() and np.isfinite(r.stats().std[-1]).all()
    tr = rp.propagate(state, craft, model, 4 * DAY, output_step=3600.0)
    assert tr.decayed_at is not None and np.isfinite(tr.positions).all()


def test_ensemble_components_use_the_survivors(setup):
    state, craft = setup
    models = {"ref": DENSE, "same": DENSE}
    ens = rp.ensemble(
        state,
        craft,
        models,
        "ref",
        duration=1.8 * DAY,
        debias=rp.Debias(cds={"same": craft.cd}),
        method=rp.MonteCarlo(n=200, kappa=rp.kappa.Constant(), progress=False),
    )
    r = ens.results["ref"]
    assert r.decayed.any()
    keep = ~r.decayed
    along = r.rtn_errors[keep, -1, 1]
    # Mean and spread of the survivors in the reference RTN frame.
    assert ens.component_means[-1, 0, 1] == pytest.approx(along.mean(), rel=1e-9)
    assert np.sqrt(ens.component_covariances[-1, 0, 1, 1]) == pytest.approx(
        along.std(ddof=1), rel=1e-6
    )
    assert ens.summary()["mixture"]["std_m"] > 0


def test_ccsp_ensemble_with_a_model_that_comes_down(setup):
    # The dense model's CCSP stops at decay: its component is NaN past its last update,
    # and a mixture there names it; earlier outputs combine as usual.
    state, craft = setup
    models = {"ref": rp.scenarios.benchmark_exponential(0.2), "dense": DENSE}
    ens = rp.ensemble(
        state,
        craft,
        models,
        "ref",
        method=rp.Ccsp(),
        duration=3 * DAY,
        debias=rp.Debias(cds={"dense": craft.cd}),
    )
    assert ens.results["dense"].decayed_at is not None
    assert len(ens.times) == 73 and np.isnan(ens.component_means[-1, 1]).all()
    with pytest.raises(ValueError, match=r"no statistics .* \['dense'\]"):
        ens.mixture()
    assert ens.mixture(10).n_modes() >= 1


def test_catalog_monte_carlo_moments_use_the_survivors():
    dense = rp.density.Exponential(3e-9, 400e3, 58.515e3, rel_sigma=0.2)
    cat = catalog.load(catalog_sample())
    end = "2002-09-09T00:00"
    res = catalog.propagate_catalog(
        cat,
        dense,
        end,
        method=rp.MonteCarlo(n=20, seed=5),
        execution=rp.Execution(progress=False),
    )
    assert set(res.status) <= {"propagated", "decayed"} and "decayed" in set(res.status)
    # Object k is the public Monte Carlo seeded with seed + k at the common epochs.
    k = int(np.flatnonzero(res.status == "decayed")[0])
    obj = cat[k]
    offsets = rp.time.to_seconds(res.epochs, obj.state.epoch)
    mc = rp.monte_carlo(
        obj.state,
        rp.Spacecraft(1.0, obj.drag_parameter),
        dense,
        output_times=offsets,
        n=20,
        seed=5 + k,
        progress=False,
        drag_sigma=0.15,  # the catalog's drag_sigma="auto" for an object without a fit
        initial_covariance=obj.covariance,  # the catalog's default, "object"
        dynamics=rp.Dynamics(zonal_degree=4),  # the catalog's default
    )
    m = mc.moments()
    ok = m.count >= 2
    np.testing.assert_array_equal(res.valid[k], ok)
    np.testing.assert_array_equal(res.mean[k, ok], m.mean[ok])
    np.testing.assert_array_equal(res.covariance[k, ok], m.covariance[ok])
    assert np.isnan(res.mean[k, ~ok]).all()
    assert res.decay_fraction[k] == pytest.approx(mc.decayed.mean())
    assert "the mean orbit decays at" in res.reason[k]


def catalog_sample():
    from pathlib import Path

    return Path(__file__).parent / "data" / "sample.tle"
