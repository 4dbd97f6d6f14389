"""Output files: CCSDS OEM (KVN, version 2.0 per CCSDS 502.0-B-3, with covariance
blocks), a columnar Parquet summary of per-object statistics, and the output folder of a
run (:class:`OutputFolder`: every file written to a temporary name and renamed, a
``manifest.json`` of what the run produced, and no mixing with another run's files).

Text copied from inputs into outputs (object names, ids, originator) is sanitised: only
printable ASCII survives, anything else (newlines, control characters) becomes ``_``."""

from __future__ import annotations

import contextlib
import datetime as _dt
import json
import os
import shutil
import sys
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..propagation import CcspResult, MonteCarloResult, Trajectory
from ..propagation.results import rtn_basis

#: The manifest every run writes into its output folder.
MANIFEST = "manifest.json"
#: What ``duplicates`` of :func:`write_oem` accepts.
DUPLICATES = ("error", "suffix")


def sanitise(text: object, limit: int = 100) -> str:
    """``text`` as one line of printable ASCII (other characters become ``_``), stripped
    and cut to ``limit`` characters: safe to copy into a KVN header or a Markdown
    table."""
    clean = "".join(c if " " <= c <= "~" else "_" for c in str(text)).strip()
    return clean[:limit]


def _iso(t: np.datetime64) -> str:
    return str(t.astype("datetime64[us]"))


def _temporary(path: Path) -> Path:
    """A temporary name beside ``path`` with the same suffix (writers such as matplotlib
    pick the format from it), unique per process and thread."""
    return path.with_name(f".{path.stem}.tmp{os.getpid()}-{id(path):x}{path.suffix}")


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yields a temporary path to write ``path`` to; renamed onto ``path`` when the block
    ends without error, removed otherwise: a reader never sees a half-written file."""
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary(final)
    try:
        yield tmp
        os.replace(tmp, final)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Writes ``text`` to ``path`` through a temporary file and a rename."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


class OutputFolder:
    """The output folder of one run (``rhoprop paper``, ``run``, ``catalog``).

    On creation it claims ``directory``: a missing or empty folder is used; a folder
    holding a previous run's files (it has a ``manifest.json``) is refused, or with
    ``overwrite=True`` emptied first; a non-empty folder without a manifest is always
    refused (rhoprop deletes only what a run of its own wrote). A manifest marked
    incomplete is written at once, so an interrupted run's folder is recognised too (a
    folder holding only the manifest of a run that wrote nothing is reused as empty).
    Files go through :meth:`path` (a temporary name, renamed when done) and are listed
    in the manifest by :meth:`finish`, with the rhoprop version and the command.
    """

    def __init__(self, directory: str | Path, *, command: str, overwrite: bool = False) -> None:
        self.directory = Path(directory)
        self.command = command
        self.files: list[Path] = []
        self.started = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        if self.directory.exists() and not self.directory.is_dir():
            raise NotADirectoryError(f"output folder {self.directory} is a file")
        entries = sorted(self.directory.iterdir()) if self.directory.exists() else []
        if entries == [self.directory / MANIFEST] and not _produced(entries[0]):
            entries = []  # a run that stopped before it wrote anything: reuse quietly
        if entries:
            names = ", ".join(p.name for p in entries[:5]) + (", ..." if len(entries) > 5 else "")
            if not (self.directory / MANIFEST).is_file():
                raise FileExistsError(
                    f"output folder {self.directory} is not empty ({names}) and holds no "
                    f"{MANIFEST} of an earlier rhoprop run; choose an empty or new folder"
                )
            if not overwrite:
                raise FileExistsError(
                    f"output folder {self.directory} holds the files of an earlier run "
                    f"({names}); choose another folder or overwrite it (--overwrite on the "
                    "command line, overwrite=True in Python)"
                )
            for entry in entries:
                if entry.is_dir() and not entry.is_symlink():
                    shutil.rmtree(entry)
                else:
                    entry.unlink()
        self.directory.mkdir(parents=True, exist_ok=True)
        self._write_manifest(complete=False)

    def _write_manifest(self, complete: bool) -> None:
        manifest = {
            "rhoprop_version": __version__,
            "command": self.command,
            "started": self.started,
            "complete": complete,
            "files": [p.relative_to(self.directory).as_posix() for p in self.files],
        }
        if complete:
            manifest["finished"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        write_text_atomic(self.directory / MANIFEST, json.dumps(manifest, indent=2) + "\n")

    @contextlib.contextmanager
    def path(self, name: str | Path) -> Iterator[Path]:
        """A temporary path for the file ``name`` (relative to the folder), renamed to it
        when the block ends without error and then listed in the manifest."""
        final = self.directory / name
        with atomic_path(final) as tmp:
            yield tmp
        self.files.append(final)

    def write_text(self, name: str | Path, text: str) -> Path:
        """Writes a text file of the run."""
        with self.path(name) as tmp:
            tmp.write_text(text)
        return self.directory / name

    def add(self, paths: list[Path]) -> None:
        """Lists files a writer already put (atomically) into the folder."""
        self.files.extend(Path(p) for p in paths)

    def finish(self) -> Path:
        """Writes the complete manifest; returns its path."""
        self._write_manifest(complete=True)
        return self.directory / MANIFEST


def _produced(manifest: Path) -> bool:
    """Whether a manifest says its run completed or wrote files (unreadable: assume so)."""
    try:
        data = json.loads(manifest.read_text())
        return bool(data.get("complete")) or bool(data.get("files"))
    except (OSError, ValueError, AttributeError):
        return True


def command_line() -> str:
    """The command that runs now, as the manifest records it."""
    return " ".join(["rhoprop", *sys.argv[1:]]) if sys.argv else "rhoprop"


def duplicate_ids(objects: list[Any]) -> list[int]:
    """NORAD ids that more than one of ``objects`` carries, sorted."""
    counts = Counter(o.norad_id for o in objects)
    return sorted(i for i, c in counts.items() if c > 1)


def oem_names(objects: list[Any], duplicates: str = "error") -> list[str]:
    """OEM file names per object: ``<NORAD id>.oem``; a repeated id is an error naming
    it (``duplicates="error"``) or gets ``_2``, ``_3``, ... in input order
    (``duplicates="suffix"``)."""
    if duplicates not in DUPLICATES:
        raise ValueError(f"duplicates must be 'error' or 'suffix', got {duplicates!r}")
    twice = duplicate_ids(objects)
    if twice and duplicates == "error":
        shown = ", ".join(map(str, twice[:10])) + (", ..." if len(twice) > 10 else "")
        raise ValueError(
            f"NORAD ids {shown} occur more than once in the catalog, so their OEM files "
            "would overwrite each other; remove the repeats or use duplicates='suffix' "
            "(--duplicates suffix)"
        )
    seen: Counter[int] = Counter()
    names = []
    for o in objects:
        seen[o.norad_id] += 1
        k = seen[o.norad_id]
        names.append(f"{o.norad_id}.oem" if k == 1 else f"{o.norad_id}_{k}.oem")
    return names


def _oem_text(
    name: str,
    object_id: str,
    ref_frame: str,
    originator: str,
    epochs: np.ndarray,
    mean: np.ndarray,
    covariance: np.ndarray | None,
    note: str = "",
    *,
    cov_frame: str | None = None,
) -> str:
    """One OEM segment: states in km and km/s, covariances in km^2, km^2/s, km^2/s^2;
    ``note`` (what the covariance includes) becomes COMMENT lines of the covariance
    section."""
    created = _dt.datetime.now(_dt.timezone.utc).replace(tzinfo=None).isoformat(timespec="seconds")
    frame = sanitise(ref_frame)
    lines = [
        "CCSDS_OEM_VERS = 2.0",
        f"CREATION_DATE = {created}",
        f"ORIGINATOR = {sanitise(originator)}",
        "",
        "META_START",
        f"OBJECT_NAME = {sanitise(name) or 'UNKNOWN'}",
        f"OBJECT_ID = {sanitise(object_id) or 'UNKNOWN'}",
        "CENTER_NAME = EARTH",
        f"REF_FRAME = {frame}",
        "TIME_SYSTEM = UTC",
        f"START_TIME = {_iso(epochs[0])}",
        f"STOP_TIME = {_iso(epochs[-1])}",
        "META_STOP",
        "",
    ]
    for t, s in zip(epochs, mean / 1e3, strict=True):
        lines.append(f"{_iso(t)} " + " ".join(f"{v:.9e}" for v in s))
    if covariance is not None:
        lines += ["", "COVARIANCE_START"]
        lines += [f"COMMENT {chunk}" for chunk in _wrap(sanitise(note, 2000))]
        for t, c in zip(epochs, covariance / 1e6, strict=True):
            lines += [f"EPOCH = {_iso(t)}", f"COV_REF_FRAME = {cov_frame or frame}"]
            for row in range(6):
                lines.append(" ".join(f"{c[row, col]:.9e}" for col in range(row + 1)))
        lines += ["COVARIANCE_STOP"]
    lines.append("")
    return "\n".join(lines)


def _wrap(text: str, width: int = 70) -> list[str]:
    """``text`` in lines of at most about ``width`` characters (none when empty)."""
    import textwrap

    return textwrap.wrap(text, width) if text else []


#: REF_FRAME values write_oem accepts: TEME for SGP4-derived catalog states, and the
#: inertial frames rhoprop's states are taken in (EME2000/J2000, GCRF, ICRF).
OEM_FRAMES = ("TEME", "EME2000", "GCRF", "ICRF")
#: Frames of the covariance blocks: the states' own frame, or each state's RTN.
COVARIANCE_FRAMES = ("inertial", "rtn")


def _rtn_covariances(mean: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """6x6 covariances rotated into the RTN frame of each mean state (R = r/|r|,
    N = r x v/|r x v|, T = N x R; position and velocity rotated alike, no omega x r term,
    as CDMs do)."""
    from ..frames import rtn_basis

    basis = rtn_basis(mean[:, :3], mean[:, 3:])  # (n, 3, 3), rows R, T, N
    big = np.zeros((len(mean), 6, 6))
    big[:, :3, :3] = basis
    big[:, 3:, 3:] = basis
    return np.asarray(np.einsum("nij,njk,nlk->nil", big, covariance, big))


def _save_oem(path: Path, text: str, file_format: str) -> Path:
    """Validates ``text`` with the ``oem`` library (CCSDS OEM 2.0) and writes it as KVN
    (the text itself, comments kept) or as XML (the library's writer), atomically."""
    from oem import OrbitEphemerisMessage

    with atomic_path(path) as tmp:
        kvn = tmp.with_name(tmp.name + ".kvn")
        try:
            kvn.write_text(text)
            try:
                message = OrbitEphemerisMessage.open(str(kvn))
            except Exception as err:  # the library raises plain exceptions on bad files
                raise ValueError(f"OEM for {path.name} failed validation: {err}") from err
            if file_format == "kvn":
                kvn.replace(tmp)
            else:
                message.save_as(str(tmp), file_format="xml")
        finally:
            with contextlib.suppress(FileNotFoundError):
                kvn.unlink()
    return path


def write_oem(
    result: Any,
    directory: str | Path,
    *,
    originator: str = "rhoprop",
    duplicates: str = "error",
    object_name: str = "OBJECT",
    object_id: str = "OBJECT",
    ref_frame: str | None = None,
    covariance_frame: str = "inertial",
    file_format: str = "kvn",
) -> list[Path]:
    """Writes CCSDS OEM 2.0 files into ``directory``: mean states (km, km/s) and a
    covariance block at each epoch (km^2, km^2/s, km^2/s^2), time system UTC. Every file
    is validated by reading it back with the maintained ``oem`` library before it is
    renamed into place; XML files are written by that library.

    Args:
        result: a catalog result (:class:`~rhoprop.catalog.CatalogResult`): one file
            per object, ``<NORAD id>.oem``, at the object's valid epochs (none for an
            object with no valid epoch); or a single :class:`~rhoprop.CcspResult` /
            :class:`~rhoprop.MonteCarloResult` (one file, ``<object_id>.oem``, its mean
            and covariance at every output with statistics) or
            :class:`~rhoprop.Trajectory` (states only).
        directory: output folder (created).
        originator: the ORIGINATOR field.
        duplicates: catalog only: ``"error"`` (default) refuses NORAD ids that occur more
            than once; ``"suffix"`` names the repeats ``<id>_2.oem``, ``<id>_3.oem``, ...
        object_name, object_id: single results: the OBJECT_NAME and OBJECT_ID fields.
        ref_frame: REF_FRAME, one of :data:`OEM_FRAMES` (default TEME for a catalog,
            whose states come from SGP4, and EME2000 for a single result, rhoprop's
            inertial frame). The states are written as computed: this names their frame,
            it does not convert them.
        covariance_frame: ``"inertial"`` (the states' frame, default) or ``"rtn"`` (each
            epoch's covariance rotated into the RTN frame of its mean state;
            ``COV_REF_FRAME = RTN``).
        file_format: ``"kvn"`` (default; ``.oem``) or ``"xml"`` (``.xml``; inertial
            covariances only: the library's XML writer does not keep COV_REF_FRAME).

    Returns:
        The paths written. Text from the inputs is sanitised (printable ASCII only).
    """
    frame = "TEME" if ref_frame is None and not _is_single(result) else ref_frame or "EME2000"
    if frame not in OEM_FRAMES:
        raise ValueError(f"ref_frame must be one of {OEM_FRAMES}, got {ref_frame!r}")
    if covariance_frame not in COVARIANCE_FRAMES:
        raise ValueError(
            f"covariance_frame must be one of {COVARIANCE_FRAMES}, got {covariance_frame!r}"
        )
    if file_format not in ("kvn", "xml"):
        raise ValueError(f"file_format must be 'kvn' or 'xml', got {file_format!r}")
    if file_format == "xml" and covariance_frame == "rtn":
        raise ValueError(
            "RTN covariances need file_format='kvn': the oem library's XML writer drops "
            "COV_REF_FRAME, so the covariances would read back as inertial"
        )
    suffix = ".oem" if file_format == "kvn" else ".xml"

    def text(name: str, oid: str, epochs: Any, mean: Any, cov: Any, note: str = "") -> str:
        if cov is not None and covariance_frame == "rtn":
            cov = _rtn_covariances(mean, cov)
        return _oem_text(
            name,
            oid,
            frame,
            originator,
            epochs,
            mean,
            cov,
            note,
            cov_frame="RTN" if covariance_frame == "rtn" else None,
        )

    out = Path(directory)
    if _is_single(result):
        m = result.moments()
        ok = np.isfinite(m.mean).all(axis=1) & np.isfinite(m.covariance).all(axis=(1, 2))
        if not ok.any():
            raise ValueError("the result has no epoch with a finite mean and covariance")
        cov = None if isinstance(result, Trajectory) else m.covariance[ok]
        body = text(object_name, object_id, m.epochs[ok], m.mean[ok], cov)
        name = (sanitise(object_id) or "OBJECT").replace("/", "_").replace(" ", "_")
        return [_save_oem(out / f"{name}{suffix}", body, file_format)]
    if not all(hasattr(result, a) for a in ("objects", "valid", "mean", "covariance")):
        raise TypeError(
            "write_oem takes a CatalogResult (one file per object) or a single CcspResult, "
            f"MonteCarloResult or Trajectory (one file), not a {type(result).__name__}"
        )
    names = oem_names(result.objects, duplicates)
    paths = []
    for k, obj in enumerate(result.objects):
        idx = np.flatnonzero(result.valid[k])
        if not len(idx):
            continue
        body = text(
            obj.name,
            str(obj.norad_id),
            result.epochs[idx],
            result.mean[k, idx],
            result.covariance[k, idx],
            _note(result, k),
        )
        paths.append(_save_oem(out / names[k].replace(".oem", suffix), body, file_format))
    return paths


def _is_single(result: Any) -> bool:
    return isinstance(result, (CcspResult, MonteCarloResult, Trajectory))


def _note(result: Any, k: int) -> str:
    """What object ``k``'s covariance includes ("" when the result does not say)."""
    notes = getattr(result, "covariance_note", None)
    return "" if notes is None else str(notes[k])


def summary_table(result: Any) -> dict[str, np.ndarray]:
    """Per-object statistics at the last valid output: radial, along-track and
    cross-track 1-sigma (m, in the RTN frame of the mean; NaN for an object with no valid
    output), the status and reason, decay epoch and fraction, and what the covariance
    includes (``covariance_includes``)."""
    n = len(result.objects)
    stats = {
        k: np.full(n, np.nan) for k in ("radial_std_m", "along_track_std_m", "cross_track_std_m")
    }
    last = np.full(n, np.datetime64("NaT"), dtype="datetime64[ns]")
    for k in range(n):
        if not result.valid[k].any():
            continue
        i = int(np.flatnonzero(result.valid[k])[-1])
        mean = result.mean[k, i]
        basis = rtn_basis(mean[None, :3], mean[None, 3:])[0]
        rtn = basis @ result.covariance[k, i, :3, :3] @ basis.T
        for j, key in enumerate(stats):
            stats[key][k] = np.sqrt(max(rtn[j, j], 0.0))
        last[k] = result.epochs[i]
    return {
        "norad_id": np.array([o.norad_id for o in result.objects]),
        "name": np.array([sanitise(o.name) for o in result.objects]),
        "epoch": np.array([o.state.epoch for o in result.objects], dtype="datetime64[ns]"),
        "drag_parameter_m2_kg": np.array([o.drag_parameter for o in result.objects]),
        "status": np.array([str(s) for s in result.status]),
        "reason": np.array([sanitise(r, 1000) for r in result.reason]),
        "last_valid_epoch": last,
        "decay_epoch": result.decay_epoch,
        "decay_fraction": result.decay_fraction,
        **stats,
        "covariance_includes": np.array([sanitise(_note(result, k), 2000) for k in range(n)]),
    }


def write_summary(result: Any, path: str | Path) -> Path:
    """The per-object summary as a Parquet file (pyarrow), one row per object (failed
    ones included, with their status and reason), written to a temporary name and
    renamed."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({k: pa.array(v) for k, v in summary_table(result).items()})
    out = Path(path)
    with atomic_path(out) as tmp:
        pq.write_table(table, tmp)
    return out
