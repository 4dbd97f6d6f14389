"""The event table of an all-on-all screen (one row per event, the columns of
:meth:`rhoprop.conjunction.AllOnAllResult.table`) as a Parquet or CSV file."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..options import TableFormat
from .files import OutputFolder
from .tables import write_folder_table

__all__ = ["write_event_table"]


def write_event_table(
    columns: dict[str, np.ndarray], folder: OutputFolder, name: str, fmt: TableFormat = "parquet"
) -> Path:
    """Writes ``columns`` (equal-length arrays; object arrays of str, names made safe
    for one-line display) as the table file ``name`` of ``folder``, ``fmt`` ``"parquet"``
    (default) or ``"csv"``. Returns its path."""
    return write_folder_table(columns, folder, name, fmt)
