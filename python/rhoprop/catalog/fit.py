"""TLE -> numerical state and ballistic coefficient: a least-squares fit of the initial
state and Cd*A/m to SGP4 positions (pseudo-observations) near the epochs of one or several
element sets of an object, with rhoprop's own dynamics (two-body + zonals + drag, RK8)
and the chosen density model, so that the state and the drag parameter are consistent
with the model the catalog is then propagated with (SGP4's B* absorbs its own static
density).

Method: Gauss-Newton on p = [r (m), v (m/s), Cd*A/m (m^2/kg)] at the newest epoch, run in
the core (``rhoprop._core.fit_orbits``, :func:`fit_histories`): the model is RK8
(:data:`FIT_STEP`, 200 s: each 600 s observation interval cut into 3 equal steps) through
the density model's field; the Jacobian by forward differences (1 m, 1 mm/s, 1 % of Cd*A/m), the
nominal orbit and its seven perturbed neighbours flying as the eight lanes of one SIMD
batch, so an accepted step already holds the next Jacobian; a step that raises the cost
is halved (up to 5 times); an update below 1 cm and 1e-4 relative in Cd*A/m ends the fit.
Many objects per core call, in parallel. ``tests/reference_fit.py`` is the independent
Python version (one propagation per column) the core is checked against.

Observations: SGP4 positions (TEME, taken as inertial) every ``spacing`` s within
``span`` of each element set's epoch (for a history, each element set only up to halfway
to its neighbours: every set speaks near its own epoch, the idea of Levit & Marshall
2011, "Improved orbit predictions using two-line elements", Adv. Space Res. 47). Each is
weighted by SGP4's own error growth away from its epoch, in the RTN frame: the published
TLE accuracy at epoch (:func:`~rhoprop.catalog.covariance.tle_accuracy`: radial,
along-track, cross-track; at 800-2000 km :data:`WEIGHT_ACCURACY`) with the along-track
sigma growing by the regime's drift rate,
sigma_T(dt) = sqrt(sigma_T0^2 + (drift dt)^2). In a history the positions of one element
set weigh together as one observation (sigmas times the square root of their number):
they share the set's error, and counted apart the scatter between sets reads as drag.
In deep-space element sets (SDP4's) each position is first debiased along-track by its
regime's :data:`ALONG_TRACK_BIAS` (SDP4's systematic lag behind precise orbits).

Prior on Cd*A/m (:func:`bstar_prior`): B* converted with the density ratio of SGP4's own
static atmosphere to the fit's model along the element set's orbit (B* was fitted by the
catalog's owner to weeks of tracking with SGP4's density; the same deceleration with the
model's density needs Cd*A/m = B_SGP4 rho_SGP4 / rho_model), with relative 1-sigma
:data:`BSTAR_PRIOR_SIGMA`; where B* <= 0, 0.022 m^2/kg with 100 %. The fitted value is kept
above ``MIN_DRAG_PARAMETER``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from ..density.model import AtmosphereLike, ModelLike
from ..frames import rtn_basis
from ..propagation import OrbitState
from ..propagation.dynamics import Dynamics, deprecated_keywords
from ..time import add_seconds, from_jd, offsets_to_epochs, ut1_seconds

if TYPE_CHECKING:
    from typing_extensions import Unpack

    from .. import _core
    from .covariance import TleAccuracy

#: SGP4 reference density times one Earth radius, kg m^-2 ER^-1 (B* = rho0 B / 2).
SGP4_RHO0 = 0.15696615
#: Cd*A/m (m^2/kg) a fit starts from when B* gives none (B* <= 0): Cd 2.2, A/m 0.01.
DEFAULT_DRAG_PARAMETER = 0.022


def drag_parameter_from_bstar(bstar: float) -> float:
    """Cd*A/m (m^2/kg) from an SGP4 B* (1/Earth radii): 2 B* / rho0."""
    return 2.0 * bstar / SGP4_RHO0


#: The smallest Cd*A/m a fit may return, m^2/kg.
MIN_DRAG_PARAMETER = 1e-4
#: Default fit span around the element set's epoch, s (start, end): the day before it. The
#: element set was fitted to tracking before its epoch; after it SGP4's positions are its
#: own forecast with a static atmosphere. Chosen on the four development weeks together
#: (docs/catalog-realism.md, "The day before the epoch"): every week's median along-track
#: error fell against one day either side, the default until 2026-12-03.
DEFAULT_SPAN = (-86400.0, 0.0)
#: Default fit span of an eccentric (e >= 0.1) deep-space orbit (period of 225 min or
#: more, SDP4's), s: one day either side. Drag does not matter there, and a state in the
#: middle of its arc is better pinned: 20 GEO / 20 GPS objects of 2023-11-13 fitted and
#: run 6 days to their 2023-11-19 element sets came within a median 13.2 / 2.2 km,
#: against 17.2 / 2.4 km with the day before (``tests/test_deep_space.py``, when this
#: span was every deep-space orbit's).
DEEP_SPACE_SPAN = (-86400.0, 86400.0)
#: Fit span of a near-circular (e < 0.1) deep-space orbit (GPS, other MEO, GEO), s: three
#: days either side. Chosen on the four development weeks together (docs/catalog-realism.md,
#: "Deep-space fit span"): against one day either side, GPS medians fell or held in every
#: week, other MEO ones in three and held in the fourth (2026-12-03). GEO kept one day
#: until its fits stopped holding SDP4's radius (:data:`LOOSE_RADIUS_REGIMES`); then
#: three days brought its errors against BeiDou's precise orbits down at 6-47 h (47 h:
#: 0.65 -> 0.53 km) and its weekly medians from 32.4 to 31.4 km summed (2026-12-06).
NEAR_CIRCULAR_SPAN = (-3 * 86400.0, 3 * 86400.0)
#: SDP4's deep-space limit of the period, min.
DEEP_SPACE_PERIOD_MIN = 225.0
#: TLE-accuracy regimes whose fits weight SDP4's radius only as its along-track position
#: (the regime's along-track accuracy, 5 km for GEO, not its 2 km radial). In
#: geosynchronous orbits SDP4's radius and its period disagree by about 130 m of
#: semi-major axis; a fit held to the radius took a semi-major axis that low and ran
#: ahead of BeiDou's precise orbits by about 1.3 km a day. Measured 2026-12-06 on the
#: development data together (docs/catalog-realism.md, "GEO fits: the period, not
#: SDP4's radius"): against the precise orbits (7 GEO, 9 IGSO) the GEO error after 47 h
#: fell from 2.77 to 0.65 km (SDP4 2.18), against the four weeks' later element sets
#: (themselves SDP4) the GEO medians moved 1.96 / 15.38 / 11.60 / 8.66 ->
#: 2.34 / 11.67 / 6.31 / 12.10 km.
LOOSE_RADIUS_REGIMES = ("GEO",)


#: The fit's weights of regimes whose covariance accuracy (:data:`~rhoprop.catalog.
#: covariance.REGIMES`) holds an error the fit follows rather than averages: radial,
#: along-track, cross-track m. At 800-2000 km the covariance carries SGP4's
#: once-per-revolution error of the orbit's shape and plane against precise orbits
#: (300 / 700 / 350 m since 2026-12-06); every position of an element set shares it, so
#: the fit inherits it whatever the weights, and weighting by it only loosened the fit
#: (the four weeks' 700-2,000 km median 1.00 -> 1.03 of SGP4's, 1.14 / 1.32 / 1.23 / 0.71
#: by week). The weights keep the accuracy they were chosen with.
WEIGHT_ACCURACY = {"LEO 800-2000 km": (150.0, 600.0, 250.0)}


def _weight_accuracy(accuracy: TleAccuracy) -> TleAccuracy:
    """``accuracy`` as the fit weights its positions (:data:`WEIGHT_ACCURACY`)."""
    if accuracy.regime not in WEIGHT_ACCURACY:
        return accuracy
    radial, along, cross = WEIGHT_ACCURACY[accuracy.regime]
    return replace(accuracy, radial=radial, along_track=along, cross_track=cross)


#: TLE debiasing (Hallgarten La Casta & Amato 2024, "Debiasing of two-line element sets
#: for batch least squares pseudo-orbit determination in MEO and GEO", arXiv:2412.15793):
#: SGP4's systematic along-track error, m (its position minus the truth; negative: SGP4
#: lags), by TLE-accuracy regime (:data:`~rhoprop.catalog.covariance.REGIMES`), removed
#: from the pseudo-observations of deep-space element sets (SDP4's, period of at least
#: :data:`DEEP_SPACE_PERIOD_MIN`) before the fit. Element sets share it, so later element
#: sets cannot show it; precise orbits can. Measured 2026-12-07 on GFZ's precise orbits
#: of BeiDou (2024-06-17..18, ``benches/precise_gnss.py``): the undebiased fits of 23 of
#: 27 MEO satellites lag (median -484 m over 0-47 h), of 15 of the 16 geosynchronous ones
#: ("GEO": 7 GEO, 9 IGSO; median -379 m); SDP4 itself lags by 625 and 487 m. Debiased,
#: the median position error over 0-47 h falls from 650 to 453 m (MEO) and from 630 to
#: 594 m (GEO); cross-validated (each satellite by the others' median; for MEO also by
#: the other orbital planes') 474 and 581 m, 610 m (docs/catalog-realism.md, "TLE
#: debiasing"). One constellation over two days: other MEO and GEO element sets are
#: assumed alike. None in LEO: there a bias measured between an object's own element
#: sets foresees nothing (``benches/tle_debias_leo.py``: SGP4's 1- and 3-day predictions
#: of the 2026 history 2-52 % worse) and the two precise orbits at 1,336 km disagree
#: (Jason-1 +302 m, TOPEX +40 m).
ALONG_TRACK_BIAS: dict[str, float] = {"MEO": -490.0, "GEO": -370.0}


def along_track_biases(table: Mapping[str, float] | None) -> dict[str, float]:
    """``table`` (regime name -> SGP4's along-track bias, m) checked, or a copy of
    :data:`ALONG_TRACK_BIAS` for None; ``{}`` removes none."""
    from .._validate import is_real
    from .covariance import REGIMES

    if table is None:
        return dict(ALONG_TRACK_BIAS)
    if not isinstance(table, Mapping):
        raise TypeError(
            f"along_track_bias must be a mapping of regime name to metres, got "
            f"{type(table).__name__}"
        )
    names = [row[3].regime for row in REGIMES]
    out = {}
    for name, value in table.items():
        if name not in names:
            raise ValueError(
                f"along_track_bias: unknown regime {name!r}; the regimes are "
                f"{', '.join(map(repr, names))}"
            )
        if not is_real(value) or not np.isfinite(float(value)):
            raise ValueError(
                f"along_track_bias[{name!r}] must be a finite number of metres, got {value!r}"
            )
        out[name] = float(value)
    return out


def _orbit_class(period_min: float, eccentricity: float) -> str:
    """ "near-Earth" (period under :data:`DEEP_SPACE_PERIOD_MIN`), else "near-circular"
    (e < 0.1) or "eccentric" deep space: what the fit's span and step follow."""
    if period_min < DEEP_SPACE_PERIOD_MIN:
        return "near-Earth"
    return "near-circular" if eccentricity < 0.1 else "eccentric"


def _near_circular_deep_space(epoch: np.datetime64, state: np.ndarray) -> bool:
    """Whether the TEME state ``state`` (m, m/s) at ``epoch`` is a near-circular deep-space
    orbit (:func:`_orbit_class` of its osculating period and eccentricity)."""
    from ..propagation.propagate import axis_and_eccentricity, orbital_period

    orbit = OrbitState(epoch, state[:3], state[3:6], "TEME")
    _, e = axis_and_eccentricity(orbit)
    return _orbit_class(orbital_period(orbit) / 60.0, e) == "near-circular"


def _element_set_class(sat: Any) -> str:
    """:func:`_orbit_class` of an ``sgp4`` ``Satrec``'s mean motion and eccentricity."""
    period = 2 * np.pi / sat.no_kozai if sat.no_kozai > 0 else np.inf
    return _orbit_class(period, sat.ecco)


def default_span(sat: Any) -> tuple[float, float]:
    """The fit span of an ``sgp4`` ``Satrec`` (s from its epoch), by :func:`_orbit_class` of
    its mean motion and eccentricity: :data:`NEAR_CIRCULAR_SPAN` for a near-circular
    deep-space orbit, :data:`DEEP_SPACE_SPAN` for another deep-space orbit, else
    :data:`DEFAULT_SPAN`."""
    return {
        "near-Earth": DEFAULT_SPAN,
        "near-circular": NEAR_CIRCULAR_SPAN,
        "eccentric": DEEP_SPACE_SPAN,
    }[_element_set_class(sat)]


#: Default spacing of the pseudo-observations, s.
DEFAULT_SPACING = 600.0
#: Largest RK8 step of the fit's orbits, s; each observation interval is cut into equal
#: steps no longer than this: 3 of 200 s per 600 s interval. At 180 s (the propagation's
#: default) the interval took 4 of 150 s; measured on 300 LEO fits of 2023-11-13 and the 38
#: fitted reentries of benches/reentry.py, the fitted Cd*A/m moved by 2-4e-5 relative
#: (median; 1.4e-3 at most, 50x below the 8 % drag-sigma floor), positions by < 1 m, and
#: the fits ran 1.2-1.3x faster.
FIT_STEP = 200.0
#: Largest RK8 step of the fits of near-circular deep-space orbits (e < 0.1, period of
#: 225 min or more), s: one step per 600 s observation interval. Their fits span six days,
#: six times the LEO day; at 200 s they made a whole-catalog run 1.2x slower. BeiDou's
#: GEO, IGSO and MEO predictions (``benches/precise_gnss.py``) and the four weeks' GEO,
#: GPS and MEO medians (``benches/deep_space.py``) agree with the 200 s fits' to 10 m
#: (2026-12-06); eccentric orbits keep 200 s (at 600 s their medians doubled).
DEEP_SPACE_FIT_STEP = 600.0


@dataclass(frozen=True)
class FitResult:
    """A fitted element set.

    Attributes:
        state: fitted state at the element set's epoch (inertial = TEME), m and m/s.
        drag_parameter: fitted Cd*A/m, m^2/kg.
        covariance: formal covariance (7, 7) of [r, v, Cd*A/m] at the epoch (m^2, m^2/s,
            m^2/s^2, m^3/kg, ...), scaled by the residuals' mean square: how well the
            numerical model reproduces SGP4, not the TLE's own accuracy.
        drag_sigma: 1-sigma of Cd*A/m from ``covariance``, m^2/kg.
        times: observation times, s from the epoch (k,).
        residuals: SGP4 minus fitted position at ``times`` in the RTN frame of the SGP4
            orbit (k, 3), m.
        rms: RMS of the residuals per RTN component (3,), m; ``rms_total`` their 3-D RMS, m.
        iterations: Gauss-Newton iterations; converged: whether the last update was below
            1 cm and 1e-4 relative in Cd*A/m.
        drag_observable: False when the prior on Cd*A/m dominated (its formal sigma is
            over half the prior's): the span barely sees drag (high orbits).
        prior, prior_sigma: the prior on Cd*A/m and its 1-sigma, m^2/kg
            (:func:`bstar_prior`); prior_note: how it was made.
        element_sets: the sources of the element sets fitted, oldest first (one without
            a history); element_set_rms: each one's 3-D RMS residual, m.
        all_times, all_residuals, observation_set: every observation of a history fit
            (s from the newest epoch; RTN residuals, m; index into ``element_sets``);
            ``times``/``residuals``/``rms`` are the newest element set's.
        along_track_bias: SGP4's along-track bias removed from the newest element set's
            positions before the fit, m (:data:`ALONG_TRACK_BIAS`; 0: none); residuals
            are against the debiased positions.
    """

    state: OrbitState
    drag_parameter: float
    covariance: np.ndarray
    drag_sigma: float
    times: np.ndarray
    residuals: np.ndarray
    rms: np.ndarray
    rms_total: float
    iterations: int
    converged: bool
    drag_observable: bool
    prior: float = np.nan
    prior_sigma: float = np.nan
    prior_note: str = ""
    element_sets: tuple[str, ...] = ()
    element_set_rms: np.ndarray | None = None
    all_times: np.ndarray | None = None
    all_residuals: np.ndarray | None = None
    observation_set: np.ndarray | None = None
    along_track_bias: float = 0.0


def _sgp4_observations(sat: Any, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions (k, 3) m and velocities (k, 3) m/s of the element set by SGP4 at
    ``times`` (s from its epoch); ValueError naming SGP4's error."""
    from sgp4.api import SGP4_ERRORS

    err, r, v = sat.sgp4_array(
        np.full(len(times), sat.jdsatepoch), sat.jdsatepochF + times / 86400.0
    )
    if np.any(err):
        bad = int(np.flatnonzero(err)[0])
        raise ValueError(
            f"SGP4 error {int(err[bad])} at {times[bad]:.0f} s from the epoch: "
            f"{SGP4_ERRORS.get(int(err[bad]), '')}"
        )
    return np.asarray(r) * 1e3, np.asarray(v) * 1e3


#: Relative 1-sigma of the B*-derived prior on Cd*A/m (:func:`bstar_prior`): weak on
#: purpose (B* is itself a fit, noisy from one element set to the next). On the four
#: development weeks of ``benches/catalog_realism.py`` the fitted Cd*A/m is the prior to
#: 1-4 % (robust log scatter 0.007-0.014, median ratio 0.96-0.99): over one day the SGP4
#: pseudo-observations carry SGP4's own deceleration, which the density ratio reproduces.
BSTAR_PRIOR_SIGMA = 0.5
#: Relative 1-sigma of the prior where B* gives none (B* <= 0): a guess.
GUESS_PRIOR_SIGMA = 1.0
#: SGP4's static atmosphere: density at q0 = 120 km altitude (kg/m^3; B* = B rho0 / 2 with
#: rho0 = 0.15696615 kg m^-2 ER^-1 over one Earth radius) and its fourth-power profile
#: ((q0 - s) / (r - s))^4 with s = 78 km (lowered for perigees below 156 km, as SGP4 does).
SGP4_RHO_Q0 = SGP4_RHO0 / 6378135.0
SGP4_Q0_KM, SGP4_S_KM, SGP4_RADIUS_KM = 120.0, 78.0, 6378.135
#: An element set of a history whose normalised RMS residual exceeds this (the fit
#: cannot reconcile it with the newer ones: a manoeuvre, a cross-tag) is dropped with every
#: older one, and the fit repeated.
HISTORY_MAX_NORMALISED_RMS = 3.0


def sgp4_density(radius_km: np.ndarray, perigee_km: float) -> np.ndarray:
    """SGP4's static density (kg/m^3) at geocentric distances ``radius_km`` for an orbit
    of perigee altitude ``perigee_km``."""
    s = SGP4_S_KM
    if perigee_km < 156.0:
        s = max(perigee_km - 78.0, 20.0)
    alt = np.maximum(np.asarray(radius_km) - SGP4_RADIUS_KM - s, 1.0)
    return SGP4_RHO_Q0 * ((SGP4_Q0_KM - s) / alt) ** 4


def _perigee_km(sat: Any) -> float:
    """Perigee altitude (km) of an ``sgp4`` ``Satrec``'s mean elements, as SGP4 takes it."""
    return float(sat.a * (1 - sat.ecco)) * SGP4_RADIUS_KM - SGP4_RADIUS_KM


def _model_density(atmosphere: Any, times: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Mean density (kg/m^3) of ``atmosphere`` at inertial ``positions`` (m) and UTC
    ``times``. An atlas is read through its day tiles (the densities a run sees, one
    interpolation in the core), not by fresh model calls (NRLMSIS's ``mean_std`` runs
    pymsis five times for its driver variance: 10 ms an object)."""
    from ..density.atlas import Atlas
    from ..frames import geodetic, inertial_to_fixed
    from ..time import ut1_seconds

    if isinstance(atmosphere, Atlas):
        field = atmosphere.field(times[0], times[-1])
        return np.asarray(field.mean_sigma(ut1_seconds(times), positions)[0])
    lla = geodetic(inertial_to_fixed(times, positions))
    return np.asarray(atmosphere.mean_std(times, lla[:, 0], lla[:, 1], lla[:, 2])[0])


def bstar_prior(
    bstar: float,
    perigee_km: float,
    atmosphere: ModelLike,
    times: np.ndarray,
    positions: np.ndarray,
) -> tuple[float, float, str]:
    """The fit's prior on Cd*A/m (m^2/kg), its 1-sigma (m^2/kg) and a note: ``bstar``
    (1/ER) scaled by the ratio of SGP4's static density (perigee altitude ``perigee_km``)
    to ``atmosphere``'s mean density at the element set's SGP4 ``positions`` (m, TEME as
    inertial) at ``times`` (UTC); where B* <= 0, :data:`DEFAULT_DRAG_PARAMETER` with
    100 %; where the model cannot be evaluated there, B*'s plain conversion with 100 %."""
    bstar = float(bstar)
    if bstar <= 0:
        return (
            DEFAULT_DRAG_PARAMETER,
            GUESS_PRIOR_SIGMA * DEFAULT_DRAG_PARAMETER,
            f"B* <= 0: prior {DEFAULT_DRAG_PARAMETER} m^2/kg +- 100 %",
        )
    radius = np.linalg.norm(positions, axis=1) / 1e3
    try:
        mean = _model_density(atmosphere, times, positions)
    except Exception:  # outside the field (any model's error): the plain conversion
        mean = np.array([np.nan])
    ratio = float(np.mean(sgp4_density(radius, perigee_km)) / np.mean(mean))
    plain = drag_parameter_from_bstar(bstar)
    if not (np.isfinite(ratio) and ratio > 0):
        return plain, plain * GUESS_PRIOR_SIGMA, "B* converted plainly (no model density)"
    prior = max(plain * ratio, MIN_DRAG_PARAMETER)
    return (
        prior,
        BSTAR_PRIOR_SIGMA * prior,
        f"prior from B*: {plain:.3g} x density ratio {ratio:.3g} = {prior:.3g} m^2/kg "
        f"+- {100 * BSTAR_PRIOR_SIGMA:.0f} %",
    )


def _windows(epochs: np.ndarray, span: tuple[float, float]) -> list[tuple[float, float]]:
    """Each element set's observation window, s from its own epoch (``epochs`` in s from
    the newest, ascending): ``span``, cut halfway to its neighbours."""
    out = []
    for k, e in enumerate(epochs):
        lo, hi = span
        if k > 0:
            lo = max(lo, (epochs[k - 1] - e) / 2)
        if k < len(epochs) - 1:
            hi = min(hi, (epochs[k + 1] - e) / 2)
        out.append((lo, hi))
    return out


@dataclass
class _Observations:
    """Pseudo-observations of one fit on the grid newest epoch + g spacing."""

    back: int  # grid steps before the newest epoch
    forward: int  # grid steps after it
    rows: np.ndarray  # row of each observation in the grid, g + back (k,)
    times: np.ndarray  # s from the newest epoch (k,)
    which: np.ndarray  # element set index of each observation (k,)
    positions: np.ndarray  # (k, 3) m
    velocities: np.ndarray  # (k, 3) m/s
    bases: np.ndarray  # (k, 3, 3) RTN rows of the SGP4 orbit
    sigmas: np.ndarray  # (k, 3) RTN 1-sigma, m
    along_track_bias: float = 0.0  # removed from the newest element set's positions, m

    @property
    def shared(self) -> np.ndarray:
        """(k,) divisor of each position's weight: in a history, the square root of its
        element set's number of positions. They share the set's error (its owner's fit
        to tracking), so together they are about one observation of the orbit, not that
        many independent ones, or the scatter between sets reads as a drag signal."""
        counts = np.bincount(self.which)
        return np.sqrt(counts[self.which]) if len(counts) > 1 else np.ones(len(self.which))


#: Relative 1-sigma of the model's density (and so drag) error over a history's arc: the
#: older element sets are weighted by the along-track error it makes between them and
#: the newest (:func:`_model_drift`), so that they inform the fit without forcing the
#: model's density error of past weeks onto the newest state.
HISTORY_DENSITY_SIGMA = 0.2


def _model_drift(old: Any, new: Any, gap: float, tau: np.ndarray) -> np.ndarray:
    """Along-track error (m) that a relative drag error :data:`HISTORY_DENSITY_SIGMA`
    makes at ``tau`` s from the newest epoch: a n_dot tau^2 / 2 times the error, with the
    mean motion's decay rate n_dot from the two element sets' mean motions (``gap`` s
    apart, negative)."""
    n_dot = abs(new.no_kozai - old.no_kozai) / 60.0 / max(abs(gap), 1.0)  # rad/s^2
    a = float(new.a) * SGP4_RADIUS_KM * 1e3
    return np.asarray(0.5 * HISTORY_DENSITY_SIGMA * a * n_dot * tau**2, dtype=float)


def _observe(
    sats: list[Any],
    span: tuple[float, float],
    spacing: float,
    bias: Mapping[str, float] | None = None,
) -> tuple[_Observations, np.datetime64]:
    """The observations of ``sats`` (ascending epochs, the newest last) and the newest
    epoch, each element set's positions less its regime's along-track ``bias`` (m;
    :func:`along_track_biases`); ValueError naming an element set SGP4 fails on."""
    from .covariance import tle_accuracy

    epochs = [from_jd(s.jdsatepoch, s.jdsatepochF, scale="utc") for s in sats]
    newest = epochs[-1]
    rel = np.array([(e - newest) / np.timedelta64(1, "ns") / 1e9 for e in epochs])
    parts = []
    bias = ALONG_TRACK_BIAS if bias is None else bias
    shift = 0.0
    for k, (sat, (lo, hi)) in enumerate(zip(sats, _windows(rel, span), strict=True)):
        # grid times (multiples of spacing from the newest epoch) within the window
        g0 = int(np.ceil((rel[k] + lo) / spacing - 1e-9))
        g1 = int(np.floor((rel[k] + hi) / spacing + 1e-9))
        if g1 < g0:
            continue
        grid = np.arange(g0, g1 + 1)
        t_own = grid * spacing - rel[k]
        try:
            r, v = _sgp4_observations(sat, t_own)
        except ValueError as err:
            raise ValueError(f"element set of {epochs[k]}: {err}") from err
        at = int(np.argmin(np.abs(t_own)))
        acc = _weight_accuracy(tle_accuracy(OrbitState(epochs[k], r[at], v[at], "TEME")))
        # measured on SDP4's element sets: near-Earth ones (SGP4) of the regime keep theirs
        deep = _element_set_class(sat) != "near-Earth"
        shift = bias.get(acc.regime, 0.0) if deep else 0.0
        if shift:
            r = r - shift * rtn_basis(r, v)[:, 1, :]
        sig = np.empty((len(grid), 3))
        sig[:, 0] = acc.along_track if acc.regime in LOOSE_RADIUS_REGIMES else acc.radial
        sig[:, 1] = np.hypot(acc.along_track, acc.drift_rate * t_own)
        if k < len(sats) - 1:
            sig[:, 1] = np.hypot(sig[:, 1], _model_drift(sats[k], sats[-1], rel[k], grid * spacing))
        sig[:, 2] = acc.cross_track
        parts.append((grid, np.full(len(grid), k), r, v, sig))
    grid = np.concatenate([p[0] for p in parts])
    back, forward = max(-int(grid.min()), 0), max(int(grid.max()), 0)
    pos = np.concatenate([p[2] for p in parts])
    vel = np.concatenate([p[3] for p in parts])
    obs = _Observations(
        back=back,
        forward=forward,
        rows=grid + back,
        times=grid * spacing,
        which=np.concatenate([p[1] for p in parts]),
        positions=pos,
        velocities=vel,
        bases=rtn_basis(pos, vel),
        sigmas=np.concatenate([p[4] for p in parts]),
        along_track_bias=shift,
    )
    return obs, newest


def fit_element_set(
    sat: Any,  # an sgp4 Satrec or a CatalogObject (sgp4 ships no type information)
    model: ModelLike,
    *,
    drag_parameter: float | None = None,
    span: tuple[float, float] = DEFAULT_SPAN,
    spacing: float = DEFAULT_SPACING,
    max_iterations: int = 8,
    dynamics: Dynamics | None = None,
    along_track_bias: Mapping[str, float] | None = None,
    **deprecated: Unpack[LooseDegree],
) -> FitResult:
    """Fits state and Cd*A/m of one element set to its SGP4 positions.

    Args:
        sat: an ``sgp4`` ``Satrec`` (or a :class:`~rhoprop.catalog.CatalogObject`, whose
            ``satrec()`` is used).
        model: density model (a sampled one through its atlas's day tiles) or a
            ``DensityField`` covering the span and the orbit's altitudes.
        drag_parameter: Cd*A/m to start from and the prior's centre, m^2/kg (default
            :func:`bstar_prior`).
        span: (start, end) of the pseudo-observations, s from the epoch; start <= 0 <= end,
            both multiples of ``spacing``. Default the day before the epoch.
        spacing: observation spacing, s (default 600).
        max_iterations: Gauss-Newton iterations at most.
        dynamics: the fit's :class:`~rhoprop.Dynamics` (None: J2 only): its zonal
            degree, 2 (J2) to 6 (use the degree the fitted state will be propagated with).
            The fit integrates on its own RK8 grid down to the default floor: an
            ``integrator``, ``step``, ``rtol``, another ``floor_altitude``,
            ``field_degree`` or ``third_bodies`` is refused (ValueError).
        along_track_bias: SGP4's systematic along-track error by TLE-accuracy regime, m
            (SGP4's position minus the truth), removed from the positions of deep-space
            element sets (SDP4's) before the fit (TLE debiasing; None:
            :data:`ALONG_TRACK_BIAS`, measured on precise orbits above LEO; ``{}``: none).
            The result's ``along_track_bias`` says what was removed.
        **deprecated: ``zonal_degree=``, now in ``dynamics``, with a DeprecationWarning.

    Returns:
        :class:`FitResult`. Raises ValueError if SGP4 fails over the span or the orbit
        decays within it.
    """
    return fit_element_sets(
        [sat],
        model,
        drag_parameter=drag_parameter,
        span=span,
        spacing=spacing,
        max_iterations=max_iterations,
        dynamics=fit_dynamics("fit_element_set", dynamics, deprecated),
        along_track_bias=along_track_bias,
    )


def _drag_from_element_set(obj: Any) -> bool:
    """Whether a :class:`~rhoprop.catalog.CatalogObject`'s Cd*A/m is what its element set
    gives (B*'s plain conversion, or the guess of a B* <= 0 set), not the user's."""
    if obj.bstar > 0:
        return bool(obj.drag_parameter == drag_parameter_from_bstar(obj.bstar))
    return bool(obj.drag_parameter == DEFAULT_DRAG_PARAMETER)


def _satrec(item: Any) -> tuple[Any, float | None, str]:
    """(Satrec, Cd*A/m override or None, source) of a Satrec or CatalogObject."""
    if hasattr(item, "satrec") and callable(item.satrec):
        sat = item.satrec()
        if sat is None:
            raise ValueError("the catalog object carries no element set to fit")
        override = None if _drag_from_element_set(item) else float(item.drag_parameter)
        return sat, override, str(item.source)
    epoch = from_jd(item.jdsatepoch, item.jdsatepochF, scale="utc")
    return item, None, f"element set of {epoch}"


def _ordered(sats: Any) -> list[tuple[Any, float | None, str]]:
    """The element sets of one object as (Satrec, override, source), ascending epochs,
    repeated epochs once; ValueError for none or for several objects."""
    items = [_satrec(s) for s in (sats if isinstance(sats, (list, tuple)) else [sats])]
    if not items:
        raise ValueError("no element sets to fit")
    if len({int(s.satnum) for s, _, _ in items}) > 1:
        raise ValueError("the element sets belong to different objects (NORAD ids)")
    by_epoch: dict[float, tuple[Any, float | None, str]] = {}
    for item in items:
        by_epoch[item[0].jdsatepoch + item[0].jdsatepochF] = item
    return [by_epoch[k] for k in sorted(by_epoch)]


def _check_span(span: tuple[float, float], spacing: float) -> tuple[float, float]:
    start, end = float(span[0]), float(span[1])
    if not (start <= 0 <= end and end > start and spacing > 0):
        raise ValueError(f"span must satisfy start <= 0 <= end, start < end; got {span}")
    if abs(start / spacing - round(start / spacing)) > 1e-9:
        raise ValueError(f"span start {start} s is not a multiple of spacing {spacing} s")
    return start, end


def fit_element_sets(
    sats: Any,
    model: ModelLike,
    *,
    drag_parameter: float | None = None,
    span: tuple[float, float] = DEFAULT_SPAN,
    spacing: float = DEFAULT_SPACING,
    max_iterations: int = 8,
    dynamics: Dynamics | None = None,
    along_track_bias: Mapping[str, float] | None = None,
    **deprecated: Unpack[LooseDegree],
) -> FitResult:
    """Fits one state and Cd*A/m to several element sets of one object (a history), each
    speaking near its own epoch (module docstring); the state is at the newest epoch.
    Element sets the fit cannot reconcile with the newer ones (normalised RMS residual
    above :data:`HISTORY_MAX_NORMALISED_RMS`: a manoeuvre) are dropped with every older
    one; ``FitResult.element_sets`` says which were used.

    Args:
        sats: ``Satrec`` objects or :class:`~rhoprop.catalog.CatalogObject` of one object,
            any order (sorted by epoch; repeated epochs count once).
        model, drag_parameter, span, spacing, max_iterations, dynamics, along_track_bias:
            as :func:`fit_element_set` (``span`` is each element set's window, s from
            its own epoch, cut halfway to its neighbours; the newest one's B* gives the
            prior).

    Returns:
        :class:`FitResult`. Raises ValueError if SGP4 fails, the orbit decays within the
        span or the element sets belong to different objects.
    """
    out = fit_histories(
        [sats if isinstance(sats, (list, tuple)) else [sats]],
        model,
        drag_parameter=drag_parameter,
        span=span,
        spacing=spacing,
        max_iterations=max_iterations,
        dynamics=fit_dynamics("fit_element_sets", dynamics, deprecated),
        along_track_bias=along_track_bias,
    )[0]
    if isinstance(out, Exception):
        raise out
    return out


def fit_histories(
    histories: Sequence[Sequence[Any]],
    model: ModelLike,
    *,
    drag_parameter: float | None = None,
    span: tuple[float, float] = DEFAULT_SPAN,
    spacing: float = DEFAULT_SPACING,
    max_iterations: int = 8,
    dynamics: Dynamics | None = None,
    threads: int | None = None,
    along_track_bias: Mapping[str, float] | None = None,
    **deprecated: Unpack[LooseDegree],
) -> list[FitResult | Exception]:
    """:func:`fit_element_sets` of many objects at once: the fits run in the core, many
    objects per call in parallel (``threads``, default all cores), each trial's nominal
    and perturbed orbits as the 8 lanes of one batch. A history grows by one older
    element set per round, every object's round in one call.

    Args:
        histories: per object, its element sets (``Satrec`` or
            :class:`~rhoprop.catalog.CatalogObject`, any order).
        model, drag_parameter, span, spacing, max_iterations, dynamics: as
            :func:`fit_element_sets`.
        threads: core threads (default: ``rhoprop.parallel``'s setting).
        along_track_bias: SGP4's along-track bias by TLE-accuracy regime, m, removed from
            the positions before the fit (TLE debiasing; None: :data:`ALONG_TRACK_BIAS`,
            ``{}``: none).

    Returns:
        Per object, in order, its :class:`FitResult` or the exception (ValueError) its fit
        raised.
    """
    start, end = _check_span(span, spacing)
    ordered: list[Any] = []
    for h in histories:
        try:
            ordered.append(_ordered(list(h)))
        except ValueError as err:
            ordered.append(err)
    results: list[Any] = [o if isinstance(o, Exception) else None for o in ordered]
    zonal_degree = fit_dynamics("fit_histories", dynamics, deprecated).zonal_degree
    bias = along_track_biases(along_track_bias)
    settings = (model, (start, end), spacing, max_iterations, zonal_degree, threads, bias)
    todo = [i for i, o in enumerate(ordered) if not isinstance(o, Exception)]
    runs = _fit_round(
        [ordered[i][-1:] for i in todo],
        [drag_parameter if drag_parameter is not None else ordered[i][-1][1] for i in todo],
        [None] * len(todo),
        *settings,
    )
    for i, run in zip(todo, runs, strict=True):
        results[i] = run if isinstance(run, Exception) else run[0]
    # One older element set at a time, from the solution of the newer ones: a long arc
    # from the SGP4 state alone starts hundreds of km off along-track.
    used = {i: 1 for i in todo if not isinstance(results[i], Exception)}
    while True:
        grow = [i for i, n in used.items() if n < len(ordered[i])]
        if not grow:
            break
        runs = _fit_round(
            [ordered[i][-(used[i] + 1) :] for i in grow],
            [None] * len(grow),
            [results[i] for i in grow],
            *settings,
        )
        for i, run in zip(grow, runs, strict=True):
            # the arc decays, SGP4 fails on the older set, or a manoeuvre: stop here
            if isinstance(run, Exception) or run[1] > HISTORY_MAX_NORMALISED_RMS:
                del used[i]
            else:
                results[i] = run[0]
                used[i] += 1
    return results


def _prior(
    sat: Any, model: Any, drag_parameter: float | None, obs: _Observations, epoch: Any
) -> tuple[float, float, str]:
    """The Cd*A/m prior of a fit: ``drag_parameter`` if given, else :func:`bstar_prior`
    along the newest element set's observations."""
    if drag_parameter is not None:
        prior = max(float(drag_parameter), MIN_DRAG_PARAMETER)
        return prior, BSTAR_PRIOR_SIGMA * prior, f"prior {prior:.4g} m^2/kg given"
    newest = obs.which == obs.which.max()
    times = offsets_to_epochs(epoch, obs.times[newest])
    return bstar_prior(sat.bstar, _perigee_km(sat), model, times, obs.positions[newest])


@dataclass
class _Job:
    """One Gauss-Newton fit, ready for the core."""

    sources: list[str]
    obs: _Observations
    epoch: np.datetime64
    p0: np.ndarray  # [r (m), v (m/s), Cd*A/m (m^2/kg)]
    prior: float
    prior_sigma: float
    prior_note: str

    def weights(self) -> np.ndarray:
        """(k, 9) RTN rows over the 1-sigmas: weighted residual = W (observed - model)."""
        w = self.obs.bases / (self.obs.sigmas * self.obs.shared[:, None])[:, :, None]
        return np.ascontiguousarray(w.reshape(-1, 9))


def _job(
    ordered: list[tuple[Any, float | None, str]],
    model: Any,
    drag_parameter: float | None,
    span: tuple[float, float],
    spacing: float,
    start: FitResult | None,
    bias: Mapping[str, float] | None = None,
) -> _Job:
    """The fit of ``ordered`` element sets, from ``start``'s solution if given, else from
    the newest one's SGP4 state at its epoch and the prior; ``bias``: as :func:`_observe`."""
    sats = [o[0] for o in ordered]
    obs, epoch = _observe(sats, span, spacing, bias)
    if start is not None:
        prior, prior_sigma, note = start.prior, start.prior_sigma, start.prior_note
        p = np.concatenate([start.state.state, [start.drag_parameter]])
    else:
        prior, prior_sigma, note = _prior(sats[-1], model, drag_parameter, obs, epoch)
        r, v = _sgp4_observations(sats[-1], np.array([0.0]))
        p = np.concatenate([r[0], v[0], [prior]])
    return _Job([o[2] for o in ordered], obs, epoch, p, prior, prior_sigma, note)


#: Most fits in one core call, and the longest time span (s) their common density field
#: may cover: bounds the memory of a call's observations and of its field's day tiles.
CALL_JOBS, CALL_SPAN = 64, 5 * 86400.0


def _fit_round(
    sets: list[list[tuple[Any, float | None, str]]],
    drags: list[float | None],
    starts: list[FitResult | None],
    model: Any,
    span: tuple[float, float],
    spacing: float,
    max_iterations: int,
    zonal_degree: int,
    threads: int | None,
    bias: Mapping[str, float] | None = None,
) -> list[tuple[FitResult, float] | Exception]:
    """One fit of each of ``sets`` (from ``starts``): groups of nearby epochs, each
    prepared in Python and run in core calls, ``threads`` groups at once (one prepares
    while another runs); per fit the result and the largest normalised RMS residual of
    its older element sets, or its exception."""
    import concurrent.futures as cf

    from ..parallel import worker_count

    newest = [o[-1][0].jdsatepoch + o[-1][0].jdsatepochF for o in sets]
    order = sorted(range(len(sets)), key=newest.__getitem__)
    groups = [order[k : k + CALL_JOBS] for k in range(0, len(order), CALL_JOBS)]

    def one(group: list[int]) -> dict[int, Any]:
        out: dict[int, Any] = {}
        jobs: list[tuple[int, _Job]] = []
        for i in group:
            try:
                jobs.append((i, _job(sets[i], model, drags[i], span, spacing, starts[i], bias)))
            except ValueError as err:
                out[i] = err
        for chunk in _chunks(jobs, spacing):
            ran = _run_chunk([j for _, j in chunk], model, spacing, max_iterations, zonal_degree)
            if len(chunk) > 1 and len(ran) == 1:
                # the chunk's field failed (drivers, coverage): each job on its own field
                ran = [
                    _run_chunk([j], model, spacing, max_iterations, zonal_degree)[0]
                    for _, j in chunk
                ]
            out.update({i: r for (i, _), r in zip(chunk, ran, strict=True)})
        return out

    merged: dict[int, Any] = {}
    with cf.ThreadPoolExecutor(max_workers=min(worker_count(threads), max(len(groups), 1))) as pool:
        for part in pool.map(one, groups):
            merged.update(part)
    return [merged[i] for i in range(len(sets))]


def _span_of(job: _Job, spacing: float) -> tuple[np.datetime64, np.datetime64]:
    """First and last time of a job's grid (UTC)."""
    return (
        add_seconds(job.epoch, -job.obs.back * spacing),
        add_seconds(job.epoch, job.obs.forward * spacing),
    )


def _chunks(jobs: list[tuple[int, _Job]], spacing: float) -> list[list[tuple[int, _Job]]]:
    """Consecutive jobs in calls of at most :data:`CALL_JOBS` whose grids together span
    at most :data:`CALL_SPAN` more than the longest of them."""
    chunks: list[list[tuple[int, _Job]]] = []
    bounds = (0.0, 0.0, 0.0)  # the last chunk's first start, last end, longest grid (s)
    for item in jobs:
        t0, t1 = (float(ut1_seconds(t)) for t in _span_of(item[1], spacing))
        if chunks and len(chunks[-1]) < CALL_JOBS:
            lo, hi, longest = min(bounds[0], t0), max(bounds[1], t1), max(bounds[2], t1 - t0)
            if hi - lo <= CALL_SPAN + longest:
                chunks[-1].append(item)
                bounds = (lo, hi, longest)
                continue
        chunks.append([item])
        bounds = (t0, t1, t1 - t0)
    return chunks


def _run_chunk(
    jobs: list[_Job], model: Any, spacing: float, max_iterations: int, zonal_degree: int
) -> list[tuple[FitResult, float] | Exception]:
    """The jobs in one core call through one field covering all their grids; a field
    that cannot be made is one exception for the whole call (a list of one)."""
    from .. import _core
    from ..constants import DEFAULT_FLOOR_ALTITUDE
    from ..propagation.propagate import run_in_field

    spans = [_span_of(j, spacing) for j in jobs]
    t0 = min(s[0] for s in spans)
    t1 = max(s[1] for s in spans)
    args = [
        _core.FitJob(
            epoch=float(ut1_seconds(j.epoch)),
            p0=np.ascontiguousarray(j.p0, dtype=float),
            prior=float(j.prior),
            prior_sigma=float(j.prior_sigma),
            spacing=float(spacing),
            back=int(j.obs.back),
            forward=int(j.obs.forward),
            rows=np.ascontiguousarray(j.obs.rows, dtype=np.int64),
            observed=np.ascontiguousarray(j.obs.positions, dtype=float),
            weights=j.weights(),
        )
        for j in jobs
    ]
    where = OrbitState(t0, jobs[0].p0[:3], jobs[0].p0[3:6], "TEME")
    # A call holds the objects of one fit span, so these orbits come alone.
    deep = all(_near_circular_deep_space(j.epoch, j.p0) for j in jobs)
    config = _core.FitConfig(
        step=DEEP_SPACE_FIT_STEP if deep else FIT_STEP,
        zonal_degree=zonal_degree,
        floor_altitude=DEFAULT_FLOOR_ALTITUDE,
        max_iterations=max_iterations,
        min_drag=MIN_DRAG_PARAMETER,
    )

    def run(atmosphere: AtmosphereLike) -> list[_core.FitOutput | Exception]:
        return _core.fit_orbits(atmosphere, args, config)

    span = (t1 - t0) / np.timedelta64(1, "ns") / 1e9
    try:
        ran = run_in_field(model, where, span, DEFAULT_FLOOR_ALTITUDE, run)
    except ValueError as err:
        return [err]
    return [
        r if isinstance(r, Exception) else _result(_solution(r), j)
        for r, j in zip(ran, jobs, strict=True)
    ]


class LooseDegree(TypedDict, total=False):
    """The deprecated keyword of the fits: ``zonal_degree``, now in ``dynamics``."""

    zonal_degree: int


def fit_dynamics(
    function: str,
    dynamics: Dynamics | None,
    loose: Mapping[str, object] | None = None,
    default: Dynamics | None = None,
) -> Dynamics:
    """The :class:`~rhoprop.Dynamics` of a fit by ``function``: ``dynamics`` (None:
    ``default``, itself None: ``Dynamics()``, J2 only) with its deprecated
    ``zonal_degree=`` folded in (``loose``, with a warning). A fit honours the zonal
    degree and integrates on its own RK8 grid down to the default floor: anything else
    set is a ValueError, never ignored."""
    dyn = deprecated_keywords(
        function, dynamics, loose or {}, default, names=("zonal_degree",), stacklevel=4
    )
    dyn.require_automatic_gravity(function)
    moved = [
        k
        for k in ("integrator", "step", "rtol", "floor_altitude")
        if getattr(dyn, k) != getattr(Dynamics(), k)
    ]
    if moved:
        raise ValueError(
            f"{function}(): the fit integrates on its own RK8 grid down to the default "
            f"floor: dynamics.{' and dynamics.'.join(moved)} would be ignored (leave "
            f"{'it' if len(moved) == 1 else 'them'} unset)"
        )
    return dyn


@dataclass
class _Solution:
    """Where a Gauss-Newton fit ended: parameters, states on the grid, J^T J of the
    weighted Jacobian, iterations and convergence."""

    p: np.ndarray
    nominal: np.ndarray
    normal: np.ndarray
    iterations: int
    converged: bool


def _solution(ran: _core.FitOutput) -> _Solution:
    """The :class:`_Solution` of a core fit's output."""
    return _Solution(
        np.asarray(ran.p),
        np.asarray(ran.states),
        np.asarray(ran.normal),
        int(ran.iterations),
        bool(ran.converged),
    )


def _result(fit: _Solution, job: _Job) -> tuple[FitResult, float]:
    """The :class:`FitResult` of a solution and the largest normalised RMS residual of
    the element sets older than the newest."""
    obs = job.obs
    count = len(job.sources)
    res3 = obs.positions - fit.nominal[obs.rows, :3]
    residuals = np.einsum("kij,kj->ki", obs.bases, res3)
    normalised = residuals / obs.sigmas  # per position: each set's own RMS
    weighted = normalised / obs.shared[:, None]  # as the fit weighed them
    s2 = float(np.sum(weighted**2)) / max(weighted.size - 7, 1)
    if not s2 > 0.0:  # as many unknowns as observations: no scale to estimate
        s2 = 1.0
    info = fit.normal / s2
    info[6, 6] += 1.0 / job.prior_sigma**2
    cov = np.linalg.pinv(info)
    cov = (cov + cov.T) / 2
    newest = obs.which == count - 1
    rms = np.sqrt(np.mean(residuals[newest] ** 2, axis=0))
    # Per element set; NaN for one whose window held no observation (a set closer to its
    # neighbour than the spacing), which the manoeuvre check skips.
    counts = np.bincount(obs.which, minlength=count).astype(float)
    counts[counts == 0] = np.nan
    set_rms = np.sqrt(np.bincount(obs.which, np.sum(residuals**2, axis=1), count) / counts)
    set_norm = np.sqrt(np.bincount(obs.which, np.sum(normalised**2, axis=1), count) / counts / 3)
    older_norm = set_norm[:-1][np.isfinite(set_norm[:-1])]
    drag_sigma = float(np.sqrt(max(cov[6, 6], 0.0)))
    result = FitResult(
        state=OrbitState(job.epoch, fit.p[:3].copy(), fit.p[3:6].copy(), "TEME"),
        drag_parameter=float(fit.p[6]),
        covariance=cov,
        drag_sigma=drag_sigma,
        times=obs.times[newest],
        residuals=residuals[newest],
        rms=rms,
        rms_total=float(np.sqrt(np.sum(rms**2))),
        iterations=fit.iterations,
        converged=fit.converged,
        drag_observable=drag_sigma < 0.5 * job.prior_sigma,
        prior=job.prior,
        prior_sigma=job.prior_sigma,
        prior_note=job.prior_note,
        element_sets=tuple(job.sources),
        element_set_rms=set_rms,
        all_times=obs.times,
        all_residuals=residuals,
        observation_set=obs.which,
        along_track_bias=obs.along_track_bias,
    )
    return result, float(older_norm.max()) if older_norm.size else 0.0


def fit_span_epochs(epoch: np.datetime64, span: tuple[float, float]) -> tuple[Any, Any]:
    """First and last epoch of a fit span around ``epoch`` (UTC)."""
    return add_seconds(epoch, span[0]), add_seconds(epoch, span[1])


__all__ = [
    "ALONG_TRACK_BIAS",
    "BSTAR_PRIOR_SIGMA",
    "DEFAULT_DRAG_PARAMETER",
    "DEFAULT_SPACING",
    "DEFAULT_SPAN",
    "HISTORY_MAX_NORMALISED_RMS",
    "MIN_DRAG_PARAMETER",
    "SGP4_RHO0",
    "FitResult",
    "along_track_biases",
    "bstar_prior",
    "drag_parameter_from_bstar",
    "fit_element_set",
    "fit_element_sets",
    "fit_histories",
    "fit_span_epochs",
    "sgp4_density",
]
