"""The consider-covariance sigma-point (CCSP) filter: orbit covariance with density as a
consider parameter (paper section 4, as made unambiguous in docs/conventions.md, "CCSP filter")."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, TypedDict

import numpy as np
import numpy.typing as npt

from .. import _core, _validate
from ..density.model import AtmosphereLike, ModelLike, as_atmosphere
from ..options import Perturbation
from ..time import DurationLike, ut1_seconds
from . import run_frame
from .dynamics import Dynamics, LooseFloorAndDegree, deprecated_keywords, zonal_degree_argument
from .kappa import Constant, GaussMarkov, KappaProcess, PiecewiseConstant, TwoScale
from .montecarlo import drag_sigma_argument
from .propagate import (
    DEFAULT_MAX_MEMORY,
    MAX_STEPS,
    axis_and_eccentricity,
    check_memory,
    check_model,
    check_steps,
    core_problem,
    explicit_times,
    fixed_step,
    mean_anomaly,
    orbital_period,
    run_in_field,
    span_of,
)
from .results import CcspResult, StateMoments
from .state import OrbitState, Spacecraft

if TYPE_CHECKING:
    from typing_extensions import Unpack

#: The paper's near-zero initial covariance: 1 mm and 1 um/s (1 sigma) on each axis.
DEFAULT_INITIAL_COVARIANCE = np.diag([1e-6, 1e-6, 1e-6, 1e-12, 1e-12, 1e-12])
#: Memory of one CCSP output (mean, covariance, cross-covariance, RTN covariance and the
#: along-track sigma as float64), bytes.
OUTPUT_BYTES = 8 * (6 + 36 + 6 + 9 + 1)
#: The CCSP's coordinates (:func:`ccsp`'s ``coordinates``).
Coordinates = Literal["equinoctial", "cartesian"]
COORDINATES: tuple[Coordinates, ...] = ("equinoctial", "cartesian")
#: The paper's update interval, s: the default for near-circular orbits.
DEFAULT_UPDATE_INTERVAL = 3600.0
#: Eccentricity from which the default schedule updates once per revolution, at apogee
#: (:func:`update_schedule`).
APOGEE_UPDATE_ECCENTRICITY = 0.1


class CcspKeywords(TypedDict, total=False):
    """The keywords of :func:`ccsp`: the settings of :class:`~rhoprop.Ccsp`
    (:data:`SETTINGS`, the same names, units and defaults), and, deprecated, the loose
    :class:`~rhoprop.Dynamics` attributes the filter took (``step``, ``floor_altitude``,
    ``zonal_degree``)."""

    update_interval: float | None
    kappa: KappaProcess | None
    scaling: tuple[float, float] | None
    perturbation: Perturbation
    drag_sigma: float
    coordinates: Coordinates
    step: float
    floor_altitude: float
    zonal_degree: int


#: The settings among :class:`CcspKeywords` (the fields of ``rp.Ccsp``).
SETTINGS = ("update_interval", "kappa", "scaling", "perturbation", "drag_sigma", "coordinates")


def ccsp(
    state: OrbitState,
    spacecraft: Spacecraft,
    model: ModelLike,
    duration: DurationLike | None = None,
    *,
    initial_covariance: npt.ArrayLike | None = None,
    update_times: npt.ArrayLike | None = None,
    output_times: npt.ArrayLike | None = None,
    dynamics: Dynamics | None = None,
    **settings: Unpack[CcspKeywords],
) -> CcspResult:
    """Propagates mean and covariance with the CCSP filter.

    The augmented state is [r, v, kappa], kappa the normalised density offset (unit
    variance): density = mean + kappa * sigma at each sigma point's own position and time,
    kappa held over an update interval. At each update the state covariance gains
    C C^T from the consider points' cross-covariance C, and new sigma points are drawn from
    the factor S = [[Chol(A), B^T], [0, sqrt(l2)]], B = C^T / sqrt(l2),
    A = l1 (P - B^T B / l2) (docs/conventions.md, "CCSP filter"; the paper prints the
    off-diagonal block transposed, which mixes units, and its A = l1 P - B^T B is this only
    at its l1 = l2 = 3). The result is the linearised covariance of a kappa piecewise
    constant over each interval with correlation 1 / l2 between consecutive intervals
    (``rp.kappa.PiecewiseConstant(update_interval, 1 / l2)``); ``kappa`` chooses l2 (and
    how the process splits between kappa and c) so that the filter stands for that
    process: by default the calibrated :class:`~rhoprop.kappa.TwoScale`. With
    ``scaling=(3, 3)`` (the paper's filter) the long-time along-track spread is
    sqrt(2 dt / D) times that of a Monte Carlo with correlation time D, i.e. 1.52x
    GaussMarkov(18 min) at 60-min updates and 0.44x at 5-min updates.

    Ballistic-coefficient uncertainty (``drag_sigma`` > 0): a second consider parameter
    c, the normalised error of Cd*A/m (a sigma point flies with Cd*A/m exp(drag_sigma c),
    the log-normal of :func:`rhoprop.monte_carlo`'s ``drag_sigma``). The augmented state
    becomes [r, v, kappa, c]. c is a constant of the object, so its cross-covariance D
    with the state is carried whole from update to update (kappa's shrinks by 1 / l2):
    the factor is S = [[Chol(A), C / sqrt(l2), a sqrt(l2) D], [0, diag(sqrt(l2),
    a sqrt(l2))]] with A = l1 (P - D D^T - C C^T / l2^2) and a = 0.001 (one c point, a
    one-sided difference in the tangent-linear limit), and P = P_set1 + C C^T + D D^T after
    each update (derivation: docs/conventions.md). This is the covariance linearised in c: a Monte
    Carlo over the same log-normal Cd*A/m samples spreads about 1 + 3 drag_sigma^2 / 4
    times as much (0.75 % more at 10 %), whatever the update interval.

    Decay: when a sigma point goes below ``floor_altitude`` the filter stops cleanly; the
    outputs end at the last update completed before it and ``decayed_at`` gives the time.

    Args:
        state, spacecraft: initial mean state and drag (and, with ``cr``, radiation
            pressure) properties.
        model: density model with uncertainty (sampled into a field once).
        duration: span, s, or a ``timedelta``; may be left out when ``update_times`` is
            given, and must then equal the last update time if given too.
        initial_covariance: 6x6 state covariance (default: the paper's near-zero
            diag(eps^2) with eps = 1 mm and 1 um/s).
        update_times: explicit update times, s from the epoch (increasing, > 0; the last
            is the end), instead of ``update_interval`` (used to align objects on common
            output epochs).
        output_times: further outputs, s from the epoch (increasing, between 0 and the
            end): the moments of the sigma points in flight, not re-drawn there. Default
            None: an output at each update only (and, for an eccentric orbit with the
            default ``update_interval``, hourly between its apogee updates).
        dynamics: :class:`~rhoprop.Dynamics`: the largest RK8 ``step`` (s; None: 180 s,
            at most 1/20 of the orbital period), the zonal degree (2: J2 only, the paper's
            model; 3 to 6 add J3..J6) and the floor altitude (m). Its integrator must be
            None or ``"rk8"``: the filter integrates its sigma points with RK8.
        **settings: the settings of :class:`~rhoprop.Ccsp`
            (``rp.Ccsp(**settings).run(...)`` is the same run):

            - ``update_interval``: s. Default None: every 60 min (the paper's tuning) for a
              near-circular orbit; for an eccentric one (e >= 0.1) once per revolution, at
              apogee, with outputs every 60 min between (:func:`update_schedule`: one kappa
              per perigee pass; it was chosen when sigma points re-drawn in Cartesian
              coordinates near perigee left the orbit's energy, which in equinoctial
              elements they no longer do).
              A number: updates every that many s whatever the orbit.
            - ``kappa``: the density error the filter stands for (default None: the calibrated
              :class:`~rhoprop.kappa.TwoScale`, as the Monte Carlo; ignored when
              ``scaling`` is given). The filter carries one kappa held over each update,
              correlated 1 / lambda2 from one update to the next, and the constant c of
              ``drag_sigma``: a ``PiecewiseConstant`` (its interval must be the update
              interval) or ``GaussMarkov`` is that kappa (correlation c = its own over the
              update interval, or the longest spacing of ``update_times``); a ``TwoScale``
              puts its fast term there (kappa scaled by sqrt(1 - w)) and its slow one, a
              density scale that holds for days, into a third consider parameter s, held
              over each update like kappa and correlated 2^(-dt / slow_half_life) from one
              update to the next (dt the spacing of the two updates); ``Constant`` is s
              alone, never decorrelating. Against 2,000 members of the same process the
              along-track sigma is 0.97-1.03x and 93-96 % of the members lie inside the
              filter's 95 % region of (a, lambda) at 1-14 days (docs/mc-vs-ccsp.md).
            - ``scaling``: (lambda1 + n, lambda2 + p). None (default): (3, 1 / c) with c the
              update-to-update correlation of ``kappa``'s process. Given (the paper's is
              (3, 3)) and ``kappa`` None: the paper's filter, the process
              ``PiecewiseConstant(update_interval, 1 / lambda2)``.
            - ``perturbation``: ``"additive"`` or ``"lognormal"``.
            - ``drag_sigma``: relative 1-sigma of the ballistic coefficient Cd*A/m (dimensionless;
              0.1 = 10 %; at most 3). Default 0: density uncertainty only, the paper's filter
              (results unchanged). Costs one more sigma point (17 with the default kappa's slow
              term: about 1.2x the run's cost).
            - ``coordinates``: where the sigma points are drawn and their moments taken:
              ``"equinoctial"`` (default: elements a, h, k, p, q, lambda, in which an
              along-track spread stays on the orbit; the Cartesian outputs are the linear
              map of that Gaussian, which is returned too as ``element_mean`` and
              ``element_covariance``) or ``"cartesian"`` (the paper's filter: its
              straight-line points leave the orbit, and its along-track sigma outgrows the
              Monte Carlo it stands for past about 5 days: 1.2x at 7 days, 8.6x at 19;
              docs/conventions.md, "CCSP coordinates").
            Deprecated, folded into ``dynamics`` with a warning: ``step``,
            ``floor_altitude``, ``zonal_degree``.

    Returns:
        :class:`CcspResult`. Ctrl-C stops the run with KeyboardInterrupt.
    """
    given, given_cov, rot = state, initial_covariance, None
    if isinstance(state, OrbitState):
        state, initial_covariance, rot = run_frame.into_run(state, initial_covariance)
    loose = {k: v for k, v in settings.items() if k not in SETTINGS}
    dyn = deprecated_keywords(
        "ccsp", dynamics, loose, names=("step", "floor_altitude", "zonal_degree")
    )
    update_interval, kappa = settings.get("update_interval"), settings.get("kappa")
    scaling, perturbation = settings.get("scaling"), settings.get("perturbation", "additive")
    drag_sigma = settings.get("drag_sigma", 0.0)
    coordinates = settings.get("coordinates", "equinoctial")
    if dyn.integrator not in (None, "rk8"):
        raise ValueError(f"the CCSP integrates with RK8; dynamics.integrator = {dyn.integrator!r}")
    dyn.require_integrator("ccsp", ("rk8",))
    step, floor_altitude, zonal_degree = dyn.step, dyn.floor_altitude, dyn.zonal_degree
    args, span = _arguments(
        state,
        spacecraft,
        model,
        duration,
        update_interval=update_interval,
        initial_covariance=initial_covariance,
        scaling=scaling,
        step=step,
        floor_altitude=floor_altitude,
        update_times=update_times,
        zonal_degree=zonal_degree,
        drag_sigma=drag_sigma,
        output_times=output_times,
        coordinates=coordinates,
        kappa=kappa,
    )

    request = args.request(
        state, spacecraft, perturbation, dyn.forces(spacecraft.radiation_parameter)
    )

    def run(atmosphere: AtmosphereLike) -> _core.CcspOutput:
        return _core.ccsp(atmosphere, request)

    out = run_in_field(model, state, span, args.floor, run)
    return _result(state, out, args.drag_sigma, given.frame, rot, given, given_cov)


@dataclass(frozen=True)
class _Arguments:
    """The checked arguments of one CCSP run, as the core takes them."""

    epoch: float
    p0: np.ndarray
    times: np.ndarray
    scaling: tuple[float, float]
    step: float
    floor: float
    degree: int
    drag_sigma: float
    outputs: np.ndarray  # output times between updates, s (may be empty)
    coordinates: Coordinates
    kappa_scale: float = 1.0
    slow: tuple[float, float] | None = None  # (scale, half-life s) of a slow density term

    def request(
        self,
        state: OrbitState,
        spacecraft: Spacecraft,
        perturbation: str = "additive",
        forces: tuple[int | None, bool | None, float] = (None, None, 0.0),
    ) -> _core.CcspRun:
        """The core's record of this run from ``state`` (in the run's axes) with
        ``spacecraft``'s Cd*A/m, checked by the core when made."""
        problem = core_problem(state, spacecraft.drag_parameter, self.floor, self.degree, forces)
        return _core.CcspRun(
            problem,
            initial_covariance=self.p0,
            update_times=self.times,
            scaling=self.scaling,
            perturbation=perturbation,
            step=self.step,
            drag_sigma=self.drag_sigma,
            output_times=self.outputs if len(self.outputs) else None,
            coordinates=self.coordinates,
            kappa_scale=self.kappa_scale,
            slow=self.slow,
        )


def _arguments(
    state: Any,
    spacecraft: Any,
    model: Any,
    duration: DurationLike | None,
    *,
    update_interval: float | None,
    initial_covariance: Any,
    scaling: tuple[float, float] | None,
    step: float | None,
    floor_altitude: float,
    update_times: Any,
    zonal_degree: int,
    drag_sigma: float,
    output_times: Any = None,
    coordinates: str = "equinoctial",
    kappa: KappaProcess | None = None,
) -> tuple[_Arguments, float]:
    """Checks the arguments of :func:`ccsp`; returns them for the core and the span, s."""
    if not isinstance(state, OrbitState):
        raise TypeError(f"state must be an OrbitState, got {type(state).__name__}")
    if not isinstance(spacecraft, Spacecraft):
        raise TypeError(f"spacecraft must be a Spacecraft, got {type(spacecraft).__name__}")
    check_model(model)
    scheduled = np.empty(0)
    if update_times is None and update_interval is None:
        span, hourly = interval_times(duration, DEFAULT_UPDATE_INTERVAL)
        times, between = update_schedule(state, hourly, DEFAULT_UPDATE_INTERVAL)
        if between is not None:
            scheduled = between
    elif update_times is None:
        dt = _validate.positive("update_interval", update_interval)
        span, times = interval_times(duration, dt)
    else:
        times = explicit_times("update_times", update_times, allow_zero=False)
        span = span_of(duration, times, "update_times")
    h = fixed_step("rk8", step, state)
    check_steps(span, h, "step")
    outputs = np.empty(0)
    if output_times is not None:
        outputs = explicit_times("output_times", output_times, allow_zero=False)
        if len(outputs) and outputs[-1] >= times[-1]:
            raise ValueError(
                f"output_times must lie before the end ({times[-1]:g} s), got {outputs[-1]:g}"
            )
        outputs = np.setdiff1d(outputs, times)
    outputs = np.setdiff1d(np.union1d(outputs, scheduled), times)
    check_memory(
        (len(times) + len(outputs) + 1) * OUTPUT_BYTES, DEFAULT_MAX_MEMORY, "the CCSP outputs"
    )
    (l1, l2), kappa_scale, slow = consider_settings(kappa, scaling, times, update_interval)
    p0 = DEFAULT_INITIAL_COVARIANCE if initial_covariance is None else initial_covariance
    p0 = np.array(p0, dtype=float)
    if p0.shape != (6, 6):
        raise ValueError(f"initial_covariance must have shape (6, 6), got {p0.shape}")
    args = _Arguments(
        epoch=ut1_seconds(state.epoch),
        p0=p0,
        times=times,
        scaling=(l1, l2),
        step=h,
        floor=_validate.real("floor_altitude", floor_altitude),
        degree=zonal_degree_argument(zonal_degree),
        drag_sigma=drag_sigma_argument(drag_sigma),
        outputs=outputs,
        coordinates=coordinates_argument(coordinates),
        kappa_scale=kappa_scale,
        slow=slow,
    )
    return args, span


def interval_times(duration: DurationLike | None, interval: float) -> tuple[float, np.ndarray]:
    """The span of ``duration`` (s, checked) and update times every ``interval`` s to its
    end, the last at the end (a shorter last interval where they do not divide)."""
    span = span_of(duration, None, "update_times")
    check_steps(span, interval, "update_interval")
    n = int(np.ceil(span / interval * (1 - 1e-12)))
    return span, np.minimum(np.arange(1, n + 1) * interval, span)


def scaling_argument(scaling: object, kappa: KappaProcess | None) -> tuple[float, float] | None:
    """``scaling`` checked: None, or two positive numbers (lambda1 + n, lambda2 + p),
    and then no ``kappa`` (both would set kappa's correlation between updates)."""
    if scaling is None:
        return None
    if kappa is not None:
        raise ValueError(
            "give kappa or scaling, not both: scaling's lambda2 sets the correlation "
            "of kappa between updates, which the kappa process sets too"
        )
    pair = list(scaling) if isinstance(scaling, (tuple, list, np.ndarray)) else []
    if len(pair) != 2:
        raise ValueError(f"scaling must be two numbers, got {scaling!r}")
    return (_validate.positive("scaling[0]", pair[0]), _validate.positive("scaling[1]", pair[1]))


def consider_settings(
    kappa: KappaProcess | None,
    scaling: tuple[float, float] | None,
    update_times: np.ndarray,
    update_interval: float | None,
) -> tuple[tuple[float, float], float, tuple[float, float] | None]:
    """((lambda1 + n, lambda2 + p), kappa_scale, slow) of a run: how the filter stands
    for ``kappa`` (see :func:`ccsp`); slow is (scale, half-life s; inf: constant) of the
    slow density term, else None."""
    pair = scaling_argument(scaling, kappa)
    if pair is not None:
        return pair, 1.0, None
    process = TwoScale() if kappa is None else kappa
    if not isinstance(process, KappaProcess):
        raise TypeError(f"kappa must be a rhoprop.kappa process, got {type(process).__name__}")
    # The nominal update interval: the given one, else the longest spacing of the updates
    # (hourly for the default schedule, whose last interval may be shorter; a revolution
    # for an eccentric orbit's apogee updates).
    spacing = (
        float(update_interval)
        if update_interval is not None
        else float(np.max(np.diff(update_times, prepend=0.0)))
    )
    scale = 1.0
    slow: tuple[float, float] | None = None
    if isinstance(process, PiecewiseConstant):
        if update_interval is not None and abs(process.interval - update_interval) > 1e-9:
            raise ValueError(
                f"kappa = {process!r} holds kappa over {process.interval:g} s but the "
                f"updates are {update_interval:g} s apart; make them equal"
            )
        c = process.correlation
    elif isinstance(process, GaussMarkov):
        c = 2.0 ** (-spacing / process.half_life)
    elif isinstance(process, TwoScale):
        c = 2.0 ** (-spacing / process.half_life)
        scale = math.sqrt(1.0 - process.slow_fraction)
        if process.slow_fraction > 0:
            slow = (math.sqrt(process.slow_fraction), float(process.slow_half_life))
    elif isinstance(process, Constant):
        c, scale, slow = 1.0 / 3.0, 0.0, (1.0, math.inf)
    else:
        raise ValueError(
            f"the CCSP holds kappa over each update: it stands for a PiecewiseConstant, "
            f"GaussMarkov, TwoScale or Constant process, not {type(process).__name__}"
        )
    if not c > 0:
        raise ValueError(f"kappa's correlation between updates must be > 0, got {c:g}")
    return (3.0, 1.0 / c), scale, slow


def _result(
    state: OrbitState,
    out: _core.CcspOutput,
    drag_sigma: float,
    frame: str = "TEME",
    rot: np.ndarray | None = None,
    given: OrbitState | None = None,
    given_cov: Any = None,
) -> CcspResult:
    """The :class:`CcspResult` of the core's output dict, of a run from ``state`` (in the
    run's axes), its outputs rotated by ``rot`` into ``frame`` (:mod:`.run_frame`); the
    first output is the ``given`` state and covariance as they were given."""
    # The binding reports decay as "decayed_at" (None when the filter ran to the end).
    decayed = out.decayed_at
    mean = run_frame.vectors(rot, out.means)
    cov = run_frame.covariances(rot, out.covariances)
    if rot is not None and given is not None:
        mean[0] = given.state
        cov[0] = DEFAULT_INITIAL_COVARIANCE if given_cov is None else given_cov
    moments = StateMoments(state.epoch, out.times, mean, cov)
    rtn = moments.rtn_covariance
    return CcspResult(
        epoch=state.epoch,
        times=moments.times,
        mean=moments.mean,
        covariance=moments.covariance,
        rtn_covariance=rtn,
        along_track_std=np.sqrt(rtn[:, 1, 1]),
        cross_covariance=run_frame.vectors(rot, out.cross),
        decayed_at=None if decayed is None else float(decayed),
        drag_sigma=drag_sigma,
        drag_cross_covariance=None
        if out.drag_cross is None
        else run_frame.vectors(rot, out.drag_cross),
        element_mean=out.element_means,
        element_covariance=out.element_covariances,
        reference=np.array(state.state, dtype=float),
        frame=frame,
    )


def coordinates_argument(coordinates: object) -> Coordinates:
    """``coordinates`` checked: ``"equinoctial"`` or ``"cartesian"``."""
    for name in COORDINATES:
        if coordinates == name:
            return name
    raise ValueError(
        f"coordinates must be one of {', '.join(map(repr, COORDINATES))}, got {coordinates!r}"
    )


@dataclass(frozen=True)
class CcspRun:
    """One object of :func:`ccsp_many`: the keywords of :func:`ccsp` that differ per
    object. ``state`` (an :class:`OrbitState`, or a (6,) inertial state), ``spacecraft``,
    ``update_times`` (s from the epoch), ``initial_covariance`` (6, 6) or None,
    ``drag_sigma`` (relative sigma of Cd*A/m), the RK8 ``step`` (s, None: the default),
    further ``output_times`` (s) and the ``kappa`` process (None: the default)."""

    state: Any
    spacecraft: Spacecraft
    update_times: npt.ArrayLike
    initial_covariance: npt.ArrayLike | None = None
    drag_sigma: float = 0.0
    step: float | None = None
    output_times: npt.ArrayLike | None = None
    kappa: KappaProcess | None = None


def ccsp_many(
    runs: Sequence[CcspRun],
    model: ModelLike,
    *,
    dynamics: Dynamics | None = None,
    progress: Callable[[int], None] | None = None,
    coordinates: Coordinates = "equinoctial",
    **deprecated: Unpack[LooseFloorAndDegree],
) -> list[CcspResult | Exception]:
    """The CCSP of several objects in one core call (a catalog chunk): each of ``runs``
    (a :class:`CcspRun`) holds the keywords of :func:`ccsp` that differ per object
    (scaling and perturbation are the defaults). Objects
    run in parallel, each object's sigma points in one SIMD batch, and every result
    equals (bit for bit) :func:`ccsp` of that object alone. Objects whose
    core atmosphere differs (a model sampled per object) go in separate calls. Returns,
    per object, its :class:`CcspResult` or the exception its run raised there (not
    raised: the caller decides, e.g. repeats the object with :func:`ccsp`, which widens
    a field an object left). ``progress(updates_done)`` is called about every 50 ms; an
    exception from it stops the call and is raised, as is Ctrl-C. ``coordinates``: as
    in :func:`ccsp`, shared by every object. ``dynamics``: the zonal degree and floor
    altitude every object shares (None: ``Dynamics()``); each run's RK8 step is its own
    ``step``, so ``dynamics.step``, an integrator other than RK8, ``rtol`` and the
    tesseral field or third bodies are refused (ValueError); ``floor_altitude=`` and
    ``zonal_degree=`` are deprecated."""
    coordinates = coordinates_argument(coordinates)
    dyn = deprecated_keywords(
        "ccsp_many", dynamics, deprecated, names=("floor_altitude", "zonal_degree")
    )
    dyn.require_automatic_gravity("ccsp_many")
    dyn.require_integrator("ccsp_many", ("rk8",))
    if dyn.step is not None:
        raise ValueError(
            "ccsp_many(): each run's RK8 step is its CcspRun's own step; leave dynamics.step None"
        )
    floor_altitude, zonal_degree = dyn.floor_altitude, dyn.zonal_degree
    prepared = []
    frames_of: list[tuple[str, np.ndarray | None, OrbitState, Any]] = []
    for k, run in enumerate(runs):
        if not isinstance(run, CcspRun):
            raise TypeError(f"runs[{k}] must be a CcspRun, got {type(run).__name__}")
        given = run.state
        state, cov, rot = (
            run_frame.into_run(given, run.initial_covariance)
            if isinstance(given, OrbitState)
            else (given, run.initial_covariance, None)
        )
        args, span = _arguments(
            state,
            run.spacecraft,
            model,
            None,
            update_interval=None,
            initial_covariance=cov,
            scaling=None,
            step=run.step,
            floor_altitude=floor_altitude,
            update_times=run.update_times,
            zonal_degree=zonal_degree,
            drag_sigma=run.drag_sigma,
            output_times=run.output_times,
            coordinates=coordinates,
            kappa=run.kappa,
        )
        prepared.append((state, run.spacecraft, args, as_atmosphere(model, state, span)))
        frames_of.append((given.frame, rot, given, run.initial_covariance))
    results: list[CcspResult | Exception] = [RuntimeError("not run")] * len(prepared)
    groups: dict[tuple[Any, ...], list[int]] = {}
    for i, (_s, _c, a, atmosphere) in enumerate(prepared):
        # One core call per atmosphere and consider settings (the objects' update
        # spacings set lambda2 for a kappa process).
        groups.setdefault((id(atmosphere), a.scaling, a.kappa_scale, a.slow), []).append(i)
    for members in groups.values():
        atmosphere = prepared[members[0]][3]
        requests = [a.request(s, c) for s, c, a, _ in (prepared[i] for i in members)]
        outs = _core.ccsp_many(atmosphere, requests, progress)
        for i, out in zip(members, outs, strict=True):
            state, _c, a, _atm = prepared[i]
            if isinstance(out, Exception):
                results[i] = out
            else:
                results[i] = _result(state, out, a.drag_sigma, *frames_of[i])
    return results


def update_schedule(
    state: OrbitState, offsets: np.ndarray, interval: float
) -> tuple[np.ndarray, np.ndarray | None]:
    """CCSP ``update_times`` and ``output_times`` (s from the epoch of ``state``) for
    outputs at ``offsets`` (increasing, s; the last is the end).

    A near-circular orbit (or an unbound one) is updated every ``interval`` s and at
    every output. An eccentric one (e >= :data:`APOGEE_UPDATE_ECCENTRICITY`) is updated
    once per revolution, at each apogee, and at the end, with the outputs between them as
    ``output_times`` (moments of the sigma points in flight). Why: sigma points re-drawn
    in Cartesian coordinates near perigee leave the orbit's energy; hourly updates grew
    the along-track sigma of CXO (e = 0.90) tenfold in 5 days against a Monte Carlo of
    its initial covariance and brought sigma points of 12-hour Molniya orbits down from
    1,500-2,500 km perigees (docs/catalog-realism.md, "Eccentric orbits"). Drag, where it
    matters, acts near perigee: one kappa per perigee pass. An apogee within 1 s of the
    epoch or the end is dropped, one within 1 s of an output moves onto it."""
    a, e = axis_and_eccentricity(state)
    end = float(offsets[-1])
    bound = np.isfinite(a) and 0.0 < a and e < 1.0
    if e < APOGEE_UPDATE_ECCENTRICITY or not bound or end <= 0.0:
        return _every(offsets, interval), None
    period = orbital_period(state)
    first = ((np.pi - mean_anomaly(state)) % (2.0 * np.pi)) / (2.0 * np.pi) * period
    apogees = first + period * np.arange(max(int(np.ceil((end - first) / period)), 0))
    outputs = offsets[(offsets > 0.0) & (offsets < end)]
    apogees = apogees[(apogees >= 1.0) & (apogees <= end - 1.0)]
    if len(outputs) and len(apogees):
        nearest = np.abs(apogees[:, None] - outputs[None, :]).argmin(axis=1)
        close = np.abs(apogees - outputs[nearest]) < 1.0
        apogees = np.unique(np.where(close, outputs[nearest], apogees))
    updates = np.append(apogees, end)
    outputs = np.setdiff1d(outputs, updates)
    return updates, outputs if len(outputs) else None


def _every(offsets: np.ndarray, interval: float) -> np.ndarray:
    """CCSP update times: every ``interval`` s, plus every output offset (> 0)."""
    if offsets[-1] / interval > MAX_STEPS:
        raise ValueError(
            f"update_interval = {interval:g} s gives {offsets[-1] / interval:.3g} updates over "
            f"{offsets[-1]:g} s, more than the {MAX_STEPS:,} a run may take; use a larger "
            "update_interval"
        )
    grid = np.arange(interval, offsets[-1], interval)
    times = np.unique(np.concatenate([grid, offsets[offsets > 0]]))
    return times if len(times) else np.array([offsets[-1]])
