"""Whether the short-encounter 2-D Pc applies to a conjunction, and a Pc over the
encounter interval where it does not.

The 2-D Pc (:func:`~rhoprop.conjunction.pc_2d`) assumes the relative motion is a
straight line at constant speed and the covariances constant while the objects can
collide. A conjunction lasts about as long as its relative position takes to cross the
combined uncertainty along the relative velocity: ``duration = 2 (k sigma_v + HBR) /
|v_rel|`` with ``sigma_v`` the combined position 1-sigma along v_rel and k =
:data:`ENCOUNTER_SIGMAS` (the time-of-closest-approach spread a linear encounter allows,
as Coppola's 2012 conjunction bounds bound it). The relative motion of two orbits curves
on the time scale of the orbital period P: over the encounter it departs from a line by
about (pi duration / P)^2 / 2 of its length. The 2-D Pc is used when ``duration <= P /
30`` (under 0.6 % curvature; :data:`SHORT_ENCOUNTER_SHARE`): a LEO crossing at km/s
lasts about a second, the limit is about 3 minutes. Co-orbiting objects, formations and
slow overtakes (metres per second or less) exceed it.

Where it does not apply, :func:`pc_interval` counts collisions over the encounter
interval: samples of the relative state at TCA from the two Gaussians (positions and
velocities), each flown by the Clohessy-Wiltshire equations about object 1's orbit
(relative motion of nearby objects on a near-circular orbit, exact to second order in
the separation over the orbit radius), the Pc the share of samples whose distance falls
below the hard-body radius within the interval (Monte Carlo; binomial standard error).
The samples are drawn here; the core counts them (``rhoprop_core::encounter``: 0.57 s a
call in numpy on the 2023 snapshot's slow encounters, the Pc stage's largest cost).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import _core, _validate
from ..constants import MU

#: Sigmas of the combined position error along the relative velocity that the encounter
#: interval spans (either side of TCA).
ENCOUNTER_SIGMAS = 5.0
#: Longest encounter, as a share of the shorter orbital period, for which the 2-D Pc's
#: straight-line motion holds (curvature (pi / 30)^2 / 2 = 0.55 %).
SHORT_ENCOUNTER_SHARE = 1.0 / 30.0
#: Samples of :func:`pc_interval` by default: binomial standard error 1.4e-5 at Pc 1e-5,
#: 4.4e-4 at Pc 1e-2; with no hit the 95 % upper bound is 6e-5.
INTERVAL_SAMPLES = 50_000
#: Grid points over the interval; each sample's minimum is refined by a parabola
#: through the squared distances around its grid minimum (exact for straight motion).
GRID_POINTS = 801
#: A first pass on this many points sets aside the samples that cannot come within the
#: hard-body radius: between two points the distance dips at most half the chord (the
#: arcs over a 1/200 of an orbit are straight to 1e-4), taken 10 % wider.
COARSE_POINTS = 101
#: Samples drawn at once (the order of the random stream).
_CHUNK = 5_000


@dataclass(frozen=True)
class EncounterCheck:
    """Whether the short-encounter model holds.

    Attributes:
        duration: the encounter's length, s (inf without relative motion).
        period: the shorter of the two orbital periods, s (inf when neither is bound).
        short: ``duration <= period * SHORT_ENCOUNTER_SHARE``: the 2-D Pc applies.
        relative_speed: |v2 - v1|, m/s; sigma_along: combined position 1-sigma along
            the relative velocity, m.
    """

    duration: float
    period: float
    short: bool
    relative_speed: float
    sigma_along: float

    def describe(self) -> str:
        """The check in words (for notes)."""
        return (
            f"encounter of {self.duration:.4g} s (relative speed {self.relative_speed:.3g} "
            f"m/s, {self.sigma_along:.3g} m 1-sigma along it) against 1/30 of the "
            f"{self.period:.4g} s period"
        )


def _period(r: np.ndarray, v: np.ndarray) -> float:
    energy = 0.5 * float(v @ v) - MU / float(np.linalg.norm(r))
    if energy >= 0:
        return math.inf
    a = -MU / (2.0 * energy)
    return 2.0 * math.pi * math.sqrt(a**3 / MU)


def encounter_check(
    r1: np.ndarray,
    v1: np.ndarray,
    cov1: np.ndarray,
    r2: np.ndarray,
    v2: np.ndarray,
    cov2: np.ndarray,
    hard_body_radius: float,
) -> EncounterCheck:
    """The short-encounter check of a conjunction at TCA: positions m, velocities m/s
    (inertial, (3,)), covariances (3, 3) or (6, 6) inertial SI (the position block
    enters), hard-body radius m. See the module docs for the criterion."""
    rel = np.asarray(v2, dtype=float) - np.asarray(v1, dtype=float)
    speed = float(np.linalg.norm(rel))
    c = np.asarray(cov1, dtype=float)[:3, :3] + np.asarray(cov2, dtype=float)[:3, :3]
    period = min(
        _period(np.asarray(r1, float), np.asarray(v1, float)),
        _period(np.asarray(r2, float), np.asarray(v2, float)),
    )
    if speed == 0.0:
        return EncounterCheck(math.inf, period, False, 0.0, float("nan"))
    u = rel / speed
    sigma = math.sqrt(max(float(u @ c @ u), 0.0))
    duration = 2.0 * (ENCOUNTER_SIGMAS * sigma + hard_body_radius) / speed
    return EncounterCheck(
        duration, period, duration <= period * SHORT_ENCOUNTER_SHARE, speed, sigma
    )


@dataclass(frozen=True)
class IntervalPcResult:
    """A Pc counted over the encounter interval (:func:`pc_interval`).

    ``float(result)`` is the Pc.

    Attributes:
        pc: hits / samples.
        std_error: binomial standard error sqrt(pc (1 - pc) / samples).
        upper: one-sided 95 % upper bound (with no hit: 1 - 0.05^(1 / samples)).
        hits, samples: samples within the hard-body radius at some time of the interval,
            and samples drawn.
        span: the interval, s, centred on TCA.
        hard_body_radius: m.
    """

    pc: float
    std_error: float
    upper: float
    hits: int
    samples: int
    span: float
    hard_body_radius: float

    def __float__(self) -> float:
        return self.pc


def _sqrt(cov: np.ndarray) -> np.ndarray:
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    return np.asarray(v * np.sqrt(np.clip(w, 0.0, None)))


def pc_interval(
    r1: object,
    v1: object,
    cov1: object,
    r2: object,
    v2: object,
    cov2: object,
    hard_body_radius: object,
    *,
    span: object,
    samples: int = INTERVAL_SAMPLES,
    seed: int = 0,
) -> IntervalPcResult:
    """Probability of collision over an interval of ``span`` s centred on TCA, without
    the short-encounter assumptions (see the module docs).

    Args:
        r1, v1: object 1's inertial position (3,), m, and velocity (3,), m/s, at TCA; its
            orbit is the reference of the relative motion (near-circular assumed).
        cov1: object 1's inertial state covariance (6, 6), SI (velocity uncertainty
            moves a slow encounter as much as position does).
        r2, v2, cov2: the same for object 2.
        hard_body_radius: combined hard-body radius, m (> 0).
        span: the interval, s (> 0), e.g. an :class:`EncounterCheck`'s duration capped
            at half the orbital period.
        samples: relative states drawn (>= 100); seed: of the draws.

    Returns:
        :class:`IntervalPcResult`.
    """
    hbr = _validate.positive("hard_body_radius", hard_body_radius)
    width = _validate.positive("span", span)
    p1, w1 = _validate.vector3("r1", r1), _validate.vector3("v1", v1)
    p2, w2 = _validate.vector3("r2", r2), _validate.vector3("v2", v2)
    covs = []
    for name, cov in (("cov1", cov1), ("cov2", cov2)):
        c = np.asarray(cov, dtype=float)
        if c.shape != (6, 6) or not np.isfinite(c).all():
            raise ValueError(f"{name} must be a finite (6, 6) state covariance, got {c.shape}")
        covs.append(c)
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 100:
        raise ValueError(f"samples must be an integer >= 100, got {samples!r}")
    _validate.seed(seed, limit=2**63)
    radius = float(np.linalg.norm(p1))
    n = math.sqrt(MU / radius**3)
    basis = np.array([p1 / radius, np.zeros(3), np.cross(p1, w1)])
    basis[2] /= np.linalg.norm(basis[2])
    basis[1] = np.cross(basis[2], basis[0])
    omega = np.cross(p1, w1) / radius**2
    mean = np.concatenate([p2 - p1, w2 - w1])
    root = _sqrt(covs[0] + covs[1])
    rng = np.random.default_rng(int(seed))
    # Drawn in chunks of _CHUNK as before the count moved to the core: the same seed
    # gives the same samples.
    draws = [
        rng.standard_normal((min(_CHUNK, samples - done), 6)) for done in range(0, samples, _CHUNK)
    ]
    rel = mean + np.concatenate(draws) @ root.T
    rho = rel[:, :3] @ basis.T
    rho_dot = (rel[:, 3:] - np.cross(omega, rel[:, :3])) @ basis.T
    states = np.ascontiguousarray(np.concatenate([rho, rho_dot], axis=1))
    hits = _core.interval_hits(states, n, width, hbr, COARSE_POINTS, GRID_POINTS)
    pc = hits / samples
    se = math.sqrt(pc * (1 - pc) / samples)
    upper = 1 - 0.05 ** (1 / samples) if hits == 0 else min(1.0, pc + 1.645 * se)
    return IntervalPcResult(pc, se, upper, hits, samples, width, hbr)
