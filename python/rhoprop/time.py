"""UTC epochs and every datetime64 <-> seconds conversion of the package.

Epochs are UTC instants held as ``numpy.datetime64[ns]`` (docs/conventions.md, "Time").
Three time arguments are kept apart:

* **Elapsed time** between two UTC epochs is in SI seconds and counts leap seconds: UTC is
  taken to TAI through the leap-second table of ERFA (``erfa.dat``, from the ``pyerfa``
  package, which tracks IERS Bulletin C), so 2016-12-31T12:00 -> 2017-01-01T12:00 is
  86401 s. :func:`seconds_between`, :func:`to_seconds`, :func:`add_seconds` and
  :func:`offsets_to_epochs` work in elapsed SI seconds, as the core's integrators do.
* **J2000** is the instant 2000-01-01T12:00:00 TT (= 11:58:55.816 UTC);
  :func:`seconds_since_j2000` gives elapsed SI seconds since then (TT seconds).
* **The core's Earth-rotation argument** (the ``epoch``/``ut1`` arguments of
  ``rhoprop._core``: GMST by the IAU-82 formula) is UT1 seconds since 2000-01-01T12:00
  UT1, with UT1 = UTC as the design contract allows: :func:`ut1_seconds`. It has 86400
  seconds per day and ignores leap seconds. The core adds elapsed SI seconds to it during
  a run, so after a leap second inside a run its UT1 runs 1 s ahead (< 0.5 km at the
  equator in the Earth-fixed frame, the size of the UT1 = UTC approximation itself).

Accepted epochs: ISO-8601 strings (``Z`` or a ``+hh:mm``/``-hh:mm`` offset, converted to
UTC), ``datetime`` (naive = UTC), ``date``, ``numpy.datetime64`` and astropy ``Time``
(any scale, converted to UTC; astropy is not imported unless such an object is passed).
Julian dates go through :func:`from_jd` (a bare number is ambiguous in scale and
origin, so it is a TypeError). A leap second ``23:59:60[.f]`` is accepted on the days
that have one and stands for the following 00:00:00 UTC, as ``datetime64`` has no second
60 (an epoch inside a leap second is represented by the end of it). Epochs must lie in
the years 1678-2261 (the range of ``datetime64[ns]``); '', 'NaT' and NaT are ValueErrors
naming the argument.
"""

from __future__ import annotations

import datetime as _dt
import math
import re
import sys
from collections.abc import Sequence
from typing import Any, Literal, Protocol, overload

import erfa  # type: ignore[import-untyped]
import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray


class TimeLike(Protocol):
    """An astropy ``Time`` (structural type; astropy is optional)."""

    @property
    def jd1(self) -> Any: ...

    @property
    def jd2(self) -> Any: ...


EpochLike = str | _dt.datetime | _dt.date | np.datetime64 | TimeLike
#: One epoch or many: an :data:`EpochLike`, a sequence of them or an array (datetime64,
#: strings, an astropy ``Time`` array).
EpochsLike = EpochLike | Sequence[EpochLike] | NDArray[Any]
#: A span: seconds (int or float), a ``datetime.timedelta`` or a ``numpy.timedelta64``.
DurationLike = float | _dt.timedelta | np.timedelta64

_NS_PER_S = 1_000_000_000
_NS_PER_DAY = 86_400 * _NS_PER_S
_NS = np.timedelta64(1, "ns")

#: Origin of the core's Earth-rotation time :func:`ut1_seconds`: 2000-01-01T12:00:00 UT1
#: (= UTC here), i.e. Julian date 2451545.0 on the UTC calendar.
UT1_ORIGIN = np.datetime64("2000-01-01T12:00:00", "ns")
#: The J2000.0 instant, 2000-01-01T12:00:00 TT, in UTC (TT - UTC = 32.184 s + 32 s).
J2000_UTC = np.datetime64("2000-01-01T11:58:55.816", "ns")
#: Kept for existing callers: the UTC calendar label of Julian date 2451545.0 (the origin
#: of :func:`ut1_seconds`), not the J2000 instant (that is :data:`J2000_UTC`).
J2000 = UT1_ORIGIN

#: Accepted epochs: [1678-01-01, 2262-01-01) UTC, inside the range of datetime64[ns].
FIRST_EPOCH = np.datetime64("1678-01-01T00:00:00", "ns")
END_EPOCH = np.datetime64("2262-01-01T00:00:00", "ns")
_FIRST_S = FIRST_EPOCH.astype("datetime64[s]")
_END_S = END_EPOCH.astype("datetime64[s]")
#: Leap-second table start: UTC (with TAI - UTC) begins 1960-01-01; earlier epochs are
#: taken as UTC with the 1960 offset (no leap seconds before UTC existed).
_UTC_START_NS = int(np.datetime64("1960-01-01", "ns").astype(np.int64))
#: From 1972 on TAI - UTC is a whole number of seconds, constant between leap seconds.
_UTC_1972_NS = int(np.datetime64("1972-01-01", "ns").astype(np.int64))
#: Days from JD 2451545.0 of the accepted range, a day wider (checked exactly later).
_JD_DAYS = (
    float((_FIRST_S - UT1_ORIGIN.astype("datetime64[s]")).astype(np.int64)) / 86400 - 1,
    float((_END_S - UT1_ORIGIN.astype("datetime64[s]")).astype(np.int64)) / 86400 + 1,
)
_FMT_HINT = "an ISO-8601 UTC time such as '2002-09-07T01:00:00Z'"
_RANGE_HINT = "epochs must lie in the years 1678-2261 (the range of datetime64[ns])"

# An ISO date-time with an optional zone: the zone is applied here (numpy only warns).
_ISO = re.compile(
    r"^(?P<date>[+-]?\d{4,}-\d{2}-\d{2})[T ]"
    r"(?P<h>\d{2})(?::(?P<m>\d{2})(?::(?P<s>\d{2})(?P<f>\.\d+)?)?)?"
    r"\s*(?P<zone>[Zz]|[+-]\d{2}(?::?\d{2})?)?$"
)


# -- leap seconds ------------------------------------------------------------------------


def _civil(ns: NDArray[np.int64]) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any], Any]:
    """(year, month, day, fraction of day) of UTC nanoseconds since 1970."""
    t = ns.astype("datetime64[ns]")
    day = t.astype("datetime64[D]")
    month = t.astype("datetime64[M]")
    year = t.astype("datetime64[Y]")
    iy = year.astype(np.int64) + 1970
    im = (month - year.astype("datetime64[M]")).astype(np.int64) + 1
    iday = (day - month.astype("datetime64[D]")).astype(np.int64) + 1
    fd = (ns - day.astype("datetime64[ns]").astype(np.int64)) / _NS_PER_DAY
    return iy, im, iday, fd


def _tai_minus_utc_ns(utc_ns: NDArray[np.int64]) -> NDArray[np.int64]:
    """TAI - UTC, ns, at UTC instants (ns since 1970) from ERFA's leap-second table
    (which also holds the 1960-1971 drift of UTC). Before 1960 the 1960 value."""
    ns = np.maximum(np.asarray(utc_ns, dtype=np.int64), _UTC_START_NS)
    if ns.size > 2:
        # Fast path: from 1972 on TAI - UTC only steps up, so equal ends mean constant.
        lo, hi = int(ns.min()), int(ns.max())
        if lo >= _UTC_1972_NS:
            ends = _tai_minus_utc_ns(np.array([lo, hi], dtype=np.int64))
            if ends[0] == ends[1]:
                return np.full(ns.shape, ends[0], dtype=np.int64)
    iy, im, iday, fd = _civil(ns)
    # The ufunc reports the status instead of warning: 1 is a "dubious year" (beyond the
    # table's horizon, where TAI - UTC is held at its last value, as it should be).
    dat, status = erfa.ufunc.dat(iy, im, iday, fd)
    if (np.asarray(status) < 0).any():  # pragma: no cover - the dates are valid by construction
        raise ValueError("invalid date for the leap-second table")
    return np.asarray(np.round(np.asarray(dat) * 1e9), dtype=np.int64)


def _tai_ns(utc_ns: NDArray[np.int64]) -> NDArray[np.int64]:
    """UTC ns since 1970 -> TAI ns on the same (1970) origin: elapsed-time coordinate."""
    return np.asarray(utc_ns, dtype=np.int64) + _tai_minus_utc_ns(utc_ns)


def _utc_from_tai_ns(tai_ns: NDArray[np.int64]) -> NDArray[np.int64]:
    """Inverse of :func:`_tai_ns`. TAI instants inside a leap second map to its end (the
    next 00:00:00 UTC), datetime64 having no second 60."""
    x = np.asarray(tai_ns, dtype=np.int64)
    u = x - _tai_minus_utc_ns(x)
    previous = u
    for _ in range(3):  # a fixed point: exact after two steps except inside a leap second
        previous, u = u, x - _tai_minus_utc_ns(u)
    inside = np.abs(u + _tai_minus_utc_ns(u) - x) > 2
    if inside.any():
        # u and previous straddle the midnight that ends the leap second.
        later = np.maximum(u, previous)[inside]
        u = u.copy()
        u[inside] = later - later % _NS_PER_DAY
    return u


def tai_minus_utc(epochs: EpochsLike) -> NDArray[np.float64] | float:
    """TAI - UTC, s, at UTC ``epochs`` (leap seconds from ERFA's table; 37 s since
    2017-01-01). Scalar in, float out."""
    ns = _ns(to_datetime64_array(epochs, "epochs"))
    out = _tai_minus_utc_ns(ns.ravel()).reshape(ns.shape) / 1e9
    return float(out) if out.ndim == 0 else out


def is_leap_second_day(day: EpochLike) -> bool:
    """Whether the UTC day ``day`` ends with a positive leap second (23:59:60)."""
    midnight = to_datetime64(day, "day").astype("datetime64[D]") + np.timedelta64(1, "D")
    m = int(midnight.astype("datetime64[ns]").astype(np.int64))
    step = _tai_minus_utc_ns(np.array([m, m - 1], dtype=np.int64))
    return bool(step[0] - step[1] >= _NS_PER_S // 2)


# -- conversion of user input ------------------------------------------------------------


def _astropy_time(value: Any) -> bool:
    """Whether ``value`` is an astropy Time (without importing astropy)."""
    module = sys.modules.get("astropy.time")
    return module is not None and isinstance(value, module.Time)


def _skyfield_time(value: Any) -> bool:
    """Whether ``value`` is a skyfield Time (without importing skyfield)."""
    module = sys.modules.get("skyfield.timelib")
    return module is not None and isinstance(value, module.Time)


def _from_skyfield(value: Any, name: str) -> NDArray[np.datetime64]:
    """A skyfield Time (any shape) as UTC ``datetime64[ns]``: its own UTC calendar fields
    (a leap second reads 23:59:60, as rhoprop's strings do), to the nanosecond."""
    utc = value.utc
    fields = [np.atleast_1d(np.asarray(f)) for f in utc]
    shape = np.shape(np.asarray(utc[0]))
    year, month, day, hour, minute = (f.astype(np.int64).ravel() for f in fields[:5])
    second = fields[5].astype(float).ravel()
    whole = np.floor(second).astype(np.int64)
    nanos = np.rint((second - whole) * 1e9).astype(np.int64)
    carry = nanos >= 1_000_000_000
    whole, nanos = whole + carry, np.where(carry, nanos - 1_000_000_000, nanos)
    texts = [
        f"{y:04d}-{mo:02d}-{d:02d}T{h:02d}:{mi:02d}:{sec:02d}.{ns:09d}Z"
        for y, mo, d, h, mi, sec, ns in zip(
            year, month, day, hour, minute, whole, nanos, strict=True
        )
    ]
    out = np.array([_parse(t, name) for t in texts], dtype="datetime64[ns]")
    return out.reshape(shape)


def _check_range(value: np.datetime64 | NDArray[np.datetime64], name: str) -> None:
    """ValueError naming ``name`` for NaT or epochs outside [1678, 2262) (checked in whole
    seconds, so coarse units never overflow)."""
    arr = _no_finer_than_ns(np.asarray(value))
    nat = np.isnat(arr)
    if nat.any():
        where = "" if arr.ndim == 0 else f" at index {_index(nat)}"
        raise ValueError(f"{name} is NaT (not a time){where}")
    seconds = arr.astype("datetime64[s]")
    bad = (seconds < _FIRST_S) | (seconds >= _END_S)
    if bad.any():
        where = "" if arr.ndim == 0 else f"[{_index(bad)}]"
        raise ValueError(f"{name}{where} = {arr[bad].flat[0]} is out of range: {_RANGE_HINT}")


#: datetime64 units finer than the nanosecond, in attoseconds.
_FINE_UNITS = {"ps": 10**6, "fs": 10**3, "as": 1}


def _no_finer_than_ns(arr: np.ndarray) -> np.ndarray:
    """A datetime64 array in ps, fs or as rounded to the nearest ns (numpy's own unit
    conversion overflows there); others unchanged."""
    if arr.dtype.kind != "M":
        return arr
    unit, count = np.datetime_data(arr.dtype)
    if unit not in _FINE_UNITS:
        return arr
    tick = _FINE_UNITS[unit] * count  # attoseconds; Python ints, so nothing overflows
    nat = np.isnat(arr)
    ticks = np.where(nat, 0, arr.astype(np.int64)).ravel()
    ns = np.array([(int(k) * tick + 5 * 10**8) // 10**9 for k in ticks], dtype=np.int64)
    ns = ns.reshape(arr.shape)
    out = ns.astype("datetime64[ns]")
    out[nat] = np.datetime64("NaT")
    return out


def _index(mask: NDArray[np.bool_]) -> Any:
    index = np.unravel_index(int(np.flatnonzero(mask)[0]), mask.shape)
    return int(index[0]) if len(index) == 1 else tuple(int(i) for i in index)


def _parse(text: str, name: str) -> np.datetime64:
    """An ISO-8601 string -> datetime64[ns] UTC (zone applied, leap second handled)."""
    stripped = text.strip()
    if not stripped:
        raise ValueError(f"{name} is an empty string; expected {_FMT_HINT}")
    if stripped.lower() == "nat":
        raise ValueError(f"{name} is 'NaT' (not a time); expected {_FMT_HINT}")
    match = _ISO.match(stripped)
    leap = False
    offset_min = 0
    if match:
        h, m, s = match["h"], match["m"] or "00", match["s"] or "00"
        leap = s == "60"
        if leap:
            s = "59"  # parsed as 23:59:59 and moved 1 s on below
        base = f"{match['date']}T{h}:{m}:{s}"
        # The fraction is applied here, rounded to the nanosecond: numpy would parse 10-18
        # digits at ps-as resolution, whose range (days to seconds around 1970) wraps.
        digits = (match["f"] or ".")[1:]
        fraction_ns = int(digits[:9].ljust(9, "0")) + (len(digits) > 9 and digits[9] >= "5")
        if leap:
            fraction_ns = min(fraction_ns, _NS_PER_S - 1)
        zone = match["zone"]
        if zone and zone not in ("Z", "z"):
            sign = -1 if zone[0] == "-" else 1
            digits = zone[1:].replace(":", "")
            hours, minutes = int(digits[:2]), int(digits[2:] or 0)
            if hours > 23 or minutes > 59:
                raise ValueError(f"{name} {text!r} has an invalid UTC offset {zone!r}")
            offset_min = sign * (60 * hours + minutes)
    else:
        base = stripped
        fraction_ns = 0
    try:
        value = np.datetime64(base)
    except ValueError as err:
        raise ValueError(f"{name} {text!r} is not {_FMT_HINT}") from err
    if np.datetime_data(value.dtype)[0] in ("ps", "fs", "as"):
        raise ValueError(f"{name} {text!r}: finer than nanoseconds; expected {_FMT_HINT}")
    _check_range(value, name)
    ns = int(value.astype("datetime64[ns]").astype(np.int64)) - offset_min * 60 * _NS_PER_S
    ns += fraction_ns
    if leap:
        # 23:59:59[.f] + 1 s (whole seconds: the fraction lies inside the leap second).
        end = ns - ns % _NS_PER_S + _NS_PER_S
        if end % _NS_PER_DAY != 0:
            raise ValueError(
                f"{name} {text!r}: second 60 exists only in a leap second, 23:59:60 UTC"
            )
        if not is_leap_second_day(np.datetime64(end - 1, "ns")):
            day = np.datetime64(end - _NS_PER_S, "ns").astype("datetime64[D]")
            raise ValueError(
                f"{name} {text!r}: {day} has no leap second (23:59:60 UTC exists only on "
                "the days of IERS Bulletin C, e.g. 2016-12-31)"
            )
        ns = end
    out = np.datetime64(ns, "ns")
    _check_range(out, name)
    return out


def _from_datetime(value: _dt.datetime | _dt.date, name: str) -> np.datetime64:
    to_numpy = getattr(value, "to_datetime64", None)
    if callable(to_numpy):
        # A pandas Timestamp (or NaT): its own conversion keeps nanoseconds (UTC if aware).
        converted = np.datetime64(to_numpy())
        _check_range(converted, name)
        ns: np.datetime64 = converted.astype("datetime64[ns]")
        return ns
    if isinstance(value, _dt.datetime) and value.tzinfo is not None:
        # A tzinfo whose offset is None makes the datetime naive (Python's own rule): UTC.
        offset = value.utcoffset()
        value = value.replace(tzinfo=None) - (offset or _dt.timedelta(0))
    if not 1678 <= value.year < 2262:
        raise ValueError(f"{name} = {value.isoformat()} is out of range: {_RANGE_HINT}")
    return np.datetime64(value, "ns")


def _from_time(value: Any, name: str) -> NDArray[np.datetime64]:
    """astropy Time (any scale and shape) -> datetime64[ns] UTC array of its shape; a
    masked element is a ValueError (its hidden value is not an epoch)."""
    mask = np.asarray(getattr(value, "mask", False))
    if mask.any():
        where = "" if mask.ndim == 0 else f" (element {int(np.flatnonzero(mask)[0])})"
        raise ValueError(f"{name}: an astropy Time with a masked value{where} is not an epoch")
    try:
        utc = value.utc
    except Exception as err:  # e.g. scale 'local', or UT1 beyond the IERS tables
        raise ValueError(
            f"{name}: an astropy Time of scale {getattr(value, 'scale', '?')!r} that cannot "
            f"be converted to UTC ({type(err).__name__}: {err})"
        ) from err
    return _jd_to_datetime64(np.asarray(utc.jd1, float), np.asarray(utc.jd2, float), name)


def _jd_to_datetime64(jd1: Any, jd2: Any, name: str) -> NDArray[np.datetime64]:
    """A UTC two-part (quasi) Julian date -> datetime64[ns]; leap seconds as elsewhere."""
    iy, im, iday, hmsf, status = erfa.ufunc.d2dtf("UTC", 9, jd1, jd2)
    iy, im, iday = (np.asarray(a, dtype=np.int64) for a in (iy, im, iday))
    if (np.asarray(status) < 0).any() or not ((iy >= 1678) & (iy < 2262)).all():
        raise ValueError(f"{name} is out of range: {_RANGE_HINT}")
    hmsf = np.asarray(hmsf)
    # A leap second (s = 60) becomes the next 00:00:00: drop its fraction.
    frac = np.where(hmsf["s"] == 60, 0, hmsf["f"]).astype(np.int64)
    seconds = (hmsf["h"] * 3600 + hmsf["m"] * 60 + hmsf["s"]).astype(np.int64)
    day = (
        (iy - 1970).astype("datetime64[Y]").astype("datetime64[M]")
        + (im - 1).astype("timedelta64[M]")
    ).astype("datetime64[D]") + (iday - 1).astype("timedelta64[D]")
    out = day.astype("datetime64[ns]") + (seconds * _NS_PER_S + frac).astype("timedelta64[ns]")
    return np.asarray(out, dtype="datetime64[ns]")


def to_datetime64(epoch: EpochLike, name: str = "epoch") -> np.datetime64:
    """One UTC epoch as ``datetime64[ns]``: an ISO-8601 string (``Z`` or ``+hh:mm`` zone
    converted to UTC; ``23:59:60`` on leap-second days), ``datetime`` (naive = UTC; aware
    converted), ``date``, ``numpy.datetime64``, a scalar astropy ``Time`` (any scale) or
    a scalar skyfield ``Time``.

    Raises:
        TypeError: for other types (a Julian date: use :func:`from_jd`).
        ValueError: naming ``name`` for unparsable strings, '', 'NaT', NaT, a ``23:59:60``
            on a day without a leap second, and epochs outside the years 1678-2261.
    """
    if isinstance(epoch, np.datetime64):
        coarse = _no_finer_than_ns(np.asarray(epoch))
        _check_range(coarse, name)
        ns: np.datetime64 = coarse.astype("datetime64[ns]")[()]  # type: ignore[assignment]
        return ns
    if isinstance(epoch, str):
        return _parse(epoch, name)
    if isinstance(epoch, (_dt.datetime, _dt.date)):
        return _from_datetime(epoch, name)
    for is_kind, convert, kind in (
        (_astropy_time, _from_time, "an astropy"),
        (_skyfield_time, _from_skyfield, "a skyfield"),
    ):
        if is_kind(epoch):
            out = convert(epoch, name)
            if out.ndim != 0:
                raise ValueError(
                    f"{name} must be one epoch, got {kind} Time of shape {out.shape} "
                    "(arrays of epochs go where the API takes several)"
                )
            single: np.datetime64 = out.reshape(1)[0]
            return single
    if isinstance(epoch, np.ndarray) and epoch.ndim == 0 and epoch.dtype.kind in "MUO":
        item: Any = epoch[()]
        return to_datetime64(item, name)
    hint = " (for a Julian date use rhoprop.time.from_jd)" if _is_number(epoch) else ""
    raise TypeError(
        f"{name} must be an ISO string, datetime, numpy.datetime64, astropy Time or skyfield "
        f"Time, got {type(epoch).__name__}{hint}"
    )


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.number)) and not isinstance(value, bool)


def to_datetime64_array(epochs: EpochsLike, name: str = "epochs") -> NDArray[np.datetime64]:
    """UTC epochs as a ``datetime64[ns]`` array of the input's shape: a datetime64 array,
    a sequence or array of anything :func:`to_datetime64` accepts, or an astropy ``Time``
    (any scale and shape). A scalar gives a 0-d array.

    Raises TypeError for numbers (Julian dates: :func:`from_jd`) and ValueError naming
    ``name`` and the index for NaT and unparsable or out-of-range epochs.
    """
    if _astropy_time(epochs):
        return _from_time(epochs, name)
    if _skyfield_time(epochs):
        return _from_skyfield(epochs, name)
    if isinstance(epochs, (str, _dt.date, np.datetime64)):
        return np.asarray(to_datetime64(epochs, name))
    arr = _no_finer_than_ns(np.asarray(epochs))
    if arr.dtype.kind == "M":
        _check_range(arr, name)
        return arr.astype("datetime64[ns]")
    if arr.dtype.kind in "OUS":
        if arr.size == 0:
            return np.empty(arr.shape, dtype="datetime64[ns]")
        flat = arr.ravel()
        values = []
        for i, value in enumerate(flat):
            label = name if arr.ndim == 0 else f"{name}[{_index_of(i, arr.shape)}]"
            text = value.decode() if isinstance(value, bytes) else value
            values.append(to_datetime64(text, label))
        return np.array(values, dtype="datetime64[ns]").reshape(arr.shape)
    if arr.size == 0:
        return np.empty(arr.shape, dtype="datetime64[ns]")
    raise TypeError(
        f"{name} must be UTC datetime64 values, ISO strings, datetimes or an astropy Time, "
        f"got dtype {arr.dtype} (for Julian dates use rhoprop.time.from_jd)"
    )


def _index_of(i: int, shape: tuple[int, ...]) -> Any:
    index = np.unravel_index(i, shape)
    return int(index[0]) if len(index) == 1 else tuple(int(k) for k in index)


@overload
def from_jd(
    jd: float, jd2: float = 0.0, *, scale: Literal["utc", "tai", "tt"] = "utc"
) -> np.datetime64: ...


@overload
def from_jd(
    jd: npt.ArrayLike, jd2: npt.ArrayLike = 0.0, *, scale: Literal["utc", "tai", "tt"] = "utc"
) -> Any: ...


def from_jd(
    jd: npt.ArrayLike, jd2: npt.ArrayLike = 0.0, *, scale: Literal["utc", "tai", "tt"] = "utc"
) -> Any:
    """A Julian date ``jd + jd2`` (days; the two-part form keeps full precision) on the
    time scale ``scale`` as UTC ``datetime64[ns]``: a scalar for scalars, else an array.

    ``scale``: ``"utc"`` counts 86400-s days from JD 2451545.0 = 2000-01-01T12:00:00 UTC,
    as TLEs and ``sgp4`` (``jdsatepoch``) do (astropy and ERFA stretch a leap-second day
    to 86401 s instead: pass an astropy ``Time`` to get that convention); ``"tai"`` and
    ``"tt"`` are uniform scales, converted through the leap-second table. Modified Julian
    dates: ``from_jd(2400000.5, mjd)``.
    """
    scales = ("utc", "tai", "tt")
    if scale not in scales:
        raise ValueError(f"scale must be one of {scales}, got {scale!r}")
    parts = []
    for label, value in (("jd", jd), ("jd2", jd2)):
        if (
            isinstance(value, (bool, np.bool_, str, bytes))
            or np.asarray(value).dtype.kind in "bUSMO"
        ):
            raise TypeError(
                f"{label} must be a number or an array of numbers, got {type(value).__name__}"
            )
        try:
            a = np.asarray(value, dtype=float)
        except (TypeError, ValueError) as err:
            raise TypeError(f"{label} must be a number or an array of numbers") from err
        if not np.isfinite(a).all():
            raise ValueError(f"{label} must be finite")
        parts.append(a)
    d1, d2 = np.broadcast_arrays(*parts)
    # Whole days exactly, the rest in ns: float days would lose ~0.1 us.
    days = (d1 - 2451545.0) + d2
    if ((days < _JD_DAYS[0]) | (days > _JD_DAYS[1])).any():  # before ns could overflow
        raise ValueError(f"jd is out of range: {_RANGE_HINT}")
    # Days from 1970-01-01T00:00 (JD 2440587.5), the origin of datetime64: in range.
    whole = np.floor(d1 - 2440587.5)
    rest = ((d1 - 2440587.5) - whole) + d2
    ns = whole.astype(np.int64) * _NS_PER_DAY + np.round(rest * _NS_PER_DAY).astype(np.int64)
    if scale == "tt":
        ns = ns - 32_184_000_000  # TT - TAI = 32.184 s
    if scale != "utc":
        ns = _utc_from_tai_ns(ns.ravel()).reshape(ns.shape)
    out = ns.astype("datetime64[ns]")
    _check_range(out, "jd")
    return np.datetime64(out[()], "ns") if out.ndim == 0 else out


def _ns(values: NDArray[np.datetime64]) -> NDArray[np.int64]:
    return np.asarray(values, dtype="datetime64[ns]").astype(np.int64)


def _seconds(a: Any, b: Any) -> NDArray[np.float64]:
    """(a - b) * 1e-9 for int64 ns, as float seconds. Epochs up to 584 years apart
    overflow int64 ns: those differences go through whole seconds instead."""
    x = np.asarray(a, dtype=np.int64)
    y = np.asarray(b, dtype=np.int64)
    with np.errstate(over="ignore"):
        d = x - y
    out = np.asarray(d * 1e-9, dtype=np.float64)
    wrapped = ((x ^ y) & (x ^ d)) < 0
    if wrapped.any():
        xs, xr = np.divmod(x, _NS_PER_S)
        ys, yr = np.divmod(y, _NS_PER_S)
        safe = (xs - ys).astype(np.float64) + (xr - yr) * 1e-9
        out = np.where(wrapped, safe, out)
    return out


def _add(a: Any, b: Any) -> NDArray[np.int64]:
    """a + b for int64 ns; ValueError when the sum leaves int64 (surely out of range)."""
    x = np.asarray(a, dtype=np.int64)
    y = np.asarray(b, dtype=np.int64)
    with np.errstate(over="ignore"):
        d = x + y
    if (((x ^ d) & (y ^ d)) < 0).any():
        raise ValueError(f"epoch + seconds is out of range: {_RANGE_HINT}")
    return d


# -- seconds -----------------------------------------------------------------------------


def seconds_between(start: EpochLike, end: EpochLike) -> float:
    """Elapsed SI seconds (float) from ``start`` to ``end`` (UTC epochs), leap seconds
    included: 2016-12-31T12:00 -> 2017-01-01T12:00 is 86401 s."""
    a = to_datetime64(start, "start")
    b = to_datetime64(end, "end")
    tai = _tai_ns(np.array([a, b], dtype="datetime64[ns]").astype(np.int64))
    return float(_seconds(tai[1], tai[0]))


def to_seconds(epochs: EpochsLike, origin: EpochLike) -> NDArray[np.float64]:
    """Elapsed SI seconds (float array of the input's shape) from ``origin`` to each of
    ``epochs`` (UTC; anything :func:`to_datetime64_array` accepts), leap seconds
    included."""
    ns = _ns(to_datetime64_array(epochs))
    o = np.array([to_datetime64(origin, "origin")], dtype="datetime64[ns]").astype(np.int64)
    return _seconds(_tai_ns(ns.ravel()), _tai_ns(o)[0]).reshape(ns.shape)


def seconds_since_j2000(epoch: EpochLike, name: str = "epoch") -> float:
    """Elapsed SI seconds (float) from J2000.0 = 2000-01-01T12:00:00 TT to the UTC
    ``epoch``: TT seconds since J2000 (leap seconds counted; 2000-01-01T12:00:00 UTC is
    64.184 s). Not the core's Earth-rotation argument: that is :func:`ut1_seconds`."""
    e = np.array([J2000_UTC, to_datetime64(epoch, name)], dtype="datetime64[ns]")
    tai = _tai_ns(e.astype(np.int64))
    return float(_seconds(tai[1], tai[0]))


@overload
def ut1_seconds(epochs: EpochLike, name: str = ...) -> float: ...


@overload
def ut1_seconds(epochs: EpochsLike, name: str = ...) -> Any: ...


def ut1_seconds(epochs: EpochsLike, name: str = "epoch") -> Any:
    """The core's Earth-rotation time: UT1 seconds since 2000-01-01T12:00 UT1 with
    UT1 = UTC (86400 s per day, leap seconds not counted), as ``rhoprop._core`` takes for
    its ``epoch`` and ``ut1`` arguments (GMST, IAU-82). A float for one epoch, else a
    float array of the input's shape."""
    values = to_datetime64_array(epochs, name)
    seconds = _seconds(_ns(values), int(UT1_ORIGIN.astype(np.int64)))
    return float(seconds) if values.ndim == 0 else np.asarray(seconds, dtype=np.float64)


def core_times(epochs: EpochsLike, origin: EpochLike) -> NDArray[np.float64]:
    """The core's time argument at ``epochs`` for a run that starts at ``origin``:
    ``ut1_seconds(origin)`` plus the elapsed SI seconds from ``origin`` (what the core
    itself computes as ``epoch + t``). Equals :func:`ut1_seconds` unless a leap second
    lies between ``origin`` and an epoch."""
    ns = _ns(to_datetime64_array(epochs))
    o = np.array([to_datetime64(origin, "origin")], dtype="datetime64[ns]").astype(np.int64)
    leaps = _tai_minus_utc_ns(ns.ravel()) - _tai_minus_utc_ns(o)[0]
    # UTC ns + the leap seconds since the origin: the UT1 label the core reaches.
    return _seconds(_add(ns.ravel(), leaps), int(UT1_ORIGIN.astype(np.int64))).reshape(ns.shape)


def add_seconds(epoch: EpochLike, seconds: float, *, round_up: bool = False) -> np.datetime64:
    """``epoch`` plus ``seconds`` elapsed SI seconds (leap seconds counted), to the
    nearest nanosecond (``round_up``: the next nanosecond at or after, so that a window
    surely covers the span)."""
    value = float(seconds)
    if not math.isfinite(value):
        raise ValueError(f"seconds must be finite, got {value}")
    if abs(value) > 9.2e9:  # s (292 years): the span int64 nanoseconds can hold
        raise ValueError(f"{value:g} s reaches outside the accepted epochs: {_RANGE_HINT}")
    ns = math.ceil(value * 1e9) if round_up else round(value * 1e9)
    return np.datetime64(_shift(to_datetime64(epoch), np.array([ns]))[0], "ns")


def offsets_to_epochs(epoch: EpochLike, seconds: npt.ArrayLike) -> NDArray[np.datetime64]:
    """``datetime64[ns]`` array of ``epoch`` plus each of ``seconds`` (float array of
    elapsed SI seconds, leap seconds counted; an offset that ends inside a leap second
    gives the next 00:00:00 UTC)."""
    s = np.asarray(seconds, dtype=float)
    if not np.isfinite(s).all():
        raise ValueError("seconds must be finite")
    limit = 9.2e9  # s (292 years): the span int64 nanoseconds can hold
    if (np.abs(s) > limit).any():
        raise ValueError(f"seconds reach outside the accepted epochs: {_RANGE_HINT}")
    ns = np.round(s * 1e9).astype(np.int64)
    return _shift(to_datetime64(epoch), ns.ravel()).reshape(s.shape)


def _shift(base: np.datetime64, ns: NDArray[np.int64]) -> NDArray[np.datetime64]:
    """``base`` plus elapsed ns (TAI arithmetic), checked against the accepted range."""
    b = int(base.astype(np.int64))
    tai = _add(_tai_ns(np.array([b], dtype=np.int64))[0], ns)
    # Fast path: no leap second between the base and any result (the usual case).
    simple = _add(ns, b)
    lo, hi = int(simple.min(initial=b)), int(simple.max(initial=b))
    first, last = _tai_minus_utc_ns(np.array([lo, hi], dtype=np.int64))
    if first == last and lo >= _UTC_1972_NS:
        out = simple
    else:
        out = _utc_from_tai_ns(tai)
    first_ns, end_ns = int(FIRST_EPOCH.astype(np.int64)), int(END_EPOCH.astype(np.int64))
    bad = (out < first_ns) | (out >= end_ns)
    if bad.any():
        raise ValueError(f"epoch + seconds is out of range: {_RANGE_HINT}")
    return out.astype("datetime64[ns]")
