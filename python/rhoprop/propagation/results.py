"""Results of the propagators: small frozen dataclasses of numpy arrays (SI units,
inertial frame) that share one moments API, :meth:`moments` -> :class:`StateMoments`
(mean state and covariance per output time), so that ensembles, catalogs and exports
treat a trajectory, a Monte Carlo and a CCSP run alike."""

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
    """

    epoch: np.datetime64
    times: Array
    mean: Array
    covariance: Array

    @property
    def epochs(self) -> Array:
        """Output epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def rtn_covariance(self) -> Array:
        """Position covariance in the RTN frame of the mean (nt, 3, 3), m^2."""
        basis = frames.rtn_basis(self.mean[:, :3], self.mean[:, 3:])
        return np.asarray(np.einsum("tij,tjk,tlk->til", basis, self.covariance[:, :3, :3], basis))

    @property
    def along_track_std(self) -> Array:
        """Square root of the along-track variance (nt,), m."""
        return np.asarray(np.sqrt(self.rtn_covariance[:, 1, 1]))

    def position_in_frame(self, ref_positions: Any, ref_velocities: Any) -> tuple[Array, Array]:
        """Mean position offset from a reference orbit (nt, 3) and the position covariance
        (nt, 3, 3), both in the reference orbit's RTN frame, m and m^2."""
        ref_p = np.asarray(ref_positions, dtype=float)
        basis = frames.rtn_basis(ref_p, ref_velocities)
        means = np.einsum("tij,tj->ti", basis, self.mean[:, :3] - ref_p)
        covs = np.einsum("tij,tjk,tlk->til", basis, self.covariance[:, :3, :3], basis)
        return means, covs


def sample_moments(states: Any) -> tuple[Array, Array]:
    """Sample mean (nt, 6) and covariance (nt, 6, 6), ddof = 1, of member states
    (n, nt, 6)."""
    s = np.asarray(states, dtype=float)
    mean = s.mean(axis=0)
    d = s - mean[None]
    return mean, np.einsum("nti,ntj->tij", d, d) / (s.shape[0] - 1)


@dataclass(frozen=True)
class Trajectory:
    """A propagated trajectory.

    Attributes:
        epoch: initial epoch (UTC, ``datetime64[ns]``).
        times: output times, s from ``epoch``, float64 (nt,).
        positions: inertial positions (nt, 3), m.
        velocities: inertial velocities (nt, 3), m/s.
        decayed_at: time (s from ``epoch``) of the first step that ended below the floor
            altitude, or None. Outputs stop there.
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
    """Per output time: mean and standard deviation of the RTN errors, m (nt, 3) each."""

    mean: Array
    std: Array


@dataclass(frozen=True)
class MonteCarloResult:
    """An ensemble of members propagated with their own density perturbation.

    Attributes:
        epoch: initial epoch (UTC).
        times: output times, s from ``epoch`` (nt,).
        positions: member positions (n, nt, 3), m, inertial.
        velocities: member velocities (n, nt, 3), m/s.
        mean_orbit: the orbit at the mean density (kappa = 0), same integrator and step.
        rtn_errors: member position minus mean orbit, in the mean orbit's RTN frame
            (n, nt, 3), m.
        clipped: density evaluations clipped at zero per member (additive form) (n,).
        decay_times: decay time per member, s from ``epoch`` (inf: no decay) (n,).
        densities: density each member saw at the output times (n, nt), kg/m^3, or None.
        kappa: the kappa process; seed: the seed; step: the integration step used, s.
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

    @property
    def epochs(self) -> Array:
        """Output epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def along_track(self) -> Array:
        """Along-track error of each member (n, nt), m: position difference projected on T."""
        return self.rtn_errors[..., 1]

    @property
    def decayed(self) -> Array:
        """Whether each member decayed below the floor altitude (n,)."""
        return np.isfinite(self.decay_times)

    def along_track_curvilinear(self) -> Array:
        """Curvilinear along-track error (n, nt), m: r_mean times the angle between the
        member and the mean position within the mean orbit's plane."""
        basis = frames.rtn_basis(self.mean_orbit.positions, self.mean_orbit.velocities)
        radial = np.einsum("tj,ntj->nt", basis[:, 0], self.positions)
        along = np.einsum("tj,ntj->nt", basis[:, 1], self.positions)
        r_mean = np.linalg.norm(self.mean_orbit.positions, axis=1)
        return np.asarray(r_mean * np.arctan2(along, radial))

    def stats(self) -> RtnStats:
        """Mean and standard deviation (ddof = 1) of the RTN errors per output time."""
        return RtnStats(self.rtn_errors.mean(axis=0), self.rtn_errors.std(axis=0, ddof=1))

    def moments(self) -> StateMoments:
        """Sample mean and covariance (ddof = 1) of the member states."""
        mean, cov = sample_moments(np.concatenate([self.positions, self.velocities], axis=2))
        return StateMoments(self.epoch, self.times, mean, cov)


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
    """

    epoch: np.datetime64
    times: Array
    mean: Array
    covariance: Array
    rtn_covariance: Array
    along_track_std: Array
    cross_covariance: Array

    @property
    def epochs(self) -> Array:
        """Update epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    def moments(self) -> StateMoments:
        """The filter's mean and covariance."""
        return StateMoments(self.epoch, self.times, self.mean, self.covariance)
