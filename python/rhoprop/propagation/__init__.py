"""Propagation: plain state types (``state``), result types sharing one moments API
(``results``), deterministic propagation (``propagate``), the kappa processes
(``kappa``), the correlated-density Monte Carlo (``montecarlo``), the CCSP filter
(``ccsp``), the two as method objects (``methods``) and fits of an orbit to measured
positions (``orbit_fit``). Everything here runs in the Rust core with the GIL released."""

from . import kappa
from .ccsp import DEFAULT_INITIAL_COVARIANCE, ccsp
from .dynamics import Dynamics
from .methods import Ccsp, Method, MonteCarlo, Request, UncertaintyPropagation
from .montecarlo import monte_carlo
from .orbit_fit import OrbitFit, fit_positions
from .propagate import (
    DEFAULT_MAX_MEMORY,
    DEFAULT_RTOL,
    DEFAULT_STEP,
    METHODS,
    output_grid,
    propagate,
)
from .results import (
    CcspResult,
    MonteCarloResult,
    RtnStats,
    StateMoments,
    Trajectory,
    sample_moments,
)
from .state import OrbitState, Spacecraft

__all__ = [
    "DEFAULT_INITIAL_COVARIANCE",
    "DEFAULT_MAX_MEMORY",
    "DEFAULT_RTOL",
    "DEFAULT_STEP",
    "METHODS",
    "Ccsp",
    "CcspResult",
    "Dynamics",
    "Method",
    "MonteCarlo",
    "MonteCarloResult",
    "OrbitFit",
    "OrbitState",
    "Request",
    "RtnStats",
    "Spacecraft",
    "StateMoments",
    "Trajectory",
    "UncertaintyPropagation",
    "ccsp",
    "fit_positions",
    "kappa",
    "monte_carlo",
    "output_grid",
    "propagate",
    "sample_moments",
]
