"""Orbit states, spacecraft, trajectories and deterministic propagation."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _core, _validate
from .density.base import as_atmosphere
from .epochs import EpochLike, offsets_to_epochs, seconds_since_j2000, to_datetime64

#: Methods of :func:`propagate` and their default step (s) or tolerance.
METHODS = ("dop853", "rk8", "rk4")
#: Default largest step of the fixed-step methods, s. RK8 at 180 s ends 3 days of the
#: paper's orbit well within 1 m of a tight reference; 180 s divides the 18-min and
#: 180-min kappa intervals. RK4 needs 5 s for the same accuracy.
DEFAULT_STEP = {"rk8": 180.0, "rk4": 5.0}
#: Default relative tolerance of the adaptive DOP853 (per step, on |r| and |v|).
DEFAULT_RTOL = 1e-10
#: Default decay floor: geodetic altitude below which an object counts as re-entered, m.
DEFAULT_FLOOR_ALTITUDE = 120e3


@dataclass(frozen=True)
class OrbitState:
    """An inertial orbit state.

    Args:
        epoch: UTC epoch: ISO string (``"2002-09-07T01:00:00Z"``), ``datetime`` (naive =
            UTC) or ``numpy.datetime64``.
        position: inertial position (3,), m.
        velocity: inertial velocity (3,), m/s.

    The inertial frame is treated as J2000/GCRF; the Earth-fixed frame is a rotation about
    z by GMST (IAU-82), precession-nutation neglected.
    """

    epoch: np.datetime64
    position: np.ndarray
    velocity: np.ndarray

    def __init__(self, epoch: EpochLike, position: Any, velocity: Any) -> None:
        object.__setattr__(self, "epoch", to_datetime64(epoch))
        object.__setattr__(self, "position", _validate.vector3("position", position))
        object.__setattr__(self, "velocity", _validate.vector3("velocity", velocity))

    @property
    def state(self) -> np.ndarray:
        """[x, y, z, vx, vy, vz] (6,), m and m/s."""
        return np.concatenate([self.position, self.velocity])


@dataclass(frozen=True)
class Spacecraft:
    """Drag properties of the object.

    Args:
        cd: drag coefficient (dimensionless, > 0).
        area_to_mass: cross-section area over mass, m^2/kg (> 0).
    """

    cd: float
    area_to_mass: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "cd", _validate.positive("cd", self.cd))
        object.__setattr__(
            self, "area_to_mass", _validate.positive("area_to_mass", self.area_to_mass)
        )

    @property
    def drag_parameter(self) -> float:
        """Cd * A / m, m^2/kg."""
        return self.cd * self.area_to_mass


@dataclass(frozen=True)
class Trajectory:
    """A propagated trajectory.

    Attributes:
        epoch: initial epoch (UTC, ``datetime64[ns]``).
        times: output times, s from ``epoch``, float64 (nt,).
        positions: inertial positions (nt, 3), m.
        velocities: inertial velocities (nt, 3), m/s.
        decayed_at: time (s from ``epoch``) of the first step that ended below the floor
            altitude, or None. Outputs stop there.
        evaluations: number of right-hand-side evaluations.
        clipped: number of density evaluations clipped at zero.
    """

    epoch: np.datetime64
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    decayed_at: float | None = None
    evaluations: int = 0
    clipped: int = 0
    method: str = field(default="dop853")

    @property
    def epochs(self) -> np.ndarray:
        """Output epochs, ``datetime64[ns]`` (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def states(self) -> np.ndarray:
        """States (nt, 6): position m, velocity m/s."""
        return np.concatenate([self.positions, self.velocities], axis=1)

    def state_at(self, index: int = -1) -> OrbitState:
        """The output ``index`` as an :class:`OrbitState`."""
        return OrbitState(self.epochs[index], self.positions[index], self.velocities[index])


def trajectory_from_core(epoch: np.datetime64, out: tuple, method: str) -> Trajectory:
    """A :class:`Trajectory` from the tuple ``_core.propagate`` returns."""
    t, states, decayed_at, evaluations, clipped = out
    return Trajectory(
        epoch=epoch,
        times=t,
        positions=states[:, :3],
        velocities=states[:, 3:],
        decayed_at=decayed_at,
        evaluations=int(evaluations),
        clipped=int(clipped),
        method=method,
    )


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
    density: Any,
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
    return trajectory_from_core(state.epoch, out, method)
