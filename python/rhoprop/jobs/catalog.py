"""The ``rhoprop catalog`` job: a TLE/OMM file propagated to a common end epoch, written
as CCSDS OEM files and a Parquet summary."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ..catalog.covariance import COVARIANCE_NAMES
from ..catalog.elements import Catalog, FitSettings, load
from ..catalog.objects import Initial
from ..catalog.run import (
    MAX_SPAN,
    STATUSES,
    CatalogResult,
    beyond_max_span,
    propagate_catalog,
)
from ..execution import Execution
from ..io import (
    OutputFolder,
    command_line,
    duplicate_ids,
    oem_names,
    sanitise,
    table_name,
    write_ephemeris,
    write_oem,
    write_summary,
)
from ..io.tables import format_argument, meta_path, write_folder_table
from ..options import Duplicates, TableFormat
from ..propagation import Dynamics
from ..propagation.methods import Ccsp, Method, MonteCarlo
from ..propagation.montecarlo import drag_sigma_argument
from ..spaceweather import SpaceWeather
from ..time import seconds_between, to_datetime64
from .models import as_of_note, model_by_name


#: Density models by the names the command line accepts.
def initial_covariance_option(value: str | None) -> Any:
    """The ``--initial-covariance`` value: None, a name (``object``, ``tle``, ``paper``)
    or the path of a text file with a 6x6 inertial covariance (m^2, m^2/s, m^2/s^2)."""
    if value is None or value in COVARIANCE_NAMES:
        return value
    path = Path(value)
    if not path.is_file():
        raise ValueError(
            f"--initial-covariance must be one of {', '.join(COVARIANCE_NAMES)} or a file "
            f"with a 6x6 matrix, got {value!r}"
        )
    try:
        matrix = np.loadtxt(path, ndmin=2)
    except (ValueError, UnicodeDecodeError) as err:
        raise ValueError(f"{path}: not a 6x6 matrix of numbers ({err})") from None
    if matrix.shape != (6, 6):
        raise ValueError(f"{path}: a 6x6 covariance matrix is needed, got {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise ValueError(f"{path}: the covariance has NaN or infinite entries")
    if not np.allclose(matrix, matrix.T, rtol=1e-9, atol=0.0):
        raise ValueError(f"{path}: the covariance is not symmetric")
    try:
        np.linalg.cholesky(matrix)
    except np.linalg.LinAlgError:
        raise ValueError(f"{path}: the covariance is not positive definite") from None
    return matrix


def refresh_data(timeout: float = 60.0) -> list[str]:
    """Downloads the current space-weather record (CelesTrak ``SW-All.csv``) and the
    JB2008 index files (SET's ``SOLFSMY.TXT`` and ``DTCFILE.TXT``) into the user cache;
    returns one line per source saying what was stored (or why not)."""
    from ..cache import cache_dir
    from ..spaceweather import DEFAULT_URL

    lines = []
    try:
        sw = SpaceWeather.refresh(timeout=timeout)
    except OSError as err:
        raise OSError(
            f"space-weather refresh from {DEFAULT_URL} failed ({err}); offline, download "
            f"SW-All.csv elsewhere and copy it to {cache_dir()}/SW-All.csv, or pass its "
            "path to rhoprop.SpaceWeather(path)"
        ) from err
    lines.append(f"space weather: {sw.source} (observed to {sw.observed_end})")
    try:
        from ..density import Jb2008Indices
    except ImportError:  # pragma: no cover - JB2008 not present in this build
        lines.append("JB2008 indices: this rhoprop has no JB2008 model; nothing to refresh")
    else:
        try:
            jb = Jb2008Indices.refresh(timeout=timeout)
        except OSError as err:
            raise OSError(
                f"space weather refreshed, but the JB2008 index download failed ({err}); "
                "offline, put SOLFSMY.TXT and DTCFILE.TXT in a directory named by "
                "$RHOPROP_JB2008_DATA"
            ) from err
        lines.append(f"JB2008 indices: {jb}")
    return lines


def connect(scheduler: str | None) -> Any:
    """A Dask ``Client`` of ``scheduler`` (checked by :func:`need_dask`), or None."""
    if not scheduler:
        return None
    from distributed import Client

    return Client(scheduler)


def need_dask() -> None:
    """ImportError in one line when the ``distributed`` extra is missing."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise ImportError("--scheduler needs Dask: pip install 'dask[distributed]'") from None


#: Default drag coefficient for a drag file that gives area-to-mass ratios.
DRAG_FILE_CD = 2.2


def read_drag_file(path: str | Path, cd: float | None = None) -> dict[int, float]:
    """{NORAD id: Cd*A/m (m^2/kg)} from a CSV with a header: ``norad_id`` and either
    ``drag_parameter`` (Cd*A/m, m^2/kg) or ``area_to_mass`` (A/m, m^2/kg, multiplied by
    ``cd``, default :data:`DRAG_FILE_CD`). ValueError naming the file, line and column
    for anything else."""
    import csv

    p = Path(path)
    if not p.is_file():
        raise ValueError(f"drag file {str(p)!r} does not exist")
    try:
        # utf-8-sig: a spreadsheet's byte-order mark is not part of the first column's name
        with p.open(newline="", encoding="utf-8-sig") as handle:
            rows = list(csv.DictReader(handle))
    except UnicodeDecodeError as err:
        raise ValueError(f"{p.name}: not UTF-8 text ({err.reason} at byte {err.start})") from None
    columns = set(rows[0]) if rows else set()
    if "norad_id" not in columns or not ({"drag_parameter", "area_to_mass"} & columns):
        raise ValueError(
            f"{p.name}: expected a header with norad_id and drag_parameter or area_to_mass, "
            f"got {sorted(columns)}"
        )
    if {"drag_parameter", "area_to_mass"} <= columns:
        raise ValueError(
            f"{p.name}: give drag_parameter (Cd*A/m) or area_to_mass (A/m, times --cd), not both"
        )
    kind = "drag_parameter" if "drag_parameter" in columns else "area_to_mass"
    if kind == "drag_parameter" and cd is not None:
        raise ValueError(f"{p.name} gives drag_parameter (Cd*A/m): --cd does not apply")
    factor = 1.0 if kind == "drag_parameter" else (DRAG_FILE_CD if cd is None else float(cd))
    if not factor > 0:
        raise ValueError(f"cd must be > 0, got {cd}")
    out: dict[int, float] = {}
    for line, row in enumerate(rows, start=2):
        try:
            norad = int(row["norad_id"])
            value = float(row[kind])
        except (TypeError, ValueError):
            raise ValueError(
                f"{p.name} line {line}: norad_id must be an integer and {kind} a number, "
                f"got {row.get('norad_id')!r}, {row.get(kind)!r}"
            ) from None
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{p.name} line {line}: {kind} must be > 0, got {value}")
        if norad in out:
            raise ValueError(f"{p.name} line {line}: NORAD id {norad} appears twice")
        out[norad] = value * factor
    return out


def _load(file: str | Path, skip_bad: bool, **options: Any) -> Catalog:
    """``load`` of a command's file: without ``skip_bad`` the first unusable element set
    stops the command, its error saying how to go on (``--skip-bad``)."""
    if skip_bad:
        return load(file, errors="record", **options)
    try:
        return load(file, errors="raise", **options)
    except ValueError as err:
        raise ValueError(
            f"{err} (--skip-bad skips such element sets, lists them and goes on)"
        ) from err


#: The default start of ``rhoprop screen`` and ``rhoprop catalog`` is the epoch this
#: fraction of the element sets is not after: the newest epoch itself would let one
#: element set dated days ahead (the 2023-07-04 snapshot holds one of 2023-07-07) move the
#: whole window. The few later ones are propagated back to it by the screen; a catalog
#: run leaves their outputs before their epoch invalid.
START_QUANTILE = 0.99


def default_start(cat: Catalog) -> np.datetime64:
    """The default start of ``rhoprop screen`` and ``rhoprop catalog``: the
    :data:`START_QUANTILE` quantile of the element sets' epochs (UTC)."""
    epochs = np.sort(np.array([o.state.epoch for o in cat], dtype="datetime64[ns]"))
    return np.datetime64(epochs[int(START_QUANTILE * (len(epochs) - 1))], "ns")


@dataclass(frozen=True)
class CatalogJob:
    """Propagates every element set of ``file`` to ``end`` (UTC ISO) and writes the
    catalog's ephemeris to ``out/ephemeris.parquet`` (:func:`~rhoprop.io.write_ephemeris`:
    every object's mean and covariance, one row per object and epoch), with ``oem`` also
    one OEM file per object to ``out/oem``, ``out/summary.parquet`` (one row per object
    with its status) and ``out/manifest.json``; ``scheduler`` is a Dask scheduler address (needs
    the ``distributed`` extra).

    ``skip_bad``: malformed element sets are skipped and objects whose propagation fails
    get status "failed" (both on stderr). ``overwrite``: clear ``out`` of an earlier run.
    ``duplicates``: a NORAD id given several times is one object, the newest element set
    (``"newest"``) or the newest fitted with the others of its last day (``"fit"``:
    ``load(history="fit")``; not with ``fit=False``), an error before any work or objects
    with suffixed OEM names (``"suffix"``). ``fit``: "auto" (default) fits the objects
    with B* (``propagate_catalog(fit="auto")``), True every object (``load(fit=True)``),
    False none. ``initial_covariance``:
    :func:`initial_covariance_option` (default: each object's own, the TLE accuracy, plus
    the fit's with ``fit``). ``zonal_degree``: 2 (J2 only) to 6 (J2..J6), default 4 (J2..J4).
    ``method``: :class:`~rhoprop.Ccsp` (default) or :class:`~rhoprop.MonteCarlo` with
    its settings (object i seeded ``seed + i``). ``drag_file``/``cd``: per-object drag
    (:func:`read_drag_file`).
    ``drag_sigma``: "auto" or a number (or its text), see ``propagate_catalog``.
    ``max_span_days``: objects with an epoch more days before ``end`` end "stale", not
    run (``propagate_catalog``'s ``max_span``; 0 or None: no limit). ``frame``: the OEM
    ephemeris's frame and the OEM files' REF_FRAME, "TEME" (default, as computed) or
    "GCRF"/"EME2000" (rotated,
    :func:`~rhoprop.io.write_oem`). ``start``: the first output epoch at or after it
    (UTC ISO; default :func:`default_start`, the epoch 99 % of the element sets are not
    after: the newer few have no valid output before their epoch). ``table_format``:
    ``"parquet"`` (default) or ``"csv"``, the format of the ephemeris and the summary
    (``ephemeris.csv``, ``summary.csv``; the ephemeris's metadata then in
    ``ephemeris.meta.json``). ``as_of`` (UTC ISO): the space weather as a forecaster had
    it then (:func:`~rhoprop.jobs.models.record_as_of`; default: the record as refreshed,
    observed and predicted). Returns the paths written."""

    file: str | Path
    end: str
    out: str | Path
    method: Method = Ccsp()
    model: str = "2.1"
    output_step: float = 3600.0
    scheduler: str | None = None
    skip_bad: bool = False
    overwrite: bool = False
    duplicates: Duplicates | Literal["newest", "fit"] = "newest"
    command: str | None = None
    fit: bool | Literal["auto"] = "auto"
    initial_covariance: str | None = None
    zonal_degree: int = 4
    drag_file: str | Path | None = None
    cd: float | None = None
    drag_sigma: str | float = "auto"
    max_span_days: float | None = MAX_SPAN / 86400.0
    frame: str = "TEME"
    start: str | None = None
    oem: bool = False
    table_format: TableFormat = "parquet"
    as_of: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "table_format", format_argument(self.table_format))

    def run(self) -> list[Path]:
        """Runs the job (see the class). Returns the paths written."""
        covariance = initial_covariance_option(self.initial_covariance or "object")
        sigma = _drag_sigma_option(self.drag_sigma)
        drag = read_drag_file(self.drag_file, self.cd) if self.drag_file is not None else None
        if self.drag_file is None and self.cd is not None:
            raise ValueError("--cd applies to a --drag-file with an area_to_mass column")
        if self.scheduler:
            need_dask()
        together = self.duplicates == "fit"
        if together and self.fit is False:
            raise ValueError("--duplicates fit fits each object's element sets: not with --no-fit")
        atmosphere = model_by_name(self.model, self.as_of)
        cat = _load(
            self.file,
            self.skip_bad,
            fit=FitSettings(atmosphere, dynamics=Dynamics(zonal_degree=self.zonal_degree))
            if self.fit is True or together
            else False,
            drag_parameters=drag,
            history={"newest": "newest", "fit": "fit"}.get(self.duplicates, "each"),
        )
        for where, message in cat.skipped:
            print(f"skipped {sanitise(where)}: {sanitise(message, 300)}", file=sys.stderr)
        if not len(cat):
            raise ValueError(
                f"{self.file}: no element set could be read ({len(cat.skipped)} skipped)"
            )
        print_as_of_note(cat, self.as_of)
        if drag is not None:
            unused = sorted(set(drag) - {o.norad_id for o in cat.objects})
            if unused:
                shown = ", ".join(str(n) for n in unused[:10]) + (
                    " ..." if len(unused) > 10 else ""
                )
                print(
                    f"note: {len(unused)} NORAD ids of {self.drag_file} are not in "
                    f"{self.file} (not used): {shown}",
                    file=sys.stderr,
                )
        # none left after "newest" or "fit"
        kind: Duplicates = "suffix" if self.duplicates == "suffix" else "error"
        _refuse_all_stale(cat, self.end, max_span_option(self.max_span_days))
        twice = duplicate_ids(cat.objects)
        if kind == "error" and not self.oem and twice:
            shown = ", ".join(map(str, twice[:10])) + (" ..." if len(twice) > 10 else "")
            raise ValueError(
                f"NORAD ids {shown} occur more than once in {self.file} (--duplicates "
                "error); --duplicates newest keeps each id's newest element set, suffix "
                "runs them all"
            )
        oem_names(cat.objects, kind)  # repeated ids fail here, before any work
        folder = OutputFolder(
            self.out, command=self.command or command_line(), overwrite=self.overwrite
        )
        client = connect(self.scheduler)
        t0 = time.perf_counter()
        result = propagate_catalog(
            cat,
            atmosphere,
            self.end,
            method=self.method,
            output_step=self.output_step,
            initial=Initial(
                covariance=covariance,
                drag_sigma=sigma,
                fit="auto" if self.fit == "auto" else False,
            ),
            dynamics=Dynamics(zonal_degree=self.zonal_degree),
            max_span=max_span_option(self.max_span_days),
            execution=Execution(client=client, errors="record" if self.skip_bad else "raise"),
            start=to_datetime64(self.start, "--start") if self.start else default_start(cat),
        )
        wall = time.perf_counter() - t0
        ephemeris, meta, paths, summary = _write_catalog_tables(
            result, folder, self.frame, self.table_format, kind if self.oem else None
        )
        manifest = folder.finish()
        counts = {s: int(np.count_nonzero(result.status == s)) for s in STATUSES}
        for obj, status, reason in zip(result.objects, result.status, result.reason, strict=True):
            if status not in ("propagated", "non_gaussian"):  # those two: counted below
                print(
                    f"{obj.norad_id} {sanitise(obj.name)}: {status}: {sanitise(reason, 300)}",
                    file=sys.stderr,
                )
        print(
            f"{len(cat)} objects ({len(cat.skipped)} skipped), {self.method.name}, "
            f"{_iso(result.epochs[0])} to {_iso(result.epochs[-1])}: "
            f"{wall:.1f} s ({len(cat) / wall:.1f} objects/s); "
            + ", ".join(f"{v} {k}" for k, v in counts.items())
        )
        no_data = len(cat) - int(np.count_nonzero(np.asarray(result.valid).any(axis=1)))
        print(
            f"wrote {ephemeris}"
            + (f" (its metadata in {meta[0].name})" if meta else "")
            + (f", {len(paths)} OEM files to {folder.directory / 'oem'}" if self.oem else "")
            + (f" ({no_data} objects without a valid epoch have no ephemeris)" if no_data else "")
            + f", {summary} and {manifest}"
        )
        print(atlas_line())
        return [ephemeris, *meta, *paths, summary, manifest]


def print_as_of_note(cat: Catalog, as_of: str | None) -> None:
    """Says on stderr when element sets are newer than ``--as-of`` (:func:`as_of_note`)."""
    note = as_of_note([o.state.epoch for o in cat.objects], as_of)
    if note:
        print(note, file=sys.stderr)


def _write_catalog_tables(
    result: CatalogResult,
    folder: OutputFolder,
    frame: str,
    table_format: TableFormat,
    oem: Duplicates | None,
) -> tuple[Path, list[Path], list[Path], Path]:
    """The ephemeris (and, for a CSV, its metadata), the OEM files (``oem``: how
    repeated ids are named; None: no OEM) and the summary of a catalog run, in
    ``folder``: (ephemeris, [metadata], OEM paths, summary)."""
    directory = folder.directory
    # Announced before they are written, so that an interrupted run's files are its own.
    ephemeris = directory / table_name("ephemeris", table_format)
    summary_path = directory / table_name("summary", table_format)
    meta = [meta_path(ephemeris)] if table_format == "csv" else []
    folder.expect([ephemeris, *meta, summary_path])
    if oem is not None:
        folder.expect([directory / "oem" / n for n in oem_names(result.objects, oem)])
    folder.add([write_ephemeris(result, ephemeris, frame=frame, fmt=table_format), *meta])
    paths = write_oem(result, directory / "oem", duplicates=oem, ref_frame=frame) if oem else []
    folder.add(paths)
    summary = write_summary(result, summary_path, table_format)
    folder.add([summary])
    return ephemeris, meta, paths, summary


def _refuse_all_stale(cat: Catalog, end: Any, limit: float | None) -> None:
    """ValueError, before any output, when every element set is too far from ``end`` to
    run (an empty ephemeris and exit 0 told a user nothing ran only in the summary)."""
    end64 = to_datetime64(end, "--end")
    reasons = [beyond_max_span(seconds_between(o.state.epoch, end64), "end", limit) for o in cat]
    if reasons and all(reasons):
        raise ValueError(
            f"no element set of {len(reasons)} can be run to {end}: the first's {reasons[0]}"
        )


def _drag_sigma_option(drag_sigma: str | float) -> float | Literal["auto"]:
    """``--drag-sigma``: "auto" or a number (its text)."""
    if isinstance(drag_sigma, str) and drag_sigma == "auto":
        return "auto"
    try:
        value = float(drag_sigma)
    except ValueError:
        msg = f"--drag-sigma must be 'auto' or a number, got {drag_sigma!r}"
        raise ValueError(msg) from None
    try:
        return drag_sigma_argument(value)
    except ValueError as err:
        raise ValueError(f"--drag-sigma: {err}") from None


def _iso(t: np.datetime64) -> str:
    return str(t.astype("datetime64[s]")) + "Z"


def max_span_option(days: float | None) -> float | None:
    """``--max-span DAYS`` as ``max_span`` seconds (0 or None: None, no limit)."""
    if days is not None and not days >= 0:
        raise ValueError(f"--max-span must be a number of days >= 0, got {days}")
    return days * 86400.0 if days else None


def atlas_line() -> str:
    """The density atlas's peak memory, for the end of a long run."""
    from ..density import field_memory

    m = field_memory()
    return (
        f"density atlas: peak {m.peak / 1e6:.0f} MB of day tiles in memory "
        f"(budget {m.budget / 1e6:.0f} MB, $RHOPROP_FIELD_MEMORY)"
    )


@dataclass(frozen=True)
class ReentryJob:
    """Reentry windows (:func:`~rhoprop.catalog.reentry.reentry`) of every element set of
    ``file`` within ``horizon_days`` of its epoch: printed as a table and written to
    ``out/reentry.csv`` (one row per object: NORAD id, name, 2.5 %, median and 97.5 %
    decay epochs in UTC, empty beyond the horizon, decayed fraction, Cd*A/m and its
    relative sigma, whether it was fitted and the fit's RMS residual) with
    ``out/manifest.json``. ``fit`` (default True): states and Cd*A/m fitted to the element
    sets first; ``history``: for an object given several times, "auto" (default) is "fit"
    with ``fit`` and "newest" without, "newest" predicts from its newest element set,
    "fit" from it fitted together with the earlier ones, "each" from every one
    (:func:`~rhoprop.catalog.reentry`). ``table_format``: ``"csv"`` (default, the epochs
    as ISO text) or ``"parquet"`` (``out/reentry.parquet``, the columns of
    :meth:`~rhoprop.catalog.ReentryResult.table`: epochs typed, NaT beyond the horizon).
    ``as_of`` (UTC ISO): the space weather as a forecaster had it then (default: the
    record as refreshed). Returns the paths written."""

    file: str | Path
    out: str | Path
    horizon_days: float = 30.0
    members: int = 100
    model: str = "2.1"
    fit: bool = True
    history: str = "auto"
    drag_sigma: float | None = None
    skip_bad: bool = False
    overwrite: bool = False
    command: str | None = None
    table_format: TableFormat = "csv"
    as_of: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "table_format", format_argument(self.table_format))

    def run(self) -> list[Path]:
        """Runs the job (see the class). Returns the paths written."""
        import csv
        import io

        from ..catalog.reentry_windows import MAX_DURATION, reentry, resolved_history

        if not 0 < self.horizon_days <= MAX_DURATION / 86400:
            raise ValueError(
                f"--horizon must lie in 0-{MAX_DURATION / 86400:g} days, got {self.horizon_days:g}"
            )
        atmosphere = model_by_name(self.model, self.as_of)
        # reentry() itself predicts a self.history once (history="newest") or each element set
        cat = _load(self.file, self.skip_bad, history="each")
        for where, message in cat.skipped:
            print(f"skipped {sanitise(where)}: {sanitise(message, 300)}", file=sys.stderr)
        if not len(cat):
            raise ValueError(
                f"{self.file}: no element set could be read ({len(cat.skipped)} skipped)"
            )
        print_as_of_note(cat, self.as_of)
        folder = OutputFolder(
            self.out, command=self.command or command_line(), overwrite=self.overwrite
        )
        t0 = time.perf_counter()
        result = reentry(
            cat,
            atmosphere,
            method=MonteCarlo(n=self.members),
            duration=self.horizon_days * 86400.0,
            drag_sigma=self.drag_sigma,
            fit=self.fit,
            history=self.history,
        )
        wall = time.perf_counter() - t0
        rows = result.rows()
        if self.table_format == "csv":
            # The epochs as ISO strings ending in Z, "" beyond the horizon (as printed).
            buffer = io.StringIO()
            writer = csv.DictWriter(buffer, fieldnames=list(rows[0]))
            writer.writeheader()
            for row in rows:
                writer.writerow({**row, "name": sanitise(row["name"])})
            path = folder.write_text("reentry.csv", buffer.getvalue())
        else:  # typed columns: datetime64 UTC epochs, NaT beyond the horizon
            path = write_folder_table(result.table(), folder, "reentry.parquet", self.table_format)
        manifest = folder.finish()
        print(f"{'NORAD':>6} {'name':24} {'2.5 %':20} {'median':20} {'97.5 %':20} decayed  state")
        for row in rows:
            how = f"fitted ({row['fit_rms_m']:.0f} m RMS)" if row["fitted"] else "B*"
            print(
                f"{row['norad_id']:>6} {sanitise(row['name'], 24):24} "
                f"{row['epoch_q025'] or '-':20} {row['epoch_median'] or '-':20} "
                f"{row['epoch_q975'] or '-':20} {100 * row['decayed_fraction']:5.1f} %  {how}"
            )
            if row["fit_note"]:
                print(f"       {sanitise(row['fit_note'], 200)}", file=sys.stderr)
            if row["element_sets"] > 1:
                which = {"newest": "the newest predicted", "fit": "fitted together"}.get(
                    resolved_history(self.history, self.fit), "each predicted"
                )
                print(f"       {row['element_sets']} element sets of this object: {which}")
        sets = f" ({len(cat)} element sets)" if len(cat) != len(rows) else ""
        print(
            f"{len(rows)} objects{sets}, {result.members} members each, "
            f"horizon {self.horizon_days:g} days: "
            f"{wall:.1f} s; wrote {path} and {manifest}"
        )
        print(atlas_line())
        return [path, manifest]
