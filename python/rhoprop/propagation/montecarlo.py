"""Monte Carlo propagation with spatio-temporally correlated density uncertainty."""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import _core, _validate, frames
from ..constants import DEFAULT_FLOOR_ALTITUDE
from ..density.model import DensityModel, as_atmosphere
from ..progress import ProgressBar
from ..time import seconds_since_j2000
from .kappa import GaussMarkov, KappaProcess
from .propagate import output_grid
from .results import MonteCarloResult, trajectory_from_core
from .state import OrbitState, Spacecraft


def monte_carlo(
    state: OrbitState,
    spacecraft: Spacecraft,
    model: DensityModel,
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
    bar = ProgressBar(int(n), "Monte Carlo") if progress else None
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
