"""TLE -> numerical state and ballistic coefficient: a least-squares fit of the initial
state and Cd*A/m to SGP4 positions (pseudo-observations) over a span around the element
set's epoch, with rhoprop's own dynamics (two-body + J2 + drag, RK8) and the chosen
density model, so that the state and the drag parameter are consistent with the model
the catalog is then propagated with (SGP4's B* absorbs its own static density).

Method: Gauss-Newton on p = [r (m), v (m/s), Cd*A/m (m^2/kg)] at the start of the span;
the model is ``rp.propagate`` (RK8, default step) with outputs every ``spacing`` s;
Jacobian by forward differences (1 m, 1 mm/s, 1 % of Cd*A/m), 8 propagations per
iteration. Observations: SGP4 positions (TEME, taken as inertial) every ``spacing`` s over
``span``, equally weighted with ``obs_sigma`` (m) per component. Cd*A/m has a weak prior:
its starting value (from B*, or 0.022 m^2/kg when B* <= 0) with 100 % sigma (at least
0.01 m^2/kg), so that an orbit whose drag the span cannot see (high LEO) keeps a sensible
value; it is kept above ``MIN_DRAG_PARAMETER``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..density.model import ModelLike
from ..frames import rtn_basis
from ..propagation import OrbitState, Spacecraft, propagate
from ..time import add_seconds, from_jd

#: SGP4 reference density times one Earth radius, kg m^-2 ER^-1 (B* = rho0 B / 2).
SGP4_RHO0 = 0.15696615
#: Cd*A/m (m^2/kg) a fit starts from when B* gives none (B* <= 0): Cd 2.2, A/m 0.01.
DEFAULT_DRAG_PARAMETER = 0.022


def drag_parameter_from_bstar(bstar: float) -> float:
    """Cd*A/m (m^2/kg) from an SGP4 B* (1/Earth radii): 2 B* / rho0."""
    return 2.0 * bstar / SGP4_RHO0


#: The smallest Cd*A/m a fit may return, m^2/kg.
MIN_DRAG_PARAMETER = 1e-4
#: Default fit span around the element set's epoch, s (start, end).
DEFAULT_SPAN = (-86400.0, 86400.0)
#: Default spacing of the pseudo-observations, s.
DEFAULT_SPACING = 600.0


@dataclass(frozen=True)
class FitResult:
    """A fitted element set.

    Attributes:
        state: fitted state at the element set's epoch (inertial = TEME), m and m/s.
        drag_parameter: fitted Cd*A/m, m^2/kg.
        covariance: formal covariance (7, 7) of [r, v, Cd*A/m] at the epoch (m^2, m^2/s,
            m^2/s^2, m^3/kg, ...), scaled by the residuals' mean square: how well the
            numerical model reproduces SGP4, not the TLE's own accuracy.
        drag_sigma: 1-sigma of Cd*A/m from ``covariance``, m^2/kg.
        times: observation times, s from the epoch (k,).
        residuals: SGP4 minus fitted position at ``times`` in the RTN frame of the SGP4
            orbit (k, 3), m.
        rms: RMS of the residuals per RTN component (3,), m; ``rms_total`` their 3-D RMS, m.
        iterations: Gauss-Newton iterations; converged: whether the last update was below
            1 cm and 1e-4 relative in Cd*A/m.
        drag_observable: False when the prior on Cd*A/m dominated (its formal sigma is
            over half the prior's): the span barely sees drag (high orbits).
    """

    state: OrbitState
    drag_parameter: float
    covariance: np.ndarray
    drag_sigma: float
    times: np.ndarray
    residuals: np.ndarray
    rms: np.ndarray
    rms_total: float
    iterations: int
    converged: bool
    drag_observable: bool


def _positions(
    p: np.ndarray,
    t0: np.datetime64,
    model: Any,
    duration: float,
    spacing: float,
    zonal_degree: int = 2,
) -> np.ndarray:
    """States (k, 6) at the observation times for parameters ``p`` at ``t0``."""
    traj = propagate(
        OrbitState(t0, p[:3], p[3:6]),
        Spacecraft(1.0, max(float(p[6]), MIN_DRAG_PARAMETER)),
        model,
        duration,
        output_step=spacing,
        integrator="rk8",
        zonal_degree=zonal_degree,
    )
    k = round(duration / spacing) + 1
    if traj.decayed_at is not None or len(traj.times) < k:
        raise ValueError("the orbit decays within the fit span; shorten span")
    return np.hstack([traj.positions[:k], traj.velocities[:k]])


def _sgp4_observations(
    sat: Any, start: float, end: float, spacing: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times (s from the epoch), positions (k, 3) m and velocities (k, 3) m/s of the
    element set by SGP4 every ``spacing`` s over [start, end]; ValueError naming SGP4's
    error."""
    from sgp4.api import SGP4_ERRORS

    times = np.arange(start, end + spacing / 2, spacing)
    err, r, v = sat.sgp4_array(
        np.full(len(times), sat.jdsatepoch), sat.jdsatepochF + times / 86400.0
    )
    if np.any(err):
        bad = int(np.flatnonzero(err)[0])
        raise ValueError(
            f"SGP4 error {int(err[bad])} at {times[bad]:.0f} s from the epoch: "
            f"{SGP4_ERRORS.get(int(err[bad]), '')}"
        )
    return times, np.asarray(r) * 1e3, np.asarray(v) * 1e3


def fit_element_set(
    sat: Any,  # an sgp4 Satrec or a CatalogObject (sgp4 ships no type information)
    model: ModelLike,
    *,
    drag_parameter: float | None = None,
    span: tuple[float, float] = DEFAULT_SPAN,
    spacing: float = DEFAULT_SPACING,
    obs_sigma: float = 1000.0,
    max_iterations: int = 8,
    zonal_degree: int = 2,
) -> FitResult:
    """Fits state and Cd*A/m of one element set to its SGP4 positions.

    Args:
        sat: an ``sgp4`` ``Satrec`` (or a :class:`~rhoprop.catalog.CatalogObject`, whose
            ``satrec()`` is used).
        model: density model (a sampled one through its atlas's day tiles) or a
            ``DensityField`` covering the span and the orbit's altitudes.
        drag_parameter: Cd*A/m to start from and the prior's centre, m^2/kg (default
            from B*, or 0.022 when B* <= 0).
        span: (start, end) of the pseudo-observations, s from the epoch; start <= 0 <= end,
            both multiples of ``spacing``. Default one day either side.
        spacing: observation spacing, s (default 600).
        obs_sigma: weight of a pseudo-observation, 1-sigma per component, m (default 1 km,
            the order of TLE accuracy); only sets the balance against the prior.
        max_iterations: Gauss-Newton iterations at most.
        zonal_degree: highest zonal harmonic of the fit's dynamics, 2 (J2) to 6; use the
            degree the fitted state will be propagated with.

    Returns:
        :class:`FitResult`. Raises ValueError if SGP4 fails over the span or the orbit
        decays within it.
    """
    if hasattr(sat, "satrec") and callable(sat.satrec):
        drag_parameter = drag_parameter if drag_parameter is not None else sat.drag_parameter
        sat = sat.satrec()
        if sat is None:
            raise ValueError("the catalog object carries no element set to fit")
    start, end = float(span[0]), float(span[1])
    if not (start <= 0 <= end and end > start and spacing > 0):
        raise ValueError(f"span must satisfy start <= 0 <= end, start < end; got {span}")
    if abs(start / spacing - round(start / spacing)) > 1e-9:
        raise ValueError(f"span start {start} s is not a multiple of spacing {spacing} s")
    epoch = from_jd(sat.jdsatepoch, sat.jdsatepochF, scale="utc")
    times, obs, obs_v = _sgp4_observations(sat, start, end, spacing)
    t0 = add_seconds(epoch, start)
    duration = end - start
    i_epoch = round(-start / spacing)
    if drag_parameter is None:
        bstar = float(sat.bstar)
        drag_parameter = drag_parameter_from_bstar(bstar) if bstar > 0 else DEFAULT_DRAG_PARAMETER
    prior = max(float(drag_parameter), MIN_DRAG_PARAMETER)
    prior_sigma = max(prior, 0.01)
    p = np.concatenate([obs[0], obs_v[0], [prior]])
    steps = np.array([1.0, 1.0, 1.0, 1e-3, 1e-3, 1e-3, 0.0])
    converged = False
    iterations = 0
    jac = np.zeros((len(times) * 3, 7))
    jac_epoch = np.zeros((6, 7))
    nominal = _positions(p, t0, model, duration, spacing, zonal_degree)
    for iterations in range(1, max_iterations + 1):  # noqa: B007 - reported
        steps[6] = 0.01 * p[6]
        for j in range(7):
            q = p.copy()
            q[j] += steps[j]
            pert = _positions(q, t0, model, duration, spacing, zonal_degree)
            jac[:, j] = ((pert[:, :3] - nominal[:, :3]) / steps[j]).ravel()
            jac_epoch[:, j] = (pert[i_epoch] - nominal[i_epoch]) / steps[j]
        res = (obs - nominal[:, :3]).ravel()
        a = np.vstack([jac / obs_sigma, np.eye(7)[6] / prior_sigma])
        b = np.concatenate([res / obs_sigma, [(prior - p[6]) / prior_sigma]])
        scale = np.linalg.norm(a, axis=0)
        dp = np.linalg.lstsq(a / scale, b, rcond=None)[0] / scale
        p = p + dp
        p[6] = max(p[6], MIN_DRAG_PARAMETER)
        nominal = _positions(p, t0, model, duration, spacing, zonal_degree)
        if np.linalg.norm(dp[:3]) < 0.01 and abs(dp[6]) < 1e-4 * p[6]:
            converged = True
            break
    res3 = obs - nominal[:, :3]
    dof = max(res3.size - 7, 1)
    s2 = float(np.sum(res3**2)) / dof
    a = np.vstack([jac * np.sqrt(1.0 / s2), np.eye(7)[6] / prior_sigma])
    cov_t0 = np.linalg.pinv(a.T @ a)
    phi = np.zeros((7, 7))
    phi[:6] = jac_epoch
    phi[6, 6] = 1.0
    cov = phi @ cov_t0 @ phi.T
    cov = (cov + cov.T) / 2
    bases = rtn_basis(obs, obs_v)
    residuals = np.einsum("kij,kj->ki", bases, res3)
    rms = np.sqrt(np.mean(residuals**2, axis=0))
    at_epoch = nominal[i_epoch]
    drag_sigma = float(np.sqrt(max(cov[6, 6], 0.0)))
    return FitResult(
        state=OrbitState(epoch, at_epoch[:3], at_epoch[3:]),
        drag_parameter=float(p[6]),
        covariance=cov,
        drag_sigma=drag_sigma,
        times=times,
        residuals=residuals,
        rms=rms,
        rms_total=float(np.sqrt(np.sum(rms**2))),
        iterations=iterations,
        converged=converged,
        drag_observable=drag_sigma < 0.5 * prior_sigma,
    )


def fit_span_epochs(epoch: np.datetime64, span: tuple[float, float]) -> tuple[Any, Any]:
    """First and last epoch of a fit span around ``epoch`` (UTC)."""
    return add_seconds(epoch, span[0]), add_seconds(epoch, span[1])


__all__ = [
    "DEFAULT_DRAG_PARAMETER",
    "DEFAULT_SPACING",
    "DEFAULT_SPAN",
    "MIN_DRAG_PARAMETER",
    "SGP4_RHO0",
    "FitResult",
    "drag_parameter_from_bstar",
    "fit_element_set",
    "fit_span_epochs",
]
