"""The independent reference of the core's batched fit (``rhoprop._core.fit_orbits``):
the Gauss-Newton that ``rhoprop.catalog.fit`` ran in Python before the core's fit, one
single-trajectory propagation (``rp.propagate``'s core call) per Jacobian column and
direction, the step by numpy's SVD least squares. Slow on purpose; used by
``tests/test_fit_core.py`` and as the baseline of ``benches/fit.py``."""

from __future__ import annotations

from typing import Any

import numpy as np

from rhoprop.catalog import fit as fit_module
from rhoprop.constants import DEFAULT_FLOOR_ALTITUDE
from rhoprop.propagation import OrbitState
from rhoprop.propagation.propagate import core_propagate, run_in_field


def grid_states(
    p: np.ndarray, epoch: Any, model: Any, back: int, forward: int, spacing: float, zonal: int
) -> np.ndarray:
    """States (back + forward + 1, 6) on the grid epoch + g spacing for parameters p."""
    state = OrbitState(epoch, p[:3], p[3:6], "TEME")  # an element set's frame
    drag = max(float(p[6]), fit_module.MIN_DRAG_PARAMETER)
    parts = [p[None, :6]]
    for steps, sign in ((back, -1.0), (forward, 1.0)):
        if steps == 0:
            continue
        times = sign * spacing * np.arange(steps + 1, dtype=float)

        def one_way(atmosphere: Any, times: np.ndarray = times) -> Any:
            return core_propagate(
                atmosphere,
                state,
                drag,
                times,
                integrator="rk8",
                step=fit_module.FIT_STEP,
                floor_altitude=DEFAULT_FLOOR_ALTITUDE,
                zonal_degree=zonal,
            )

        _, states, decayed_at, _, _ = run_in_field(
            model, state, float(times[-1]), DEFAULT_FLOOR_ALTITUDE, one_way
        )
        if decayed_at is not None or len(states) < steps + 1:
            raise ValueError("the orbit decays within the fit span")
        rest = states[1:][::-1] if sign < 0 else states[1:]
        parts.insert(0 if sign < 0 else len(parts), rest)
    return np.vstack(parts)


def reference_fit(
    sat: Any, model: Any, *, span=(-86400.0, 86400.0), spacing=600.0, zonal=4, iterations=8
) -> tuple[np.ndarray, np.ndarray]:
    """(fitted p (7,), its formal covariance (7, 7)) of one element set."""
    job = fit_module._job([(sat, None, "reference")], model, None, span, spacing, None)
    obs, prior, prior_sigma = job.obs, job.prior, job.prior_sigma

    def states(q: np.ndarray) -> np.ndarray:
        return grid_states(q, job.epoch, model, obs.back, obs.forward, spacing, zonal)

    def weighted(d: np.ndarray) -> np.ndarray:
        return np.asarray(np.einsum("kij,kj->ki", obs.bases, d) / obs.sigmas).ravel()

    def cost(q: np.ndarray, s: np.ndarray) -> float:
        r = weighted(obs.positions - s[obs.rows, :3])
        return float(r @ r) + float((prior - q[6]) / prior_sigma) ** 2

    p = job.p0.copy()
    steps = np.array([1.0, 1.0, 1.0, 1e-3, 1e-3, 1e-3, 0.0])
    jac = np.zeros((len(obs.rows) * 3, 7))
    nominal = states(p)
    for _ in range(iterations):
        steps[6] = 0.01 * p[6]
        for j in range(7):
            q = p.copy()
            q[j] += steps[j]
            jac[:, j] = weighted(states(q)[obs.rows, :3] - nominal[obs.rows, :3]) / steps[j]
        res = weighted(obs.positions - nominal[obs.rows, :3])
        a = np.vstack([jac, np.eye(7)[6] / prior_sigma])
        b = np.concatenate([res, [(prior - p[6]) / prior_sigma]])
        scale = np.linalg.norm(a, axis=0)
        dp = np.linalg.lstsq(a / scale, b, rcond=None)[0] / scale
        before = cost(p, nominal)
        for _ in range(5):
            q = p + dp
            q[6] = max(q[6], fit_module.MIN_DRAG_PARAMETER)
            trial = states(q)
            if cost(q, trial) <= before * (1 + 1e-9):
                break
            dp = dp / 2
        else:
            break
        p, nominal = q, trial
        if np.linalg.norm(dp[:3]) < 0.01 and abs(dp[6]) < 1e-4 * p[6]:
            break
    normalised = weighted(obs.positions - nominal[obs.rows, :3])
    s2 = float(normalised @ normalised) / max(normalised.size - 7, 1)
    a = np.vstack([jac / np.sqrt(s2), np.eye(7)[6] / prior_sigma])
    return p, np.linalg.pinv(a.T @ a)
