"""rhoprop: orbit uncertainty of low-Earth-orbit objects caused by uncertainty in
thermospheric density. Rust core, numpy in and out; SI units (m, m/s, s, kg/m^3)."""

from . import catalog, density, frames, io, kappa, scenarios
from ._core import DensityFieldError, IntegrationError, RhopropError
from .ccsp import CcspResult, ccsp
from .debias import debias_drag_coefficient
from .ensemble import EnsembleResult, ensemble
from .epochs import seconds_since_j2000, to_datetime64
from .mixture import GaussianMixture
from .montecarlo import MonteCarloResult, monte_carlo
from .orbit import OrbitState, Spacecraft, Trajectory, propagate
from .spaceweather import SpaceWeather

__version__ = "0.1.0"

__all__ = [
    "CcspResult",
    "DensityFieldError",
    "EnsembleResult",
    "GaussianMixture",
    "IntegrationError",
    "MonteCarloResult",
    "OrbitState",
    "RhopropError",
    "SpaceWeather",
    "Spacecraft",
    "Trajectory",
    "__version__",
    "catalog",
    "ccsp",
    "debias_drag_coefficient",
    "density",
    "ensemble",
    "frames",
    "io",
    "kappa",
    "monte_carlo",
    "propagate",
    "scenarios",
    "seconds_since_j2000",
    "to_datetime64",
]
