"""Reentry windows: when each object of a catalog comes down, from a Monte Carlo over
density uncertainty (the model's sigma, correlated in time by ``kappa``: by default one
draw per member held over the whole run, :data:`DEFAULT_KAPPA`) and the uncertainty of
the ballistic coefficient Cd*A/m.

Ballistic coefficient per member, exactly and without the core's help: the ``n`` members
are run as ``groups`` Monte Carlos, each with its own Cd*A/m. The group values are the
midpoints (in probability) of ``groups`` equally likely bins of the Cd*A/m distribution,
a log-normal with median the object's Cd*A/m and log-sigma ``drag_sigma`` (relative):
a stratified sample of Cd*A/m, every member a correct draw of (Cd*A/m, density path).
Each group's density draws use their own seed, so no two members share a path.

Decayed members are counted (the decay epoch of each member), never frozen into
statistics: quantiles are taken over all ``n`` members with the ones still in orbit at
the horizon counted as later than it, so a quantile beyond the horizon is NaT.
"""

from __future__ import annotations

import datetime as _dt
import threading
import warnings
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from statistics import NormalDist
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from .. import _validate
from ..density.model import ModelLike
from ..parallel import map_in_threads, worker_count
from ..progress import ProgressBar
from ..propagation import Spacecraft, monte_carlo
from ..propagation.dynamics import Dynamics, deprecated_keywords
from ..propagation.kappa import Constant, KappaProcess
from ..propagation.methods import MonteCarlo, require_defaults, with_keywords
from ..propagation.montecarlo import METHODS as MONTE_CARLO_INTEGRATORS
from ..propagation.montecarlo import SETTINGS, drag_sigma_argument
from ..propagation.results import optional_import
from ..time import DurationLike, add_seconds
from .elements import CatalogObject, fit_objects, raise_named
from .objects import DEFAULT_DRAG_RELATIVE_SIGMA, scaled_bstar_drag

if TYPE_CHECKING:
    import pandas
    from typing_extensions import Unpack

#: Default density perturbation of a reentry run: one N(0,1) draw per member held over
#: the whole run (``Constant``), so each member's density is the model's mean + kappa x
#: the model's sigma (for NRLMSIS the model-error floor, 11.4 % calibrated, plus the
#: drivers') for all of its remaining life. The model's error is a bias over days (the
#: observed/model density ratios behind the floor are daily and orbit means, Emmert et
#: al. 2021); the
#: 18-minute ``GaussMarkov()`` of the paper, used here until 2026-12-03, averages it away
#: over a multi-day decay (about 2 % left after 3 days) and left the Cd*A/m floor as the
#: only spread of the window. Measured on the 49 real decays of benches/reentry.py:
#: 55 % -> 76 % of 95 % windows hold the decay day, median width 36 % -> 61 % of the
#: remaining life (docs/catalog-realism.md, "Reentry windows").
DEFAULT_KAPPA: KappaProcess = Constant()

#: Fit span of a reentry's state and Cd*A/m, s from the element set's epoch: one day
#: either side (the day before it when the orbit comes down within the day after). Catalog
#: fits use the day before the epoch (``fit.DEFAULT_SPAN``, chosen on the four realism
#: weeks); on the 49 real decays of ``benches/reentry.py`` that span held 69 % of the
#: decay days against 71 % with this one (one object), same median error (32 %): no
#: evidence for a change, so reentries keep the span their windows were measured with.
REENTRY_FIT_SPAN = (-86400.0, 86400.0)


@dataclass(frozen=True)
class ReentryResult:
    """Reentry windows per object.

    Attributes:
        objects: the objects, in order.
        horizon: the horizon, s after each object's epoch.
        epoch_median, epoch_q025, epoch_q975: (objects,) datetime64[ns] median and
            2.5 % / 97.5 % quantiles of the members' decay epochs (UTC); NaT where the
            quantile lies beyond the horizon (fewer members came down), so all NaT where
            no member decays within it.
        decayed_fraction: (objects,) fraction of members decayed within the horizon.
        drag_parameter: (objects,) median Cd*A/m used, m^2/kg; drag_sigma: (objects,) its
            relative (log) 1-sigma.
        members: members per object; groups: Cd*A/m values per object.
        fitted: (objects,) whether the state and Cd*A/m were fitted to the element set
            (by :func:`reentry` or before it); fit_rms: (objects,) the fit's RMS residual
            against SGP4, m (NaN where not fitted); fit_note: (objects,) why an object was
            not fitted ("" where fitted or not asked to).
        element_sets: (objects,) how many element sets of the object's NORAD id the input
            held (with ``history="newest"`` only the newest was predicted).
        decay_times: (objects, members) each member's decay time, s after its object's
            epoch (inf: not down within the horizon); :meth:`window` gives a window of
            any probability from them.
    """

    objects: list[CatalogObject]
    horizon: float
    epoch_median: np.ndarray
    epoch_q025: np.ndarray
    epoch_q975: np.ndarray
    decayed_fraction: np.ndarray
    drag_parameter: np.ndarray
    drag_sigma: np.ndarray
    members: int
    groups: int
    fitted: np.ndarray
    fit_rms: np.ndarray
    fit_note: list[str]
    element_sets: np.ndarray
    decay_times: np.ndarray

    def window(self, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
        """The central window holding a fraction ``level`` (0 < level < 1) of the members'
        decays: (objects,) datetime64[ns] start and end, the (1 - level) / 2 and
        (1 + level) / 2 quantiles of the decay epochs (UTC), NaT where beyond the horizon.
        ``window(0.95)`` is (``epoch_q025``, ``epoch_q975``)."""
        q = _validate.real("level", level)
        if not 0 < q < 1:
            raise ValueError(f"level must lie strictly between 0 and 1, got {level!r}")
        lo = _quantile_epochs(self.objects, self.decay_times, (1 - q) / 2)
        return lo, _quantile_epochs(self.objects, self.decay_times, (1 + q) / 2)

    def rows(self) -> list[dict[str, Any]]:
        """One dict per object (NORAD id, name, the epochs as ISO strings or "": the 95 %
        window's ends, the median and the 80 % window's ends ``epoch_q10`` /
        ``epoch_q90``; the decayed fraction ...), for printing and CSV."""

        def iso(t: np.datetime64) -> str:
            return "" if np.isnat(t) else str(t.astype("datetime64[s]")) + "Z"

        q10, q90 = self.window(0.8)
        return [
            {
                "norad_id": o.norad_id,
                "name": o.name,
                "epoch_q025": iso(self.epoch_q025[k]),
                "epoch_q10": iso(q10[k]),
                "epoch_median": iso(self.epoch_median[k]),
                "epoch_q90": iso(q90[k]),
                "epoch_q975": iso(self.epoch_q975[k]),
                "decayed_fraction": float(self.decayed_fraction[k]),
                "drag_parameter_m2_kg": float(self.drag_parameter[k]),
                "drag_relative_sigma": float(self.drag_sigma[k]),
                "fitted": bool(self.fitted[k]),
                "fit_rms_m": float(self.fit_rms[k]),
                "fit_note": self.fit_note[k],
                "element_sets": int(self.element_sets[k]),
            }
            for k, o in enumerate(self.objects)
        ]

    def table(self) -> dict[str, np.ndarray]:
        """One row per object as columns: ``norad_id``, ``name``, the 95 % window's ends
        ``epoch_q025`` / ``epoch_q975``, the 80 % window's ``epoch_q10`` / ``epoch_q90``
        and ``epoch_median`` (datetime64[ns] UTC, NaT beyond the horizon), then the
        columns of :meth:`rows` (decayed fraction, Cd*A/m m^2/kg and its relative sigma,
        fit, fit RMS m, fit note, element sets)."""
        q10, q90 = self.window(0.8)
        rows = self.rows()
        cols: dict[str, np.ndarray] = {
            "norad_id": np.array([o.norad_id for o in self.objects], dtype=np.int64),
            "name": np.array([o.name for o in self.objects], dtype=object),
            "epoch_q025": self.epoch_q025,
            "epoch_q10": q10,
            "epoch_median": self.epoch_median,
            "epoch_q90": q90,
            "epoch_q975": self.epoch_q975,
        }
        for key in [k for k in (rows[0] if rows else {}) if k not in cols]:
            values = [r[key] for r in rows]
            cols[key] = np.array(values, dtype=object if key == "fit_note" else None)
        return cols

    def to_pandas(self) -> pandas.DataFrame:
        """:meth:`table` as a ``pandas.DataFrame``, one row per object (needs pandas, e.g.
        the ``[xarray]`` extra)."""
        pd = optional_import("pandas", "ReentryResult.to_pandas()")
        frame: pandas.DataFrame = pd.DataFrame(self.table())
        return frame


def _seconds(horizon: object) -> float:
    if isinstance(horizon, _dt.timedelta):
        value = horizon.total_seconds()
    elif isinstance(horizon, np.timedelta64):
        value = float(horizon / np.timedelta64(1, "ns")) / 1e9
    elif isinstance(horizon, (int, float, np.integer, np.floating)) and not isinstance(
        horizon, bool
    ):
        value = float(horizon)
    else:
        raise TypeError(f"duration must be seconds or a timedelta, got {type(horizon).__name__}")
    if not np.isfinite(value) or value <= 0:
        raise ValueError(f"duration must be positive, got {horizon!r}")
    if value > MAX_DURATION:
        raise ValueError(
            f"duration must be at most {MAX_DURATION / 86400:g} days (ten years), got "
            f"{value / 86400:g} days"
        )
    return value


#: Longest reentry horizon, s: ten years (a longer one would also exceed the steps a run
#: may take at the Monte Carlo's step).
MAX_DURATION = 3660 * 86400.0


def _relative_sigma(obj: CatalogObject, drag_sigma: float | None) -> float:
    if drag_sigma is not None:
        return float(drag_sigma)
    fit = obj.fit
    if fit is not None and obj.drag_parameter > 0:
        return max(float(fit.drag_sigma) / obj.drag_parameter, DEFAULT_DRAG_RELATIVE_SIGMA)
    return DEFAULT_DRAG_RELATIVE_SIGMA


class ReentryKeywords(TypedDict, total=False):
    """The deprecated keywords of :func:`reentry`: the Monte Carlo's settings (now in
    ``method=rp.MonteCarlo(n=, kappa=, seed=, threads=)``), ``floor_altitude`` (now in
    ``dynamics``) and ``horizon`` (an older name of ``duration``)."""

    n: int
    kappa: KappaProcess | None
    seed: int
    threads: int | None
    floor_altitude: float
    horizon: DurationLike


#: A reentry run's Monte Carlo: 100 members per object, kappa :data:`DEFAULT_KAPPA`.
REENTRY_MONTE_CARLO = MonteCarlo(n=100)


def reentry(
    objects: Iterable[CatalogObject],
    model: ModelLike,
    *,
    method: MonteCarlo = REENTRY_MONTE_CARLO,
    duration: DurationLike = 30 * 86400.0,
    groups: int = 10,
    drag_sigma: float | None = None,
    dynamics: Dynamics | None = None,
    fit: bool = True,
    history: str = "auto",
    **deprecated: Unpack[ReentryKeywords],
) -> ReentryResult:
    """Reentry windows of ``objects`` within ``duration`` of their epochs.

    Args:
        objects: a :class:`~rhoprop.catalog.Catalog` or list of
            :class:`~rhoprop.catalog.CatalogObject` (fitted ones give their own Cd*A/m
            uncertainty).
        model: density model (a sampled one serves each object the day tiles of its own
            span from its atlas, :mod:`rhoprop.density.atlas`) or a field/atmosphere.
        method: the :class:`~rhoprop.MonteCarlo` of every object (default
            ``rp.MonteCarlo(n=100)``): ``n`` members per object (a multiple of ``groups``
            is used: rounded up); its ``kappa`` (None: :data:`DEFAULT_KAPPA`, the model's
            density error held over the whole run); object i group g seeded
            ``seed + 1000 * i + g``; ``threads`` objects run at once (None: all cores);
            its ``perturbation`` and ``max_memory`` per run; its ``progress`` (default
            True: a bar of the objects done; False: none; a callable: called with the
            number done). Its ``drag_sigma`` and ``record_density`` are this function's
            own (a ValueError away from their defaults); its ``output_step`` is not used
            (decay times only).
        duration: how far to look, s after each object's epoch, or a ``timedelta``
            (default 30 days).
        groups: Cd*A/m values per object (stratified; 1 turns Cd*A/m uncertainty off).
        drag_sigma: relative (log) 1-sigma of Cd*A/m for every object; default: the
            fit's (at least :data:`DEFAULT_DRAG_RELATIVE_SIGMA`) or that default.
        dynamics: a :class:`~rhoprop.Dynamics` for every member's run: its zonal degree,
            floor (default 120 km), integrator (``"rk8"``, ``"rk4"`` or ``"abm"``) and
            step are the Monte Carlo's; ``rtol``, ``field_degree`` and ``third_bodies``
            are refused (ValueError).
        fit: fit each object's state and Cd*A/m to its element set with ``model`` first
            (:func:`~rhoprop.catalog.fit_objects`; default True). Objects already fitted
            (``load(fit=True)``) are used as they are; an object whose fit fails keeps
            its B*-derived state and Cd*A/m, and ``fit_note`` says why. On real decays
            fitting is what makes the windows hold (benches/reentry.py).
        history: what to do with several element sets of one NORAD id (a history, as
            catalogs publish them): ``"auto"`` (default since 2026-12-05) is ``"fit"``
            with ``fit`` and ``"newest"`` without; ``"newest"`` predicts the object once,
            from its newest element set, and ``element_sets`` counts them; ``"fit"``
            predicts it once from the newest element set with the fit taking the older
            ones (within :data:`~rhoprop.catalog.elements.HISTORY_DAYS`) too
            (:func:`~rhoprop.catalog.fit_objects` ``history=``; needs ``fit``): on the
            natural reentries of the dense 2026 history it cut the error at 1-2 days'
            lead (median 17 % of the remaining life against 24 %, forecast drivers;
            ``benches/reentry_history.py``); ``"each"`` predicts every element set on its
            own (one row each, ``element_sets`` still > 1). They are never silently
            separate objects.
        **deprecated: ``n=``, ``kappa=``, ``seed=``, ``threads=`` (folded into
            ``method``), ``floor_altitude=`` (into ``dynamics``) and ``horizon=`` (an
            older name of ``duration``), each with a DeprecationWarning.

    Returns:
        :class:`ReentryResult`.
    """
    objs = list(objects)
    if not objs:
        raise ValueError("the catalog has no objects")
    _check_objects(objs)
    method, dyn, duration = _settings(method, dynamics, duration, dict(deprecated))
    n, seed, threads = method.n, method.seed, method.threads
    groups = _validate.count("groups", groups, minimum=1)
    drag_sigma = None if drag_sigma is None else drag_sigma_argument(drag_sigma)
    per_group = max(int(np.ceil(n / groups)), 2)
    total = per_group * int(groups)
    span = _seconds(duration)
    objs, notes, counts = _histories_and_fits(objs, model, fit, history, threads)
    process = method.kappa or DEFAULT_KAPPA
    probabilities = (np.arange(groups) + 0.5) / groups

    stop = threading.Event()

    def check(_done: int) -> None:
        # Called by the core about every 50 ms: a Ctrl-C (or an error) of another object
        # ends this object's run too, instead of letting it finish (17-21 s before).
        if stop.is_set():
            raise KeyboardInterrupt("reentry run interrupted")

    def one(i: int, obj: CatalogObject) -> tuple[np.ndarray, float, float]:
        rel = _relative_sigma(obj, drag_sigma)
        normal = np.array([NormalDist().inv_cdf(float(p)) for p in probabilities])
        values = obj.drag_parameter * np.exp(rel * normal) if groups > 1 else [obj.drag_parameter]
        times = []
        for g, value in enumerate(values):
            try:
                mc = monte_carlo(
                    obj.state,
                    Spacecraft(1.0, float(value)),
                    model,
                    span,
                    n=per_group,
                    kappa=process,
                    seed=seed + 1000 * i + g,
                    output_step=None,
                    perturbation=method.perturbation,
                    max_memory=method.max_memory,
                    progress=check,
                    dynamics=dyn,
                    threads=1,
                )
            except Exception as err:  # named: one element set below the floor, say
                raise_named(err, obj)
            times.append(np.asarray(mc.decay_times, dtype=float))
        return np.concatenate(times), obj.drag_parameter, rel

    # In epoch order, so that objects running at once share their day tiles.
    order = sorted(range(len(objs)), key=lambda i: objs[i].state.epoch)
    ran = _with_progress(lambda i: one(i, objs[i]), order, threads, stop, method.progress)
    done = [ran[k] for k in np.argsort(order)]
    decay_times = np.vstack([np.where(d[0] <= span, d[0], np.inf) for d in done])
    lo, med, hi = (_quantile_epochs(objs, decay_times, q) for q in (0.025, 0.5, 0.975))
    fraction = np.isfinite(decay_times).mean(axis=1)
    return ReentryResult(
        objects=objs,
        horizon=span,
        epoch_median=med,
        epoch_q025=lo,
        epoch_q975=hi,
        decayed_fraction=fraction,
        drag_parameter=np.array([d[1] for d in done]),
        drag_sigma=np.array([d[2] for d in done]),
        members=total,
        groups=int(groups),
        fitted=np.array([o.fit is not None for o in objs]),
        fit_rms=np.array([o.fit.rms_total if o.fit is not None else np.nan for o in objs]),
        fit_note=notes,
        element_sets=np.array([counts[o.norad_id] for o in objs]),
        decay_times=decay_times,
    )


def _check_objects(objs: list[Any]) -> None:
    wrong = next((o for o in objs if not isinstance(o, CatalogObject)), None)
    if wrong is not None:
        raise TypeError(
            "objects must be a Catalog or CatalogObjects (rp.catalog.load), got "
            f"{type(wrong).__name__} {wrong!r:.60}"
        )


def _with_progress(
    fn: Callable[[int], Any],
    order: list[int],
    threads: int | None,
    stop: threading.Event,
    progress: bool | Callable[[int], object],
) -> list[Any]:
    """``fn`` over the object indices ``order`` on the run's threads, reporting the
    objects done: a bar (``progress`` True), a callable, or nothing (False)."""
    bar = ProgressBar(len(order), "reentry", unit="objects") if progress is True else None
    shown = bar if bar is not None else (progress if callable(progress) else None)
    try:
        return map_in_threads(
            fn,
            order,
            worker_count(threads),
            stop,
            None if shown is None else lambda k, _result: shown(k + 1),
        )
    finally:
        if bar is not None:
            bar.close()


def _settings(
    method: MonteCarlo, dynamics: Dynamics | None, duration: DurationLike, loose: dict[str, Any]
) -> tuple[MonteCarlo, Dynamics, DurationLike]:
    """:func:`reentry`'s method, dynamics and duration, checked, with its deprecated
    keywords ``loose`` folded in (each with a DeprecationWarning)."""
    if "horizon" in loose:
        warnings.warn(
            "reentry(horizon=...) is deprecated; the span after each epoch is duration=",
            DeprecationWarning,
            stacklevel=3,
        )
        duration = loose.pop("horizon")
    if not isinstance(method, MonteCarlo):
        raise TypeError(
            "reentry(): method must be rp.MonteCarlo(...) (a reentry window is the spread "
            f"of members' decay times), got {type(method).__name__}"
        )
    own = {k: loose.pop(k) for k in SETTINGS if k in loose}
    method = with_keywords(method, "reentry", own, stacklevel=4)
    require_defaults(
        method,
        "reentry",
        ("drag_sigma", "record_density"),
        "reentry's drag_sigma= and groups= give each object's Cd*A/m spread",
    )
    dyn = deprecated_keywords("reentry", dynamics, loose, names=("floor_altitude",), stacklevel=4)
    dyn.require_automatic_gravity("reentry")
    dyn.require_integrator("reentry", MONTE_CARLO_INTEGRATORS)
    return method, dyn, duration


def resolved_history(history: str, fit: bool) -> str:
    """What ``history="auto"`` means: ``"fit"`` when fitting, else ``"newest"``."""
    return ("fit" if fit is True else "newest") if history == "auto" else history


def _histories_and_fits(
    objs: list[CatalogObject], model: ModelLike, fit: bool, history: str, threads: int | None
) -> tuple[list[CatalogObject], list[str], Counter[int]]:
    """The objects to predict (one per NORAD id with ``history="newest"``), fitted when
    ``fit``; a note per object where its fit failed; the element sets per NORAD id."""
    if not isinstance(fit, bool):
        raise TypeError(f"fit must be True or False, got {type(fit).__name__}")
    if history not in ("auto", "newest", "fit", "each"):
        raise ValueError(f"history must be 'auto', 'newest', 'fit' or 'each', got {history!r}")
    history = resolved_history(history, fit)
    if history == "fit" and not fit:
        raise ValueError("history='fit' fits the element sets together: it needs fit=True")
    counts = Counter(o.norad_id for o in objs)
    older: dict[int, list[CatalogObject]] = {}
    if history in ("newest", "fit") and len(counts) < len(objs):
        newest: dict[int, CatalogObject] = {}
        for o in objs:
            if o.norad_id not in newest or o.state.epoch > newest[o.norad_id].state.epoch:
                newest[o.norad_id] = o
        if history == "fit":
            for o in objs:
                keep = newest[o.norad_id]
                if o is not keep and o.state.epoch < keep.state.epoch:
                    older.setdefault(o.norad_id, []).append(o)
        objs = [o for o in objs if newest[o.norad_id] is o]
    notes = ["" for _ in objs]
    if fit:
        todo = [k for k, o in enumerate(objs) if o.fit is None]
        fits = fit_objects(
            [objs[k] for k in todo], model, span=REENTRY_FIT_SPAN, threads=threads, history=older
        )
        for k, res in zip(todo, fits, strict=True):
            if isinstance(res, CatalogObject):
                objs[k] = res
            else:
                notes[k] = f"fit failed ({type(res).__name__}: {res}); B* used"
    # An object not fitted flies with B* scaled to the model, as in propagate_catalog,
    # so that a catalog run and a reentry run of one element set agree on its drag.
    objs = [scaled_bstar_drag(o, model) for o in objs]
    return objs, notes, counts


def _quantile_epochs(objs: list[CatalogObject], decay_times: np.ndarray, q: float) -> np.ndarray:
    """The ``q`` quantile of each object's members' decay epochs (NaT where it lies beyond
    the horizon: the members not down count as later than it), from their decay times
    (objects, members), s after each object's epoch, inf where not down."""
    out = np.full(len(objs), np.datetime64("NaT", "ns"))
    for k, times in enumerate(decay_times):
        t = float(np.quantile(times, q, method="inverted_cdf"))
        if np.isfinite(t):
            out[k] = add_seconds(objs[k].state.epoch, t)
    return out
