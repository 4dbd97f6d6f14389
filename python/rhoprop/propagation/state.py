"""Plain data: an orbit state and the drag properties of the object. Nothing here
imports an algorithm."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _validate
from ..time import EpochLike, to_datetime64


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
