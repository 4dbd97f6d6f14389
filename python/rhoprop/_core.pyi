"""Type stubs of the compiled extension ``rhoprop._core`` (the thin binding of the Rust
core). Users call the documented ``rhoprop`` API instead; array arguments are float64."""

from collections.abc import Callable
from typing import final

import numpy as np
import numpy.typing as npt
from typing_extensions import Self

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
    "Approaches",
    "Candidates",
    "CcspOutput",
    "CcspRun",
    "ExponentialAtmosphere",
    "FieldTile",
    "FitConfig",
    "FitJob",
    "FitOutput",
    "GriddedAtmosphere",
    "ModelPoints",
    "MonteCarloOutput",
    "MonteCarloRun",
    "PairsPc",
    "Pc2d",
    "Problem",
    "Propagated",
    "StreamedAtmosphere",
    "Stretches",
    "Tracks",
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

@final
class Problem:
    """The initial-value problem every run shares, checked when made: epoch (UT1 s since
    J2000), state (6,) m and m/s, Cd*A/m (m^2/kg), floor altitude (m), zonal degree and
    forces (field degree, third bodies, Cr*A/m m^2/kg; None automatic by regime)."""

    def __new__(
        cls,
        *,
        epoch: float,
        state: _F64,
        drag: float,
        floor_altitude: float,
        zonal_degree: int = 2,
        forces: tuple[int | None, bool | None, float] = ...,
    ) -> Problem: ...

@final
class Propagated:
    """What ``propagate`` returns."""

    @property
    def times(self) -> _F64:
        """Output times (n,), s."""
    @property
    def states(self) -> _F64:
        """States (n, 6), m and m/s."""
    @property
    def decayed_at(self) -> float | None:
        """When the orbit crossed the floor, s, or None."""
    @property
    def rhs_evaluations(self) -> int:
        """Right-hand-side evaluations."""
    @property
    def clipped(self) -> int:
        """Evaluations whose density was clipped at 0."""

@final
class MonteCarloRun:
    """A Monte Carlo run, checked when made: its problem, output times (s), kappa
    process (kind, parameters), perturbation, fixed-step method and largest step (s),
    members, seed, optional initial covariance (6, 6), recorded densities, drag_sigma."""

    def __new__(
        cls,
        problem: Problem,
        *,
        output_times: _F64,
        kappa: tuple[str, list[float]],
        perturbation: str,
        method: str,
        step: float,
        members: int,
        seed: int,
        initial_covariance: _F64 | None = None,
        record_density: bool = False,
        drag_sigma: float = 0.0,
    ) -> MonteCarloRun: ...

@final
class MonteCarloOutput:
    """What ``monte_carlo`` returns."""

    @property
    def positions(self) -> _F64:
        """(n, nt, 3), m."""
    @property
    def velocities(self) -> _F64:
        """(n, nt, 3), m/s."""
    @property
    def densities(self) -> _F64 | None:
        """(n, nt), kg/m^3, or None unless recorded."""
    @property
    def clipped(self) -> npt.NDArray[np.uint64]:
        """Clipped evaluations per member (n,)."""
    @property
    def decay_times(self) -> _F64:
        """Decay time per member (n,), s (inf: none)."""
    @property
    def step(self) -> float:
        """The integration step used, s."""
    @property
    def drag_factors(self) -> _F64:
        """Factor on Cd*A/m per member (n,), log-normal with log-sigma drag_sigma."""

@final
class CcspRun:
    """A CCSP run, checked when made: its problem, initial covariance (6, 6), update
    times (s), scaling (lambda1 + n, lambda2 + p), perturbation, largest RK8 step (s),
    drag_sigma (the relative 1-sigma of Cd*A/m carried as the second consider
    parameter), further output times between updates (the sigma points' moments in
    flight, not re-drawn), coordinates, the weight of the per-update kappa and a slow
    density term (scale, half-life s, inf: constant) held over each update and
    correlated 2^(-dt / half-life) across updates, a third consider parameter."""

    def __new__(
        cls,
        problem: Problem,
        *,
        initial_covariance: _F64,
        update_times: _F64,
        scaling: tuple[float, float],
        perturbation: str,
        step: float,
        drag_sigma: float = 0.0,
        output_times: _F64 | None = None,
        coordinates: str = "equinoctial",
        kappa_scale: float = 1.0,
        slow: tuple[float, float] | None = None,
    ) -> CcspRun: ...

@final
class CcspOutput:
    """What ``ccsp`` returns (and ``ccsp_many`` per object)."""

    @property
    def decayed_at(self) -> float | None:
        """When a sigma point crossed the floor, s (the outputs end before it), or None."""
    @property
    def times(self) -> _F64:
        """(nt,), s."""
    @property
    def means(self) -> _F64:
        """(nt, 6), m and m/s."""
    @property
    def covariances(self) -> _F64:
        """(nt, 6, 6)."""
    @property
    def cross(self) -> _F64:
        """Cross-covariance of the state and kappa (nt, 6)."""
    @property
    def drag_cross(self) -> _F64:
        """Cross-covariance of the state and the Cd*A/m parameter (nt, 6)."""
    @property
    def element_means(self) -> _F64 | None:
        """Equinoctial means (nt, 6) in equinoctial coordinates, else None."""
    @property
    def element_covariances(self) -> _F64 | None:
        """Equinoctial covariances (nt, 6, 6) in equinoctial coordinates, else None."""

@final
class FitJob:
    """One object of ``fit_orbits``, checked when made: epoch (UT1 s), p0 (7,) =
    [r, v, Cd*A/m], the Cd*A/m prior and its sigma (m^2/kg), grid spacing (s), grid
    steps back and forward, the observations' grid rows (k,), observed positions (k, 3)
    m and weights (k, 9) 1/m (row-major 3x3)."""

    def __new__(
        cls,
        *,
        epoch: float,
        p0: _F64,
        prior: float,
        prior_sigma: float,
        spacing: float,
        back: int,
        forward: int,
        rows: npt.NDArray[np.int64],
        observed: _F64,
        weights: _F64,
    ) -> FitJob: ...

@final
class FitConfig:
    """Settings every job of a ``fit_orbits`` call shares: grid step (s), zonal degree,
    floor altitude (m), most iterations and the smallest Cd*A/m (m^2/kg)."""

    def __new__(
        cls,
        *,
        step: float,
        zonal_degree: int,
        floor_altitude: float,
        max_iterations: int,
        min_drag: float,
    ) -> FitConfig: ...

@final
class FitOutput:
    """What ``fit_orbits`` returns per job."""

    @property
    def p(self) -> _F64:
        """[r, v, Cd*A/m] (7,) at the epoch."""
    @property
    def states(self) -> _F64:
        """States on the grid (n, 6)."""
    @property
    def normal(self) -> _F64:
        """J^T J of the weighted Jacobian (7, 7)."""
    @property
    def iterations(self) -> int:
        """Gauss-Newton iterations."""
    @property
    def converged(self) -> bool:
        """Whether the fit converged."""

def propagate(
    atmosphere: _Atmosphere,
    problem: Problem,
    output_times: _F64,
    method: str,
    step: float | None = None,
    rtol: float | None = None,
) -> Propagated:
    """One trajectory of ``problem`` to ``output_times`` (s) with ``method`` ("dop853",
    "rk8", "rk4" or "abm"), its largest ``step`` (s) and DOP853's ``rtol``."""

def ccsp(atmosphere: _Atmosphere, run: CcspRun) -> CcspOutput:
    """The CCSP filter of ``run``."""

def ccsp_many(
    atmosphere: _Atmosphere,
    runs: list[CcspRun],
    progress: Callable[[int], object] | None = None,
) -> list[CcspOutput | Exception]:
    """The CCSP of several objects in one call: per object its output or the exception
    its run raised."""

def fit_orbits(
    atmosphere: _Atmosphere,
    jobs: list[FitJob],
    config: FitConfig,
    progress: Callable[[int], object] | None = None,
) -> list[FitOutput | Exception]:
    """Least-squares fits of [r, v, Cd*A/m], one per job, in one call: per job its
    output or the exception of that job."""

def monte_carlo(
    atmosphere: _Atmosphere,
    run: MonteCarloRun,
    threads: int | None = None,
    progress: Callable[[int], object] | None = None,
) -> MonteCarloOutput:
    """The ensemble of ``run`` on ``threads`` workers (None: the core's pool);
    ``progress(done)`` is called about every 50 ms."""

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

@final
class ModelPoints:
    """What the model functions return per point (n,)."""

    @property
    def exospheric_temperature(self) -> _F64:
        """K."""
    @property
    def temperature(self) -> _F64:
        """Temperature at the point, K."""
    @property
    def density(self) -> _F64:
        """kg/m^3."""

def jb2008_core(amjd: _F64, geometry: _F64, indices: _F64) -> ModelPoints:
    """JB2008 as the reference routine: amjd (n,), geometry (n, 5) [Sun RA, Sun Dec,
    point RA, latitude rad, altitude km], indices (n, 9) -> per point the exospheric
    and local temperatures and the density."""

def jb2008_geodetic(amjd: _F64, lat: _F64, lon: _F64, alt: _F64, indices: _F64) -> ModelPoints:
    """JB2008 at MJD (UTC), geodetic lat/lon deg, alt m -> per point the exospheric and
    local temperatures and the density."""

def jacchia_roberts_geodetic(
    mjd: _F64, lat: _F64, lon: _F64, alt: _F64, drivers: _F64
) -> ModelPoints:
    """Jacchia-Roberts 1971 at MJD (UTC), lat/lon deg, alt m (>= 90 km), drivers (n, 3)
    [F10.7, F10.7a, Kp] -> per point the exospheric and local temperatures and the density."""

@final
class Pc2d:
    """What ``pc_2d`` returns."""

    @property
    def pc(self) -> float:
        """Probability of collision."""
    @property
    def miss_distance(self) -> float:
        """m."""
    @property
    def relative_speed(self) -> float:
        """m/s."""
    @property
    def covariance(self) -> _F64:
        """Encounter-plane covariance integrated (2, 2), m^2."""
    @property
    def repaired(self) -> bool:
        """Whether the projected covariance was repaired."""
    @property
    def projected_covariance(self) -> _F64:
        """Encounter-plane covariance before repair (2, 2), m^2."""
    @property
    def axes(self) -> _F64:
        """Encounter axes (3, 3), rows x, y, z."""

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
) -> Pc2d:
    """Short-encounter 2-D Pc: inertial r (3,) m, v (3,) m/s, position covariances
    (3, 3) m^2."""

@final
class Tracks:
    """Sampled tracks of n objects on a common grid, checked when made: grid times
    (nt,) s, positions and velocities (n, nt, 3) m and m/s (C-contiguous; held, not
    copied) and the samples each object has (n,)."""

    def __new__(
        cls,
        *,
        times: _F64,
        positions: _F64,
        velocities: _F64,
        samples: npt.NDArray[np.uint64],
    ) -> Tracks: ...

@final
class Candidates:
    """What ``screen_candidates`` returns."""

    @property
    def i(self) -> npt.NDArray[np.uint32]:
        """First object of each candidate interval."""
    @property
    def j(self) -> npt.NDArray[np.uint32]:
        """Second object."""
    @property
    def k(self) -> npt.NDArray[np.uint32]:
        """Grid interval."""
    @property
    def spatial(self) -> int:
        """Pair-intervals through the spatial grid."""
    @property
    def coarse(self) -> int:
        """Pair-intervals through the coarse distance bound."""
    @property
    def interpolated(self) -> int:
        """Pair-intervals through the interpolated distance bound."""

def screen_candidates(
    tracks: Tracks,
    fourth: _F64,
    distance: float,
    max_acceleration: float,
    hermite_samples: int,
    progress: Callable[[int], object] | None = None,
) -> Candidates:
    """All-on-all sieve of ``tracks`` with each object's interpolation coefficient
    ``fourth`` (n,): the candidate intervals (i, j, k) sorted and the counts."""

@final
class Approaches:
    """What ``screen_approaches`` returns."""

    @property
    def i(self) -> npt.NDArray[np.uint32]:
        """First object of each minimum."""
    @property
    def j(self) -> npt.NDArray[np.uint32]:
        """Second object."""
    @property
    def t(self) -> _F64:
        """Time of the minimum, s."""
    @property
    def states1(self) -> _F64:
        """State of i there (m, 6)."""
    @property
    def states2(self) -> _F64:
        """State of j there (m, 6)."""
    @property
    def edge(self) -> npt.NDArray[np.uint8]:
        """0 inside the window, 1 at its start, 2 at its end."""

def screen_approaches(
    tracks: Tracks,
    i: npt.NDArray[np.uint32],
    j: npt.NDArray[np.uint32],
    k: npt.NDArray[np.uint32],
    zonal_degree: int,
    distance: float,
    progress: Callable[[int], object] | None = None,
    window_start: bool = False,
    window_end: bool = False,
) -> Approaches:
    """Minima of the distance within ``distance`` in candidate intervals (i, j, k) of
    ``tracks``, on the quintic Hermite interpolant with the gravity acceleration; the
    ends count where ``window_start`` / ``window_end`` say the grid's are the window's
    own."""

@final
class Stretches:
    """What ``screen_stretches`` returns."""

    @property
    def first(self) -> _F64:
        """First time within the distance, s."""
    @property
    def last(self) -> _F64:
        """Last time within the distance, s."""

def screen_stretches(
    tracks: Tracks,
    i: npt.NDArray[np.uint32],
    j: npt.NDArray[np.uint32],
    t: _F64,
    distance: float,
    progress: Callable[[int], object] | None = None,
) -> Stretches:
    """Per minimum (i, j, t s) of ``tracks``, the (first, last) times s between which
    the objects stay within ``distance`` m around it (cubic Hermite relative motion,
    crossings by bisection)."""

@final
class PairsPc:
    """What ``pc_pairs`` returns."""

    @property
    def hits(self) -> int:
        """Pairs whose relative motion passes within the hard-body radius."""
    @property
    def pairs(self) -> int:
        """All pairs."""
    @property
    def pc(self) -> float:
        """hits / pairs."""
    @property
    def variance(self) -> float:
        """Variance of pc."""

def pc_pairs(members1: _F64, members2: _F64, hard_body_radius: float) -> PairsPc:
    """Monte Carlo Pc over all pairs of member states (n1, 6), (n2, 6) (m, m/s)."""

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
