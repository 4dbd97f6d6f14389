"""Catalog output files: CCSDS OEM (KVN, version 2.0 per CCSDS 502.0-B-3, with covariance blocks)
and a columnar Parquet summary of per-object statistics."""

from __future__ import annotations

import datetime as _dt
from pathlib import Path
from typing import Any

import numpy as np

from .. import frames


def _iso(t: np.datetime64) -> str:
    return str(t.astype("datetime64[us]"))


def write_oem(result: Any, directory: str | Path, *, originator: str = "rhoprop") -> list[Path]:
    """One OEM file per object (``<NORAD id>.oem``) with the mean states at the valid
    common epochs (km, km/s) and a covariance block at each (km^2, km^2/s, km^2/s^2),
    frame TEME, time system UTC. Returns the paths."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    created = _dt.datetime.now(_dt.timezone.utc).replace(tzinfo=None).isoformat(timespec="seconds")
    paths = []
    for k, obj in enumerate(result.objects):
        idx = np.flatnonzero(result.valid[k])
        if not len(idx):
            continue
        lines = [
            "CCSDS_OEM_VERS = 2.0",
            f"CREATION_DATE = {created}",
            f"ORIGINATOR = {originator}",
            "",
            "META_START",
            f"OBJECT_NAME = {obj.name}",
            f"OBJECT_ID = {obj.norad_id}",
            "CENTER_NAME = EARTH",
            "REF_FRAME = TEME",
            "TIME_SYSTEM = UTC",
            f"START_TIME = {_iso(result.epochs[idx[0]])}",
            f"STOP_TIME = {_iso(result.epochs[idx[-1]])}",
            "META_STOP",
            "",
        ]
        for i in idx:
            s = result.mean[k, i] / 1e3
            lines.append(f"{_iso(result.epochs[i])} " + " ".join(f"{v:.9e}" for v in s))
        lines += ["", "COVARIANCE_START"]
        for i in idx:
            c = result.covariance[k, i] / 1e6
            lines += [f"EPOCH = {_iso(result.epochs[i])}", "COV_REF_FRAME = TEME"]
            for row in range(6):
                lines.append(" ".join(f"{c[row, col]:.9e}" for col in range(row + 1)))
        lines += ["COVARIANCE_STOP", ""]
        path = out / f"{obj.norad_id}.oem"
        path.write_text("\n".join(lines))
        paths.append(path)
    return paths


def summary_table(result: Any) -> dict[str, np.ndarray]:
    """Per-object statistics at the last valid output: radial, along-track and
    cross-track 1-sigma (m, in the RTN frame of the mean), decay epoch."""
    n = len(result.objects)
    stats = {k: np.zeros(n) for k in ("radial_std_m", "along_track_std_m", "cross_track_std_m")}
    last = np.zeros(n, dtype="datetime64[ns]")
    for k in range(n):
        i = int(np.flatnonzero(result.valid[k])[-1]) if result.valid[k].any() else 0
        mean = result.mean[k, i]
        basis = frames.rtn_basis(mean[:3], mean[3:])
        rtn = basis @ result.covariance[k, i, :3, :3] @ basis.T
        for j, key in enumerate(stats):
            stats[key][k] = np.sqrt(max(rtn[j, j], 0.0))
        last[k] = result.epochs[i]
    return {
        "norad_id": np.array([o.norad_id for o in result.objects]),
        "name": np.array([o.name for o in result.objects]),
        "epoch": np.array([o.state.epoch for o in result.objects], dtype="datetime64[ns]"),
        "drag_parameter_m2_kg": np.array([o.drag_parameter for o in result.objects]),
        "last_valid_epoch": last,
        "decay_epoch": result.decay_epoch,
        "decay_fraction": result.decay_fraction,
        **stats,
    }


def write_summary(result: Any, path: str | Path) -> Path:
    """The per-object summary as a Parquet file (pyarrow)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({k: pa.array(v) for k, v in summary_table(result).items()})
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(table, out)
    return out
