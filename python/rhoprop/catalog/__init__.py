"""Catalogs: element sets in (``elements``: TLE and CCSDS OMM through ``sgp4``), runs
over many objects to common epochs, locally or on Dask (``run``), and files out
(``export``: CCSDS OEM and a Parquet summary)."""

from .elements import SGP4_RHO0, Catalog, CatalogObject, drag_parameter_from_bstar, load
from .export import summary_table, write_oem, write_summary
from .run import CatalogResult, common_epochs, propagate_catalog

__all__ = [
    "SGP4_RHO0",
    "Catalog",
    "CatalogObject",
    "CatalogResult",
    "common_epochs",
    "drag_parameter_from_bstar",
    "load",
    "propagate_catalog",
    "summary_table",
    "write_oem",
    "write_summary",
]
