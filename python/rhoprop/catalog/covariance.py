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

from dataclasses import dataclass

import numpy as np

from ..constants import R_EARTH
from ..frames import rtn_basis
from ..propagation import DEFAULT_INITIAL_COVARIANCE, OrbitState
from ..propagation.propagate import axis_and_eccentricity

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

#: Regimes by perigee altitude (m) and eccentricity, first match wins.
REGIMES = (
    # (max perigee altitude m, max eccentricity, accuracy)
    (800e3, 0.1, TleAccuracy(200.0, 1000.0, 300.0, 1.0 * _KM_PER_DAY, "LEO below 800 km")),
    (2000e3, 0.1, TleAccuracy(150.0, 600.0, 250.0, 0.5 * _KM_PER_DAY, "LEO 800-2000 km")),
    (np.inf, 0.1, TleAccuracy(500.0, 3000.0, 500.0, 1.0 * _KM_PER_DAY, "above LEO")),
    (np.inf, 1.0, TleAccuracy(1000.0, 5000.0, 1000.0, 3.0 * _KM_PER_DAY, "eccentric")),
)


def tle_accuracy(state: OrbitState) -> TleAccuracy:
    """The :class:`TleAccuracy` of the regime of ``state`` (perigee altitude above the
    equatorial radius and eccentricity of its osculating orbit)."""
    a, e = axis_and_eccentricity(state)
    perigee = a * (1 - e) - R_EARTH
    for max_perigee, max_e, accuracy in REGIMES:
        if perigee <= max_perigee and e <= max_e:
            return accuracy
    return REGIMES[-1][2]


def tle_covariance(state: OrbitState, accuracy: TleAccuracy | None = None) -> np.ndarray:
    """6x6 inertial covariance (m^2, m^2/s, m^2/s^2) of a TLE-derived ``state`` with the
    RMS errors of ``accuracy`` (default: :func:`tle_accuracy` of the state), by the
    Clohessy-Wiltshire model of the module docstring."""
    acc = accuracy or tle_accuracy(state)
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
    var_y0 = max(acc.along_track**2 - amp2, 0.0)
    b2 = 2.0 * acc.cross_track**2
    rot = np.zeros((6, 6))  # rotating-frame RTN covariance [x y z xdot ydot zdot]
    rot[0, 0] = amp2 / 2 + var_a
    rot[1, 1] = var_y0 + amp2
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


def paper_covariance() -> np.ndarray:
    """The paper's near-zero initial covariance, diag(1 mm^2, 1 (um/s)^2)."""
    return np.array(DEFAULT_INITIAL_COVARIANCE, dtype=float)
