"""Files in and out, below the catalog and the studies: tables as Parquet or CSV
(``tables``, what ``--format`` chooses), CCSDS OEM (``oem``), the Parquet
ephemeris and summary of a catalog run (``ephemeris``, ``summary``), the event table of an
all-on-all screen (``events``), the output folder of a run with its manifest and atomic
writes (``files``), and one format read in: precise orbits to judge predictions against
(``sp3``). The writers take protocols of their own (``protocols``: what a catalog run
gives them), not the catalog's types. A new output format is a module here. Two formats stay with
what they describe: CCSDS conjunction data messages in :mod:`rhoprop.conjunction.cdm` (a
message computes its own Pc, which belongs to the conjunction stage above this one) and
the xarray datasets in the results'
``to_xarray`` (:mod:`rhoprop.propagation`, the catalog).
"""

from .ephemeris import ephemeris_table, write_ephemeris
from .events import write_event_table
from .files import MANIFEST, OutputFolder, atomic_path, command_line, sanitise, write_text_atomic
from .oem import DUPLICATES, duplicate_ids, oem_names, write_oem
from .protocols import CatalogEntry, CatalogRun
from .sp3 import Sp3, read_sp3
from .summary import summary_table, write_summary
from .tables import FORMATS, table_name, write_table

__all__ = [
    "DUPLICATES",
    "FORMATS",
    "MANIFEST",
    "CatalogEntry",
    "CatalogRun",
    "OutputFolder",
    "Sp3",
    "atomic_path",
    "command_line",
    "duplicate_ids",
    "ephemeris_table",
    "oem_names",
    "read_sp3",
    "sanitise",
    "summary_table",
    "table_name",
    "write_ephemeris",
    "write_event_table",
    "write_oem",
    "write_summary",
    "write_table",
    "write_text_atomic",
]
