"""Catalogs: TLE and CCSDS OMM input through ``sgp4``, CCSP or Monte Carlo over many
objects from their own epochs to a common end epoch, locally or on a Dask cluster, decay
prediction, CCSDS OEM and Parquet output.

Frames: the SGP4 state at an element set's epoch is in TEME, which rhoprop takes as its
inertial frame (the difference to J2000 is a slow precession-nutation rotation that the
design contract neglects). Drag: Cd*A/m = 2 B* / rho0 with B* in 1/Earth radii and
rho0 = 0.15696615 kg m^-2 ER^-1 (the SGP4 reference density 2.461e-8 kg/m^3 times one Earth
radius), i.e. 12.7416 B* m^2/kg, unless the caller gives a drag parameter per object.
"""

from __future__ import annotations

import csv
import io
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import _validate
from ._core import RhopropError
from .ccsp import ccsp
from .density.base import SampledModel, altitude_band
from .density.exponential import Exponential
from .density.field import DensityField
from .epochs import J2000, EpochLike, offsets_to_epochs, to_datetime64
from .kappa import KappaProcess
from .orbit import DEFAULT_FLOOR_ALTITUDE, OrbitState, Spacecraft, propagate

#: SGP4 reference density times one Earth radius, kg m^-2 ER^-1 (B* = rho0 B / 2).
SGP4_RHO0 = 0.15696615


def drag_parameter_from_bstar(bstar: float) -> float:
    """Cd*A/m (m^2/kg) from an SGP4 B* (1/Earth radii): 2 B* / rho0."""
    return 2.0 * bstar / SGP4_RHO0


@dataclass(frozen=True)
class CatalogObject:
    """One element set: ``state`` at its epoch (TEME taken as inertial), the drag
    parameter Cd*A/m (m^2/kg), B* (1/ER) and where it came from."""

    name: str
    norad_id: int
    state: OrbitState
    drag_parameter: float
    bstar: float
    source: str


@dataclass
class Catalog:
    """Objects read from a file, and the entries skipped (with ``errors="skip"``) as
    (where, message) pairs."""

    objects: list[CatalogObject]
    skipped: list[tuple[str, str]] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.objects)

    def __iter__(self):
        return iter(self.objects)

    def __getitem__(self, i: int) -> CatalogObject:
        return self.objects[i]


def _object_from_satrec(sat: Any, name: str, where: str, drag: float | None) -> CatalogObject:
    from sgp4.api import SGP4_ERRORS

    err, r, v = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
    if err:
        raise ValueError(f"{where}: SGP4 error {err} at the epoch: {SGP4_ERRORS.get(err, '')}")
    days = (sat.jdsatepoch - 2451545.0) + sat.jdsatepochF
    epoch = J2000 + np.timedelta64(round(days * 86400e9), "ns")
    bstar = float(sat.bstar)
    if drag is None:
        if not bstar > 0:
            raise ValueError(
                f"{where}: B* = {bstar} is not positive, so no drag parameter follows from it; "
                "give drag_parameters for this object"
            )
        drag = drag_parameter_from_bstar(bstar)
    state = OrbitState(epoch, np.array(r) * 1e3, np.array(v) * 1e3)
    return CatalogObject(name or str(sat.satnum), int(sat.satnum), state, drag, bstar, where)


def _checksum_ok(line: str) -> bool:
    total = sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68])
    return line[68].isdigit() and total % 10 == int(line[68])


def _parse_tle(text: str, path: str) -> list[tuple[str, Any]]:
    """(where, callable returning an object) per TLE in ``text``."""
    from sgp4.api import Satrec

    lines = [(i + 1, ln.rstrip()) for i, ln in enumerate(text.splitlines()) if ln.strip()]
    entries = []
    k = 0
    while k < len(lines):
        name = ""
        _n0, first = lines[k]
        if not first.startswith("1 ") and k + 1 < len(lines) and lines[k + 1][1].startswith("1 "):
            name = first[2:].strip() if first.startswith("0 ") else first.strip()
            k += 1
        if k + 1 >= len(lines):
            entries.append((f"{path} line {lines[k][0]}", ValueError("a TLE needs two lines")))
            break
        (n1, l1), (n2, l2) = lines[k], lines[k + 1]
        k += 2
        where = f"{path} lines {n1}-{n2}"
        problem = None
        for n, ln, tag in ((n1, l1, "1"), (n2, l2, "2")):
            if not ln.startswith(tag + " "):
                problem = f"line {n} should start with '{tag} '"
            elif len(ln) < 69:
                problem = f"line {n} has {len(ln)} characters, a TLE line has 69"
            elif not _checksum_ok(ln):
                problem = f"line {n} fails its checksum (column 69)"
            if problem:
                break
        if problem is None and l1[2:7] != l2[2:7]:
            problem = f"catalog numbers differ: {l1[2:7]!r} on line {n1}, {l2[2:7]!r} on line {n2}"
        if problem:
            entries.append((where, ValueError(f"{where}: {problem}")))
            continue
        try:
            sat = Satrec.twoline2rv(l1, l2)
        except (ValueError, IndexError) as err:
            entries.append((where, ValueError(f"{where}: unreadable field: {err}")))
            continue
        entries.append((where, (sat, name)))
    return entries


def _parse_omm(text: str, path: str) -> list[tuple[str, Any]]:
    from sgp4 import omm
    from sgp4.api import Satrec

    stripped = text.lstrip()
    if stripped.startswith(("[", "{")):
        data = json.loads(text)
        records = data if isinstance(data, list) else [data]
        kind = "JSON"
    elif stripped.startswith("<"):
        records = list(omm.parse_xml(io.StringIO(text)))
        kind = "XML"
    else:
        records = list(csv.DictReader(io.StringIO(text)))
        kind = "CSV"
    entries = []
    for i, rec in enumerate(records):
        where = f"{path} {kind} record {i}"
        if not isinstance(rec, dict):
            entries.append((where, ValueError(f"{where}: not a record")))
            continue
        sat = Satrec()
        try:
            omm.initialize(sat, rec)
        except KeyError as err:
            entries.append((where, ValueError(f"{where}: missing field {err}")))
            continue
        except (ValueError, TypeError) as err:
            entries.append((where, ValueError(f"{where}: unreadable field: {err}")))
            continue
        entries.append((where, (sat, str(rec.get("OBJECT_NAME", "")).strip())))
    return entries


def load(
    path: str | Path, *, errors: str = "raise", drag_parameters: dict[int, float] | None = None
) -> Catalog:
    """Reads a TLE file (2- or 3-line) or a CCSDS OMM file (JSON, CSV or XML as CelesTrak
    serves them), detected by content.

    Args:
        path: the file.
        errors: ``"raise"`` (default): the first malformed line/record raises ValueError
            naming it and the field; ``"skip"``: it is skipped and listed in
            ``Catalog.skipped``.
        drag_parameters: optional {NORAD id: Cd*A/m (m^2/kg)} overriding B*.
    """
    if errors not in ("raise", "skip"):
        raise ValueError(f"errors must be 'raise' or 'skip', got {errors!r}")
    p = Path(path)
    text = p.read_text()
    head = text.lstrip()[:200]
    is_omm = head.startswith(("[", "{", "<")) or "NORAD_CAT_ID" in head or "OBJECT_NAME" in head
    entries = _parse_omm(text, p.name) if is_omm else _parse_tle(text, p.name)
    out = Catalog([])
    for where, item in entries:
        try:
            if isinstance(item, Exception):
                raise item
            sat, name = item
            drag = (drag_parameters or {}).get(int(sat.satnum))
            out.objects.append(_object_from_satrec(sat, name, where, drag))
        except ValueError as err:
            if errors == "raise":
                raise
            out.skipped.append((where, str(err)))
    if not out.objects and not out.skipped:
        raise ValueError(f"{p} holds no TLE or OMM element sets")
    return out


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


def _payload(model: Any, objects: list[CatalogObject], end: np.datetime64) -> tuple:
    """A picklable description of the atmosphere for all objects: one field covering every
    object's altitude band from the earliest epoch to the end."""
    if isinstance(model, Exponential):
        return ("exponential", (model.rho0, model.h0, model.scale_height, model.rel_sigma))
    if isinstance(model, SampledModel):
        lows, highs = zip(
            *(altitude_band(o.state.position, o.state.velocity) for o in objects), strict=True
        )
        start = min(o.state.epoch for o in objects)
        model = model.field(start, end, altitude_range=(max(min(lows), 0.0), max(highs)))
    if isinstance(model, DensityField):
        return (
            "field",
            (
                str(model.epoch),
                model.times,
                model.altitudes,
                model.latitudes,
                model.longitudes,
                model.ln_mean,
                model.rel_sigma,
            ),
        )
    raise TypeError(f"model must be a density model or DensityField, got {type(model).__name__}")


def _model_from_payload(payload: tuple) -> Any:
    kind, args = payload
    if kind == "exponential":
        return Exponential(*args)
    return DensityField.from_arrays(*args)


def _run_object(obj: CatalogObject, model: Any, epochs: np.ndarray, index: int, cfg: dict) -> dict:
    """Propagates one object to the common epochs; returns arrays for the result."""
    craft = Spacecraft(1.0, obj.drag_parameter)
    offsets = (epochs - obj.state.epoch).astype(np.int64) * 1e-9
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
    decay_ns = -1 if decay is None else round(decay * 1e9)
    return {
        "mean": out_mean,
        "cov": out_cov,
        "valid": valid,
        "decay_ns": decay_ns,
        "fraction": fraction,
    }


def _mc_moments(obj, model, craft, offsets, cfg, index):
    """Sample mean and covariance of a Monte Carlo at the given offsets (s), and the
    fraction of members that decayed."""
    from . import _core
    from .density.base import as_atmosphere
    from .epochs import seconds_since_j2000

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
    mean = states.mean(axis=0)
    d = states - mean[None]
    cov = np.einsum("nti,ntj->tij", d, d) / (states.shape[0] - 1)
    return mean, cov, float(np.mean(np.isfinite(out["decay_times"])))


def _update_times(offsets: np.ndarray, interval: float) -> np.ndarray:
    """CCSP update times: every ``interval`` s, plus every output offset."""
    grid = np.arange(interval, offsets[-1], interval)
    times = np.unique(np.concatenate([grid, offsets[offsets > 0]]))
    return times if len(times) else np.array([offsets[-1]])


def _run_chunk(
    payload: tuple, chunk: list[tuple[int, CatalogObject]], epochs: np.ndarray, cfg: dict
) -> list[tuple[int, dict]]:
    """A Dask task: rebuild the atmosphere once, run the objects of the chunk."""
    model = _model_from_payload(payload)
    return [(i, _run_object(o, model, epochs, i, cfg)) for i, o in chunk]


def _run_on_dask(
    client: Any, payload: tuple, chunks: list, epochs: np.ndarray, cfg: dict, progress: bool
) -> dict[int, dict]:
    """Runs the chunks on a Dask cluster. The atmosphere is scattered to every worker once
    (broadcast); tasks retry twice; a chunk whose task is lost with a dying worker (or
    whose scattered atmosphere went with it) is submitted again, up to three rounds, so no
    object is lost and none is counted twice (results are keyed by object index)."""
    import sys

    results: dict[int, dict] = {}
    pending = list(range(len(chunks)))
    for _ in range(3):
        shared = client.scatter(payload, broadcast=True)
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
        if progress and sys.stderr.isatty():
            sys.stderr.write(f"\rcatalog: {len(chunks) - len(failed)}/{len(chunks)} chunks")
        if not failed:
            return results
        pending = failed
    raise RuntimeError(f"{len(pending)} catalog chunks failed on the cluster three times")


def common_epochs(objects: list[CatalogObject], end: np.datetime64, step: float) -> np.ndarray:
    """Output epochs shared by all objects: end, end - step, ... not before the latest
    object epoch (at least the end itself)."""
    latest = max(o.state.epoch for o in objects)
    span = float((end - latest) / np.timedelta64(1, "ns")) * 1e-9
    k = int(np.floor(span / step * (1 + 1e-12)))
    offsets = -step * np.arange(k, -1, -1)
    return offsets_to_epochs(end, offsets)


def propagate_catalog(
    objects: Any,
    model: Any,
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
        progress: print progress to stderr.
    """
    import sys

    from .kappa import GaussMarkov

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
    payload = _payload(model, objs, end64)
    indexed = list(enumerate(objs))
    chunks = [indexed[i : i + chunk_size] for i in range(0, len(indexed), chunk_size)]
    results: dict[int, dict] = {}
    if client is None:
        # Objects run concurrently on threads (the core releases the GIL), each also
        # parallel over its own sigma points or members.
        from concurrent.futures import ThreadPoolExecutor

        local = _model_from_payload(payload)
        workers = os.cpu_count() or 1
        with ThreadPoolExecutor(max_workers=workers) as pool:
            runs = pool.map(lambda item: _run_object(item[1], local, epochs, item[0], cfg), indexed)
            for i, r in enumerate(runs):
                results[i] = r
                if progress and sys.stderr.isatty() and (i + 1) % 10 == 0:
                    sys.stderr.write(f"\rcatalog: {i + 1}/{len(objs)}")
    else:
        results.update(_run_on_dask(client, payload, chunks, epochs, cfg, progress))
    if progress and sys.stderr.isatty():
        sys.stderr.write("\n")
    order = [results[i] for i in range(len(objs))]
    decay = np.array(
        [
            np.datetime64("NaT", "ns")
            if r["decay_ns"] < 0
            else o.state.epoch + np.timedelta64(r["decay_ns"], "ns")
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
