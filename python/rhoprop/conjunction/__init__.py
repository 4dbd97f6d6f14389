"""Conjunction assessment under density uncertainty: close approaches between propagated
objects (``approach``) and catalog screening (``screening``), the probability of
collision for Gaussian states, Gaussian mixtures and Monte Carlo members
(``probability``), CCSDS conjunction data messages (``cdm``) and a message's Pc with the
density models' disagreement added (``with_density``). Positions m, velocities m/s,
covariances m^2, hard-body radius m."""

from .approach import CloseApproach, closest_approach
from .cdm import CdmObject, ConjunctionMessage, read_cdm, write_cdm
from .probability import (
    MixturePcResult,
    MonteCarloPcResult,
    PcResult,
    pc_2d,
    pc_mixture,
    pc_monte_carlo,
)
from .screening import ScreeningResult, screen
from .with_density import DensityPc, density_pc

__all__: list[str] = [
    "CdmObject",
    "CloseApproach",
    "ConjunctionMessage",
    "DensityPc",
    "MixturePcResult",
    "MonteCarloPcResult",
    "PcResult",
    "ScreeningResult",
    "closest_approach",
    "density_pc",
    "pc_2d",
    "pc_mixture",
    "pc_monte_carlo",
    "read_cdm",
    "screen",
    "write_cdm",
]
