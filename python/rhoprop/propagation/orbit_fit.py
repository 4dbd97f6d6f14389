"""Fits of an orbit to measured positions: a precise orbit (GNSS, DORIS, SLR), a tracking
campaign, an ephemeris from elsewhere. Gauss-Newton on the state, and on the radiation
pressure coefficient where the data allow it, through the dynamics the prediction then
uses; the span is grown in stages (an eighth, a quarter, a half, all of it) so that a
first velocity differenced from the positions converges. Element sets are fitted by
:func:`rhoprop.catalog.fit_objects` instead (to their SGP4 positions, with drag).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..density.model import ModelLike
from ..time import EpochsLike, to_datetime64_array, to_seconds
from .dynamics import Dynamics
from .propagate import DEFAULT_RTOL, DEFAULT_STEP, core_propagate, fixed_step, run_in_field
from .state import MAX_CR, OrbitState, Spacecraft

#: Forward-difference steps of the state's parameters: position m, velocity m/s; Cr's and
#: Cd's is 0.01.
_STEPS = np.array([1.0, 1.0, 1.0, 1e-3, 1e-3, 1e-3])
_COEFFICIENT_STEP = 1e-2
#: Bounds of a fitted Cd: positive, and a value beyond 20 is a fit that has run away.
_CD_BOUNDS = (1e-3, 20.0)
#: Model positions (k, 3), m, of parameters ``p`` at ``times`` s from the first epoch.
Positions = Callable[[np.ndarray, np.ndarray], np.ndarray]
#: Gauss-Newton stops when an update moves the position by less than this, m.
_CONVERGED_M = 1e-3


@dataclass(frozen=True)
class OrbitFit:
    """An orbit fitted to positions.

    Attributes:
        state: the fitted state at the first observation's epoch, in the positions' frame.
        spacecraft: the spacecraft given, with the fitted ``cr`` when Cr was fitted.
        residuals: observed minus fitted positions (n, 3), m.
        rms: root mean square of the residuals' norms, m.
        covariance: of the fitted parameters (6, 6), or larger with Cr and then Cd
            after the state: position m, velocity m/s, from the residuals' own scatter
            (sigma = rms / sqrt(3)).
        iterations: Gauss-Newton iterations over all stages.
    """

    state: OrbitState
    spacecraft: Spacecraft
    residuals: np.ndarray
    rms: float
    covariance: np.ndarray
    iterations: int


def _first_velocity(t: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Velocity (m/s) at t[0]: the derivative of the polynomial through the first five (or
    fewer) positions."""
    k = min(5, len(t))
    ts, rs = t[:k], r[:k]
    # d/dt of the Lagrange basis at ts[0]: sum over j != 0 of 1 / (ts[0] - ts[j]) for the
    # first, prod form for the others.
    weights = np.empty(k)
    for i in range(k):
        if i == 0:
            weights[i] = sum(1.0 / (ts[0] - ts[j]) for j in range(1, k))
        else:
            others = [j for j in range(k) if j not in (0, i)]
            weights[i] = np.prod([(ts[0] - ts[j]) / (ts[i] - ts[j]) for j in others]) / (
                ts[i] - ts[0]
            )
    return np.asarray(weights @ rs, dtype=float)


def fit_positions(
    epochs: EpochsLike,
    positions: npt.ArrayLike,
    spacecraft: Spacecraft,
    model: ModelLike,
    *,
    frame: str = "GCRF",
    dynamics: Dynamics | None = None,
    fit_cr: bool = False,
    fit_cd: bool = False,
    max_iterations: int = 20,
) -> OrbitFit:
    """Fits an orbit's state (and Cr, Cd) to measured positions.

    Args:
        epochs: UTC epochs of the positions (n >= 5, increasing).
        positions: positions (n, 3), m, in ``frame``.
        spacecraft: drag and radiation properties; with ``fit_cr`` its ``cr`` (default
            1.5 when None) is where the fit starts and ``area_to_mass`` the area it
            scales.
        model: the density model the prediction uses (drag acts with the spacecraft's
            Cd*A/m, or the fitted Cd's).
        frame: frame of the positions and of the fitted state: ``"GCRF"`` (default),
            ``"TEME"`` or another inertial frame :class:`OrbitState` takes.
        dynamics: the dynamics (default :meth:`Dynamics.precise`: a precise orbit is
            fitted with the precise field; DOP853).
        fit_cr: also fit the radiation pressure coefficient Cr (0 to 5).
        fit_cd: also fit the drag coefficient Cd (0.001 to 20), from the spacecraft's:
            the drag this model needs to fly the observed orbit, a measured ballistic
            coefficient.
        max_iterations: largest number of Gauss-Newton iterations per stage.

    Returns:
        :class:`OrbitFit` (its covariance has Cr, then Cd, after the state). Predict
        with ``propagate(fit.state, fit.spacecraft, model, ..., dynamics=dynamics)``.

    Raises:
        ValueError: fewer than 5 positions, epochs not increasing, positions not (n, 3)
            finite numbers, or a fit that does not converge.

    Warns:
        RuntimeWarning: a fitted Cr or Cd lies on a bound: the data do not support a
            value inside (the parameter is then held there).
    """
    when = to_datetime64_array(epochs, "epochs")
    t = to_seconds(when, when[0])
    r = _validate.real_array("positions", positions)
    if r.ndim != 2 or r.shape[1] != 3 or r.shape[0] != t.size:
        raise ValueError(f"positions must be ({t.size}, 3) to match epochs, got {r.shape}")
    if not np.all(np.isfinite(r)):
        row = int(np.flatnonzero(~np.isfinite(r).all(axis=1))[0])
        raise ValueError(f"positions must be finite, got {r[row].tolist()} in row {row}")
    if t.size < 5:
        raise ValueError(f"fit_positions needs at least 5 positions, got {t.size}")
    if np.any(np.diff(t) <= 0):
        raise ValueError("epochs must be increasing")
    if not isinstance(spacecraft, Spacecraft):
        raise TypeError(f"spacecraft must be a Spacecraft, got {type(spacecraft).__name__}")
    if dynamics is not None and not isinstance(dynamics, Dynamics):
        raise TypeError(f"dynamics must be a rhoprop.Dynamics, got {type(dynamics).__name__}")
    max_iterations = _validate.count("max_iterations", max_iterations, minimum=1)
    dyn = Dynamics.precise() if dynamics is None else dynamics
    epoch = when[0]
    # The coefficients fitted beside the state: (name, start, bounds).
    extra = [("Cr", 1.5 if spacecraft.cr is None else spacecraft.cr, (0.0, MAX_CR))] * fit_cr
    extra += [("Cd", spacecraft.cd, _CD_BOUNDS)] * fit_cd
    p = np.concatenate([r[0], _first_velocity(t, r), [start for _, start, _ in extra]])
    bounds = np.array([(-np.inf, np.inf)] * 6 + [b for _, _, b in extra])

    def craft(q: np.ndarray) -> Spacecraft:
        cr = float(q[6]) if fit_cr else spacecraft.cr
        cd = float(q[-1]) if fit_cd else spacecraft.cd
        return Spacecraft(cd, spacecraft.area_to_mass, cr=cr)

    state0 = OrbitState(epoch, p[:3], p[3:6], frame=frame)
    atmosphere = run_in_field(model, state0, float(t[-1]), dyn.floor_altitude, lambda a: a)
    method = dyn.integrator or "dop853"
    step = fixed_step(method, dyn.step, state0) if method in DEFAULT_STEP else dyn.step
    rtol = (DEFAULT_RTOL if dyn.rtol is None else dyn.rtol) if method == "dop853" else None

    def positions_of(q: np.ndarray, times: np.ndarray) -> np.ndarray:
        sc = craft(q)
        out = core_propagate(
            atmosphere,
            OrbitState(epoch, q[:3], q[3:6], frame=frame),
            sc.drag_parameter,
            times,
            integrator=method,
            step=step,
            rtol=rtol,
            floor_altitude=dyn.floor_altitude,
            zonal_degree=dyn.zonal_degree,
            forces=dyn.forces(sc.radiation_parameter),
        )
        if len(out[0]) < len(times):
            raise ValueError("the fitted orbit decays within the observations")
        return out[1][:, :3]

    iterations = 0
    for limit in sorted({t[-1] / 8, t[-1] / 4, t[-1] / 2, t[-1]}):
        use = t <= limit
        if use.sum() < 5:
            continue
        times, observed = t[use], r[use]
        p, its = _gauss_newton(p, times, observed, positions_of, max_iterations, bounds)
        iterations += its
    residuals = r - positions_of(p, t)
    rms = float(np.sqrt(np.mean(np.sum(residuals**2, axis=1))))
    jac = _jacobian(p, t, positions_of(p, t), positions_of, bounds)
    sigma2 = rms**2 / 3.0
    covariance = sigma2 * np.linalg.pinv(jac.T @ jac)
    for k, (name, _, (low, high)) in enumerate(extra, start=6):
        if p[k] in (low, high):
            warnings.warn(
                f"fit_positions: {name} ended at its bound {p[k]:g}: the positions do not "
                f"support a value inside {low:g}..{high:g} at area_to_mass "
                f"{spacecraft.area_to_mass:g} m^2/kg",
                RuntimeWarning,
                stacklevel=2,
            )
    return OrbitFit(
        OrbitState(epoch, p[:3], p[3:6], frame=frame),
        craft(p),
        residuals,
        rms,
        covariance,
        iterations,
    )


def _jacobian(
    p: np.ndarray,
    times: np.ndarray,
    base: np.ndarray,
    positions_of: Positions,
    bounds: np.ndarray,
) -> np.ndarray:
    """d(model positions)/d(parameters) by forward differences (backward at an upper
    bound), (3 len(times), n)."""
    columns = []
    for i in range(p.size):
        q = p.copy()
        h = _STEPS[i] if i < 6 else _COEFFICIENT_STEP
        if q[i] + h > bounds[i, 1]:
            h = -h
        q[i] += h
        columns.append(((positions_of(q, times) - base) / h).ravel())
    return np.array(columns).T


def _gauss_newton(
    p: np.ndarray,
    times: np.ndarray,
    observed: np.ndarray,
    positions_of: Positions,
    max_iterations: int,
    bounds: np.ndarray,
) -> tuple[np.ndarray, int]:
    """Gauss-Newton with step halving on one stage: (parameters, iterations)."""
    model = positions_of(p, times)
    cost = float(np.sum((observed - model) ** 2))
    for it in range(1, max_iterations + 1):
        trial: np.ndarray | None = None
        jac = _jacobian(p, times, model, positions_of, bounds)
        res = (observed - model).ravel()
        dp = np.linalg.lstsq(jac, res, rcond=None)[0]
        out = (p + dp < bounds[:, 0]) | (p + dp > bounds[:, 1])
        if out.any():
            # A coefficient would leave its bounds: take it to the bound and the other
            # parameters' best step given that (an active set), not the unconstrained
            # step cut off, which can raise the cost while a step that lowers it exists.
            dp[out] = np.clip(p + dp, bounds[:, 0], bounds[:, 1])[out] - p[out]
            free = ~out
            rest = res - jac[:, out] @ dp[out]
            dp[free] = np.linalg.lstsq(jac[:, free], rest, rcond=None)[0]
        for _ in range(8):
            q = np.clip(p + dp, bounds[:, 0], bounds[:, 1])
            try:
                trial = positions_of(q, times)
            except ValueError:
                trial = None
            if trial is not None and float(np.sum((observed - trial) ** 2)) <= cost:
                break
            dp = dp / 2
        else:
            return p, it  # no step lowers the cost: the minimum within rounding
        assert trial is not None  # the loop breaks only on a trial that ran
        moved = float(np.linalg.norm(q[:3] - p[:3]))
        p, model = q, trial
        cost = float(np.sum((observed - model) ** 2))
        if moved < _CONVERGED_M:
            return p, it
    raise ValueError(
        f"fit_positions did not converge in {max_iterations} iterations over "
        f"{times[-1] - times[0]:g} s of positions; check their frame and units (m)"
    )
