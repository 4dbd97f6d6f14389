"""Monte Carlo propagation with spatio-temporally correlated density uncertainty."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _core, _validate, frames
from .density.base import as_atmosphere
from .epochs import offsets_to_epochs, seconds_since_j2000
from .kappa import GaussMarkov, KappaProcess
from .orbit import (
    DEFAULT_FLOOR_ALTITUDE,
    OrbitState,
    Spacecraft,
    Trajectory,
    output_grid,
    trajectory_from_core,
)


@dataclass(frozen=True)
class RtnStats:
    """Per output time: mean and standard deviation of the RTN errors, m (nt, 3) each."""

    mean: np.ndarray
    std: np.ndarray


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
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    mean_orbit: Trajectory
    rtn_errors: np.ndarray
    clipped: np.ndarray
    decay_times: np.ndarray
    densities: np.ndarray | None
    kappa: KappaProcess
    seed: int
    step: float

    @property
    def epochs(self) -> np.ndarray:
        """Output epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def along_track(self) -> np.ndarray:
        """Along-track error of each member (n, nt), m: position difference projected on T."""
        return self.rtn_errors[..., 1]

    @property
    def decayed(self) -> np.ndarray:
        """Whether each member decayed below the floor altitude (n,)."""
        return np.isfinite(self.decay_times)

    def along_track_curvilinear(self) -> np.ndarray:
        """Curvilinear along-track error (n, nt), m: r_mean times the angle between the
        member and the mean position within the mean orbit's plane."""
        basis = frames.rtn_basis(self.mean_orbit.positions, self.mean_orbit.velocities)
        radial = np.einsum("tj,ntj->nt", basis[:, 0], self.positions)
        along = np.einsum("tj,ntj->nt", basis[:, 1], self.positions)
        r_mean = np.linalg.norm(self.mean_orbit.positions, axis=1)
        return r_mean * np.arctan2(along, radial)

    def stats(self) -> RtnStats:
        """Mean and standard deviation (ddof = 1) of the RTN errors per output time."""
        return RtnStats(self.rtn_errors.mean(axis=0), self.rtn_errors.std(axis=0, ddof=1))


class _ProgressBar:
    """A one-line progress bar on a terminal, shown once a run has taken 1 s."""

    def __init__(self, total: int, label: str) -> None:
        self.total, self.label = total, label
        self.start = time.perf_counter()
        self.shown = False

    def __call__(self, done: int) -> None:
        elapsed = time.perf_counter() - self.start
        if elapsed < 1.0 or not sys.stderr.isatty():
            return
        self.shown = True
        frac = done / self.total
        bar = "#" * int(30 * frac)
        sys.stderr.write(
            f"\r{self.label} [{bar:<30}] {done}/{self.total} members  {elapsed:5.1f} s"
        )
        sys.stderr.flush()

    def close(self) -> None:
        if self.shown:
            sys.stderr.write("\n")


def monte_carlo(
    state: OrbitState,
    spacecraft: Spacecraft,
    model: Any,
    duration: Any,
    *,
    n: int = 1000,
    kappa: KappaProcess | None = None,
    seed: int = 0,
    output_step: float | None = 3600.0,
    initial_covariance: Any = None,
    perturbation: str = "additive",
    record_density: bool = False,
    progress: bool = True,
    method: str = "rk8",
    step: float = 180.0,
    threads: int | None = None,
    floor_altitude: float = DEFAULT_FLOOR_ALTITUDE,
) -> MonteCarloResult:
    """Propagates ``n`` members, each with its own density perturbation kappa(t).

    Args:
        state: initial :class:`~rhoprop.OrbitState` (the mean, if ``initial_covariance``).
        spacecraft: :class:`~rhoprop.Spacecraft`.
        model: a density model with uncertainty (e.g. ``rp.density.Msis()``); its mean and
            sigma are sampled into a field once and interpolated by the core.
        duration: span, s (> 0) or a ``timedelta``.
        n: number of members (>= 2).
        kappa: the kappa process (default ``GaussMarkov(1080)``, 18 min half-life).
        seed: seed of the members' random streams (same seed, same numbers, whatever the
            thread count).
        output_step: output spacing, s (a multiple of the integration step); None gives
            the start and end only. The end is always an output.
        initial_covariance: optional 6x6 covariance of the initial state (m^2, m^2/s,
            m^2/s^2), symmetric positive semi-definite; members then start from samples.
        perturbation: ``"additive"`` (rho = mean + kappa sigma, clipped at 0 and counted)
            or ``"lognormal"``.
        record_density: also return the density each member sees at the output times.
        progress: show a progress bar on a terminal for runs longer than a second.
        method: ``"rk8"`` (default) or ``"rk4"`` fixed step.
        step: largest integration step, s; the step used divides the kappa node spacing
            (e.g. 10 s for ``White(10)``).
        threads: worker threads (default: all cores).
        floor_altitude: decay floor, m (decayed members stop there and are reported).

    Returns:
        :class:`MonteCarloResult`. Ctrl-C stops the run with KeyboardInterrupt.
    """
    if not isinstance(state, OrbitState):
        raise TypeError(f"state must be an OrbitState, got {type(state).__name__}")
    if not isinstance(spacecraft, Spacecraft):
        raise TypeError(f"spacecraft must be a Spacecraft, got {type(spacecraft).__name__}")
    kappa = GaussMarkov() if kappa is None else kappa
    if not isinstance(kappa, KappaProcess):
        raise TypeError(f"kappa must be a rhoprop.kappa process, got {type(kappa).__name__}")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    if threads is not None and (not isinstance(threads, (int, np.integer)) or threads < 1):
        raise ValueError(f"threads must be a positive integer, got {threads!r}")
    span = _validate.positive("duration", _validate.seconds("duration", duration))
    step = _validate.positive("step", step)
    floor = _validate.real("floor_altitude", floor_altitude)
    cov = None
    if initial_covariance is not None:
        cov = np.ascontiguousarray(initial_covariance, dtype=float)
        if cov.shape != (6, 6):
            raise ValueError(f"initial_covariance must have shape (6, 6), got {cov.shape}")
    times = output_grid(span, output_step)
    epoch = seconds_since_j2000(state.epoch)
    atmosphere = as_atmosphere(model, state, span)
    bar = _ProgressBar(int(n), "Monte Carlo") if progress else None
    try:
        out = _core.monte_carlo(
            atmosphere,
            epoch,
            state.state,
            spacecraft.drag_parameter,
            times,
            kappa._spec(),
            perturbation,
            method,
            step,
            int(n),
            int(seed),
            cov,
            floor,
            bool(record_density),
            threads,
            bar,
        )
    finally:
        if bar is not None:
            bar.close()
    h = float(out["step"])
    mean = trajectory_from_core(
        state.epoch,
        _core.propagate(
            atmosphere,
            epoch,
            state.state,
            spacecraft.drag_parameter,
            times,
            method,
            h,
            None,
            floor,
        ),
        method,
    )
    t, decayed_at = mean.times, mean.decayed_at
    if len(t) < len(times):
        raise ValueError(
            f"the mean orbit decays below the floor at {decayed_at} s; shorten the duration"
        )
    rtn = frames.to_rtn(out["positions"], mean.positions, mean.velocities)
    return MonteCarloResult(
        epoch=state.epoch,
        times=times,
        positions=out["positions"],
        velocities=out["velocities"],
        mean_orbit=mean,
        rtn_errors=rtn,
        clipped=out["clipped"],
        decay_times=out["decay_times"],
        densities=out["densities"],
        kappa=kappa,
        seed=int(seed),
        step=h,
    )
