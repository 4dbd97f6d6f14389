"""Element sets: TLE and CCSDS OMM input through ``sgp4``.

Frames: the SGP4 state at an element set's epoch is in TEME, which rhoprop takes as its
inertial frame (the difference to J2000 is a slow precession-nutation rotation that the
design contract neglects). Drag: Cd*A/m = 2 B* / rho0 with B* in 1/Earth radii and
rho0 = 0.15696615 kg m^-2 ER^-1 (the SGP4 reference density 2.461e-8 kg/m^3 times one Earth
radius), i.e. 12.7416 B* m^2/kg, unless the caller gives a drag parameter per object.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..propagation import OrbitState
from ..time import from_jd

#: SGP4 reference density times one Earth radius, kg m^-2 ER^-1 (B* = rho0 B / 2).
SGP4_RHO0 = 0.15696615


def drag_parameter_from_bstar(bstar: float) -> float:
    """Cd*A/m (m^2/kg) from an SGP4 B* (1/Earth radii): 2 B* / rho0."""
    return 2.0 * bstar / SGP4_RHO0


@dataclass(frozen=True)
class CatalogObject:
    """One element set: ``state`` at its epoch (TEME taken as inertial), the drag
    parameter Cd*A/m (m^2/kg), B* (1/ER) and where it came from."""

    name: str
    norad_id: int
    state: OrbitState
    drag_parameter: float
    bstar: float
    source: str


@dataclass
class Catalog:
    """Objects read from a file, and the entries skipped (with ``errors="skip"``) as
    (where, message) pairs."""

    objects: list[CatalogObject]
    skipped: list[tuple[str, str]] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.objects)

    def __iter__(self) -> Iterator[CatalogObject]:
        return iter(self.objects)

    def __getitem__(self, i: int) -> CatalogObject:
        return self.objects[i]


def _object_from_satrec(sat: Any, name: str, where: str, drag: float | None) -> CatalogObject:
    from sgp4.api import SGP4_ERRORS

    err, r, v = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
    if err:
        raise ValueError(f"{where}: SGP4 error {err} at the epoch: {SGP4_ERRORS.get(err, '')}")
    # A TLE epoch counts 86400-s days on the UTC calendar (no leap seconds).
    epoch = from_jd(sat.jdsatepoch, sat.jdsatepochF, scale="utc")
    bstar = float(sat.bstar)
    if drag is None:
        if not bstar > 0:
            raise ValueError(
                f"{where}: B* = {bstar} is not positive, so no drag parameter follows from it; "
                "give drag_parameters for this object"
            )
        drag = drag_parameter_from_bstar(bstar)
    state = OrbitState(epoch, np.array(r) * 1e3, np.array(v) * 1e3)
    return CatalogObject(name or str(sat.satnum), int(sat.satnum), state, drag, bstar, where)


def _checksum_ok(line: str) -> bool:
    total = sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68])
    return line[68].isdigit() and total % 10 == int(line[68])


def _parse_tle(text: str, path: str) -> list[tuple[str, Any]]:
    """(where, callable returning an object) per TLE in ``text``."""
    from sgp4.api import Satrec

    lines = [(i + 1, ln.rstrip()) for i, ln in enumerate(text.splitlines()) if ln.strip()]
    entries: list[tuple[str, Any]] = []
    k = 0
    while k < len(lines):
        name = ""
        _n0, first = lines[k]
        if not first.startswith("1 ") and k + 1 < len(lines) and lines[k + 1][1].startswith("1 "):
            name = first[2:].strip() if first.startswith("0 ") else first.strip()
            k += 1
        if k + 1 >= len(lines):
            entries.append((f"{path} line {lines[k][0]}", ValueError("a TLE needs two lines")))
            break
        (n1, l1), (n2, l2) = lines[k], lines[k + 1]
        k += 2
        where = f"{path} lines {n1}-{n2}"
        problem = None
        for n, ln, tag in ((n1, l1, "1"), (n2, l2, "2")):
            if not ln.startswith(tag + " "):
                problem = f"line {n} should start with '{tag} '"
            elif len(ln) < 69:
                problem = f"line {n} has {len(ln)} characters, a TLE line has 69"
            elif not _checksum_ok(ln):
                problem = f"line {n} fails its checksum (column 69)"
            if problem:
                break
        if problem is None and l1[2:7] != l2[2:7]:
            problem = f"catalog numbers differ: {l1[2:7]!r} on line {n1}, {l2[2:7]!r} on line {n2}"
        if problem:
            entries.append((where, ValueError(f"{where}: {problem}")))
            continue
        try:
            sat = Satrec.twoline2rv(l1, l2)
        except (ValueError, IndexError) as err:
            entries.append((where, ValueError(f"{where}: unreadable field: {err}")))
            continue
        entries.append((where, (sat, name)))
    return entries


def _parse_omm(text: str, path: str) -> list[tuple[str, Any]]:
    from sgp4 import omm
    from sgp4.api import Satrec

    stripped = text.lstrip()
    if stripped.startswith(("[", "{")):
        data = json.loads(text)
        records = data if isinstance(data, list) else [data]
        kind = "JSON"
    elif stripped.startswith("<"):
        records = list(omm.parse_xml(io.StringIO(text)))
        kind = "XML"
    else:
        records = list(csv.DictReader(io.StringIO(text)))
        kind = "CSV"
    entries: list[tuple[str, Any]] = []
    for i, rec in enumerate(records):
        where = f"{path} {kind} record {i}"
        if not isinstance(rec, dict):
            entries.append((where, ValueError(f"{where}: not a record")))
            continue
        sat = Satrec()
        try:
            omm.initialize(sat, rec)
        except KeyError as err:
            entries.append((where, ValueError(f"{where}: missing field {err}")))
            continue
        except (ValueError, TypeError) as err:
            entries.append((where, ValueError(f"{where}: unreadable field: {err}")))
            continue
        entries.append((where, (sat, str(rec.get("OBJECT_NAME", "")).strip())))
    return entries


def load(
    path: str | Path, *, errors: str = "raise", drag_parameters: dict[int, float] | None = None
) -> Catalog:
    """Reads a TLE file (2- or 3-line) or a CCSDS OMM file (JSON, CSV or XML as CelesTrak
    serves them), detected by content.

    Args:
        path: the file.
        errors: ``"raise"`` (default): the first malformed line/record raises ValueError
            naming it and the field; ``"skip"``: it is skipped and listed in
            ``Catalog.skipped``.
        drag_parameters: optional {NORAD id: Cd*A/m (m^2/kg)} overriding B*.
    """
    if errors not in ("raise", "skip"):
        raise ValueError(f"errors must be 'raise' or 'skip', got {errors!r}")
    p = Path(path)
    raw = p.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        if errors == "raise":
            line = raw[: err.start].count(b"\n") + 1
            raise ValueError(
                f"{p.name} line {line}: byte {raw[err.start]:#04x} is not UTF-8 text"
            ) from err
        # Element sets are ASCII: a stray byte becomes U+FFFD, so that a damaged data
        # line fails its own checks (and is skipped) while the rest loads.
        text = raw.decode("utf-8", errors="replace")
    head = text.lstrip()[:200]
    is_omm = head.startswith(("[", "{", "<")) or "NORAD_CAT_ID" in head or "OBJECT_NAME" in head
    entries = _parse_omm(text, p.name) if is_omm else _parse_tle(text, p.name)
    out = Catalog([])
    for where, item in entries:
        try:
            if isinstance(item, Exception):
                raise item
            sat, name = item
            drag = (drag_parameters or {}).get(int(sat.satnum))
            out.objects.append(_object_from_satrec(sat, name, where, drag))
        except ValueError as err:
            if errors == "raise":
                raise
            out.skipped.append((where, str(err)))
    if not out.objects and not out.skipped:
        raise ValueError(f"{p} holds no TLE or OMM element sets")
    return out
