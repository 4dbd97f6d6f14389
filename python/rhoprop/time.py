"""UTC epochs: conversion of user input to ``numpy.datetime64[ns]`` and between epochs
and the core's time scale, seconds (float) since J2000 (2000-01-01T12:00:00 UTC) or since
another epoch. UT1 = UTC is assumed, as the design contract allows; leap seconds are not
modelled (numpy's datetime64 has none).

Every datetime64 <-> seconds conversion of the package goes through this module.
"""

from __future__ import annotations

import datetime as _dt
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

EpochLike = str | _dt.datetime | _dt.date | np.datetime64

#: The J2000 epoch, 2000-01-01T12:00:00 (UTC, taken as UT1).
J2000 = np.datetime64("2000-01-01T12:00:00", "ns")
_NS = np.timedelta64(1, "ns")


def to_datetime64(epoch: EpochLike, name: str = "epoch") -> np.datetime64:
    """Converts an ISO-8601 string, ``datetime`` (naive = UTC; aware converted to UTC),
    ``date`` or ``numpy.datetime64`` to a ``datetime64[ns]`` in UTC.

    Raises TypeError for other types and ValueError for unparsable strings.
    """
    if isinstance(epoch, np.datetime64):
        if np.isnat(epoch):
            raise ValueError(f"{name} is NaT (not a time)")
        ns: np.datetime64 = epoch.astype("datetime64[ns]")
        return ns
    if isinstance(epoch, _dt.datetime):
        if epoch.tzinfo is not None:
            epoch = epoch.astimezone(_dt.timezone.utc).replace(tzinfo=None)
        return np.datetime64(epoch, "ns")
    if isinstance(epoch, _dt.date):
        return np.datetime64(epoch, "ns")
    if isinstance(epoch, str):
        text = epoch.strip()
        if text.endswith(("Z", "z")):
            text = text[:-1]
        elif text.endswith("+00:00"):
            text = text[:-6]
        try:
            return np.datetime64(text, "ns")
        except ValueError as err:
            raise ValueError(
                f"{name} {epoch!r} is not an ISO-8601 UTC time such as '2002-09-07T01:00:00Z'"
            ) from err
    raise TypeError(
        f"{name} must be an ISO string, datetime or numpy.datetime64, got {type(epoch).__name__}"
    )


def seconds_between(start: np.datetime64, end: np.datetime64) -> float:
    """``end - start`` in seconds (float) for datetime64 values."""
    return float((end - start) / _NS) * 1e-9


def to_seconds(epochs: Any, origin: np.datetime64 = J2000) -> NDArray[np.float64]:
    """Seconds (float array) from ``origin`` (default J2000) to each of ``epochs``
    (datetime64 array-like)."""
    arr = np.asarray(epochs).astype("datetime64[ns]")
    return np.asarray((arr - origin).astype(np.int64) * 1e-9, dtype=np.float64)


def seconds_since_j2000(epoch: EpochLike, name: str = "epoch") -> float:
    """Seconds (float) from J2000 to ``epoch`` (UTC = UT1)."""
    return seconds_between(J2000, to_datetime64(epoch, name))


def add_seconds(epoch: np.datetime64, seconds: float, *, round_up: bool = False) -> np.datetime64:
    """``epoch`` plus ``seconds`` (float), to the nearest nanosecond (``round_up``: the next
    nanosecond at or after, so that a window surely covers the span)."""
    ns = math.ceil(seconds * 1e9) if round_up else round(seconds * 1e9)
    start: np.datetime64 = epoch.astype("datetime64[ns]")
    return start + np.timedelta64(int(ns), "ns")


def offsets_to_epochs(epoch: EpochLike, seconds: Any) -> NDArray[np.datetime64]:
    """``datetime64[ns]`` array of ``epoch`` plus ``seconds`` (float array, s)."""
    base = to_datetime64(epoch)
    ns = np.round(np.asarray(seconds, dtype=float) * 1e9).astype(np.int64)
    return base + ns.astype("timedelta64[ns]")
