"""Where a catalog run's objects run: on local threads (:func:`_run_local`: chunks of
CCSP objects per core call, objects in epoch order) or on a Dask cluster
(:func:`_run_on_dask`: the atlas travels as a reference, lost chunks are resubmitted).
The per-object logic is :mod:`rhoprop.catalog.objects`."""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from ..parallel import map_in_threads, worker_count
from ..propagation.methods import Ccsp
from .objects import ObjectOutcome, ObjectPlan, RunSettings, _ccsp_chunk, _run_object

#: Most objects per core call of a local CCSP run (:func:`_ccsp_chunk`).
CCSP_CHUNK = 16


class Outcomes:
    """The objects' outcomes as they arrive, copied at once into the arrays of the
    catalog's result, (objects, epochs, 6) means, (objects, epochs, 6, 6) covariances and
    (objects, epochs) validity; the outcome itself is dropped. A whole catalog's results
    are then held once (about 0.5 GB for 8,800 objects over 7 days hourly), not once per
    outcome and again when stacked. An object with its own, fewer, epochs fills the first
    of its row (the rest stay NaN, not valid)."""

    def __init__(self, objects: int, epochs: int) -> None:
        self.mean = np.full((objects, epochs, 6), np.nan)
        self.cov = np.full((objects, epochs, 6, 6), np.nan)
        self.valid = np.zeros((objects, epochs), dtype=bool)
        self.gaussian = np.ones((objects, epochs), dtype=bool)
        self.rest: dict[int, ObjectOutcome] = {}

    def __setitem__(self, i: int, outcome: ObjectOutcome) -> None:
        k = len(outcome.valid)
        self.mean[i, :k], self.cov[i, :k] = outcome.mean, outcome.cov
        self.valid[i, :k] = outcome.valid
        if outcome.gaussian is not None:
            self.gaussian[i, :k] = outcome.gaussian
        # The small fields only: the arrays live in the result's arrays.
        self.rest[i] = dataclasses.replace(
            outcome,
            mean=self.mean[i],
            cov=self.cov[i],
            valid=self.valid[i],
            gaussian=self.gaussian[i],
        )

    def __getitem__(self, i: int) -> ObjectOutcome:
        return self.rest[i]

    def __len__(self) -> int:
        return len(self.rest)

    def update(self, done: list[tuple[int, ObjectOutcome]]) -> None:
        for i, outcome in done:
            self[i] = outcome


def _run_chunk(
    model: Any, chunk: list[ObjectPlan], epochs: np.ndarray, cfg: RunSettings
) -> list[tuple[int, ObjectOutcome]]:
    """A Dask task: run the objects of the chunk (the model arrives unpickled once per
    worker); CCSPs in one core call per chunk."""
    if isinstance(cfg.method, Ccsp):
        return _ccsp_chunk(model, chunk, epochs, cfg)
    return [(p.index, _run_object(p, model, epochs, cfg)) for p in chunk]


def _lost_with_a_worker(err: BaseException) -> bool:
    """Whether a Dask future failed because the cluster lost its work (a dying worker, a
    cancelled future, a closed connection) rather than because the task raised."""
    if isinstance(err, (cf.CancelledError, OSError, TimeoutError)):
        return True
    try:
        from distributed.scheduler import KilledWorker
    except ImportError:  # pragma: no cover - a client implies distributed
        return False
    return isinstance(err, KilledWorker)


def _run_on_dask(
    client: Any,
    model: Any,
    chunks: list[list[ObjectPlan]],
    epochs: np.ndarray,
    cfg: RunSettings,
    bar: Callable[[int], object] | None,
    results: Outcomes,
) -> Outcomes:
    """Runs the chunks on a Dask cluster, into ``results``. The atmosphere is scattered to
    every worker once (broadcast); tasks retry twice; a chunk whose task is lost with a
    dying worker (or whose scattered atmosphere went with it) is submitted again, up to
    three rounds, so no object is lost and none is counted twice (results are keyed by
    object index). An exception the task itself raised is raised here at once, with its
    own type."""
    pending = list(range(len(chunks)))
    last: BaseException | None = None
    for _ in range(3):
        # A fresh random key (hash=False), never the content's hash: the same model
        # scattered by the run before may still be being released under its hashed key,
        # and a broadcast that reused it once hung the test suite (the workers looped
        # asking each other for data neither held). It also saves hashing a big field.
        shared = client.scatter(model, broadcast=True, hash=False)
        futures = {
            c: client.submit(_run_chunk, shared, chunks[c], epochs, cfg, retries=2, pure=False)
            for c in pending
        }
        failed = []
        try:
            for c, fut in futures.items():
                try:
                    for i, r in fut.result():
                        results[i] = r
                except Exception as err:
                    if not _lost_with_a_worker(err):
                        raise  # the worker's own exception, type and traceback intact
                    failed.append(c)
                    last = err
                if bar is not None:
                    bar(len(results))
        except BaseException:
            client.cancel(list(futures.values()))
            raise
        if not failed:
            return results
        pending = failed
    assert last is not None
    if hasattr(last, "add_note"):
        last.add_note(f"{len(pending)} catalog chunks were lost on the cluster three times")
    raise last


def by_epoch(plans: list[ObjectPlan]) -> list[ObjectPlan]:
    """The plans in epoch order: chunks of objects close in time share their atlas tiles,
    so the tiles in use at once stay few however the epochs spread."""
    return sorted(plans, key=lambda plan: plan.obj.state.epoch)


def _run_local(
    plans: list[ObjectPlan],
    shipped: Any,
    epochs: np.ndarray,
    cfg: RunSettings,
    bar: Callable[[int], object] | None,
    results: Outcomes,
) -> Outcomes:
    """Objects on threads, into ``results`` (the core releases the GIL), each also parallel
    over its own sigma points or members. Ctrl-C (or an error) cancels the objects not started and
    stops running Monte Carlos at once; a running CCSP finishes its object first."""
    stop = threading.Event()
    workers = worker_count()

    def tick(_i: int, _result: object) -> None:
        if bar is not None:
            bar(len(results))

    if isinstance(cfg.method, Ccsp):
        # Chunks of objects per core call (objects in parallel there), small enough that
        # every worker gets several.
        size = max(1, min(CCSP_CHUNK, -(-len(plans) // (4 * workers))))
        indexed = by_epoch(plans)
        chunks = [indexed[c : c + size] for c in range(0, len(indexed), size)]

        def chunk_done(i: int, done: list[tuple[int, ObjectOutcome]]) -> None:
            results.update(done)
            tick(i, done)

        map_in_threads(
            lambda chunk: _ccsp_chunk(shipped, chunk, epochs, cfg, stop),
            chunks,
            workers,
            stop,
            chunk_done,
        )
    else:

        def object_done(i: int, result: ObjectOutcome) -> None:
            results[i] = result
            tick(i, result)

        map_in_threads(
            lambda plan: _run_object(plan, shipped, epochs, cfg, stop),
            plans,
            workers,
            stop,
            object_done,
        )
    return results
