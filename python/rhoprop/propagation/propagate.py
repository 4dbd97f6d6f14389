"""Deterministic propagation of one orbit at the mean density."""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _core, _validate
from ..constants import DEFAULT_FLOOR_ALTITUDE
from ..density.model import DensityModel, as_atmosphere
from ..time import seconds_since_j2000
from .results import Trajectory, trajectory_from_core
from .state import OrbitState, Spacecraft

#: Methods of :func:`propagate` and their default step (s) or tolerance.
METHODS = ("dop853", "rk8", "rk4")
#: Default largest step of the fixed-step methods, s. RK8 at 180 s ends 3 days of the
#: paper's orbit well within 1 m of a tight reference; 180 s divides the 18-min and
#: 180-min kappa intervals. RK4 needs 5 s for the same accuracy.
DEFAULT_STEP = {"rk8": 180.0, "rk4": 5.0}
#: Default relative tolerance of the adaptive DOP853 (per step, on |r| and |v|).
DEFAULT_RTOL = 1e-10


def output_grid(duration: float, output_step: float | None) -> np.ndarray:
    """Output times 0, step, 2 step, ... and always ``duration`` itself, s."""
    if output_step is None:
        return np.array([0.0, duration])
    step = _validate.positive("output_step", output_step)
    n = int(np.floor(duration / step * (1 + 1e-12)))
    grid = np.arange(n + 1, dtype=float) * step
    if duration - grid[-1] > 1e-9 * max(duration, 1.0):
        grid = np.append(grid, duration)
    else:
        grid[-1] = duration
    return grid


def propagate(
    state: OrbitState,
    spacecraft: Spacecraft,
    density: DensityModel,
    duration: Any,
    *,
    output_step: float | None = None,
    method: str = "dop853",
    rtol: float | None = None,
    step: float | None = None,
    floor_altitude: float = DEFAULT_FLOOR_ALTITUDE,
) -> Trajectory:
    """Propagates one orbit with two-body + J2 + drag at the mean density.

    Args:
        state: initial :class:`OrbitState`.
        spacecraft: :class:`Spacecraft` (Cd and A/m, m^2/kg).
        density: a density model, e.g. :class:`rhoprop.density.Exponential`.
        duration: propagation span, s (> 0), or a ``timedelta``.
        output_step: spacing of the outputs, s; None gives the start and end only. The end
            is always an output.
        method: ``"dop853"`` (adaptive, dense output; default), ``"rk8"`` (fixed-step
            8th-order Dormand-Prince) or ``"rk4"`` (fixed-step classic RK4).
        rtol: relative tolerance of ``"dop853"`` (default 1e-10).
        step: largest step of ``"rk8"`` / ``"rk4"``, s (defaults 180 s / 5 s); for
            ``"dop853"`` an optional largest step.
        floor_altitude: geodetic altitude below which the object counts as decayed, m.

    Returns:
        :class:`Trajectory` at the output times (shorter if the object decayed).

    Example:
        >>> import rhoprop as rp
        >>> s = rp.OrbitState("2002-09-07T01:00Z", [3782900.7, -5441600.7, -1420075.1],
        ...                   [-606.66, 1539.2559, -7488.3946])
        >>> tr = rp.propagate(s, rp.Spacecraft(3.0912, 0.0015),
        ...                   rp.density.Exponential(3.725e-12, 400e3, 58.515e3), 86400.0)
        >>> tr.positions.shape
        (2, 3)
    """
    if not isinstance(state, OrbitState):
        raise TypeError(f"state must be an OrbitState, got {type(state).__name__}")
    if not isinstance(spacecraft, Spacecraft):
        raise TypeError(f"spacecraft must be a Spacecraft, got {type(spacecraft).__name__}")
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
    span = _validate.positive("duration", _validate.seconds("duration", duration))
    if rtol is not None:
        rtol = _validate.positive("rtol", rtol)
        if method != "dop853":
            raise ValueError(f"rtol applies to method 'dop853' only, not {method!r}")
    if step is not None:
        step = _validate.positive("step", step)
    elif method in DEFAULT_STEP:
        step = DEFAULT_STEP[method]
    floor = _validate.real("floor_altitude", floor_altitude)
    times = output_grid(span, output_step)
    epoch = seconds_since_j2000(state.epoch)
    atmosphere = as_atmosphere(density, state, span)
    out = _core.propagate(
        atmosphere,
        epoch,
        state.state,
        spacecraft.drag_parameter,
        times,
        method,
        step,
        DEFAULT_RTOL if rtol is None and method == "dop853" else rtol,
        floor,
    )
    return trajectory_from_core(state.epoch, out)
