"""Drag-coefficient debiasing across density models (paper section 5)."""

from __future__ import annotations

import numpy as np

from .. import _validate, frames
from ..density.model import DensityModel, ModelLike, as_atmosphere
from ..propagation import OrbitState, Spacecraft
from ..propagation.propagate import DEFAULT_STEP, core_propagate
from ..time import offsets_to_epochs

#: Cadence of the density samples along the backward orbit, s.
DEBIAS_CADENCE = 60.0


def backward_orbit(
    state: OrbitState,
    spacecraft: Spacecraft,
    model: ModelLike,
    window: float,
    cadence: float = DEBIAS_CADENCE,
) -> tuple[np.ndarray, np.ndarray]:
    """The mean orbit through ``model`` propagated backwards over ``window`` s before the
    epoch (RK8, 180 s or shorter steps). Returns (epochs (k,), inertial positions (k, 3) m)
    at every ``cadence`` s from the epoch back to ``epoch - window``."""
    atmosphere = as_atmosphere(model, state, -window)
    times = -np.arange(0.0, window + 0.5 * cadence, cadence)
    times[-1] = -window
    t, states, _decayed, _, _ = core_propagate(
        atmosphere,
        state,
        spacecraft.drag_parameter,
        times,
        integrator="rk8",
        step=DEFAULT_STEP["rk8"],
        # Backwards in time the orbit only rises: no floor to stop at.
        floor_altitude=0.0,
        zonal_degree=2,
    )
    return offsets_to_epochs(state.epoch, t), states[:, :3]


def debias_drag_coefficient(
    state: OrbitState,
    spacecraft: Spacecraft,
    reference_model: DensityModel,
    model: DensityModel,
    window: float = 8 * 3600.0,
    *,
    cadence: float = DEBIAS_CADENCE,
) -> float:
    """Drag coefficient for ``model`` that matches the reference drag over a past window.

    Cd_model = Cd_ref * mean(rho_ref / rho_model): the mean of the density ratio (not the
    ratio of means), sampled every ``cadence`` s (default 60 s) along the reference mean
    orbit propagated backwards over ``window`` s (default 8 h) before the epoch, with
    ``spacecraft.cd`` as Cd_ref. Densities are the models' mean values, evaluated directly
    (not through sampled fields).

    Args:
        state: the epoch state; spacecraft: carries Cd_ref and A/m.
        reference_model, model: density models with ``mean_std``.
        window: s (> 0); cadence: s (> 0).

    Returns:
        Cd for ``model`` (dimensionless).
    """
    window = _validate.positive("window", window)
    cadence = _validate.positive("cadence", cadence)
    epochs, positions = backward_orbit(state, spacecraft, reference_model, window, cadence)
    lla = frames.geodetic(frames.inertial_to_fixed(epochs, positions))
    where = (epochs, lla[:, 0], lla[:, 1], lla[:, 2])
    rho_ref, _ = reference_model.mean_std(*where)
    rho, _ = model.mean_std(*where)
    return float(spacecraft.cd * np.mean(np.asarray(rho_ref) / np.asarray(rho)))
