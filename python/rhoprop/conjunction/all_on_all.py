"""All-on-all screening of a catalog (:func:`screen_all`): every object propagated once
on a common grid, a sieve in the core that keeps only the object pairs and grid
intervals where two objects can come within the distance (spatial grid of the motion's
bounding balls, then the coarse and interpolated distance bounds of one-primary
screening), and the refinement of :mod:`.approach` on what is left; then each event's
probability of collision per density model and for their mixture (:mod:`.event_pc`).
docs/conjunction.md, "All-on-all screening"."""

from __future__ import annotations

import dataclasses
import itertools
import re
import threading
import time
from collections import defaultdict
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .. import _core, _validate
from .._deprecated import fold_keywords
from ..catalog.run import CATALOG_ZONAL_DEGREE, beyond_max_span
from ..constants import J2, R_EARTH
from ..density.model import ModelLike
from ..execution import Execution, execution_argument
from ..options import Errors
from ..parallel import map_in_threads, worker_count
from ..progress import ProgressBar
from ..propagation.dynamics import Dynamics, LooseFloorAndDegree, deprecated_keywords
from ..propagation.propagate import check_model
from ..propagation.results import optional_import
from ..time import EpochLike, add_seconds, seconds_between
from .approach import event_columns
from .event_mc import event_monte_carlo
from .event_pc import EventPcs, check_coverage, check_weights, event_probabilities
from .kernel import (
    CloseApproach,
    EventPlan,
    ScreenedObject,
    TrackDynamics,
    Window,
    as_object,
    make_event,
    models_for,
    radial_ranges,
    secondaries_list,
    window_span,
)
from .screen_stages import DaskStages, Track, core_tracks, refine_slice, track_one
from .screening import (
    HERMITE_SAMPLES,
    MAX_ACCELERATION,
    RADIAL_MARGIN,
    ZONAL_PAD,
    ScreenObject,
)
from .settings import PcSettings, Search

if TYPE_CHECKING:
    import pandas
    from typing_extensions import Unpack

__all__ = ["ALL_ON_ALL_STAGES", "DEFAULT_MAX_MEMORY", "AllOnAllResult", "screen_all"]

#: Memory the tracks of one time chunk may take, bytes (48 B per object and sample).
DEFAULT_MAX_MEMORY = 5e8
#: Names of :attr:`AllOnAllResult.counts`, in the order of the stages.
ALL_ON_ALL_STAGES = (
    "objects",
    "screened",
    "pairs",
    "radial_pairs",
    "spatial",
    "coarse_grid",
    "interpolated",
    "refined_pairs",
    "events",
)
#: What the progress of each stage counts.
STAGE_UNITS = {
    "propagation": "objects",
    "sieve": "grid intervals",
    "refinement": "candidates",
    "Pc (Cd debiasing: orbits)": "objects",
    "Pc (Cd debiasing: densities)": "blocks of 20,000 points",
    "Pc (CCSP per model)": "objects",
    "Pc (per event)": "events",
}
#: Events of one pair closer in time than this are one event (found from two chunks), s.
SAME_EVENT = 1e-3


#: The core's edge codes (``screen_approaches``): a minimum inside the window, at its
#: start, at its end.
EDGES: tuple[Literal["start", "end"] | None, ...] = (None, "start", "end")


@dataclass(frozen=True)
class AllOnAllResult:
    """What :func:`screen_all` found.

    Attributes:
        events: close approaches within ``distance`` (object 1 the one listed first in
            the input), sorted by mixture Pc (largest first), then TCA; without Pc by
            TCA.
        models: the density models' names (reference first); weights: their mixture
            weights; spread: the factor every model's density sigma ran with in the Pc
            stage (1: its own; the calibrated families' default mixture: 0.861).
        pc_models: per event and model, the 2-D Pc (events, models); NaN where a model's
            covariance is not available at TCA (see ``pc_notes``).
        pc: per event the mixture's Pc, sum_k w_k Pc_k over the models with a value
            (weights renormalised).
        hard_body_radius: per event, m.
        pc_notes: per event, what was approximated or missing ("" when nothing).
        pc_method: per event, which Pc: ``"2d"`` (the short-encounter 2-D Pc),
            ``"interval"`` (an encounter too slow for it, by
            :func:`~rhoprop.conjunction.encounter.encounter_check`, under at least one
            model: Pc counted over the encounter interval,
            :func:`~rhoprop.conjunction.encounter.pc_interval`), ``""`` (no Pc).
        pc_max, dilution: per event, the reference model's largest Pc over scalings of
            its combined covariance and whether its Pc lies in the dilution region (a
            smaller covariance would raise it: :meth:`PcResult.maximum`); NaN / False
            where its Pc is not a 2-D one.
        pc_monte_carlo_models, pc_monte_carlo: the member Monte Carlo's Pc per event and
            model (events, models) and mixed (events,), for the ``monte_carlo_events``
            most probable events; NaN for the others.
        covariance1, covariance2: per event, each object's reference-model state
            covariance at TCA in the RTN axes of its state (events, 6, 6), m^2, m^2/s,
            m^2/s^2 (NaN without Pc), as the CDMs carry them.
        counts: objects and pairs after each stage, in the order of
            :data:`ALL_ON_ALL_STAGES`: ``objects`` given, ``screened`` (propagated over
            some of the window), ``pairs`` (all pairs of screened objects),
            ``radial_pairs`` (pairs whose padded perigee-apogee ranges overlap, the
            classical first filter: reported, not needed by the grid), ``spatial``,
            ``coarse_grid`` and ``interpolated`` (pair-intervals passing the sieve's
            tests), ``refined_pairs`` (pairs re-propagated) and ``events``.
        skipped: (name, reason) of objects not screened (decayed before ``start``, the
            same element set twice, failed with ``errors="skip"``).
        notes: (name, note) of objects screened in part (decayed inside the window).
        timings: seconds per stage (wall clock): ``field``, ``propagation``, ``sieve``,
            ``refinement``, ``pc_drag`` (Cd debiasing per model), ``pc_covariance``
            (CCSP per model of the objects in events) and ``pc``.
        wall: whole run, s; threads: worker threads; chunks: time chunks the window was
            cut into (memory).
        start, end: the window (UTC); distance: m; grid_step: s.
        objects: the screened objects' names and ids, index-aligned with the sieve.
    """

    events: list[CloseApproach]
    models: list[str]
    weights: np.ndarray
    pc_models: np.ndarray
    pc: np.ndarray
    hard_body_radius: np.ndarray
    pc_notes: list[str]
    covariance1: np.ndarray
    covariance2: np.ndarray
    pc_monte_carlo_models: np.ndarray
    pc_monte_carlo: np.ndarray
    counts: dict[str, int]
    skipped: list[tuple[str, str]]
    notes: list[tuple[str, str]]
    timings: dict[str, float]
    wall: float
    threads: int
    chunks: int
    start: np.datetime64
    end: np.datetime64
    distance: float
    grid_step: float
    objects: list[tuple[str, int | None]] = field(default_factory=list)
    pc_method: list[str] = field(default_factory=list)
    pc_max: np.ndarray = field(default_factory=lambda: np.empty(0))
    dilution: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=bool))
    spread: float = 1.0

    def table(self) -> dict[str, np.ndarray]:
        """The events as columns (one row per event, in order): names and ids, TCA
        (datetime64[ns] UTC), miss distance m, relative speed m/s, ``edge`` ("start" /
        "end" for a minimum at the window's start / end, else ""), ``within_start`` and
        ``within_end`` (the stretch around TCA within the distance, UTC), hard-body radius m,
        mixture Pc, Pc per model (``pc_<model>``, the model's name in lower case with every
        run of other characters than letters and digits as one ``_``: ``pc_nrlmsis_2_1``,
        names a Parquet reader or pandas' attribute access takes), the member Monte
        Carlo's mixed Pc (NaN where not run), the reference model's ``pc_max`` and
        ``dilution``, ``pc_method`` and the Pc note."""
        ev = self.events
        cols: dict[str, np.ndarray] = {
            **event_columns(ev),
            "hard_body_radius": np.asarray(self.hard_body_radius, dtype=float),
            "pc": np.asarray(self.pc, dtype=float),
        }
        for k, name in enumerate(self.models):
            column = model_column(name)
            while column in cols:  # two names alike once lower-cased and joined
                column += "_"
            cols[column] = np.asarray(self.pc_models[:, k], dtype=float)
        cols["pc_monte_carlo"] = np.asarray(self.pc_monte_carlo, dtype=float)
        n = len(ev)
        cols["pc_max"] = np.asarray(self.pc_max if len(self.pc_max) else np.full(n, np.nan))
        cols["dilution"] = np.asarray(
            self.dilution if len(self.dilution) else np.zeros(n, dtype=bool), dtype=bool
        )
        cols["pc_method"] = np.array(
            self.pc_method if self.pc_method else [""] * len(ev), dtype=object
        )
        cols["pc_note"] = np.array(self.pc_notes, dtype=object)
        return cols

    def to_pandas(self) -> pandas.DataFrame:
        """:meth:`table` as a ``pandas.DataFrame``, one row per event (needs pandas, e.g.
        the ``[xarray]`` extra), as ``CatalogResult.to_pandas()`` gives its objects."""
        pd = optional_import("pandas", "AllOnAllResult.to_pandas()")
        frame: pandas.DataFrame = pd.DataFrame(self.table())
        return frame


def model_column(name: str) -> str:
    """The Pc column of a model named ``name``: ``pc_`` and the name in lower case, each
    run of characters other than ASCII letters and digits one ``_``."""
    slug = re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_")
    return f"pc_{slug or 'model'}"


@dataclass
class _Chunk:
    """The screened objects on grid samples ``times`` (s from start) of one time chunk."""

    times: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    samples: np.ndarray


class ScreenAllKeywords(LooseFloorAndDegree, total=False):
    """The deprecated keywords of :func:`screen_all`, each now in a settings record:
    ``pc=PcSettings(...)``, ``search=Search(...)``, ``execution=rp.Execution(...)`` and
    ``dynamics=rp.Dynamics(...)`` (:data:`_LOOSE`)."""

    weights: Mapping[str, float] | None
    hard_body_radius: float | None
    radii: Mapping[int, float] | None
    monte_carlo_events: int
    members: int
    seed: int
    grid_step: float
    fine_step: float
    max_span: float | None
    max_memory: float
    threads: int | None
    client: object
    errors: Errors
    progress: bool | Callable[[str, int, int], object]


#: Where each deprecated keyword of :func:`screen_all` goes now.
_LOOSE = {
    "pc": ("weights", "hard_body_radius", "radii", "monte_carlo_events", "members", "seed"),
    "search": ("grid_step", "fine_step", "max_span"),
    "execution": ("max_memory", "threads", "client", "errors", "progress"),
}


def _pc_settings(pc: object, loose: dict[str, object]) -> PcSettings:
    """The :class:`PcSettings` of ``pc=`` (True: the defaults; False: the defaults, unused)
    with the deprecated Pc keywords ``loose`` folded in."""
    if not isinstance(pc, (bool, np.bool_, PcSettings)):
        raise TypeError(f"pc must be True, False or a PcSettings, got {type(pc).__name__}")
    record = pc if isinstance(pc, PcSettings) else None
    return fold_keywords(
        "screen_all", "pc", record, PcSettings(), loose, "rp.conjunction.PcSettings", 4
    )


def screen_all(
    objects: Iterable[ScreenObject],
    model: ModelLike | Mapping[str, ModelLike],
    *,
    start: EpochLike,
    end: EpochLike,
    distance: float,
    reference: str | None = None,
    pc: bool | PcSettings = True,
    search: Search | None = None,
    dynamics: Dynamics | None = None,
    execution: Execution | None = None,
    **deprecated: Unpack[ScreenAllKeywords],
) -> AllOnAllResult:
    """Screens every object of a catalog against every other for close approaches within
    ``distance`` over [start, end] (UTC), each with its probability of collision per
    density model and for their mixture.

    Objects as for :func:`~rhoprop.conjunction.screen` (catalog objects or
    ``(OrbitState, Spacecraft[, name])``); an element set given twice (same epoch and
    state) is screened once.

    Stages (``counts``, ``timings``):

    1. **Propagation**: every object once, through the reference model's density atlas,
       from its epoch to ``start`` (backwards when later) and over the window with
       outputs every ``grid_step`` s, in time chunks whose tracks fit ``max_memory``.
    2. **Sieve** (in the core, per grid interval): the spatial grid of the balls that
       hold each object's motion over the interval, then the coarse and the interpolated
       distance bounds of :func:`~rhoprop.conjunction.screen`: all necessary conditions for
       an approach within ``distance``, so none is lost (``rhoprop_core::sieve``).
    3. **Refinement**: each surviving pair's intervals are re-propagated for both
       objects at ``fine_step`` and every minimum within ``distance`` is an event, as in
       :func:`~rhoprop.conjunction.closest_approach`.
    4. **Pc** (``pc=True``): per model, the CCSP (the catalog's defaults: each object's
       own covariance, Cd*A/m uncertainty, J2..J4) of the objects in events, Cd debiased
       against the reference over the 8 h before each epoch; at TCA each object's
       Gaussian is its screened state plus the model's mean offset from the reference
       model's, with the model's covariance; the 2-D Pc per model and their mixture
       ``sum_k w_k Pc_k`` (both objects fly through the same atmosphere, as in
       :func:`~rhoprop.conjunction.density_pc`). Hard-body radius: ``hard_body_radius``
       for every event, else the sum of both objects' radii from ``radii`` {NORAD id: m}
       or the rule of :data:`~rhoprop.conjunction.event_pc.RADII` by object kind.

    Args:
        objects: the catalog (a :class:`~rhoprop.catalog.Catalog` or a list).
        model: a density model, or {name: model} for several (``reference`` names the one
            the screening propagates with; default the first); e.g.
            ``rhoprop.studies.scenarios.default_models()``.
        start, end: the window, UTC; distance: screening distance, m.
        pc: compute the Pc of every event: True (default, ``PcSettings()``), a
            :class:`~rhoprop.conjunction.PcSettings` (its mixture weights, hard-body
            radii and the member Monte Carlo of the events of largest Pc), or False.
            Default weights are as ``rp.ensemble``'s: when every model is a calibrated
            family, the calibrated weights (NRLMSIS 2.1 0.849, JB2008 0.151,
            Jacchia-Roberts 0) with every model's density sigma times the calibrated
            spread 0.861 in its CCSP and Monte Carlo (``spread`` of the result;
            docs/density-calibration.md); else equal weights and each model's own sigma.
            Given weights keep each model's own sigma.
        search: a :class:`~rhoprop.conjunction.Search` (None: ``Search()``): the coarse
            grid step (at most 300 s), the refinement's output step, and ``max_span``: an
            object whose epoch lies more than this (s) before ``start`` or after ``end`` is
            not screened and is listed in ``skipped`` (default 60 days: a propagation holds
            the density tiles of every day it flies through; None: no limit).
        dynamics: a :class:`~rhoprop.Dynamics` (default ``Dynamics(zonal_degree=4)``,
            J2..J4, the catalog's). The tracks follow its ``integrator``, ``step`` and
            ``rtol`` (default adaptive DOP853); the Pc stage runs its CCSP and Monte Carlo
            with RK8 at that ``step`` (default each object's catalog step, 180 s in LEO),
            so with ``pc`` the integrator must be None or ``"rk8"`` (ValueError
            otherwise; ``rtol`` applies to the tracks); ``field_degree`` and
            ``third_bodies`` are refused.
        execution: an :class:`~rhoprop.Execution` (None: the defaults): ``threads``;
            ``max_memory``, bytes the tracks of one time chunk may take (None: 0.5 GB; the
            window is cut into time chunks that fit); ``errors`` ``"raise"`` (the first
            object whose propagation fails raises, named) or ``"record"`` (it is listed in
            ``skipped`` and the screen goes on); ``progress`` (bars on a terminal, or a
            callable given (stage, done, total)); ``client``, a
            ``dask.distributed.Client``: every stage runs there, each time chunk's
            propagation in blocks of objects, its sieve in ranges of grid intervals, its
            refinement in slices of candidates (:mod:`.screen_stages`), the Pc stage's
            CCSP as ``propagate_catalog`` on Dask; the events equal the local run's, bit
            for bit (``benches/screening.py --dask`` measures how it scales). Its
            ``chunk_size`` is refused (ValueError): the Dask stages cut their own blocks.
        **deprecated: the keywords that moved into ``pc`` (``weights``,
            ``hard_body_radius``, ``radii``, ``monte_carlo_events``, ``members``,
            ``seed``), ``search`` (``grid_step``, ``fine_step``, ``max_span``),
            ``execution`` (``max_memory``, ``threads``, ``client``, ``errors``,
            ``progress``) and ``dynamics`` (``floor_altitude``, ``zonal_degree``), folded
            in with a DeprecationWarning.

    Returns:
        :class:`AllOnAllResult`. Ctrl-C stops the run with KeyboardInterrupt.

    Raises:
        TypeError, ValueError: bad objects or arguments (named).
    """
    wall0 = time.perf_counter()
    models, ref_name = _model_set(model, reference)
    loose: dict[str, object] = dict(deprecated)
    part = {k: {n: loose.pop(n) for n in names if n in loose} for k, names in _LOOSE.items()}
    settings = _pc_settings(pc, part["pc"])
    enabled = pc is not False
    found = fold_keywords(
        "screen_all", "search", search, Search(), part["search"], "rp.conjunction.Search"
    )
    run_on = execution_argument("screen_all", execution, part["execution"])
    run_on.require_defaults("screen_all", ("chunk_size",))
    cfg = _settings(start, end, distance, found, dynamics, loose, enabled)
    errors, client, workers = run_on.errors, run_on.client, worker_count(run_on.threads)
    budget = DEFAULT_MAX_MEMORY if run_on.max_memory is None else run_on.max_memory
    objs, skipped, given = _unique_objects(objects)
    objs = _recent(objs, skipped, cfg.start, cfg.end, found.max_span)
    earliest = min([cfg.start, *(o.state.epoch for o in objs)])
    latest = max([cfg.end, *(o.state.epoch for o in objs)])
    check_weights(models, settings.weights)
    if enabled:
        check_coverage(models, earliest, latest)
    timings = dict.fromkeys(("field", "propagation", "sieve", "refinement"), 0.0)
    t0 = time.perf_counter()
    atlases = models_for(
        models[ref_name], [o.state for o in objs], earliest, latest, cfg.dynamics.floor_altitude
    )
    for obj, own in zip(objs, atlases, strict=True):
        obj.model = own
    timings["field"] = time.perf_counter() - t0
    run = _Run(objs, cfg, workers, errors, _reporter(run_on.progress), client)
    try:
        events, pairs, counts, notes, gone, chunks = run.screen(budget, timings)
        plan = EventPlan(events, pairs, objs, models, ref_name, cfg)
        pcs = event_probabilities(
            plan, settings, enabled, timings, client=client, report=run.report
        )
    finally:
        run.close()
    skipped += gone
    counts["objects"] = given
    n_mc = settings.monte_carlo_events if enabled else 0
    mc_models, mc = _monte_carlo(plan, pcs, n_mc, settings.members, settings.seed, timings)
    order = _by_pc(events, pcs.pc)
    return AllOnAllResult(
        events=[events[i] for i in order],
        models=list(models),
        weights=pcs.weights,
        spread=pcs.spread,
        pc_models=pcs.pc_models[order],
        pc=pcs.pc[order],
        hard_body_radius=pcs.hard_body_radius[order],
        pc_notes=[pcs.notes[i] for i in order],
        pc_method=[pcs.methods[i] for i in order],
        pc_max=pcs.pc_max[order],
        dilution=pcs.dilution[order],
        covariance1=pcs.covariance1[order],
        covariance2=pcs.covariance2[order],
        pc_monte_carlo_models=mc_models[order],
        pc_monte_carlo=mc[order],
        counts={key: counts.get(key, 0) for key in ALL_ON_ALL_STAGES},
        skipped=skipped,
        notes=notes,
        timings=timings,
        wall=time.perf_counter() - wall0,
        threads=workers,
        chunks=chunks,
        start=cfg.start,
        end=cfg.end,
        distance=cfg.limit,
        grid_step=cfg.step,
        objects=[(o.name, o.object_id) for o in objs],
    )


def _by_pc(events: list[CloseApproach], pc: np.ndarray) -> np.ndarray:
    """Event indices by mixture Pc (largest first; no Pc last), then TCA and name."""
    key = [(-np.nan_to_num(p, nan=-1.0), e.tca, e.name1) for p, e in zip(pc, events, strict=True)]
    return np.array(sorted(range(len(events)), key=key.__getitem__), dtype=np.intp)


def _monte_carlo(
    plan: EventPlan,
    pcs: EventPcs,
    chosen: int,
    members: int,
    seed: int,
    timings: dict[str, float],
) -> tuple[np.ndarray, np.ndarray]:
    """The member Monte Carlo's Pc (per model, mixed) of the ``chosen`` events of
    largest mixture Pc (:mod:`.event_mc`), timed in ``timings["pc_monte_carlo"]``."""
    t0 = time.perf_counter()
    top = sorted(range(len(plan.events)), key=lambda i: -np.nan_to_num(pcs.pc[i], nan=-1.0))
    out = event_monte_carlo(plan, pcs, top[:chosen], members, _validate.seed(seed, limit=2**63))
    timings["pc_monte_carlo"] = time.perf_counter() - t0
    return out


def _settings(
    start: EpochLike,
    end: EpochLike,
    distance: float,
    search: Search,
    dynamics: Dynamics | None,
    loose: Mapping[str, object],
    pc: bool,
) -> Window:
    t_start, t_end, span = window_span(start, end)
    step = search.grid_step
    if step > 300.0:
        raise ValueError(
            f"grid_step = {step:g} s is too coarse: at most 300 s (1/18 of a low orbit) keeps "
            "the cubic Hermite interpolant of the relative motion meaningful"
        )
    dyn = deprecated_keywords(
        "screen_all",
        dynamics,
        loose,
        Dynamics(zonal_degree=CATALOG_ZONAL_DEGREE),
        names=("floor_altitude", "zonal_degree"),
        stacklevel=4,
    )
    dyn.require_automatic_gravity("screen_all")
    if pc and dyn.integrator not in (None, "rk8"):
        raise ValueError(
            "screen_all()'s Pc stage integrates with rk8 (its CCSP and Monte Carlo), not "
            f"dynamics.integrator = {dyn.integrator!r}: give None or 'rk8', or pc=False"
        )
    return Window(
        t_start,
        t_end,
        span,
        _validate.positive("distance", distance),
        step,
        search.fine_step,
        dyn,
    )


def _model_set(model: Any, reference: str | None) -> tuple[dict[str, Any], str]:
    """{name: model} and the reference's name, checked."""
    if isinstance(model, Mapping):
        models = dict(model)
        if not models:
            raise ValueError("model must name at least one density model")
    else:
        models = {getattr(model, "name", type(model).__name__): model}
    for name, m in models.items():
        try:
            check_model(m)
        except TypeError as err:
            raise TypeError(f"model {name!r}: {err}") from err
    ref = reference if reference is not None else next(iter(models))
    if ref not in models:
        raise ValueError(f"reference {ref!r} is not one of the models {list(models)}")
    return {ref: models[ref], **{k: v for k, v in models.items() if k != ref}}, ref


def _recent(
    objs: list[ScreenedObject],
    skipped: list[tuple[str, str]],
    start: np.datetime64,
    end: np.datetime64,
    max_span: float | None,
) -> list[ScreenedObject]:
    """The objects whose epoch lies within ``max_span`` s before ``start`` or after
    ``end``; (name, reason) of the others go to ``skipped``."""
    kept = objs
    if max_span is not None:
        limit = _validate.positive("max_span", max_span)
        kept = []
        for o in objs:
            t = o.state.epoch
            reason = ""
            if t <= start:
                reason = beyond_max_span(seconds_between(t, start), "start", limit)
            if t > end:
                reason = beyond_max_span(seconds_between(t, end), "end", limit)
            if reason:
                skipped.append((o.name, reason))
            else:
                kept.append(o)
    if len(kept) < 2:
        same = [name for name, why in skipped if why.startswith("same element set")]
        raise ValueError(
            "screen_all needs at least two different objects within max_span of the "
            f"window; got {len(kept)}: {len(objs) - len(kept)} of {len(objs)} lie further"
            + (
                f", and {len(same)} repeat another's epoch and state ({', '.join(same[:3])})"
                if same
                else ""
            )
        )
    return kept


def _unique_objects(objects: Any) -> tuple[list[ScreenedObject], list[tuple[str, str]], int]:
    """The objects, each element set once (same epoch and state: the later copy is
    skipped, named), and how many were given."""
    items = secondaries_list(objects, "objects")
    objs = [as_object(item, f"objects[{i}]", i) for i, item in enumerate(items)]
    if len(objs) < 2:
        raise ValueError(f"screen_all needs at least two objects, got {len(objs)}")
    seen: dict[tuple[Any, bytes], ScreenedObject] = {}
    kept: list[ScreenedObject] = []
    skipped: list[tuple[str, str]] = []
    for o in objs:
        key = (o.state.epoch, np.asarray(o.state.state, dtype=float).tobytes())
        if key in seen:
            skipped.append((o.name, f"same element set as {seen[key].name}: screened once"))
            continue
        seen[key] = o
        kept.append(o)
    return kept, skipped, len(objs)


class _StageBars:
    """Progress bars on a terminal, one per stage in turn (the previous one closed)."""

    def __init__(self) -> None:
        self.bar: ProgressBar | None = None
        self.stage = ""

    def __call__(self, stage: str, done: int, total: int) -> None:
        if stage != self.stage or self.bar is None:
            self.close()
            unit = STAGE_UNITS.get(stage, "steps")
            self.bar, self.stage = ProgressBar(total, f"screen_all: {stage}", unit=unit), stage
        self.bar(done)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _reporter(progress: Any) -> Callable[[str, int, int], object] | None:
    if callable(progress):
        return progress  # type: ignore[no-any-return]
    return _StageBars() if progress else None


def radial_pair_count(objs: list[ScreenedObject], distance: float, degree: int) -> int:
    """Pairs whose perigee-apogee ranges, padded as one-primary screening pads them
    (zonal oscillation and margin, no drag), overlap within ``distance``."""
    perigee, apogee, _a, p = radial_ranges(objs)
    pad = ZONAL_PAD[2 if degree == 2 else 6] * J2 * R_EARTH**2 / p + RADIAL_MARGIN
    low, high = np.sort(perigee - pad), apogee + pad + distance
    n = len(objs)
    # Pairs (i, j) with low_j > high_i cannot overlap; each disjoint pair counts once.
    disjoint = int(np.sum(n - np.searchsorted(low, high, side="right")))
    return n * (n - 1) // 2 - disjoint


class _Run:
    """One all-on-all screen: time chunks of tracks, the sieve and the refinement."""

    def __init__(
        self,
        objs: list[ScreenedObject],
        cfg: Window,
        workers: int,
        errors: str,
        report: Callable[[str, int, int], object] | None,
        client: Any = None,
    ) -> None:
        self.objs, self.cfg, self.workers, self.errors = objs, cfg, workers, errors
        self.report = report
        self.dask = None if client is None else DaskStages(client)
        self.stop = threading.Event()
        self.dyn = TrackDynamics(cfg.start, True, cfg.dynamics, cfg.fine)
        self.skipped: list[tuple[str, str]] = []
        self.notes: list[tuple[str, str]] = []

    def close(self) -> None:
        if isinstance(self.report, _StageBars):
            self.report.close()

    def _tell(self, stage: str, done: int, total: int) -> None:
        if self.report is not None:
            self.report(stage, done, total)

    def screen(
        self, budget: float, timings: dict[str, float]
    ) -> tuple[
        list[CloseApproach], list[tuple[int, int]], dict[str, int], list[Any], list[Any], int
    ]:
        """Events, their object pairs, counts, notes, skipped objects and the number of
        chunks."""
        cfg = self.cfg
        grid = np.arange(0.0, cfg.span, cfg.step)
        grid = np.append(grid, cfg.span) if cfg.span - grid[-1] > 1e-6 else grid
        per = max(2, min(len(grid), int(budget // (48 * len(self.objs)))))
        bounds = [*range(0, len(grid) - 1, per - 1), len(grid) - 1]
        state: list[Any] = [None] * len(self.objs)  # each object's state at the chunk start
        counts: dict[str, int] = defaultdict(int)
        found: dict[tuple[int, int], list[CloseApproach]] = defaultdict(list)
        refined: set[tuple[int, int]] = set()
        screened = np.zeros(len(self.objs), dtype=bool)
        for c, (a, b) in enumerate(itertools.pairwise(bounds)):
            t0 = time.perf_counter()
            chunk = self._propagate(grid[a : b + 1], state, first=c == 0)
            timings["propagation"] += time.perf_counter() - t0
            screened |= chunk.samples >= 2
            t0 = time.perf_counter()
            cand = self._sieve(chunk, counts)
            timings["sieve"] += time.perf_counter() - t0
            t0 = time.perf_counter()
            refined.update(zip(cand[:, 0].tolist(), cand[:, 1].tolist(), strict=True))
            for pair, events in self._refine_chunk(chunk, cand).items():
                found[pair] += events
            timings["refinement"] += time.perf_counter() - t0
        kept = [o for o, s in zip(self.objs, screened, strict=True) if s]
        counts["screened"] = len(kept)
        counts["pairs"] = len(kept) * (len(kept) - 1) // 2
        counts["radial_pairs"] = (
            radial_pair_count(kept, cfg.limit, cfg.dynamics.zonal_degree) if kept else 0
        )
        counts["refined_pairs"] = len(refined)
        per_pair = [
            (pair, e) for pair in sorted(found) for e in _joined(_one_per_minimum(found[pair]))
        ]
        counts["events"] = len(per_pair)
        events = [e for _p, e in per_pair]
        pairs = [p for p, _e in per_pair]
        return events, pairs, counts, self.notes, self.skipped, len(bounds) - 1

    def _propagate(self, times: np.ndarray, state: list[Any], first: bool) -> _Chunk:
        """Every object on the chunk's samples; ``state`` is updated to the chunk's end.
        Each worker writes its object's samples straight into the chunk's arrays (the
        tracks are the run's memory: they are never held twice)."""
        n, m = len(self.objs), len(times)
        pos, vel = np.zeros((n, m, 3)), np.zeros((n, m, 3))
        samples = np.zeros(n, dtype=np.uint64)
        todo = [i for i in range(n) if first or state[i] is not None]

        def keep(i: int, track: Track) -> float | None:
            t, p, v, decay, why = track
            if why:
                self.skipped.append((self.objs[i].name, why))
            k = min(len(t), m)
            if k and not np.allclose(t[:k], times[:k], rtol=0, atol=1e-6):
                raise AssertionError("track off the common grid")  # guarded by track_one
            pos[i, :k], vel[i, :k], samples[i] = p[:k], v[:k], k
            state[i] = None if decay is not None or k < m else (p[-1].copy(), v[-1].copy())
            return decay

        def one(i: int) -> float | None:
            if self.stop.is_set():
                raise KeyboardInterrupt("screening interrupted")
            track = track_one(
                self.objs[i], state[i], times, first, self.dyn, self.cfg.step, self.errors
            )
            return keep(i, track)

        done = 0
        total = len(todo)

        def tick(_k: int, _r: object) -> None:
            nonlocal done
            done += 1
            self._tell("propagation", done, total)

        if self.dask is None:
            decays = map_in_threads(one, todo, self.workers, self.stop, tick)
        else:
            found = self.dask.tracks(
                self.objs, state, times, first, self.dyn, self.cfg.step, self.errors, todo, tick
            )
            decays = [keep(i, found[i]) for i in todo]
        for i, decay in zip(todo, decays, strict=True):
            if decay is None:
                continue
            name, when = self.objs[i].name, add_seconds(self.cfg.start, decay)
            if samples[i] < 2 and first:
                self.skipped.append((name, f"decayed at {when} UTC, before {times[1]:g} s"))
            else:
                self.notes.append((name, f"decayed at {when} UTC: screened up to then"))
        return _Chunk(times, pos, vel, samples)

    def _sieve(self, chunk: _Chunk, counts: dict[str, int]) -> np.ndarray:
        """Candidate (i, j, k) rows of the chunk, sorted."""
        fourth = np.zeros(len(chunk.samples))
        steps = np.arange(len(chunk.times))[None, :]
        for lo in range(0, len(fourth), 512):  # blocks: no (objects, samples) temporaries
            rn = np.linalg.norm(chunk.pos[lo : lo + 512], axis=2)
            vn = np.linalg.norm(chunk.vel[lo : lo + 512], axis=2)
            valid = steps < chunk.samples[lo : lo + 512, None].astype(np.int64)
            with np.errstate(divide="ignore", invalid="ignore"):
                f = np.where(valid, (vn / np.where(rn > 0, rn, 1.0)) ** 4 * rn, 0.0)
            fourth[lo : lo + 512] = f.max(axis=1)
        total = len(chunk.times) - 1

        def tick(done: int) -> None:
            self._tell("sieve", int(done), total)

        if self.dask is not None:
            i, j, k, (spatial, coarse, interp) = self.dask.sieve(
                chunk.times, chunk.pos, chunk.vel, chunk.samples, fourth, self.cfg.limit
            )
        else:
            out = _core.screen_candidates(
                core_tracks(chunk.times, chunk.pos, chunk.vel, chunk.samples),
                fourth,
                self.cfg.limit,
                MAX_ACCELERATION,
                HERMITE_SAMPLES,
                tick if self.report is not None else None,
            )
            i, j, k = out.i, out.j, out.k
            spatial, coarse, interp = out.spatial, out.coarse, out.interpolated
        self._tell("sieve", total, total)  # the core reports only while it runs long
        counts["spatial"] += int(spatial)
        counts["coarse_grid"] += int(coarse)
        counts["interpolated"] += int(interp)
        return np.column_stack([i, j, k]).astype(np.int64)

    def _refine_chunk(
        self, chunk: _Chunk, cand: np.ndarray
    ) -> dict[tuple[int, int], list[CloseApproach]]:
        """Events within the distance per candidate pair of the chunk: the minima on the
        quintic Hermite interpolant of both objects' samples (the core's
        ``screen_approaches``)."""
        if not len(cand):
            return {}
        total = len(cand)

        def tick(done: int) -> None:
            self._tell("refinement", int(done), total)

        arrays = {
            "times": chunk.times,
            "pos": chunk.pos,
            "vel": chunk.vel,
            "samples": chunk.samples,
        }
        settings = (self.cfg.dynamics.zonal_degree, self.cfg.limit, self.cfg.span)
        if self.dask is None:
            found = refine_slice(arrays, cand, *settings, tick if self.report else None)
        else:
            found = self.dask.refine(arrays, cand, *settings)
        i, j, t, s1, s2, edge, first, last = found
        self._tell("refinement", total, total)
        out: dict[tuple[int, int], list[CloseApproach]] = defaultdict(list)
        for m in range(len(t)):
            a, b = self.objs[int(i[m])], self.objs[int(j[m])]
            where = EDGES[int(edge[m])]
            event = make_event(self.dyn, a, b, float(t[m]), s1[m].copy(), s2[m].copy(), where)
            span = (
                add_seconds(self.cfg.start, float(first[m])),
                add_seconds(self.cfg.start, float(last[m])),
            )
            out[int(i[m]), int(j[m])].append(dataclasses.replace(event, within=span))
        return out


def _joined(events: list[CloseApproach]) -> list[CloseApproach]:
    """A pair's events (TCA order) with the ``within`` intervals that overlap or touch
    (one stretch within the distance, or its parts in two time chunks) joined: every
    minimum of a stretch carries the whole stretch."""
    groups: list[list[CloseApproach]] = []
    tol = np.timedelta64(1, "ms")
    for e in events:
        if groups and e.within is not None and groups[-1][-1].within is not None:
            last = max(g.within[1] for g in groups[-1] if g.within is not None)
            if e.within[0] <= last + tol:
                groups[-1].append(e)
                continue
        groups.append([e])
    out: list[CloseApproach] = []
    for g in groups:
        spans = [e.within for e in g if e.within is not None]
        if len(g) > 1 and spans:
            union = (min(a for a, _ in spans), max(b for _, b in spans))
            g = [dataclasses.replace(e, within=union) for e in g]
        out += g
    return out


def _one_per_minimum(events: list[CloseApproach]) -> list[CloseApproach]:
    """A pair's events in TCA order, those within :data:`SAME_EVENT` of the previous one
    dropped (the same minimum found from two brackets or chunks)."""
    out: list[CloseApproach] = []
    for e in sorted(events, key=lambda e: e.tca):
        if out and abs(seconds_between(out[-1].tca, e.tca)) < SAME_EVENT:
            continue
        out.append(e)
    return out
