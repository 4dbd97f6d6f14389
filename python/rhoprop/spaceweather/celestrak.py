"""CelesTrak's space-weather file format (https://celestrak.org/SpaceData/
SpaceWx-format.php): the legacy fixed-width ``.txt`` and the ``.csv`` form, detected from
the content, parsed into columns of one row per day. :class:`~rhoprop.SpaceWeather` holds
the result."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

_DAY = np.timedelta64(1, "D")
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

SCALARS = (
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
GEOMAGNETIC = ("kp", "ap", "ap_daily", "cp", "c9")

# Fixed-width txt layout, FORMAT(I4,I3,I3,I5,I3,8I3,I4,8I4,I4,F4.1,I2,I4,F6.1,I2,5F6.1):
# 0-based [start, stop) character columns of the fields that are kept.
_TXT_WIDTH = 130
_TXT_DATE = {"year": (0, 4), "month": (4, 7), "day": (7, 10)}
_TXT_KP = [(18 + 3 * i, 21 + 3 * i) for i in range(8)]
_TXT_AP = [(46 + 4 * i, 50 + 4 * i) for i in range(8)]
_TXTSCALARS = {
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

_CSVSCALARS = {
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
    return np.asarray(value)


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
    return np.asarray(dates)


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
    spans.update(_TXTSCALARS)
    fields = _fixed_width(chars, spans)
    columns = {
        "date": _dates_from_ymd(fields["year"], fields["month"], fields["day"]),
        "kp": np.column_stack([fields[f"Kp{i + 1}"] for i in range(8)]) / 10.0,
        "ap": np.column_stack([fields[f"ap{i + 1}"] for i in range(8)]),
        "section": np.full(len(chars), section, dtype=np.int8),
    }
    columns.update({name: fields[name] for name in _TXTSCALARS})
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
    needed = ["DATE", *_CSV_KP, *_CSV_AP, *_CSVSCALARS.values(), "F10.7_DATA_TYPE"]
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
    for index, name in enumerate(_CSVSCALARS):
        columns[name] = values[:, 16 + index]
    return columns


def read(path: Path) -> tuple[dict[str, np.ndarray], dict[str, int] | None]:
    """Columns and declared counts (txt only) of a space-weather file of either form; a
    file that does not parse is a ValueError naming it."""
    text = path.read_text(encoding="utf-8", errors="replace")
    try:
        if _is_csv(text):
            return _parse_csv(text), None
        return _parse_txt(text)
    except ValueError as err:
        raise ValueError(f"{path}: {err}") from None


#: Physical ranges of the record's values (inclusive; NaN is a blank field): a value
#: outside is a damaged or hand-made file, never a clamp.
RANGES = {
    "kp": (0.0, 9.0),
    "ap": (0.0, 400.0),
    "ap_daily": (0.0, 400.0),
    "cp": (0.0, 2.5),
    "c9": (0.0, 9.0),
    "isn": (0.0, 2000.0),
    **{name: (1.0, 3000.0) for name in SCALARS if name.startswith("f107")},
}


def check_ranges(columns: dict[str, np.ndarray]) -> None:
    """Raises ValueError naming the first value outside :data:`RANGES` (column, value,
    date)."""
    for name, (low, high) in RANGES.items():
        values = np.asarray(columns[name], dtype=float)
        bad = np.isfinite(values) & ((values < low) | (values > high))
        if bad.any():
            row = np.flatnonzero(bad.reshape(len(values), -1).any(axis=1))[0]
            value = values[row].ravel()[bad[row].ravel()][0] if values.ndim > 1 else values[row]
            raise ValueError(
                f"space-weather record: {name} = {value:g} on {columns['date'][row]} is "
                f"outside its range {low:g}-{high:g}"
            )


def check_record(columns: dict[str, np.ndarray]) -> int:
    """Validates the row order and the values' ranges (:func:`check_ranges`); returns the
    number of daily (observed or daily predicted) rows, which must come first and be
    consecutive days."""
    check_ranges(columns)
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
