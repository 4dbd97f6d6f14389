"""Catalog runs: CCSP or Monte Carlo over many objects from their own epochs to common
output epochs, locally (objects on threads) or on a Dask cluster, with decay prediction."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _core, _validate
from ..constants import DEFAULT_FLOOR_ALTITUDE
from ..density import DensityModel, SampledModel, altitude_band, as_atmosphere
from ..errors import RhopropError
from ..progress import ProgressBar
from ..propagation import (
    Spacecraft,
    ccsp,
    propagate,
    sample_moments,
)
from ..propagation.kappa import GaussMarkov, KappaProcess
from ..time import (
    EpochLike,
    add_seconds,
    offsets_to_epochs,
    seconds_between,
    seconds_since_j2000,
    to_datetime64,
    to_seconds,
)
from .elements import CatalogObject


@dataclass(frozen=True)
class CatalogResult:
    """Per object mean and covariance on common output epochs.

    Attributes:
        objects: the input objects, in order.
        epochs: common output epochs, datetime64[ns] (nt,).
        mean: mean states (objects, nt, 6), m and m/s (TEME/inertial).
        covariance: covariances (objects, nt, 6, 6), SI.
        valid: False where the object had decayed before that output (its state is then
            the last valid one).
        decay_epoch: predicted decay epoch of the mean orbit, or NaT.
        decay_fraction: Monte Carlo only: fraction of members decayed by the end (else 0).
        method: "ccsp" or "monte_carlo".
    """

    objects: list[CatalogObject]
    epochs: np.ndarray
    mean: np.ndarray
    covariance: np.ndarray
    valid: np.ndarray
    decay_epoch: np.ndarray
    decay_fraction: np.ndarray
    method: str


def _shipped_model(model: Any, objects: list[CatalogObject], end: np.datetime64) -> Any:
    """The atmosphere for all objects, as an object that pickles itself (``__reduce__``)
    to travel to Dask workers: a sampled model becomes one field covering every object's
    altitude band from the earliest epoch to the end; other models travel as they are."""
    if isinstance(model, SampledModel):
        lows, highs = zip(
            *(altitude_band(o.state.position, o.state.velocity) for o in objects), strict=True
        )
        start = min(o.state.epoch for o in objects)
        return model.field(start, end, altitude_range=(max(min(lows), 0.0), max(highs)))
    if not callable(getattr(model, "atmosphere", None)):
        raise TypeError(
            f"model must be a density model or DensityField, got {type(model).__name__}"
        )
    return model


def _run_object(
    obj: CatalogObject, model: Any, epochs: np.ndarray, index: int, cfg: dict[str, Any]
) -> dict[str, Any]:
    """Propagates one object to the common epochs; returns arrays for the result."""
    craft = Spacecraft(1.0, obj.drag_parameter)
    offsets = to_seconds(epochs, obj.state.epoch)
    nt = len(epochs)
    end = float(offsets[-1])
    mean = propagate(
        obj.state,
        craft,
        model,
        end,
        method="rk8",
        floor_altitude=cfg["floor_altitude"],
        output_step=None,
    )
    decay = mean.decayed_at
    usable = offsets <= (decay if decay is not None else np.inf)
    out_mean = np.zeros((nt, 6))
    out_cov = np.zeros((nt, 6, 6))
    fraction = 0.0
    k = int(np.count_nonzero(usable))
    if k:
        if cfg["method"] == "ccsp":
            # Close to re-entry the linearised covariance can stop being positive definite:
            # then the outputs from there on are reported invalid (shrink until it holds).
            while k:
                times = _update_times(offsets[:k], cfg["update_interval"])
                try:
                    r = ccsp(
                        obj.state,
                        craft,
                        model,
                        float(times[-1]),
                        update_times=times,
                        floor_altitude=cfg["floor_altitude"],
                    )
                    break
                except RhopropError:
                    k = k - 1 if k < 8 else (3 * k) // 4
            if k:
                pick = np.searchsorted(r.times, offsets[:k])
                out_mean[:k], out_cov[:k] = r.mean[pick], r.covariance[pick]
        else:
            out_mean[:k], out_cov[:k], fraction = _mc_moments(
                obj, model, craft, offsets[:k], cfg, index
            )
    if k < nt:
        out_mean[k:] = (
            out_mean[k - 1] if k else np.concatenate([obj.state.position, obj.state.velocity])
        )
        out_cov[k:] = out_cov[k - 1] if k else 0.0
    valid = np.arange(nt) < k

    return {
        "mean": out_mean,
        "cov": out_cov,
        "valid": valid,
        "decay": decay,
        "fraction": fraction,
    }


def _mc_moments(
    obj: CatalogObject,
    model: Any,
    craft: Spacecraft,
    offsets: np.ndarray,
    cfg: dict[str, Any],
    index: int,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Sample mean and covariance of a Monte Carlo at the given offsets (s), and the
    fraction of members that decayed."""
    atmosphere = as_atmosphere(model, obj.state, float(offsets[-1]))
    out = _core.monte_carlo(
        atmosphere,
        seconds_since_j2000(obj.state.epoch),
        obj.state.state,
        craft.drag_parameter,
        np.asarray(offsets, dtype=float),
        cfg["kappa"]._spec(),
        "additive",
        "rk8",
        180.0,
        int(cfg["n"]),
        int(cfg["seed"] + index),
        None,
        cfg["floor_altitude"],
        False,
        None,
        None,
    )
    states = np.concatenate([out["positions"], out["velocities"]], axis=2)  # (n, nt, 6)
    mean, cov = sample_moments(states)
    return mean, cov, float(np.mean(np.isfinite(out["decay_times"])))


def _update_times(offsets: np.ndarray, interval: float) -> np.ndarray:
    """CCSP update times: every ``interval`` s, plus every output offset."""
    grid = np.arange(interval, offsets[-1], interval)
    times = np.unique(np.concatenate([grid, offsets[offsets > 0]]))
    return times if len(times) else np.array([offsets[-1]])


def _run_chunk(
    model: Any, chunk: list[tuple[int, CatalogObject]], epochs: np.ndarray, cfg: dict[str, Any]
) -> list[tuple[int, dict[str, Any]]]:
    """A Dask task: run the objects of the chunk (the model arrives unpickled once per
    worker)."""
    return [(i, _run_object(o, model, epochs, i, cfg)) for i, o in chunk]


def _run_on_dask(
    client: Any,
    model: Any,
    chunks: list[list[tuple[int, CatalogObject]]],
    epochs: np.ndarray,
    cfg: dict[str, Any],
    bar: ProgressBar | None,
) -> dict[int, dict[str, Any]]:
    """Runs the chunks on a Dask cluster. The atmosphere is scattered to every worker once
    (broadcast); tasks retry twice; a chunk whose task is lost with a dying worker (or
    whose scattered atmosphere went with it) is submitted again, up to three rounds, so no
    object is lost and none is counted twice (results are keyed by object index)."""
    results: dict[int, dict[str, Any]] = {}
    pending = list(range(len(chunks)))
    for _ in range(3):
        shared = client.scatter(model, broadcast=True)
        futures = {
            c: client.submit(_run_chunk, shared, chunks[c], epochs, cfg, retries=2, pure=False)
            for c in pending
        }
        failed = []
        for c, fut in futures.items():
            try:
                for i, r in fut.result():
                    results[i] = r
            except Exception:
                failed.append(c)
        if bar is not None:
            bar(len(results))
        if not failed:
            return results
        pending = failed
    raise RuntimeError(f"{len(pending)} catalog chunks failed on the cluster three times")


def common_epochs(objects: list[CatalogObject], end: np.datetime64, step: float) -> np.ndarray:
    """Output epochs shared by all objects: end, end - step, ... not before the latest
    object epoch (at least the end itself)."""
    latest = max(o.state.epoch for o in objects)
    span = seconds_between(latest, end)
    k = int(np.floor(span / step * (1 + 1e-12)))
    offsets = -step * np.arange(k, -1, -1)
    return offsets_to_epochs(end, offsets)


def propagate_catalog(
    objects: Any,
    model: DensityModel,
    end: EpochLike,
    *,
    method: str = "ccsp",
    n: int = 100,
    kappa: KappaProcess | None = None,
    seed: int = 0,
    output_step: float = 3600.0,
    update_interval: float = 3600.0,
    floor_altitude: float = DEFAULT_FLOOR_ALTITUDE,
    client: Any = None,
    chunk_size: int = 50,
    progress: bool = True,
) -> CatalogResult:
    """Propagates every object from its own epoch to ``end`` (UTC).

    Args:
        objects: a :class:`Catalog` or list of :class:`CatalogObject`.
        model: density model (sampled once into a field covering all objects) or a
            :class:`~rhoprop.density.DensityField` / ``Exponential``.
        end: common end epoch, after every object's epoch.
        method: ``"ccsp"`` (default; ``update_interval`` s) or ``"monte_carlo"`` (``n``
            members, ``kappa`` process, object i seeded with ``seed + i``).
        output_step: spacing of the common output epochs, s, counted back from ``end``.
        client: a ``dask.distributed.Client``: objects are split into chunks of
            ``chunk_size``, the atmosphere is sent once and replicated to every worker
            (recomputed if a worker dies), failed tasks are retried twice; results equal
            the local run.
        progress: show a progress bar (objects done) on a terminal for runs over a second.
    """
    objs = list(objects)
    if not objs:
        raise ValueError("the catalog has no objects")
    if method not in ("ccsp", "monte_carlo"):
        raise ValueError(f"unknown method {method!r}; expected 'ccsp' or 'monte_carlo'")
    end64 = to_datetime64(end, "end")
    late = [o for o in objs if o.state.epoch >= end64]
    if late:
        raise ValueError(
            f"end {end64} is not after the epoch of object {late[0].norad_id} "
            f"({late[0].state.epoch})"
        )
    step = _validate.positive("output_step", output_step)
    cfg = {
        "method": method,
        "n": int(n),
        "kappa": kappa or GaussMarkov(),
        "seed": int(seed),
        "update_interval": _validate.positive("update_interval", update_interval),
        "floor_altitude": _validate.real("floor_altitude", floor_altitude),
    }
    epochs = common_epochs(objs, end64, step)
    shipped = _shipped_model(model, objs, end64)
    indexed = list(enumerate(objs))
    chunks = [indexed[i : i + chunk_size] for i in range(0, len(indexed), chunk_size)]
    results: dict[int, dict[str, Any]] = {}
    bar = ProgressBar(len(objs), "catalog", unit="objects") if progress else None
    if client is None:
        # Objects run concurrently on threads (the core releases the GIL), each also
        # parallel over its own sigma points or members.
        from concurrent.futures import ThreadPoolExecutor

        workers = os.cpu_count() or 1
        with ThreadPoolExecutor(max_workers=workers) as pool:
            runs = pool.map(
                lambda item: _run_object(item[1], shipped, epochs, item[0], cfg), indexed
            )
            for i, r in enumerate(runs):
                results[i] = r
                if bar is not None:
                    bar(i + 1)
    else:
        results.update(_run_on_dask(client, shipped, chunks, epochs, cfg, bar))
    if bar is not None:
        bar.close()
    order = [results[i] for i in range(len(objs))]
    decay = np.array(
        [
            np.datetime64("NaT", "ns")
            if r["decay"] is None
            else add_seconds(o.state.epoch, r["decay"])
            for r, o in zip(order, objs, strict=True)
        ],
        dtype="datetime64[ns]",
    )
    return CatalogResult(
        objects=objs,
        epochs=epochs,
        mean=np.stack([r["mean"] for r in order]),
        covariance=np.stack([r["cov"] for r in order]),
        valid=np.stack([r["valid"] for r in order]),
        decay_epoch=decay,
        decay_fraction=np.array([r["fraction"] for r in order]),
        method=method,
    )
