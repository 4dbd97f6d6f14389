"""Density models with uncertainty: each gives the mean and standard deviation of
thermospheric density (kg/m^3) and an atmosphere the Rust core evaluates."""

from .base import DensityModel, as_atmosphere
from .exponential import Exponential

__all__ = ["DensityModel", "Exponential", "as_atmosphere"]
