"""Results of the propagators: small frozen dataclasses of numpy arrays (SI units,
inertial frame) that share one moments API, :meth:`moments` -> :class:`StateMoments`
(mean state and covariance per output time), so that ensembles, catalogs and exports
treat a trajectory, a Monte Carlo and a CCSP run alike.

Decay: a Monte Carlo member that decayed is NaN in its positions, velocities, RTN errors
and densities from its decay time on, and every statistic here is taken over the members
still flying at each output time (:attr:`MonteCarloResult.survivors`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import frames
from ..time import offsets_to_epochs
from .kappa import KappaProcess
from .state import OrbitState

Array = NDArray[Any]


@dataclass(frozen=True)
class StateMoments:
    """Mean and covariance of the state at each output time.

    Attributes:
        epoch: initial epoch (UTC).
        times: output times, s from ``epoch`` (nt,).
        mean: mean state (nt, 6), m and m/s, inertial.
        covariance: state covariance (nt, 6, 6), m^2, m^2/s, m^2/s^2.
        count: for a Monte Carlo, the number of members behind each time's statistics
            (the survivors, (nt,)); None for a filter or a single trajectory. Where fewer
            than two members remain the covariance is NaN (and the mean too where none
            does).
    """

    epoch: np.datetime64
    times: Array
    mean: Array
    covariance: Array
    count: Array | None = None

    @property
    def epochs(self) -> Array:
        """Output epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def rtn_covariance(self) -> Array:
        """Position covariance in the RTN frame of the mean (nt, 3, 3), m^2 (NaN where the
        mean is)."""
        basis = rtn_basis(self.mean[:, :3], self.mean[:, 3:])
        return np.asarray(np.einsum("tij,tjk,tlk->til", basis, self.covariance[:, :3, :3], basis))

    @property
    def along_track_std(self) -> Array:
        """Square root of the along-track variance (nt,), m."""
        return np.asarray(np.sqrt(self.rtn_covariance[:, 1, 1]))

    def position_in_frame(self, ref_positions: Any, ref_velocities: Any) -> tuple[Array, Array]:
        """Mean position offset from a reference orbit (nt, 3) and the position covariance
        (nt, 3, 3), both in the reference orbit's RTN frame, m and m^2."""
        ref_p = np.asarray(ref_positions, dtype=float)
        basis = rtn_basis(ref_p, ref_velocities)
        means = np.einsum("tij,tj->ti", basis, self.mean[:, :3] - ref_p)
        covs = np.einsum("tij,tjk,tlk->til", basis, self.covariance[:, :3, :3], basis)
        return means, covs


def rtn_basis(positions: Any, velocities: Any) -> Array:
    """RTN bases (nt, 3, 3) of reference states (nt, 3) that may hold NaN rows (a decayed
    reference): those rows give a NaN basis instead of an error."""
    p = np.asarray(positions, dtype=float).reshape(-1, 3)
    v = np.asarray(velocities, dtype=float).reshape(-1, 3)
    ok = np.isfinite(p).all(axis=1) & np.isfinite(v).all(axis=1)
    out = np.full((len(p), 3, 3), np.nan)
    if ok.any():
        out[ok] = frames.rtn_basis(p[ok], v[ok]).reshape(-1, 3, 3)
    return out


def sample_moments(states: Any, alive: Any = None) -> tuple[Array, Array]:
    """Sample mean (nt, k) and covariance (nt, k, k), ddof = 1, of member values
    (n, nt, k) (states: k = 6), over the members ``alive`` (n, nt) at each time (default:
    those with finite values, so decayed members, NaN after their decay, are left out).
    The mean is NaN where no member is alive, the covariance where fewer than two are."""
    s = np.asarray(states, dtype=float)
    ok = np.isfinite(s).all(axis=2) if alive is None else np.asarray(alive, dtype=bool)
    count = ok.sum(axis=0)  # (nt,)
    w = ok[..., None].astype(float)
    values = np.where(ok[..., None], s, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = (w * values).sum(axis=0) / count[:, None]
        d = np.where(ok[..., None], values - mean[None], 0.0)
        cov = np.einsum("nti,ntj->tij", d, d) / (count - 1)[:, None, None]
    mean[count == 0] = np.nan
    cov[count < 2] = np.nan
    return mean, cov


@dataclass(frozen=True)
class Trajectory:
    """A propagated trajectory.

    Attributes:
        epoch: initial epoch (UTC, ``datetime64[ns]``).
        times: output times, s from ``epoch``, float64 (nt,).
        positions: inertial positions (nt, 3), m.
        velocities: inertial velocities (nt, 3), m/s.
        decayed_at: time (s from ``epoch``) at which the object went below the floor
            altitude, or None. Outputs stop before it.
        evaluations: number of right-hand-side evaluations.
        clipped: number of density evaluations clipped at zero.
    """

    epoch: np.datetime64
    times: Array
    positions: Array
    velocities: Array
    decayed_at: float | None = None
    evaluations: int = 0
    clipped: int = 0

    @property
    def epochs(self) -> Array:
        """Output epochs, ``datetime64[ns]`` (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def states(self) -> Array:
        """States (nt, 6): position m, velocity m/s."""
        return np.concatenate([self.positions, self.velocities], axis=1)

    def state_at(self, index: int = -1) -> OrbitState:
        """The output ``index`` as an :class:`OrbitState`."""
        return OrbitState(self.epochs[index], self.positions[index], self.velocities[index])

    def moments(self) -> StateMoments:
        """The states with zero covariance (a deterministic orbit)."""
        return StateMoments(self.epoch, self.times, self.states, np.zeros((len(self.times), 6, 6)))


def trajectory_from_core(epoch: np.datetime64, out: tuple[Any, ...]) -> Trajectory:
    """A :class:`Trajectory` from the tuple ``_core.propagate`` returns."""
    t, states, decayed_at, evaluations, clipped = out
    return Trajectory(
        epoch=epoch,
        times=t,
        positions=states[:, :3],
        velocities=states[:, 3:],
        decayed_at=decayed_at,
        evaluations=int(evaluations),
        clipped=int(clipped),
    )


@dataclass(frozen=True)
class RtnStats:
    """Per output time: mean and standard deviation (ddof = 1) of the RTN errors over the
    surviving members, m (nt, 3) each, and their number ``count`` (nt,). NaN where fewer
    than two members (mean: none) survive."""

    mean: Array
    std: Array
    count: Array


@dataclass(frozen=True)
class MonteCarloResult:
    """An ensemble of members propagated with their own density perturbation.

    Decayed members: a member that went below the floor altitude at ``decay_times[i]`` is
    NaN in ``positions``, ``velocities``, ``rtn_errors`` and ``densities`` at every output
    time at or after its decay (``alive`` is False there); :meth:`stats`, :meth:`moments`
    and everything built on them use the members still flying, counted per output time
    by :attr:`survivors`. Plain numpy reductions over the member axis therefore give NaN
    once a member has decayed: use ``np.nanstd`` or :meth:`stats`.

    Attributes:
        epoch: initial epoch (UTC).
        times: output times, s from ``epoch`` (nt,).
        positions: member positions (n, nt, 3), m, inertial (NaN after decay).
        velocities: member velocities (n, nt, 3), m/s (NaN after decay).
        mean_orbit: the orbit at the mean density (kappa = 0), same integrator and step;
            shorter than ``times`` if it decayed (``mean_orbit.decayed_at``).
        rtn_errors: member position minus the reference position, in the reference's RTN
            frame (n, nt, 3), m (NaN after the member's decay).
        clipped: density evaluations clipped at zero per member (additive form) (n,).
        decay_times: decay time per member, s from ``epoch`` (inf: no decay) (n,).
        densities: density each member saw at the output times (n, nt), kg/m^3, or None.
        kappa: the kappa process; seed: the seed; step: the integration step used, s.
        reference_positions, reference_velocities: the reference of ``rtn_errors``
            (nt, 3), m and m/s: the mean orbit while it flies; after the mean orbit's
            decay, the sample mean of the surviving members (NaN once none survives).
    """

    epoch: np.datetime64
    times: Array
    positions: Array
    velocities: Array
    mean_orbit: Trajectory
    rtn_errors: Array
    clipped: Array
    decay_times: Array
    densities: Array | None
    kappa: KappaProcess
    seed: int
    step: float
    reference_positions: Array
    reference_velocities: Array

    @property
    def epochs(self) -> Array:
        """Output epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def along_track(self) -> Array:
        """Along-track error of each member (n, nt), m: position difference projected on T
        (NaN after the member's decay)."""
        return self.rtn_errors[..., 1]

    @property
    def decayed(self) -> Array:
        """Whether each member decayed below the floor altitude (n,)."""
        return np.isfinite(self.decay_times)

    @property
    def alive(self) -> Array:
        """Whether each member is still flying at each output time (n, nt): the output
        time is before its decay time."""
        return np.asarray(self.times[None, :] < self.decay_times[:, None])

    @property
    def survivors(self) -> Array:
        """Number of members still flying at each output time (nt,)."""
        return np.asarray(self.alive.sum(axis=0))

    def along_track_curvilinear(self) -> Array:
        """Curvilinear along-track error (n, nt), m: r_ref times the angle between the
        member and the reference position within the reference orbit's plane."""
        basis = rtn_basis(self.reference_positions, self.reference_velocities)
        radial = np.einsum("tj,ntj->nt", basis[:, 0], self.positions)
        along = np.einsum("tj,ntj->nt", basis[:, 1], self.positions)
        r_ref = np.linalg.norm(self.reference_positions, axis=1)
        return np.asarray(r_ref * np.arctan2(along, radial))

    def stats(self) -> RtnStats:
        """Mean and standard deviation (ddof = 1) of the RTN errors per output time, over
        the members still flying then."""
        mean, cov = sample_moments(self.rtn_errors, self.alive)
        std = np.sqrt(np.diagonal(cov, axis1=1, axis2=2))
        return RtnStats(mean, std, self.survivors)

    def moments(self) -> StateMoments:
        """Sample mean and covariance (ddof = 1) of the surviving members' states, with
        their number per time (``count``)."""
        alive = self.alive
        mean, cov = sample_moments(np.concatenate([self.positions, self.velocities], axis=2), alive)
        return StateMoments(self.epoch, self.times, mean, cov, alive.sum(axis=0))


@dataclass(frozen=True)
class CcspResult:
    """CCSP outputs at every update time.

    Attributes:
        epoch: initial epoch (UTC).
        times: update times, s from ``epoch`` (nt,), starting at 0.
        mean: mean state (nt, 6), m and m/s, inertial.
        covariance: state covariance (nt, 6, 6), SI units.
        rtn_covariance: position covariance in the RTN frame of the mean (nt, 3, 3), m^2.
        along_track_std: sqrt of the along-track variance (nt,), m.
        cross_covariance: covariance of the state with the normalised density offset kappa
            (nt, 6), m and m/s.
        decayed_at: None, or the time (s from ``epoch``) at which a sigma point first went
            below the floor altitude: the filter stopped there and the outputs end at the
            last update completed before it.
    """

    epoch: np.datetime64
    times: Array
    mean: Array
    covariance: Array
    rtn_covariance: Array
    along_track_std: Array
    cross_covariance: Array
    decayed_at: float | None = None

    @property
    def epochs(self) -> Array:
        """Update epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    def moments(self) -> StateMoments:
        """The filter's mean and covariance."""
        return StateMoments(self.epoch, self.times, self.mean, self.covariance)
