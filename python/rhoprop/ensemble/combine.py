"""Multi-model ensembles (paper section 5): each model propagated with its debiased drag
coefficient, each model's position PDF fitted by a Gaussian, combined as a mixture in the
RTN frame of the reference model's mean orbit."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..density import DensityModel
from ..propagation import (
    CcspResult,
    MonteCarloResult,
    OrbitState,
    Spacecraft,
    ccsp,
    monte_carlo,
)
from .debias import debias_drag_coefficient
from .mixture import GaussianMixture

METHODS = ("monte_carlo", "ccsp")


@dataclass(frozen=True)
class EnsembleResult:
    """An ensemble of density models.

    Attributes:
        names: model names, in order; ``reference`` the reference model's name.
        cd: drag coefficient used per model (the reference keeps Cd_ref).
        results: per model, the MonteCarloResult or CcspResult.
        times: output times, s from the epoch (nt,).
        reference_positions, reference_velocities: the reference mean orbit (nt, 3).
        component_means: per time and model, the mean position offset from the reference
            mean orbit in its RTN frame (nt, k, 3), m.
        component_covariances: the matching covariances (nt, k, 3, 3), m^2.
        weights: mixture weights (k,), summing to 1.
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

    def mixture(self, time_index: int = -1) -> GaussianMixture:
        """The 3-D position mixture (RTN of the reference mean orbit, m) at an output."""
        return GaussianMixture(
            self.weights,
            self.component_means[time_index],
            self.component_covariances[time_index],
        )

    def along_track_mixture(self, time_index: int = -1) -> GaussianMixture:
        """The 1-D along-track mixture, m."""
        return self.mixture(time_index).marginal(axes=[1])

    def along_track_pdf(self, x: Any, time_index: int = -1) -> np.ndarray:
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


def ensemble(
    state: OrbitState,
    spacecraft: Spacecraft,
    models: dict[str, DensityModel],
    reference: str,
    *,
    method: str = "monte_carlo",
    weights: Any = None,
    debias_window: float = 8 * 3600.0,
    duration: float = 259200.0,
    cds: dict[str, float] | None = None,
    **method_options: Any,
) -> EnsembleResult:
    """Propagates ``state`` through every model and combines them into a Gaussian mixture.

    Args:
        state, spacecraft: the initial state and the object (``spacecraft.cd`` is Cd_ref,
            the drag coefficient that belongs to the reference model).
        models: {name: density model}; ``reference`` names the reference model.
        method: ``"monte_carlo"`` (default; GaussMarkov 18 min unless ``kappa`` is given)
            or ``"ccsp"``.
        weights: mixture weights per model, in the order of ``models`` (default equal).
        debias_window: s before the epoch over which each model's Cd is debiased against
            the reference (:func:`~rhoprop.debias_drag_coefficient`); ``cds`` overrides it
            per model.
        duration: s.
        **method_options: passed to :func:`~rhoprop.monte_carlo` (n, kappa, seed,
            output_step, ...) or :func:`~rhoprop.ccsp` (update_interval, ...).

    Returns:
        :class:`EnsembleResult`; ``.mixture()`` and ``.along_track_pdf(x)`` give the PDF.
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected 'monte_carlo' or 'ccsp'")
    if not models:
        raise ValueError("models must name at least one density model")
    if reference not in models:
        raise ValueError(f"reference {reference!r} is not one of the models {list(models)}")
    names = list(models)
    w = np.ones(len(names)) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != (len(names),) or not np.isfinite(w).all() or (w < 0).any() or w.sum() <= 0:
        raise ValueError(f"weights must be {len(names)} finite non-negative numbers, not all 0")
    cd: dict[str, float] = {}
    for name in names:
        if cds and name in cds:
            cd[name] = float(cds[name])
        elif name == reference:
            cd[name] = spacecraft.cd
        else:
            cd[name] = debias_drag_coefficient(
                state, spacecraft, models[reference], models[name], debias_window
            )
    results: dict[str, MonteCarloResult | CcspResult] = {}
    run = monte_carlo if method == "monte_carlo" else ccsp
    for name in names:
        craft = Spacecraft(cd[name], spacecraft.area_to_mass)
        results[name] = run(state, craft, models[name], duration, **method_options)
    ref = results[reference]
    if isinstance(ref, MonteCarloResult):
        ref_p, ref_v = ref.mean_orbit.positions, ref.mean_orbit.velocities
    else:
        ref_p, ref_v = ref.mean[:, :3], ref.mean[:, 3:]
    parts = [results[name].moments().position_in_frame(ref_p, ref_v) for name in names]
    return EnsembleResult(
        names=names,
        reference=reference,
        cd=cd,
        results=results,
        times=ref.times,
        reference_positions=ref_p,
        reference_velocities=ref_v,
        component_means=np.stack([p[0] for p in parts], axis=1),
        component_covariances=np.stack([p[1] for p in parts], axis=1),
        weights=w / w.sum(),
    )
