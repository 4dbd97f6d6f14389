"""Input checks shared by the public API: clear ValueError/TypeError naming the argument."""

from __future__ import annotations

import datetime as _dt
import math
import warnings
from numbers import Real
from typing import Any

import numpy as np

from .options import Errors


def is_real(value: object) -> bool:
    """Whether ``value`` is a real number, numpy's scalars included (np.float32,
    np.int64), and not a bool."""
    return isinstance(value, (Real, np.floating, np.integer)) and not isinstance(
        value, (bool, np.bool_)
    )


def real(name: str, value: object) -> float:
    """``value`` as a finite float, else TypeError/ValueError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (Real, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    out = float(value)
    if not math.isfinite(out):
        raise ValueError(f"{name} must be finite, got {out}")
    return out


def positive(name: str, value: object) -> float:
    """``value`` as a finite float > 0."""
    out = real(name, value)
    if out <= 0.0:
        raise ValueError(f"{name} must be > 0, got {out}")
    return out


def seed(value: object, name: str = "seed", limit: int = 2**64) -> int:
    """A random seed: a whole number from 0 to ``limit - 1`` (the core's streams take
    64-bit seeds; a larger one would overflow or, reduced, repeat a smaller seed's
    numbers)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"{name} must be a non-negative integer, got {value!r}")
    if value >= limit:
        raise ValueError(f"{name} must be below 2**{limit.bit_length() - 1}, got {value}")
    return int(value)


def count(name: str, value: object, minimum: int = 0) -> int:
    """``value`` as a whole number >= ``minimum``: TypeError for a non-integer (bool
    included), ValueError below the minimum, naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__}")
    if value < minimum:
        raise ValueError(f"{name} must be >= {minimum}, got {value}")
    return int(value)


def days(name: str, value: object) -> float:
    """A number of days in 0-3660 (ten years), as a float; TypeError or ValueError
    naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a number of days, got {type(value).__name__}")
    out = float(value)
    if not np.isfinite(out) or not 0.0 <= out <= 3660.0:
        raise ValueError(f"{name} must lie in 0-3660 days, got {value}")
    return out


def seconds(name: str, value: object) -> float:
    """A finite duration in seconds from a number, ``datetime.timedelta`` or
    ``timedelta64`` (NaT is a ValueError naming ``name``)."""
    if isinstance(value, _dt.timedelta):
        return value.total_seconds()
    if isinstance(value, np.timedelta64):
        if np.isnat(value):
            raise ValueError(f"{name} is NaT (not a time)")
        unit = np.datetime_data(value.dtype)[0]
        if unit in ("Y", "M"):
            raise ValueError(f"{name} in years or months is ambiguous; give seconds or days")
        if unit in ("W", "D", "h", "m", "s"):
            # In whole seconds: a coarse unit converted to ns could overflow.
            return real(name, float(value.astype("timedelta64[s]").astype(np.int64)))
        return real(name, float(value / np.timedelta64(1, "ns")) * 1e-9)
    return real(name, value)


def real_array(name: str, value: object) -> np.ndarray:
    """``value`` as a new float64 array, refusing what only converts by accident:
    strings ("1e6"), complex numbers (their imaginary part would be dropped or raise),
    dates. TypeError naming ``name`` (finiteness is the caller's check)."""
    raw = value if isinstance(value, np.ndarray) else np.asarray(value, dtype=object)
    kind = raw.dtype.kind
    if kind == "O":
        flat = raw.ravel()
        if not all(
            isinstance(x, (Real, np.floating, np.integer)) and not isinstance(x, bool) for x in flat
        ):
            bad = next(
                x
                for x in flat
                if not isinstance(x, (Real, np.floating, np.integer)) or isinstance(x, bool)
            )
            raise TypeError(f"{name} must be real numbers, got {type(bad).__name__} {bad!r}")
    elif kind not in "iuf":
        raise TypeError(f"{name} must be real numbers, got an array of dtype {raw.dtype}")
    return np.array(raw, dtype=float)


def vector3(name: str, value: object) -> np.ndarray:
    """A finite float64 array of shape (3,)."""
    try:
        arr = real_array(name, value)
    except ValueError as err:  # ragged nesting
        raise TypeError(f"{name} must be 3 numbers, got {value!r}") from err
    if arr.shape != (3,):
        raise ValueError(f"{name} must have shape (3,), got {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise ValueError(f"{name}[{bad[0]}] must be finite, got {arr[bad[0]]}")
    arr.flags.writeable = False
    return arr


def client(function: str, value: object) -> None:
    """TypeError unless ``value`` is None or looks like a ``dask.distributed.Client``
    (``submit``, ``scatter``, ``gather``): an object without them failed with an
    AttributeError after the run's local stages."""
    if value is None:
        return
    missing = [m for m in ("submit", "scatter", "gather") if not callable(getattr(value, m, None))]
    if missing:
        raise TypeError(
            f"{function}: client must be a dask.distributed.Client or None, got "
            f"{type(value).__name__} (no {', '.join(missing)})"
        )


def errors_and_client(function: str, errors: object, value: object) -> Errors:
    """:func:`errors_argument` and :func:`client` of a batch run that takes both."""
    client(function, value)
    return errors_argument(function, errors)


def errors_argument(function: str, value: object) -> Errors:
    """``errors=`` of ``function`` checked: "raise" or "record"; the old spelling "skip"
    (of ``catalog.load`` and ``conjunction.screen``) is "record" with a
    DeprecationWarning."""
    if value == "skip":
        warnings.warn(
            f'{function}(errors="skip") is deprecated; errors="record" goes on and records '
            "each failure",
            DeprecationWarning,
            stacklevel=3,
        )
        return "record"
    if value == "raise" or value == "record":
        return value
    raise ValueError(f"errors must be 'raise' or 'record', got {value!r}")


def json_text(text: str, where: str) -> Any:
    """``json.loads(text)``, with JSON nested deeper than Python's recursion limit (a
    hostile or damaged file: ``[`` repeated 100,000 times) a ValueError naming ``where``
    instead of a RecursionError; invalid JSON stays ``json.JSONDecodeError`` (a
    ValueError)."""
    import json
    import sys

    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError(
            f"{where}: JSON nested deeper than Python's recursion limit "
            f"({sys.getrecursionlimit()} levels): a damaged or hostile file"
        ) from None
