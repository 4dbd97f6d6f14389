"""Close approaches between propagated objects: :func:`closest_approach` of two
trajectories, and the event types and refinement that screening shares.

How an event is found (docs/conjunction.md, "Screening"):

1. **Local minima on a common grid.** Both objects are sampled at the same absolute
   times. A close approach is a root of f(t) = r_rel . v_rel going from negative to
   positive (distance shrinking, then growing); sign changes are looked for on the samples
   and on the cubic Hermite interpolant (positions + velocities) between them.
2. **Refinement with real dynamics.** Each bracketing output interval is re-propagated for
   both objects from their output states with ``rp.propagate`` (same density model, drag
   parameter and zonal degree, adaptive DOP853) at a fine output step (1 s by default);
   the root of f is found by bisection on the cubic Hermite interpolant of the fine
   outputs (error ~1e-10 m in LEO at 1 s), and the states at the time of closest approach
   (TCA) are propagated to it exactly from the last fine output before it.

:func:`~rhoprop.conjunction.screening.screen` (module ``screening``) adds prefilters
before this: radial ranges and a coarse-grid distance filter.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol

import numpy as np

from .. import _validate, frames
from ..constants import DEFAULT_FLOOR_ALTITUDE
from ..density import SampledModel
from ..density.model import ModelLike
from ..propagation import OrbitState, Spacecraft, Trajectory, propagate
from ..propagation.dynamics import Dynamics, resolve
from ..propagation.propagate import check_model
from ..time import add_seconds, to_seconds

__all__ = [
    "DEFAULT_FINE_STEP",
    "CloseApproach",
    "closest_approach",
]

#: Output step of the re-propagation over a bracketing interval, s.
DEFAULT_FINE_STEP = 1.0
#: Largest output spacing that :func:`closest_approach` refines by interpolation alone
#: (without ``model``), s: the cubic Hermite error is below 0.1 mm in LEO there.
MAX_INTERPOLATION_SPACING = 10.0
#: Longest bracket re-propagated at once, s (a minimum on a boundary between two is found
#: in one of them and counted once).
MAX_BRACKET = 6 * 3600.0
#: Events closer in time than this are one event (found from two brackets), s.
_SAME_EVENT = 1e-3


@dataclass(frozen=True)
class CloseApproach:
    """A close approach of two objects (a local minimum of their distance).

    Attributes:
        tca: time of closest approach, UTC ``datetime64[ns]``.
        miss_distance: distance at TCA, m.
        relative_speed: |v2 - v1| at TCA, m/s.
        state1, state2: inertial states [x, y, z, vx, vy, vz] of both objects at TCA (6,),
            m and m/s, in ``frame``.
        name1, name2: the objects' names.
        id1, id2: the objects' ids (NORAD catalog numbers for catalog objects), or None.
        edge: ``None`` for a minimum inside the window; ``"start"`` when the distance grows
            from the window's start, ``"end"`` when it still falls at the window's end
            (the closest approach may lie outside the window; ``tca`` is the window's
            start or end). The all-on-all screen reports these.
        within: (first, last) UTC epochs around ``tca`` between which the two stay
            within the screening distance (:func:`screen_all`; None from the pairwise
            functions). A fast encounter passes in a second or two; co-orbiting objects
            can stay within it for hours or the whole window (then every minimum in
            that stretch carries the same interval).
        frame: the frame of the states: ``"TEME"`` for screens (they run in the catalogs'
            frame, other states rotated into it), the trajectories' own for
            :func:`closest_approach`.
    """

    tca: np.datetime64
    miss_distance: float
    relative_speed: float
    state1: np.ndarray
    state2: np.ndarray
    name1: str = "object 1"
    name2: str = "object 2"
    id1: int | None = None
    id2: int | None = None
    edge: Literal["start", "end"] | None = None
    within: tuple[np.datetime64, np.datetime64] | None = None
    frame: str = "TEME"

    @property
    def within_seconds(self) -> float | None:
        """Length of :attr:`within`, s (None without it)."""
        if self.within is None:
            return None
        return float((self.within[1] - self.within[0]) / np.timedelta64(1, "ns")) * 1e-9

    @property
    def relative_position(self) -> np.ndarray:
        """Position of object 2 relative to object 1 at TCA (3,), m."""
        return np.asarray(self.state2[:3] - self.state1[:3])

    @property
    def relative_velocity(self) -> np.ndarray:
        """Velocity of object 2 relative to object 1 at TCA (3,), m/s."""
        return np.asarray(self.state2[3:] - self.state1[3:])


def _hermite(
    r0: np.ndarray, v0: np.ndarray, r1: np.ndarray, v1: np.ndarray, h: Any, s: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite position and velocity at fractions ``s`` of intervals of length
    ``h`` (s) from end states (..., 3); ``s`` broadcasts against the leading axes."""
    s = np.asarray(s, dtype=float)[..., None]
    hh = np.asarray(h, dtype=float)[..., None]
    s2, s3 = s * s, s * s * s
    pos = (
        (2 * s3 - 3 * s2 + 1) * r0
        + (s3 - 2 * s2 + s) * hh * v0
        + (-2 * s3 + 3 * s2) * r1
        + (s3 - s2) * hh * v1
    )
    vel = (
        (6 * s2 - 6 * s) * r0 / hh
        + (3 * s2 - 4 * s + 1) * v0
        + (-6 * s2 + 6 * s) * r1 / hh
        + (3 * s2 - 2 * s) * v1
    )
    return pos, vel


def _root_in_interval(
    r0: np.ndarray, v0: np.ndarray, r1: np.ndarray, v1: np.ndarray, h: float
) -> float:
    """Fraction s in [0, 1] of the interval where f = r . v of the cubic Hermite relative
    motion changes sign from negative to non-negative (bisection to 1e-14)."""
    lo, hi = 0.0, 1.0
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        p, v = _hermite(r0, v0, r1, v1, h, mid)
        if float(p @ v) < 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@dataclass
class _Track:
    """One object's samples on times ``t`` (s from the reference epoch)."""

    name: str
    object_id: int | None
    craft: Spacecraft | None
    t: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    model: Any = None


@dataclass
class _Dynamics:
    """What re-propagation needs: the reference epoch, whether to re-propagate at all
    (False: interpolation only), the checked :class:`Dynamics` (every setting of it goes
    to ``propagate``: zonal degree, floor, integrator, step, rtol and, for
    closest_approach, the field and third bodies; screens run the automatic terms) and
    the fine output step. Each track carries its own spacecraft and density model (or
    field)."""

    ref: np.datetime64
    propagates: bool
    settings: Dynamics
    fine_step: float
    #: The frame of the tracks' states (a screen's are TEME).
    frame: str = "TEME"

    @property
    def floor(self) -> float:
        """The floor altitude, m."""
        return self.settings.floor_altitude

    @property
    def degree(self) -> int:
        """The zonal degree."""
        return self.settings.zonal_degree

    def run(
        self, track: _Track, t0: float, state: np.ndarray, span: float, step: float | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Times (s from ``ref``), positions and velocities of ``track``'s object from
        ``state`` at ``t0`` over ``span`` s (outputs every ``step`` s, or the end only)."""
        if track.craft is None or track.model is None:
            raise AssertionError("re-propagation without a model")  # guarded by callers
        s0 = OrbitState(add_seconds(self.ref, t0), state[:3], state[3:], self.frame)
        tr = self.forward(s0, track.craft, track.model, span, step)
        return t0 + tr.times, tr.positions, tr.velocities

    def forward(
        self,
        state: OrbitState,
        craft: Spacecraft,
        model: ModelLike,
        span: float,
        step: float | None,
    ) -> Trajectory:
        """``propagate`` of ``state`` over ``span`` s with these dynamics (outputs every
        ``step`` s, or the end only)."""
        return propagate(state, craft, model, span, output_step=step, dynamics=self.settings)

    def state_at(self, track: _Track, t: float) -> np.ndarray | None:
        """The exact state of ``track`` at ``t``: a sample, or propagated from the last
        sample before it (None if the object decayed before ``t``)."""
        i = int(np.searchsorted(track.t, t + 1e-9, side="right")) - 1
        i = max(i, 0)
        base = np.concatenate([track.pos[i], track.vel[i]])
        dt = t - float(track.t[i])
        if abs(dt) <= 1e-9:
            return base
        times, p, v = self.run(track, float(track.t[i]), base, dt, None)
        if times[-1] < t - 1e-9:
            return None
        return np.concatenate([p[-1], v[-1]])


def _fine_pair(
    dyn: _Dynamics, a: _Track, b: _Track, lo: float, hi: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """Both objects on a common fine grid over [lo, hi]: times, positions and velocities
    of a and b (re-propagated), or their own samples when interpolating only."""
    if not dyn.propagates:
        ka = (a.t >= lo - 1e-9) & (a.t <= hi + 1e-9)
        return a.t[ka], a.pos[ka], a.vel[ka], b.pos[ka], b.vel[ka]
    sa, sb = dyn.state_at(a, lo), dyn.state_at(b, lo)
    if sa is None or sb is None:
        return None
    ta, pa, va = dyn.run(a, lo, sa, hi - lo, dyn.fine_step)
    tb, pb, vb = dyn.run(b, lo, sb, hi - lo, dyn.fine_step)
    n = min(len(ta), len(tb))
    return ta[:n], pa[:n], va[:n], pb[:n], vb[:n]


def _refine(
    dyn: _Dynamics, a: _Track, b: _Track, lo: float, hi: float, first: float, last: float
) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """Close approaches (TCA s from ``ref``, state of a, state of b) in [lo, hi], from a
    fine re-propagation of both objects; when the bracket (from interpolated coarse
    outputs) holds no minimum but the distance still shrinks at an end, it moves one
    width that way, at most three times, staying inside [first, last]."""
    width = hi - lo
    found: list[tuple[float, np.ndarray, np.ndarray]] = []
    for _ in range(4):
        fine = _fine_pair(dyn, a, b, lo, hi)
        if fine is None or len(fine[0]) < 2:
            return found
        t, pa, va, pb, vb = fine
        r, v = pb - pa, vb - va
        f = np.einsum("ij,ij->i", r, v)
        idx = np.flatnonzero((f[:-1] < 0) & (f[1:] >= 0))
        if len(idx):
            break
        if f[0] >= 0 and lo > first + 1e-9:
            lo, hi = max(first, lo - width), lo
        elif f[-1] < 0 and hi < last - 1e-9 and len(t) and t[-1] >= hi - 1e-9:
            lo, hi = hi, min(last, hi + width)
        else:
            return found
    else:
        return found
    for i in idx:
        h = float(t[i + 1] - t[i])
        s = _root_in_interval(r[i], v[i], r[i + 1], v[i + 1], h)
        tca = float(t[i]) + s * h
        if not dyn.propagates:
            p1, v1 = _hermite(pa[i], va[i], pa[i + 1], va[i + 1], h, s)
            p2, v2 = _hermite(pb[i], vb[i], pb[i + 1], vb[i + 1], h, s)
            found.append((tca, np.concatenate([p1, v1]), np.concatenate([p2, v2])))
            continue
        fine_a = _Track(a.name, a.object_id, a.craft, t, pa, va, a.model)
        fine_b = _Track(b.name, b.object_id, b.craft, t, pb, vb, b.model)
        s1, s2 = dyn.state_at(fine_a, tca), dyn.state_at(fine_b, tca)
        if s1 is not None and s2 is not None:
            found.append((tca, s1, s2))
    return found


class _Named(Protocol):
    """What an event takes from each object: its name and id."""

    name: str
    object_id: int | None


def _event(
    dyn: _Dynamics,
    a: _Named,
    b: _Named,
    tca: float,
    s1: np.ndarray,
    s2: np.ndarray,
    edge: Literal["start", "end"] | None = None,
) -> CloseApproach:
    rel = s2 - s1
    s1.flags.writeable = False
    s2.flags.writeable = False
    return CloseApproach(
        tca=add_seconds(dyn.ref, tca),
        miss_distance=float(np.linalg.norm(rel[:3])),
        relative_speed=float(np.linalg.norm(rel[3:])),
        state1=s1,
        state2=s2,
        name1=a.name,
        name2=b.name,
        id1=a.object_id,
        id2=b.object_id,
        edge=edge,
        frame=dyn.frame,
    )


def _merge(brackets: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
    """Overlapping or touching [lo, hi] brackets merged, in order, each at most
    :data:`MAX_BRACKET` s long (objects that stay close all along, such as vehicles docked
    to a station, would otherwise make one bracket of the whole window)."""
    out: list[tuple[float, float]] = []
    for lo, hi in sorted(brackets):
        if out and lo <= out[-1][1] + 1e-9 and hi - out[-1][0] <= MAX_BRACKET:
            out[-1] = (out[-1][0], max(out[-1][1], hi))
        else:
            out.append((lo, hi))
    return out


def _dedupe(found: list[tuple[float, np.ndarray, np.ndarray]]) -> list[Any]:
    out: list[tuple[float, np.ndarray, np.ndarray]] = []
    for item in sorted(found, key=lambda x: x[0]):
        if out and item[0] - out[-1][0] < _SAME_EVENT:
            continue
        out.append(item)
    return out


# ---------------------------------------------------------------------------------------
# closest_approach


def _spacecraft_pair(spacecraft: Any) -> tuple[Spacecraft | None, Spacecraft | None]:
    if spacecraft is None:
        return None, None
    if isinstance(spacecraft, Spacecraft):
        return spacecraft, spacecraft
    try:
        first, second = spacecraft
    except (TypeError, ValueError) as err:
        raise TypeError(
            "spacecraft must be a Spacecraft (both objects) or a pair of them, got "
            f"{type(spacecraft).__name__}"
        ) from err
    for k, c in enumerate((first, second), start=1):
        if not isinstance(c, Spacecraft):
            raise TypeError(f"spacecraft[{k - 1}] must be a Spacecraft, got {type(c).__name__}")
    return first, second


def _models_for(
    model: Any, states: Sequence[OrbitState], start: Any, end: Any, floor: float
) -> list[Any]:
    """The model to propagate each of ``states`` with over [start, end]: a sampled model's
    atlas (day tiles over every altitude, extrapolated above the ceiling, so LEO, HEO and
    GEO objects share it) or the model as it is."""
    return [model.atlas if isinstance(model, SampledModel) else model] * len(states)


def event_columns(events: Sequence[CloseApproach]) -> dict[str, np.ndarray]:
    """The events as columns, one row per event in order: ``name1``, ``id1``, ``name2``,
    ``id2`` (-1 for no id), ``tca`` (datetime64[ns] UTC), ``miss_distance`` m,
    ``relative_speed`` m/s, ``edge`` ("start" / "end" for a minimum at the window's
    start / end, else "") and ``within_start`` / ``within_end`` (UTC, NaT without)."""
    nat = np.datetime64("NaT")
    return {
        "name1": np.array([e.name1 for e in events], dtype=object),
        "id1": np.array([-1 if e.id1 is None else e.id1 for e in events], dtype=np.int64),
        "name2": np.array([e.name2 for e in events], dtype=object),
        "id2": np.array([-1 if e.id2 is None else e.id2 for e in events], dtype=np.int64),
        "tca": np.array([e.tca for e in events], dtype="datetime64[ns]"),
        "miss_distance": np.array([e.miss_distance for e in events], dtype=float),
        "relative_speed": np.array([e.relative_speed for e in events], dtype=float),
        "edge": np.array(["" if e.edge is None else e.edge for e in events], dtype=object),
        "within_start": np.array(
            [nat if e.within is None else e.within[0] for e in events], dtype="datetime64[ns]"
        ),
        "within_end": np.array(
            [nat if e.within is None else e.within[1] for e in events], dtype="datetime64[ns]"
        ),
    }


def closest_approach(
    traj1: Trajectory,
    traj2: Trajectory,
    *,
    model: ModelLike | None = None,
    spacecraft: Spacecraft | tuple[Spacecraft, Spacecraft] | None = None,
    names: tuple[str, str] = ("object 1", "object 2"),
    ids: tuple[int | None, int | None] = (None, None),
    max_distance: float | None = None,
    fine_step: float = DEFAULT_FINE_STEP,
    floor_altitude: float = DEFAULT_FLOOR_ALTITUDE,
    zonal_degree: int = 2,
    dynamics: Dynamics | None = None,
) -> list[CloseApproach]:
    """Close approaches of two trajectories: every local minimum of their distance over
    the absolute times both cover, with the time of closest approach refined to well under
    1 ms by re-propagating both objects over the bracketing output interval.

    The trajectories may start at different epochs and have different output grids: both
    are sampled on the union of their output times within the common span (each exact at
    its own outputs, cubic Hermite at the other's), minima are bracketed there (sign
    changes of r_rel . v_rel on the samples and on the Hermite interpolant), and each
    bracketing interval is re-propagated for both objects from their own outputs with
    ``rp.propagate`` (adaptive DOP853) at ``fine_step``. The outputs must resolve the
    relative motion (a spacing up to ~1/20 of an orbit, 300 s in LEO, is safe): minima
    that leave no trace on the grid or its interpolant are not found.

    Args:
        traj1, traj2: :class:`~rhoprop.Trajectory` objects (e.g. from ``rp.propagate``).
        model: the density model the trajectories were propagated with (for a sampled
            model, one field is sampled for the common span). None: no re-propagation;
            allowed only for outputs at most :data:`MAX_INTERPOLATION_SPACING` s apart,
            refined by cubic Hermite interpolation of the outputs themselves.
        spacecraft: the :class:`~rhoprop.Spacecraft` of both objects, or a pair; required
            with ``model``.
        names, ids: names and ids of the two objects, carried into the events.
        max_distance: keep only approaches at most this far, m (None: all minima).
        fine_step: output step of the re-propagation, s (default 1 s).
        floor_altitude, zonal_degree: as the trajectories were propagated with.
        dynamics: a :class:`~rhoprop.Dynamics` holding ``floor_altitude`` and
            ``zonal_degree`` at once (then leave those keywords at their defaults), and
            the ``field_degree`` and ``third_bodies`` the trajectories were propagated
            with (e.g. :meth:`~rhoprop.Dynamics.precise`), which the refinement uses
            with its ``integrator``, ``step`` and ``rtol`` (as ``propagate`` does).

    Returns:
        The :class:`CloseApproach` events sorted by TCA (object 1 = ``traj1``), states at
        TCA propagated to it exactly. Decayed trajectories are used up to their last
        output.

    Raises:
        TypeError: arguments of the wrong type.
        ValueError: trajectories that share no time span or have fewer than two outputs
            in it, outputs too far apart to interpolate without ``model``, bad numbers.
    """
    for k, tr in enumerate((traj1, traj2), start=1):
        if not isinstance(tr, Trajectory):
            raise TypeError(f"traj{k} must be a rhoprop Trajectory, got {type(tr).__name__}")
        if len(tr.times) < 2:
            raise ValueError(f"traj{k} has {len(tr.times)} output(s); at least two are needed")
    if not frames.same_axes(traj1.frame, traj2.frame):
        raise ValueError(
            f"traj1 is in {traj1.frame} and traj2 in {traj2.frame}: propagate both from "
            "states in one frame (OrbitState.in_frame)"
        )
    craft1, craft2 = _spacecraft_pair(spacecraft)
    if model is not None:
        check_model(model)
        if craft1 is None or craft2 is None:
            raise TypeError(
                "closest_approach(model=...) re-propagates both objects and needs their "
                "spacecraft: pass spacecraft=Spacecraft(...) or a pair of them"
            )
    step = _validate.positive("fine_step", fine_step)
    limit = None if max_distance is None else _validate.positive("max_distance", max_distance)
    settings = resolve(
        "closest_approach",
        dynamics,
        Dynamics(),
        floor_altitude=floor_altitude,
        zonal_degree=zonal_degree,
    )
    floor = settings.floor_altitude
    ref = traj1.epoch
    t1 = to_seconds(traj1.epochs, ref)
    t2 = to_seconds(traj2.epochs, ref)
    first, last = max(t1[0], t2[0]), min(t1[-1], t2[-1])
    if not last > first:
        raise ValueError(
            "the trajectories share no time span: "
            f"{traj1.epochs[0]}..{traj1.epochs[-1]} and {traj2.epochs[0]}..{traj2.epochs[-1]}"
        )
    grid = np.union1d(t1[(t1 >= first) & (t1 <= last)], t2[(t2 >= first) & (t2 <= last)])
    grid = np.unique(np.concatenate([[first], grid, [last]]))
    # Times within a microsecond are one sample.
    grid = grid[np.concatenate([[True], np.diff(grid) > 1e-6])]
    if len(grid) < 2:
        raise ValueError("the trajectories have fewer than two outputs in their common span")
    # Each trajectory's own output spacing over the common span.
    spacing = max(
        float(np.max(np.diff(t[max(0, lo - 1) : hi + 1]), initial=0.0))
        for t, lo, hi in (
            (t1, int(np.searchsorted(t1, first)), int(np.searchsorted(t1, last))),
            (t2, int(np.searchsorted(t2, first)), int(np.searchsorted(t2, last))),
        )
    )
    if model is None and spacing > MAX_INTERPOLATION_SPACING:
        raise ValueError(
            f"outputs up to {spacing:g} s apart are too coarse to refine by interpolation "
            f"alone (at most {MAX_INTERPOLATION_SPACING:g} s): pass model=... and "
            "spacecraft=... so the bracketing intervals are re-propagated"
        )
    own1 = _Track(names[0], ids[0], craft1, t1, traj1.positions, traj1.velocities)
    own2 = _Track(names[1], ids[1], craft2, t2, traj2.positions, traj2.velocities)
    on1 = _on_grid(own1, grid)
    on2 = _on_grid(own2, grid)
    brackets = _brackets(on1, on2, grid, samples=16)
    if model is not None and brackets:
        states = [traj1.state_at(0), traj2.state_at(0)]
        # From the earlier start: re-propagation starts at an output at or before a bracket.
        window = (add_seconds(ref, min(t1[0], t2[0])), add_seconds(ref, last, round_up=True))
        own1.model, own2.model = _models_for(model, states, *window, floor)
    dyn = _Dynamics(ref, model is not None, settings, step, traj1.frame)
    found: list[tuple[float, np.ndarray, np.ndarray]] = []
    for lo, hi in _merge(brackets):
        if model is None:
            found += _refine(dyn, on1, on2, lo, hi, first, last)
        else:
            found += _refine(dyn, own1, own2, lo, hi, first, last)
    events = [_event(dyn, own1, own2, *item) for item in _dedupe(found)]
    if limit is not None:
        events = [e for e in events if e.miss_distance <= limit]
    return events


def _on_grid(track: _Track, grid: np.ndarray) -> _Track:
    """``track`` sampled on ``grid`` (exact at its own outputs, cubic Hermite between)."""
    i = np.clip(np.searchsorted(track.t, grid, side="right") - 1, 0, len(track.t) - 2)
    h = track.t[i + 1] - track.t[i]
    s = np.clip((grid - track.t[i]) / h, 0.0, 1.0)
    pos, vel = _hermite(track.pos[i], track.vel[i], track.pos[i + 1], track.vel[i + 1], h, s)
    exact = np.isclose(grid, track.t[i], rtol=0, atol=1e-6)
    pos[exact], vel[exact] = track.pos[i][exact], track.vel[i][exact]
    end = np.isclose(grid, track.t[i + 1], rtol=0, atol=1e-6)
    pos[end], vel[end] = track.pos[i + 1][end], track.vel[i + 1][end]
    return _Track(track.name, track.object_id, track.craft, grid, pos, vel)


def _brackets(
    a: _Track, b: _Track, grid: np.ndarray, samples: int, mask: np.ndarray | None = None
) -> list[tuple[float, float]]:
    """Grid intervals (of those in ``mask``) where f = r_rel . v_rel goes from negative to
    non-negative on the samples or on the cubic Hermite interpolant (``samples``
    sub-samples per interval)."""
    r, v = b.pos - a.pos, b.vel - a.vel
    k = np.arange(len(grid) - 1) if mask is None else np.flatnonzero(mask)
    if not len(k):
        return []
    s = np.linspace(0.0, 1.0, samples + 1)
    h = grid[k + 1] - grid[k]
    p, q = _hermite(
        r[k][:, None], v[k][:, None], r[k + 1][:, None], v[k + 1][:, None], h[:, None], s[None]
    )
    f = np.einsum("ksj,ksj->ks", p, q)
    f[:, 0] = np.einsum("kj,kj->k", r[k], v[k])
    f[:, -1] = np.einsum("kj,kj->k", r[k + 1], v[k + 1])
    hit = ((f[:, :-1] < 0) & (f[:, 1:] >= 0)).any(axis=1)
    return [(float(grid[j]), float(grid[j + 1])) for j in k[hit]]


# ---------------------------------------------------------------------------------------
# screen
