"""rhoprop: orbit uncertainty of low-Earth-orbit objects caused by uncertainty in
thermospheric density. Rust core, numpy in and out; SI units (m, m/s, s, kg/m^3).

The package is laid out by stage of the data flow, each importing only from stages
below it (docs/architecture.md): time, frames, constants, errors -> spaceweather ->
density -> propagation -> ensemble -> catalog -> conjunction -> studies -> cli. The catalog,
the conjunction tools, the studies and the ``io``/``scenarios`` aliases load on first use.
"""

import importlib as _importlib
import typing as _typing

from . import cache, constants, density, errors, frames, options, parallel, spaceweather, time
from . import propagation as propagation
from ._version import __version__
from .ensemble import Debias, EnsembleResult, GaussianMixture, debias_drag_coefficient
from .ensemble import ensemble as ensemble  # the function; the package stays importable
from .errors import (
    CovarianceError,
    DecayError,
    DensityFieldError,
    IntegrationError,
    OutsideRecordError,
    RhopropError,
    ScenarioError,
)
from .execution import Execution
from .propagation import (
    Ccsp,
    CcspResult,
    Dynamics,
    MonteCarlo,
    MonteCarloResult,
    OrbitFit,
    OrbitState,
    Spacecraft,
    StateMoments,
    Trajectory,
    ccsp,
    fit_positions,
    kappa,
    monte_carlo,
    propagate,
)
from .spaceweather import SpaceWeather
from .time import seconds_since_j2000, to_datetime64

if _typing.TYPE_CHECKING:
    from . import catalog, conjunction, io, plot, studies
    from .studies import scenarios

#: Heavy or optional parts, imported on first attribute access (PEP 562).
_LAZY = {
    "catalog": "rhoprop.catalog",
    "conjunction": "rhoprop.conjunction",
    "plot": "rhoprop.plot",
    "studies": "rhoprop.studies",
    "io": "rhoprop.io",
    "scenarios": "rhoprop.studies.scenarios",
}


def __getattr__(name: str) -> object:
    if name in _LAZY:
        module = _importlib.import_module(_LAZY[name])
        globals()[name] = module
        return module
    raise AttributeError(f"module 'rhoprop' has no attribute {name!r}")


def __dir__() -> list[str]:
    # The public names only (what ``__all__`` lists): the imported helpers and the
    # implementation modules (``progress``) stay attributes but out of the listing.
    return sorted(__all__)


__all__ = [
    "Ccsp",
    "CcspResult",
    "CovarianceError",
    "Debias",
    "DecayError",
    "DensityFieldError",
    "Dynamics",
    "EnsembleResult",
    "Execution",
    "GaussianMixture",
    "IntegrationError",
    "MonteCarlo",
    "MonteCarloResult",
    "OrbitFit",
    "OrbitState",
    "OutsideRecordError",
    "RhopropError",
    "ScenarioError",
    "SpaceWeather",
    "Spacecraft",
    "StateMoments",
    "Trajectory",
    "__version__",
    "cache",
    "catalog",
    "ccsp",
    "conjunction",
    "constants",
    "debias_drag_coefficient",
    "density",
    "ensemble",
    "errors",
    "fit_positions",
    "frames",
    "io",
    "kappa",
    "monte_carlo",
    "options",
    "parallel",
    "plot",
    "propagate",
    "propagation",
    "scenarios",
    "seconds_since_j2000",
    "spaceweather",
    "studies",
    "time",
    "to_datetime64",
]
