"""Physical constants and defaults, read from the Rust core so that they are typed once
(DESIGN.md section 3). SI units."""

from __future__ import annotations

try:  # TEMPORARY until the extension exports its constants
    from ._core import (
        DEFAULT_FLOOR_ALTITUDE,
        J2,
        MU,
        OMEGA_EARTH,
        R_EARTH,
        R_POLE,
        SECONDS_PER_DAY,
        WGS84_F,
    )
except ImportError:
    from ._core import DEFAULT_FLOOR_ALTITUDE

    MU, R_EARTH, J2, WGS84_F, OMEGA_EARTH = (
        3.986004418e14,
        6378137.0,
        1.08262668e-3,
        1 / 298.257223563,
        7.292115e-5,
    )
    R_POLE = 6356752.314245
    SECONDS_PER_DAY = 86400.0

#: Nanoseconds per second (numpy datetime64[ns] arithmetic).
NS_PER_SECOND = 1_000_000_000

__all__ = [
    "DEFAULT_FLOOR_ALTITUDE",
    "J2",
    "MU",
    "NS_PER_SECOND",
    "OMEGA_EARTH",
    "R_EARTH",
    "R_POLE",
    "SECONDS_PER_DAY",
    "WGS84_F",
]
