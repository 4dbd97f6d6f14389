"""The event table of an all-on-all screen as a Parquet file (pyarrow): one row per
event, the columns of :meth:`rhoprop.conjunction.AllOnAllResult.table`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .files import OutputFolder, sanitise

__all__ = ["write_event_table"]


def write_event_table(columns: dict[str, np.ndarray], folder: OutputFolder, name: str) -> Path:
    """Writes ``columns`` (equal-length arrays; object arrays of str, names made safe
    for one-line display) as the Parquet file ``name`` of ``folder``. Returns its path."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    cols = {}
    for key, value in columns.items():
        if value.dtype == object:
            cols[key] = pa.array([sanitise(x, 200) for x in value])
        else:
            cols[key] = pa.array(value)
    with folder.path(name) as tmp:
        pq.write_table(pa.table(cols), tmp)
    return folder.directory / name
