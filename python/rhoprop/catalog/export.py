"""Moved to :mod:`rhoprop.io` (OEM, Parquet summary, output folders); this alias stays
for one release and warns when imported."""

import warnings

from ..io.files import (
    MANIFEST,
    OutputFolder,
    atomic_path,
    command_line,
    sanitise,
    write_text_atomic,
)
from ..io.oem import DUPLICATES, duplicate_ids, oem_names, write_oem
from ..io.summary import summary_table, write_summary

warnings.warn(
    "rhoprop.catalog.export is deprecated; import from rhoprop.io",
    DeprecationWarning,
    stacklevel=2,
)

__all__ = [
    "DUPLICATES",
    "MANIFEST",
    "OutputFolder",
    "atomic_path",
    "command_line",
    "duplicate_ids",
    "oem_names",
    "sanitise",
    "summary_table",
    "write_oem",
    "write_summary",
    "write_text_atomic",
]
