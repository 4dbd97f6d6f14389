"""Monte Carlo propagation with spatio-temporally correlated density uncertainty."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from .. import _core, _validate, frames
from ..density.model import AtmosphereLike, ModelLike
from ..options import Integrator, Perturbation
from ..parallel import core_threads, worker_count
from ..progress import ProgressBar
from ..time import DurationLike
from . import run_frame
from .dynamics import Dynamics, LooseDynamics, deprecated_keywords, zonal_degree_argument
from .kappa import KappaProcess, TwoScale
from .propagate import (
    DEFAULT_MAX_MEMORY,
    check_memory,
    check_model,
    check_steps,
    core_problem,
    core_propagate,
    explicit_times,
    fixed_step,
    output_grid,
    run_in_field,
    span_of,
)
from .results import MonteCarloResult, Trajectory, sample_moments, trajectory_from_core
from .state import OrbitState, Spacecraft

if TYPE_CHECKING:
    from typing_extensions import Unpack

#: Methods of :func:`monte_carlo` (fixed step: kappa nodes fall on step boundaries).
METHODS = ("rk8", "rk4", "abm")


def drag_sigma_argument(value: object) -> float:
    """``drag_sigma`` checked: the relative 1-sigma of Cd*A/m, a finite number from 0 to
    ``rhoprop._core.MAX_DRAG_SIGMA`` (3); else a ValueError/TypeError naming it."""
    out = _validate.real("drag_sigma", value)
    if not 0.0 <= out <= _core.MAX_DRAG_SIGMA:
        raise ValueError(
            f"drag_sigma must be from 0 to {_core.MAX_DRAG_SIGMA:g} (the relative 1-sigma of "
            f"Cd*A/m, e.g. 0.1 = 10 %), got {out}"
        )
    return out


def members_argument(value: object) -> int:
    """``n`` checked: the number of members, an integer >= 2."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 2:
        raise ValueError(f"n must be an integer >= 2, got {value!r}")
    return int(value)


def threads_argument(value: object) -> int:
    """``threads`` checked: a positive integer, at most the limit of every pool
    (:func:`rhoprop.parallel.worker_count`)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"threads must be a positive integer, got {value!r}")
    return worker_count(int(value))


#: Member-outputs per block of the RTN conversion (bounds its temporaries: ~100 MB).
RTN_BLOCK = 1 << 20


def result_bytes(n: int, nt: int, record_density: bool) -> int:
    """Peak memory of a Monte Carlo, bytes: its member arrays, positions, velocities and
    RTN errors (9 float64 per member and output), the densities (1 more) if recorded,
    and the masks of decayed members (2 bytes); 64 bytes per member (drag factors, decay
    times, clip counts, in the core and in numpy); and the RTN conversion's temporaries
    (at most 4 arrays of :data:`RTN_BLOCK` x 3 float64). The core writes each batch of
    members straight into the result, so nothing else grows with ``n`` (measured:
    10**7 members x 2 outputs peak at 1.98 GB against this estimate's 2.2 GB)."""
    block = min(n * nt, RTN_BLOCK)
    return n * nt * (8 * (9 + int(record_density)) + 2) + 64 * n + 4 * 24 * block


class MonteCarloKeywords(LooseDynamics, total=False):
    """The keywords of :func:`monte_carlo`: the settings of :class:`~rhoprop.MonteCarlo`
    (:data:`SETTINGS`, the same names, units and defaults), and, deprecated, the loose
    :class:`~rhoprop.Dynamics` attributes and ``method`` (an older name of
    ``integrator``)."""

    n: int
    kappa: KappaProcess | None
    seed: int
    output_step: float | None
    perturbation: Perturbation
    record_density: bool
    progress: bool | Callable[[int], object]
    threads: int | None
    max_memory: float
    drag_sigma: float
    method: Integrator


#: Default members and output spacing (s) of a Monte Carlo.
MEMBERS, OUTPUT_STEP = 1000, 3600.0
#: The settings among :class:`MonteCarloKeywords` (the fields of ``rp.MonteCarlo``).
SETTINGS = (
    "n",
    "seed",
    "kappa",
    "output_step",
    "perturbation",
    "drag_sigma",
    "record_density",
    "threads",
    "max_memory",
    "progress",
)


def monte_carlo(
    state: OrbitState,
    spacecraft: Spacecraft,
    model: ModelLike,
    duration: DurationLike | None = None,
    *,
    output_times: npt.ArrayLike | None = None,
    initial_covariance: npt.ArrayLike | None = None,
    dynamics: Dynamics | None = None,
    **settings: Unpack[MonteCarloKeywords],
) -> MonteCarloResult:
    """Propagates ``n`` members, each with its own density perturbation kappa(t).

    Args:
        state: initial :class:`~rhoprop.OrbitState` (the mean, if ``initial_covariance``).
        spacecraft: :class:`~rhoprop.Spacecraft` (with ``cr``: radiation pressure too).
        model: a density model with uncertainty (e.g. ``rp.density.Msis()``); its mean and
            sigma are sampled into a field once and interpolated by the core.
        duration: span, s (> 0) or a ``timedelta``; may be left out when ``output_times``
            is given (then it must equal the last of them).
        output_times: explicit output times instead of ``output_step``, s from the epoch
            (increasing, >= 0, on the integration step grid; the last is the end).
        initial_covariance: optional 6x6 covariance of the initial state (m^2, m^2/s,
            m^2/s^2), symmetric positive semi-definite, finite; members then start from
            samples.
        dynamics: :class:`~rhoprop.Dynamics`: the integrator (``"rk8"``, the default,
            ``"rk4"`` or ``"abm"``, fixed step; ``"abm"``, 2 evaluations a step restarted
            with RK8 at every kappa node, pays for held kappa processes such as
            ``Constant``: about half RK8's cost at its 80-s default), the largest
            ``step`` (s; None: RK8 180 s, RK4 5 s, ABM 80 s, at most 1/20 of the orbital
            period; the step used divides the kappa node spacing), the zonal degree (2: J2
            only, the paper's model; 3 to 6 add J3..J6) and the floor altitude (m).
        **settings: the settings of :class:`~rhoprop.MonteCarlo`
            (``rp.MonteCarlo(**settings).run(...)`` is the same run):

            - ``n``: number of members (>= 2).
            - ``kappa``: the kappa process (default :class:`~rhoprop.kappa.TwoScale`, calibrated on
              observed densities: half-lives 4.6 h and 4.4 days, 54 % of the variance in
              the slow term; the paper's was ``GaussMarkov(1080)``, 18 min).
            - ``seed``: seed of the members' random streams (same seed, same numbers, whatever the
              thread count).
            - ``output_step``: output spacing, s (a multiple of the integration step); None gives
              the start and end only. The end is always an output.
            - ``perturbation``: ``"additive"`` (rho = mean + kappa sigma, clipped at 0 and counted)
              or ``"lognormal"``.
            - ``record_density``: also return the density each member sees at the output times.
            - ``progress``: True shows a progress bar on a terminal for runs longer than a second;
              or a callable, called with the number of members done about every 50 ms (an
              exception it raises stops the run and is raised).
            - ``threads``: worker threads (default: all cores; at most 4 per core).
            - ``max_memory``: limit on the run's peak memory, bytes (default 8 GiB): a run whose
              estimate (:func:`result_bytes`: n x outputs x 9 float64, 10 with densities,
              plus per-member arrays and bounded temporaries) would exceed it is refused
              before it starts, with the estimate in the message.
            - ``drag_sigma``: relative 1-sigma of the ballistic coefficient Cd*A/m (dimensionless;
              0.1 = 10 %; default 0: every member flies the spacecraft's value). Member i
              flies Cd*A/m times exp(drag_sigma c_i), c_i ~ N(0, 1): a log-normal with
              median the nominal value (always positive; for small sigma, 1 + drag_sigma c).
              c_i comes from a stream of its own per member, so it depends only on ``seed``
              and i (not on the thread count) and leaves the member's kappa draws as they
              are without it. The factors are ``result.drag_factors``. At most 3.

            Deprecated, folded into ``dynamics`` with a warning: ``integrator``,
            ``step``, ``floor_altitude``, ``zonal_degree`` (and ``method``, an older name
            of ``integrator``).

    Returns:
        :class:`MonteCarloResult`. Decayed members are NaN from their decay time on and
        statistics use the survivors (:attr:`MonteCarloResult.survivors`). If the mean
        orbit itself decays the run still completes: ``rtn_errors`` are relative to the
        mean orbit until its decay and to the survivors' mean state after it. Ctrl-C stops
        the run with KeyboardInterrupt.
    """
    if not isinstance(state, OrbitState):
        raise TypeError(f"state must be an OrbitState, got {type(state).__name__}")
    if not isinstance(spacecraft, Spacecraft):
        raise TypeError(f"spacecraft must be a Spacecraft, got {type(spacecraft).__name__}")
    check_model(model)
    loose = {k: v for k, v in settings.items() if k not in SETTINGS}
    dyn = deprecated_keywords("monte_carlo", dynamics, loose, aliases={"method": "integrator"})
    n, seed, kappa = settings.get("n", MEMBERS), settings.get("seed", 0), settings.get("kappa")
    output_step = settings.get("output_step", OUTPUT_STEP)
    perturbation = settings.get("perturbation", "additive")
    record_density, progress = settings.get("record_density", False), settings.get("progress", True)
    threads, drag_sigma = settings.get("threads"), settings.get("drag_sigma", 0.0)
    max_memory = settings.get("max_memory", DEFAULT_MAX_MEMORY)
    kappa = TwoScale() if kappa is None else kappa
    if not isinstance(kappa, KappaProcess):
        raise TypeError(f"kappa must be a rhoprop.kappa process, got {type(kappa).__name__}")
    n = members_argument(n)
    seed = _validate.seed(seed)
    threads = core_threads() if threads is None else threads_argument(threads)
    method = dyn.integrator or "rk8"
    step, floor_altitude, zonal_degree = dyn.step, dyn.floor_altitude, dyn.zonal_degree
    if method not in METHODS:
        raise ValueError(f"unknown integrator {method!r}; a Monte Carlo uses 'rk8', 'rk4' or 'abm'")
    dyn.require_integrator("monte_carlo", METHODS)
    h = fixed_step(method, step, state)
    if output_times is None:
        span = span_of(duration, None, "output_times")
        times = output_grid(span, output_step)
    else:
        if output_step not in (None, OUTPUT_STEP):
            raise ValueError("give output_step or output_times, not both")
        times = explicit_times("output_times", output_times, allow_zero=True)
        span = span_of(duration, times, "output_times")
    nodes = kappa.node_spacing()
    check_steps(span, h, "step")
    if nodes is not None:
        check_steps(span, nodes, f"the node spacing of {kappa!r}")
    limit = _validate.positive("max_memory", max_memory)
    check_memory(
        result_bytes(int(n), len(times), record_density),
        limit,
        f"{n} members x {len(times)} outputs",
    )
    floor = _validate.real("floor_altitude", floor_altitude)
    degree = zonal_degree_argument(zonal_degree)
    drag_sigma = drag_sigma_argument(drag_sigma)
    cov = None
    if initial_covariance is not None:
        cov = np.array(initial_covariance, dtype=float)
        if cov.shape != (6, 6):
            raise ValueError(f"initial_covariance must have shape (6, 6), got {cov.shape}")
        if not np.isfinite(cov).all():
            i, j = np.argwhere(~np.isfinite(cov))[0]
            raise ValueError(f"initial_covariance[{i}][{j}] must be finite, got {cov[i, j]}")
    given = state
    state, cov, rot = run_frame.into_run(state, cov)

    problem = core_problem(
        state, spacecraft.drag_parameter, floor, degree, dyn.forces(spacecraft.radiation_parameter)
    )
    request = _core.MonteCarloRun(
        problem,
        output_times=times,
        kappa=kappa._spec(),
        perturbation=perturbation,
        method=method,
        step=h,
        members=int(n),
        seed=int(seed),
        initial_covariance=cov,
        record_density=bool(record_density),
        drag_sigma=drag_sigma,
    )

    def run(atmosphere: AtmosphereLike) -> tuple[_core.MonteCarloOutput, Trajectory]:
        bar = ProgressBar(int(n), "Monte Carlo") if progress is True else None
        callback = bar if bar is not None else (progress if callable(progress) else None)
        try:
            out = _core.monte_carlo(atmosphere, request, threads, callback)
        finally:
            if bar is not None:
                bar.close()
        # The mean orbit: same integrator, step and field, kappa = 0, nominal Cd*A/m.
        mean = core_propagate(
            atmosphere,
            state,
            spacecraft.drag_parameter,
            times,
            integrator=method,
            step=float(out.step),
            floor_altitude=floor,
            zonal_degree=degree,
            forces=dyn.forces(spacecraft.radiation_parameter),
        )
        return out, trajectory_from_core(state.epoch, mean, state.frame)

    out, mean = run_in_field(model, state, span, floor, run)
    decay = np.asarray(out.decay_times, dtype=float)
    alive = times[None, :] < decay[:, None]
    positions = run_frame.vectors_in_place(rot, out.positions)
    velocities = run_frame.vectors_in_place(rot, out.velocities)
    if rot is not None and cov is None and len(times) and times[0] == 0.0:
        positions[:, 0], velocities[:, 0] = given.position, given.velocity  # as given
    if rot is not None:
        mp, mv = run_frame.vectors(rot, mean.positions), run_frame.vectors(rot, mean.velocities)
        if len(mean.times) and mean.times[0] == 0.0:
            mp[0], mv[0] = given.position, given.velocity
        mean = replace(mean, positions=mp, velocities=mv, frame=given.frame)
    # A decayed member's frozen state would bias every statistic: NaN from its decay on.
    positions[~alive] = np.nan
    velocities[~alive] = np.nan
    densities = out.densities
    if densities is not None:
        densities[~alive] = np.nan
    ref_p, ref_v = _reference(mean, positions, velocities, alive)
    return MonteCarloResult(
        epoch=state.epoch,
        times=times,
        positions=positions,
        velocities=velocities,
        mean_orbit=mean,
        rtn_errors=_rtn(positions, ref_p, ref_v),
        clipped=out.clipped,
        decay_times=decay,
        densities=densities,
        kappa=kappa,
        seed=int(seed),
        step=float(out.step),
        reference_positions=ref_p,
        reference_velocities=ref_v,
        drag_sigma=drag_sigma,
        drag_factors=np.asarray(out.drag_factors, dtype=float),
        frame=given.frame,
    )


def _reference(
    mean: Trajectory, positions: np.ndarray, velocities: np.ndarray, alive: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The reference orbit of the RTN errors (nt, 3) x 2: the mean orbit while it flies,
    then the survivors' mean state (NaN once none survives)."""
    k = len(mean.times)
    ref_p, ref_v = np.empty((positions.shape[1], 3)), np.empty((positions.shape[1], 3))
    ref_p[:k], ref_v[:k] = mean.positions, mean.velocities
    if k < len(ref_p):
        states = np.concatenate([positions[:, k:], velocities[:, k:]], axis=2)
        survivors, _ = sample_moments(states, alive[:, k:])
        ref_p[k:], ref_v[k:] = survivors[:, :3], survivors[:, 3:]
    return ref_p, ref_v


def _rtn(positions: np.ndarray, ref_p: np.ndarray, ref_v: np.ndarray) -> np.ndarray:
    """Members' positions minus the reference in its RTN frame (n, nt, 3); NaN where the
    member or the reference is."""
    ok = np.isfinite(ref_p).all(axis=1) & np.isfinite(ref_v).all(axis=1)
    rtn = np.full(positions.shape, np.nan)
    if ok.any():
        # In blocks of members, so that the temporaries stay small beside the result.
        size = max(1, RTN_BLOCK // max(1, positions.shape[1]))
        for i in range(0, len(positions), size):
            part = positions[i : i + size]
            rtn[i : i + size, ok] = frames.to_rtn(part[:, ok], ref_p[ok], ref_v[ok])
    return rtn
