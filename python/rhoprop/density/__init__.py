"""Density models with uncertainty: each gives the mean and standard deviation of
thermospheric density (kg/m^3) and an atmosphere the Rust core evaluates."""

from .base import DensityModel, SampledModel, altitude_band, as_atmosphere
from .exponential import Exponential
from .field import DensityField, FieldResolution

__all__ = [
    "DensityField",
    "DensityModel",
    "Exponential",
    "FieldResolution",
    "SampledModel",
    "altitude_band",
    "as_atmosphere",
]
