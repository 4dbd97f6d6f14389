"""``rhoprop screen``: a catalog file screened all-on-all (:func:`screen_all`), the
events written as a Parquet table and as CCSDS CDMs, the most probable printed."""

from __future__ import annotations

import csv
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import frames
from ..catalog.elements import Catalog, load
from ..catalog.run import MAX_SPAN
from ..conjunction.all_on_all import AllOnAllResult, screen_all
from ..conjunction.cdm import CdmObject, ConjunctionMessage
from ..conjunction.settings import PcSettings, Search
from ..execution import Execution
from ..io.events import write_event_table
from ..io.files import OutputFolder, command_line, sanitise
from ..io.tables import format_argument, table_name
from ..options import TableFormat
from ..progress import ProgressBar
from ..time import to_datetime64
from .catalog import connect, default_start, max_span_option, need_dask, print_as_of_note
from .models import FAMILIES, models_by_name

__all__ = [
    "CDM_MIN_PC",
    "ScreenJob",
    "cdm_events",
    "default_start",
    "output_events",
    "read_radii",
]

#: Events printed by ``rhoprop screen`` (all are written).
PRINTED = 15


def read_radii(path: str | Path) -> dict[int, float]:
    """{NORAD id: radius m} from a CSV with ``norad_id`` and ``radius_m`` columns (the
    hard-body radius of an event is the sum of both objects' radii)."""
    out: dict[int, float] = {}
    first: dict[int, int] = {}
    try:
        # utf-8-sig: a spreadsheet's byte-order mark is not part of the first column's name
        with open(path, newline="", encoding="utf-8-sig") as fh:
            rows = list(csv.DictReader(fh))
            names = set(rows[0]) if rows else set()
    except UnicodeDecodeError as err:
        raise ValueError(f"{path}: not UTF-8 text ({err.reason} at byte {err.start})") from None
    if not {"norad_id", "radius_m"} <= names:
        raise ValueError(f"{path}: needs columns norad_id and radius_m")
    for line, row in enumerate(rows, start=2):
        try:
            key, radius = int(row["norad_id"]), float(row["radius_m"])
        except (TypeError, ValueError) as err:
            raise ValueError(f"{path} line {line}: {err}") from err
        if not (np.isfinite(radius) and radius > 0):
            raise ValueError(f"{path} line {line}: radius_m must be > 0, got {radius}")
        if key in first:
            raise ValueError(
                f"{path} line {line}: NORAD id {key} repeats line {first[key]}; give each "
                "object one radius"
            )
        first[key] = line
        out[key] = radius
    return out


def _message(res: AllOnAllResult, n: int, created: np.datetime64) -> ConjunctionMessage:
    """Event ``n`` as a CDM: the screened states at TCA (TEME, the catalog's frame)
    rotated to EME2000 (GCRF axes: :func:`rhoprop.frames.convert`), the reference
    model's covariances in RTN (the same in either frame) and the mixture's Pc."""
    e = res.events[n]
    covs = (res.covariance1[n], res.covariance2[n])
    objs = []
    sides = ((e.state1, e.name1, e.id1, covs[0]), (e.state2, e.name2, e.id2, covs[1]))
    for teme, name, oid, cov in sides:
        state = frames.convert(e.tca, teme, "TEME", "EME2000")
        objs.append(
            CdmObject(
                name=name,
                designator="" if oid is None else str(oid),
                position=state[:3],
                velocity=state[3:],
                covariance=cov if np.isfinite(cov).all() else np.zeros((6, 6)),
            )
        )
    pcs = zip(res.models, res.pc_models[n], strict=True)
    per_model = ", ".join(f"{m} {p:.3g}" for m, p in pcs)
    return ConjunctionMessage(
        tca=e.tca,
        object1=objs[0],
        object2=objs[1],
        creation_date=created,
        miss_distance=e.miss_distance,
        relative_speed=e.relative_speed,
        collision_probability=float(res.pc[n]) if np.isfinite(res.pc[n]) else None,
        collision_probability_method=f"rhoprop mixture of density models ({per_model})"[:200],
        hard_body_radius=float(res.hard_body_radius[n]),
        message_id=f"rhoprop-{n + 1}",
    )


#: Mixture Pc from which ``rhoprop screen`` writes an event's CDM by default: the event
#: table holds every event; a message is for the events someone may act on. 1e-7 is below
#: every operator's manoeuvre threshold (NASA CARA's is 1e-4) with three decades to spare.
CDM_MIN_PC = 1e-7


def cdm_events(res: AllOnAllResult, min_pc: float | None) -> list[int]:
    """Indices of the events that get a CDM: those with mixture Pc >= ``min_pc`` (a Pc not
    computed, ``--no-pc``, is never above it); ``min_pc`` 0: every event; None: none."""
    if min_pc is None:
        return []
    _check_threshold(min_pc)
    if min_pc == 0:
        return list(range(len(res.events)))
    pc = np.asarray(res.pc, dtype=float)
    return [int(n) for n in np.flatnonzero(np.isfinite(pc) & (pc >= min_pc))]


def _check_threshold(min_pc: float | None) -> None:
    if min_pc is not None and not (np.isfinite(min_pc) and 0 <= min_pc <= 1):
        raise ValueError(f"the CDM threshold must be a probability in [0, 1], got {min_pc}")


def output_events(
    res: AllOnAllResult,
    folder: OutputFolder,
    cdm_min_pc: float | None = CDM_MIN_PC,
    table_format: TableFormat = "parquet",
) -> list[Path]:
    """``events.parquet`` (one row per event, :meth:`AllOnAllResult.table`; ``events.csv``
    with ``table_format="csv"``) and a KVN CDM
    in ``cdm/`` (``<rank>_<id1>_<id2>.cdm``, rank by mixture Pc) for each event of
    :func:`cdm_events` (mixture Pc >= ``cdm_min_pc``, default :data:`CDM_MIN_PC`; 0: every
    event; None: none). CDMs need ``ccsds-ndm``, the ``[cdm]`` extra: without it they are
    left out, said on stderr. Returns the paths written."""
    chosen = cdm_events(res, cdm_min_pc)
    name = table_name("events", table_format)
    written = [write_event_table(res.table(), folder, name, table_format)]
    if not chosen:
        return written
    try:
        from ..conjunction.cdm import cdm_text

        created = np.datetime64("now", "ns")
        (folder.directory / "cdm").mkdir(exist_ok=True)
        # Thousands of messages take tens of seconds: a log hears of it.
        bar = ProgressBar(len(chosen), "writing CDMs", unit="files")
        try:
            for k, n in enumerate(chosen):
                e = res.events[n]
                name = f"cdm/{n + 1:05d}_{e.id1}_{e.id2}.cdm"
                written.append(folder.write_text(name, cdm_text(_message(res, n, created))))
                bar(k + 1)
        finally:
            bar.close()
    except ImportError as err:
        print(f"CDMs not written: {err}", file=sys.stderr)
    return written


def _catalog(file: str | Path, skip_bad: bool) -> Catalog:
    cat = load(
        file,
        errors="record" if skip_bad else "raise",
        nonpositive_bstar="prior",
        far_orbits="skip" if skip_bad else "error",  # --strict stops at them too
    )
    for where, message in cat.skipped:
        print(f"skipped {sanitise(where)}: {sanitise(message, 300)}", file=sys.stderr)
    if len(cat) < 2:
        raise ValueError(f"{file}: fewer than two element sets could be read")
    return cat


@dataclass(frozen=True)
class ScreenJob:
    """Every element set of ``file`` screened against every other from ``start`` (default
    :func:`default_start`: the epoch 99 % of the element sets are not after) to ``end``
    (UTC ISO) within ``distance`` m through ``models`` (reference first); B* <= 0 objects
    load with an assumed Cd*A/m (``load(nonpositive_bstar="prior")``). Writes
    ``out/events.parquet`` (every event), ``out/cdm/`` (a CDM for each event with mixture
    Pc >= ``cdm_min_pc``: :func:`output_events`) and ``out/manifest.json``; prints the events
    with the largest mixture Pc, the filter counts and the time per stage;
    ``monte_carlo_events`` events of largest Pc also get the member Monte Carlo's Pc
    (``members`` members). ``max_span_days``: element sets further than that from the
    window are listed as skipped, not screened (0 or None: no limit). ``scheduler``: a
    Dask scheduler address, every stage runs there (:func:`screen_all`'s ``client``; the
    same events). ``table_format``: ``"parquet"`` (default) or ``"csv"``, the format of
    the event table. ``as_of`` (UTC ISO): every model's drivers as a forecaster had them
    then (default: the record as refreshed, observed and predicted). Returns the paths
    written."""

    file: str | Path
    out: str | Path
    end: str
    start: str | None = None
    distance: float = 5e3
    model: str = FAMILIES
    pc: bool = True
    hard_body_radius: float | None = None
    radii_file: str | Path | None = None
    monte_carlo_events: int = 0
    members: int = 200
    skip_bad: bool = True
    overwrite: bool = False
    command: str | None = None
    max_span_days: float | None = MAX_SPAN / 86400.0
    cdm_min_pc: float | None = CDM_MIN_PC
    scheduler: str | None = None
    table_format: TableFormat = "parquet"
    as_of: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "table_format", format_argument(self.table_format))

    def run(self) -> list[Path]:
        """Runs the job (see the class). Returns the paths written."""
        if self.scheduler:
            need_dask()
        span = max_span_option(self.max_span_days)
        _check_threshold(self.cdm_min_pc)  # before any work
        cat = _catalog(self.file, self.skip_bad)
        radii = read_radii(self.radii_file) if self.radii_file else None
        t0 = to_datetime64(self.start, "start") if self.start else default_start(cat)
        models = models_by_name(self.model, self.as_of)  # a bad as_of fails before the folder
        print_as_of_note(cat, self.as_of)
        folder = OutputFolder(
            self.out, command=self.command or command_line(), overwrite=self.overwrite
        )
        client = connect(self.scheduler)
        try:
            res = screen_all(
                cat,
                models,
                start=t0,
                end=to_datetime64(self.end, "end"),
                distance=self.distance,
                pc=PcSettings(
                    hard_body_radius=self.hard_body_radius,
                    radii=radii,
                    monte_carlo_events=self.monte_carlo_events,
                    members=self.members,
                )
                if self.pc
                else False,
                search=Search(max_span=span),
                execution=Execution(client=client, errors="record" if self.skip_bad else "raise"),
            )
        finally:
            if client is not None:
                client.close()
        written = output_events(res, folder, self.cdm_min_pc, self.table_format)
        manifest = folder.finish()
        _report(res)
        rule = "none asked" if self.cdm_min_pc is None else f"events with Pc >= {self.cdm_min_pc:g}"
        print(f"wrote {written[0]}, {len(written) - 1} CDM file(s) ({rule}) and {manifest}")
        return [*written, manifest]


def _report(res: AllOnAllResult) -> None:
    for name, why in res.skipped:
        print(f"skipped {sanitise(name)}: {sanitise(why, 200)}", file=sys.stderr)
    print(f"{'TCA (UTC)':29} {'object 1':24} {'object 2':24} {'miss m':>8} {'Pc':>9}")
    for n, e in enumerate(res.events[:PRINTED]):
        mc = res.pc_monte_carlo[n]
        print(
            f"{str(e.tca)[:29]:29} {sanitise(e.name1, 24):24} {sanitise(e.name2, 24):24} "
            f"{e.miss_distance:8.0f} {res.pc[n]:9.2g}"
            + (f"  (Monte Carlo {mc:.2g})" if np.isfinite(mc) else "")
        )
    counts = ", ".join(f"{k} {v:,}" for k, v in res.counts.items())
    stages = ", ".join(f"{k} {v:.1f} s" for k, v in res.timings.items())
    print(f"{len(res.events)} events within {res.distance:g} m, {res.start} to {res.end}")
    print(f"models: {', '.join(res.models)} (weights {np.round(res.weights, 3).tolist()})")
    print(f"counts: {counts}")
    print(f"stages: {stages}; {res.wall:.1f} s on {res.threads} threads")
