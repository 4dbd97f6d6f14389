"""Precise orbits in the SP3 format (SP3-a to SP3-d: IGS and its analysis centres, the
DORIS and SLR centres): the truth a prediction is judged against. Read here: the epochs
on the UTC scale and each satellite's Earth-fixed positions; velocities and clock records
are skipped (one centre's velocities were in m/s where the format says dm/s).
"""

from __future__ import annotations

import gzip
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..time import _utc_from_tai_ns

#: Offset of each supported SP3 time system from TAI, ns (system = TAI + offset), None:
#: UTC. GPS and Galileo time run 19 s behind TAI, BeiDou time 33 s.
_FROM_TAI_NS = {
    "GPS": -19_000_000_000,
    "GAL": -19_000_000_000,
    "BDT": -33_000_000_000,
    "TAI": 0,
    "UTC": None,
}
#: An SP3 value this large marks a missing one (999999.999999 or 0.000000 in the file).
_MISSING = 9e5


@dataclass(frozen=True)
class Sp3:
    """The positions of an SP3 file.

    Attributes:
        epochs: record epochs on the UTC scale, ``datetime64[ns]`` (n,).
        positions: satellite id (``"C01"``, ``"L08"``) -> Earth-fixed positions (n, 3),
            m, in ``frame``; NaN where the file has none at that epoch.
        time_system: the file's own time scale (GPS, GAL, BDT, TAI or UTC).
        frame: the file's coordinate system (``"IGS20"``, ``"ITRF"``...).
    """

    epochs: np.ndarray
    positions: dict[str, np.ndarray]
    time_system: str
    frame: str


def _epoch(line: str, where: str) -> np.datetime64:
    try:
        y, mo, d, h, mi = (int(x) for x in line[3:31].split()[:5])
        sec = float(line[3:31].split()[5])
        return np.datetime64(f"{y:04d}-{mo:02d}-{d:02d}T{h:02d}:{mi:02d}", "ns") + np.timedelta64(
            round(sec * 1e9), "ns"
        )
    except (ValueError, IndexError):
        raise ValueError(f"{where}: unreadable epoch line {line.rstrip()!r}") from None


def _to_utc(epochs: list[np.datetime64], system: str, where: str) -> np.ndarray:
    if system not in _FROM_TAI_NS:
        raise ValueError(
            f"{where}: time system {system!r} is not supported (expected one of "
            f"{', '.join(_FROM_TAI_NS)})"
        )
    ns = np.array(epochs, dtype="datetime64[ns]").astype(np.int64)
    offset = _FROM_TAI_NS[system]
    if offset is not None:
        ns = _utc_from_tai_ns(ns - np.int64(offset))
    return ns.astype("datetime64[ns]")


def read_sp3(path: str | Path) -> Sp3:
    """Reads the position records of an SP3 file (plain or gzip-compressed).

    Args:
        path: the file.

    Returns:
        :class:`Sp3`: epochs converted to UTC from the file's time system (the first
        ``%c`` line; GPS for SP3-a), positions in metres.

    Raises:
        ValueError: not an SP3 file, an unreadable record, or a time system other than
            GPS, GAL, BDT, TAI or UTC.
    """
    where = str(path)
    opener = gzip.open if Path(path).suffix == ".gz" else open
    with opener(path, "rt") as text:
        lines = text.read().splitlines()
    if not lines or not lines[0].startswith("#") or lines[0][1:2] not in "abcd":
        raise ValueError(f"{where}: not an SP3 file (the first line must start #a..#d)")
    frame = lines[0][46:51].strip()
    system = next((ln[9:12].strip() for ln in lines if ln.startswith("%c")), "GPS")
    epochs: list[np.datetime64] = []
    found: dict[str, dict[int, list[float]]] = {}
    for number, line in enumerate(lines, 1):
        if line.startswith("*"):
            epochs.append(_epoch(line, f"{where}, line {number}"))
        elif line.startswith("P") and epochs:
            try:
                xyz = [float(line[4 + 14 * k : 18 + 14 * k]) for k in range(3)]
            except ValueError:
                raise ValueError(f"{where}, line {number}: unreadable position record") from None
            if any(xyz) and all(abs(v) < _MISSING for v in xyz):
                found.setdefault(line[1:4].strip(), {})[len(epochs) - 1] = xyz
    positions = {}
    for sat, rows in found.items():
        pos = np.full((len(epochs), 3), np.nan)
        for i, xyz in rows.items():
            pos[i] = xyz
        positions[sat] = pos * 1e3
    return Sp3(_to_utc(epochs, system, where), positions, system, frame)
