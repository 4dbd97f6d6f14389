"""The string options of rhoprop's API as ``Literal`` types, one place for each meaning:
``integrator`` is how an orbit is integrated, ``method`` how uncertainty is propagated,
``errors`` what happens on a failure. Every function that takes one of these checks the
value and names the argument in its ValueError."""

from __future__ import annotations

from typing import Literal

#: The integrators: adaptive DOP853 (deterministic runs), fixed-step RK8 and RK4, and
#: Adams-Bashforth-Moulton (fixed step, RK8 start).
Integrator = Literal["dop853", "rk8", "rk4", "abm"]
#: How density uncertainty is propagated (``ensemble``, ``propagate_catalog``,
#: ``density_pc``): a Monte Carlo of members or the CCSP filter.
UncertaintyMethod = Literal["monte_carlo", "ccsp"]
#: How kappa perturbs the density: mean + kappa sigma, or mean exp(kappa s - s^2/2).
Perturbation = Literal["additive", "lognormal"]
#: ``errors=``: the first failure raises, or each failure is recorded and the rest goes on.
Errors = Literal["raise", "record"]
#: The format of a table a command writes (``--format``): Parquet or CSV.
TableFormat = Literal["parquet", "csv"]
#: What ``write_oem`` does with a repeated object id: an error, or ``_2``, ``_3`` suffixes.
Duplicates = Literal["error", "suffix"]
#: The hard body of a collision probability: a circle of the hard-body radius, a square of
#: that half-side, or the square of the circle's area.
HardBodyShape = Literal["circle", "square", "square_equal_area"]
#: A projected covariance that is not positive definite: repaired as NASA CARA does, or an
#: error.
NpdPolicy = Literal["repair", "raise"]

__all__ = [
    "Duplicates",
    "Errors",
    "HardBodyShape",
    "Integrator",
    "NpdPolicy",
    "Perturbation",
    "TableFormat",
    "UncertaintyMethod",
]
