"""Physical constants and defaults, read from the Rust core so that they are typed once
(docs/conventions.md, "Frames and dynamics"). SI units."""

from __future__ import annotations

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
