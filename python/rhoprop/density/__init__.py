"""Density models with uncertainty: each gives the mean and standard deviation of
thermospheric density (kg/m^3) and an atmosphere the Rust core evaluates.

- :class:`Msis`: NRLMSIS 2.1 / 2.0 / NRLMSISE-00 through pymsis, with
  :class:`DriverUncertainty` (default) or :class:`RelativeSigma`.
- :class:`Jb2008`: JB2008 in the Rust core, from SET's index files (:class:`Jb2008Indices`),
  with :class:`ActivitySigma`.
- :class:`JacchiaRoberts`: Jacchia-Roberts 1971 in the Rust core from the bundled record.
- :class:`Exponential`: the analytic benchmark atmosphere.
- :class:`Gridded`: a user grid (arrays or an xarray Dataset).
- :class:`PcaRom`: a PCA reduced-order model as HASDM-ML outputs it.
- :class:`FromFunction`: any callable (times, lat, lon, alt) -> (mean, std).
- :class:`DensityField`: a sampled field (what :meth:`SampledModel.field` returns).
- :class:`SigmaScaled`: any model with its standard deviation scaled (an ensemble's
  spread-adjusted pool).
- :class:`Atlas`: how a sampled model reaches the core, as UTC-day tiles under a memory
  budget (:func:`set_memory_budget`, :func:`field_memory`).

Layout: ``_inputs`` (input checks, altitude band) <- ``field`` (sampling, the field type)
<- ``atlas`` (day tiles, their caches) <- ``model`` (the protocol and the sampling base) <-
one module per model.
"""

from . import atlas, calibrated
from ._inputs import altitude_band
from .atlas import Atlas, FieldMemory, field_memory, set_memory_budget
from .calibrated import PRESETS, Preset
from .catalog_corrected import CatalogCorrected, DensityCorrection
from .correction import MeanCorrection
from .exponential import Exponential
from .field import DensityField, FieldResolution
from .function import FromFunction
from .gridded import Gridded
from .jacchia_roberts import JR_CALIBRATED, JR_SIGMA, JacchiaRoberts
from .jb2008 import JB2008_CALIBRATED, JB2008_SIGMA, Jb2008, Jb2008Indices
from .model import DensityModel, SampledModel, as_atmosphere
from .msis import DriverUncertainty, Msis, RelativeSigma
from .pcarom import PcaRom
from .point_model import ActivitySigma
from .scaled import SigmaScaled

__all__ = [
    "JB2008_CALIBRATED",
    "JB2008_SIGMA",
    "JR_CALIBRATED",
    "JR_SIGMA",
    "PRESETS",
    "ActivitySigma",
    "Atlas",
    "CatalogCorrected",
    "DensityCorrection",
    "DensityField",
    "DensityModel",
    "DriverUncertainty",
    "Exponential",
    "FieldMemory",
    "FieldResolution",
    "FromFunction",
    "Gridded",
    "JacchiaRoberts",
    "Jb2008",
    "Jb2008Indices",
    "MeanCorrection",
    "Msis",
    "PcaRom",
    "Preset",
    "RelativeSigma",
    "SampledModel",
    "SigmaScaled",
    "altitude_band",
    "as_atmosphere",
    "atlas",
    "calibrated",
    "field_memory",
    "set_memory_budget",
]
