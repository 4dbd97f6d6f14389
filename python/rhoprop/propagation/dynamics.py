"""One settings object for how every propagating function integrates an orbit and where a
run ends: :class:`Dynamics`. Every propagating function (``propagate``, ``monte_carlo``,
``ccsp``, ``ensemble``, ``propagate_catalog``, ``catalog.reentry``, the screening and
close-approach functions) takes it whole as ``dynamics=``. Their older loose keywords
(``zonal_degree``, ``floor_altitude``, ``integrator``, ``step``, ``rtol``) still work for
one release with a DeprecationWarning (:func:`deprecated_keywords`), so a setting has one
place and one code path."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TypedDict

import numpy as np

from .. import _validate
from ..constants import DEFAULT_FLOOR_ALTITUDE
from ..options import Integrator

INTEGRATORS: tuple[Integrator, ...] = ("dop853", "rk8", "rk4", "abm")
#: Highest zonal degree the dynamics include (J2..J6).
MAX_ZONAL_DEGREE = 6
#: Highest degree and order of the EGM2008 field the dynamics can include.
MAX_FIELD_DEGREE = 40


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


def field_degree_argument(value: object) -> int:
    """``value`` as a field degree: 0 (none) or 2 to :data:`MAX_FIELD_DEGREE`."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"field_degree must be an integer or None, got {value!r}")
    if value != 0 and not 2 <= value <= MAX_FIELD_DEGREE:
        raise ValueError(
            f"field_degree = {value} is invalid: it must be 0 (none) or 2 to "
            f"{MAX_FIELD_DEGREE} (EGM2008 to degree and order {MAX_FIELD_DEGREE})"
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
        field_degree: the Earth's field (EGM2008) to this degree and order: every
            harmonic of order m >= 1 and the zonals above ``zonal_degree``, 0 (none) or 2
            to :data:`MAX_FIELD_DEGREE`; None (default): automatic, degree 8 of the
            orders m >= 1 for deep-space orbits (period >= 225 min, where SGP4 switches
            to SDP4) and none near the Earth, where every catalog object's element set
            (SGP4) has none either. A prediction from a precise near-Earth state needs
            it: GRACE-A a day from its precise orbit was 3.3 km off with J2..J6 and
            0.23 km with the field to degree 40 (:meth:`precise`,
            ``benches/precise_grace.py``).
        third_bodies: whether the Sun's and the Moon's pull act; None (default):
            automatic, as ``field_degree``.

    Only the single-object runs (``propagate``, ``monte_carlo``, ``ccsp`` and
    ``ensemble``) and ``closest_approach`` take ``field_degree`` and ``third_bodies``
    other than None; the catalog, reentry and screening functions do not take them yet
    and give a ValueError for them rather than ignore them. Every function honours the
    ``integrator``, ``step`` and ``rtol`` it is given or refuses them with a ValueError
    (:meth:`require_integrator`; docs/conventions.md, "Integrators and defaults").

    Example:
        >>> import rhoprop as rp
        >>> rp.Dynamics(zonal_degree=4, floor_altitude=100e3)  # doctest: +NORMALIZE_WHITESPACE
        Dynamics(zonal_degree=4, floor_altitude=100000.0, integrator=None, step=None,
                 rtol=None, field_degree=None, third_bodies=None)
    """

    zonal_degree: int = 2
    floor_altitude: float = DEFAULT_FLOOR_ALTITUDE
    integrator: Integrator | None = None
    step: float | None = None
    rtol: float | None = None
    field_degree: int | None = None
    third_bodies: bool | None = None

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
        if self.field_degree is not None:
            object.__setattr__(self, "field_degree", field_degree_argument(self.field_degree))
        if self.third_bodies is not None and not isinstance(self.third_bodies, (bool, np.bool_)):
            raise TypeError(f"third_bodies must be True, False or None, got {self.third_bodies!r}")

    @classmethod
    def precise(cls, floor_altitude: float = DEFAULT_FLOOR_ALTITUDE) -> Dynamics:
        """The dynamics of a prediction from a precise state (a GPS or laser-ranging
        orbit, not an element set): J2..J6, the EGM2008 field to degree and order 40 and
        the Sun and the Moon. GRACE-A from its precise orbit: 120 m off after 24 h
        (NRLMSIS 2.1, observed drivers), against 3.3 km with J2..J6 and 9.1 km with J2
        alone (``benches/precise_grace.py``). Each force evaluation costs about 60 times
        J2's (5.7 against 0.09 microseconds per state, one lane, the same bench)."""
        return cls(
            zonal_degree=MAX_ZONAL_DEGREE,
            floor_altitude=floor_altitude,
            field_degree=MAX_FIELD_DEGREE,
            third_bodies=True,
        )

    @property
    def gravity(self) -> tuple[int | None, bool | None]:
        """(field_degree, third_bodies) as the core takes them."""
        return (
            self.field_degree,
            None if self.third_bodies is None else bool(self.third_bodies),
        )

    @property
    def integration(self) -> tuple[Integrator | None, float | None, float | None]:
        """(integrator, step s, rtol) as :func:`~rhoprop.propagate` takes them."""
        return self.integrator, self.step, self.rtol

    def forces(self, radiation_parameter: float = 0.0) -> tuple[int | None, bool | None, float]:
        """(field_degree, third_bodies, Cr*A/m in m^2/kg) as the core takes them: the
        gravity of these dynamics and the object's radiation pressure
        (:attr:`Spacecraft.radiation_parameter`, 0: none)."""
        return (*self.gravity, float(radiation_parameter))

    def require_integrator(self, function: str, integrators: tuple[str, ...]) -> None:
        """ValueError if ``function``, which integrates with one of ``integrators`` only,
        is given another :attr:`integrator`, or :attr:`rtol` without DOP853 among them: a
        setting a function cannot use is refused, never ignored."""
        if self.integrator is not None and self.integrator not in integrators:
            raise ValueError(
                f"{function}() integrates with {' or '.join(integrators)}, not "
                f"dynamics.integrator = {self.integrator!r}"
            )
        if self.rtol is not None and "dop853" not in integrators:
            raise ValueError(
                f"{function}() integrates with a fixed step ({' or '.join(integrators)}); "
                f"dynamics.rtol = {self.rtol:g} applies to 'dop853' only (leave it None)"
            )

    def require_automatic_gravity(self, function: str) -> None:
        """ValueError if ``function`` (a catalog, reentry, screening or close-approach run)
        is given ``field_degree`` or ``third_bodies``, which it does not honour."""
        given = [
            k
            for k, v in zip(("field_degree", "third_bodies"), self.gravity, strict=True)
            if v is not None
        ]
        if given:
            raise ValueError(
                f"{function}() propagates with the automatic terms of each orbit's regime; "
                f"dynamics.{' and dynamics.'.join(given)} apply to propagate, monte_carlo, "
                "ccsp and ensemble only (leave them None here)"
            )


class LooseFloorAndDegree(TypedDict, total=False):
    """The two attributes of :class:`Dynamics` the catalog, screening and close-approach
    functions took as keywords of their own; deprecated: give them in ``dynamics=``."""

    floor_altitude: float
    zonal_degree: int


class LooseDynamics(LooseFloorAndDegree, total=False):
    """Attributes of :class:`Dynamics` the single-object runs took as keywords of their
    own before ``dynamics=`` existed; deprecated: give them in ``dynamics=``."""

    integrator: Integrator
    step: float
    rtol: float


#: The loose keywords every propagating function still takes, deprecated.
LOOSE = ("floor_altitude", "zonal_degree", "integrator", "step", "rtol")


def deprecated_keywords(
    function: str,
    dynamics: Dynamics | None,
    given: Mapping[str, object],
    defaults: Dynamics | None = None,
    names: tuple[str, ...] = LOOSE,
    aliases: Mapping[str, str] | None = None,
    stacklevel: int = 3,
) -> Dynamics:
    """The :class:`Dynamics` of a call to ``function`` whose loose keywords ``given``
    (attributes of :class:`Dynamics`: ``floor_altitude``, ``zonal_degree``, ...) are
    deprecated in favour of ``dynamics=``: those given are folded in with a
    DeprecationWarning; giving one of them with ``dynamics=`` is a TypeError too. Without
    either, ``defaults`` (the function's own; None: ``Dynamics()``). ``names`` are the
    loose keywords the function took (default all of :data:`LOOSE`); ``aliases`` maps an
    older name still accepted (``method``) to its attribute (``integrator``). A keyword that
    is none of these is a TypeError naming it, as Python's own. ``stacklevel`` points the
    warning at the user's call (3: ``function`` calls this directly)."""
    aliases = aliases or {}
    wrong = sorted(set(given) - set(names) - set(aliases))
    if wrong:
        raise TypeError(f"{function}() got an unexpected keyword argument {wrong[0]!r}")
    base = Dynamics() if defaults is None else defaults
    if dynamics is not None and not isinstance(dynamics, Dynamics):
        raise TypeError(f"dynamics must be a rhoprop.Dynamics, got {type(dynamics).__name__}")
    if not given:
        return base if dynamics is None else dynamics
    warnings.warn(
        f"{function}({', '.join(f'{k}=' for k in given)}) is deprecated; give "
        f"dynamics=rp.Dynamics({', '.join(f'{aliases.get(k, k)}=...' for k in given)})",
        DeprecationWarning,
        stacklevel=stacklevel,
    )
    if dynamics is not None:
        raise TypeError(
            f"{function}() got dynamics= and {', '.join(f'{k}=' for k in given)}; give the "
            "settings in one place"
        )
    settings: dict[str, object] = {}
    for old, new in aliases.items():
        if old in given and new in given:
            raise TypeError(f"{function}() got both {old}= and {new}=; give {new} only")
    for name, value in given.items():
        settings[aliases.get(name, name)] = value
    return replace(base, **settings)  # type: ignore[arg-type]
