"""Type stubs of the compiled extension ``rhoprop._core`` (the thin binding of the Rust
core). Users call the documented ``rhoprop`` API instead; array arguments are float64."""

from collections.abc import Callable
from typing import NamedTuple, TypedDict, final

import numpy as np
import numpy.typing as npt
from typing_extensions import NotRequired, Self

_F64 = npt.NDArray[np.float64]

__all__ = [
    "DEFAULT_FLOOR_ALTITUDE",
    "HARD_BODY_SHAPES",
    "J2",
    "KAPPA_KINDS",
    "MAX_DRAG_SIGMA",
    "MAX_STEPS",
    "MU",
    "OMEGA_EARTH",
    "R_EARTH",
    "R_POLE",
    "SECONDS_PER_DAY",
    "WGS84_F",
    "ExponentialAtmosphere",
    "FieldTile",
    "GriddedAtmosphere",
    "StreamedAtmosphere",
    "ccsp",
    "ccsp_many",
    "equinoctial_elements",
    "equinoctial_to_cartesian",
    "fit_orbits",
    "geodetic",
    "geodetic_to_fixed",
    "gmst",
    "inertial_to_fixed",
    "interval_hits",
    "jacchia_roberts_geodetic",
    "jb2008_core",
    "jb2008_geodetic",
    "monte_carlo",
    "pc_2d",
    "pc_pairs",
    "propagate",
    "rtn_basis",
    "screen_approaches",
    "screen_candidates",
    "screen_stretches",
    "simd_path",
]

# Constants of rhoprop-core (SI units, rad/s; see rust/core/src/constants.rs).
MU: float
R_EARTH: float
R_POLE: float
J2: float
WGS84_F: float
OMEGA_EARTH: float
SECONDS_PER_DAY: float
DEFAULT_FLOOR_ALTITUDE: float
MAX_STEPS: int
# Largest relative 1-sigma of Cd*A/m (drag_sigma) that monte_carlo and ccsp accept.
MAX_DRAG_SIGMA: float
# Names of the kappa processes: the first item of monte_carlo's kappa spec.
KAPPA_KINDS: tuple[str, ...]
# Names of the hard-body shapes pc_2d accepts.
HARD_BODY_SHAPES: tuple[str, ...]

def simd_path() -> str:
    """Instruction set of the batch kernels on this CPU: "avx2+fma" or "portable"."""

@final
class ExponentialAtmosphere:
    """Exponential atmosphere rho0 * exp(-(h - h0)/H), h = |r| - Re."""

    def __new__(
        cls, rho0: float, h0: float, scale_height: float, rel_sigma: float = 0.0
    ) -> Self: ...
    def with_sigma_scale(self, factor: float) -> ExponentialAtmosphere:
        """This atmosphere with every sigma times ``factor`` (finite, >= 0)."""

    def mean_sigma(self, ut1: _F64, positions: _F64) -> tuple[_F64, _F64]:
        """Mean and sigma (kg/m^3) at inertial positions (n, 3) m, UT1 s since J2000 (n,)."""

@final
class GriddedAtmosphere:
    """Density sampled on a (time, altitude, latitude, longitude) grid of ln(mean) and
    sigma/mean; multilinear, periodic in longitude, an error outside the grid."""

    def __new__(
        cls,
        epoch: float,
        time: _F64,
        altitude: tuple[float, float, int],
        latitude: tuple[float, float, int],
        lon0: float,
        ln_mean: _F64,
        rel_sigma: _F64,
    ) -> Self: ...
    @staticmethod
    def from_tiles(epoch: float, tiles: list[FieldTile], open_altitude: bool) -> GriddedAtmosphere:
        """A field of tiles that follow each other in time on one spatial grid."""
    @property
    def nbytes(self) -> int:
        """Bytes of the values of the field's tiles."""
    def with_sigma_scale(self, factor: float) -> GriddedAtmosphere:
        """This atmosphere with every sigma times ``factor`` (finite, >= 0)."""

    def mean_sigma(self, ut1: _F64, positions: _F64) -> tuple[_F64, _F64]:
        """Mean and sigma (kg/m^3) at inertial positions (n, 3) m, UT1 s since J2000 (n,)."""

@final
class StreamedAtmosphere:
    """A field whose tiles ``source(k)`` gives when a run reaches them (at most ``keep``
    held besides those in use); lookups give the bits of the field of all the tiles."""

    def __new__(
        cls,
        epoch: float,
        bounds: list[float],
        source: Callable[[int], FieldTile],
        open_altitude: bool,
        keep: int,
    ) -> Self: ...
    @property
    def loads(self) -> int:
        """Tiles asked of the source so far."""
    @property
    def nbytes(self) -> int:
        """Bytes of the tiles the field holds now."""
    def __len__(self) -> int: ...
    def with_sigma_scale(self, factor: float) -> StreamedAtmosphere:
        """This atmosphere with every sigma times ``factor`` (finite, >= 0)."""

    def mean_sigma(self, ut1: _F64, positions: _F64) -> tuple[_F64, _F64]:
        """Mean and sigma (kg/m^3) at inertial positions (n, 3) m, UT1 s since J2000 (n,)."""

#: The core atmospheres every propagator takes.
_Atmosphere = ExponentialAtmosphere | GriddedAtmosphere | StreamedAtmosphere

@final
class FieldTile:
    """One time window of a sampled field (an atlas tile)."""

    def __new__(
        cls,
        time: _F64,
        altitude: tuple[float, float, int],
        latitude: tuple[float, float, int],
        lon0: float,
        ln_mean: _F64,
        rel_sigma: _F64,
    ) -> Self: ...
    @property
    def nbytes(self) -> int:
        """Bytes of the values held."""
    @property
    def span(self) -> tuple[float, float]:
        """First and last time node, s."""

class _Propagated(NamedTuple):
    """What ``propagate`` returns (a plain tuple at runtime, in this order)."""

    times: _F64
    states: _F64
    decayed_at: float | None
    rhs_evaluations: int
    clipped: int

class _CcspOutput(TypedDict):
    """What ``ccsp`` returns (and ``ccsp_many`` per object)."""

    decayed_at: float | None
    times: _F64
    means: _F64
    covariances: _F64
    cross: _F64
    drag_cross: _F64
    element_means: NotRequired[_F64]
    element_covariances: NotRequired[_F64]

class _MonteCarloOutput(TypedDict):
    """What ``monte_carlo`` returns."""

    positions: _F64
    velocities: _F64
    densities: _F64 | None
    clipped: npt.NDArray[np.uint64]
    decay_times: _F64
    step: float
    drag_factors: _F64

def propagate(
    atmosphere: _Atmosphere,
    epoch: float,
    state: _F64,
    drag: float,
    output_times: _F64,
    method: str,
    step: float | None,
    rtol: float | None,
    floor_altitude: float,
    zonal_degree: int = 2,
    forces: tuple[int | None, bool | None, float] = ...,
) -> _Propagated:
    """(times (n,), states (n, 6), decayed_at, RHS evaluations, clipped evaluations);
    forces: (field degree, third bodies, Cr*A/m m^2/kg), default (None, None, 0.0), the
    same in ccsp and monte_carlo: None automatic by regime, radiation 0 none."""

def ccsp(
    atmosphere: _Atmosphere,
    epoch: float,
    state: _F64,
    drag: float,
    initial_covariance: _F64,
    update_times: _F64,
    scaling: tuple[float, float],
    perturbation: str,
    step: float,
    floor_altitude: float,
    zonal_degree: int = 2,
    drag_sigma: float = 0.0,
    output_times: _F64 | None = None,
    coordinates: str = "equinoctial",
    kappa_scale: float = 1.0,
    slow: tuple[float, float] | None = None,
    forces: tuple[int | None, bool | None, float] = ...,
) -> _CcspOutput:
    """CCSP filter: decayed_at (s or None), times (nt,), means (nt, 6), covariances
    (nt, 6, 6), cross (nt, 6), drag_cross (nt, 6); drag_sigma is the relative 1-sigma of
    Cd*A/m carried as the second consider parameter; output_times are further outputs
    between updates (the sigma points' moments in flight, not re-drawn); kappa_scale
    weighs the per-update kappa, slow (scale, half-life s, inf: constant) adds a slow
    density term held over each update and correlated 2^(-dt / half-life) across
    updates, a third consider parameter."""

def ccsp_many(
    atmosphere: _Atmosphere,
    objects: list[tuple[float, _F64, float, _F64, _F64, float, float, _F64]],
    scaling: tuple[float, float],
    perturbation: str,
    floor_altitude: float,
    zonal_degree: int = 2,
    progress: Callable[[int], object] | None = None,
    coordinates: str = "equinoctial",
    kappa_scale: float = 1.0,
    slow: tuple[float, float] | None = None,
) -> list[_CcspOutput | Exception]:
    """CCSP of several objects, each (epoch, state, drag, initial_covariance,
    update_times, step, drag_sigma, output_times (empty: none)), in one call: per object
    the dict of ``ccsp`` or the exception its run raised; kappa_scale and slow as in
    ``ccsp``, shared."""

def fit_orbits(
    atmosphere: _Atmosphere,
    jobs: list[
        tuple[float, _F64, float, float, float, int, int, npt.NDArray[np.int64], _F64, _F64]
    ],
    step: float,
    zonal_degree: int,
    floor_altitude: float,
    max_iterations: int,
    min_drag: float,
    progress: Callable[[int], object] | None = None,
) -> list[tuple[_F64, _F64, _F64, int, bool] | Exception]:
    """Least-squares fits of [r, v, Cd*A/m], each job (epoch UT1 s, p0 (7,), prior and
    its sigma (m^2/kg), spacing (s), grid steps back and forward, observation rows (k,),
    observed positions (k, 3) m, weights (k, 9) 1/m) in one call: per job (p (7,), grid
    states (n, 6), J^T J (7, 7), iterations, converged) or the exception of that job."""

def monte_carlo(
    atmosphere: _Atmosphere,
    epoch: float,
    state: _F64,
    drag: float,
    output_times: _F64,
    kappa: tuple[str, list[float]],
    perturbation: str,
    method: str,
    step: float,
    members: int,
    seed: int,
    initial_covariance: _F64 | None,
    floor_altitude: float,
    record_density: bool,
    threads: int | None,
    progress: Callable[[int], object] | None,
    zonal_degree: int = 2,
    drag_sigma: float = 0.0,
    forces: tuple[int | None, bool | None, float] = ...,
) -> _MonteCarloOutput:
    """Ensemble run: positions/velocities (n, nt, 3), densities (n, nt) or None, clipped
    (n,), decay_times (n,), step (s), drag_factors (n,) (factor on Cd*A/m per member,
    log-normal with log-sigma drag_sigma)."""

def gmst(ut1: _F64) -> _F64:
    """GMST (IAU-82), rad, for UT1 seconds since J2000."""

def inertial_to_fixed(ut1: _F64, positions: _F64) -> _F64:
    """Inertial (n, 3) -> Earth-fixed (n, 3), m."""

def geodetic(positions: _F64) -> _F64:
    """Earth-fixed (n, 3) m -> (n, 3) [lat deg, lon deg, alt m] on WGS-84."""

def geodetic_to_fixed(lla: _F64) -> _F64:
    """(n, 3) [lat deg, lon deg, alt m] -> Earth-fixed (n, 3) m."""

def rtn_basis(positions: _F64, velocities: _F64) -> _F64:
    """RTN bases (n, 3, 3), rows R, T, N."""

def equinoctial_elements(states: _F64, reference: _F64, semi_major: str = "osculating") -> _F64:
    """Cartesian states (n, 6) -> equinoctial elements (n, 6) in the axes of `reference`
    (6,), lambda within pi of the reference's; a "osculating" or "energy" (J2 field)."""

def equinoctial_to_cartesian(
    elements: _F64, reference: _F64, semi_major: str = "osculating"
) -> _F64:
    """Equinoctial elements (n, 6) -> Cartesian states (n, 6) in the axes of `reference`."""

def jb2008_core(amjd: _F64, geometry: _F64, indices: _F64) -> tuple[_F64, _F64, _F64]:
    """JB2008 as the reference routine: amjd (n,), geometry (n, 5) [Sun RA, Sun Dec,
    point RA, latitude rad, altitude km], indices (n, 9) -> (Tinf K, T K, rho kg/m^3)."""

def jb2008_geodetic(
    amjd: _F64, lat: _F64, lon: _F64, alt: _F64, indices: _F64
) -> tuple[_F64, _F64, _F64]:
    """JB2008 at MJD (UTC), geodetic lat/lon deg, alt m -> (Tinf K, T K, rho kg/m^3)."""

def jacchia_roberts_geodetic(
    mjd: _F64, lat: _F64, lon: _F64, alt: _F64, drivers: _F64
) -> tuple[_F64, _F64, _F64]:
    """Jacchia-Roberts 1971 at MJD (UTC), lat/lon deg, alt m (>= 90 km), drivers (n, 3)
    [F10.7, F10.7a, Kp] -> (Tinf K, T K, rho kg/m^3)."""

def pc_2d(
    r1: _F64,
    v1: _F64,
    cov1: _F64,
    r2: _F64,
    v2: _F64,
    cov2: _F64,
    hard_body_radius: float,
    shape: str,
    npd: str,
) -> tuple[float, float, float, _F64, bool, _F64, _F64]:
    """Short-encounter 2-D Pc: inertial r (3,) m, v (3,) m/s, position covariances
    (3, 3) m^2 -> (pc, miss distance m, relative speed m/s, covariance integrated (2, 2)
    m^2, repaired, projected covariance (2, 2) m^2, encounter axes (3, 3) rows x, y, z)."""

def screen_candidates(
    times: _F64,
    positions: _F64,
    velocities: _F64,
    samples: npt.NDArray[np.uint64],
    fourth: _F64,
    distance: float,
    max_acceleration: float,
    hermite_samples: int,
    progress: Callable[[int], object] | None = None,
) -> tuple[
    npt.NDArray[np.uint32],
    npt.NDArray[np.uint32],
    npt.NDArray[np.uint32],
    tuple[int, int, int],
]:
    """All-on-all sieve: times (nt,) s, positions/velocities (n, nt, 3) m, m/s, samples
    (n,) valid per object, fourth (n,) -> candidate (i, j, k) sorted, and the pair-interval
    counts (spatial, coarse, interpolated)."""

def screen_approaches(
    times: _F64,
    positions: _F64,
    velocities: _F64,
    samples: npt.NDArray[np.uint64],
    i: npt.NDArray[np.uint32],
    j: npt.NDArray[np.uint32],
    k: npt.NDArray[np.uint32],
    zonal_degree: int,
    distance: float,
    progress: Callable[[int], object] | None = None,
    window_start: bool = False,
    window_end: bool = False,
) -> tuple[npt.NDArray[np.uint32], npt.NDArray[np.uint32], _F64, _F64, _F64, npt.NDArray[np.uint8]]:
    """Minima of the distance within ``distance`` in candidate intervals (i, j, k), on the
    quintic Hermite interpolant with the gravity acceleration -> (i, j, t s, states of i
    (m, 6), states of j (m, 6), edge: 0 inside, 1 at the window's start, 2 at its end;
    the ends count where ``window_start`` / ``window_end`` say the grid's are the
    window's own)."""

def screen_stretches(
    times: _F64,
    positions: _F64,
    velocities: _F64,
    samples: npt.NDArray[np.uint64],
    i: npt.NDArray[np.uint32],
    j: npt.NDArray[np.uint32],
    t: _F64,
    distance: float,
    progress: Callable[[int], object] | None = None,
) -> tuple[_F64, _F64]:
    """Per minimum (i, j, t s) of tracks as for ``screen_approaches``, the (first, last)
    times s between which the objects stay within ``distance`` m around it (cubic Hermite
    relative motion, crossings by bisection)."""

def pc_pairs(
    members1: _F64, members2: _F64, hard_body_radius: float
) -> tuple[int, int, float, float]:
    """Monte Carlo Pc over all pairs of member states (n1, 6), (n2, 6) (m, m/s) ->
    (hits, pairs, pc, variance)."""

def interval_hits(
    states: _F64,
    mean_motion: float,
    span: float,
    hard_body_radius: float,
    coarse_points: int,
    grid_points: int,
) -> int:
    """How many LVLH relative states (n, 6) (m, m/s at TCA) come within the hard-body
    radius (m) over [-span/2, span/2] s of Clohessy-Wiltshire motion (mean motion rad/s),
    on ``coarse_points`` and ``grid_points`` even times (``encounter.pc_interval``)."""
