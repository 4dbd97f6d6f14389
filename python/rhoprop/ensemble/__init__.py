"""Multi-model ensembles (paper section 5): drag-coefficient debiasing across models
(``debias``), the Gaussian mixture (``mixture``) and the ensemble run that combines each
model's propagation into one mixture (``combine``).

Note: ``rhoprop.ensemble`` the attribute is the function :func:`ensemble`; this package
is reached as ``rhoprop.ensemble`` only by import statements (``from rhoprop.ensemble
import GaussianMixture``).
"""

from .combine import METHODS, EnsembleResult, ensemble
from .debias import DEBIAS_CADENCE, DEBIAS_WINDOW, Debias, backward_orbit, debias_drag_coefficient
from .mixture import GaussianMixture

__all__ = [
    "DEBIAS_CADENCE",
    "DEBIAS_WINDOW",
    "METHODS",
    "Debias",
    "EnsembleResult",
    "GaussianMixture",
    "backward_orbit",
    "debias_drag_coefficient",
    "ensemble",
]
