"""Catalog runs: CCSP or Monte Carlo over many objects from their own epochs to common
output epochs, locally (objects on threads) or on a Dask cluster, with decay prediction.
Every object ends with a status and a reason; errors are raised (or, on request,
recorded per object), never swallowed."""

from __future__ import annotations

import concurrent.futures as cf
import enum
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..constants import DEFAULT_FLOOR_ALTITUDE, R_EARTH
from ..density import DensityModel, SampledModel
from ..errors import CovarianceError, RhopropError
from ..parallel import map_in_threads, worker_count
from ..progress import ProgressBar
from ..propagation import (
    Spacecraft,
    ccsp,
    monte_carlo,
    propagate,
)
from ..propagation.ccsp import ccsp_many
from ..propagation.dynamics import Dynamics, resolve, zonal_degree_argument
from ..propagation.kappa import GaussMarkov, KappaProcess
from ..propagation.montecarlo import drag_sigma_argument
from ..propagation.results import (
    CcspResult,
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
from .covariance import paper_covariance
from .elements import CatalogObject
from .reentry_windows import DEFAULT_DRAG_RELATIVE_SIGMA

if TYPE_CHECKING:
    import pandas
    import xarray

#: Most objects per core call of a local CCSP run (:func:`_ccsp_chunk`).
CCSP_CHUNK = 16

#: The ``frame`` attribute of catalog datasets: states come from SGP4.
CATALOG_FRAME = "TEME (SGP4's frame, taken as inertial)"

#: Status of an object in a :class:`CatalogResult`.
#: ``initial_covariance`` of a catalog run: "object", "tle", "paper", one (6, 6) matrix
#: for all, a callable giving each object's, or None (the paper's).
InitialCovariance = (
    Literal["object", "tle", "paper"]
    | npt.ArrayLike
    | Callable[[CatalogObject], npt.ArrayLike]
    | None
)
#: ``drag_sigma`` of a catalog run: "auto", one relative sigma, or a callable per object.
DragSigma = Literal["auto"] | float | Callable[[CatalogObject], float]
#: The statuses an object can end with (:class:`Status` values).
STATUSES = ("propagated", "decayed", "shortened", "failed")
#: What ``errors`` of :func:`propagate_catalog` accepts.
ERRORS = ("raise", "record")  # the values of errors= (rhoprop._validate.Errors)


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
        method: "ccsp" or "monte_carlo".
        covariance_note: per object, what the covariance includes (initial covariance
            and what propagation adds), in words.
        status: per object (objects,): ``"propagated"`` (every output valid),
            ``"decayed"`` (the mean orbit came down at ``decay_epoch``), ``"shortened"``
            (the CCSP stopped early: a sigma point came down, or its covariance lost
            positive definiteness near decay), ``"failed"`` (only with
            ``errors="record"``).
        reason: per object, what happened in words ("" when propagated): the decay epoch,
            where the CCSP stopped, or the error (type and message) of a failed object.
        drag_sigma: per object (objects,), the relative 1-sigma of Cd*A/m propagated (0:
            none); None for results built by hand.
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

    def to_xarray(self) -> xarray.Dataset:
        """The run as an ``xarray.Dataset`` (needs the ``[xarray]`` extra).

        Dims ``object`` (0 .. n-1, with ``norad_id`` and ``name`` coordinates), ``epoch``
        (the common output epochs, datetime64[ns] UTC, with ``elapsed`` s since the
        first), ``state``/``state2`` (x ... vz), ``rtn``/``rtn2`` (R, T, N; RTN of each
        object's mean). Variables per object and epoch: ``mean``, ``covariance``,
        ``rtn_covariance``, ``along_track_std`` (NaN where not ``valid``), ``valid``;
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


#: What the covariance of a catalog run includes beside the initial covariance.
PROPAGATED_NOTE = (
    "propagated: density uncertainty of the model (kappa); not included: ballistic "
    "coefficient uncertainty, space-weather forecast error beyond the model's driver "
    "sigma, manoeuvres"
)


#: Largest relative Cd*A/m sigma of ``drag_sigma="auto"``: a fit whose prior dominated
#: (``FitResult.drag_observable`` False) reports formal sigmas of several times Cd*A/m.
AUTO_DRAG_SIGMA_MAX = 1.0
#: Smallest relative Cd*A/m sigma of ``drag_sigma="auto"`` for a fitted object: the fit's
#: formal sigma ignores how the density (and so the effective Cd*A/m) wanders after the
#: fit span. 0.08 gives close to Gaussian 1/2/3-sigma fractions on the realism benchmark
#: (docs/catalog-realism.md; chosen there, so in-sample); 0.15 overstates 1 sigma.
AUTO_FITTED_DRAG_SIGMA_MIN = 0.08


def _auto_drag_sigma(obj: CatalogObject) -> float:
    """``drag_sigma="auto"`` before the cap: a fitted object's formal relative sigma but
    at least :data:`AUTO_FITTED_DRAG_SIGMA_MIN`; without a fit (Cd*A/m from B*, which
    absorbs SGP4's own density model) ``DEFAULT_DRAG_RELATIVE_SIGMA`` (0.15)."""
    fit = obj.fit
    if fit is not None and obj.drag_parameter > 0:
        return max(float(fit.drag_sigma) / obj.drag_parameter, AUTO_FITTED_DRAG_SIGMA_MIN)
    return DEFAULT_DRAG_RELATIVE_SIGMA


def _drag_sigma(obj: CatalogObject, choice: Any) -> float:
    """The relative 1-sigma of Cd*A/m of ``obj`` for ``drag_sigma=choice``: "auto" is
    :func:`_auto_drag_sigma` (the fit's formal relative sigma, at least 0.08; 0.15 without
    a fit) capped at ``AUTO_DRAG_SIGMA_MAX`` (1); a number for every object; a callable
    object -> number. Checked like ``rp.ccsp``'s ``drag_sigma``."""
    if isinstance(choice, str):
        if choice != "auto":
            raise ValueError(f"drag_sigma must be 'auto', a number or a callable, got {choice!r}")
        value: Any = min(_auto_drag_sigma(obj), AUTO_DRAG_SIGMA_MAX)
    elif callable(choice):
        value = choice(obj)
    else:
        value = choice
    try:
        return drag_sigma_argument(value)
    except (TypeError, ValueError) as err:
        raise type(err)(f"object {obj.norad_id} ({obj.name}): {err}") from None


def _drag_note(obj: CatalogObject, sigma: float, choice: Any) -> str:
    """What the propagation includes, in words, for a relative Cd*A/m sigma ``sigma``."""
    if sigma == 0.0:
        return PROPAGATED_NOTE
    if isinstance(choice, str):
        why = (
            f"the fit's formal sigma, at least {AUTO_FITTED_DRAG_SIGMA_MIN:g}, at most "
            f"{AUTO_DRAG_SIGMA_MAX:g}"
            if obj.fit is not None
            else "assumed, no fit"
        )
    else:
        why = "user-supplied"
    return (
        f"propagated: density uncertainty of the model (kappa) and the ballistic "
        f"coefficient's (Cd*A/m relative 1-sigma {sigma:.3g}, {why}); not included: "
        f"space-weather forecast error beyond the model's driver sigma, manoeuvres"
    )


_PAPER_NOTE = "initial covariance: the paper's near-zero 1 mm, 1 um/s (Monte Carlo: none)"


def _strings(values: list[str]) -> np.ndarray:
    """Text per object as an object array (variable-length strings in netCDF)."""
    out = np.empty(len(values), dtype=object)
    out[:] = values
    return out


def _initial_covariance(obj: CatalogObject, choice: Any) -> tuple[np.ndarray | None, str]:
    """The initial covariance (6, 6) of ``obj`` for ``initial_covariance=choice`` and
    what it includes, in words; None for the propagators' own default (the paper's
    near-zero covariance in the CCSP, an exact initial state in a Monte Carlo)."""
    from .covariance import tle_covariance

    if isinstance(choice, str) and choice == "object":
        if obj.covariance is not None:
            return np.asarray(obj.covariance, dtype=float), obj.covariance_note
        return None, _PAPER_NOTE
    if choice is None or isinstance(choice, str):
        if choice is None or choice == "paper":
            return None, _PAPER_NOTE
        if choice == "tle":
            from .covariance import tle_accuracy
            from .elements import _tle_note

            return tle_covariance(obj.state), _tle_note(tle_accuracy(obj.state))
        raise ValueError(
            f"initial_covariance must be 'object', 'tle', 'paper', a (6, 6) matrix or a "
            f"callable, got {choice!r}"
        )
    if callable(choice):
        cov = np.asarray(choice(obj), dtype=float)
        note = "initial covariance: user-supplied (per object)"
    else:
        cov = np.asarray(choice, dtype=float)
        note = "initial covariance: user-supplied matrix"
    if cov.shape != (6, 6) or not np.all(np.isfinite(cov)):
        raise ValueError(f"initial_covariance must be a finite (6, 6) matrix, got {cov.shape}")
    return cov, note


class Status(enum.Enum):
    """How one object's run ended (the strings of :data:`STATUSES` in results)."""

    PROPAGATED = "propagated"
    DECAYED = "decayed"
    SHORTENED = "shortened"
    FAILED = "failed"


@dataclass(frozen=True)
class RunSettings:
    """The settings every object of a catalog run shares (checked by
    :func:`propagate_catalog`): ``method`` ("ccsp" or "monte_carlo"), members ``n`` and
    ``kappa`` and base ``seed`` of a Monte Carlo, the CCSP's ``update_interval`` (s), the
    ``floor_altitude`` (m), ``errors`` ("raise" or "record") and the ``zonal_degree``."""

    method: str
    n: int
    kappa: KappaProcess
    seed: int
    update_interval: float
    floor_altitude: float
    errors: str
    zonal_degree: int


@dataclass(frozen=True)
class ObjectOutcome:
    """One object's run: means (nt, 6) and covariances (nt, 6, 6) on the common epochs
    (NaN where invalid), which are ``valid``, the mean orbit's decay (s from the object's
    epoch, or None), the fraction of members decayed, the :class:`Status` and its reason,
    and the exception of a failed object (``errors="record"``)."""

    mean: np.ndarray
    cov: np.ndarray
    valid: np.ndarray
    decay: float | None
    fraction: float
    status: Status
    reason: str
    error: Exception | None = None


@dataclass(frozen=True)
class ObjectPlan:
    """What one object of a catalog run is run with, decided once before any run: its
    index in the catalog, the object, its initial covariance (None: the propagators'
    default) and what that covariance includes, and its Cd*A/m relative sigma. A user's
    ``initial_covariance`` callable is called here, once per object."""

    index: int
    obj: CatalogObject
    initial: np.ndarray | None
    initial_note: str
    drag_sigma: float


def _plans(objs: list[CatalogObject], initial_covariance: Any, drag_sigma: Any) -> list[ObjectPlan]:
    """One :class:`ObjectPlan` per object, in catalog order."""
    plans = []
    for i, obj in enumerate(objs):
        initial, note = _initial_covariance(obj, initial_covariance)
        plans.append(ObjectPlan(i, obj, initial, note, _drag_sigma(obj, drag_sigma)))
    return plans


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


def _object_error(err: Exception, obj: CatalogObject) -> Exception:
    """``err`` again (same type) with the object named in front, or ``err`` itself when
    its type takes no plain message."""
    try:
        named = type(err)(f"object {obj.norad_id} ({obj.name}, {obj.source}): {err}")
    except Exception:  # an exception type with a different constructor
        return err
    named.__dict__.update(vars(err))  # the core's values (time, axis, ...) stay attributes
    return named


def _run_object(
    plan: ObjectPlan,
    model: Any,
    epochs: np.ndarray,
    cfg: RunSettings,
    stop: threading.Event | None = None,
    done: dict[str, Any] | None = None,
) -> ObjectOutcome:
    """Propagates one object to the common epochs; returns arrays for the result. With
    ``cfg.errors == "record"`` an error becomes status "failed"; else it is raised
    with the object named and chained to the cause. ``stop`` (local runs) ends the
    object's Monte Carlo early after Ctrl-C in the caller. ``done`` holds runs already
    made for this object by :func:`_ccsp_chunk` (its mean orbit, its CCSP), used instead
    of running them again."""
    if stop is not None and stop.is_set():
        raise KeyboardInterrupt("catalog run interrupted")
    try:
        return _propagate_object(plan, model, epochs, cfg, stop, done or {})
    except Exception as err:
        if cfg.errors == "raise":
            named = _object_error(err, plan.obj)
            if named is err:
                raise
            raise named from err
        nt = len(epochs)
        return ObjectOutcome(
            mean=np.full((nt, 6), np.nan),
            cov=np.full((nt, 6, 6), np.nan),
            valid=np.zeros(nt, dtype=bool),
            decay=None,
            fraction=0.0,
            status=Status.FAILED,
            reason=f"{type(err).__name__}: {err}",
            error=err,
        )


def _propagate_object(
    plan: ObjectPlan,
    model: Any,
    epochs: np.ndarray,
    cfg: RunSettings,
    stop: threading.Event | None,
    done: dict[str, Any],
) -> ObjectOutcome:
    obj, initial = plan.obj, plan.initial
    craft = Spacecraft(1.0, obj.drag_parameter)
    offsets = to_seconds(epochs, obj.state.epoch)
    nt = len(epochs)
    out_mean = np.full((nt, 6), np.nan)
    out_cov = np.full((nt, 6, 6), np.nan)
    fraction = 0.0
    status, reason = Status.PROPAGATED, ""
    if cfg.method == "ccsp":
        decay, k = _mean_orbit(obj, craft, model, offsets, cfg, done)
        if k:
            means, covs, stopped = _ccsp_outputs(
                obj,
                craft,
                model,
                offsets[:k],
                cfg,
                initial,
                plan.drag_sigma,
                done.get("ccsp"),
            )
            reached = len(means)
            out_mean[:reached], out_cov[:reached] = means, covs
            if stopped:
                status, reason = Status.SHORTENED, stopped
    else:

        def check(_done: int) -> None:
            # Called by the core about every 50 ms: ends the run once the caller stops.
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt("catalog run interrupted")

        mc = monte_carlo(
            obj.state,
            craft,
            model,
            output_times=offsets,
            n=cfg.n,
            drag_sigma=plan.drag_sigma,
            kappa=cfg.kappa,
            seed=cfg.seed + plan.index,
            output_step=None,
            initial_covariance=initial,
            progress=check,
            floor_altitude=cfg.floor_altitude,
            zonal_degree=cfg.zonal_degree,
        )
        decay = mc.mean_orbit.decayed_at
        m = mc.moments()
        out_mean[:], out_cov[:] = m.mean, m.covariance
        fraction = float(np.mean(mc.decayed))
    valid = np.isfinite(out_cov).all(axis=(1, 2)) & np.isfinite(out_mean).all(axis=1)
    out_mean[~valid], out_cov[~valid] = np.nan, np.nan
    if decay is not None:
        at = add_seconds(obj.state.epoch, decay)
        # Decay is the headline; an earlier stop of the CCSP stays in the reason.
        reason = f"the mean orbit decays at {_iso(at)}" + (f"; {reason}" if reason else "")
        status = Status.DECAYED
    return ObjectOutcome(
        mean=out_mean,
        cov=out_cov,
        valid=valid,
        decay=decay,
        fraction=fraction,
        status=status,
        reason=reason,
    )


def _mean_orbit(
    obj: CatalogObject,
    craft: Spacecraft,
    model: Any,
    offsets: np.ndarray,
    cfg: RunSettings,
    done: dict[str, Any],
) -> tuple[float | None, int]:
    """The decay time of the mean orbit (s from the object's epoch, or None) and how many
    of ``offsets`` come before it; the propagation is kept in ``done["mean"]`` (None when
    :func:`_ccsp_chunk` found the object clear of the floor: no decay)."""
    if done.get("mean", False) is None:
        return None, len(offsets)
    if "mean" not in done:
        done["mean"] = propagate(
            obj.state,
            craft,
            model,
            float(offsets[-1]),
            integrator="rk8",
            floor_altitude=cfg.floor_altitude,
            zonal_degree=cfg.zonal_degree,
        )
    decay = done["mean"].decayed_at
    return decay, int(np.count_nonzero(offsets < (np.inf if decay is None else decay)))


def _ccsp_chunk(
    model: Any,
    chunk: list[ObjectPlan],
    epochs: np.ndarray,
    cfg: RunSettings,
    stop: threading.Event | None = None,
) -> list[tuple[int, ObjectOutcome]]:
    """The CCSP objects of a chunk: each object's mean orbit first, then the CCSPs of all
    of them in one core call (objects in parallel, each object's sigma points in one
    batch; bit-identical to running each alone), then each object as
    :func:`_run_object` with those runs reused. An object whose mean orbit or batched
    CCSP raised runs again alone, so statuses, shortened runs, field widening and errors
    are exactly those of the object-by-object run."""
    done: dict[int, dict[str, Any]] = {p.index: {} for p in chunk}
    runs, owners = [], []
    for plan in chunk:
        if stop is not None and stop.is_set():
            raise KeyboardInterrupt("catalog run interrupted")
        i, obj = plan.index, plan.obj
        craft = Spacecraft(1.0, obj.drag_parameter)
        offsets = to_seconds(epochs, obj.state.epoch)
        if offsets[-1] <= 0:
            continue
        # Optimistically over every output: the mean orbit (one lane, for its decay time)
        # is needed only if the CCSP comes near the floor (checked below).
        runs.append(
            {
                "state": obj.state,
                "spacecraft": craft,
                "update_times": _update_times(offsets, cfg.update_interval),
                "initial_covariance": plan.initial,
                "drag_sigma": plan.drag_sigma,
            }
        )
        owners.append(i)

    def check(_done: int) -> None:
        # Called by the core about every 50 ms: ends the call once the caller stops.
        if stop is not None and stop.is_set():
            raise KeyboardInterrupt("catalog run interrupted")

    if runs:
        try:
            outs = ccsp_many(
                runs,
                model,
                floor_altitude=cfg.floor_altitude,
                zonal_degree=cfg.zonal_degree,
                progress=check,
            )
        except Exception:
            outs = []  # every object runs alone, raising (or recording) as before
        for i, out in zip(owners, outs, strict=False):
            if not isinstance(out, Exception) and _clear_of_floor(out, cfg):
                done[i]["ccsp"] = out
                done[i]["mean"] = None  # the mean orbit cannot have come down
    return [(p.index, _run_object(p, model, epochs, cfg, stop, done[p.index])) for p in chunk]


#: How far above the floor (m) a CCSP's mean must stay, at every update, for the mean
#: orbit's decay check to be skipped: an orbit on its way down within the span has its
#: sigma points come down (the CCSP stops) or its mean sinks towards the floor first.
MEAN_ORBIT_MARGIN = 50e3


def _clear_of_floor(result: CcspResult, cfg: RunSettings) -> bool:
    """Whether a CCSP ran to its end with its mean at least :data:`MEAN_ORBIT_MARGIN`
    above the floor throughout (|r| - equatorial radius, a lower bound of the geodetic
    altitude)."""
    if result.decayed_at is not None:
        return False
    low = float(np.min(np.linalg.norm(result.mean[:, :3], axis=1))) - R_EARTH
    return bool(low > float(cfg.floor_altitude) + MEAN_ORBIT_MARGIN)


def _iso(t: np.datetime64) -> str:
    return str(t.astype("datetime64[ms]")) + "Z"


def _ccsp_outputs(
    obj: CatalogObject,
    craft: Spacecraft,
    model: Any,
    offsets: np.ndarray,
    cfg: RunSettings,
    initial: np.ndarray | None,
    drag_sigma: float = 0.0,
    first: CcspResult | None = None,
) -> tuple[np.ndarray, np.ndarray, str]:
    """CCSP means (k, 6) and covariances (k, 6, 6) at the first k of ``offsets`` (s from
    the object's epoch) it reached, and "" or why it stopped before the last. Only a
    covariance that stops being positive definite (near decay) or a sigma point that
    comes down shortens the outputs; every other error is raised. ``first`` is the run
    over all of ``offsets`` if already made (:func:`_ccsp_chunk`)."""
    state = obj.state

    def run(k: int) -> Any:
        if offsets[k - 1] <= 0:  # every output at the object's own epoch
            return None
        return ccsp(
            state,
            craft,
            model,
            update_times=_update_times(offsets[:k], cfg.update_interval),
            initial_covariance=initial,
            floor_altitude=cfg.floor_altitude,
            zonal_degree=cfg.zonal_degree,
            drag_sigma=drag_sigma,
        )

    k, why = len(offsets), ""
    try:
        r = first if first is not None and offsets[k - 1] > 0 else run(k)
    except CovarianceError as err:
        if err.time is None or err.time <= 0:
            raise  # the initial covariance itself: bad input, not a shortened run
        t_bad = float(err.time)
        k = int(np.count_nonzero(offsets < t_bad))
        why = (
            f"the CCSP covariance lost positive definiteness at "
            f"{_iso(add_seconds(state.epoch, t_bad))} (near decay); later outputs invalid"
        )
        if k == 0:
            return np.empty((0, 6)), np.empty((0, 6, 6)), why
        try:
            r = run(k)
        except RhopropError as again:
            raise again from err
    if r is None:
        means = np.broadcast_to(state.state, (k, 6))
        start = paper_covariance() if initial is None else initial
        return means, np.broadcast_to(start, (k, 6, 6)), why
    reached = int(np.count_nonzero(offsets[:k] <= r.times[-1] * (1 + 1e-12)))
    if r.decayed_at is not None and reached < len(offsets):
        why = (
            f"the CCSP stopped when a sigma point came down at "
            f"{_iso(add_seconds(state.epoch, r.decayed_at))}; later outputs invalid"
        )
    pick = np.searchsorted(r.times, offsets[:reached] * (1 - 1e-12))
    return r.mean[pick], r.covariance[pick], why


def _update_times(offsets: np.ndarray, interval: float) -> np.ndarray:
    """CCSP update times: every ``interval`` s, plus every output offset (> 0)."""
    grid = np.arange(interval, offsets[-1], interval)
    times = np.unique(np.concatenate([grid, offsets[offsets > 0]]))
    return times if len(times) else np.array([offsets[-1]])


def _run_chunk(
    model: Any, chunk: list[ObjectPlan], epochs: np.ndarray, cfg: RunSettings
) -> list[tuple[int, ObjectOutcome]]:
    """A Dask task: run the objects of the chunk (the model arrives unpickled once per
    worker); CCSPs in one core call per chunk."""
    if cfg.method == "ccsp":
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
    bar: ProgressBar | None,
) -> dict[int, ObjectOutcome]:
    """Runs the chunks on a Dask cluster. The atmosphere is scattered to every worker once
    (broadcast); tasks retry twice; a chunk whose task is lost with a dying worker (or
    whose scattered atmosphere went with it) is submitted again, up to three rounds, so no
    object is lost and none is counted twice (results are keyed by object index). An
    exception the task itself raised is raised here at once, with its own type."""
    results: dict[int, ObjectOutcome] = {}
    pending = list(range(len(chunks)))
    last: BaseException | None = None
    for _ in range(3):
        shared = client.scatter(model, broadcast=True)
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


def common_epochs(objects: list[CatalogObject], end: np.datetime64, step: float) -> np.ndarray:
    """Output epochs shared by all objects: end, end - step, ... not before the latest
    object epoch (at least the end itself)."""
    latest = max(o.state.epoch for o in objects)
    span = seconds_between(latest, end)
    k = int(np.floor(span / step * (1 + 1e-12)))
    offsets = -step * np.arange(k, -1, -1)
    return offsets_to_epochs(end, offsets)


def by_epoch(plans: list[ObjectPlan]) -> list[ObjectPlan]:
    """The plans in epoch order: chunks of objects close in time share their atlas tiles,
    so the tiles in use at once stay few however the epochs spread."""
    return sorted(plans, key=lambda plan: plan.obj.state.epoch)


def _run_local(
    plans: list[ObjectPlan],
    shipped: Any,
    epochs: np.ndarray,
    cfg: RunSettings,
    bar: ProgressBar | None,
) -> dict[int, ObjectOutcome]:
    """Objects on threads (the core releases the GIL), each also parallel over its own
    sigma points or members. Ctrl-C (or an error) cancels the objects not started and
    stops running Monte Carlos at once; a running CCSP finishes its object first."""
    stop = threading.Event()
    workers = worker_count()
    results: dict[int, ObjectOutcome] = {}

    def tick(_i: int, _result: object) -> None:
        if bar is not None:
            bar(len(results))

    if cfg.method == "ccsp":
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


def propagate_catalog(
    objects: Iterable[CatalogObject],
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
    client: Any = None,  # a distributed.Client (Any: distributed stays optional)
    chunk_size: int = 50,
    progress: bool = True,
    errors: _validate.Errors = "raise",
    initial_covariance: InitialCovariance = None,
    zonal_degree: int = 2,
    drag_sigma: DragSigma = "auto",
    dynamics: Dynamics | None = None,
) -> CatalogResult:
    """Propagates every object from its own epoch to ``end`` (UTC).

    Args:
        objects: a :class:`Catalog` or list of :class:`CatalogObject`.
        model: density model (sampled once into a field covering all objects, down to
            50 km below the floor) or a :class:`~rhoprop.density.DensityField` /
            ``Exponential``.
        end: common end epoch, after every object's epoch.
        method: ``"ccsp"`` (default; ``update_interval`` s) or ``"monte_carlo"`` (``n``
            members, ``kappa`` process, object i seeded with ``seed + i``; statistics over
            the members still flying at each output).
        output_step: spacing of the common output epochs, s, counted back from ``end``.
        client: a ``dask.distributed.Client``: objects are split into chunks of
            ``chunk_size``, the atmosphere is sent once and replicated to every worker
            (recomputed if a worker dies), failed tasks are retried twice; results equal
            the local run.
        progress: show a progress bar (objects done) on a terminal for runs over a second.
        errors: ``"raise"`` (default): the first object that fails raises its error (same
            type, the object named, chained to the cause); ``"record"``: it gets status
            "failed" with the error as reason and no valid output, and the run goes on.
        initial_covariance: each object's initial covariance at its epoch:
            ``"object"`` (recommended; the ``rhoprop catalog`` default): the object's own
            ``covariance`` (``load`` sets the published TLE accuracy of its regime; fitted
            objects add the fit's); ``"tle"``: the TLE accuracy of the regime;
            ``"paper"`` or ``None`` (the default, kept for compatibility): the paper's
            near-zero diag(1 mm^2, 1 um^2/s^2), 100x too small for TLE-derived states
            (docs/catalog-realism.md); a (6, 6) matrix (m^2, m^2/s, m^2/s^2, inertial) for
            every object; or a callable object -> matrix. What it includes is in
            ``covariance_note`` (and the OEM and summary).
        zonal_degree: highest zonal harmonic of the gravity field: 2 (default) is J2
            only, the paper's model; up to 6 adds J3..J6 (EGM2008).
        drag_sigma: relative 1-sigma of each object's Cd*A/m (dimensionless, 0.15 =
            15 %), propagated as the CCSP's second consider parameter or sampled per Monte
            Carlo member (log-normal, see ``rp.monte_carlo``): ``"auto"`` (default) the
            fit's formal relative sigma but at least 0.08 (at most 1, for fits whose prior
            dominated), or 0.15 for an object without a fit (as ``rp.catalog.reentry``);
            a number for every object (0: none,
            the behaviour before issue 16); or a callable object -> number. Recorded in
            ``drag_sigma`` and ``covariance_note`` (docs/catalog-realism.md).
        dynamics: a :class:`~rhoprop.Dynamics` holding ``floor_altitude`` and
            ``zonal_degree`` at once (then leave those keywords at their defaults; its
            integrator and step are not used: the CCSP integrates with RK8 at its default
            step, the Monte Carlo with its defaults).

    Returns:
        :class:`CatalogResult`, with a ``status`` and ``reason`` per object. Ctrl-C stops
        the run with KeyboardInterrupt.
    """
    objs = list(objects)
    if not objs:
        raise ValueError("the catalog has no objects")
    if method not in ("ccsp", "monte_carlo"):
        raise ValueError(f"unknown method {method!r}; expected 'ccsp' or 'monte_carlo'")
    errors = _validate.errors_argument("propagate_catalog", errors)
    bad = [o for o in objs if not isinstance(o, CatalogObject)]
    if bad:
        raise TypeError(f"objects must be CatalogObjects, got a {type(bad[0]).__name__}")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    process = kappa or GaussMarkov()
    if not isinstance(process, KappaProcess):
        raise TypeError(f"kappa must be a rhoprop.kappa process, got {type(kappa).__name__}")
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
        raise ValueError(f"chunk_size must be a positive integer, got {chunk_size!r}")
    end64 = to_datetime64(end, "end")
    late = [o for o in objs if o.state.epoch >= end64]
    if late:
        raise ValueError(
            f"end {end64} is not after the epoch of object {late[0].norad_id} "
            f"({late[0].state.epoch})"
        )
    step = _validate.positive("output_step", output_step)
    dyn = resolve(
        "propagate_catalog",
        dynamics,
        Dynamics(),
        floor_altitude=floor_altitude,
        zonal_degree=zonal_degree,
    )
    floor, zonal_degree = dyn.floor_altitude, dyn.zonal_degree
    cfg = RunSettings(
        method=method,
        n=int(n),
        kappa=process,
        seed=int(seed),
        update_interval=_validate.positive("update_interval", update_interval),
        floor_altitude=floor,
        errors=errors,
        zonal_degree=zonal_degree_argument(zonal_degree),
    )
    plans = _plans(objs, initial_covariance, drag_sigma)
    notes = [f"{p.initial_note}; {_drag_note(p.obj, p.drag_sigma, drag_sigma)}" for p in plans]
    epochs = common_epochs(objs, end64, step)
    shipped = _shipped_model(model)
    bar = ProgressBar(len(objs), "catalog", unit="objects") if progress else None
    try:
        if client is None:
            results = _run_local(plans, shipped, epochs, cfg, bar)
        else:
            indexed = by_epoch(plans)
            chunks = [indexed[i : i + chunk_size] for i in range(0, len(indexed), chunk_size)]
            results = _run_on_dask(client, shipped, chunks, epochs, cfg, bar)
    finally:
        if bar is not None:
            bar.close()
    order = [results[i] for i in range(len(objs))]
    decay = np.array(
        [
            np.datetime64("NaT", "ns") if r.decay is None else add_seconds(o.state.epoch, r.decay)
            for r, o in zip(order, objs, strict=True)
        ],
        dtype="datetime64[ns]",
    )
    return CatalogResult(
        objects=objs,
        epochs=epochs,
        mean=np.stack([r.mean for r in order]),
        covariance=np.stack([r.cov for r in order]),
        valid=np.stack([r.valid for r in order]),
        decay_epoch=decay,
        decay_fraction=np.array([r.fraction for r in order]),
        method=method,
        status=np.array([r.status.value for r in order], dtype=object),
        reason=np.array([r.reason for r in order], dtype=object),
        covariance_note=np.array(notes, dtype=object),
        drag_sigma=np.array([p.drag_sigma for p in plans], dtype=float),
    )
