"""Probability of collision (Pc) at a time of closest approach (TCA).

Three estimates, all for straight-line (short-encounter) relative motion at TCA:

- :func:`pc_2d`: the 2-D Pc of two Gaussian states (Foster; Alfano; NASA CARA's
  ``Pc2D_Foster``): the combined position covariance projected on the encounter plane
  and the 2-D Gaussian integrated over the hard-body circle (or square), to ~1e-10
  relative (the quadrature tolerance; tested to 1e-9 where Pc > 1e-10).
- :func:`pc_mixture`: the Pc of two Gaussian mixtures (for instance one component per
  density model): ``sum_ij w_i w_j Pc_ij``, every component pair with its own encounter
  geometry.
- :func:`pc_monte_carlo`: the fraction of all member pairs of two ensembles whose
  relative motion passes within the hard-body radius, with a confidence interval.

Units: positions m, velocities m/s, covariances m^2 (position block), hard-body radius
m (the combined radius of both objects). States and covariances are inertial unless
``frame="rtn"`` says a covariance is in its own object's RTN frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist
from typing import Any, Literal, TypeVar

import numpy as np
from numpy.typing import NDArray

from .. import _core, _validate
from ..ensemble.mixture import GaussianMixture
from ..frames import rtn_basis
from ..options import HardBodyShape, NpdPolicy
from ..propagation.results import MonteCarloResult

Array = NDArray[Any]

#: Hard-body shapes: a disc of radius HBR, a square of half-side HBR, the square of the
#: disc's area (half-side sqrt(pi)/2 HBR); squares are aligned with the encounter frame.
SHAPES: tuple[str, ...] = tuple(_core.HARD_BODY_SHAPES)

#: Frames a covariance may be given in.
FRAMES = ("inertial", "rtn")

#: What to do with a projected covariance that is not positive definite.
NPD_POLICIES = ("repair", "raise")


@dataclass(frozen=True)
class PcResult:
    """The 2-D probability of collision of one conjunction.

    ``float(result)`` is the Pc.

    Attributes:
        pc: probability of collision, in [0, 1].
        miss_distance: straight-line miss distance |r_perp| of the relative motion, m
            (equal to the distance at TCA when the states are at TCA).
        relative_speed: |v2 - v1|, m/s.
        encounter_covariance: the combined position covariance projected on the
            encounter plane that was integrated (after any repair), (2, 2), m^2, in the
            encounter axes (x along the miss, z along r x v).
        repaired: True where the projected covariance was not positive definite and its
            eigenvalues were clipped (CARA's remediation, ``npd="repair"``).
        projected_covariance: the projection before any repair, (2, 2), m^2.
        encounter_axes: rows x, y, z of the encounter frame, inertial unit vectors
            (3, 3): y along v2 - v1, z along (r2 - r1) x (v2 - v1), x = y x z.
        hard_body_radius: m; shape: the hard-body shape.
    """

    pc: float
    miss_distance: float
    relative_speed: float
    encounter_covariance: Array
    repaired: bool
    projected_covariance: Array
    encounter_axes: Array
    hard_body_radius: float
    shape: str

    def __float__(self) -> float:
        return self.pc

    def maximum(self) -> PcMaximum:
        """The largest Pc any scaling of the combined covariance gives, and whether this
        Pc lies in the dilution region (:class:`PcMaximum`; Alfano 2005, as CARA reports
        it): the encounter-plane covariance times k^2 for k^2 on 41 log-spaced values
        within a factor 100 of the small-radius optimum (k^2 = m^2 / 2, m the miss's
        Mahalanobis distance), its largest Pc taken. Where the miss is within the
        hard-body radius the maximum is 1 (a covariance shrunk to nothing)."""
        cov = np.asarray(self.encounter_covariance, dtype=float)
        miss = float(self.miss_distance)
        if miss <= self.hard_body_radius:
            return PcMaximum(1.0, 0.0, True)
        m2 = miss * miss * float(np.linalg.inv(cov)[0, 0])
        scales = 0.5 * m2 * np.logspace(-2.0, 2.0, 41)
        plane = np.zeros((3, 3))
        plane[1, 1] = 1.0
        best, at = -1.0, 1.0
        for k2 in scales:
            plane[np.ix_([0, 2], [0, 2])] = cov * k2
            pc = float(
                _core.pc_2d(
                    np.zeros(3),
                    np.zeros(3),
                    np.zeros((3, 3)),
                    np.array([miss, 0.0, 0.0]),
                    np.array([0.0, 1.0, 0.0]),
                    np.ascontiguousarray(plane),
                    self.hard_body_radius,
                    self.shape,
                    "repair",
                ).pc
            )
            if pc > best:
                best, at = pc, float(k2)
        return PcMaximum(max(best, self.pc), at, at < 1.0)


@dataclass(frozen=True)
class PcMaximum:
    """The maximum Pc over scalings of the combined covariance (:meth:`PcResult.maximum`).

    Attributes:
        pc_max: the largest Pc of the covariance times k^2 over k, in [0, 1].
        covariance_scale: the k^2 at which it is reached (0 where the miss lies within
            the hard-body radius).
        dilution: True where k^2 < 1: a smaller covariance would give a larger Pc, so a
            small Pc says the states are too uncertain to tell, not that the objects
            miss (CARA's "dilution region").
    """

    pc_max: float
    covariance_scale: float
    dilution: bool


@dataclass(frozen=True)
class MixturePcResult:
    """The Pc of two Gaussian mixtures.

    ``float(result)`` is the Pc.

    Attributes:
        pc: ``sum_ij weights1[i] weights2[j] pair_pc[i, j]``.
        pair_pc: the 2-D Pc of each component pair (k1, k2).
        weights1, weights2: the mixtures' normalised weights (k1,), (k2,).
        repaired: which pairs had a repaired projected covariance (k1, k2).
        miss_distance: miss distance of each pair's component means (k1, k2), m.
        hard_body_radius: m; shape: the hard-body shape.
    """

    pc: float
    pair_pc: Array
    weights1: Array
    weights2: Array
    repaired: Array
    miss_distance: Array
    hard_body_radius: float
    shape: str

    def __float__(self) -> float:
        return self.pc


@dataclass(frozen=True)
class MonteCarloPcResult:
    """The Monte Carlo Pc over all member pairs of two ensembles.

    ``float(result)`` is the Pc.

    Attributes:
        pc: hits / pairs.
        interval: (low, high) confidence interval at ``level``. With hits, the normal
            approximation ``pc -+ z * std_error`` clipped to [0, 1]. With no hit, the
            one-sided upper bound ``(0, 1 - (1 - level)^(1 / min(n1, n2)))`` (see
            :func:`pc_monte_carlo`; ``one_sided`` is then True).
        std_error: standard error of ``pc`` from the U-statistic variance.
        hits: pairs whose straight-line miss is <= the hard-body radius.
        pairs: n1 * n2 pairs counted.
        n1, n2: members of each ensemble used (the survivors for a Monte Carlo result).
        level: confidence level; one_sided: whether ``interval`` is the zero-hit bound.
        hard_body_radius: m.
    """

    pc: float
    interval: tuple[float, float]
    std_error: float
    hits: int
    pairs: int
    n1: int
    n2: int
    level: float
    one_sided: bool
    hard_body_radius: float

    def __float__(self) -> float:
        return self.pc


# ---------------------------------------------------------------------- checks


_S = TypeVar("_S")


def _choice(name: str, value: _S, choices: tuple[str, ...]) -> _S:
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, one of {choices}, got {value!r}")
    if value not in choices:
        raise ValueError(f"unknown {name} {value!r}; expected one of {choices}")
    return value


def _array(name: str, value: object) -> Array:
    try:
        arr = _validate.real_array(name, value)
    except (TypeError, ValueError) as err:
        raise TypeError(f"{name} must be an array of numbers: {err}") from None
    return arr


def _covariance(name: str, value: object) -> Array:
    """The position block (3, 3) of a 3x3 or 6x6 covariance, finite and symmetric."""
    c = _array(name, value)
    if c.shape not in ((3, 3), (6, 6)):
        raise ValueError(f"{name} must have shape (3, 3) or (6, 6), got {c.shape}")
    bad = np.argwhere(~np.isfinite(c))
    if bad.size:
        i, j = bad[0]
        raise ValueError(f"{name}[{i}, {j}] must be finite, got {c[i, j]}")
    scale = float(np.max(np.abs(c)))
    asym = float(np.max(np.abs(c - c.T)))
    if asym > 1e-8 * scale:
        raise ValueError(f"{name} is not symmetric (max |C - C^T| = {asym:.3g})")
    return np.asarray(c[:3, :3])


def _rtn_to_inertial(cov: Array, r: Array, v: Array, name: str) -> Array:
    """C_inertial = M C M^T with M = [R T N] (columns) of the orbit through (r, v)."""
    if np.linalg.norm(np.cross(r, v)) == 0.0:
        raise ValueError(
            f"{name}: position and velocity are parallel (or zero), so its RTN frame is "
            "undefined; give the covariance in the inertial frame"
        )
    rows = rtn_basis(r, v)  # rows R, T, N = M^T
    return np.asarray(rows.T @ cov @ rows)


def _pc_core(
    r1: Array,
    v1: Array,
    c1: Array,
    r2: Array,
    v2: Array,
    c2: Array,
    hbr: float,
    shape: str,
    npd: str,
) -> PcResult:
    out = _core.pc_2d(
        np.ascontiguousarray(r1),
        np.ascontiguousarray(v1),
        np.ascontiguousarray(c1),
        np.ascontiguousarray(r2),
        np.ascontiguousarray(v2),
        np.ascontiguousarray(c2),
        hbr,
        shape,
        npd,
    )
    cov, projected, axes = out.covariance, out.projected_covariance, out.axes
    for a in (cov, projected, axes):
        a.flags.writeable = False
    return PcResult(
        pc=float(out.pc),
        miss_distance=float(out.miss_distance),
        relative_speed=float(out.relative_speed),
        encounter_covariance=cov,
        repaired=bool(out.repaired),
        projected_covariance=projected,
        encounter_axes=axes,
        hard_body_radius=hbr,
        shape=shape,
    )


# ---------------------------------------------------------------------- 2-D Pc


def pc_2d(
    r1: object,
    v1: object,
    cov1: object,
    r2: object,
    v2: object,
    cov2: object,
    hard_body_radius: object,
    *,
    frame: Literal["inertial", "rtn"] = "inertial",
    shape: HardBodyShape = "circle",
    npd: NpdPolicy = "repair",
) -> PcResult:
    """Short-encounter 2-D probability of collision of two objects at TCA.

    The relative position r = r2 - r1 and velocity v = v2 - v1 define the encounter frame
    (y along v, z along r x v, x = y x z; the miss vector is (|r_perp|, 0)); the
    combined position covariance ``C1 + C2`` (the objects' errors are independent) is
    projected on the x-z plane and the 2-D Gaussian centred on the miss point is
    integrated over the hard-body region (Foster 1992; Alfano 2005; NASA CARA
    ``Pc2D_Foster``). The integral is a 1-D adaptive quadrature of normal distribution
    functions to ~1e-10 relative.

    Args:
        r1, v1: object 1's inertial position (3,), m, and velocity (3,), m/s, at TCA.
        cov1: object 1's covariance, (3, 3) position, m^2, or (6, 6) state (position
            m^2, position-velocity m^2/s, velocity m^2/s^2; only the position block
            enters).
        r2, v2, cov2: the same for object 2.
        hard_body_radius: combined hard-body radius, m (> 0).
        frame: ``"inertial"`` (default): covariances in the frame of r and v;
            ``"rtn"``: each covariance in its own object's RTN frame (R = r/|r|,
            N = r x v/|r x v|, T = N x R, order R, T, N), rotated to inertial with
            ``M C M^T``, ``M = [R T N]`` (columns).
        shape: ``"circle"`` (default; disc of radius HBR), ``"square"`` (half-side HBR)
            or ``"square_equal_area"`` (half-side sqrt(pi)/2 HBR, the disc's area);
            squares have sides along the encounter-frame x and z axes.
        npd: a projected 2x2 covariance that is not positive definite is repaired as
            CARA does (``"repair"``, default: its eigenvalues below (1e-4 HBR)^2 are
            raised to that floor, and ``repaired`` is True in the result) or refused
            (``"raise"``: a ValueError). A positive-definite one is never changed.

    Returns:
        :class:`PcResult` (``.pc`` the probability; ``float(result)`` too).

    Raises:
        TypeError: non-numeric input, a non-string option.
        ValueError: wrong shapes, NaN/inf, non-symmetric covariance, hard_body_radius
            <= 0, zero relative velocity, unknown frame/shape/npd, a non-positive-definite
            projected covariance with ``npd="raise"``.

    Where r is parallel to v (a miss of exactly 0 included) the z axis is any unit vector
    perpendicular to v: the circle's Pc does not depend on it, a square's orientation
    does.
    """
    hbr = _validate.positive("hard_body_radius", hard_body_radius)
    frame = _choice("frame", frame, FRAMES)
    shape = _choice("shape", shape, SHAPES)
    npd = _choice("npd", npd, NPD_POLICIES)
    p1 = _validate.vector3("r1", r1)
    w1 = _validate.vector3("v1", v1)
    p2 = _validate.vector3("r2", r2)
    w2 = _validate.vector3("v2", v2)
    c1 = _covariance("cov1", cov1)
    c2 = _covariance("cov2", cov2)
    if frame == "rtn":
        c1 = _rtn_to_inertial(c1, p1, w1, "object 1")
        c2 = _rtn_to_inertial(c2, p2, w2, "object 2")
    return _pc_core(p1, w1, c1, p2, w2, c2, hbr, shape, npd)


# ---------------------------------------------------------------------- mixtures


def _as_mixture(name: str, value: object) -> GaussianMixture:
    if isinstance(value, GaussianMixture):
        mix = value
    elif isinstance(value, tuple) and len(value) == 2:
        mean = _array(f"{name} mean", value[0])
        cov = _array(f"{name} covariance", value[1])
        if mean.shape not in ((3,), (6,)) or cov.shape != mean.shape * 2:
            raise ValueError(
                f"{name} as a single Gaussian must be (mean (6,), covariance (6, 6)) or "
                f"(mean (3,), covariance (3, 3)), got {mean.shape} and {cov.shape}"
            )
        mix = GaussianMixture(None, mean[None], cov[None])
    else:
        raise TypeError(
            f"{name} must be a GaussianMixture or a (mean, covariance) pair, "
            f"got {type(value).__name__}"
        )
    if mix.dim not in (3, 6):
        raise ValueError(
            f"{name} must be a mixture of 6-D states (m, m/s) or 3-D positions (m), "
            f"got dimension {mix.dim}"
        )
    return mix


def _component_velocities(name: str, mix: GaussianMixture, velocity: object, vname: str) -> Array:
    """Velocity (k, 3) of every component: its mean's for 6-D, ``velocity`` for 3-D."""
    if mix.dim == 6:
        if velocity is not None:
            raise ValueError(
                f"{vname} is only for 3-D (position) mixtures; {name} holds 6-D states "
                "whose component means carry the velocity"
            )
        return np.asarray(mix.means[:, 3:])
    if velocity is None:
        raise ValueError(f"{name} is a 3-D (position) mixture: give {vname} (3,), m/s")
    v = _validate.vector3(vname, velocity)
    return np.asarray(np.broadcast_to(v, (mix.n_components, 3)))


def pc_mixture(
    mix1: object,
    mix2: object,
    hard_body_radius: object,
    *,
    velocity1: object = None,
    velocity2: object = None,
    shape: HardBodyShape = "circle",
    npd: NpdPolicy = "repair",
) -> MixturePcResult:
    """Probability of collision of two objects whose states at TCA are Gaussian mixtures.

    ``Pc = sum_ij w1_i w2_j Pc_ij`` where ``Pc_ij`` is the 2-D Pc (:func:`pc_2d`) of
    component i of object 1 and component j of object 2, each pair with its own
    encounter geometry from its component means (so components that sit on different
    sides of the other object count as they should, which one Gaussian fitted to the
    mixture cannot do). The objects' mixtures are taken as independent.

    Args:
        mix1, mix2: :class:`rhoprop.ensemble.GaussianMixture` of inertial 6-D states
            (position m, velocity m/s; covariances in SI) or of 3-D positions (m), or a
            single Gaussian as a ``(mean, covariance)`` pair of shape (6,), (6, 6) or
            (3,), (3, 3).
        hard_body_radius: combined hard-body radius, m (> 0).
        velocity1, velocity2: inertial velocity (3,), m/s, of a 3-D mixture's object
            (required for 3-D, refused for 6-D mixtures).
        shape, npd: as :func:`pc_2d`.

    Returns:
        :class:`MixturePcResult` with the total ``pc`` and the per-pair matrix.
    """
    hbr = _validate.positive("hard_body_radius", hard_body_radius)
    shape = _choice("shape", shape, SHAPES)
    npd = _choice("npd", npd, NPD_POLICIES)
    m1 = _as_mixture("mix1", mix1)
    m2 = _as_mixture("mix2", mix2)
    vel1 = _component_velocities("mix1", m1, velocity1, "velocity1")
    vel2 = _component_velocities("mix2", m2, velocity2, "velocity2")
    k1, k2 = m1.n_components, m2.n_components
    pair = np.empty((k1, k2))
    repaired = np.zeros((k1, k2), dtype=bool)
    miss = np.empty((k1, k2))
    for i in range(k1):
        for j in range(k2):
            try:
                res = _pc_core(
                    m1.means[i, :3],
                    vel1[i],
                    m1.covariances[i, :3, :3],
                    m2.means[j, :3],
                    vel2[j],
                    m2.covariances[j, :3, :3],
                    hbr,
                    shape,
                    npd,
                )
            except ValueError as err:
                raise type(err)(f"component pair ({i}, {j}): {err}") from err
            pair[i, j] = res.pc
            repaired[i, j] = res.repaired
            miss[i, j] = res.miss_distance
    total = float(m1.weights @ pair @ m2.weights)
    for a in (pair, repaired, miss):
        a.flags.writeable = False
    return MixturePcResult(
        pc=min(max(total, 0.0), 1.0),
        pair_pc=pair,
        weights1=m1.weights,
        weights2=m2.weights,
        repaired=repaired,
        miss_distance=miss,
        hard_body_radius=hbr,
        shape=shape,
    )


# ---------------------------------------------------------------------- Monte Carlo


def _members(name: str, value: object, index: int) -> tuple[Array, np.datetime64 | None]:
    """Member states (n, 6) and their epoch (None for a plain array)."""
    if isinstance(value, MonteCarloResult):
        nt = len(value.times)
        if not -nt <= index < nt:
            raise ValueError(f"index {index} is out of range for {name}'s {nt} output times")
        alive = value.alive[:, index]
        states = np.concatenate(
            [value.positions[alive, index], value.velocities[alive, index]], axis=1
        )
        return np.ascontiguousarray(states), value.epochs[index]
    arr = _array(name, value)
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise ValueError(
            f"{name} must be member states of shape (n, 6) (m, m/s) or a MonteCarloResult, "
            f"got shape {arr.shape}"
        )
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
    if bad.size:
        raise ValueError(
            f"{name}[{bad[0]}] is not finite (a decayed member? pass the MonteCarloResult "
            "to use only the members still flying)"
        )
    return np.ascontiguousarray(arr), None


def pc_monte_carlo(
    members1: object,
    members2: object,
    hard_body_radius: object,
    *,
    level: float = 0.95,
    index: int = -1,
) -> MonteCarloPcResult:
    """Monte Carlo probability of collision from member states of two ensembles at TCA.

    Every pair (i, j) of a member of object 1 and a member of object 2 is tested: the
    pair's straight-line relative motion (its own relative position and velocity, as the
    2-D Pc assumes for the means) passes within ``hard_body_radius`` of zero. The
    estimate is the fraction of all n1 n2 pairs that do: a two-sample U-statistic, which
    uses every combination of the two independent ensembles and so has far lower variance
    than pairing member i with member i (n pairs), notably for small Pc.

    Variance: ``s10^2 / n1 + s01^2 / n2`` with s10^2 the sample variance over i of the
    row hit fractions (mean over j) and s01^2 that over j of the column fractions (the
    DeLong estimator; it slightly overstates the variance, by about pc / (n1 n2)).
    Interval: ``pc -+ z sqrt(variance)`` (normal approximation, z the two-sided normal
    quantile of ``level``), clipped to [0, 1]; it needs some tens of hits to be
    reliable. With no hit the estimate is 0 and the variance 0; the interval is then the
    one-sided upper bound ``1 - (1 - level)^(1 / min(n1, n2))`` (about 3 / min(n1, n2)
    at 95 %): the exact binomial bound for min(n1, n2) disjoint, independent pairs, valid
    because no pair hit among all of them.

    Args:
        members1, members2: member states (n, 6), inertial position m and velocity m/s,
            at (or near) TCA, at least 2 each; or :class:`~rhoprop.MonteCarloResult`,
            whose members still flying at output ``index`` are used (both results must
            then be at the same epoch).
        hard_body_radius: combined hard-body radius, m (> 0).
        level: confidence level of the interval, in (0, 1).
        index: output time of a :class:`~rhoprop.MonteCarloResult` (default: the last).

    Returns:
        :class:`MonteCarloPcResult`.
    """
    hbr = _validate.positive("hard_body_radius", hard_body_radius)
    lev = _validate.real("level", level)
    if not 0.0 < lev < 1.0:
        raise ValueError(f"level must be in (0, 1), got {lev}")
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
        raise TypeError(f"index must be an integer, got {type(index).__name__}")
    s1, t1 = _members("members1", members1, int(index))
    s2, t2 = _members("members2", members2, int(index))
    if t1 is not None and t2 is not None and t1 != t2:
        raise ValueError(
            f"members1 is at {t1} but members2 at {t2}: the ensembles must be at the same "
            "epoch (the time of closest approach)"
        )
    for name, s in (("members1", s1), ("members2", s2)):
        if len(s) < 2:
            raise ValueError(f"{name} has {len(s)} member(s); at least 2 are needed")
    out = _core.pc_pairs(s1, s2, hbr)
    hits, pairs, pc, variance = out.hits, out.pairs, out.pc, out.variance
    n1, n2 = len(s1), len(s2)
    se = math.sqrt(variance)
    if hits == 0:
        interval = (0.0, 1.0 - (1.0 - lev) ** (1.0 / min(n1, n2)))
    else:
        z = NormalDist().inv_cdf(0.5 * (1.0 + lev))
        interval = (max(0.0, pc - z * se), min(1.0, pc + z * se))
    return MonteCarloPcResult(
        pc=float(pc),
        interval=interval,
        std_error=se,
        hits=int(hits),
        pairs=int(pairs),
        n1=n1,
        n2=n2,
        level=lev,
        one_sided=hits == 0,
        hard_body_radius=hbr,
    )
