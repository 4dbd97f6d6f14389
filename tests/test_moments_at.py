"""Mean and covariance at any epoch between outputs (StateMoments.at and the results'
moments_at), against a run that has an output at that epoch itself."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import catalog
from rhoprop.time import add_seconds

SAMPLE = Path(__file__).parent / "data" / "sample.tle"


def _rtn_sigmas(mean, cov):
    b = rp.frames.rtn_basis(mean[:3], mean[3:])
    return np.sqrt(np.diag(b @ cov[:3, :3] @ b.T))


def test_ccsp_moments_between_outputs_match_an_output_there():
    # Outputs every 120 s; the truth: the same filter with outputs every 60 s (its
    # outputs in flight are the sigma points' moments at that epoch). Measured: mean
    # within 0.2 mm, RTN sigmas within 0.02 % at 12 and 22 h (where the spread has grown;
    # in the first half hour, where the along-track sigma grows from 3 to 5 cm between
    # two outputs, 8 %: linear interpolation of a quadratic growth).
    s, c = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    m = rp.scenarios.benchmark_exponential(0.2)
    coarse = rp.ccsp(s, c, m, 86400.0, output_times=np.arange(120.0, 86400.0, 120.0))
    fine = rp.ccsp(s, c, m, 86400.0, output_times=np.arange(60.0, 86400.0, 60.0))
    for t in (43560.0, 80160.0):
        state, cov = coarse.moments_at(add_seconds(s.epoch, t))
        k = int(np.argmin(np.abs(fine.times - t)))
        assert state.frame == coarse.frame == "GCRF" and state.epoch == fine.epochs[k]
        assert np.linalg.norm(state.position - fine.mean[k, :3]) < 1e-3
        assert np.linalg.norm(state.velocity - fine.mean[k, 3:]) < 1e-6
        np.testing.assert_allclose(
            _rtn_sigmas(fine.mean[k], cov), _rtn_sigmas(fine.mean[k], fine.covariance[k]), rtol=1e-3
        )
        np.testing.assert_allclose(cov, cov.T)
    # At an output: that output's own numbers.
    state, cov = coarse.moments_at(coarse.epochs[100])
    np.testing.assert_array_equal(state.position, coarse.mean[100, :3])
    np.testing.assert_allclose(cov, coarse.covariance[100], rtol=1e-12, atol=1e-12)
    # Hourly outputs are too far apart in LEO: said, not guessed.
    hourly = rp.ccsp(s, c, m, 86400.0)
    with pytest.raises(ValueError, match="too far apart"):
        hourly.moments_at(add_seconds(s.epoch, 5400.0))
    with pytest.raises(ValueError, match="outside the outputs"):
        coarse.moments_at(add_seconds(s.epoch, 2 * 86400.0))


def test_monte_carlo_and_catalog_moments_at():
    # The members' mean between outputs against the mean orbit there (the members spread
    # by metres in half an hour); a catalog object's against a run with an output there.
    s, c = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    m = rp.scenarios.benchmark_exponential(0.2)
    mc = rp.monte_carlo(s, c, m, 3600.0, n=40, output_step=60.0, progress=False, seed=3)
    at = add_seconds(s.epoch, 1830.0)
    state, cov = mc.moments_at(at)
    assert state.frame == "GCRF"
    assert np.linalg.norm(state.position - mc.mean_orbit.state_at(at).position) < 100.0
    assert np.all(np.diag(cov) > 0)
    cat = catalog.load(SAMPLE)
    end = "2002-09-07T06:00"
    kw = {"initial": catalog.Initial(fit=False), "execution": rp.Execution(progress=False)}
    res = catalog.propagate_catalog(cat[:2], m, end, output_step=60.0, **kw)
    fine = catalog.propagate_catalog(cat[:2], m, end, output_step=30.0, **kw)
    at = res.epochs[10] + np.timedelta64(30, "s")
    k = int(np.flatnonzero(fine.epochs == at)[0])
    state, cov = res.moments_at(1, at)
    assert state.frame == "TEME" and state.epoch == at
    assert np.linalg.norm(state.position - fine.mean[1, k, :3]) < 1.0
    np.testing.assert_allclose(
        _rtn_sigmas(fine.mean[1, k], cov),
        _rtn_sigmas(fine.mean[1, k], fine.covariance[1, k]),
        rtol=0.02,
    )
    with pytest.raises(ValueError, match="out of range"):
        res.moments_at(5, at)
    with pytest.raises(TypeError, match="index"):
        res.moments_at("1", at)
