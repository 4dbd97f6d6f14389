"""Pc of every event an all-on-all screen finds, per density model and for their
mixture, from each object's propagated covariance.

Per model k, the objects in events are propagated with the catalog's CCSP
(:func:`rhoprop.catalog.propagate_catalog` defaults: each object's own covariance,
Cd*A/m uncertainty) with their Cd debiased against the reference model (the mean density
ratio over the 8 h before the epoch along the reference orbit, as
:func:`rhoprop.debias_drag_coefficient`, sampled every :data:`DEBIAS_CADENCE` s). At an
event's TCA each object's model-k Gaussian is centred on its screened state plus the
model's mean offset from the reference model's mean, with the model's covariance: each
object's CCSP gives its outputs at its own TCAs (and updates there, besides hourly:
:func:`~rhoprop.catalog.run.propagate_to_own_epochs`), where offset and covariance are
taken in the RTN frame of the reference model's mean and turned into inertial axes with
the RTN frame of the screened state. Both objects fly through the same
atmosphere, so the mixture's Pc is ``sum_k w_k Pc_k`` (as
:func:`~rhoprop.conjunction.density_pc`). An event before an object's epoch uses the
object's covariance at its epoch and no offset.
"""

from __future__ import annotations

import dataclasses
import time
from collections import defaultdict
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import frames
from ..catalog.covariance import tle_covariance
from ..catalog.elements import CatalogObject
from ..catalog.run import OwnEpochsResult, propagate_to_own_epochs
from ..ensemble.combine import default_spread, default_weights
from ..ensemble.debias import DEBIAS_WINDOW, backward_orbit
from ..propagation import Dynamics, Spacecraft
from ..propagation.results import rtn_basis as nan_tolerant_rtn_basis
from ..time import seconds_between
from .encounter import encounter_check, pc_interval
from .kernel import CloseApproach, EventPlan, catalog_object
from .probability import PcResult, pc_2d
from .settings import PcSettings

__all__ = ["DEBIAS_CADENCE", "DEBIAS_WINDOW", "RADII", "object_radius"]

#: Radius of an object's circumscribing sphere by kind, m, when no table gives it: the
#: hard-body radius of an event is the sum of both. Payloads 5 m (a Starlink with its
#: array spans ~9-10 m end to end), rocket bodies 5 m (upper stages are ~3-12 m long),
#: debris 1 m (most tracked fragments are 10 cm to 1 m). Kind from the catalog name:
#: "R/B" a rocket body, "DEB" debris, else a payload.
RADII = {"payload": 5.0, "rocket body": 5.0, "debris": 1.0}
#: Cd debiasing: sample spacing along the reference orbit, s (the window before each epoch
#: is the ensemble's, :data:`~rhoprop.ensemble.debias.DEBIAS_WINDOW`).
DEBIAS_CADENCE = 600.0
#: Objects whose epochs lie within this of each other share one catalog run (their
#: atmosphere's day tiles), s.
BATCH_EPOCH_SPREAD = 2 * 86400.0
BATCH_SIZE = 100


def object_radius(name: str) -> float:
    """Circumscribing radius of an object from its catalog name (:data:`RADII`), m."""
    upper = name.upper()
    if "R/B" in upper:
        return RADII["rocket body"]
    if "DEB" in upper:
        return RADII["debris"]
    return RADII["payload"]


@dataclass(frozen=True)
class EventPcs:
    """Per event: Pc per model (events, models), mixture Pc, hard-body radius m, note,
    and both objects' reference-model covariances at TCA in their RTN axes (events, 6, 6)
    (NaN where not available, or without Pc), and per event which Pc was used ("2d",
    "interval" where a model's encounter was not short, "" without Pc), and the reference
    model's maximum Pc over covariance scalings and dilution flag (NaN / False where its
    Pc is not a 2-D one)."""

    weights: np.ndarray
    pc_models: np.ndarray
    pc: np.ndarray
    hard_body_radius: np.ndarray
    notes: list[str]
    covariance1: np.ndarray
    covariance2: np.ndarray
    drag: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    index: dict[int, int] = dataclasses.field(default_factory=dict)
    methods: list[str] = dataclasses.field(default_factory=list)
    pc_max: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0))
    dilution: np.ndarray = dataclasses.field(default_factory=lambda: np.empty(0, dtype=bool))
    spread: float = 1.0


def _weights(models: dict[str, Any], weights: Any) -> np.ndarray:
    names = list(models)
    if weights is None:
        w = default_weights(models)
    else:
        if set(weights) != set(names):
            raise ValueError(f"weights must name exactly the models {names}, got {list(weights)}")
        w = np.array([float(weights[n]) for n in names])
    if not np.isfinite(w).all() or (w < 0).any() or w.sum() <= 0:
        raise ValueError(f"weights must be finite, non-negative and not all 0, got {w}")
    return np.asarray(w / w.sum())


def check_weights(models: dict[str, Any], weights: Mapping[str, float] | None) -> None:
    """The Pc weights checked against the models before any work (ValueError/TypeError
    naming them)."""
    _weights(models, weights)


def _radii(events: list[Any], hbr: float | None, radii: Any) -> np.ndarray:
    if hbr is not None:
        return np.full(len(events), float(hbr))
    table = dict(radii or {})

    def one(name: str, oid: int | None) -> float:
        return float(table[oid]) if oid in table else object_radius(name)

    return np.array([one(e.name1, e.id1) + one(e.name2, e.id2) for e in events])


#: Points of the debiasing's density evaluations per model call: a model library call
#: holds the interpreter, so the run reports (and its log's heartbeat runs) between them.
DEBIAS_BLOCK = 20_000


def debiased_drag(
    objs: list[Any],
    models: dict[str, Any],
    ref: str,
    report: Callable[[str, int, int], object] | None = None,
) -> dict[str, np.ndarray]:
    """Per model, each object's Cd*A/m debiased against the reference (m^2/kg);
    ``report(stage, done, total)`` hears of the objects' backward orbits and then of the
    density evaluations."""
    base = np.array([o.craft.drag_parameter for o in objs])
    out = {ref: base}
    others = [k for k in models if k != ref]
    if not others or not objs:
        return out
    epochs, pts, owner = [], [], []
    for m, o in enumerate(objs):
        if report is not None and m % 100 == 0:
            report("Pc (Cd debiasing: orbits)", m, len(objs))
        ep, pos = backward_orbit(
            o.state,
            Spacecraft(1.0, o.craft.drag_parameter),
            o.model,
            DEBIAS_WINDOW,
            DEBIAS_CADENCE,
        )
        epochs.append(ep)
        pts.append(pos)
        owner.append(np.full(len(ep), m))
    ep_all, pos_all = np.concatenate(epochs), np.concatenate(pts)
    who = np.concatenate(owner)
    lla = frames.geodetic(frames.inertial_to_fixed(ep_all, pos_all))
    where = (ep_all, lla[:, 0], lla[:, 1], lla[:, 2])
    names = [ref, *others]
    blocks = range(0, len(ep_all), DEBIAS_BLOCK)
    rho: dict[str, np.ndarray] = {name: np.empty(len(ep_all)) for name in names}
    done, total = 0, len(names) * len(blocks)
    for name in names:
        for lo in blocks:
            part = tuple(w[lo : lo + DEBIAS_BLOCK] for w in where)
            rho[name][lo : lo + DEBIAS_BLOCK] = np.asarray(models[name].mean_std(*part)[0])
            done += 1
            if report is not None:
                report("Pc (Cd debiasing: densities)", done, total)
    rho_ref = rho[ref]
    for k in others:
        ratio = rho_ref / rho[k]
        mean_ratio = np.bincount(who, ratio, len(objs)) / np.bincount(who, None, len(objs))
        out[k] = base * mean_ratio
    return out


def check_coverage(models: dict[str, Any], first: np.datetime64, last: np.datetime64) -> None:
    """Fails before any work if a model cannot give densities from the debiasing window
    before ``first`` to ``last`` (its drivers' or index files' span): ValueError naming
    the model and why."""
    span = np.array([first - np.timedelta64(int(DEBIAS_WINDOW), "s"), last], dtype="datetime64[ns]")
    for name, model in models.items():
        try:
            model.mean_std(span, np.zeros(2), np.zeros(2), np.full(2, 400e3))
        except (ValueError, OSError) as err:
            raise ValueError(
                f"density model {name!r} cannot cover the screening and its Pc, {span[0]} "
                f"to {span[1]} UTC: {err}"
            ) from err


def _batches(cats: list[CatalogObject]) -> list[list[int]]:
    """Indices grouped by epoch (sorted), each group within :data:`BATCH_EPOCH_SPREAD`."""
    order = sorted(range(len(cats)), key=lambda m: cats[m].state.epoch)
    groups: list[list[int]] = []
    for m in order:
        if (
            groups
            and len(groups[-1]) < BATCH_SIZE
            and seconds_between(cats[groups[-1][0]].state.epoch, cats[m].state.epoch)
            <= BATCH_EPOCH_SPREAD
        ):
            groups[-1].append(m)
        else:
            groups.append([m])
    return groups


def _rtn_moments(mean: np.ndarray, cov: np.ndarray, ref: np.ndarray) -> tuple[Any, Any]:
    """Position offsets of ``mean`` from ``ref`` (nt, 3) and ``mean``'s state covariances
    (nt, 6, 6), in the RTN axes of ``ref`` (position and velocity blocks rotated alike,
    as a CDM gives them); NaN where ``ref`` is (an output before the object's epoch)."""
    basis = nan_tolerant_rtn_basis(ref[:, :3], ref[:, 3:])
    off = np.einsum("tij,tj->ti", basis, mean[:, :3] - ref[:, :3])
    b6 = np.zeros((len(basis), 6, 6))
    b6[:, :3, :3] = b6[:, 3:, 3:] = basis
    return off, np.einsum("tij,tjk,tlk->til", b6, cov, b6)


def event_probabilities(
    plan: EventPlan,
    settings: PcSettings,
    enabled: bool,
    timings: dict[str, float],
    *,
    client: object = None,
    report: Callable[[str, int, int], object] | None = None,
) -> EventPcs:
    """Pc per event and model and the mixture's (see the module docs) with ``settings``'
    weights and radii (computed only when ``enabled``); ``client`` (a
    ``distributed.Client``) runs the CCSP on Dask, ``report(stage, done, total)`` is told
    the objects done; an encounter too slow for the 2-D Pc gets
    :func:`~rhoprop.conjunction.encounter.pc_interval`, its draws seeded with
    ``settings.seed`` and the event's index."""
    weights, seed = settings.weights, settings.seed
    events, pairs, objs, models = plan.events, plan.pairs, plan.objects, plan.models
    ref, cfg = plan.reference, plan.window
    w = _weights(models, weights)
    # The calibrated families with their calibrated weights mix as rp.ensemble does: each
    # model's density sigma times the calibrated spread.
    spread = default_spread(models) if weights is None else 1.0
    radius = _radii(events, settings.hard_body_radius, settings.radii)
    n_ev, n_mod = len(events), len(models)
    pcm = np.full((n_ev, n_mod), np.nan)
    notes = [""] * n_ev
    cov = np.full((2, n_ev, 6, 6), np.nan)
    if not enabled or not n_ev:
        return EventPcs(
            w,
            pcm,
            np.full(n_ev, np.nan),
            radius,
            notes,
            cov[0],
            cov[1],
            methods=[""] * n_ev,
            pc_max=np.full(n_ev, np.nan),
            dilution=np.zeros(n_ev, dtype=bool),
            spread=spread,
        )
    involved = sorted({i for p in pairs for i in p})
    local = {g: m for m, g in enumerate(involved)}
    sub = [objs[g] for g in involved]
    t0 = time.perf_counter()
    drag = debiased_drag(sub, models, ref, report)
    timings["pc_drag"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    # Where each object is needed: (event, side) at each TCA.
    needs: dict[int, list[tuple[int, int]]] = defaultdict(list)
    for e, (i, j) in enumerate(pairs):
        needs[local[i]].append((e, 0))
        needs[local[j]].append((e, 1))
    moments = _model_moments(events, sub, models, ref, drag, needs, cfg, spread, client, report)
    timings["pc_covariance"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    methods = [""] * n_ev
    top = np.full(n_ev, np.nan)
    diluted = np.zeros(n_ev, dtype=bool)
    for e, ev in enumerate(events):
        for k, name in enumerate(models):
            pcm[e, k], why, how, res = _pc_one(ev, moments, name, e, float(radius[e]), seed + e)
            if name == ref and res is not None:
                highest = res.maximum()
                top[e], diluted[e] = highest.pc_max, highest.dilution
            if why and why not in notes[e]:
                notes[e] = f"{notes[e]}; {why}" if notes[e] else why
            if how == "interval" or (how and not methods[e]):
                methods[e] = how
        if report is not None:
            report("Pc (per event)", e + 1, n_ev)
    have = np.isfinite(pcm)
    wk = np.where(have, w[None, :], 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        pc = np.where(have.any(axis=1), np.nansum(pcm * wk, axis=1) / wk.sum(axis=1), np.nan)
    for (name, e, side), (_off, c6, _note) in moments.items():
        if name == ref:
            cov[side, e] = c6
    timings["pc"] = time.perf_counter() - t0
    return EventPcs(
        w, pcm, pc, radius, notes, cov[0], cov[1], drag, local, methods, top, diluted, spread
    )


#: Per (model, event, side): (RTN offset (3,), RTN covariance (6, 6), note) at TCA.
_Moments = dict[tuple[str, int, int], tuple[np.ndarray, np.ndarray, str]]


def _model_moments(
    events: list[CloseApproach],
    sub: list[Any],
    models: dict[str, Any],
    ref: str,
    drag: dict[str, np.ndarray],
    needs: dict[int, list[tuple[int, int]]],
    cfg: Any,
    spread: float,
    client: Any,
    report: Any,
) -> _Moments:
    """CCSP per model (in epoch batches, each object to its own TCAs) and each needed
    (event, side)'s moments."""
    cats = [catalog_object(o) for o in sub]
    out: _Moments = {}
    done = 0
    for batch in _batches(cats):
        tcas = {m: _own_tcas(cats[m], events, needs[m]) for m in batch}
        running = [m for m in batch if len(tcas[m])]
        row = {m: b for b, m in enumerate(running)}
        base: OwnEpochsResult | None = None  # the reference model's run (models hold it first)
        for name, model in models.items():
            res = None
            if running:
                res = propagate_to_own_epochs(
                    [
                        dataclasses.replace(cats[m], drag_parameter=float(drag[name][m]))
                        for m in running
                    ],
                    model,
                    [tcas[m] for m in running],
                    dynamics=Dynamics(
                        zonal_degree=cfg.dynamics.zonal_degree,
                        floor_altitude=cfg.dynamics.floor_altitude,
                        step=cfg.dynamics.step,
                    ),
                    sigma_scale=spread,
                    client=client,
                )
            base = res if name == ref else base
            # One model's run at a time is held (with the reference's): bounded memory.
            for m in batch:
                # An object needed only before its epoch is not run (no row): None.
                runs = None
                if res is not None and base is not None and m in row:
                    runs = (res, base, row[m], tcas[m])
                _object_moments(events, cats[m], name, runs, needs[m], out)
        done += len(batch)
        if report is not None:
            report("Pc (CCSP per model)", done, len(cats))
    return out


def _own_tcas(
    cat: CatalogObject, events: list[CloseApproach], needs: list[tuple[int, int]]
) -> np.ndarray:
    """The TCAs (datetime64[ns], increasing, unique) an object is needed at after its
    epoch."""
    tcas = np.unique(np.array([events[e].tca for e, _ in needs], dtype="datetime64[ns]"))
    return tcas[tcas > cat.state.epoch]


def _object_moments(
    events: list[CloseApproach],
    cat: CatalogObject,
    name: str,
    runs: tuple[OwnEpochsResult, OwnEpochsResult, int, np.ndarray] | None,
    needs: list[tuple[int, int]],
    out: _Moments,
) -> None:
    """One object's moments under model ``name`` at the TCAs it is needed at (in
    ``out``); ``runs``: that model's run and the reference model's, the object's row in
    them and its TCAs (None when every TCA is before its epoch)."""
    if runs is not None:
        res, base, b, tcas = runs
        k = len(tcas)
        valid = res.valid[b, :k] & base.valid[b, :k]
        off, cov = _rtn_moments(res.mean[b, :k], res.covariance[b, :k], base.mean[b, :k])
    for e, side in needs:
        tca = events[e].tca
        if runs is None or tca <= cat.state.epoch:
            c0 = cat.covariance if cat.covariance is not None else tle_covariance(cat.state)
            basis = frames.rtn_basis(cat.state.position, cat.state.velocity)
            b6 = np.zeros((6, 6))
            b6[:3, :3] = b6[3:, 3:] = basis
            note = "an object's epoch is after TCA: its covariance at epoch"
            out[name, e, side] = (np.zeros(3), b6 @ c0 @ b6.T, note)
            continue
        j = int(np.searchsorted(tcas, tca))
        if not valid[j]:
            out[name, e, side] = (np.full(3, np.nan), np.full((6, 6), np.nan), "")
            continue
        out[name, e, side] = (
            off[j],
            cov[j],
            f"{name}: {cat.name}'s spread curves along its orbit at TCA (its Gaussian "
            "does not hold the shape): the 2-D Pc is approximate"
            if not res.gaussian[b, j]
            else "",
        )


def _pc_one(
    ev: CloseApproach, moments: _Moments, name: str, e: int, hbr: float, seed: int = 0
) -> tuple[float, str, str, PcResult | None]:
    """The event's Pc under one model, a note, which Pc: "2d" (short encounter),
    "interval" (:func:`pc_interval` over the encounter, capped at half an orbital period:
    the 2-D model's straight-line assumption fails, :func:`encounter_check`), "" (NaN: a
    minimum at the window's edge, no covariance); and the 2-D result (or None)."""
    if ev.edge is not None:
        return (
            float("nan"),
            (
                f"minimum at the window's {ev.edge}: no short-encounter Pc (the closest "
                "approach may lie outside the window)"
            ),
            "",
            None,
        )
    parts = []
    for side, state in ((0, ev.state1), (1, ev.state2)):
        off, cov, note = moments[name, e, side]
        if not np.isfinite(off).all():
            return (
                float("nan"),
                f"{name}: no valid covariance at TCA (decayed or shortened)",
                "",
                None,
            )
        basis = frames.rtn_basis(state[:3], state[3:])
        b6 = np.zeros((6, 6))
        b6[:3, :3] = b6[3:, 3:] = basis
        parts.append((state[:3] + basis.T @ off, state[3:], b6.T @ cov @ b6, note))
    (r1, v1, c1, n1), (r2, v2, c2, n2) = parts
    said = "; ".join(n for n in (n1, n2) if n)
    check = encounter_check(r1, v1, c1, r2, v2, c2, hbr)
    if not check.short:
        span = min(check.duration, 0.5 * check.period)
        if not np.isfinite(span):
            return float("nan"), f"{name}: no Pc ({check.describe()}: no bound orbit)", "", None
        res_i = pc_interval(r1, v1, c1, r2, v2, c2, hbr, span=span, seed=seed)
        why = (
            f"{name}: not a short encounter ({check.describe()}): Pc counted over "
            f"{span:.4g} s about TCA from {res_i.samples} samples (Clohessy-Wiltshire), "
            "not the 2-D Pc"
        )
        return res_i.pc, f"{why}; {said}" if said else why, "interval", None
    res = pc_2d(r1, v1, c1[:3, :3], r2, v2, c2[:3, :3], hbr)
    return float(res.pc), said, "2d", res
