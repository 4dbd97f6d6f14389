"""Multi-model ensembles (paper section 5): each model propagated with its debiased drag
coefficient, each model's position PDF fitted by a Gaussian, combined as a mixture in the
RTN frame of the reference model's mean orbit."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from .. import _validate
from .._deprecated import fold_keywords
from ..density import (
    JB2008_CALIBRATED,
    JR_CALIBRATED,
    DensityModel,
    JacchiaRoberts,
    Jb2008,
    MeanCorrection,
    Msis,
    SigmaScaled,
    calibrated,
)
from ..propagation import (
    CcspResult,
    Dynamics,
    MonteCarlo,
    MonteCarloResult,
    OrbitState,
    Spacecraft,
)
from ..propagation.methods import Ccsp, Method, MethodName, method_argument, with_keywords
from ..propagation.propagate import check_model
from ..propagation.results import (
    dataset_attrs,
    epoch_coords,
    iso_utc,
    kappa_attrs,
    label_coords,
    optional_import,
)
from ..time import offsets_to_epochs
from .debias import Debias, debias_drag_coefficient
from .mixture import GaussianMixture

if TYPE_CHECKING:
    import xarray

#: The names of the uncertainty methods (``EnsembleResult.to_xarray``'s ``method``).
METHODS = (MonteCarlo.name, Ccsp.name)


@dataclass(frozen=True)
class EnsembleResult:
    """An ensemble of density models.

    Attributes:
        names: model names, in order; ``reference`` the reference model's name.
        cd: drag coefficient used per model (the reference keeps Cd_ref).
        results: per model, the MonteCarloResult or CcspResult.
        times: output times, s from the epoch (nt,).
        reference_positions, reference_velocities: the reference mean orbit (nt, 3):
            the reference model's mean orbit (Monte Carlo: its ``reference_positions``,
            the mean orbit until it decays, then the survivors' mean) or CCSP mean.
        component_means: per time and model, the mean position offset from the reference
            mean orbit in its RTN frame (nt, k, 3), m, over the members still flying
            (Monte Carlo); NaN where a model has no statistics (decayed).
        component_covariances: the matching covariances (nt, k, 3, 3), m^2.
        weights: mixture weights (k,), summing to 1.
        spread: the factor every model's density sigma ran with (1: the model's own;
            the calibrated families with their calibrated weights run narrowed,
            :func:`default_spread`).
    """

    names: list[str]
    reference: str
    cd: dict[str, float]
    results: dict[str, MonteCarloResult | CcspResult]
    times: np.ndarray
    reference_positions: np.ndarray
    reference_velocities: np.ndarray
    component_means: np.ndarray
    component_covariances: np.ndarray
    weights: np.ndarray
    spread: float = 1.0

    def gaussian(self) -> np.ndarray:
        """Per output and model (nt, k), whether that model's Gaussian holds the shape of
        its spread (False: it curves along the orbit, and the component, an ellipsoid,
        misses members): a CCSP's arc sag share below 0.5, a Monte Carlo's members 90 %
        or more inside their own 95 % region (:mod:`rhoprop.propagation.gaussian_check`,
        docs/mc-vs-ccsp.md, "Every run knows")."""
        from ..propagation.gaussian_check import arc_sag_share, holds, member_coverage

        out = np.ones((len(self.times), len(self.names)), dtype=bool)
        for j, name in enumerate(self.names):
            r = self.results[name]
            if isinstance(r, CcspResult):
                if r.element_mean is None or r.element_covariance is None:
                    continue
                ok = holds(
                    sag_share=arc_sag_share(r.element_mean, r.element_covariance, r.rtn_covariance)
                )
            else:
                m = r.moments()
                ok = holds(coverage=member_coverage(r.positions, m.mean, m.covariance))
            at = np.searchsorted(r.times, np.asarray(self.times) * (1 - 1e-12))
            out[:, j] = ok[np.clip(at, 0, len(ok) - 1)]
        return out

    def mixture(self, time_index: int = -1) -> GaussianMixture:
        """The 3-D position mixture (RTN of the reference mean orbit, m) at an output.
        A model without statistics then (all its members, or its CCSP, came down) is a
        ValueError naming it."""
        means = self.component_means[time_index]
        covs = self.component_covariances[time_index]
        missing = [
            name
            for i, name in enumerate(self.names)
            if not (np.isfinite(means[i]).all() and np.isfinite(covs[i]).all())
        ]
        if missing:
            raise ValueError(
                f"no statistics at t = {self.times[time_index]:g} s for {missing}: the object "
                "decayed in those models (fewer than two members left, or the CCSP stopped) "
                "or the reference orbit did"
            )
        return GaussianMixture(
            self.weights,
            self.component_means[time_index],
            self.component_covariances[time_index],
        )

    def along_track_mixture(self, time_index: int = -1) -> GaussianMixture:
        """The 1-D along-track mixture, m."""
        return self.mixture(time_index).marginal(axes=[1])

    def along_track_pdf(self, x: npt.ArrayLike, time_index: int = -1) -> np.ndarray:
        """Along-track PDF of the mixture at ``x`` (m), 1/m."""
        return self.along_track_mixture(time_index).pdf(np.asarray(x, dtype=float))

    def summary(self, time_index: int = -1) -> dict[str, Any]:
        """Per model Cd and along-track mean/std; mixture mean, std, 95 % interval, modes."""
        at = self.along_track_mixture(time_index)
        lo, hi = at.interval(0.95)
        models = {
            name: {
                "cd": self.cd[name],
                "along_track_mean_m": float(self.component_means[time_index, i, 1]),
                "along_track_std_m": float(
                    np.sqrt(self.component_covariances[time_index, i, 1, 1])
                ),
            }
            for i, name in enumerate(self.names)
        }
        mixture = {
            "mean_m": float(at.mean()[0]),
            "std_m": float(np.sqrt(at.covariance()[0, 0])),
            "q025_m": float(lo),
            "q975_m": float(hi),
            "modes": int(at.n_modes()),
        }
        return {"models": models, "mixture": mixture}

    def to_xarray(self) -> xarray.Dataset:
        """The ensemble as an ``xarray.Dataset`` (needs the ``[xarray]`` extra).

        Dims ``model`` (the model names), ``epoch`` (datetime64[ns] UTC coordinate, with
        ``elapsed`` s), ``rtn``/``rtn2`` (R, T, N; the RTN frame of the reference mean
        orbit) and ``component`` (x, y, z). Variables: ``cd`` and ``weight`` per model;
        ``component_mean`` (m) and ``component_covariance`` (m^2) per model and epoch;
        ``mixture_along_track_mean`` and ``mixture_along_track_std`` (m, the mixture's
        along-track moments; NaN where a model has no statistics); the reference mean
        orbit ``reference_position``/``reference_velocity`` (inertial). Attributes: the
        reference model, the method, its kappa process, seed and members (Monte Carlo),
        the initial epoch and the rhoprop version. Each model's own run:
        ``results[name].to_xarray()``.
        """
        xr = optional_import("xarray", "EnsembleResult.to_xarray()")
        first = self.results[self.reference]
        means = np.asarray(self.component_means, dtype=float)  # (nt, k, 3)
        covs = np.asarray(self.component_covariances, dtype=float)  # (nt, k, 3, 3)
        w = np.asarray(self.weights, dtype=float)
        mu, var = means[:, :, 1], covs[:, :, 1, 1]
        ok = np.isfinite(mu).all(axis=1) & np.isfinite(var).all(axis=1)
        mix_mean = np.where(ok, (mu * w).sum(axis=1), np.nan)
        second = ((var + mu**2) * w).sum(axis=1)
        mix_std = np.where(ok, np.sqrt(np.maximum(second - mix_mean**2, 0.0)), np.nan)
        rtn = "RTN of the reference mean orbit"
        vec = ("epoch", "component")
        extra: dict[str, Any] = {}
        if isinstance(first, MonteCarloResult):
            extra = {
                **kappa_attrs(first.kappa),
                "seed": int(first.seed),
                "members": len(first.decay_times),
            }
        ds: xarray.Dataset = xr.Dataset(
            {
                "cd": (
                    "model",
                    [self.cd[n] for n in self.names],
                    {"units": "1", "long_name": "drag coefficient"},
                ),
                "weight": ("model", w, {"units": "1", "long_name": "mixture weight"}),
                "spread": (
                    (),
                    float(self.spread),
                    {"units": "1", "long_name": "factor on every model's density sigma"},
                ),
                "component_mean": (
                    ("model", "epoch", "rtn"),
                    means.transpose(1, 0, 2),
                    {"units": "m", "long_name": "mean position offset", "frame": rtn},
                ),
                "component_covariance": (
                    ("model", "epoch", "rtn", "rtn2"),
                    covs.transpose(1, 0, 2, 3),
                    {"units": "m^2", "long_name": "position covariance", "frame": rtn},
                ),
                "mixture_along_track_mean": (
                    "epoch",
                    mix_mean,
                    {"units": "m", "long_name": "along-track mean of the mixture", "frame": rtn},
                ),
                "mixture_along_track_std": (
                    "epoch",
                    mix_std,
                    {"units": "m", "long_name": "along-track std of the mixture", "frame": rtn},
                ),
                "reference_position": (
                    vec,
                    np.asarray(self.reference_positions, dtype=float),
                    {"units": "m", "long_name": "reference mean orbit", "frame": first.frame},
                ),
                "reference_velocity": (
                    vec,
                    np.asarray(self.reference_velocities, dtype=float),
                    {"units": "m/s", "long_name": "reference mean orbit", "frame": first.frame},
                ),
            },
            coords={
                **epoch_coords(offsets_to_epochs(first.epoch, self.times), self.times),
                "model": ("model", np.array(self.names, dtype=object)),
                **label_coords("component", "rtn", "rtn2"),
            },
            attrs=dataset_attrs(
                "EnsembleResult",
                first.frame,
                rtn_frame=rtn,
                initial_epoch=iso_utc(first.epoch),
                reference=self.reference,
                method=MonteCarlo.name if isinstance(first, MonteCarloResult) else Ccsp.name,
                **extra,
            ),
        )
        return ds


def _family(model: object) -> str | None:
    """The calibrated family a model belongs to (with its calibrated mean correction in
    force), else None."""
    if isinstance(model, Msis) and model.version in ("2.1", "2.0"):
        name = "NRLMSIS 2.1"
        expected = MeanCorrection(calibrated.MSIS_SCALE, calibrated.MSIS_F107_EXPONENT)
    elif isinstance(model, Jb2008):
        name, expected = "JB2008", JB2008_CALIBRATED[1]
    elif isinstance(model, JacchiaRoberts):
        name, expected = "Jacchia-Roberts", JR_CALIBRATED[1]
    else:
        return None
    return name if model.correction == expected else None


def _calibrated_weights(models: Mapping[str, object]) -> np.ndarray | None:
    """The calibrated weights of ``models`` (by log score on observed densities) when
    every model is a calibrated family and they give a positive total, else None: the
    one rule behind both :func:`default_weights` and :func:`default_spread`."""
    families = [_family(m) for m in models.values()]
    if not all(f is not None for f in families):
        return None
    w = np.array([calibrated.ENSEMBLE_WEIGHTS[str(f)] for f in families])
    return w if w.sum() > 0 else None


def default_weights(models: Mapping[str, object]) -> np.ndarray:
    """Mixture weights of ``models``: :data:`rhoprop.density.calibrated.ENSEMBLE_WEIGHTS`
    (by log score on observed orbit-averaged densities) when every model is a calibrated
    family and they give a positive total, else equal."""
    w = _calibrated_weights(models)
    return np.ones(len(models)) if w is None else w


def default_spread(models: Mapping[str, object]) -> float:
    """The factor on every model's density sigma of an ensemble with the default weights:
    :data:`rhoprop.density.calibrated.ENSEMBLE_SPREAD` when :func:`default_weights` are
    the calibrated families' (fitted together with them by log score on observed
    densities: a pool of calibrated models is over-dispersed where their means differ),
    else 1."""
    return 1.0 if _calibrated_weights(models) is None else calibrated.ENSEMBLE_SPREAD


def ensemble(
    state: OrbitState,
    spacecraft: Spacecraft,
    models: dict[str, DensityModel],
    reference: str,
    *,
    method: Method | MethodName = MonteCarlo(),
    weights: npt.ArrayLike | Mapping[str, float] | None = None,
    spread: float | None = None,
    debias: Debias | None = None,
    duration: float = 259200.0,
    dynamics: Dynamics | None = None,
    **deprecated: object,
) -> EnsembleResult:
    """Propagates ``state`` through every model and combines them into a Gaussian mixture.

    Args:
        state, spacecraft: the initial state and the object (``spacecraft.cd`` is Cd_ref,
            the drag coefficient that belongs to the reference model).
        models: {name: density model}; ``reference`` names the reference model.
        method: :class:`~rhoprop.MonteCarlo` (default ``rp.MonteCarlo()``: 1,000 members
            of the calibrated :class:`~rhoprop.kappa.TwoScale`, hourly outputs) or
            :class:`~rhoprop.Ccsp`, with its settings (``rp.MonteCarlo(n=300, seed=2)``);
            every model runs with them. The strings ``"monte_carlo"`` and ``"ccsp"`` are
            deprecated (the default objects, with a warning).
        weights: mixture weights per model, in the order of ``models`` or as a mapping
            {model name: weight}. Default: :func:`default_weights` (the weights calibrated
            by log score on observed densities when every model is a calibrated NRLMSIS
            2.x, JB2008 or Jacchia-Roberts; else equal).
        spread: factor on every model's density sigma inside the mixture (each runs as
            :class:`~rhoprop.density.SigmaScaled`); None (default): with the default
            weights :func:`default_spread` (the calibrated families' fitted factor), with
            weights given 1 (each model's own sigma).
        debias: a :class:`~rhoprop.Debias` (None: ``Debias()``): each model's Cd is
            debiased against the reference over its ``window`` before the epoch (default
            8 h; :func:`~rhoprop.debias_drag_coefficient`), except the models whose Cd its
            ``cds`` gives.
        duration: s.
        dynamics: the :class:`~rhoprop.Dynamics` every model's run integrates with
            (None: the method's defaults).
        **deprecated: the method's settings (``n=``, ``seed=``, ``update_interval=``,
            ...: give them in the method object) and ``debias_window=``, ``cds=`` (in
            ``debias``: ``window``, ``cds``), folded in with a DeprecationWarning.

    Returns:
        :class:`EnsembleResult`; ``.mixture()`` and ``.along_track_pdf(x)`` give the PDF.
    """
    method = method_argument(method, "ensemble", MonteCarlo())
    loose = dict(deprecated)
    moved: dict[str, object] = {k: loose.pop(k) for k in ("debias_window", "cds") if k in loose}
    method = with_keywords(method, "ensemble", loose)
    debias = fold_keywords(
        "ensemble",
        "debias",
        debias,
        Debias(),
        moved,
        "rp.Debias",
        renamed={"debias_window": "window"},
    )
    cds = debias.cds
    if not models:
        raise ValueError("models must name at least one density model")
    if reference not in models:
        raise ValueError(f"reference {reference!r} is not one of the models {list(models)}")
    for name, model in models.items():
        try:
            check_model(model)
        except TypeError as err:
            raise TypeError(f"models[{name!r}]: {err}") from err
    names = list(models)
    if isinstance(weights, Mapping):
        if set(weights) != set(names):
            raise ValueError(
                f"weights given by model name must name exactly the models {names}, got "
                f"{list(weights)}"
            )
        weights = [weights[name] for name in names]
    w = default_weights(models) if weights is None else _validate.real_array("weights", weights)
    if w.shape != (len(names),) or not np.isfinite(w).all() or (w < 0).any() or w.sum() <= 0:
        raise ValueError(f"weights must be {len(names)} finite non-negative numbers, not all 0")
    if spread is None:
        factor = default_spread(models) if weights is None else 1.0
    else:
        factor = _validate.real("spread", spread)
        if not (np.isfinite(factor) and factor > 0):
            raise ValueError(f"spread must be a finite positive number, got {spread!r}")
    cd: dict[str, float] = {}
    for name in names:
        if cds and name in cds:
            cd[name] = float(cds[name])
        elif name == reference:
            cd[name] = spacecraft.cd
        else:
            cd[name] = debias_drag_coefficient(
                state, spacecraft, models[reference], models[name], debias.window
            )
    results: dict[str, MonteCarloResult | CcspResult] = {}
    for name in names:
        craft = Spacecraft(cd[name], spacecraft.area_to_mass, spacecraft.cr)
        model = models[name] if factor == 1.0 else SigmaScaled(models[name], factor)
        results[name] = method.run(state, craft, model, duration, dynamics=dynamics)
    # A CCSP that stopped at decay has fewer outputs: every component is laid on the
    # longest output grid, NaN where its model has no statistics.
    times = max((r.times for r in results.values()), key=len)
    ref_p, ref_v = _reference_orbit(results[reference], len(times))
    parts = [_component(results[name], ref_p, ref_v) for name in names]
    return EnsembleResult(
        names=names,
        reference=reference,
        cd=cd,
        results=results,
        times=times,
        reference_positions=ref_p,
        reference_velocities=ref_v,
        component_means=np.stack([p[0] for p in parts], axis=1),
        component_covariances=np.stack([p[1] for p in parts], axis=1),
        weights=w / w.sum(),
        spread=factor,
    )


def _reference_orbit(result: MonteCarloResult | CcspResult, nt: int) -> tuple[Any, Any]:
    """The reference model's mean orbit on ``nt`` outputs, (nt, 3) x 2, NaN past its end."""
    if isinstance(result, MonteCarloResult):
        p, v = result.reference_positions, result.reference_velocities
    else:
        p, v = result.mean[:, :3], result.mean[:, 3:]
    ref_p, ref_v = np.full((nt, 3), np.nan), np.full((nt, 3), np.nan)
    ref_p[: len(p)], ref_v[: len(v)] = p, v
    return ref_p, ref_v


def _component(
    result: MonteCarloResult | CcspResult, ref_p: np.ndarray, ref_v: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """A model's position mean (nt, 3) and covariance (nt, 3, 3) in the reference RTN
    frame, NaN past the model's last output."""
    nt = len(ref_p)
    k = len(result.times)
    means, covs = np.full((nt, 3), np.nan), np.full((nt, 3, 3), np.nan)
    means[:k], covs[:k] = result.moments().position_in_frame(ref_p[:k], ref_v[:k])
    return means, covs
