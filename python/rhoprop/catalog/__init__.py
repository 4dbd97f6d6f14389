"""Catalogs: element sets in (``elements``: TLE and CCSDS OMM through ``sgp4``), states
and ballistic coefficients fitted to them (``fit``), their initial covariance
(``covariance``: published TLE accuracy), runs over many objects to common epochs, locally
or on Dask (``run``), reentry windows (``reentry_windows``), the decay of element-set
histories as a density sensor (``density_sensor``) and files out (``export``: CCSDS OEM
and a Parquet summary)."""

from ..io import summary_table, write_oem, write_summary
from .covariance import TleAccuracy, fitted_accuracy, tle_accuracy, tle_covariance
from .density_sensor import (
    DecayIntervals,
    corrected_model,
    decay_intervals,
    drag_parameters,
    estimate_density_correction,
)
from .elements import (
    HISTORY_DAYS,
    SGP4_RHO0,
    Catalog,
    CatalogObject,
    FitSettings,
    drag_parameter_from_bstar,
    fit_objects,
    load,
)
from .fit import FitResult, bstar_prior, fit_element_set, fit_element_sets
from .objects import Initial, scaled_bstar_drag
from .reentry_windows import ReentryResult, reentry
from .run import CatalogResult, common_epochs, propagate_catalog

__all__ = [
    "HISTORY_DAYS",
    "SGP4_RHO0",
    "Catalog",
    "CatalogObject",
    "CatalogResult",
    "DecayIntervals",
    "FitResult",
    "FitSettings",
    "Initial",
    "ReentryResult",
    "TleAccuracy",
    "bstar_prior",
    "common_epochs",
    "corrected_model",
    "decay_intervals",
    "drag_parameter_from_bstar",
    "drag_parameters",
    "estimate_density_correction",
    "fit_element_set",
    "fit_element_sets",
    "fit_objects",
    "fitted_accuracy",
    "load",
    "propagate_catalog",
    "reentry",
    "scaled_bstar_drag",
    "summary_table",
    "tle_accuracy",
    "tle_covariance",
    "write_oem",
    "write_summary",
]
