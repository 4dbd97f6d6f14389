"""A catalog run's ephemeris as one table (Parquet by default, or CSV): every object's
mean and covariance at its valid epochs, one row per object and epoch, readable by any
Parquet reader (pandas, polars, DuckDB, Arrow), or any spreadsheet as CSV, without
rhoprop. One file whatever the catalog's size: 8,834 objects at hourly outputs for 3 days
is about 640,000 rows."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..options import TableFormat
from .files import sanitise
from .oem import OEM_FRAMES, _from_teme
from .protocols import CatalogRun
from .tables import table_writer

#: Names of the state's components, in the order of ``mean``'s last axis.
STATE = ("x", "y", "z", "vx", "vy", "vz")
#: The covariance columns: the lower triangle, row by row (``cov_x_x``, ``cov_y_x``, ...).
COVARIANCE_COLUMNS = tuple(f"cov_{STATE[i]}_{STATE[j]}" for i in range(6) for j in range(i + 1))


#: Objects per row group of the Parquet file: the columns of one group are built at a
#: time (a whole catalog's at once added about 1 GB to its run's peak memory).
ROW_GROUP_OBJECTS = 500


def ephemeris_table(
    result: CatalogRun, frame: str = "TEME", objects: slice | None = None
) -> dict[str, np.ndarray]:
    """The columns of :func:`write_ephemeris`: ``object`` (index in the result),
    ``norad_id``, ``epoch`` (datetime64[ns] UTC), ``x`` .. ``z`` (m), ``vx`` .. ``vz``
    (m/s) and the 21 covariance columns of :data:`COVARIANCE_COLUMNS` (m^2, m^2/s,
    m^2/s^2), in ``frame`` (TEME as computed; GCRF, EME2000 or ICRF rotated by each
    object's epoch's TEME -> GCRF, as :func:`~rhoprop.io.write_oem`). Only valid
    epochs: an object with none has no row (its status is in the summary). ``objects``:
    those of this slice of the result only (default all)."""
    if frame not in OEM_FRAMES:
        raise ValueError(f"frame must be one of {OEM_FRAMES}, got {frame!r}")
    part = objects if objects is not None else slice(None)
    first = part.indices(len(result.objects))[0]
    local, epochs = np.nonzero(np.asarray(result.valid[part], dtype=bool))
    objects_ = local + first
    mean = np.asarray(result.mean)[objects_, epochs]
    cov = np.asarray(result.covariance)[objects_, epochs]
    if frame != "TEME":
        for k in np.unique(objects_):
            rows = objects_ == k
            mean[rows], cov[rows] = _from_teme(result.objects[k].state.epoch, mean[rows], cov[rows])
    rows_, cols_ = np.tril_indices(6)
    table = {
        "object": objects_.astype(np.int64),
        "norad_id": np.array([result.objects[int(k)].norad_id for k in objects_], dtype=np.int64),
        "epoch": np.asarray(result.epochs, dtype="datetime64[ns]")[epochs],
        **{name: mean[:, i] for i, name in enumerate(STATE)},
    }
    # np.tril_indices runs row by row, as COVARIANCE_COLUMNS does.
    for name, i, j in zip(COVARIANCE_COLUMNS, rows_, cols_, strict=True):
        table[name] = cov[:, i, j]
    return table


def write_ephemeris(
    result: CatalogRun, path: str | Path, *, frame: str = "TEME", fmt: TableFormat = "parquet"
) -> Path:
    """Writes a catalog run's ephemeris (:func:`ephemeris_table`) to the table file
    ``path``: ``fmt`` ``"parquet"`` (default; pyarrow, zstd-compressed) or ``"csv"``,
    through a temporary name and a rename. The metadata (JSON: the frame, the time scale
    (UTC), the units and each object's NORAD id and name) is the Parquet file's key
    ``rhoprop``, or the file ``name.meta.json`` beside a CSV; the summary of the same run
    (:func:`~rhoprop.io.write_summary`) gives each object's status.

    Args:
        result: a catalog run (:class:`~rhoprop.catalog.CatalogResult`, or anything with
            the attributes of :class:`~rhoprop.io.protocols.CatalogRun`).
        path: the file to write (``.parquet`` or ``.csv``).
        frame: "TEME" (default, the states as computed) or "GCRF"/"EME2000"/"ICRF".
        fmt: ``"parquet"`` or ``"csv"``.

    Returns:
        ``path``.
    """
    import pyarrow as pa

    if not all(hasattr(result, a) for a in ("objects", "valid", "mean", "covariance")):
        raise TypeError(f"write_ephemeris takes a CatalogResult, not a {type(result).__name__}")
    meta = {
        "frame": frame,
        "time_scale": "UTC",
        "units": {"position": "m", "velocity": "m/s", "covariance": "SI (m, m/s)"},
        "covariance_columns": "lower triangle, row by row, of the 6x6 over x y z vx vy vz",
        "objects": [
            {"object": k, "norad_id": o.norad_id, "name": sanitise(o.name)}
            for k, o in enumerate(result.objects)
        ],
    }
    types = {"object": pa.int64(), "norad_id": pa.int64(), "epoch": pa.timestamp("ns", tz="UTC")}
    types.update({k: pa.float64() for k in (*STATE, *COVARIANCE_COLUMNS)})
    schema = pa.schema(list(types.items()), metadata={"rhoprop": json.dumps(meta)})
    out = Path(path)
    n = len(result.objects)
    with table_writer(out, schema, fmt) as write:
        for lo in range(0, max(n, 1), ROW_GROUP_OBJECTS):
            write(ephemeris_table(result, frame, slice(lo, lo + ROW_GROUP_OBJECTS)))
    return out
