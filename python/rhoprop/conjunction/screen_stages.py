"""The work of an all-on-all screen's stages in pieces that run anywhere: on this
machine's threads or as Dask tasks on other machines, with the same numbers.

- **Propagation**: a block of objects over one time chunk (:func:`track_block`); each
  object's track is its own, whoever computes it.
- **Sieve**: a range of the chunk's grid intervals (:func:`sieve_range`); the core sieves
  every interval on its own (the objects' two samples and their acceleration bound), so
  the candidates of a range are those the whole chunk gives there.
- **Refinement**: a slice of the chunk's candidates (:func:`refine_slice`), each minimum
  and its stretch within the distance found from the whole chunk's tracks, as one call
  over all candidates finds them (the core treats candidates one by one).

:class:`DaskStages` sends the pieces to a ``distributed.Client`` (the chunk's tracks
scattered once per chunk, to every worker) and puts the results back together in the
local order: a screen on Dask gives the events of a local one, bit for bit
(``tests/test_screen_all.py``).
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _core
from ..propagation import OrbitState
from ..time import add_seconds
from .kernel import ScreenedObject, TrackDynamics, coarse_track, object_error
from .screening import HERMITE_SAMPLES, MAX_ACCELERATION

#: One object's track over a chunk: times (s from start), positions, velocities, the
#: decay time (s from start, or None) and why it was skipped ("" when it was not).
Track = tuple[np.ndarray, np.ndarray, np.ndarray, float | None, str]
#: An object's state at a chunk's start: (position, velocity), m and m/s, TEME; None once
#: it has decayed.
StartState = tuple[np.ndarray, np.ndarray] | None


def track_one(
    obj: ScreenedObject,
    start_state: StartState,
    times: np.ndarray,
    first: bool,
    dyn: TrackDynamics,
    step: float,
    errors: str,
) -> Track:
    """``obj`` over the chunk's ``times``: from its epoch in the first chunk, else from
    ``start_state`` (position, velocity at ``times[0]``, TEME); with ``errors="record"`` a
    failure is a skip reason, else it is raised with the object named."""
    span = float(times[-1] - times[0])
    try:
        if first:
            tr, decay = coarse_track(obj, dyn, dyn.ref, span, step)
            return tr.t, tr.pos, tr.vel, decay, ""
        if start_state is None:
            raise ValueError("no state at the chunk's start")  # guarded by the caller
        p0, v0 = start_state
        s0 = OrbitState(add_seconds(dyn.ref, float(times[0])), p0, v0, "TEME")
        out = dyn.forward(s0, obj.craft, obj.model, span, step)
        decay = None if out.decayed_at is None else float(times[0]) + out.decayed_at
        return times[0] + out.times, out.positions, out.velocities, decay, ""
    except Exception as err:
        if errors != "record":
            named = object_error(err, obj, "object")
            if named is err:
                raise
            raise named from err
        empty = np.empty((0, 3))
        return np.empty(0), empty, empty, None, f"{type(err).__name__}: {err}"


def track_block(
    objs: list[ScreenedObject],
    which: list[int],
    models: list[Any],
    states: list[StartState],
    times: np.ndarray,
    first: bool,
    dyn: TrackDynamics,
    step: float,
    errors: str,
) -> list[Track]:
    """A Dask task: :func:`track_one` for each object of a block, object k flying
    through ``models[which[k]]`` (the density fields travel once per worker, not with
    every block)."""
    out = []
    for o, w, s in zip(objs, which, states, strict=True):
        own = dataclasses.replace(o, model=models[w])
        out.append(track_one(own, s, times, first, dyn, step, errors))
    return out


def sieve_range(
    times: np.ndarray,
    pos: np.ndarray,
    vel: np.ndarray,
    samples: np.ndarray,
    fourth: np.ndarray,
    limit: float,
    k0: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int, int]]:
    """The candidates (i, j, k) and counts of grid intervals ``k0 .. k0 + len(times) - 2``
    of a chunk, given that range's samples (``times``, ``pos[:, ...]``, ``vel[:, ...]``
    and each object's ``samples`` there): k is the chunk's interval index."""
    c = np.ascontiguousarray
    tracks = core_tracks(c(times), c(pos), c(vel), c(samples))
    out = _core.screen_candidates(tracks, c(fourth), limit, MAX_ACCELERATION, HERMITE_SAMPLES)
    counts = (out.spatial, out.coarse, out.interpolated)
    return out.i, out.j, np.asarray(out.k, dtype=np.int64) + k0, counts


def refine_slice(
    chunk: dict[str, np.ndarray],
    cand: np.ndarray,
    degree: int,
    limit: float,
    span: float,
    tick: Callable[[int], object] | None = None,
) -> tuple[np.ndarray, ...]:
    """The minima within ``limit`` of candidate rows ``cand`` (i, j, k) over the whole
    ``chunk`` (its ``times``, ``pos``, ``vel``, ``samples``; ``span`` the window's length,
    s) on the quintic Hermite interpolant of both objects' samples, and each one's stretch
    within the distance (the cubic Hermite relative motion walked away from the minimum,
    crossings to 1 ms: ``rhoprop_core::sieve::stretches``, held within the samples both
    objects have): (i, j, t, state_i, state_j, edge, first, last). ``tick(done)``: the
    core's progress (None on a Dask worker)."""
    # Copies: arrays that came through Dask's serialisation can be views the core's
    # borrow refuses.
    times, pos, vel, samples = (
        np.array(chunk[key], copy=True, order="C") for key in ("times", "pos", "vel", "samples")
    )
    c = cand.astype(np.uint32)
    tracks = core_tracks(times, pos, vel, samples)
    found = _core.screen_approaches(
        tracks,
        np.ascontiguousarray(c[:, 0]),
        np.ascontiguousarray(c[:, 1]),
        np.ascontiguousarray(c[:, 2]),
        degree,
        limit,
        tick,
        window_start=bool(times[0] == 0.0),
        window_end=bool(times[-1] == span),
    )
    i, j, t = found.i, found.j, found.t
    stretch = _core.screen_stretches(tracks, i, j, t, limit)
    return i, j, t, found.states1, found.states2, found.edge, stretch.first, stretch.last


def core_tracks(
    times: np.ndarray, pos: np.ndarray, vel: np.ndarray, samples: np.ndarray
) -> _core.Tracks:
    """The core's record of sampled tracks (held, not copied): grid ``times`` (nt,) s,
    ``pos`` and ``vel`` (n, nt, 3) m and m/s, C-contiguous, and the ``samples`` each object
    has (n,); checked by the core when made."""
    return _core.Tracks(times=times, positions=pos, velocities=vel, samples=samples)


def _parts(n: int, pieces: int) -> list[tuple[int, int]]:
    """[lo, hi) bounds cutting ``n`` items into at most ``pieces`` nearly equal parts."""
    edges = np.linspace(0, n, min(max(pieces, 1), max(n, 1)) + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in itertools.pairwise(edges) if b > a]


@dataclass
class DaskStages:
    """The screening stages of one run on a ``distributed.Client``: each stage of each
    time chunk cut into ``pieces`` tasks (default four per worker thread)."""

    client: Any
    pieces: int = 0
    #: The run's density fields, scattered to every worker at the first chunk, and the
    #: index of each object's field among them (by identity).
    _fields: Any = None
    _field_of: dict[int, int] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.pieces <= 0:
            threads = sum(self.client.nthreads().values()) or 1
            self.pieces = 4 * threads

    def _share_fields(self, objs: list[ScreenedObject]) -> None:
        if self._fields is not None:
            return
        unique: dict[int, Any] = {}
        for o in objs:
            unique.setdefault(id(o.model), o.model)
        self._field_of = {key: n for n, key in enumerate(unique)}
        # Random keys (hash=False), as rhoprop.catalog.backends scatters a model.
        self._fields = self.client.scatter(list(unique.values()), broadcast=True, hash=False)

    def tracks(
        self,
        objs: list[ScreenedObject],
        states: list[StartState],
        times: np.ndarray,
        first: bool,
        dyn: TrackDynamics,
        step: float,
        errors: str,
        todo: list[int],
        tick: Callable[[int, Track], object],
    ) -> dict[int, Track]:
        """:func:`track_one` of the objects ``todo`` in blocks, as {index: track}."""
        self._share_fields(objs)
        futures = []
        for lo, hi in _parts(len(todo), self.pieces):
            idx = todo[lo:hi]
            futures.append(
                (
                    idx,
                    self.client.submit(
                        track_block,
                        [dataclasses.replace(objs[i], model=None, item=None) for i in idx],
                        [self._field_of[id(objs[i].model)] for i in idx],
                        self._fields,
                        [states[i] for i in idx],
                        times,
                        first,
                        dyn,
                        step,
                        errors,
                        pure=False,
                    ),
                )
            )
        out: dict[int, Track] = {}

        def keep(k: int, tracks: list[Track]) -> None:  # as each block comes in
            for i, track in zip(futures[k][0], tracks, strict=True):
                out[i] = track
                tick(i, track)

        self._gather([f for _idx, f in futures], keep)
        return out

    def _gather(
        self, futures: list[Any], each: Callable[[int, Any], object] | None = None
    ) -> list[Any]:
        """The futures' results in order (``each(k, result)`` as each comes in); an
        error or Ctrl-C cancels the rest."""
        results = []
        try:
            for k, f in enumerate(futures):
                results.append(f.result())
                if each is not None:
                    each(k, results[-1])
        except BaseException:
            self.client.cancel(futures)
            raise
        return results

    def sieve(
        self,
        times: np.ndarray,
        pos: np.ndarray,
        vel: np.ndarray,
        samples: np.ndarray,
        fourth: np.ndarray,
        limit: float,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int, int]]:
        """:func:`sieve_range` over ranges of the chunk's intervals; the candidates sorted
        (i, j, k) as the core sorts them and the counts summed."""
        futures = []
        for lo, hi in _parts(len(times) - 1, self.pieces):
            local = np.clip(samples.astype(np.int64) - lo, 0, hi + 1 - lo).astype(np.uint64)
            futures.append(
                self.client.submit(
                    sieve_range,
                    times[lo : hi + 1],
                    np.ascontiguousarray(pos[:, lo : hi + 1]),
                    np.ascontiguousarray(vel[:, lo : hi + 1]),
                    local,
                    fourth,
                    limit,
                    lo,
                    pure=False,
                )
            )
        parts = self._gather(futures)
        i = np.concatenate([p[0] for p in parts]).astype(np.int64)
        j = np.concatenate([p[1] for p in parts]).astype(np.int64)
        k = np.concatenate([p[2] for p in parts]).astype(np.int64)
        order = np.lexsort((k, j, i))
        counts = tuple(int(sum(p[3][c] for p in parts)) for c in range(3))
        return i[order], j[order], k[order], (counts[0], counts[1], counts[2])

    def refine(
        self,
        chunk: dict[str, np.ndarray],
        cand: np.ndarray,
        degree: int,
        limit: float,
        span: float,
    ) -> tuple[np.ndarray, ...]:
        """:func:`refine_slice` over slices of the candidates, the chunk scattered once;
        the results concatenated in the candidates' order."""
        shared = self.client.scatter(chunk, broadcast=True, hash=False)
        futures = [
            self.client.submit(refine_slice, shared, cand[lo:hi], degree, limit, span, pure=False)
            for lo, hi in _parts(len(cand), self.pieces)
        ]
        parts = self._gather(futures)
        return tuple(np.concatenate([p[m] for p in parts]) for m in range(8))
