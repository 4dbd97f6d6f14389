"""Screening one primary against many secondaries (:func:`screen`): radial
(perigee/apogee) ranges padded for the zonal-harmonic oscillation and drag decay over the
span, then a coarse-grid distance filter whose margin bounds the distance travelled
between samples (relative speed x half the spacing), so that no approach closer than
``distance`` is lost between samples; the survivors' brackets are refined as in
:mod:`.approach` (docs/conjunction.md, "Screening")."""

from __future__ import annotations

import enum
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._deprecated import fold_keywords
from ..catalog.elements import CatalogObject
from ..catalog.run import beyond_max_span
from ..constants import J2, MU, R_EARTH, R_POLE
from ..density.model import ModelLike
from ..errors import DecayError
from ..execution import Execution, execution_argument
from ..options import Errors
from ..parallel import map_in_threads, worker_count
from ..progress import ProgressBar
from ..propagation import OrbitState, Spacecraft
from ..propagation.dynamics import Dynamics, LooseFloorAndDegree, deprecated_keywords
from ..propagation.propagate import (
    check_model,
)
from ..propagation.results import optional_import
from ..time import EpochLike, add_seconds, seconds_between, to_seconds
from .approach import event_columns
from .kernel import (
    CloseApproach,
    SampledTrack,
    ScreenedObject,
    TrackDynamics,
    Window,
    as_object,
    coarse_track,
    dedupe,
    drag_decay,
    hermite,
    make_event,
    make_window,
    merge_brackets,
    models_for,
    object_error,
    radial_ranges,
    refine,
    secondaries_list,
)
from .settings import DEFAULT_GRID_STEP, Search

if TYPE_CHECKING:
    import pandas
    from typing_extensions import Unpack

__all__ = ["DEFAULT_GRID_STEP", "STAGES", "ScreeningResult", "screen"]

#: Bound on the acceleration of either object, m/s^2: two-body gravity at the polar
#: radius (9.86 m/s^2) plus 1 % for J2..J6 and drag (J2 adds 0.2 %; drag stays below
#: 0.1 m/s^2 above the floor for any ordinary object).
MAX_ACCELERATION = 1.01 * MU / R_POLE**2
#: Sub-samples of the cubic Hermite interpolant per coarse interval in :func:`screen`.
HERMITE_SAMPLES = 64
#: Radial prefilter: pad of the osculating perigee/apogee radii for the zonal-harmonic
#: oscillation, in units of J2 Re^2 / p (~6.5 km in LEO). The largest excursion beyond the
#: osculating range, measured on seeded samples of the 2023-11-13 CelesTrak snapshot
#: (400 objects over 3 days, 150 over 25 days), is 2.0 (J2 only) and 3.0 (J2..J6) of it;
#: the pads are about twice that (keys: zonal degree 2, and 3 to 6).
ZONAL_PAD = {2: 4.0, 6: 6.0}
#: Radial prefilter: fixed margin added to every pad, m.
RADIAL_MARGIN = 5e3
#: Names of the counts in :attr:`ScreeningResult.counts`, in order of the stages.
STAGES = ("secondaries", "radial", "propagated", "coarse_grid", "interpolated", "events")


#: An object :func:`screen` takes: a catalog object, or (state, spacecraft[, name]).
ScreenObject = CatalogObject | tuple[OrbitState, Spacecraft] | tuple[OrbitState, Spacecraft, str]


class Reached(enum.IntEnum):
    """How far one secondary got through stages 2-5 of :func:`screen`."""

    #: Not screened: decayed before the window's first grid step, or (``errors="record"``)
    #: its propagation raised.
    SKIPPED = 0
    #: Propagated; no grid step within reach of the primary.
    PROPAGATED = 1
    #: Some grid step passed the coarse-grid bound.
    COARSE_GRID = 2
    #: Some interval passed the interpolated bound and was refined.
    INTERPOLATED = 3


@dataclass(frozen=True)
class _Outcome:
    """One secondary's stages 2-5: how far it got, why it was skipped or what to note
    (its decay inside the window), its events within the distance, the exception that
    skipped it (``errors="record"``) and the time per stage (s)."""

    reached: Reached
    reason: str = ""
    events: tuple[CloseApproach, ...] = ()
    error: Exception | None = None
    timings: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class ScreeningResult:
    """What :func:`screen` found.

    Attributes:
        events: close approaches within ``distance``, sorted by TCA (object 1 is the
            primary).
        counts: objects left after each stage, in the order of :data:`STAGES`:
            ``secondaries`` (given, less the primary itself if it is among them: same
            epoch and state; it is listed in ``skipped``), ``radial`` (radial ranges
            overlap),
            ``propagated`` (propagated over the window; objects decayed before ``start``
            are skipped), ``coarse_grid`` (some grid interval's lower distance bound is
            within ``distance``), ``interpolated`` (the cubic Hermite interpolant comes
            within ``distance`` plus its margin) and ``events`` (objects with an event).
        skipped: (name, reason) of the secondaries not screened (decayed before
            ``start``; with ``errors="record"``, failed ones).
        notes: (name, note) of objects screened only in part (decayed inside the window).
        timings: seconds spent per stage, summed over the worker threads (``primary``:
            the primary's field and propagation, ``radial``: the vectorised prefilter,
            ``field``: sampling the density field(s) of the survivors,
            ``propagation``: the coarse propagation, ``coarse_grid``,
            ``interpolated`` and ``refinement``).
        wall: wall-clock time of the whole screen, s.
        threads: worker threads used.
        start, end: the window (UTC); distance: the threshold, m; grid_step: the coarse
            grid spacing, s.
    """

    events: list[CloseApproach]
    counts: dict[str, int]
    skipped: list[tuple[str, str]]
    notes: list[tuple[str, str]]
    timings: dict[str, float]
    wall: float
    threads: int
    start: np.datetime64
    end: np.datetime64
    distance: float
    grid_step: float

    def table(self) -> dict[str, np.ndarray]:
        """The events as columns, one row per event in order
        (:func:`~rhoprop.conjunction.approach.event_columns`: names, ids, TCA UTC, miss
        distance m, relative speed m/s, edge, the stretch within the distance)."""
        return event_columns(self.events)

    def to_pandas(self) -> pandas.DataFrame:
        """:meth:`table` as a ``pandas.DataFrame``, one row per event (needs pandas, e.g.
        the ``[xarray]`` extra), as ``AllOnAllResult.to_pandas()`` gives its events."""
        pd = optional_import("pandas", "ScreeningResult.to_pandas()")
        frame: pandas.DataFrame = pd.DataFrame(self.table())
        return frame


# ---------------------------------------------------------------------------------------
# Geometry on sampled tracks


def _lower_bounds(a: SampledTrack, b: SampledTrack, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Distances at the first ``n`` samples and a lower bound of the distance over each
    interval: (d_k + d_k+1)/2 - (V + A h/2) h/2 with V the larger relative speed at the
    ends, A = 2 x :data:`MAX_ACCELERATION` and h the interval length."""
    r = b.pos[:n] - a.pos[:n]
    v = b.vel[:n] - a.vel[:n]
    d = np.linalg.norm(r, axis=1)
    s = np.linalg.norm(v, axis=1)
    h = np.diff(a.t[:n])
    speed = np.maximum(s[:-1], s[1:]) + MAX_ACCELERATION * h
    return d, 0.5 * (d[:-1] + d[1:]) - 0.5 * speed * h


def _hermite_bounds(a: SampledTrack, b: SampledTrack, k: np.ndarray) -> np.ndarray:
    """Lower bound of the distance on the cubic Hermite interpolant over intervals ``k``:
    the same Lipschitz bound on :data:`HERMITE_SAMPLES` sub-intervals."""
    n = len(b.t)  # b may end early (decay)
    r, v = b.pos - a.pos[:n], b.vel - a.vel[:n]
    s = np.linspace(0.0, 1.0, HERMITE_SAMPLES + 1)
    h = a.t[k + 1] - a.t[k]
    p, q = hermite(
        r[k][:, None], v[k][:, None], r[k + 1][:, None], v[k + 1][:, None], h[:, None], s[None]
    )
    d = np.linalg.norm(p, axis=2)
    sp = np.linalg.norm(q, axis=2)
    dh = (h / HERMITE_SAMPLES)[:, None]
    speed = np.maximum(sp[:, :-1], sp[:, 1:]) + MAX_ACCELERATION * dh
    low = 0.5 * (d[:, :-1] + d[:, 1:]) - 0.5 * speed * dh
    return np.asarray(low.min(axis=1))


def _interpolation_margin(a: SampledTrack, b: SampledTrack, h: float) -> float:
    """Margin for the cubic Hermite error over intervals of ``h`` s: ten times
    h^4/384 |r''''| with |r''''| ~ (v/r)^4 r for each object (two-body), plus 100 m."""

    def fourth(track: SampledTrack) -> float:
        rn = np.linalg.norm(track.pos, axis=1)
        vn = np.linalg.norm(track.vel, axis=1)
        return float(np.max((vn / rn) ** 4 * rn)) if len(rn) else 0.0

    return 10.0 * h**4 / 384.0 * (fourth(a) + fourth(b)) + 100.0


class ScreenKeywords(LooseFloorAndDegree, total=False):
    """The deprecated keywords of :func:`screen`, each now in a settings record:
    ``search=Search(grid_step=, fine_step=)``, ``execution=rp.Execution(threads=,
    errors=, progress=)`` and ``dynamics=rp.Dynamics(floor_altitude=, zonal_degree=)``."""

    grid_step: float
    fine_step: float
    threads: int | None
    errors: Errors | Literal["skip"]
    progress: bool | Callable[[int], object]


#: Where each deprecated keyword of :func:`screen` goes now.
_LOOSE = {"search": ("grid_step", "fine_step"), "execution": ("threads", "errors", "progress")}


def screen(
    primary: ScreenObject,
    secondaries: Iterable[ScreenObject],
    model: ModelLike,
    *,
    start: EpochLike,
    end: EpochLike,
    distance: float,
    search: Search | None = None,
    dynamics: Dynamics | None = None,
    execution: Execution | None = None,
    **deprecated: Unpack[ScreenKeywords],
) -> ScreeningResult:
    """Screens one primary against many secondaries for close approaches within
    ``distance`` over [start, end] (UTC).

    Objects: a :class:`~rhoprop.catalog.CatalogObject` (state at its own epoch, TEME
    taken as inertial; drag parameter Cd*A/m, as ``rp.catalog.load`` gives them; id = NORAD
    number) or a tuple ``(OrbitState, Spacecraft)`` / ``(OrbitState, Spacecraft, name)``
    (id = position in ``secondaries`` without a name, else None). ``secondaries`` is a
    :class:`~rhoprop.catalog.Catalog` or a list of such objects.

    Stages (counts and times in the result):

    1. **Radial**: a secondary whose osculating perigee-apogee range, padded by
       :data:`ZONAL_PAD` x J2 Re^2/p for the zonal oscillation, :data:`RADIAL_MARGIN`, and
       downwards by a bound on its drag decay from its epoch to ``end``, stays more than
       ``distance`` from the primary's range (its propagated radii over the window, padded
       for sampling) is dropped.
    2. **Propagation**: the others are propagated with rhoprop's dynamics through
       ``model`` (a sampled model through its density atlas: day tiles over every
       altitude, shared by all objects, see :func:`models_for`)
       from their epochs to ``start`` (backwards when later) and then over the window
       with outputs every ``grid_step`` s (adaptive DOP853), on threads.
    3. **Coarse grid**: on each grid interval the distance is at least
       (d_k + d_k+1)/2 - (V + A h/2) h/2 (V: the larger relative speed at its ends, A = 2 x
       :data:`MAX_ACCELERATION`, h: the spacing): intervals where that exceeds
       ``distance`` cannot hold a closer approach and are dropped.
    4. **Interpolated**: the same bound on 64 sub-intervals of the cubic Hermite
       interpolant of the relative motion, against ``distance`` plus a margin for the
       interpolation error (:func:`_interpolation_margin`, >= 100 m).
    5. **Refinement**: the surviving intervals are re-propagated for both objects at
       ``fine_step`` (:func:`closest_approach`'s method); every minimum within
       ``distance`` is an event.

    Args:
        primary: the primary object.
        secondaries: the objects to screen it against.
        model: density model (e.g. ``rp.density.Exponential.benchmark()``, ``Msis()``).
        start, end: the window, UTC (end > start).
        distance: screening distance, m (> 0).
        search: a :class:`~rhoprop.conjunction.Search` (None: ``Search()``): the coarse
            grid spacing (default 60 s; at most 1/20 of the primary's period, else
            ValueError), the refinement's output step (s), and ``max_span``: a secondary
            whose epoch lies more than this (s) before ``start`` or after ``end`` is not
            screened and is listed in ``skipped``, a primary's is a ValueError (default
            60 days; None: no limit).
        dynamics: a :class:`~rhoprop.Dynamics` (None: ``Dynamics()``, J2 only, floor
            120 km); the tracks follow its ``integrator``, ``step`` and ``rtol`` as
            ``rp.propagate`` does (default adaptive DOP853; an object propagated back to
            ``start`` uses RK8 at 30 s, the one backward integrator); ``field_degree``
            and ``third_bodies`` are refused (ValueError).
        execution: an :class:`~rhoprop.Execution` (None: the defaults): ``threads``
            (default: CPU count; the core releases the GIL); ``errors`` ``"raise"``
            (a secondary that fails raises its error with the object named) or
            ``"record"`` (it is listed in ``skipped`` and the screen goes on); ``progress``
            (a bar of the secondaries done on a terminal for screens over a second, or a
            callable given the number done). Its ``client``, ``chunk_size`` and
            ``max_memory`` are refused (ValueError): the screen runs in this process.
        **deprecated: ``grid_step=``, ``fine_step=`` (now in ``search``), ``threads=``,
            ``errors=``, ``progress=`` (in ``execution``), ``floor_altitude=`` and
            ``zonal_degree=`` (in ``dynamics``), folded in with a DeprecationWarning.

    Returns:
        :class:`ScreeningResult`. Secondaries that decayed before ``start`` are skipped
        (listed with their decay time); one that decays inside the window is screened up to
        its decay (listed in ``notes``). Ctrl-C stops the screen with KeyboardInterrupt.

    Raises:
        TypeError: objects or arguments of the wrong type.
        ValueError: end <= start, distance <= 0, no secondaries (or only the primary
            itself), a grid step over 1/20 of the primary's period; a primary that decays
            before ``end`` (:class:`~rhoprop.errors.DecayError`).
    """
    wall0 = time.perf_counter()
    prim, objs, itself = _objects(primary, secondaries)
    check_model(model)
    loose: dict[str, object] = dict(deprecated)
    part = {k: {n: loose.pop(n) for n in names if n in loose} for k, names in _LOOSE.items()}
    found = fold_keywords(
        "screen", "search", search, Search(), part["search"], "rp.conjunction.Search"
    )
    run_on = execution_argument("screen", execution, part["execution"])
    run_on.require_defaults("screen", ("client", "chunk_size", "max_memory"))
    settings = deprecated_keywords(
        "screen", dynamics, loose, names=("floor_altitude", "zonal_degree")
    )
    settings.require_automatic_gravity("screen")
    w = make_window(prim, start, end, distance, found.grid_step, found.fine_step, settings)
    given = len(objs)
    objs, far = _within_span(prim, objs, w, found.max_span)
    errors, progress = run_on.errors, run_on.progress
    workers = worker_count(run_on.threads)
    timings = dict.fromkeys(
        ("primary", "radial", "field", "propagation", "coarse_grid", "interpolated", "refinement"),
        0.0,
    )
    t0 = time.perf_counter()
    dyn, ptrack, p_range = _primary_track(prim, model, w)
    timings["primary"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    survivors = _radial_survivors(objs, model, w, p_range)
    timings["radial"] = time.perf_counter() - t0

    counts = dict.fromkeys(STAGES, 0)
    counts["secondaries"] = given
    counts["radial"] = len(survivors)
    skipped: list[tuple[str, str]] = [(o.name, "the primary itself") for o in itself] + far
    notes: list[tuple[str, str]] = []
    events: list[CloseApproach] = []
    if survivors:
        t0 = time.perf_counter()
        earliest = min([w.start, *(o.state.epoch for o in survivors)])
        latest = max([w.end, *(o.state.epoch for o in survivors)])
        models = models_for(
            model, [o.state for o in survivors], earliest, latest, w.dynamics.floor_altitude
        )
        for obj, own in zip(survivors, models, strict=True):
            obj.model = own
        timings["field"] = time.perf_counter() - t0
        results = _run_threads(
            survivors, dyn, ptrack, w.start, w.span, w.step, w.limit, workers, errors, progress
        )
        for obj, res in zip(survivors, results, strict=True):
            for key, seconds in res.timings.items():
                timings[key] += seconds
            if res.reached == Reached.SKIPPED:
                skipped.append((obj.name, res.reason))
                continue
            counts["propagated"] += 1
            if res.reason:
                notes.append((obj.name, res.reason))
            counts["coarse_grid"] += res.reached >= Reached.COARSE_GRID
            counts["interpolated"] += res.reached >= Reached.INTERPOLATED
            counts["events"] += bool(res.events)
            events += res.events
    events.sort(key=lambda e: (e.tca, e.name2))
    return ScreeningResult(
        events=events,
        counts=counts,
        skipped=skipped,
        notes=notes,
        timings=timings,
        wall=time.perf_counter() - wall0,
        threads=workers,
        start=w.start,
        end=w.end,
        distance=w.limit,
        grid_step=w.step,
    )


def _within_span(
    prim: ScreenedObject, objs: list[ScreenedObject], w: Window, max_span: float | None
) -> tuple[list[ScreenedObject], list[tuple[str, str]]]:
    """The secondaries whose epoch lies within ``max_span`` s before the window's start
    or after its end, and (name, reason) of the others; a ValueError if the primary's
    does not."""
    if max_span is None:
        return objs, []

    def beyond(obj: ScreenedObject) -> str:
        t = obj.state.epoch
        if t <= w.start:
            return beyond_max_span(seconds_between(t, w.start), "start", max_span)
        return beyond_max_span(seconds_between(t, w.end), "end", max_span) if t > w.end else ""

    if why := beyond(prim):
        raise ValueError(f"the primary {prim.name}: {why}")
    reasons = [beyond(o) for o in objs]
    kept = [o for o, why in zip(objs, reasons, strict=True) if not why]
    far = [(o.name, why) for o, why in zip(objs, reasons, strict=True) if why]
    return kept, far


def _objects(
    primary: Any, secondaries: Any
) -> tuple[ScreenedObject, list[ScreenedObject], list[ScreenedObject]]:
    """The primary, the secondaries without the primary itself, and those left out as
    being the primary (same epoch and state)."""
    prim = as_object(primary, "primary", 0)
    items = secondaries_list(secondaries)
    if not items:
        raise ValueError("secondaries is empty: nothing to screen the primary against")
    objs = [as_object(item, f"secondaries[{i}]", i) for i, item in enumerate(items)]
    itself = [
        o
        for o in objs
        if o.state.epoch == prim.state.epoch and np.array_equal(o.state.state, prim.state.state)
    ]
    objs = [o for o in objs if not any(o is x for x in itself)]
    if not objs:
        raise ValueError("secondaries hold only the primary itself: nothing to screen")
    return prim, objs, itself


def _primary_track(
    prim: ScreenedObject, model: Any, w: Window
) -> tuple[TrackDynamics, SampledTrack, tuple[float, float]]:
    """The dynamics of the screen, the primary's track over the window and its radial
    range (m, padded for sampling); DecayError if it decays before the end."""
    (prim.model,) = models_for(
        model,
        [prim.state],
        min(w.start, prim.state.epoch),
        max(w.end, prim.state.epoch),
        w.dynamics.floor_altitude,
    )
    dyn = TrackDynamics(w.start, True, w.dynamics, w.fine)
    ptrack, pdecay = coarse_track(prim, dyn, w.start, w.span, w.step)
    if len(ptrack.t) < 2 or pdecay is not None:
        at = add_seconds(w.start, pdecay) if pdecay is not None else w.start
        raise DecayError(
            f"the primary {prim.name} decays at {at} UTC, before the end of the screening "
            f"window ({w.end}); screen a window that ends before its decay"
        )
    rp_n = np.linalg.norm(ptrack.pos, axis=1)
    rdot = np.abs(np.einsum("ij,ij->i", ptrack.pos, ptrack.vel)) / rp_n
    pad = float(rdot.max()) * w.step / 2 + MAX_ACCELERATION * w.step**2 / 8
    return dyn, ptrack, (float(rp_n.min()) - pad, float(rp_n.max()) + pad)


def _radial_survivors(
    objs: list[ScreenedObject], model: Any, w: Window, p_range: tuple[float, float]
) -> list[ScreenedObject]:
    """Stage 1: the secondaries whose padded radial range (with a bound on their drag
    decay) comes within the distance of the primary's."""
    p_low, p_high = p_range
    perigee, apogee, a, p = radial_ranges(objs)
    pad = ZONAL_PAD[2 if w.dynamics.zonal_degree == 2 else 6] * J2 * R_EARTH**2 / p + RADIAL_MARGIN
    # Each object's span: from the earlier of its epoch and start to the later of it and end.
    epochs = np.array([o.state.epoch for o in objs], dtype="datetime64[ns]")
    offsets = to_seconds(epochs, w.start)
    spans = np.maximum(offsets, w.span) - np.minimum(offsets, 0.0)
    high = apogee + pad
    low_no_drag = perigee - pad
    above = low_no_drag > p_high + w.limit
    decay = np.zeros(len(objs))
    if above.any():
        idx = np.flatnonzero(above)
        first = min(w.start, epochs[idx].min())
        decay[idx] = drag_decay(
            model, [objs[i] for i in idx], perigee[idx], a[idx], spans[idx], first, w.end
        )
    keep = ~((low_no_drag - decay > p_high + w.limit) | (high < p_low - w.limit))
    return [o for o, k in zip(objs, keep, strict=True) if k]


def _screen_one(
    obj: ScreenedObject,
    dyn: TrackDynamics,
    prim: SampledTrack,
    start: np.datetime64,
    span: float,
    step: float,
    limit: float,
) -> _Outcome:
    """Stages 2-5 for one secondary."""
    tm: dict[str, float] = {}
    t0 = time.perf_counter()
    track, decay = coarse_track(obj, dyn, start, span, step)
    tm["propagation"] = time.perf_counter() - t0
    if len(track.t) < 2:
        when = add_seconds(start, decay) if decay is not None else start
        why = f"decayed at {when} UTC, before the window ends its first grid step"
        return _Outcome(Reached.SKIPPED, why, timings=tm)
    note = ""
    if decay is not None:
        note = f"decayed at {add_seconds(start, decay)} UTC: screened up to then"
    t0 = time.perf_counter()
    _d, lower = _lower_bounds(prim, track, len(track.t))
    k = np.flatnonzero(lower <= limit)
    tm["coarse_grid"] = time.perf_counter() - t0
    if not len(k):
        return _Outcome(Reached.PROPAGATED, note, timings=tm)
    t0 = time.perf_counter()
    margin = _interpolation_margin(prim, track, step)
    k = k[_hermite_bounds(prim, track, k) <= limit + margin]
    tm["interpolated"] = time.perf_counter() - t0
    if not len(k):
        return _Outcome(Reached.COARSE_GRID, note, timings=tm)
    t0 = time.perf_counter()
    last = float(track.t[-1])
    found: list[tuple[float, np.ndarray, np.ndarray]] = []
    for lo, hi in merge_brackets((float(track.t[j]), float(track.t[j + 1])) for j in k):
        found += refine(dyn, prim, track, lo, hi, 0.0, last)
    events = [make_event(dyn, prim, track, *item) for item in dedupe(found)]
    tm["refinement"] = time.perf_counter() - t0
    near = tuple(ev for ev in events if ev.miss_distance <= limit)
    return _Outcome(Reached.INTERPOLATED, note, near, timings=tm)


def _run_threads(
    objs: list[ScreenedObject],
    dyn: TrackDynamics,
    prim: SampledTrack,
    start: np.datetime64,
    span: float,
    step: float,
    limit: float,
    workers: int,
    errors: str,
    progress: bool | Callable[[int], object],
) -> list[_Outcome]:
    """Stages 2-5 for every object on ``workers`` threads, results in order. Ctrl-C (or
    an error) cancels the objects not started; the running ones end within ~1 ms."""
    stop = threading.Event()

    def one(obj: ScreenedObject) -> _Outcome:
        if stop.is_set():
            raise KeyboardInterrupt("screening interrupted")
        try:
            return _screen_one(obj, dyn, prim, start, span, step, limit)
        except Exception as err:
            if errors == "record":
                return _Outcome(Reached.SKIPPED, f"{type(err).__name__}: {err}", error=err)
            named = object_error(err, obj)
            if named is err:
                raise
            raise named from err

    bar: Callable[[int], object] | None
    shown: ProgressBar | None = None
    if callable(progress):
        bar = progress
    elif progress:
        shown = ProgressBar(len(objs), "screening", unit="objects")
        bar = shown
    else:
        bar = None
    try:
        return map_in_threads(
            one, objs, workers, stop, None if bar is None else lambda i, _r: bar(i + 1)
        )
    finally:
        if shown is not None:
            shown.close()
