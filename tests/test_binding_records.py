"""The records that cross the binding (``rhoprop._core``): a run request is built with
keywords and checked when made, a result has named attributes (no positional tuples or
dicts), and both are frozen. The runs themselves are checked against independent
references elsewhere; here, that a record carries what the call returns."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import _core

STATE = rp.scenarios.paper_state()
AIR = rp.scenarios.benchmark_exponential(0.2).atmosphere(None, 0.0)


def problem(**changes):
    given = dict(epoch=0.0, state=STATE.state, drag=0.005, floor_altitude=120e3)
    return _core.Problem(**{**given, **changes})


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"zonal_degree": 7}, "zonal_degree = 7 is invalid"),
        ({"drag": -1.0}, "drag parameter"),
        ({"state": np.zeros(5)}, "state"),
        ({"floor_altitude": 1e7}, "floor"),
    ],
)
def test_a_problem_is_checked_when_made(changes, match):
    with pytest.raises(ValueError, match=match):
        problem(**changes)


def test_the_requests_take_keywords_only_and_are_checked_when_made():
    with pytest.raises(TypeError):
        _core.Problem(0.0, STATE.state, 0.005, 120e3)  # type: ignore[misc]
    with pytest.raises(ValueError, match="perturbation"):
        _core.MonteCarloRun(
            problem(), output_times=np.array([0.0, 60.0]), kappa=rp.kappa.Constant()._spec(),
            perturbation="other", method="rk8", step=60.0, members=2, seed=0,
        )  # fmt: skip
    with pytest.raises(ValueError, match="coordinates"):
        _core.CcspRun(
            problem(), initial_covariance=np.eye(6), update_times=np.array([60.0]),
            scaling=(3.0, 3.0), perturbation="additive", step=60.0, coordinates="polar",
        )  # fmt: skip
    with pytest.raises(ValueError, match="shape"):
        _core.Tracks(
            times=np.zeros(3), positions=np.zeros((2, 4, 3)), velocities=np.zeros((2, 3, 3)),
            samples=np.zeros(2, dtype=np.uint64),
        )  # fmt: skip


def test_results_are_records_with_named_attributes():
    out = _core.propagate(AIR, problem(), np.array([0.0, 600.0, 1200.0]), "rk8", 60.0)
    assert isinstance(out, _core.Propagated) and not isinstance(out, (tuple, dict))
    assert out.states.shape == (3, 6) and out.decayed_at is None and out.rhs_evaluations > 0
    np.testing.assert_array_equal(out.states[0], STATE.state)
    run = _core.MonteCarloRun(
        problem(), output_times=np.array([0.0, 600.0]), kappa=rp.kappa.Constant()._spec(),
        perturbation="additive", method="rk8", step=60.0, members=3, seed=1,
    )  # fmt: skip
    mc = _core.monte_carlo(AIR, run)
    assert mc.positions.shape == (3, 2, 3) and mc.densities is None and mc.step == 60.0
    # Same request, same numbers: a request is reusable and changes nothing.
    np.testing.assert_array_equal(_core.monte_carlo(AIR, run).positions, mc.positions)
    cc = _core.ccsp(
        AIR,
        _core.CcspRun(
            problem(), initial_covariance=np.eye(6), update_times=np.array([600.0]),
            scaling=(3.0, 3.0), perturbation="additive", step=60.0,
        ),
    )  # fmt: skip
    assert cc.covariances.shape == (2, 6, 6) and cc.element_means is not None
    pc = _core.pc_2d(
        np.zeros(3), np.array([0.0, 7e3, 0.0]), np.eye(3) * 1e4,
        np.array([50.0, 0.0, 0.0]), np.array([0.0, 0.0, 7e3]), np.eye(3) * 1e4,
        10.0, "circle", "repair",
    )  # fmt: skip
    assert 0.0 < pc.pc < 1.0 and pc.miss_distance == pytest.approx(50.0)
    for record in (out, mc, cc, pc, run):
        with pytest.raises(AttributeError):
            record.step = 1.0  # type: ignore[misc]
