"""A catalog run's per-object statistics as one table (Parquet or CSV)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..options import TableFormat
from ..propagation.results import rtn_basis
from .files import sanitise
from .oem import _note
from .protocols import CatalogRun
from .tables import write_table


def summary_table(result: CatalogRun) -> dict[str, np.ndarray]:
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


def write_summary(result: CatalogRun, path: str | Path, fmt: TableFormat = "parquet") -> Path:
    """The per-object summary (:func:`summary_table`) as a table file, one row per object
    (failed ones included, with their status and reason): ``fmt`` ``"parquet"``
    (default) or ``"csv"`` (:mod:`rhoprop.io.tables`), written to a temporary name and
    renamed. Returns ``path``."""
    return write_table(summary_table(result), path, fmt)
