"""One object of a catalog run: its plan (decided once before any run: initial covariance,
Cd*A/m sigma), its run (CCSP or Monte Carlo from its own epoch to the common epochs, with
decay prediction; CCSPs of a chunk of objects in one core call) and its typed outcome
(:class:`ObjectOutcome`, a :class:`Status` and its reason). The backends that run many
objects (threads, Dask) are in :mod:`rhoprop.catalog.backends`."""

from __future__ import annotations

import enum
import threading
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..constants import MU, R_EARTH
from ..density.model import ModelLike
from ..density.scaled import SigmaScaled
from ..errors import CovarianceError, RhopropError
from ..options import Integrator
from ..progress import ProgressBar
from ..propagation import (
    OrbitState,
    Spacecraft,
    ccsp,
    monte_carlo,
    propagate,
)
from ..propagation.ccsp import DEFAULT_UPDATE_INTERVAL, CcspRun, ccsp_many, update_schedule
from ..propagation.dynamics import Dynamics, zonal_degree_argument
from ..propagation.gaussian_check import arc_sag_share, holds, member_coverage
from ..propagation.kappa import KappaProcess
from ..propagation.methods import Ccsp, Method, require_defaults
from ..propagation.montecarlo import METHODS as MONTE_CARLO_INTEGRATORS
from ..propagation.montecarlo import drag_sigma_argument
from ..propagation.propagate import (
    DEFAULT_STEP,
    axis_and_eccentricity,
)
from ..propagation.results import (
    CcspResult,
)
from ..time import (
    add_seconds,
    to_seconds,
)
from .covariance import COVARIANCE_NAMES, paper_covariance
from .elements import CatalogObject, object_error
from .fit import DEFAULT_DRAG_PARAMETER

#: Default relative 1-sigma of Cd*A/m when the object carries no fit (assumed: the
#: spread of fitted ballistic coefficients over successive element sets of one object is
#: of this order; drag-coefficient models for the same body differ by 10-20 %).
DEFAULT_DRAG_RELATIVE_SIGMA = 0.15

#: Status of an object in a :class:`CatalogResult`.
#: ``initial_covariance`` of a catalog run: "object", "tle", "paper", one (6, 6) matrix
#: for all, a callable giving each object's, or None (the paper's).
InitialCovariance = (
    Literal["object", "tle", "paper"]
    | npt.ArrayLike
    | Callable[[CatalogObject], npt.ArrayLike]
    | None
)


#: ``drag_sigma`` of a catalog run: "auto", one relative sigma, or a callable per object.
DragSigma = Literal["auto"] | float | Callable[[CatalogObject], float]


#: What the covariance of a catalog run includes beside the initial covariance.
PROPAGATED_NOTE = (
    "propagated: density uncertainty of the model (kappa); not included: ballistic "
    "coefficient uncertainty, space-weather forecast error beyond the model's driver "
    "sigma, manoeuvres"
)


#: Largest relative Cd*A/m sigma of ``drag_sigma="auto"``: a fit whose prior dominated
#: (``FitResult.drag_observable`` False) reports formal sigmas of several times Cd*A/m.
AUTO_DRAG_SIGMA_MAX = 1.0


#: Smallest relative Cd*A/m sigma of ``drag_sigma="auto"`` for a fitted object: the fit's
#: formal sigma ignores how the density (and so the effective Cd*A/m) wanders after the
#: fit span. 0.08 gives close to Gaussian 1/2/3-sigma fractions on the realism benchmark
#: (docs/catalog-realism.md; chosen there, so in-sample); 0.15 overstates 1 sigma.
AUTO_FITTED_DRAG_SIGMA_MIN = 0.08


def _auto_drag_sigma(obj: CatalogObject) -> float:
    """``drag_sigma="auto"`` before the cap: a fitted object's formal relative sigma but
    at least :data:`AUTO_FITTED_DRAG_SIGMA_MIN`; without a fit (Cd*A/m from B*, which
    absorbs SGP4's own density model) ``DEFAULT_DRAG_RELATIVE_SIGMA`` (0.15); a B* <= 0
    object loaded with an assumed Cd*A/m (``load(nonpositive_bstar="prior")``): 100 %."""
    fit = obj.fit
    if fit is not None and obj.drag_parameter > 0:
        return max(float(fit.drag_sigma) / obj.drag_parameter, AUTO_FITTED_DRAG_SIGMA_MIN)
    if obj.bstar <= 0 and obj.drag_parameter == DEFAULT_DRAG_PARAMETER:
        return AUTO_DRAG_SIGMA_MAX
    return DEFAULT_DRAG_RELATIVE_SIGMA


def object_drag_sigma(obj: CatalogObject, choice: DragSigma) -> float:
    """The relative 1-sigma of Cd*A/m of ``obj`` for ``drag_sigma=choice``: "auto" is
    :func:`_auto_drag_sigma` (the fit's formal relative sigma, at least 0.08; 0.15 without
    a fit) capped at ``AUTO_DRAG_SIGMA_MAX`` (1); a number for every object; a callable
    object -> number. Checked like ``rp.ccsp``'s ``drag_sigma``."""
    if isinstance(choice, str):
        if choice != "auto":
            raise ValueError(f"drag_sigma must be 'auto', a number or a callable, got {choice!r}")
        value: Any = min(_auto_drag_sigma(obj), AUTO_DRAG_SIGMA_MAX)
    elif callable(choice):
        value = choice(obj)
    else:
        value = choice
    try:
        return drag_sigma_argument(value)
    except (TypeError, ValueError) as err:
        raise type(err)(f"object {obj.norad_id} ({obj.name}): {err}") from None


def _drag_note(obj: CatalogObject, sigma: float, choice: Any) -> str:
    """What the propagation includes, in words, for a relative Cd*A/m sigma ``sigma``."""
    if sigma == 0.0:
        return PROPAGATED_NOTE
    if isinstance(choice, str):
        why = (
            f"the fit's formal sigma, at least {AUTO_FITTED_DRAG_SIGMA_MIN:g}, at most "
            f"{AUTO_DRAG_SIGMA_MAX:g}"
            if obj.fit is not None
            else "B* scaled to the model's density; it also covers the unfitted state"
            if "scaled to the model" in obj.covariance_note
            else "assumed, no fit"
        )
    else:
        why = "user-supplied"
    return (
        f"propagated: density uncertainty of the model (kappa) and the ballistic "
        f"coefficient's (Cd*A/m relative 1-sigma {sigma:.3g}, {why}); not included: "
        f"space-weather forecast error beyond the model's driver sigma, manoeuvres"
    )


_PAPER_NOTE = "initial covariance: the paper's near-zero 1 mm, 1 um/s (Monte Carlo: none)"


def _initial_covariance(obj: CatalogObject, choice: Any) -> tuple[np.ndarray | None, str]:
    """The initial covariance (6, 6) of ``obj`` for ``initial_covariance=choice`` and
    what it includes, in words; None for the propagators' own default (the paper's
    near-zero covariance in the CCSP, an exact initial state in a Monte Carlo)."""
    from .covariance import tle_covariance

    if isinstance(choice, str) and choice == "object":
        if obj.covariance is not None:
            return np.asarray(obj.covariance, dtype=float), obj.covariance_note
        return None, _PAPER_NOTE
    if choice is None or isinstance(choice, str):
        if choice is None or choice == "paper":
            return None, _PAPER_NOTE
        if choice == "tle":
            from .covariance import tle_accuracy
            from .elements import _tle_note

            return tle_covariance(obj.state), _tle_note(tle_accuracy(obj.state))
        raise ValueError(
            f"initial_covariance must be 'object', 'tle', 'paper', a (6, 6) matrix or a "
            f"callable, got {choice!r}"
        )
    if callable(choice):
        cov = np.asarray(choice(obj), dtype=float)
        note = "initial covariance: user-supplied (per object)"
    else:
        cov = np.asarray(choice, dtype=float)
        note = "initial covariance: user-supplied matrix"
    if cov.shape != (6, 6):
        raise ValueError(f"initial_covariance must be a (6, 6) matrix, got shape {cov.shape}")
    if not np.all(np.isfinite(cov)):
        raise ValueError("initial_covariance must be finite, got NaN or infinite entries")
    return cov, note


class Status(enum.Enum):
    """How one object's run ended (the strings of :data:`STATUSES` in results)."""

    PROPAGATED = "propagated"
    DECAYED = "decayed"
    SHORTENED = "shortened"
    FAILED = "failed"
    STALE = "stale"
    NON_GAUSSIAN = "non_gaussian"


@dataclass(frozen=True)
class RunSettings:
    """The settings every object of a catalog run shares (checked by
    :func:`propagate_catalog`): the uncertainty ``method`` (a :class:`~rhoprop.MonteCarlo`,
    object i seeded ``seed + i``, or a :class:`~rhoprop.Ccsp`), the ``floor_altitude``
    (m), ``errors`` ("raise" or "record"), the ``zonal_degree``, and the user's
    ``integrator`` and fixed ``step`` (s) of :class:`~rhoprop.Dynamics` (None: the CCSP's
    RK8 at each object's :func:`catalog_step`, the Monte Carlo's RK8 at 180 s)."""

    method: Method
    floor_altitude: float
    errors: str
    zonal_degree: int
    integrator: Integrator | None = None
    step: float | None = None
    #: Factor on the model's density sigma in the CCSP and the Monte Carlo (1: the
    #: model's own; a mixture's calibrated spread, :class:`~rhoprop.density.SigmaScaled`).
    sigma_scale: float = 1.0

    @property
    def dynamics(self) -> Dynamics:
        """The :class:`~rhoprop.Dynamics` every object's run integrates with."""
        return Dynamics(
            zonal_degree=self.zonal_degree,
            floor_altitude=self.floor_altitude,
            integrator=self.integrator,
            step=self.step,
        )

    @classmethod
    def checked(
        cls,
        method: Method,
        dynamics: Dynamics,
        errors: str,
        sigma_scale: float = 1.0,
        function: str = "propagate_catalog",
    ) -> RunSettings:
        """The settings of a run, checked (ValueError or TypeError naming the argument):
        ``dynamics``' integrator must be one the method integrates with (RK8 for the
        CCSP); the method's settings that the catalog takes per object or not at all
        (its own outputs, ``drag_sigma`` and progress; the CCSP's scaling, perturbation
        and coordinates) must be at their defaults."""
        if isinstance(method, Ccsp):
            require_defaults(
                method,
                function,
                ("scaling", "perturbation", "drag_sigma", "coordinates"),
                "a catalog's CCSP runs the calibrated filter in equinoctial elements, "
                "with each object's own drag_sigma",
            )
            integrators: tuple[str, ...] = ("rk8",)
        else:
            require_defaults(
                method,
                function,
                ("output_step", "drag_sigma", "record_density", "progress"),
                "a catalog has its own output_step, drag_sigma and progress",
            )
            # Object i runs with seed + i: room for any catalog below 2**64.
            _validate.seed(method.seed, limit=2**63)
            integrators = MONTE_CARLO_INTEGRATORS
        dynamics.require_integrator(function, integrators)
        return cls(
            method=method,
            floor_altitude=dynamics.floor_altitude,
            errors=errors,
            zonal_degree=zonal_degree_argument(dynamics.zonal_degree),
            integrator=dynamics.integrator,
            step=dynamics.step,
            sigma_scale=_validate.positive("sigma_scale", sigma_scale),
        )

    @property
    def update_interval(self) -> float:
        """The CCSP's update interval, s (hourly when the method leaves it None)."""
        given = self.method.update_interval if isinstance(self.method, Ccsp) else None
        return DEFAULT_UPDATE_INTERVAL if given is None else given

    @property
    def kappa(self) -> KappaProcess | None:
        """The method's kappa process (None: the calibrated default)."""
        return self.method.kappa


@dataclass(frozen=True)
class ObjectOutcome:
    """One object's run: means (nt, 6) and covariances (nt, 6, 6) on the common epochs
    (NaN where invalid), which are ``valid``, the mean orbit's decay (s from the object's
    epoch, or None), the fraction of members decayed, the :class:`Status` and its reason,
    the exception of a failed object (``errors="record"``) and, per epoch, whether the
    Cartesian Gaussian holds the spread (:mod:`~rhoprop.propagation.gaussian_check`)."""

    mean: np.ndarray
    cov: np.ndarray
    valid: np.ndarray
    decay: float | None
    fraction: float
    status: Status
    reason: str
    error: Exception | None = None
    gaussian: np.ndarray | None = None

    @classmethod
    def without_output(
        cls, nt: int, status: Status, reason: str, error: Exception | None = None
    ) -> ObjectOutcome:
        """An object with no valid output (failed, or not run): NaN on all ``nt`` epochs."""
        return cls(
            mean=np.full((nt, 6), np.nan),
            cov=np.full((nt, 6, 6), np.nan),
            valid=np.zeros(nt, dtype=bool),
            decay=None,
            fraction=0.0,
            status=status,
            reason=reason,
            error=error,
        )


@dataclass(frozen=True)
class ObjectPlan:
    """What one object of a catalog run is run with, decided once before any run: its
    index in the catalog, the object, its initial covariance (None: the propagators'
    default) and what that covariance includes, its Cd*A/m relative sigma and its RK8
    step (s, :func:`catalog_step`). A user's ``initial_covariance`` callable is called
    here, once per object. ``epochs``: the object's own output epochs (increasing,
    datetime64[ns] UTC) where a run gives each object its own instead of common ones
    (:func:`~rhoprop.catalog.run.propagate_to_own_epochs`)."""

    index: int
    obj: CatalogObject
    initial: np.ndarray | None
    initial_note: str
    drag_sigma: float
    step: float = DEFAULT_STEP["rk8"]
    epochs: np.ndarray | None = None

    def output_epochs(self, common: np.ndarray) -> np.ndarray:
        """The epochs this object's outputs are at: its own, else the run's ``common``."""
        return common if self.epochs is None else self.epochs


def _plans(
    objs: list[CatalogObject],
    initial_covariance: Any,
    drag_sigma: Any,
    model: Any = None,
    step: float | None = None,
) -> list[ObjectPlan]:
    """One :class:`ObjectPlan` per object, in catalog order; with ``model``, an object
    whose Cd*A/m is B*'s plain conversion runs with it scaled to the model
    (:func:`scaled_bstar_drag`); each with the fixed ``step`` (s), or its own
    :func:`catalog_step` when None."""
    plans = []
    for i, obj in enumerate(objs):
        scaled = scaled_bstar_drag(obj, model) if model is not None else obj
        initial, note = _initial_covariance(scaled, initial_covariance)
        sigma = (
            SCALED_BSTAR_DRAG_SIGMA
            if scaled is not obj and isinstance(drag_sigma, str) and drag_sigma == "auto"
            else object_drag_sigma(scaled, drag_sigma)
        )
        own = catalog_step(scaled.state) if step is None else step
        plans.append(ObjectPlan(i, scaled, initial, note, sigma, own))
    return plans


#: RK8 steps per period of a circular orbit at the perigee radius, for high orbits
#: (:func:`catalog_step`).
STEPS_PER_PERIGEE_PERIOD = 64


def catalog_step(state: OrbitState) -> float:
    """RK8 step (s) of a catalog object's CCSP and mean orbit: the RK8 default (180 s)
    where the perigee is low, longer for high orbits: 1 / :data:`STEPS_PER_PERIGEE_PERIOD`
    of the period of a circular orbit at the perigee radius, shortened by sqrt(1 + e) for
    the faster perigee passage of an eccentric orbit (GEO 1,350 s, GPS 630 s; every orbit
    with perigee below about 5,000 km keeps 180 s). Measured error of the step over 7 days
    through NRLMSIS 2.1 against RK8 at 30 s: GEO 1,800 s 0.6 mm, MEO (20,000 km) 900 s
    0.6 mm, against 1 m at 550 km and 9 m at 310 km for the 180 s every LEO object keeps
    (docs/performance.md). An unbound state keeps 180 s."""
    a, e = axis_and_eccentricity(state)
    if not np.isfinite(a):
        return DEFAULT_STEP["rk8"]
    perigee_period = 2.0 * np.pi * np.sqrt((a * (1.0 - e)) ** 3 / MU)
    h = perigee_period / (STEPS_PER_PERIGEE_PERIOD * np.sqrt(1.0 + e))
    return float(max(DEFAULT_STEP["rk8"], h))


#: Relative Cd*A/m sigma of ``drag_sigma="auto"`` for an unfitted object whose B* was
#: scaled to the model: its Cd*A/m is the fit's to 1-2 %, but its state is SGP4's
#: osculating one, whose mean-motion error the fit would remove; the wider sigma covers it.
#: Chosen on the four development weeks of ``benches/catalog_realism.py`` together: with
#: 0.08 (the fitted floor) 53-90 % of objects fell inside 2 sigma along-track, with 0.5
#: 97-98 % in every week (docs/catalog-realism.md).
SCALED_BSTAR_DRAG_SIGMA = 0.5

#: Span (s) after the epoch over which :func:`scaled_bstar_drag` averages the densities.
SCALE_SPAN = 86400.0
#: Perigee (km, of the element set's mean elements) below which B* keeps its plain
#: conversion. Chosen on the 11 real decays of ``benches/reentry.py`` whose fit fails (all
#: 1-2.5 days before reentry, perigee 202-300 km): scaled to NRLMSIS 2.1 the 95 % window
#: held 3 of them, plain 8 (scaled, the five at 219-249 km came down a day early); the
#: scaling was chosen on objects at 400-2,000 km. The same rule for catalog and reentry
#: runs keeps their decay epochs of one element set in agreement.
SCALED_BSTAR_MIN_PERIGEE_KM = 250.0


def scaled_bstar_drag(obj: CatalogObject, model: ModelLike) -> CatalogObject:
    """``obj`` with its Cd*A/m scaled from B*'s plain conversion to ``model``: B* was
    fitted with SGP4's static density, so the same deceleration with the model's density
    needs Cd*A/m times rho_SGP4 / rho_model, averaged over the element set's SGP4 orbit
    for a day from its epoch (:func:`~rhoprop.catalog.fit.bstar_prior`, the fit's prior,
    which matches the fitted Cd*A/m to 1-2 %; ``drag_sigma="auto"`` then propagates
    :data:`SCALED_BSTAR_DRAG_SIGMA`). Only for models of the real atmosphere (a sampled
    model, its atlas, a ``DensityField``); analytic atmospheres (``Exponential``, a
    function) are test atmospheres, with which B* keeps its plain conversion. Objects
    fitted, given their Cd*A/m, with B* <= 0 or with perigee below
    :data:`SCALED_BSTAR_MIN_PERIGEE_KM` come back as they are, and so does any whose
    densities cannot be evaluated (note unchanged)."""
    import dataclasses

    from ..density import SampledModel
    from .fit import _perigee_km, _sgp4_observations, bstar_prior, drag_parameter_from_bstar

    if obj.fit is not None or obj.bstar <= 0:
        return obj
    if obj.drag_parameter != drag_parameter_from_bstar(obj.bstar):
        return obj
    sat = obj.satrec()
    if sat is None:
        return obj
    times = np.arange(0.0, SCALE_SPAN + 1.0, 600.0)
    try:
        r, _ = _sgp4_observations(sat, times)
    except ValueError:
        return obj
    epochs = obj.state.epoch + (times * 1e9).astype("timedelta64[ns]")
    atmosphere = model.atlas if isinstance(model, SampledModel) else model
    if not _real_atmosphere(atmosphere):
        return obj  # an analytic test atmosphere (Exponential, a function): as given
    perigee = _perigee_km(sat)
    if perigee < SCALED_BSTAR_MIN_PERIGEE_KM:
        return obj  # near reentry: the plain conversion (see the constant)
    value, _, note = bstar_prior(obj.bstar, perigee, atmosphere, epochs, r)
    if not note.startswith("prior from B*"):
        return obj
    return dataclasses.replace(
        obj,
        drag_parameter=value,
        covariance_note=f"{obj.covariance_note}; Cd*A/m scaled to the model: "
        f"{note.removeprefix('prior from B*: ')}",
    )


#: Objects that ``propagate_catalog(fit="auto")`` fits before it runs them: those with
#: perigee below this altitude (km) and the deep-space ones. Infinite since 2026-12-04:
#: every object whose Cd*A/m comes from its element set is fitted. Below 700 km (the four
#: development weeks of ``benches/catalog_realism.py``) the fit halves the along-track
#: error of B*'s scaled conversion (pooled 8.5 against 15.2 km); at 700-2,000 km (the
#: same weeks, 150 objects each, ``--altitudes 700,2000 --configs default,fit``, forecast
#: drivers) the raw SGP4 state at epoch drifts (median 8.5 km against SGP4's 0.22 km, 38x)
#: and the fitted one predicts 0.20 km, 0.90x SGP4's (0.96 / 0.86 / 0.95 / 0.68 per week),
#: along-track inside 2 sigma 99 % (docs/catalog-realism.md, "Fitted at every altitude").
AUTO_FIT_PERIGEE_KM = float("inf")
#: SGP4's near-Earth limit of the period, min. Deep-space orbits (period at least this)
#: are fitted too: their dynamics carry the Sun, the Moon and the tesseral field (as SDP4 does), and
#: an SGP4 state (mean in those terms) started under them drifts along-track by km a day;
#: fitted, 40 objects of 2023-11-13 each came 6 days later within a median 15 km of their
#: 2023-11-19 element sets (GEO), 2.3 km (GPS), 1.4 km (other MEO), against 25, 5.7 and
#: 6.2 km from SGP4's state without those forces (SGP4 itself: 8.1, 1.0, 0.8 km;
#: docs/catalog-realism.md, "Deep space").
AUTO_FIT_MAX_PERIOD_MIN = 225.0

FitChoice = bool | Literal["auto"]


def _real_atmosphere(model: object) -> bool:
    """Whether ``model`` is a model of the real atmosphere (sampled, an atlas, a field)."""
    from ..density import DensityField, SampledModel
    from ..density.atlas import Atlas

    return isinstance(model, (SampledModel, Atlas, DensityField))


@dataclass(frozen=True)
class Initial:
    """How each object of a catalog run starts: its state (fitted or not) and its initial
    uncertainty. Checked when made; the per-object values (a matrix, a callable's result)
    when the run plans each object.

    Attributes:
        covariance: each object's initial covariance at its epoch: ``"object"`` (the
            default, as in ``rhoprop catalog``): the object's own ``covariance`` (``load``
            sets the published TLE accuracy of its regime; fitted objects add the fit's);
            ``"tle"``: the TLE accuracy of the regime; ``"paper"`` or None: the paper's
            near-zero diag(1 mm^2, 1 um^2/s^2), 100x too small for TLE-derived states
            (docs/catalog-realism.md; the default until 0.1); a (6, 6) matrix (m^2,
            m^2/s, m^2/s^2, inertial) for every object; or a callable object -> matrix.
            What it includes is in the result's ``covariance_note`` (and the OEM and
            summary).
        drag_sigma: relative 1-sigma of each object's Cd*A/m (dimensionless, 0.15 =
            15 %), propagated as the CCSP's second consider parameter or sampled per Monte
            Carlo member (log-normal, see ``rp.monte_carlo``): ``"auto"`` (default) the
            fit's formal relative sigma but at least 0.08 (at most 1, for fits whose prior
            dominated); for an object without a fit whose B* is scaled to a real model
            0.5, else 0.15 (as ``rp.catalog.reentry``); a number for every object (0:
            none); or a callable object -> number. Recorded in the result's
            ``drag_sigma`` and ``covariance_note`` (docs/catalog-realism.md).
        fit: ``"auto"`` (default): with a model of the real atmosphere, the objects whose
            Cd*A/m comes from the element set (B*, or the guess for B* <= 0), at every
            altitude, are first fitted to their element sets with the run's model (state
            and Cd*A/m, :func:`~rhoprop.catalog.fit_objects`, in the core at about 100
            objects/s on 2 cores; :data:`AUTO_FIT_PERIGEE_KM`); True: every unfitted
            object with an element set; False: none (B* scaled to the model). A failed
            fit leaves the object as it was, the failure in its note.

    Example:
        >>> import rhoprop as rp
        >>> rp.catalog.Initial(covariance="tle", fit=False).drag_sigma
        'auto'
    """

    covariance: InitialCovariance = "object"
    drag_sigma: DragSigma = "auto"
    fit: FitChoice = "auto"

    def __post_init__(self) -> None:
        c = self.covariance
        if isinstance(c, str) and c not in COVARIANCE_NAMES:
            raise ValueError(
                f"covariance (a catalog run's initial_covariance) must be one of "
                f"{', '.join(map(repr, COVARIANCE_NAMES))}, a (6, 6) matrix, a callable or "
                f"None, got {c!r}"
            )
        d = self.drag_sigma
        if isinstance(d, str) and d != "auto":
            raise ValueError(f"drag_sigma must be 'auto', a number or a callable, got {d!r}")
        if not isinstance(d, str) and not callable(d) and not _validate.is_real(d):
            raise TypeError(
                f"drag_sigma must be 'auto', a number or a callable, got {type(d).__name__}"
            )
        if not (isinstance(self.fit, bool) or (isinstance(self.fit, str) and self.fit == "auto")):
            raise ValueError(f"fit must be True, False or 'auto', got {self.fit!r}")


def fit_choice(obj: CatalogObject, fit: FitChoice) -> bool:
    """Whether ``propagate_catalog(fit=...)`` fits ``obj``: never if False or if it is
    fitted already or carries no element set; if True every other object; if "auto" the
    near-Earth ones below :data:`AUTO_FIT_PERIGEE_KM` (since 2026-12-04 all of them) and
    the deep-space ones (period of at least :data:`AUTO_FIT_MAX_PERIOD_MIN`) whose Cd*A/m
    comes from B* (or is the guess of a B* <= 0 element set) rather than from the user."""
    from .fit import _drag_from_element_set, _perigee_km

    if fit is False or obj.fit is not None:
        return False
    sat = obj.satrec()
    if sat is None:
        return False
    if fit is True:
        return True
    period = 2 * np.pi / sat.no_kozai if sat.no_kozai > 0 else np.inf
    deep = period >= AUTO_FIT_MAX_PERIOD_MIN
    return bool(_drag_from_element_set(obj) and (deep or _perigee_km(sat) < AUTO_FIT_PERIGEE_KM))


def fit_catalog_objects(
    objs: list[CatalogObject],
    model: ModelLike,
    fit: FitChoice,
    dynamics: Dynamics,
    progress: bool = False,
) -> list[CatalogObject]:
    """``objs`` with those :func:`fit_choice` picks fitted to their element sets with
    ``model`` (real-atmosphere models only; batched in the core,
    :func:`~rhoprop.catalog.fit_objects`) at the zonal degree of the run's ``dynamics``
    (the fit keeps its own RK8 grid and floor). An object whose fit fails stays as it was,
    the failure in its ``covariance_note``. ``progress``: a progress bar (or log lines)
    of the objects fitted."""
    import dataclasses

    from .elements import fit_objects

    if fit not in (True, False, "auto"):
        raise ValueError(f"fit must be True, False or 'auto', got {fit!r}")
    if not _real_atmosphere(model):
        return objs
    picked = [i for i, o in enumerate(objs) if fit_choice(o, fit)]
    if not picked:
        return objs
    out = list(objs)
    bar = ProgressBar(len(picked), "catalog: fitting", unit="objects") if progress else None
    try:
        fitted = fit_objects(
            [objs[i] for i in picked],
            model,
            dynamics=Dynamics(zonal_degree=dynamics.zonal_degree),
            progress=bar,
        )
    finally:
        if bar is not None:
            bar.close()
    for i, f in zip(picked, fitted, strict=True):
        if isinstance(f, Exception):
            note = f"{objs[i].covariance_note}; fit failed: {type(f).__name__}: {f}"
            out[i] = dataclasses.replace(objs[i], covariance_note=note)
        else:
            out[i] = f
    return out


def _run_object(
    plan: ObjectPlan,
    model: Any,
    epochs: np.ndarray,
    cfg: RunSettings,
    stop: threading.Event | None = None,
    done: dict[str, Any] | None = None,
) -> ObjectOutcome:
    """Propagates one object to the common epochs; returns arrays for the result. With
    ``cfg.errors == "record"`` an error becomes status "failed"; else it is raised
    with the object named and chained to the cause. ``stop`` (local runs) ends the
    object's Monte Carlo early after Ctrl-C in the caller. ``done`` holds runs already
    made for this object by :func:`_ccsp_chunk` (its mean orbit, its CCSP), used instead
    of running them again. Epochs before the object's own (a run's ``start`` before it)
    are not valid: rhoprop propagates forward only."""
    if stop is not None and stop.is_set():
        raise KeyboardInterrupt("catalog run interrupted")
    epochs = plan.output_epochs(epochs)
    try:
        lead = leading_epochs(epochs, plan.obj)
        out = _propagate_object(plan, model, epochs[lead:], cfg, stop, done or {})
        return out if not lead else _after(out, lead)
    except Exception as err:
        if cfg.errors == "raise":
            named = object_error(err, plan.obj)
            if named is err:
                raise
            raise named from err
        return ObjectOutcome.without_output(
            len(epochs), Status.FAILED, f"{type(err).__name__}: {err}", err
        )


def leading_epochs(epochs: np.ndarray, obj: CatalogObject) -> int:
    """How many of the (increasing) ``epochs`` come before the object's epoch."""
    return int(np.count_nonzero(to_seconds(epochs, obj.state.epoch) < 0))


def _after(out: ObjectOutcome, lead: int) -> ObjectOutcome:
    """``out`` behind ``lead`` epochs without output (before the object's epoch)."""
    import dataclasses

    def pad(a: np.ndarray, fill: float) -> np.ndarray:
        return np.concatenate([np.full((lead, *a.shape[1:]), fill, dtype=a.dtype), a])

    return dataclasses.replace(
        out,
        mean=pad(out.mean, np.nan),
        cov=pad(out.cov, np.nan),
        valid=pad(out.valid, False),
        gaussian=None if out.gaussian is None else pad(out.gaussian, True),
    )


def _propagate_object(
    plan: ObjectPlan,
    model: Any,
    epochs: np.ndarray,
    cfg: RunSettings,
    stop: threading.Event | None,
    done: dict[str, Any],
) -> ObjectOutcome:
    obj, initial = plan.obj, plan.initial
    craft = Spacecraft(1.0, obj.drag_parameter)
    offsets = to_seconds(epochs, obj.state.epoch)
    nt = len(epochs)
    out_mean = np.full((nt, 6), np.nan)
    out_cov = np.full((nt, 6, 6), np.nan)
    fraction = 0.0
    gaussian = np.ones(nt, dtype=bool)
    status, reason = Status.PROPAGATED, ""
    uncertain = _with_spread(model, cfg)
    if isinstance(cfg.method, Ccsp):
        decay, k = _mean_orbit(obj, craft, model, offsets, cfg, done, plan.step)
        if k:
            means, covs, stopped, checked = _ccsp_outputs(
                obj,
                craft,
                uncertain,
                offsets[:k],
                cfg,
                initial,
                plan.drag_sigma,
                done.get("ccsp"),
                plan.step,
            )
            reached = len(means)
            out_mean[:reached], out_cov[:reached] = means, covs
            gaussian[:reached] = checked
            if stopped:
                status, reason = Status.SHORTENED, stopped
    else:

        def check(_done: int) -> None:
            # Called by the core about every 50 ms: ends the run once the caller stops.
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt("catalog run interrupted")

        mc = monte_carlo(
            obj.state,
            craft,
            uncertain,
            output_times=offsets,
            n=cfg.method.n,
            drag_sigma=plan.drag_sigma,
            kappa=cfg.method.kappa,
            seed=cfg.method.seed + plan.index,
            output_step=None,
            initial_covariance=initial,
            perturbation=cfg.method.perturbation,
            threads=cfg.method.threads,
            max_memory=cfg.method.max_memory,
            progress=check,
            dynamics=cfg.dynamics,
        )
        decay = mc.mean_orbit.decayed_at
        m = mc.moments()
        out_mean[:], out_cov[:] = m.mean, m.covariance
        fraction = float(np.mean(mc.decayed))
        gaussian[:] = holds(coverage=member_coverage(mc.positions, m.mean, m.covariance))
    valid = np.isfinite(out_cov).all(axis=(1, 2)) & np.isfinite(out_mean).all(axis=1)
    out_mean[~valid], out_cov[~valid] = np.nan, np.nan
    gaussian[~valid] = True  # nothing to judge
    status, reason = _gaussian_status(gaussian, epochs, status, reason)
    if decay is not None:
        at = add_seconds(obj.state.epoch, decay)
        # Decay is the headline; an earlier stop of the CCSP stays in the reason.
        reason = f"the mean orbit decays at {_iso(at)}" + (f"; {reason}" if reason else "")
        status = Status.DECAYED
    return ObjectOutcome(
        mean=out_mean,
        cov=out_cov,
        valid=valid,
        decay=decay,
        fraction=fraction,
        status=status,
        reason=reason,
        gaussian=gaussian,
    )


def _gaussian_status(
    gaussian: np.ndarray, epochs: np.ndarray, status: Status, reason: str
) -> tuple[Status, str]:
    """The status and reason of a run whose Cartesian Gaussian does not hold at some
    epochs (``gaussian`` False): "non_gaussian" for a run otherwise propagated, its
    reason naming the first such epoch (a decayed or shortened run keeps its status)."""
    if gaussian.all():
        return status, reason
    bad = int(np.flatnonzero(~gaussian)[0])
    said = (
        f"from {_iso(epochs[bad])} the Cartesian covariance does not hold the spread's "
        "shape: it curves along the orbit (its moments stay right; for the shape use "
        "method=rp.MonteCarlo(...) or rhoprop.ccsp's element_covariance)"
    )
    return (
        Status.NON_GAUSSIAN if status is Status.PROPAGATED else status,
        f"{reason}; {said}" if reason else said,
    )


def _with_spread(model: Any, cfg: RunSettings) -> Any:
    """``model`` with its density sigma times ``cfg.sigma_scale`` (itself when 1)."""
    return model if cfg.sigma_scale == 1.0 else SigmaScaled(model, cfg.sigma_scale)


def _mean_orbit(
    obj: CatalogObject,
    craft: Spacecraft,
    model: Any,
    offsets: np.ndarray,
    cfg: RunSettings,
    done: dict[str, Any],
    step: float | None = None,
) -> tuple[float | None, int]:
    """The decay time of the mean orbit (s from the object's epoch, or None) and how many
    of ``offsets`` come before it; the propagation is kept in ``done["mean"]`` (None when
    :func:`_ccsp_chunk` found the object clear of the floor: no decay)."""
    if done.get("mean", False) is None:
        return None, len(offsets)
    if "mean" not in done:
        done["mean"] = propagate(
            obj.state,
            craft,
            model,
            float(offsets[-1]),
            dynamics=replace(cfg.dynamics, integrator="rk8", step=step),
        )
    decay = done["mean"].decayed_at
    return decay, int(np.count_nonzero(offsets < (np.inf if decay is None else decay)))


def _ccsp_chunk(
    model: Any,
    chunk: list[ObjectPlan],
    epochs: np.ndarray,
    cfg: RunSettings,
    stop: threading.Event | None = None,
) -> list[tuple[int, ObjectOutcome]]:
    """The CCSP objects of a chunk: each object's mean orbit first, then the CCSPs of all
    of them in one core call (objects in parallel, each object's sigma points in one
    batch; bit-identical to running each alone), then each object as
    :func:`_run_object` with those runs reused. An object whose mean orbit or batched
    CCSP raised runs again alone, so statuses, shortened runs, field widening and errors
    are exactly those of the object-by-object run."""
    done: dict[int, dict[str, Any]] = {p.index: {} for p in chunk}
    runs, owners = [], []
    for plan in chunk:
        if stop is not None and stop.is_set():
            raise KeyboardInterrupt("catalog run interrupted")
        i, obj = plan.index, plan.obj
        craft = Spacecraft(1.0, obj.drag_parameter)
        own = plan.output_epochs(epochs)
        offsets = to_seconds(own, obj.state.epoch)
        offsets = offsets[leading_epochs(own, obj) :]
        if offsets[-1] <= 0:
            continue
        updates, outputs = update_schedule(obj.state, offsets, cfg.update_interval)
        # Optimistically over every output: the mean orbit (one lane, for its decay time)
        # is needed only if the CCSP comes near the floor (checked below).
        runs.append(
            CcspRun(
                obj.state,
                craft,
                updates,
                initial_covariance=plan.initial,
                drag_sigma=plan.drag_sigma,
                step=plan.step,
                output_times=outputs,
                kappa=cfg.kappa,
            )
        )
        owners.append(i)

    def check(_done: int) -> None:
        # Called by the core about every 50 ms: ends the call once the caller stops.
        if stop is not None and stop.is_set():
            raise KeyboardInterrupt("catalog run interrupted")

    if runs:
        try:
            outs = ccsp_many(
                runs,
                _with_spread(model, cfg),
                dynamics=Dynamics(zonal_degree=cfg.zonal_degree, floor_altitude=cfg.floor_altitude),
                progress=check,
            )
        except Exception:
            outs = []  # every object runs alone, raising (or recording) as before
        for i, out in zip(owners, outs, strict=False):
            if not isinstance(out, Exception) and _clear_of_floor(out, cfg):
                done[i]["ccsp"] = out
                done[i]["mean"] = None  # the mean orbit cannot have come down
    return [(p.index, _run_object(p, model, epochs, cfg, stop, done[p.index])) for p in chunk]


#: How far above the floor (m) a CCSP's mean must stay, at every update, for the mean
#: orbit's decay check to be skipped: an orbit on its way down within the span has its
#: sigma points come down (the CCSP stops) or its mean sinks towards the floor first.
MEAN_ORBIT_MARGIN = 50e3


def _clear_of_floor(result: CcspResult, cfg: RunSettings) -> bool:
    """Whether a CCSP ran to its end with its mean at least :data:`MEAN_ORBIT_MARGIN`
    above the floor throughout (|r| - equatorial radius, a lower bound of the geodetic
    altitude)."""
    if result.decayed_at is not None:
        return False
    low = float(np.min(np.linalg.norm(result.mean[:, :3], axis=1))) - R_EARTH
    return bool(low > float(cfg.floor_altitude) + MEAN_ORBIT_MARGIN)


#: Perigee altitude (m) below which a CCSP covariance that loses definiteness is said to
#: be near decay; above it the spread has outgrown one Gaussian (an HEO of 372 x 31,841 km
#: was reported "near decay").
NEAR_DECAY_PERIGEE = 250e3


def _why_indefinite(state: OrbitState) -> str:
    """Why a CCSP covariance of an object starting at ``state`` lost definiteness, in words."""
    a, e = axis_and_eccentricity(state)
    if np.isfinite(a) and a * (1.0 - e) - R_EARTH < NEAR_DECAY_PERIGEE:
        return "near decay"
    return (
        "its spread outgrew one Gaussian, perigee above "
        f"{NEAR_DECAY_PERIGEE / 1e3:.0f} km: method=rp.MonteCarlo(...) gives its shape"
    )


def _iso(t: np.datetime64) -> str:
    return str(t.astype("datetime64[ms]")) + "Z"


def _ccsp_outputs(
    obj: CatalogObject,
    craft: Spacecraft,
    model: Any,
    offsets: np.ndarray,
    cfg: RunSettings,
    initial: np.ndarray | None,
    drag_sigma: float = 0.0,
    first: CcspResult | None = None,
    step: float | None = None,
) -> tuple[np.ndarray, np.ndarray, str, np.ndarray]:
    """CCSP means (k, 6) and covariances (k, 6, 6) at the first k of ``offsets`` (s from
    the object's epoch) it reached, "" or why it stopped before the last, and whether
    the Cartesian Gaussian holds there (k,) (:func:`arc_sag_share`). Only a
    covariance that stops being positive definite (near decay) or a sigma point that
    comes down shortens the outputs; every other error is raised. ``first`` is the run
    over all of ``offsets`` if already made (:func:`_ccsp_chunk`)."""
    state = obj.state

    def run(k: int) -> Any:
        if offsets[k - 1] <= 0:  # every output at the object's own epoch
            return None
        updates, outputs = update_schedule(state, offsets[:k], cfg.update_interval)
        return ccsp(
            state,
            craft,
            model,
            update_times=updates,
            output_times=outputs,
            initial_covariance=initial,
            dynamics=replace(cfg.dynamics, step=step),
            drag_sigma=drag_sigma,
            kappa=cfg.kappa,
        )

    k, why = len(offsets), ""
    try:
        r = first if first is not None and offsets[k - 1] > 0 else run(k)
    except CovarianceError as err:
        if err.time is None or err.time <= 0:
            raise  # the initial covariance itself: bad input, not a shortened run
        t_bad = float(err.time)
        k = int(np.count_nonzero(offsets < t_bad))
        why = (
            f"the CCSP covariance lost positive definiteness at "
            f"{_iso(add_seconds(state.epoch, t_bad))} ({_why_indefinite(state)}); later "
            "outputs invalid"
        )
        if k == 0:
            return np.empty((0, 6)), np.empty((0, 6, 6)), why, np.empty(0, dtype=bool)
        try:
            r = run(k)
        except RhopropError as again:
            raise again from err
    if r is None:
        means = np.broadcast_to(state.state, (k, 6))
        start = paper_covariance() if initial is None else initial
        return means, np.broadcast_to(start, (k, 6, 6)), why, np.ones(k, dtype=bool)
    reached = int(np.count_nonzero(offsets[:k] <= r.times[-1] * (1 + 1e-12)))
    if r.decayed_at is not None and reached < len(offsets):
        why = (
            f"the CCSP stopped when a sigma point came down at "
            f"{_iso(add_seconds(state.epoch, r.decayed_at))}; later outputs invalid"
        )
    pick = np.searchsorted(r.times, offsets[:reached] * (1 - 1e-12))
    checked = np.ones(len(pick), dtype=bool)
    if r.element_mean is not None and r.element_covariance is not None:
        share = arc_sag_share(
            r.element_mean[pick], r.element_covariance[pick], r.rtn_covariance[pick]
        )
        checked = holds(sag_share=share)
    return r.mean[pick], r.covariance[pick], why, checked
