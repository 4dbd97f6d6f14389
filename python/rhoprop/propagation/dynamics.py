"""One settings object for how every propagating function integrates an orbit and where a
run ends: :class:`Dynamics`. Each of ``propagate``, ``monte_carlo``, ``ccsp``,
``ensemble``, ``propagate_catalog``, ``catalog.reentry``, ``conjunction.screen`` and
``conjunction.closest_approach`` takes ``dynamics=``; their keywords ``zonal_degree``,
``floor_altitude``, ``integrator`` (``method`` of ``propagate``/``monte_carlo``, deprecated)
and ``step`` stay as a documented convenience and are turned into a :class:`Dynamics` by
:func:`resolve`, so there is one code path."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .. import _validate
from ..constants import DEFAULT_FLOOR_ALTITUDE
from ..options import Integrator

INTEGRATORS: tuple[Integrator, ...] = ("dop853", "rk8", "rk4", "abm")
#: Highest zonal degree the dynamics include (J2..J6).
MAX_ZONAL_DEGREE = 6


def zonal_degree_argument(value: object) -> int:
    """``value`` as the zonal degree of a run: an integer from 2 (J2 only) to
    :data:`MAX_ZONAL_DEGREE` (J2..J6); anything else is a TypeError or ValueError."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"zonal_degree must be an integer, got {value!r}")
    if not 2 <= value <= MAX_ZONAL_DEGREE:
        raise ValueError(
            f"zonal_degree = {value} is invalid: it must be 2 (J2 only, the paper's model) "
            f"to {MAX_ZONAL_DEGREE} (J2..J{MAX_ZONAL_DEGREE})"
        )
    return int(value)


@dataclass(frozen=True)
class Dynamics:
    """How an orbit is integrated and where a run ends.

    Attributes:
        zonal_degree: highest zonal harmonic, 2 (J2 only, the paper's model; the default
            of single-object runs) to 6 (J2..J6; what SGP4-derived states need).
        floor_altitude: geodetic altitude, m, below which an object (member, sigma point)
            has decayed and stops (default 120 km).
        integrator: "dop853" (adaptive, deterministic runs), "rk8", "rk4" or "abm" (fixed
            step); None: each function's own default (DOP853 for ``propagate``, RK8 for
            ensembles and the CCSP).
        step: fixed step, s (None: the integrator's default, 180 s for RK8).
        rtol: relative tolerance of DOP853 (None: its default, 1e-10).

    Example:
        >>> import rhoprop as rp
        >>> rp.Dynamics(zonal_degree=4, floor_altitude=100e3)
        Dynamics(zonal_degree=4, floor_altitude=100000.0, integrator=None, step=None, rtol=None)
    """

    zonal_degree: int = 2
    floor_altitude: float = DEFAULT_FLOOR_ALTITUDE
    integrator: Integrator | None = None
    step: float | None = None
    rtol: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "zonal_degree", zonal_degree_argument(self.zonal_degree))
        object.__setattr__(
            self, "floor_altitude", _validate.real("floor_altitude", self.floor_altitude)
        )
        if self.integrator is not None and self.integrator not in INTEGRATORS:
            raise ValueError(
                f"integrator must be one of {', '.join(INTEGRATORS)} or None, "
                f"got {self.integrator!r}"
            )
        for name in ("step", "rtol"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _validate.positive(name, value))


def resolve(
    function: str, dynamics: Dynamics | None, defaults: Dynamics, **given: object
) -> Dynamics:
    """The :class:`Dynamics` of a call to ``function``: ``dynamics`` itself, or one made
    from the call's keywords ``given`` (some of the attributes). ``defaults`` holds the
    function's own defaults of those keywords: giving ``dynamics`` together with a keyword
    that is not at its default is a TypeError naming it."""
    if dynamics is None:
        return Dynamics(**given)  # type: ignore[arg-type]
    if not isinstance(dynamics, Dynamics):
        raise TypeError(f"dynamics must be a rhoprop.Dynamics, got {type(dynamics).__name__}")
    clash = [k for k, v in given.items() if v != getattr(defaults, k)]
    if clash:
        raise TypeError(
            f"{function}() got dynamics= and {', '.join(f'{k}=' for k in clash)}; give the "
            "settings in one place"
        )
    return dynamics


def integrator_argument(function: str, method: str | None, integrator: str | None) -> str | None:
    """The integrator of a call that may still use the deprecated keyword ``method``
    (which now names the uncertainty method of ``ensemble`` and ``propagate_catalog``)."""
    if method is None:
        return integrator
    warnings.warn(
        f"{function}(method=...) is deprecated; the integrator is called integrator= "
        "(method= names the uncertainty method of ensemble and propagate_catalog)",
        DeprecationWarning,
        stacklevel=3,
    )
    if integrator is not None:
        raise TypeError(f"{function}() got both method= and integrator=; give integrator only")
    return method
