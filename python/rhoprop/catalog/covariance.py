"""Initial covariance of a state derived from a TLE: the published accuracy of SGP4 element
sets, by orbit regime, turned into a 6x6 inertial covariance with consistent velocities.

Sources (orders of magnitude, not transcribed tables; the regime figures below are
rhoprop's choice within them, see docs/catalog-realism.md):

* Flohrer, Krag & Klinkrad (2008), "Assessment and categorization of TLE orbit errors for
  the US SSN catalogue", AMOS conference: TLE errors at epoch from orbit determination on
  TLE pseudo-observations, by eccentricity, perigee height and inclination; in LEO a few
  hundred metres radially and cross-track, the largest errors along-track (up to about a
  kilometre).
* Vallado & Cefola (2012), "Two-line element sets - practice and use", IAC-12.A6.6.11:
  about 1 km at epoch in LEO, growing by 1-3 km per day.
* Osweiler (2006), "Covariance estimation and autocorrelation of NORAD two-line element
  sets", AFIT thesis: RTN covariances of TLE-derived states, along-track dominant.

Model: the error at epoch is a Clohessy-Wiltshire relative motion with random phases: a
radial oscillation of amplitude A (an eccentricity error: radial A cos, along-track
-2 A sin), an along-track offset y0, a semi-major-axis error da (constant radial offset,
along-track drift -1.5 n da per second) and a cross-track oscillation of amplitude B.
Given the RMS errors at epoch (radial, along-track, cross-track) and the RMS drift rate of
the along-track error, A, y0, da and B follow, and with them velocity variances and the
radial/along-track correlations that a diagonal matrix would miss. Velocities are turned
from the rotating RTN frame to inertial (v_in = v_rot + n N x r).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..constants import MU, R_EARTH
from ..frames import rtn_basis
from ..propagation import DEFAULT_INITIAL_COVARIANCE, OrbitState
from ..propagation.propagate import axis_and_eccentricity, mean_anomaly, orbital_period

#: What ``initial_covariance`` of :func:`~rhoprop.catalog.propagate_catalog` and the
#: ``--initial-covariance`` option accept as names.
COVARIANCE_NAMES = ("object", "tle", "paper")


@dataclass(frozen=True)
class TleAccuracy:
    """RMS errors of a TLE-derived state at the element set's epoch.

    Attributes:
        radial, along_track, cross_track: RMS position errors at epoch, m.
        drift_rate: RMS rate of growth of the along-track error from the epoch state
            alone (a semi-major-axis error), m/s (1 km/day = 0.01157 m/s); at most
            1.5 n radial / sqrt(2) is used (n the orbital rate, :func:`tle_covariance`).
        regime: the regime's name, for reports.
    """

    radial: float
    along_track: float
    cross_track: float
    drift_rate: float
    regime: str


_KM_PER_DAY = 1e3 / 86400.0

#: Regimes by perigee altitude (m), eccentricity and orbital period (s), first match
#: wins. The two near-circular regimes above LEO were chosen on the four development
#: weeks together (docs/catalog-realism.md, "Deep-space covariance"): the single "above
#: LEO" regime before (500 m, 3 km, 500 m, 1 km/day) held 100 % of GPS and MEO errors
#: inside 2 sigma and 30-55 % of GEO ones. The eccentric regime's cross-track error
#: (1 km before) was doubled on the same weeks: 50 % of its cross-track errors fell
#: inside 2 sigma, 95 % now. The LEO radial error, 200 m before 2026-12-04, is 300 m: the
#: later element sets of the same weeks sit 0.2-0.7 km above the earlier ones' orbits,
#: and with 300 m the RTN Mahalanobis goal holds in every week ("Week by week"). The
#: LEO 800-2000 km row (150 m, 600 m, 250 m before 2026-12-06) is SGP4's error against
#: the precise orbits of Jason-1 and TOPEX/Poseidon within 3 h of their element sets'
#: epochs, the two satellites weighted equally (273 / 693 / 357 m RMS; mostly a
#: once-per-revolution error of the orbit's shape and plane, which element sets share
#: and later element sets cannot show: docs/catalog-realism.md, "The covariance against
#: precise orbits").
REGIMES = (
    # (max perigee altitude m, max eccentricity, max period s, accuracy)
    (800e3, 0.1, np.inf, TleAccuracy(300.0, 1000.0, 300.0, 1.0 * _KM_PER_DAY, "LEO below 800 km")),
    (2000e3, 0.1, np.inf, TleAccuracy(300.0, 700.0, 350.0, 0.5 * _KM_PER_DAY, "LEO 800-2000 km")),
    (np.inf, 0.1, 16 * 3600.0, TleAccuracy(200.0, 1000.0, 150.0, 0.3 * _KM_PER_DAY, "MEO")),
    (np.inf, 0.1, np.inf, TleAccuracy(2000.0, 5000.0, 2000.0, 6.0 * _KM_PER_DAY, "GEO")),
    (np.inf, 1.0, np.inf, TleAccuracy(1000.0, 5000.0, 2000.0, 3.0 * _KM_PER_DAY, "eccentric")),
)


#: Regimes whose fitted states start with at most :data:`FITTED_DRIFT_RATE`
#: (:func:`fitted_accuracy`): low Earth orbits, where the rest of the along-track growth
#: is drag's.
FITTED_DRIFT_REGIMES = ("LEO below 800 km", "LEO 800-2000 km")

#: The along-track drift rate (m/s; 0.3 km/day) a fitted state's covariance starts with
#: in :data:`FITTED_DRIFT_REGIMES`, where the regime's is larger. The regime's drift is
#: SGP4's own error growth (the fit's weights use it; an unfitted state keeps it). A
#: state fitted to a day of SGP4's positions has its mean motion pinned; what grows after
#: it is the density's and Cd*A/m's error, which the propagation carries, and what is not
#: drag: against the precise orbits of Jason-1 and TOPEX (1,336 km, little drag) the
#: fitted predictions' along-track error grows by 0.25-0.3 km/day (RMS 0.95 km at 3
#: days, 1.7 km at 5, from 0.6 km at epoch). Counted again, the regimes' 1 and 0.5
#: km/day made the 2026 history's 1-day sigmas too wide below 800 km (median error over
#: sigma 0.43 / 0.60 at 1 / 3 days, 0.67 if calibrated) and Jason-1's 1.5x too wide at
#: 2-5 days; with 0.05 km/day Jason-1's errors were 1.3-2.6 sigma
#: (docs/catalog-realism.md, "The drift of a fitted state").
FITTED_DRIFT_RATE = 0.3 * _KM_PER_DAY


def fitted_accuracy(accuracy: TleAccuracy) -> TleAccuracy:
    """The accuracy a state fitted to SGP4's positions starts with: the regime's errors
    at epoch, and in :data:`FITTED_DRIFT_REGIMES` a drift rate of at most
    :data:`FITTED_DRIFT_RATE` (m/s)."""
    if accuracy.regime not in FITTED_DRIFT_REGIMES:
        return accuracy
    return replace(accuracy, drift_rate=min(accuracy.drift_rate, FITTED_DRIFT_RATE))


def tle_accuracy(state: OrbitState) -> TleAccuracy:
    """The :class:`TleAccuracy` of the regime of ``state`` (perigee altitude above the
    equatorial radius, eccentricity and period of its osculating orbit; above LEO a
    period under 16 hours is "MEO", GPS included, and a longer one "GEO")."""
    a, e = axis_and_eccentricity(state)
    perigee = a * (1 - e) - R_EARTH
    period = orbital_period(state)
    for max_perigee, max_e, max_period, accuracy in REGIMES:
        if perigee <= max_perigee and e <= max_e and period <= max_period:
            return accuracy
    return REGIMES[-1][3]


#: Eccentricity from which :func:`tle_covariance` uses the element model (the
#: "eccentric" regime's bound): the Clohessy-Wiltshire model is one of near-circular
#: relative motion.
ELEMENT_MODEL_ECCENTRICITY = 0.1


def tle_covariance(state: OrbitState, accuracy: TleAccuracy | None = None) -> np.ndarray:
    """6x6 inertial covariance (m^2, m^2/s, m^2/s^2) of a TLE-derived ``state`` with the
    RMS errors of ``accuracy`` (default: :func:`tle_accuracy` of the state): by the
    Clohessy-Wiltshire model of the module docstring for near-circular orbits, by
    :func:`element_covariance` from eccentricity :data:`ELEMENT_MODEL_ECCENTRICITY`
    (below 1: an unbound orbit keeps the near-circular model)."""
    acc = accuracy or tle_accuracy(state)
    a, e = axis_and_eccentricity(state)
    if ELEMENT_MODEL_ECCENTRICITY <= e < 1.0 and np.isfinite(a) and a > 0.0:
        return element_covariance(state, acc)
    r, v = state.position, state.velocity
    n = float(np.linalg.norm(np.cross(r, v))) / float(r @ r)  # orbital rate, rad/s
    # The semi-major-axis error gives the drift; where the drift alone would take more
    # than half the radial variance (slow orbits: near the apogee of an eccentric one),
    # it is held to half, so the eccentricity amplitude A keeps the other half and the
    # matrix keeps full rank (with A = 0 the radial velocity has no variance and the
    # radial / along-track-rate block is rank 1: a singular covariance that stopped the
    # CCSP of 57045 NUSANTARA TIGA, e = 0.78, in the 2023-07-04 snapshot). The drift is
    # then smaller than the regime's: 1.5 n radial / sqrt(2).
    var_a = min((acc.drift_rate / (1.5 * n)) ** 2, acc.radial**2 / 2.0)
    amp2 = 2.0 * (acc.radial**2 - var_a)  # A^2, >= radial^2
    # The along-track oscillation 2 A sin(nt) has variance 2 A^2; the rest is the offset.
    # Where the stated along-track error is smaller than the oscillation a radial error
    # implies (radial above along-track / 2), the along-track variance is the
    # oscillation's: any less and the matrix is not a covariance (before 2026-12-03 it
    # took A^2 there and a 600 m radial, 1 km along-track accuracy gave a negative
    # eigenvalue, which made every CCSP of such objects invalid).
    var_y0 = max(acc.along_track**2 - 2.0 * amp2, 0.0)
    b2 = 2.0 * acc.cross_track**2
    rot = np.zeros((6, 6))  # rotating-frame RTN covariance [x y z xdot ydot zdot]
    rot[0, 0] = amp2 / 2 + var_a
    rot[1, 1] = var_y0 + 2.0 * amp2
    rot[2, 2] = b2 / 2
    rot[3, 3] = amp2 * n**2 / 2
    rot[4, 4] = 2 * amp2 * n**2 + 2.25 * n**2 * var_a
    rot[5, 5] = b2 * n**2 / 2
    rot[0, 4] = rot[4, 0] = -amp2 * n - 1.5 * n * var_a
    rot[1, 3] = rot[3, 1] = amp2 * n
    to_inertial_rate = np.eye(6)
    to_inertial_rate[3:, :3] = n * np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    basis = rtn_basis(r, v)  # rows R, T, N
    big = np.zeros((6, 6))
    big[:3, :3] = big[3:, 3:] = basis.T
    m = big @ to_inertial_rate
    cov = m @ rot @ m.T
    return (cov + cov.T) / 2


def _in_plane_state(
    frame: tuple[np.ndarray, np.ndarray], a: float, e: float, dw: float, m: float
) -> np.ndarray:
    """Inertial state [r, v] (m, m/s) of the Kepler orbit with semi-major axis ``a`` (m),
    eccentricity ``e``, perigee turned by ``dw`` (rad) from the unit vector ``frame[0]``
    towards ``frame[1]`` (in the orbit's plane, in the direction of motion) and mean
    anomaly ``m`` (rad)."""
    big_e = np.pi if e > 0.8 else m  # a start from which Newton converges for any m
    for _ in range(50):  # Newton on Kepler's equation; converges in a few steps
        step = (big_e - e * np.sin(big_e) - m) / (1.0 - e * np.cos(big_e))
        big_e -= step
        if abs(step) < 1e-15:
            break
    c, s = np.cos(big_e), np.sin(big_e)
    b = a * np.sqrt(1.0 - e * e)
    rate = np.sqrt(MU / a**3) / (1.0 - e * c)  # dE/dt
    p = np.cos(dw) * frame[0] + np.sin(dw) * frame[1]
    q = np.cos(dw) * frame[1] - np.sin(dw) * frame[0]
    return np.concatenate([a * (c - e) * p + b * s * q, (-a * s * rate) * p + (b * c * rate) * q])


def element_covariance(state: OrbitState, accuracy: TleAccuracy) -> np.ndarray:
    """6x6 inertial covariance of a TLE-derived ``state`` of an eccentric orbit: six
    independent element errors mapped by the orbit's own (Kepler) partials, so that the
    error keeps the orbit's energy where the element set does. The Clohessy-Wiltshire
    model, with the local angular rate at the perigee of a 0.9-eccentric orbit, gave the
    velocities an energy error of a few hundred km of semi-major axis (an along-track
    error of thousands of km after one revolution, CCSP sigma points that came down: 33
    of the 42 eccentric objects of the 2023-11-13 catalog stopped early).

    The errors: the semi-major axis, from the regime's drift rate read as the orbit's
    mean along-track rate, sigma_a = (2/3) drift / n (n the mean motion); the
    eccentricity vector, isotropic in the plane (sigma_e per component, perigee turned
    at fixed mean longitude); the mean anomaly (a timing error); the orbit plane, turned
    about the radial and the along-track axes by sigma_N / r each (the cross-track RMS
    at epoch is the regime's). sigma_e and the mean anomaly's sigma are solved for so
    that the RMS errors at epoch along the velocity and across it in the plane are the
    regime's along-track and radial ones (on a circular orbit these are T and R; on an
    eccentric one a timing error lies along the velocity, which away from the apsides
    is not T) where the orbit's phase allows it (:func:`_positive_fit`); the drift takes
    at most half of either, as the near-circular model holds it to half the radial
    variance, so the matrix keeps full rank."""
    r, v = state.position, state.velocity
    h = np.cross(r, v)
    rn = float(np.linalg.norm(r))
    e_vec = np.cross(v, h) / MU - r / rn
    e = float(np.linalg.norm(e_vec))
    a = 1.0 / (2.0 / rn - float(v @ v) / MU)
    n = np.sqrt(MU / a**3)
    w_hat = h / np.linalg.norm(h)
    frame = (e_vec / e, np.cross(w_hat, e_vec / e))
    m = mean_anomaly(state)

    def column(da: float, de: float, dw: float, dm: float, step: float) -> np.ndarray:
        # Central difference of the state over the element change (da, de, dw, dm) x step.
        hi = _in_plane_state(frame, a + da * step, e + de * step, dw * step, m + dm * step)
        lo = _in_plane_state(frame, a - da * step, e - de * step, -dw * step, m - dm * step)
        return np.asarray((hi - lo) / (2.0 * step), dtype=float)

    eps = 1e-6
    cols = {
        "a": column(a, 0.0, 0.0, 0.0, eps) / a,  # per m of a
        "e_par": column(0.0, 1.0, 0.0, 0.0, eps),  # per unit of eccentricity
        "e_perp": column(0.0, 0.0, 1.0, -1.0, eps) / e,  # perigee turned, mean longitude kept
        "m": column(0.0, 0.0, 0.0, 1.0, eps),  # per rad of mean anomaly
    }
    # The plane: rigid turns about the radial and along-track axes (cross-track).
    basis = rtn_basis(r, v)

    def turn(axis: np.ndarray) -> np.ndarray:
        return np.concatenate([np.cross(axis, r), np.cross(axis, v)])

    var_turn = accuracy.cross_track**2 / rn**2
    plane = [turn(basis[0]), turn(basis[1])]
    # In the plane, the regime's along-track error is taken along the velocity and the
    # radial one across it (R and T on a circular orbit): a TLE's in-track error is a
    # timing error, which away from the apsides also has a radial part in RTN.
    along_dir = v / np.linalg.norm(v)
    across_dir = np.cross(along_dir, w_hat)
    rad = {k: float(across_dir @ c[:3]) ** 2 for k, c in cols.items()}
    along = {k: float(along_dir @ c[:3]) ** 2 for k, c in cols.items()}
    var_a = (2.0 / 3.0 * accuracy.drift_rate / n) ** 2
    target = np.array([accuracy.radial**2, accuracy.along_track**2])
    # The drift alone may not take more than half of either (as the near-circular model
    # holds it to half the radial variance).
    own = np.array([rad["a"], along["a"]])
    var_a = min(var_a, float(np.min(target / (2.0 * np.maximum(own, 1e-300)))))
    # radial^2 and along-track^2 = sum of each mode's square x its variance; the two
    # eccentricity-vector components share one variance.
    lhs = np.array(
        [
            [rad["e_par"] + rad["e_perp"], rad["m"]],
            [along["e_par"] + along["e_perp"], along["m"]],
        ]
    )
    var_e, var_m = _positive_fit(lhs, target - own * var_a, target)
    modes = [
        (cols["a"], var_a),
        (cols["e_par"], var_e),
        (cols["e_perp"], var_e),
        (cols["m"], var_m),
        (plane[0], var_turn),
        (plane[1], var_turn),
    ]
    cov = np.zeros((6, 6))
    for col, var in modes:
        cov += var * np.outer(col, col)
    return (cov + cov.T) / 2


def _positive_fit(lhs: np.ndarray, rhs: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """Variances x >= a floor with lhs x = rhs exactly where that has a positive solution,
    else the boundary solution nearest in relative terms (the regime's RMS errors then
    hold only roughly: at some orbit phases an eccentricity error that makes the radial
    RMS makes more than the along-track one). The floor, 1e-4 of each column's own scale,
    keeps the matrix full rank."""
    floor = 1e-4 * np.min(target[None, :] / np.maximum(lhs, 1e-300), axis=0)
    try:
        x = np.linalg.solve(lhs, rhs)
        if np.all(x >= floor):
            return float(x[0]), float(x[1])
    except np.linalg.LinAlgError:
        pass
    best, best_cost = (float(floor[0]), float(floor[1])), np.inf
    weights = 1.0 / target
    for free in (0, 1):
        fixed = 1 - free
        # weighted least squares for the free variance, the other at its floor
        a = lhs[:, free] * weights
        b = (rhs - lhs[:, fixed] * floor[fixed]) * weights
        value = max(float(a @ b / (a @ a)), float(floor[free]))
        x = np.empty(2)
        x[free], x[fixed] = value, floor[fixed]
        cost = float(np.sum(((lhs @ x - rhs) * weights) ** 2))
        if cost < best_cost:
            best, best_cost = (float(x[0]), float(x[1])), cost
    return best


def paper_covariance() -> np.ndarray:
    """The paper's near-zero initial covariance, diag(1 mm^2, 1 (um/s)^2)."""
    return np.array(DEFAULT_INITIAL_COVARIANCE, dtype=float)
