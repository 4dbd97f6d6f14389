"""Conjunction assessment under density uncertainty: the machinery every search shares
(``kernel``: tracks, the window check, refinement, events), close approaches between
propagated objects (``approach``), catalog screening (``screening``: one primary against many;
``all_on_all``: every pair, with each event's Pc per density model, ``event_pc``), the
settings records of a screening (``settings``: :class:`Search`, :class:`PcSettings`),
the probability of collision for Gaussian states, Gaussian mixtures and Monte Carlo members
(``probability``), whether the short-encounter model applies and a Pc over the encounter
where it does not (``encounter``), CCSDS conjunction data messages (``cdm``) and a
message's Pc with the density models' disagreement added (``with_density``). Positions
m, velocities m/s, covariances m^2, hard-body radius m."""

from .all_on_all import AllOnAllResult, screen_all
from .approach import closest_approach
from .cdm import CdmObject, ConjunctionMessage, read_cdm, write_cdm
from .encounter import EncounterCheck, IntervalPcResult, encounter_check, pc_interval
from .kernel import CloseApproach
from .probability import (
    MixturePcResult,
    MonteCarloPcResult,
    PcResult,
    pc_2d,
    pc_mixture,
    pc_monte_carlo,
)
from .screening import ScreeningResult, screen
from .settings import PcSettings, Search
from .with_density import DensityPc, density_pc

__all__: list[str] = [
    "AllOnAllResult",
    "CdmObject",
    "CloseApproach",
    "ConjunctionMessage",
    "DensityPc",
    "EncounterCheck",
    "IntervalPcResult",
    "MixturePcResult",
    "MonteCarloPcResult",
    "PcResult",
    "PcSettings",
    "ScreeningResult",
    "Search",
    "closest_approach",
    "density_pc",
    "encounter_check",
    "pc_2d",
    "pc_interval",
    "pc_mixture",
    "pc_monte_carlo",
    "read_cdm",
    "screen",
    "screen_all",
    "write_cdm",
]
