"""Catalog runs: CCSP or Monte Carlo over many objects from their own epochs to common
output epochs, locally (objects on threads) or on a Dask cluster, with decay prediction.
Every object ends with a status and a reason; errors are raised (or, on request,
recorded per object), never swallowed. This module checks the arguments and assembles
the :class:`CatalogResult`; one object's plan, run and outcome are
:mod:`rhoprop.catalog.objects`, the threads and Dask backends
:mod:`rhoprop.catalog.backends`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import _validate
from .._deprecated import fold_keywords
from ..density import DensityModel, SampledModel
from ..execution import Execution, execution_argument
from ..options import Errors
from ..progress import ProgressBar
from ..propagation import OrbitState
from ..propagation.dynamics import Dynamics, LooseFloorAndDegree, deprecated_keywords
from ..propagation.interpolate import DEFAULT_TOLERANCE
from ..propagation.kappa import KappaProcess
from ..propagation.methods import (
    Ccsp,
    Method,
    MethodName,
    MonteCarlo,
    method_argument,
    with_keywords,
)
from ..propagation.propagate import MAX_STEPS
from ..propagation.results import (
    StateMoments,
    dataset_attrs,
    epoch_coords,
    label_coords,
    moment_vars,
    optional_import,
)
from ..time import (
    EpochLike,
    add_seconds,
    offsets_to_epochs,
    seconds_between,
    to_datetime64,
    to_seconds,
)
from .backends import Outcomes, _run_local, _run_on_dask, by_epoch
from .elements import CatalogObject
from .objects import (  # noqa: F401 - the names tests and older code import from here
    DragSigma,
    FitChoice,
    Initial,
    InitialCovariance,
    ObjectOutcome,
    ObjectPlan,
    RunSettings,
    Status,
    _drag_note,
    _plans,
    _run_object,
    fit_catalog_objects,
)

if TYPE_CHECKING:
    import pandas
    import xarray
    from typing_extensions import Unpack

#: Zonal degree of catalog runs from element sets: J2..J4, the zonal terms SGP4 (which
#: produced the element sets) carries; J2 alone moves a LEO orbit by km a day from them.
CATALOG_ZONAL_DEGREE = 4


#: The ``frame`` attribute of catalog datasets: states come from SGP4.
CATALOG_FRAME = "TEME (SGP4's frame, taken as inertial)"

#: The statuses an object can end with (:class:`Status` values).
STATUSES = ("propagated", "non_gaussian", "decayed", "shortened", "failed", "stale")

#: Longest run (s) :func:`propagate_catalog` makes by default, from an object's epoch to
#: ``end``. A run holds the density tiles of every day it flies through (about 25 MB per
#: day of NRLMSIS) until it ends, so an element set months older than the rest of a
#: catalog (decayed or lost objects in merged snapshots) took the memory of months: 16 GB
#: for the 2023 snapshots merged. Such objects end "stale" instead; ``max_span=None``
#: runs them anyway. A TLE state that old is of little use in LEO: 1-3 km/day of error
#: growth (docs/catalog-realism.md). 60 days keeps a single published snapshot whole in a
#: 30-day run (its oldest element sets are about 30 days old: 27 days in CelesTrak's
#: 2023-11-13 "active" snapshot).
MAX_SPAN = 60 * 86400.0
#: What ``errors`` of :func:`propagate_catalog` accepts.
ERRORS = ("raise", "record")  # the values of errors= (rhoprop.Errors)


@dataclass(frozen=True)
class CatalogResult:
    """Per object mean and covariance on common output epochs.

    Attributes:
        objects: the input objects, in order.
        epochs: common output epochs, datetime64[ns] (nt,).
        mean: mean states (objects, nt, 6), m and m/s (TEME/inertial); NaN where not valid.
        covariance: covariances (objects, nt, 6, 6), SI; NaN where not valid.
        valid: whether the object has statistics at each output (objects, nt): False
            after its decay, after a CCSP stopped near decay, and everywhere for a failed
            object.
        decay_epoch: predicted decay epoch of the mean orbit, or NaT.
        decay_fraction: Monte Carlo only: fraction of members decayed by the end (else 0).
        method: the name of the uncertainty method, "ccsp" or "monte_carlo".
        covariance_note: per object, what the covariance includes (initial covariance
            and what propagation adds), in words.
        status: per object (objects,): ``"propagated"`` (every output from the
            object's epoch on valid),
            ``"non_gaussian"`` (every output valid, but from some epoch on the Cartesian
            covariance no longer holds the spread's shape: see ``gaussian``),
            ``"decayed"`` (the mean orbit came down at ``decay_epoch``), ``"shortened"``
            (the CCSP stopped early: a sigma point came down, or its covariance lost
            positive definiteness near decay), ``"failed"`` (only with
            ``errors="record"``), ``"stale"`` (not run: its epoch lies more than
            ``max_span`` before the end).
        reason: per object, what happened in words ("" when propagated): the decay epoch,
            where the CCSP stopped, or the error (type and message) of a failed object.
        drag_sigma: per object (objects,), the relative 1-sigma of Cd*A/m propagated (0:
            none); None for results built by hand.
        gaussian: per object and epoch (objects, nt), whether the Gaussian of ``mean``
            and ``covariance`` holds the spread's shape (False: the spread curves along
            the orbit; the object's status or reason says from when): for a CCSP its arc
            sag share below 0.5, for a Monte Carlo 90 % or more of its members inside the
            95 % position region (:mod:`rhoprop.propagation.gaussian_check`,
            docs/mc-vs-ccsp.md, "Every run knows"). True where not valid; None for
            results built by hand.
    """

    objects: list[CatalogObject]
    epochs: np.ndarray
    mean: np.ndarray
    covariance: np.ndarray
    valid: np.ndarray
    decay_epoch: np.ndarray
    decay_fraction: np.ndarray
    method: str
    status: np.ndarray
    reason: np.ndarray
    covariance_note: np.ndarray | None = None
    drag_sigma: np.ndarray | None = None
    gaussian: np.ndarray | None = None

    def moments_at(
        self, index: int, at: EpochLike, *, tolerance: float = DEFAULT_TOLERANCE
    ) -> tuple[OrbitState, np.ndarray]:
        """Object ``index``'s mean state (TEME, an :class:`~rhoprop.OrbitState`) and
        covariance (6, 6), SI, at the UTC epoch ``at``, interpolated between the outputs
        as :meth:`rhoprop.propagation.StateMoments.at` does (a ValueError where its
        outputs are too far apart for ``tolerance`` m, outside them or where not valid:
        hourly LEO outputs are; ``output_step`` of 600 s or less interpolates)."""
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
            raise TypeError(f"index must be an object's position, got {type(index).__name__}")
        if not -len(self.objects) <= index < len(self.objects):
            raise ValueError(f"index {index} is out of range for {len(self.objects)} objects")
        moments = StateMoments(
            self.epochs[0],
            to_seconds(self.epochs, self.epochs[0]),
            self.mean[index],
            self.covariance[index],
            frame="TEME",
        )
        try:
            return moments.at(at, tolerance=tolerance)
        except ValueError as err:
            raise ValueError(f"{self.objects[index].name}: {err}") from None

    def to_xarray(self) -> xarray.Dataset:
        """The run as an ``xarray.Dataset`` (needs the ``[xarray]`` extra).

        Dims ``object`` (0 .. n-1, with ``norad_id`` and ``name`` coordinates), ``epoch``
        (the common output epochs, datetime64[ns] UTC, with ``elapsed`` s since the
        first), ``state``/``state2`` (x ... vz), ``rtn``/``rtn2`` (R, T, N; RTN of each
        object's mean). Variables per object and epoch: ``mean``, ``covariance``,
        ``rtn_covariance``, ``along_track_std`` (NaN where not ``valid``), ``valid``,
        ``gaussian`` (whether the Gaussian holds the spread's shape);
        per object: ``status``, ``reason``, ``decay_epoch`` (NaT: none),
        ``decay_fraction``, ``drag_parameter`` (m^2/kg), ``object_epoch`` and
        ``covariance_note``. Attributes: frame (TEME), units, method, rhoprop version.
        """
        xr = optional_import("xarray", "CatalogResult.to_xarray()")
        times = to_seconds(self.epochs, self.epochs[0])
        data = moment_vars(("object", "epoch"), self.mean, self.covariance, CATALOG_FRAME)
        n = len(self.objects)
        notes = self.covariance_note if self.covariance_note is not None else [""] * n
        data.update(
            {
                "valid": (("object", "epoch"), np.asarray(self.valid, dtype=bool)),
                "gaussian": (
                    ("object", "epoch"),
                    (
                        np.ones(self.valid.shape, dtype=bool)
                        if self.gaussian is None
                        else np.asarray(self.gaussian, dtype=bool)
                    ),
                    {"long_name": "whether the Gaussian holds the spread's shape"},
                ),
                "status": ("object", _strings([str(v) for v in self.status])),
                "reason": ("object", _strings([str(v) for v in self.reason])),
                "decay_epoch": (
                    "object",
                    np.asarray(self.decay_epoch, dtype="datetime64[ns]"),
                    {"long_name": "decay epoch of the mean orbit (NaT: none)"},
                ),
                "decay_fraction": (
                    "object",
                    np.asarray(self.decay_fraction, dtype=float),
                    {
                        "units": "1",
                        "long_name": "fraction of Monte Carlo members decayed by the end",
                    },
                ),
                "drag_parameter": (
                    "object",
                    np.array([o.drag_parameter for o in self.objects], dtype=float),
                    {"units": "m^2/kg", "long_name": "Cd A/m"},
                ),
                "object_epoch": (
                    "object",
                    np.array([o.state.epoch for o in self.objects], dtype="datetime64[ns]"),
                    {"long_name": "epoch of the object's initial state"},
                ),
                "covariance_note": ("object", _strings([str(v) for v in notes])),
            }
        )
        ds: xarray.Dataset = xr.Dataset(
            data,
            coords={
                "object": ("object", np.arange(n)),
                "norad_id": ("object", np.array([o.norad_id for o in self.objects])),
                "name": ("object", _strings([o.name for o in self.objects])),
                **epoch_coords(self.epochs, times),
                **label_coords("state", "state2", "rtn", "rtn2"),
            },
            attrs=dataset_attrs(
                "CatalogResult",
                CATALOG_FRAME,
                rtn_frame="RTN of each object's mean state",
                method=self.method,
            ),
        )
        return ds

    def to_pandas(self) -> pandas.DataFrame:
        """The per-object summary (:func:`rhoprop.io.summary_table`: NORAD id, name,
        epoch, status and reason, last valid and decay epochs, RTN 1-sigma at the last
        valid output in m, what the covariance includes) as a ``pandas.DataFrame``, one
        row per object in input order (needs pandas, e.g. the ``[xarray]`` extra)."""
        pd = optional_import("pandas", "CatalogResult.to_pandas()")
        from ..io import summary_table

        frame: pandas.DataFrame = pd.DataFrame(summary_table(self))
        return frame


def _strings(values: list[str]) -> np.ndarray:
    """Text per object as an object array (variable-length strings in netCDF)."""
    out = np.empty(len(values), dtype=object)
    out[:] = values
    return out


def _shipped_model(model: Any) -> Any:
    """The atmosphere for all objects, as an object that pickles as a reference to travel
    to Dask workers: a sampled model becomes its :class:`~rhoprop.density.atlas.Atlas`
    (each object then gets the day tiles of its own span, every altitude included, so an
    object that comes down is reported as decayed); other models travel as they are."""
    if isinstance(model, SampledModel):
        return model.atlas
    if not callable(getattr(model, "atmosphere", None)):
        raise TypeError(
            f"model must be a density model or DensityField, got {type(model).__name__}"
        )
    return model


def common_epochs(
    objects: list[CatalogObject],
    end: np.datetime64,
    step: float,
    start: np.datetime64 | None = None,
) -> np.ndarray:
    """Output epochs shared by all objects: end, end - step, ... not before ``start``
    (default: the latest object epoch), at least the end itself."""
    first = max(o.state.epoch for o in objects) if start is None else start
    span = seconds_between(first, end)
    if span / step > MAX_STEPS:
        raise ValueError(
            f"output_step = {step:g} s gives {span / step:.3g} output epochs over {span:g} s, "
            f"more than the {MAX_STEPS:,} a run may have; use a larger output_step"
        )
    k = int(np.floor(span / step * (1 + 1e-12)))
    offsets = -step * np.arange(k, -1, -1)
    return offsets_to_epochs(end, offsets)


class CatalogKeywords(LooseFloorAndDegree, total=False):
    """The deprecated keywords of :func:`propagate_catalog`, each now in a settings
    record: the method's (``method=rp.MonteCarlo(n=, kappa=, seed=)`` or
    ``rp.Ccsp(update_interval=, kappa=)``), ``initial=rp.catalog.Initial(covariance=,
    drag_sigma=, fit=)``, ``execution=rp.Execution(client=, chunk_size=, progress=,
    errors=)`` and ``dynamics=rp.Dynamics(floor_altitude=, zonal_degree=)``."""

    n: int
    kappa: KappaProcess
    seed: int
    update_interval: float
    initial_covariance: InitialCovariance
    drag_sigma: DragSigma
    fit: FitChoice
    client: object
    chunk_size: int
    progress: bool | Callable[[int], object]
    errors: Errors


def propagate_catalog(
    objects: Iterable[CatalogObject],
    model: DensityModel,
    end: EpochLike,
    *,
    start: EpochLike | None = None,
    method: Method | MethodName = Ccsp(),
    output_step: float = 3600.0,
    initial: Initial | None = None,
    dynamics: Dynamics | None = None,
    max_span: float | None = MAX_SPAN,
    execution: Execution | None = None,
    **deprecated: Unpack[CatalogKeywords],
) -> CatalogResult:
    """Propagates every object from its own epoch to ``end`` (UTC).

    Args:
        objects: a :class:`Catalog` or list of :class:`CatalogObject`.
        model: density model (sampled once into a field covering all objects, down to
            50 km below the floor) or a :class:`~rhoprop.density.DensityField` /
            ``Exponential``.
        end: common end epoch, after every object's epoch.
        method: :class:`~rhoprop.Ccsp` (default ``rp.Ccsp()``: updates hourly, for an
            eccentric orbit, e >= 0.1, once per revolution at apogee with the outputs in
            between; its ``update_interval`` and ``kappa`` are honoured; its scaling,
            perturbation, ``drag_sigma`` and coordinates must stay at their defaults) or
            :class:`~rhoprop.MonteCarlo` (its ``n`` members, ``kappa``, ``perturbation``,
            ``threads`` and ``max_memory``; object i seeded with ``seed + i``;
            statistics over the members still flying at each output; its
            ``output_step``, ``drag_sigma``, ``record_density`` and ``progress`` must
            stay at their defaults: the catalog has its own). The strings ``"ccsp"`` and
            ``"monte_carlo"`` are deprecated: ``rp.Ccsp()`` and ``rp.MonteCarlo(n=100)``
            with a warning.
        start: no output epoch before it (UTC; default: the newest object's epoch, so
            every object is valid at every output). An earlier start gives the objects
            whose epoch is later no valid output before their epoch (rhoprop propagates
            forward only); it must be before ``end``.
        output_step: spacing of the common output epochs, s, counted back from ``end``.
        initial: a :class:`~rhoprop.catalog.Initial` (None: ``Initial()``): each object's
            initial covariance (default its own), Cd*A/m uncertainty (default ``"auto"``)
            and whether its state and Cd*A/m are first fitted to its element set (default
            ``"auto"``). An object whose Cd*A/m is B*'s plain conversion runs with it
            scaled to the model's density (:func:`~rhoprop.catalog.scaled_bstar_drag`;
            real-atmosphere models only), and ``objects`` of the result carry the value
            used and the fitted objects.
        dynamics: a :class:`~rhoprop.Dynamics` (None: ``Dynamics(zonal_degree=4)``,
            J2..J4 as SGP4 carries, from which the element sets come; 2 is the paper's
            J2-only model, the default until 0.1; up to 6). Its ``floor_altitude`` (m) is
            every object's decay floor, its ``step`` (s) every object's fixed step
            (None: the CCSP's RK8 at each object's
            :func:`~rhoprop.catalog.objects.catalog_step`, the Monte Carlo's 180 s); its
            ``integrator`` must be ``"rk8"`` for the CCSP and ``"rk8"``, ``"rk4"`` or
            ``"abm"`` for the Monte Carlo; ``rtol``, ``field_degree`` and
            ``third_bodies`` are refused (ValueError), never ignored. The fit before the
            run (``fit``) keeps its own RK8 grid.
        max_span: longest run, s from an object's epoch to ``end`` (default
            :data:`MAX_SPAN`, 60 days): an object whose epoch is older is not fitted or
            propagated and ends with status ``"stale"``, its reason saying so, so that a
            catalog holding a few months-old element sets runs in bounded memory (the
            density tiles of every day of a run stay in memory while it runs); None: no
            limit.
        execution: an :class:`~rhoprop.Execution` (None: the defaults): ``errors``
            ``"raise"`` (the first object that fails raises its error, same type, the
            object named, chained to the cause) or ``"record"`` (it gets status "failed"
            with the error as reason and no valid output, and the run goes on);
            ``progress`` (a bar of the objects done on a terminal for runs over a second,
            or a callable called with the number done); ``client``, a
            ``dask.distributed.Client``: objects are split into chunks of ``chunk_size``,
            the atmosphere is sent once and replicated to every worker (recomputed if a
            worker dies), failed tasks are retried twice; results equal the local run.
            Its ``threads`` and ``max_memory`` are refused (ValueError): a Monte Carlo's
            are the method's.
        **deprecated: the method's ``n=``, ``kappa=``, ``seed=``, ``update_interval=``
            (give them in ``method``); ``initial_covariance=``, ``drag_sigma=``, ``fit=``
            (in ``initial``: ``covariance``, ``drag_sigma``, ``fit``); ``client=``,
            ``chunk_size=``, ``progress=``, ``errors=`` (in ``execution``);
            ``floor_altitude=``, ``zonal_degree=`` (in ``dynamics``); each folded in with
            a DeprecationWarning.

    Returns:
        :class:`CatalogResult`, with a ``status`` and ``reason`` per object. Ctrl-C stops
        the run with KeyboardInterrupt.
    """
    objs = list(objects)
    if not objs:
        raise ValueError("the catalog has no objects")
    chosen, dyn, init, run_on = _settings(method, dynamics, initial, execution, deprecated)
    bad = [o for o in objs if not isinstance(o, CatalogObject)]
    if bad:
        raise TypeError(f"objects must be CatalogObjects, got a {type(bad[0]).__name__}")
    end64 = to_datetime64(end, "end")
    late = [o for o in objs if o.state.epoch >= end64]
    if late:
        raise ValueError(
            f"end {end64} is not after the epoch of object {late[0].norad_id} "
            f"({late[0].state.epoch})"
        )
    step = _validate.positive("output_step", output_step)
    limit = None if max_span is None else _validate.positive("max_span", max_span)
    stale = {
        i: reason
        for i, o in enumerate(objs)
        if (reason := beyond_max_span(seconds_between(o.state.epoch, end64), "end", limit))
    }
    cfg = RunSettings.checked(chosen, dyn, run_on.errors)
    fresh = [i for i in range(len(objs)) if i not in stale]
    fitted = fit_catalog_objects(
        [objs[i] for i in fresh],
        model,
        init.fit,
        cfg.dynamics,
        progress=run_on.progress is True,
    )
    for i, obj in zip(fresh, fitted, strict=True):
        objs[i] = obj
    plans = _plans(objs, init.covariance, init.drag_sigma, model, cfg.step)
    notes = [f"{p.initial_note}; {_drag_note(p.obj, p.drag_sigma, init.drag_sigma)}" for p in plans]
    epochs = common_epochs(objs, end64, step, _start(start, end64))
    shipped = _shipped_model(model)
    shown = None
    progress, client = run_on.progress, run_on.client
    if callable(progress):
        bar: Callable[[int], object] | None = progress
    else:
        shown = ProgressBar(len(objs), "catalog", unit="objects") if progress else None
        bar = shown
    try:
        results = Outcomes(len(objs), len(epochs))
        for i, reason in sorted(stale.items()):
            results[i] = ObjectOutcome.without_output(len(epochs), Status.STALE, reason)
        running = [plans[i] for i in fresh]
        if running and client is None:
            _run_local(running, shipped, epochs, cfg, bar, results)
        elif running:
            indexed = by_epoch(running)
            size = run_on.chunk_size
            chunks = [indexed[i : i + size] for i in range(0, len(indexed), size)]
            _run_on_dask(client, shipped, chunks, epochs, cfg, bar, results)
    finally:
        if shown is not None:
            shown.close()
    return _result(objs, epochs, cfg.method.name, results, plans, notes)


class OwnEpochsKeywords(LooseFloorAndDegree, total=False):
    """The deprecated keywords of :func:`propagate_to_own_epochs`, now in ``dynamics``."""

    step: float | None


#: Where each deprecated keyword of :func:`propagate_catalog` goes now.
_LOOSE = {
    "method": ("n", "kappa", "seed", "update_interval"),
    "initial": ("initial_covariance", "drag_sigma", "fit"),
    "execution": ("client", "chunk_size", "progress", "errors"),
}


def _settings(
    method: object,
    dynamics: Dynamics | None,
    initial: Initial | None,
    execution: Execution | None,
    deprecated: Mapping[str, object],
) -> tuple[Method, Dynamics, Initial, Execution]:
    """:func:`propagate_catalog`'s settings records, checked, with its deprecated loose
    keywords folded in (each with a DeprecationWarning pointing to its record)."""
    loose = dict(deprecated)
    part = {k: {n: loose.pop(n) for n in names if n in loose} for k, names in _LOOSE.items()}
    name = "propagate_catalog"
    chosen = method_argument(method, name, MonteCarlo(n=100), stacklevel=4)
    chosen = with_keywords(chosen, name, part["method"], stacklevel=4)
    init = fold_keywords(
        name,
        "initial",
        initial,
        Initial(),
        part["initial"],
        "rp.catalog.Initial",
        4,
        renamed={"initial_covariance": "covariance"},
    )
    run_on = execution_argument(name, execution, part["execution"], stacklevel=5)
    run_on.require_defaults(name, ("threads", "max_memory"))
    dyn = deprecated_keywords(
        name,
        dynamics,
        loose,
        Dynamics(zonal_degree=CATALOG_ZONAL_DEGREE),
        names=("floor_altitude", "zonal_degree"),
        stacklevel=4,
    )
    dyn.require_automatic_gravity(name)
    return chosen, dyn, init, run_on


@dataclass(frozen=True)
class OwnEpochsResult:
    """Per object, CCSP means (objects, k, 6) and covariances (objects, k, 6, 6) at its
    own epochs (``epochs[i]``; row i holds its first ``len(epochs[i])`` entries, NaN
    after), which are ``valid``, where the Cartesian Gaussian holds the spread
    (``gaussian``), and each object's status and reason, as :class:`CatalogResult`'s."""

    objects: list[CatalogObject]
    epochs: list[np.ndarray]
    mean: np.ndarray
    covariance: np.ndarray
    valid: np.ndarray
    gaussian: np.ndarray
    status: np.ndarray
    reason: np.ndarray


def propagate_to_own_epochs(
    objects: list[CatalogObject],
    model: DensityModel,
    epochs: list[np.ndarray],
    *,
    dynamics: Dynamics | None = None,
    sigma_scale: float = 1.0,
    client: object = None,  # a distributed.Client
    errors: Errors = "record",
    **deprecated: Unpack[OwnEpochsKeywords],
) -> OwnEpochsResult:
    """The CCSP of every object to its own output epochs (``epochs[i]``: increasing,
    from the object's epoch on, UTC), with :func:`propagate_catalog`'s defaults (no fit,
    each object's own covariance, ``drag_sigma="auto"``, hourly updates and one at each
    output; objects in chunks on threads or on Dask). Why: a run needing each object
    at a few epochs of its own (a screen's Pc at each event's TCA) would otherwise
    update every object's CCSP at the union of them all (a 300-s grid cost 3.5x an
    hourly run: benches/README.md, "All-on-all"). ``dynamics``: as
    :func:`propagate_catalog`'s (None: ``Dynamics(zonal_degree=4)``; its ``step`` every
    object's RK8 step, s, None: its :func:`~rhoprop.catalog.objects.catalog_step`;
    ``floor_altitude=``, ``zonal_degree=``, ``step=`` are deprecated); ``sigma_scale``:
    the factor on the model's density sigma (a mixture's spread: screen_all's Pc
    stage)."""
    objs = list(objects)
    if len(epochs) != len(objs):
        raise ValueError(f"epochs must give one array per object ({len(objs)}), got {len(epochs)}")
    own = [np.asarray(e, dtype="datetime64[ns]") for e in epochs]
    for o, e in zip(objs, own, strict=True):
        if e.ndim != 1 or not len(e) or (np.diff(e) <= np.timedelta64(0)).any():
            raise ValueError(f"object {o.norad_id}: its epochs must be 1-D, increasing, not empty")
        if e[0] < o.state.epoch:
            raise ValueError(f"object {o.norad_id}: epoch {e[0]} is before its own")
    errors = _validate.errors_and_client("propagate_to_own_epochs", errors, client)
    dyn = deprecated_keywords(
        "propagate_to_own_epochs",
        dynamics,
        deprecated,
        Dynamics(zonal_degree=CATALOG_ZONAL_DEGREE),
        names=("floor_altitude", "zonal_degree", "step"),
    )
    dyn.require_automatic_gravity("propagate_to_own_epochs")
    cfg = RunSettings.checked(Ccsp(), dyn, errors, sigma_scale, function="propagate_to_own_epochs")
    plans = [
        dataclasses.replace(p, epochs=e)
        for p, e in zip(_plans(objs, "object", "auto", model, cfg.step), own, strict=True)
    ]
    shipped = _shipped_model(model)
    results = Outcomes(len(objs), max(len(e) for e in own))
    none = np.empty(0, dtype="datetime64[ns]")  # every plan has its own
    if client is None:
        _run_local(plans, shipped, none, cfg, None, results)
    else:
        indexed = by_epoch(plans)
        chunks = [indexed[i : i + 50] for i in range(0, len(indexed), 50)]
        _run_on_dask(client, shipped, chunks, none, cfg, None, results)
    order = [results[i] for i in range(len(objs))]
    return OwnEpochsResult(
        objects=[p.obj for p in plans],
        epochs=own,
        mean=results.mean,
        covariance=results.cov,
        valid=results.valid,
        gaussian=results.gaussian,
        status=np.array([r.status.value for r in order], dtype=object),
        reason=np.array([r.reason for r in order], dtype=object),
    )


def _start(start: EpochLike | None, end: np.datetime64) -> np.datetime64 | None:
    """``start`` checked against ``end`` (None: the default)."""
    if start is None:
        return None
    first = to_datetime64(start, "start")
    if not first < end:
        raise ValueError(f"start {first} must be before end {end}")
    return first


def beyond_max_span(seconds: float, side: str, limit: float | None) -> str:
    """Why an epoch ``seconds`` from the ``side`` ("end": before it, "start", or "end"
    with negative seconds: after it) is not run, or "" when within ``limit`` (s; None:
    no limit)."""
    if limit is None or abs(seconds) <= limit:
        return ""
    where = f"before the {side}" if seconds > 0 else f"after the {side}"
    return (
        f"epoch {abs(seconds) / 86400:.1f} days {where}, beyond max_span "
        f"({limit / 86400:g} days; max_span=None, or --max-span 0, runs it)"
    )


def _result(
    objs: list[CatalogObject],
    epochs: np.ndarray,
    method: str,
    results: Outcomes,
    plans: list[ObjectPlan],
    notes: list[str],
) -> CatalogResult:
    """The :class:`CatalogResult` of the objects' outcomes (their arrays already in
    ``results``' catalog-ordered arrays)."""
    order = [results[i] for i in range(len(objs))]
    decay = np.array(
        [
            np.datetime64("NaT", "ns") if r.decay is None else add_seconds(o.state.epoch, r.decay)
            for r, o in zip(order, objs, strict=True)
        ],
        dtype="datetime64[ns]",
    )
    return CatalogResult(
        objects=[p.obj for p in plans],
        epochs=epochs,
        mean=results.mean,
        covariance=results.cov,
        valid=results.valid,
        decay_epoch=decay,
        decay_fraction=np.array([r.fraction for r in order]),
        method=method,
        status=np.array([r.status.value for r in order], dtype=object),
        reason=np.array([r.reason for r in order], dtype=object),
        covariance_note=np.array(notes, dtype=object),
        drag_sigma=np.array([p.drag_sigma for p in plans], dtype=float),
        gaussian=results.gaussian,
    )
