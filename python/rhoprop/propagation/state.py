"""Plain data: an orbit state and the drag properties of the object. Nothing here
imports an algorithm."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .. import _validate, frames
from ..constants import MU, R_EARTH, R_POLE
from ..time import EpochLike, to_datetime64

#: Largest accepted distance from the Earth's centre, in equatorial radii.
MAX_RADII = 10.0
#: Largest accepted radiation pressure coefficient: fitted Cr of real objects reach 2-3
#: (a mirror is 2); above 5 a value is a units or parameter mistake.
MAX_CR = 5.0
#: Accepted speeds, as fractions of the circular speed sqrt(mu / |r|) at the position:
#: below 0.3 the perigee radius is at most 5 % of |r| (2a - |r| with a = |r| / 1.91),
#: deep inside the Earth; 1.5 is beyond the escape speed (sqrt 2 = 1.41), so every bound
#: orbit and mildly hyperbolic states pass.
SPEED_RANGE = (0.3, 1.5)


@dataclass(frozen=True, eq=False)
class OrbitState:
    """An inertial orbit state in a named frame.

    Args:
        epoch: UTC epoch: ISO string (``"2002-09-07T01:00:00Z"``, also with a ``+hh:mm``
            offset), ``datetime`` (naive = UTC), ``numpy.datetime64`` or astropy ``Time``
            (see :mod:`rhoprop.time`; Julian dates through :func:`rhoprop.time.from_jd`).
        position: inertial position (3,), m.
        velocity: inertial velocity (3,), m/s.
        frame: the frame of ``position`` and ``velocity``, one of
            :data:`rhoprop.frames.INERTIAL_FRAMES`: ``"GCRF"`` (default; ``"EME2000"``
            and ``"ICRF"`` name the same axes here) or ``"TEME"`` (SGP4's, as element sets
            give it). An Earth-fixed (ITRF) state is converted first with
            :func:`rhoprop.frames.convert`.

    Runs integrate in the true-of-date axes of the initial epoch (TEME's: the zonal
    field's pole, the Earth's rotation by GMST and the Sun and Moon of date are written
    there); a GCRF state is rotated into them and every result back out, so results are
    in the frame of their initial state and say so (``frame``).

    Raises:
        ValueError: for a position inside the WGS-84 ellipsoid or beyond 10 Earth radii,
            a speed outside 0.3-1.5 times the circular speed at that radius, values that
            look like km or km/s (the message says what was expected), or an unknown
            frame.
    """

    epoch: np.datetime64
    position: np.ndarray
    velocity: np.ndarray
    frame: str

    def __init__(
        self,
        epoch: EpochLike,
        position: npt.ArrayLike,
        velocity: npt.ArrayLike,
        frame: str = "GCRF",
    ) -> None:
        object.__setattr__(self, "epoch", to_datetime64(epoch))
        r = _validate.vector3("position", position)
        v = _validate.vector3("velocity", velocity)
        _check_orbit(r, v)
        object.__setattr__(self, "position", r)
        object.__setattr__(self, "velocity", v)
        object.__setattr__(self, "frame", frames.frame_name("frame", frame, frames.INERTIAL_FRAMES))

    def in_frame(self, frame: str) -> OrbitState:
        """This state converted to inertial ``frame`` (:func:`rhoprop.frames.convert`)."""
        target = frames.frame_name("frame", frame, frames.INERTIAL_FRAMES)
        s = frames.convert(self.epoch, self.state, self.frame, target)
        return OrbitState(self.epoch, s[:3], s[3:], target)

    @property
    def state(self) -> np.ndarray:
        """[x, y, z, vx, vy, vz] (6,), m and m/s."""
        return np.concatenate([self.position, self.velocity])

    def __eq__(self, other: object) -> bool:
        """Equal epochs and frames and bitwise-equal position and velocity (the dataclass default
        compared the arrays element-wise and raised)."""
        if not isinstance(other, OrbitState):
            return NotImplemented
        return bool(
            self.epoch == other.epoch
            and self.frame == other.frame
            and np.array_equal(self.position, other.position)
            and np.array_equal(self.velocity, other.velocity)
        )

    def __hash__(self) -> int:
        return hash(
            (
                int(self.epoch.astype(np.int64)),
                self.frame,
                self.position.tobytes(),
                self.velocity.tobytes(),
            )
        )


@dataclass(frozen=True)
class Spacecraft:
    """Drag and radiation-pressure properties of the object.

    Args:
        cd: drag coefficient (dimensionless, > 0).
        area_to_mass: cross-section area over mass, m^2/kg (> 0).
        cr: radiation pressure coefficient (dimensionless, 0 to 5; 1: a black body, 2: a
            mirror facing the Sun; fitted values of real objects range wider). None (the
            default): no solar radiation pressure, as SGP4. The Sun's light then pushes
            the cannonball of ``cr * area_to_mass`` away from the Sun, dimmed in the
            Earth's conical shadow (``docs/conventions.md``); the same area as drag's,
            so for a different mean area in sunlight scale ``cr`` by their ratio.
    """

    cd: float
    area_to_mass: float
    cr: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "cd", _validate.positive("cd", self.cd))
        object.__setattr__(
            self, "area_to_mass", _validate.positive("area_to_mass", self.area_to_mass)
        )
        product = self.cd * self.area_to_mass
        if not (math.isfinite(product) and product > 0):
            raise ValueError(
                f"cd * area_to_mass = {self.cd:g} * {self.area_to_mass:g} m^2/kg is "
                f"{product:g}: out of the float range"
            )
        if self.cr is not None:
            cr = _validate.real("cr", self.cr)
            if not 0.0 <= cr <= MAX_CR:
                raise ValueError(
                    f"cr = {cr:g} is out of range: the radiation pressure coefficient must "
                    f"be 0 to {MAX_CR:g} (None: no radiation pressure)"
                )
            object.__setattr__(self, "cr", cr)

    @property
    def drag_parameter(self) -> float:
        """Cd * A / m, m^2/kg."""
        return self.cd * self.area_to_mass

    @property
    def radiation_parameter(self) -> float:
        """Cr * A / m, m^2/kg; 0 without ``cr`` (no radiation pressure)."""
        return 0.0 if self.cr is None else self.cr * self.area_to_mass


def radii_beyond_reach(r: npt.ArrayLike) -> float | None:
    """The distance of position ``r`` (m) from the centre in Earth radii where it exceeds
    :data:`MAX_RADII` (the loader sets such element sets aside), else None."""
    # hypot: no overflow for huge components (np.linalg.norm of 1e154 overflowed).
    radii = math.hypot(*(float(c) for c in np.asarray(r).ravel())) / R_EARTH
    return radii if radii > MAX_RADII else None


def _check_orbit(r: np.ndarray, v: np.ndarray) -> None:
    """ValueError unless ``r`` (m) and ``v`` (m/s) look like an Earth orbit in SI units.
    Inside the WGS-84 ellipsoid is exact without an epoch: it is symmetric about z, the
    axis that the inertial and Earth-fixed frames share."""
    rn = math.hypot(*(float(c) for c in r))
    top = MAX_RADII * R_EARTH
    if radii_beyond_reach(r) is not None:
        raise ValueError(
            f"position is {rn / R_EARTH:.3g} Earth radii from the centre (|r| = {rn:.4g} m); "
            f"rhoprop takes Earth orbits within {MAX_RADII:g} Earth radii ({top:.4g} m), "
            "positions in metres"
        )
    inside = (r[0] ** 2 + r[1] ** 2) / R_EARTH**2 + r[2] ** 2 / R_POLE**2 < 1.0
    if inside:
        if R_POLE <= 1e3 * rn <= top:
            raise ValueError(
                f"position looks like km: |r| = {rn:.4g}; rhoprop takes metres "
                f"(that would be {1e3 * rn:.4g} m)"
            )
        raise ValueError(
            f"position is below the Earth's surface: |r| = {rn:.4g} m, inside the WGS-84 "
            f"ellipsoid ({R_POLE:.0f} to {R_EARTH:.0f} m from the centre); positions are "
            "inertial, in metres"
        )
    speed = math.hypot(*(float(c) for c in v))
    circular = math.sqrt(MU / rn)
    low, high = SPEED_RANGE
    if not low * circular <= speed <= high * circular:
        if low * circular <= 1e3 * speed <= high * circular:
            raise ValueError(
                f"velocity looks like km/s: |v| = {speed:.4g}; rhoprop takes m/s "
                f"(that would be {1e3 * speed:.4g} m/s)"
            )
        raise ValueError(
            f"speed |v| = {speed:.4g} m/s is not orbital at |r| = {rn:.4g} m: expected "
            f"{low:g} to {high:g} times the circular speed there ({circular:.4g} m/s), "
            "velocities inertial, in m/s"
        )
