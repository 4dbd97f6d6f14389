"""UTC epochs: conversion of user input to ``numpy.datetime64`` and to the core's time
scale, seconds since J2000 (2000-01-01T12:00:00 UTC). UT1 = UTC is assumed, as the design
contract allows; leap seconds are not modelled (numpy's datetime64 has none)."""

from __future__ import annotations

import datetime as _dt

import numpy as np

EpochLike = str | _dt.datetime | _dt.date | np.datetime64

#: The J2000 epoch, 2000-01-01T12:00:00 (UTC, taken as UT1).
J2000 = np.datetime64("2000-01-01T12:00:00", "ns")


def to_datetime64(epoch: EpochLike, name: str = "epoch") -> np.datetime64:
    """Converts an ISO-8601 string, ``datetime`` (naive = UTC; aware converted to UTC),
    ``date`` or ``numpy.datetime64`` to a ``datetime64[ns]`` in UTC.

    Raises TypeError for other types and ValueError for unparsable strings.
    """
    if isinstance(epoch, np.datetime64):
        if np.isnat(epoch):
            raise ValueError(f"{name} is NaT (not a time)")
        return epoch.astype("datetime64[ns]")
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


def seconds_since_j2000(epoch: EpochLike, name: str = "epoch") -> float:
    """Seconds (float) from J2000 to ``epoch`` (UTC = UT1)."""
    delta = to_datetime64(epoch, name) - J2000
    return float(delta.astype("timedelta64[ns]").astype(np.int64)) * 1e-9


def offsets_to_epochs(epoch: EpochLike, seconds: np.ndarray) -> np.ndarray:
    """``datetime64[ns]`` array of ``epoch`` plus ``seconds`` (float array, s)."""
    base = to_datetime64(epoch)
    ns = np.round(np.asarray(seconds, dtype=float) * 1e9).astype(np.int64)
    return base + ns.astype("timedelta64[ns]")
