"""Deterministic propagation of one orbit at the mean density, and the checks every
propagator makes before it calls the core: the model argument, per-method step defaults,
a step fit for the orbit, step and output counts and memory bounded against the span, and
a sampled field widened once when an object comes down through its lower edge."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
import numpy.typing as npt

from .. import _core, _validate
from ..constants import MU
from ..density.atlas import Atlas
from ..density.model import (
    AtmosphereLike,
    CoreAtmosphere,
    ModelLike,
    as_atmosphere,
)
from ..options import Integrator
from ..time import DurationLike, add_seconds, ut1_seconds
from . import run_frame
from .dynamics import Dynamics, LooseDynamics, deprecated_keywords, zonal_degree_argument
from .results import Trajectory, trajectory_from_core
from .state import OrbitState, Spacecraft

if TYPE_CHECKING:
    from typing_extensions import Unpack

T = TypeVar("T")

#: Methods of :func:`propagate` and their default step (s) or tolerance.
METHODS = ("dop853", "rk8", "rk4", "abm")
#: Default largest step of the fixed-step methods, s, for propagate, Monte Carlo and CCSP
#: alike (``step=None``). RK8 at 180 s ends 3 days of the paper's orbit well within 1 m of
#: a tight reference; 180 s divides the 18-min and 180-min kappa intervals. RK4 needs 5 s
#: for the same accuracy. The Adams-Bashforth-Moulton multistep method (``"abm"``, 2
#: evaluations a step, restarted with RK8 at kappa nodes) ends 0.34 m off at 80 s with
#: half RK8's evaluations where the force is smooth for many steps.
DEFAULT_STEP = {"rk8": 180.0, "rk4": 5.0, "abm": 80.0}
#: Default relative tolerance of the adaptive DOP853 (per step, on |r| and |v|).
DEFAULT_RTOL = 1e-10
#: Accepted relative tolerances of DOP853 (a few hundred times float64's epsilon up).
MIN_RTOL, MAX_RTOL = 1e-14, 1e-2
#: A fixed step may be at most this fraction of the orbital period: beyond it a run is
#: meaningless (RK8 at 86400 s ends 3.6e9 m off), so it is refused rather than run.
MAX_STEP_FRACTION = 1.0 / 20.0
#: Most integration steps (or output/update times) one run may take: the core's own limit,
#: checked here before anything is allocated.
MAX_STEPS = _core.MAX_STEPS
#: Default limit on the memory of a run's results, bytes (8 GiB).
DEFAULT_MAX_MEMORY = 8 * 2**30


def output_grid(duration: float, output_step: float | None) -> np.ndarray:
    """Output times 0, step, 2 step, ... and always ``duration`` itself, s. More than
    :data:`MAX_STEPS` outputs is a ValueError (checked before the grid is allocated)."""
    if output_step is None:
        return np.array([0.0, duration])
    step = _validate.positive("output_step", output_step)
    count = duration / step
    if count > MAX_STEPS:
        raise ValueError(
            f"output_step = {step:g} s gives {count:.3g} outputs over {duration:g} s, more "
            f"than the {MAX_STEPS:,} a run may have; use a larger output_step"
        )
    n = int(np.floor(count * (1 + 1e-12)))
    grid = np.arange(n + 1, dtype=float) * step
    if duration - grid[-1] > 1e-9 * max(duration, 1.0):
        grid = np.append(grid, duration)
    else:
        grid[-1] = duration
    return grid


def explicit_times(name: str, values: npt.ArrayLike, *, allow_zero: bool) -> np.ndarray:
    """``values`` as a 1-D float array of finite, strictly increasing times, s (>= 0 when
    ``allow_zero``, else > 0), at most :data:`MAX_STEPS` of them."""
    try:
        times = np.array(values, dtype=float)
    except (TypeError, ValueError) as err:
        raise TypeError(f"{name} must be numbers (s from the epoch), got {values!r}") from err
    if times.ndim != 1 or len(times) == 0:
        raise ValueError(f"{name} must be a non-empty 1-D sequence of times, s")
    if len(times) > MAX_STEPS:
        raise ValueError(f"{name} has {len(times):,} times, more than {MAX_STEPS:,}")
    if not np.isfinite(times).all():
        raise ValueError(f"{name} must be finite, got {times[~np.isfinite(times)][0]}")
    low = times[0] < 0 if allow_zero else times[0] <= 0
    if low or (np.diff(times) <= 0).any():
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must increase strictly from {bound}, got {times[:4]}...")
    if times[-1] <= 0:
        raise ValueError(f"{name} must end after the epoch (last time > 0)")
    return times


def span_of(duration: DurationLike | None, times: np.ndarray | None, name: str) -> float:
    """The run's span, s: ``duration``, or the last of explicit ``times`` (``name``);
    both given must agree (to 1 ns)."""
    if times is None:
        if duration is None:
            raise TypeError("duration is required (a span in s or a timedelta)")
        return _validate.positive("duration", _validate.seconds("duration", duration))
    end = float(times[-1])
    if duration is not None:
        span = _validate.positive("duration", _validate.seconds("duration", duration))
        if abs(span - end) > 1e-9:
            raise ValueError(
                f"duration = {span:g} s disagrees with the last of {name} ({end:g} s); "
                f"give one of them (duration may be left out when {name} is given)"
            )
    return end


def check_model(model: ModelLike) -> None:
    """TypeError unless ``model`` is a density model (or a core atmosphere)."""
    if isinstance(model, CoreAtmosphere) or callable(getattr(model, "atmosphere", None)):
        return
    raise TypeError(
        "model must be a rhoprop density model (e.g. rhoprop.density.Exponential), "
        f"got {type(model).__name__}"
    )


def axis_and_eccentricity(state: OrbitState) -> tuple[float, float]:
    """Osculating two-body semi-major axis (m; inf for an unbound orbit) and eccentricity
    of ``state``."""
    r, v = state.position, state.velocity
    rn = float(np.linalg.norm(r))
    v2 = float(v @ v)
    energy = v2 / 2 - MU / rn
    a = -MU / (2 * energy) if energy < 0 else math.inf
    e = float(np.linalg.norm(((v2 - MU / rn) * r - float(r @ v) * v) / MU))
    return a, e


def mean_anomaly(state: OrbitState) -> float:
    """Osculating mean anomaly of a bound ``state``, rad in (-pi, pi] (ValueError for an
    unbound or circular one)."""
    a, e = axis_and_eccentricity(state)
    if not (math.isfinite(a) and 0.0 < e < 1.0):
        raise ValueError(f"no mean anomaly: semi-major axis {a:g} m, eccentricity {e:g}")
    r, v = state.position, state.velocity
    big_e = math.atan2(float(r @ v) / math.sqrt(MU * a), 1.0 - float(np.linalg.norm(r)) / a)
    return big_e - e * math.sin(big_e)


def orbital_period(state: OrbitState) -> float:
    """Osculating two-body period of ``state``, s (inf for an unbound orbit)."""
    r = float(np.linalg.norm(state.position))
    v2 = float(state.velocity @ state.velocity)
    inverse_a = 2.0 / r - v2 / MU
    if inverse_a <= 0:
        return math.inf
    return 2.0 * math.pi * math.sqrt(inverse_a**-3 / MU)


def fixed_step(method: str, step: float | None, state: OrbitState) -> float:
    """The step of a fixed-step ``method`` (``"rk8"``/``"rk4"``/``"abm"``): ``step`` or the
    method's default; a step over :data:`MAX_STEP_FRACTION` of the orbital period is a
    ValueError naming both."""
    h = DEFAULT_STEP[method] if step is None else _validate.positive("step", step)
    period = orbital_period(state)
    if h > MAX_STEP_FRACTION * period:
        raise ValueError(
            f"step = {h:g} s is too large for this orbit: its period is {period:.0f} s and "
            f"a fixed step may be at most 1/{round(1 / MAX_STEP_FRACTION)} of it "
            f"({MAX_STEP_FRACTION * period:.0f} s); the {method} default is "
            f"{DEFAULT_STEP[method]:g} s"
        )
    return h


def check_steps(span: float, spacing: float, name: str) -> None:
    """ValueError if ``span`` s cut at ``spacing`` s (the argument ``name``) needs more
    than :data:`MAX_STEPS` steps."""
    count = span / spacing
    if count > MAX_STEPS:
        raise ValueError(
            f"{name} = {spacing:g} s gives {count:.3g} steps over {span:g} s, more than the "
            f"{MAX_STEPS:,} a run may take; use a larger {name}"
        )


def check_memory(estimate: float, limit: float, what: str) -> None:
    """ValueError if the ``estimate`` (bytes) of a run's results exceeds ``limit``."""
    if estimate > limit:
        raise ValueError(
            f"{what} would need about {estimate / 2**30:.3g} GiB, over the limit of "
            f"{limit / 2**30:.3g} GiB (max_memory); use fewer members or outputs, or raise "
            "max_memory"
        )


def core_propagate(
    atmosphere: AtmosphereLike,
    state: OrbitState,
    drag_parameter: float,
    times: np.ndarray,
    *,
    integrator: str,
    step: float | None,
    floor_altitude: float,
    zonal_degree: int,
    rtol: float | None = None,
    forces: tuple[int | None, bool | None, float] = (None, None, 0.0),
) -> tuple[np.ndarray, np.ndarray, float | None, int, int]:
    """The one call of ``_core.propagate``: ``state`` through ``atmosphere`` to ``times``
    (s from its epoch, increasing from 0, or decreasing for a backward run) with Cd*A/m
    ``drag_parameter`` (m^2/kg); returns (times, states, decayed_at, RHS evaluations,
    clipped evaluations), the states in ``state.frame`` (:mod:`.run_frame`). ``forces``:
    :meth:`Dynamics.forces`."""
    inside, _cov, rot = run_frame.into_run(state)
    problem = core_problem(inside, drag_parameter, floor_altitude, zonal_degree, forces)
    out = _core.propagate(atmosphere, problem, times, integrator, step, rtol)
    t = out.times
    states = run_frame.vectors(rot, out.states)
    if rot is not None and len(t) and t[0] == 0.0:
        states[0] = state.state  # the initial state as given, not rotated there and back
    return t, states, out.decayed_at, out.rhs_evaluations, out.clipped


def core_problem(
    state: OrbitState,
    drag_parameter: float,
    floor_altitude: float,
    zonal_degree: int,
    forces: tuple[int | None, bool | None, float] = (None, None, 0.0),
) -> _core.Problem:
    """The core's record of the problem every run shares: ``state`` (in the run's axes,
    :mod:`.run_frame`) at its epoch, Cd*A/m ``drag_parameter`` (m^2/kg), the floor
    altitude (m), the zonal degree and the other ``forces``
    (:meth:`Dynamics.forces`), checked by the core when made."""
    return _core.Problem(
        epoch=ut1_seconds(state.epoch),
        state=state.state,
        drag=drag_parameter,
        floor_altitude=floor_altitude,
        zonal_degree=zonal_degree,
        forces=forces,
    )


def run_in_field(
    model: ModelLike, state: OrbitState, span: float, floor: float, run: Callable[[Any], T]
) -> T:
    """``run(atmosphere)`` with the core atmosphere of ``model`` for ``span`` s from
    ``state`` (negative: backwards). A sampled model's atmosphere is the field of its
    atlas's day tiles over the span, every altitude from the model's lowest one up
    (:mod:`rhoprop.density.atlas`), so an object that comes down reaches the floor inside
    the field and is reported as decayed. A decay ``floor`` (m) below the atlas's lowest
    altitude is a ValueError: the field holds its bottom level below it."""
    check_model(model)
    try:
        add_seconds(state.epoch, span)  # results carry datetime64[ns] epochs
    except ValueError as err:
        raise ValueError(
            f"a run of {span:g} s from {state.epoch} would end outside the epochs rhoprop "
            f"can represent ({err})"
        ) from None
    served = getattr(model, "served_by", None)  # a sampled model, or a wrapper of one
    atlas = served() if callable(served) else model
    if isinstance(atlas, Atlas) and floor < atlas.altitude[0]:
        raise ValueError(
            f"floor_altitude = {floor:g} m is below {atlas.model!r}'s lowest altitude "
            f"({atlas.altitude[0]:g} m); raise the floor or use a model defined lower"
        )
    return run(as_atmosphere(model, state, span))


def model_argument(model: ModelLike | None, density: ModelLike | None, function: str) -> ModelLike:
    """The model of a call that may still use the deprecated keyword ``density``."""
    if density is None:
        if model is None:
            raise TypeError(f"{function}() missing required argument: 'model'")
        return model
    warnings.warn(
        f"{function}(density=...) is deprecated; the argument is called model",
        DeprecationWarning,
        stacklevel=3,
    )
    if model is not None:
        raise TypeError(f"{function}() got both model and density; give model only")
    return density


class PropagateKeywords(LooseDynamics, total=False):
    """The deprecated keywords of :func:`propagate`: the loose :class:`Dynamics`
    attributes, ``method`` (an older name of ``integrator``) and ``density`` (of
    ``model``)."""

    method: Integrator
    density: ModelLike


def propagate(
    state: OrbitState,
    spacecraft: Spacecraft,
    model: ModelLike | None = None,
    duration: DurationLike | None = None,
    *,
    output_step: float | None = None,
    dynamics: Dynamics | None = None,
    **deprecated: Unpack[PropagateKeywords],
) -> Trajectory:
    """Propagates one orbit with two-body + J2 (optionally up to J6) + drag at the mean
    density; a deep-space orbit (period of 225 min or more) also feels the Sun, the Moon
    and the tesseral field to degree 8 (docs/conventions.md, "Frames and dynamics").

    Args:
        state: initial :class:`OrbitState`.
        spacecraft: :class:`Spacecraft` (Cd and A/m, m^2/kg; with ``cr`` the Sun's
            radiation pressure acts too).
        model: a density model, e.g. :class:`rhoprop.density.Exponential` (the same name
            as in :func:`monte_carlo` and :func:`ccsp`; ``density=`` is a deprecated alias).
        duration: propagation span, s (> 0), or a ``timedelta``.
        output_step: spacing of the outputs, s; None gives the start and end only. The end
            is always an output.
        dynamics: :class:`~rhoprop.Dynamics`: the integrator (``"dop853"``, adaptive with
            dense output, the default; ``"rk8"``, ``"rk4"`` or ``"abm"``, fixed step),
            its ``step`` (s; for DOP853 an optional largest step) and ``rtol`` (DOP853's,
            default 1e-10), the zonal degree (2: J2 only, the paper's model; up to 6) and
            the floor altitude (m). None: ``Dynamics()``.
        **deprecated: ``integrator=``, ``rtol=``, ``step=``, ``floor_altitude=``,
            ``zonal_degree=`` (and ``method=``, an older name of ``integrator``), folded
            into ``dynamics`` with a DeprecationWarning; ``density=``, an older name of
            ``model``.

    Returns:
        :class:`Trajectory` at the output times (shorter if the object decayed; its
        ``decayed_at`` then says when). Ctrl-C stops the run with KeyboardInterrupt.

    Example:
        >>> import rhoprop as rp
        >>> s = rp.OrbitState("2002-09-07T01:00Z", [3782900.7, -5441600.7, -1420075.1],
        ...                   [-606.66, 1539.2559, -7488.3946])
        >>> tr = rp.propagate(s, rp.Spacecraft(3.0912, 0.0015),
        ...                   rp.density.Exponential(3.725e-12, 400e3, 58.515e3), 86400.0)
        >>> tr.positions.shape
        (2, 3)
    """
    loose = dict(deprecated)
    model = model_argument(model, loose.pop("density", None), "propagate")  # type: ignore[arg-type]
    if not isinstance(state, OrbitState):
        raise TypeError(f"state must be an OrbitState, got {type(state).__name__}")
    if not isinstance(spacecraft, Spacecraft):
        raise TypeError(f"spacecraft must be a Spacecraft, got {type(spacecraft).__name__}")
    check_model(model)
    dyn = deprecated_keywords("propagate", dynamics, loose, aliases={"method": "integrator"})
    method = dyn.integrator or "dop853"
    step, rtol, floor_altitude, zonal_degree = (
        dyn.step,
        dyn.rtol,
        dyn.floor_altitude,
        dyn.zonal_degree,
    )
    span = span_of(duration, None, "")
    if rtol is not None:
        rtol = _validate.positive("rtol", rtol)
        if method != "dop853":
            raise ValueError(f"rtol applies to integrator 'dop853' only, not {method!r}")
        if not MIN_RTOL <= rtol <= MAX_RTOL:
            raise ValueError(
                f"rtol = {rtol:g} is outside [{MIN_RTOL:g}, {MAX_RTOL:g}]: below, float64 "
                "rounding (2.2e-16 per operation) is larger than the error asked for and "
                "the step shrinks without end; above, the solution has no digits"
            )
    if method in DEFAULT_STEP:
        step = fixed_step(method, step, state)
        check_steps(span, step, "step")
    elif step is not None:
        step = _validate.positive("step", step)
    floor = _validate.real("floor_altitude", floor_altitude)
    degree = zonal_degree_argument(zonal_degree)
    times = output_grid(span, output_step)
    tol = DEFAULT_RTOL if rtol is None and method == "dop853" else rtol

    def run(atmosphere: AtmosphereLike) -> tuple[Any, ...]:
        return core_propagate(
            atmosphere,
            state,
            spacecraft.drag_parameter,
            times,
            integrator=method,
            step=step,
            rtol=tol,
            floor_altitude=floor,
            zonal_degree=degree,
            forces=dyn.forces(spacecraft.radiation_parameter),
        )

    out = run_in_field(model, state, span, floor, run)
    return trajectory_from_core(state.epoch, out, state.frame)
