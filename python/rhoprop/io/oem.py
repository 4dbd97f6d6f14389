"""CCSDS OEM files (KVN, version 2.0 per CCSDS 502.0-B-3, with covariance blocks) of
trajectories, Monte Carlo and CCSP results and catalog runs; file names per object."""

from __future__ import annotations

import contextlib
import datetime as _dt
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..frames import same_axes, teme_to_gcrf_matrix
from ..options import Duplicates
from ..propagation import CcspResult, MonteCarloResult, Trajectory, run_frame
from .files import _iso, atomic_path, sanitise, write_text_atomic

if TYPE_CHECKING:
    from typing import TypeAlias

    from .protocols import CatalogRun

    #: What :func:`write_oem` writes: one trajectory, a Monte Carlo or CCSP result, a
    #: catalog run.
    ResultLike: TypeAlias = Trajectory | MonteCarloResult | CcspResult | CatalogRun

#: What ``duplicates`` of :func:`write_oem` accepts.
DUPLICATES = ("error", "suffix")


def duplicate_ids(objects: Sequence[Any]) -> list[int]:
    """NORAD ids that more than one of ``objects`` carries, sorted."""
    counts = Counter(o.norad_id for o in objects)
    return sorted(i for i, c in counts.items() if c > 1)


def oem_names(objects: Sequence[Any], duplicates: Duplicates = "error") -> list[str]:
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
        *_interpolation(epochs, mean),
        "META_STOP",
        "",
    ]
    if not any(line.startswith("INTERPOLATION") for line in lines) and len(epochs) >= 4:
        lines.insert(len(lines) - 1, INTERPOLATION_NOTE)
    # One %-format per line (formatting is most of a whole catalog's output time). States
    # with 16 significant digits, float64's own (10 rounded LEO positions to a metre).
    stamps = np.datetime_as_string(np.asarray(epochs).astype("datetime64[us]"), unit="us")
    state_line = "%s " + " ".join(["%.15e"] * 6)
    for t, s in zip(stamps, (mean / 1e3).tolist(), strict=True):
        lines.append(state_line % (t, *s))
    if covariance is not None:
        lines += ["", "COVARIANCE_START"]
        lines += [f"COMMENT {chunk}" for chunk in _wrap(sanitise(note, 2000))]
        rows, cols = np.tril_indices(6)
        block = "\n".join(" ".join(["%.9e"] * (r + 1)) for r in range(6))
        head = f"\nCOV_REF_FRAME = {cov_frame or frame}\n"
        for t, c in zip(stamps, (covariance / 1e6)[:, rows, cols].tolist(), strict=True):
            lines.append("EPOCH = " + t + head + block % tuple(c))
        lines += ["COVARIANCE_STOP"]
    lines.append("")
    return "\n".join(lines)


#: The data section's first line where the states cannot be interpolated to 1 m: what to
#: do instead (degree-7 Hermite at 400 km, measured: 4 cm at 300 s, 5 m at 600 s).
INTERPOLATION_NOTE = (
    "COMMENT states too far apart to interpolate to 1 m: no INTERPOLATION given; "
    "write them every 300 s or less in LEO"
)


def _interpolation(epochs: np.ndarray, mean: np.ndarray) -> list[str]:
    """INTERPOLATION = HERMITE, INTERPOLATION_DEGREE = 7 where a reader can interpolate the
    states to 1 m that way (checked as ``Trajectory.state_at`` checks it, at the middle of
    the first, a central and the last interval); none where the states are too far apart
    (hourly LEO states) or fewer than four."""
    from ..propagation.interpolate import interpolate_state

    n = len(epochs)
    if n < 4:
        return []
    t = (np.asarray(epochs, dtype="datetime64[ns]") - epochs[0]).astype(np.int64) / 1e9
    for i in sorted({0, (n - 1) // 2, n - 2}):
        try:
            interpolate_state(t, mean[:, :3], mean[:, 3:], 0.5 * (t[i] + t[i + 1]))
        except ValueError:
            return []
    return ["INTERPOLATION = HERMITE", "INTERPOLATION_DEGREE = 7"]


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


def _save_oem(path: Path, text: str, file_format: str, validate: bool = True) -> Path:
    """Validates ``text`` with the ``oem`` library (CCSDS OEM 2.0) and writes it as KVN
    (the text itself, comments kept) or as XML (the library's writer), atomically;
    ``validate=False`` (KVN only) writes the text without reading it back."""
    from oem import OrbitEphemerisMessage

    if not validate and file_format == "kvn":
        return write_text_atomic(path, text)
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
    result: ResultLike,
    directory: str | Path,
    *,
    originator: str = "rhoprop",
    duplicates: Duplicates = "error",
    object_name: str = "OBJECT",
    object_id: str = "OBJECT",
    ref_frame: str | None = None,
    covariance_frame: Literal["inertial", "rtn"] = "inertial",
    file_format: Literal["kvn", "xml"] = "kvn",
) -> list[Path]:
    """Writes CCSDS OEM 2.0 files into ``directory``: mean states (km, km/s) and a
    covariance block at each epoch (km^2, km^2/s, km^2/s^2), time system UTC. Every file
    is written to a temporary name and renamed into place. The first file of a catalog
    (and every single result's) is validated by reading it back with the maintained
    ``oem`` library; the others come from the same writer with sanitised text, so they are
    not read back (reading back took about 25 ms a file: three minutes of a whole
    catalog's run). XML files are written, so validated, by that library.

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
        ref_frame: REF_FRAME, one of :data:`OEM_FRAMES`. A catalog's states are in TEME
            (from SGP4: each object's TEME of its epoch, taken as inertial): TEME
            (default) writes them as they are; EME2000, GCRF or ICRF converts them, with
            their covariances, by the rotation of the object's epoch
            (:func:`rhoprop.frames.teme_to_gcrf_matrix`: 43 km in LEO, which a reader
            taking TEME for GCRF would carry). A single result's states are in its
            ``frame``, its initial state's: the default writes them in it (GCRF as
            GCRF, TEME as TEME); another ``ref_frame`` converts them (TEME <-> GCRF,
            EME2000 and ICRF, by the rotation of the initial epoch, the axes the run
            integrated in; GCRF, EME2000 and ICRF share axes and are relabelled).
        covariance_frame: ``"inertial"`` (the states' frame, default) or ``"rtn"`` (each
            epoch's covariance rotated into the RTN frame of its mean state;
            ``COV_REF_FRAME = RTN``).
        file_format: ``"kvn"`` (default; ``.oem``) or ``"xml"`` (``.xml``; inertial
            covariances only: the library's XML writer does not keep COV_REF_FRAME).

    Returns:
        The paths written. Text from the inputs is sanitised (printable ASCII only).
    """
    own = str(getattr(result, "frame", "TEME")) if _is_single(result) else "TEME"
    frame = own if ref_frame is None else ref_frame
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

    def text(
        name: str,
        oid: str,
        epochs: np.ndarray,
        mean: np.ndarray,
        cov: np.ndarray | None,
        note: str = "",
    ) -> str:
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
    if isinstance(result, (CcspResult, MonteCarloResult, Trajectory)):
        m = result.moments()
        ok = np.isfinite(m.mean).all(axis=1) & np.isfinite(m.covariance).all(axis=(1, 2))
        if not ok.any():
            raise ValueError("the result has no epoch with a finite mean and covariance")
        cov = None if isinstance(result, Trajectory) else m.covariance[ok]
        mean, note = m.mean[ok], ""
        if not same_axes(own, frame):
            rot = teme_to_gcrf_matrix(result.epoch)
            rot = rot if own == "TEME" else rot.T
            mean = run_frame.vectors(rot, mean)
            cov = None if cov is None else run_frame.covariances(rot, cov)
            note = f"states and covariances rotated from {own} of the initial epoch"
        body = text(object_name, object_id, m.epochs[ok], mean, cov, note)
        name = (sanitise(object_id) or "OBJECT").replace("/", "_").replace(" ", "_")
        return [_save_oem(out / f"{name}{suffix}", body, file_format)]
    if not all(hasattr(result, a) for a in ("objects", "valid", "mean", "covariance")):
        raise TypeError(
            "write_oem takes a CatalogResult (one file per object) or a single CcspResult, "
            f"MonteCarloResult or Trajectory (one file), not a {type(result).__name__}"
        )
    names = oem_names(result.objects, duplicates)
    paths: list[Path] = []
    for k, obj in enumerate(result.objects):
        idx = np.flatnonzero(result.valid[k])
        if not len(idx):
            continue
        mean, cov = result.mean[k, idx], result.covariance[k, idx]
        note = _note(result, k)
        if frame != "TEME":
            mean, cov = _from_teme(obj.state.epoch, mean, cov)
            note = f"{note}; states and covariances rotated from TEME of the element set's epoch"
        body = text(obj.name, str(obj.norad_id), result.epochs[idx], mean, cov, note.lstrip("; "))
        path = out / names[k].replace(".oem", suffix)
        paths.append(_save_oem(path, body, file_format, validate=not paths))
    return paths


def _from_teme(
    epoch: np.datetime64, mean: np.ndarray, cov: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """States (n, 6) and covariances (n, 6, 6) in TEME of ``epoch`` -> GCRF."""
    m = teme_to_gcrf_matrix(epoch)
    return run_frame.vectors(m, mean), run_frame.covariances(m, cov)


def _is_single(result: Any) -> bool:
    return isinstance(result, (CcspResult, MonteCarloResult, Trajectory))


def _note(result: Any, k: int) -> str:
    """What object ``k``'s covariance includes ("" when the result does not say)."""
    notes = getattr(result, "covariance_note", None)
    return "" if notes is None else str(notes[k])
