"""The paper's studies and the user's own: the paper's scenario as data (``scenarios``),
its studies as computations (``paper``), their figures (``plots``, matplotlib loaded
only when drawing), the ``rhoprop paper`` run (``report``) and TOML scenario files for
``rhoprop run`` (``scenario_file``)."""

from . import scenarios
from .paper import (
    METHODS,
    CcspComparison,
    MethodComparison,
    case_ensembles,
    ccsp_vs_monte_carlo,
    method_comparison,
    model_label,
)
from .plots import ensemble_figure

__all__ = [
    "METHODS",
    "CcspComparison",
    "MethodComparison",
    "case_ensembles",
    "ccsp_vs_monte_carlo",
    "ensemble_figure",
    "method_comparison",
    "model_label",
    "scenarios",
]
