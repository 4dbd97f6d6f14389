"""The machinery every conjunction search shares (``closest_approach``, ``screen``,
``screen_all`` and its Pc and Monte Carlo stages): the objects a screen holds
(:class:`ScreenedObject`, :func:`as_object`, :func:`catalog_object`) and their radial
ranges; tracks (:class:`SampledTrack`, :func:`coarse_track`, cubic :func:`hermite`
interpolation) and how they are propagated (:class:`TrackDynamics`); the window check
(:class:`Window`, :func:`make_window`, :func:`window_span`); refinement of a bracketed
minimum by re-propagation (:func:`refine`, :func:`merge_brackets`, :func:`dedupe`) and
the event it becomes (:class:`CloseApproach`, :func:`make_event`).

One module, so that no file reaches into another's private names: ``approach``,
``screening``, ``all_on_all``, ``screen_stages``, ``event_pc`` and ``event_mc`` import
what they share from here (a test keeps it so). How an event is found:
docs/conjunction.md, "Screening"."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..catalog.covariance import tle_covariance
from ..catalog.elements import CatalogObject
from ..constants import MU, R_EARTH
from ..density import SampledModel
from ..density.model import DensityModel, ModelLike, as_atmosphere
from ..propagation import OrbitState, Spacecraft, Trajectory, propagate
from ..propagation.dynamics import Dynamics
from ..propagation.propagate import (
    MAX_STEP_FRACTION,
    core_propagate,
    orbital_period,
)
from ..time import EpochLike, add_seconds, seconds_between, to_datetime64

#: Longest bracket re-propagated at once, s (a minimum on a boundary between two is found
#: in one of them and counted once).
MAX_BRACKET = 6 * 3600.0


#: Events closer in time than this are one event (found from two brackets), s.
SAME_EVENT = 1e-3


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


def hermite(
    r0: np.ndarray,
    v0: np.ndarray,
    r1: np.ndarray,
    v1: np.ndarray,
    h: npt.ArrayLike,
    s: npt.ArrayLike,
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


def root_in_interval(
    r0: np.ndarray, v0: np.ndarray, r1: np.ndarray, v1: np.ndarray, h: float
) -> float:
    """Fraction s in [0, 1] of the interval where f = r . v of the cubic Hermite relative
    motion changes sign from negative to non-negative (bisection to 1e-14)."""
    lo, hi = 0.0, 1.0
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        p, v = hermite(r0, v0, r1, v1, h, mid)
        if float(p @ v) < 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@dataclass
class SampledTrack:
    """One object's samples on times ``t`` (s from the reference epoch)."""

    name: str
    object_id: int | None
    craft: Spacecraft | None
    t: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    model: Any = None


@dataclass
class TrackDynamics:
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
        self, track: SampledTrack, t0: float, state: np.ndarray, span: float, step: float | None
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

    def state_at(self, track: SampledTrack, t: float) -> np.ndarray | None:
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


def fine_pair(
    dyn: TrackDynamics, a: SampledTrack, b: SampledTrack, lo: float, hi: float
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


def refine(
    dyn: TrackDynamics,
    a: SampledTrack,
    b: SampledTrack,
    lo: float,
    hi: float,
    first: float,
    last: float,
) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """Close approaches (TCA s from ``ref``, state of a, state of b) in [lo, hi], from a
    fine re-propagation of both objects; when the bracket (from interpolated coarse
    outputs) holds no minimum but the distance still shrinks at an end, it moves one
    width that way, at most three times, staying inside [first, last]."""
    width = hi - lo
    found: list[tuple[float, np.ndarray, np.ndarray]] = []
    for _ in range(4):
        fine = fine_pair(dyn, a, b, lo, hi)
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
        s = root_in_interval(r[i], v[i], r[i + 1], v[i + 1], h)
        tca = float(t[i]) + s * h
        if not dyn.propagates:
            p1, v1 = hermite(pa[i], va[i], pa[i + 1], va[i + 1], h, s)
            p2, v2 = hermite(pb[i], vb[i], pb[i + 1], vb[i + 1], h, s)
            found.append((tca, np.concatenate([p1, v1]), np.concatenate([p2, v2])))
            continue
        fine_a = SampledTrack(a.name, a.object_id, a.craft, t, pa, va, a.model)
        fine_b = SampledTrack(b.name, b.object_id, b.craft, t, pb, vb, b.model)
        s1, s2 = dyn.state_at(fine_a, tca), dyn.state_at(fine_b, tca)
        if s1 is not None and s2 is not None:
            found.append((tca, s1, s2))
    return found


class Named(Protocol):
    """What an event takes from each object: its name and id."""

    name: str
    object_id: int | None


def make_event(
    dyn: TrackDynamics,
    a: Named,
    b: Named,
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


def merge_brackets(brackets: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
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


def dedupe(found: list[tuple[float, np.ndarray, np.ndarray]]) -> list[Any]:
    out: list[tuple[float, np.ndarray, np.ndarray]] = []
    for item in sorted(found, key=lambda x: x[0]):
        if out and item[0] - out[-1][0] < SAME_EVENT:
            continue
        out.append(item)
    return out


def models_for(
    model: ModelLike,
    states: Sequence[OrbitState],
    start: np.datetime64,
    end: np.datetime64,
    floor: float,
) -> list[ModelLike]:
    """The model to propagate each of ``states`` with over [start, end]: a sampled model's
    atlas (day tiles over every altitude, extrapolated above the ceiling, so LEO, HEO and
    GEO objects share it) or the model as it is."""
    return [model.atlas if isinstance(model, SampledModel) else model] * len(states)


#: Radial prefilter: safety factor on the drag decay da = rho B sqrt(mu a) T, with rho the
#: model's mean + 3 sigma at the perigee altitude (largest over 12 places and 5 times).
DRAG_SAFETY = 3.0


#: Radial prefilter: altitude step and top of the density table the drag bound reads, m
#: (above the top, the density at the top: drag there moves no orbit by kilometres).
DRAG_TABLE_STEP = 10e3


DRAG_TABLE_TOP = 2000e3


#: Step of the fixed-step RK8 that takes an object back from a later epoch to ``start``, s.
BACKWARD_STEP = 30.0


@dataclass
class ScreenedObject:
    name: str
    object_id: int | None
    state: OrbitState
    craft: Spacecraft
    model: Any = None
    item: Any = None  # what was given (a CatalogObject carries its covariance)


def as_object(item: object, where: str, index: int) -> ScreenedObject:
    if isinstance(item, CatalogObject):
        craft = Spacecraft(1.0, item.drag_parameter)
        return ScreenedObject(item.name, item.norad_id, item.state, craft, item=item)
    if isinstance(item, tuple) and len(item) in (2, 3):
        state, craft = item[0], item[1]
        if not isinstance(state, OrbitState) or not isinstance(craft, Spacecraft):
            raise TypeError(
                f"{where} must be (OrbitState, Spacecraft[, name]), got "
                f"({', '.join(type(x).__name__ for x in item)})"
            )
        name = str(item[2]) if len(item) == 3 else f"{where}"
        # Screens run in TEME, the catalogs' frame: a state in another is rotated once.
        state = state.in_frame("TEME")
        return ScreenedObject(name, None if len(item) == 3 else index, state, craft, item=item)
    raise TypeError(
        f"{where} must be a rhoprop.catalog.CatalogObject or an (OrbitState, Spacecraft"
        f"[, name]) tuple, got {type(item).__name__}"
    )


def radial_ranges(
    objs: Sequence[ScreenedObject],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Osculating perigee and apogee radii, semi-major axis and semi-latus rectum (m) of
    the objects' states (apogee inf for an unbound orbit)."""
    r = np.array([o.state.position for o in objs])
    v = np.array([o.state.velocity for o in objs])
    rn = np.linalg.norm(r, axis=1)
    inv_a = 2.0 / rn - np.einsum("ij,ij->i", v, v) / MU
    h = np.cross(r, v)
    p = np.einsum("ij,ij->i", h, h) / MU
    e_vec = np.cross(v, h) / MU - r / rn[:, None]
    e = np.linalg.norm(e_vec, axis=1)
    with np.errstate(divide="ignore"):
        a = np.where(inv_a > 0, 1.0 / np.where(inv_a > 0, inv_a, 1.0), np.inf)
    perigee = p / (1.0 + e)
    apogee = np.where(e < 1.0, p / np.maximum(1.0 - e, 1e-300), np.inf)
    return perigee, apogee, a, p


def drag_decay(
    model: DensityModel,
    objs: Sequence[ScreenedObject],
    perigee: np.ndarray,
    a: np.ndarray,
    spans: np.ndarray,
    first: np.datetime64,
    end: np.datetime64,
) -> np.ndarray:
    """Bound on the drop of each object's perigee radius over its span (m): the decay of a
    circular orbit da = rho B sqrt(mu a) T times :data:`DRAG_SAFETY`, with rho the model's
    mean + 3 sigma at the perigee altitude, the largest over 12 places (latitudes -60, 0,
    60 deg x 4 longitudes) and 5 times from ``first`` to ``end``. The density comes from a
    table every :data:`DRAG_TABLE_STEP` m of altitude up to :data:`DRAG_TABLE_TOP`, read at
    the node at or below the perigee (density falls with altitude, so that bounds it);
    inf where the model cannot say (no ``mean_std``, or an error)."""
    out = np.full(len(objs), np.inf)
    if not len(objs) or not callable(getattr(model, "mean_std", None)):
        return out
    span = seconds_between(first, end)
    times = np.array(
        [add_seconds(first, f * span) for f in np.linspace(0.0, 1.0, 5)], dtype="datetime64[ns]"
    )
    lat = np.array([-60.0, 0.0, 60.0])
    lon = np.array([0.0, 90.0, 180.0, 270.0])
    alt = np.clip(perigee - R_EARTH, 0.0, DRAG_TABLE_TOP)
    bottom = DRAG_TABLE_STEP * np.floor(alt.min() / DRAG_TABLE_STEP)
    nodes = np.arange(bottom, alt.max() + DRAG_TABLE_STEP, DRAG_TABLE_STEP)
    try:
        mean, std = model.mean_std(
            times[None, :, None, None],
            lat[None, None, :, None],
            lon[None, None, None, :],
            nodes[:, None, None, None],
        )
    except ValueError:
        return out
    table = np.asarray(mean + 3.0 * std, dtype=float).reshape(len(nodes), -1).max(axis=1)
    rho = table[np.clip(((alt - bottom) // DRAG_TABLE_STEP).astype(int), 0, len(nodes) - 1)]
    drag = np.array([o.craft.drag_parameter for o in objs])
    decay = DRAG_SAFETY * rho * drag * np.sqrt(MU * np.where(np.isfinite(a), a, perigee)) * spans
    return np.where(np.isfinite(decay), decay, np.inf)


def coarse_track(
    obj: ScreenedObject, dyn: TrackDynamics, start: np.datetime64, span: float, grid_step: float
) -> tuple[SampledTrack, float | None]:
    """The object on the common grid start + k grid_step (s from ``start``): propagated
    from its epoch to ``start`` (backwards when its epoch is later), then over the window.
    The decay time (s from ``start``) or None; a track of < 2 samples if it decayed
    before ``start`` or right after."""
    lead = seconds_between(obj.state.epoch, start)
    state0 = obj.state
    if lead > 1e-9:
        tr = dyn.forward(obj.state, obj.craft, obj.model, lead, None)
        if tr.decayed_at is not None:
            empty = np.empty((0, 3))
            gone = SampledTrack(obj.name, obj.object_id, obj.craft, np.empty(0), empty, empty)
            return gone, tr.decayed_at - lead
        state0 = OrbitState(start, tr.positions[-1], tr.velocities[-1], "TEME")
    elif lead < -1e-9:
        atmosphere = as_atmosphere(obj.model, obj.state, lead)  # backwards: lead < 0
        # The core integrates backwards with the fixed-step RK8 only (as the debiasing's
        # backward orbit does); 30 s steps keep it at the millimetre level over days.
        _t, states, _d, _e, _c = core_propagate(
            atmosphere,
            obj.state,
            obj.craft.drag_parameter,
            np.array([0.0, lead]),
            integrator="rk8",
            step=BACKWARD_STEP,
            floor_altitude=dyn.floor,
            zonal_degree=dyn.degree,
        )
        state0 = OrbitState(start, states[-1, :3], states[-1, 3:], "TEME")
    tr = dyn.forward(state0, obj.craft, obj.model, span, grid_step)
    track = SampledTrack(
        obj.name, obj.object_id, obj.craft, tr.times, tr.positions, tr.velocities, obj.model
    )
    return track, tr.decayed_at


def secondaries_list(secondaries: Iterable[Any], name: str = "secondaries") -> list[Any]:
    """``secondaries`` as a list; TypeError naming the parameter ``name`` for a single
    object or something that is not a collection of objects."""
    if isinstance(secondaries, (CatalogObject, tuple)):
        raise TypeError(
            f"{name} must be a Catalog or a list of objects, not a single object: wrap it in a list"
        )
    try:
        return list(secondaries)
    except TypeError as err:
        raise TypeError(
            f"{name} must be a rhoprop.catalog.Catalog or a list of CatalogObjects or "
            f"(OrbitState, Spacecraft[, name]) tuples, got {type(secondaries).__name__}"
        ) from err


@dataclass(frozen=True)
class Window:
    """The checked window and settings of a screen: UTC start and end, span (s), distance
    (m), grid and fine steps (s) and the checked :class:`Dynamics` (floor altitude m,
    zonal degree, the tracks' integrator, step and rtol)."""

    start: np.datetime64
    end: np.datetime64
    span: float
    limit: float
    step: float
    fine: float
    dynamics: Dynamics


def window_span(start: EpochLike, end: EpochLike) -> tuple[np.datetime64, np.datetime64, float]:
    """UTC start and end of a screening window and its span (s), checked: ValueError
    unless end is after start."""
    t_start = to_datetime64(start, "start")
    t_end = to_datetime64(end, "end")
    span = seconds_between(t_start, t_end)
    if not span > 0:
        raise ValueError(f"end ({t_end}) must be after start ({t_start})")
    return t_start, t_end, span


def make_window(
    prim: ScreenedObject,
    start: EpochLike,
    end: EpochLike,
    distance: float,
    grid_step: float,
    fine_step: float,
    dynamics: Dynamics,
) -> Window:
    """The screen's window and settings, checked (ValueError naming the argument)."""
    t_start, t_end, span = window_span(start, end)
    limit = _validate.positive("distance", distance)
    step = _validate.positive("grid_step", grid_step)
    period = orbital_period(prim.state)
    if step > MAX_STEP_FRACTION * period:
        raise ValueError(
            f"grid_step = {step:g} s is too coarse for the primary's orbit (period "
            f"{period:.0f} s): at most 1/{round(1 / MAX_STEP_FRACTION)} of it, "
            f"{MAX_STEP_FRACTION * period:.0f} s, keeps the cubic Hermite interpolant of the "
            "relative motion meaningful"
        )
    return Window(
        t_start,
        t_end,
        span,
        limit,
        step,
        _validate.positive("fine_step", fine_step),
        dynamics,
    )


def object_error(err: Exception, obj: ScreenedObject, role: str = "secondary") -> Exception:
    """``err`` again with the object named (the same type), or ``err`` itself when its
    type cannot be built from a message."""
    try:
        return type(err)(f"{role} {obj.name} (id {obj.object_id}): {err}")
    except Exception:  # an exception type with a different constructor
        return err


def catalog_object(obj: ScreenedObject) -> CatalogObject:
    """The object as a CatalogObject (a tuple gets the TLE accuracy of its regime)."""
    item = obj.item
    if isinstance(item, CatalogObject):
        return item
    return CatalogObject(
        name=obj.name,
        norad_id=-1 if obj.object_id is None else int(obj.object_id),
        state=obj.state,
        drag_parameter=obj.craft.drag_parameter,
        bstar=0.0,
        source="(OrbitState, Spacecraft)",
        covariance=tle_covariance(obj.state),
        covariance_note="TLE accuracy of its regime (no covariance given)",
    )


@dataclass(frozen=True)
class EventPlan:
    """What the Pc stages of a screen take of its events (one record instead of a dozen
    arguments): the ``events``, each one's ``pairs`` of indices into ``objects``, the
    density ``models`` (by name) with the ``reference`` model's name, and the screen's
    ``window`` (its span, dynamics, floor and zonal degree)."""

    events: list[CloseApproach]
    pairs: list[tuple[int, int]]
    objects: list[ScreenedObject]
    models: dict[str, Any]  # density models as screen_all checked them
    reference: str
    window: Window
