"""Tables out, in the format a user asks for: Parquet (typed columns, compressed, the
default of the catalog and screening commands) or CSV (any spreadsheet; the reentry
command's default). Every table the commands write goes through :func:`write_table` or
:func:`table_writer`, so ``--format`` means the same everywhere. What a CSV cannot
hold, the file's metadata (frame, units, time scale), goes to a JSON file beside it
(``name.csv`` -> ``name.meta.json``)."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, get_args

import numpy as np

from ..options import TableFormat
from .files import OutputFolder, atomic_path, sanitise, write_text_atomic

if TYPE_CHECKING:
    import pyarrow

__all__ = [
    "FORMATS",
    "format_argument",
    "table_name",
    "table_writer",
    "write_folder_table",
    "write_table",
]

#: The table formats, the default first.
FORMATS: tuple[TableFormat, ...] = get_args(TableFormat)
#: File suffix of each format.
SUFFIX = {"parquet": ".parquet", "csv": ".csv"}


def format_argument(value: object) -> TableFormat:
    """``format`` checked: one of :data:`FORMATS`; else a ValueError naming it."""
    if value not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(FORMATS)}, got {value!r}")
    return value


def table_name(stem: str, fmt: TableFormat) -> str:
    """The file name of table ``stem`` in format ``fmt`` (``"summary"`` -> ``summary.csv``)."""
    return stem + SUFFIX[format_argument(fmt)]


def meta_path(path: Path) -> Path:
    """Where a CSV table's metadata goes: ``name.csv`` -> ``name.meta.json``."""
    return path.with_suffix(".meta.json")


@contextmanager
def table_writer(
    path: str | Path, schema: pyarrow.Schema, fmt: TableFormat
) -> Iterator[Callable[[Mapping[str, Any]], None]]:
    """Writes a table in pieces (row groups of Parquet, blocks of CSV rows): yields a
    function that appends rows (one array per column of ``schema``, equal lengths). The
    file is written through a temporary name, renamed when the block ends without error.
    The schema's metadata (key ``rhoprop``, JSON) stays in a Parquet file and goes beside
    a CSV (:func:`meta_path`)."""
    import pyarrow as pa
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    fmt = format_argument(fmt)
    out = Path(path)
    plain = schema.remove_metadata()
    with atomic_path(out) as tmp:
        writer = (
            pq.ParquetWriter(tmp, schema, compression="zstd")
            if fmt == "parquet"
            else pcsv.CSVWriter(tmp, plain)
        )
        try:
            yield lambda columns: writer.write_table(
                pa.table(dict(columns), schema=schema if fmt == "parquet" else plain)
            )
        finally:
            writer.close()
    meta = (schema.metadata or {}).get(b"rhoprop")
    if fmt == "csv" and meta is not None:
        write_text_atomic(meta_path(out), json.dumps(json.loads(meta), indent=1) + "\n")


def write_table(
    columns: Mapping[str, np.ndarray],
    path: str | Path,
    fmt: TableFormat = "parquet",
    metadata: Mapping[str, object] | None = None,
) -> Path:
    """Writes ``columns`` (equal-length arrays, one per column) as a table at ``path``
    in format ``fmt`` (``"parquet"`` or ``"csv"``), through a temporary name and a
    rename; ``metadata`` (JSON-able) goes in the Parquet file's key ``rhoprop`` or beside
    the CSV (:func:`meta_path`). Returns ``path``."""
    import pyarrow as pa

    table = pa.table({k: pa.array(v) for k, v in columns.items()})
    schema = table.schema
    if metadata is not None:
        schema = schema.with_metadata({"rhoprop": json.dumps(metadata)})
    with table_writer(path, schema, fmt) as write:
        write({k: table.column(k) for k in table.column_names})
    return Path(path)


def write_folder_table(
    columns: Mapping[str, np.ndarray], folder: OutputFolder, name: str, fmt: TableFormat
) -> Path:
    """Writes ``columns`` as the table file ``name`` of a run's ``folder`` (listed in
    its manifest), text columns (object arrays) made safe for one-line display. Returns
    its path."""
    cols = {
        key: np.array([sanitise(x, 200) for x in value], dtype=object)
        if value.dtype == object
        else value
        for key, value in columns.items()
    }
    with folder.path(name) as tmp:
        write_table(cols, tmp, fmt)
    return folder.directory / name
