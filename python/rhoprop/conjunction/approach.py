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

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import _validate, frames
from ..density.model import ModelLike
from ..propagation import Spacecraft, Trajectory
from ..propagation.dynamics import Dynamics, LooseFloorAndDegree, deprecated_keywords
from ..propagation.propagate import check_model
from ..time import add_seconds, to_seconds

if TYPE_CHECKING:
    from typing_extensions import Unpack

from .kernel import (
    CloseApproach,
    SampledTrack,
    TrackDynamics,
    dedupe,
    hermite,
    make_event,
    merge_brackets,
    models_for,
    refine,
)

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
    dynamics: Dynamics | None = None,
    **deprecated: Unpack[LooseFloorAndDegree],
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
        dynamics: the :class:`~rhoprop.Dynamics` the trajectories were propagated with
            (its ``floor_altitude``, ``zonal_degree``, ``field_degree`` and
            ``third_bodies``, e.g. :meth:`~rhoprop.Dynamics.precise`), which the
            refinement uses with its ``integrator``, ``step`` and ``rtol`` (as
            ``propagate`` does). Default: ``rp.Dynamics()``.
        **deprecated: ``floor_altitude`` and ``zonal_degree`` as keywords of their own
            (folded into ``dynamics`` with a DeprecationWarning; give them there).

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
    settings = deprecated_keywords(
        "closest_approach", dynamics, deprecated, names=("floor_altitude", "zonal_degree")
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
    own1 = SampledTrack(names[0], ids[0], craft1, t1, traj1.positions, traj1.velocities)
    own2 = SampledTrack(names[1], ids[1], craft2, t2, traj2.positions, traj2.velocities)
    on1 = _on_grid(own1, grid)
    on2 = _on_grid(own2, grid)
    brackets = _brackets(on1, on2, grid, samples=16)
    if model is not None and brackets:
        states = [traj1.state_at(0), traj2.state_at(0)]
        # From the earlier start: re-propagation starts at an output at or before a bracket.
        window = (add_seconds(ref, min(t1[0], t2[0])), add_seconds(ref, last, round_up=True))
        own1.model, own2.model = models_for(model, states, *window, floor)
    dyn = TrackDynamics(ref, model is not None, settings, step, traj1.frame)
    found: list[tuple[float, np.ndarray, np.ndarray]] = []
    for lo, hi in merge_brackets(brackets):
        if model is None:
            found += refine(dyn, on1, on2, lo, hi, first, last)
        else:
            found += refine(dyn, own1, own2, lo, hi, first, last)
    events = [make_event(dyn, own1, own2, *item) for item in dedupe(found)]
    if limit is not None:
        events = [e for e in events if e.miss_distance <= limit]
    return events


def _on_grid(track: SampledTrack, grid: np.ndarray) -> SampledTrack:
    """``track`` sampled on ``grid`` (exact at its own outputs, cubic Hermite between)."""
    i = np.clip(np.searchsorted(track.t, grid, side="right") - 1, 0, len(track.t) - 2)
    h = track.t[i + 1] - track.t[i]
    s = np.clip((grid - track.t[i]) / h, 0.0, 1.0)
    pos, vel = hermite(track.pos[i], track.vel[i], track.pos[i + 1], track.vel[i + 1], h, s)
    exact = np.isclose(grid, track.t[i], rtol=0, atol=1e-6)
    pos[exact], vel[exact] = track.pos[i][exact], track.vel[i][exact]
    end = np.isclose(grid, track.t[i + 1], rtol=0, atol=1e-6)
    pos[end], vel[end] = track.pos[i + 1][end], track.vel[i + 1][end]
    return SampledTrack(track.name, track.object_id, track.craft, grid, pos, vel)


def _brackets(
    a: SampledTrack, b: SampledTrack, grid: np.ndarray, samples: int, mask: np.ndarray | None = None
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
    p, q = hermite(
        r[k][:, None], v[k][:, None], r[k + 1][:, None], v[k + 1][:, None], h[:, None], s[None]
    )
    f = np.einsum("ksj,ksj->ks", p, q)
    f[:, 0] = np.einsum("kj,kj->k", r[k], v[k])
    f[:, -1] = np.einsum("kj,kj->k", r[k + 1], v[k + 1])
    hit = ((f[:, :-1] < 0) & (f[:, 1:] >= 0)).any(axis=1)
    return [(float(grid[j]), float(grid[j + 1])) for j in k[hit]]


# ---------------------------------------------------------------------------------------
# screen
