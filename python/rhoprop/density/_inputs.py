"""Checks and broadcasting of density-model inputs, and the altitude band an orbit can
reach: a leaf module that the model protocol and the sampled field both use."""

from __future__ import annotations

from typing import Protocol

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..constants import MU, R_EARTH, R_POLE
from ..time import EpochsLike, to_datetime64_array


class StateLike(Protocol):
    """What a density model needs of an orbit state (:class:`~rhoprop.OrbitState`): its
    UTC epoch and inertial position (m) and velocity (m/s)."""

    @property
    def epoch(self) -> np.datetime64: ...
    @property
    def position(self) -> np.ndarray: ...
    @property
    def velocity(self) -> np.ndarray: ...


def broadcast_inputs(
    times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Broadcasts and checks ``mean_std`` inputs: UTC times (datetime64, ISO strings,
    datetimes or an astropy Time; see :func:`rhoprop.time.to_datetime64_array`) as
    datetime64[ns], finite latitude in [-90, 90] deg, finite longitude (deg) and altitude
    (m)."""
    t = to_datetime64_array(times, "times")
    arrays = []
    for name, value in (("lat", lat), ("lon", lon), ("alt", alt)):
        a = _validate.real_array(name, value)
        bad = ~np.isfinite(a)
        if bad.any():
            raise ValueError(f"{name} must be finite; got {a[bad].flat[0]}")
        arrays.append(a)
    la, lo, al = arrays
    if (np.abs(la) > 90.0).any():
        raise ValueError(f"lat must lie in [-90, 90] deg; got {la[np.abs(la) > 90].flat[0]}")
    t, la, lo, al = np.broadcast_arrays(t, la, lo, al)
    return t, la, lo, al


def altitude_band(
    position: npt.ArrayLike, velocity: npt.ArrayLike, below: float = 50e3, above: float = 25e3
) -> tuple[float, float]:
    """Geodetic altitude range (m) an orbit can reach: perigee radius minus the equatorial
    radius, apogee radius minus the polar radius, widened by ``below``/``above`` m for
    decay and margin."""
    r = np.asarray(position, dtype=float)
    v = np.asarray(velocity, dtype=float)
    rn = np.linalg.norm(r)
    a = 1.0 / (2.0 / rn - v @ v / MU)
    e_vec = np.cross(v, np.cross(r, v)) / MU - r / rn
    e = float(np.linalg.norm(e_vec))
    if not (a > 0 and e < 1):
        raise ValueError("the orbit is not elliptic: a sampled density field needs a bounded orbit")
    low = a * (1 - e) - R_EARTH - below
    high = a * (1 + e) - R_POLE + above
    return max(low, 0.0), high
