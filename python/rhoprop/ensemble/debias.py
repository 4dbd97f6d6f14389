"""Drag-coefficient debiasing across density models (paper section 5)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .. import _validate, frames
from ..density.model import DensityModel, ModelLike, as_atmosphere
from ..propagation import OrbitState, Spacecraft
from ..propagation.propagate import DEFAULT_STEP, core_propagate
from ..time import offsets_to_epochs

#: Cadence of the density samples along the backward orbit, s.
DEBIAS_CADENCE = 60.0
#: Default span before the epoch over which a model's Cd is debiased, s (8 hours).
DEBIAS_WINDOW = 8 * 3600.0


@dataclass(frozen=True)
class Debias:
    """How an ensemble gives each model its drag coefficient, checked when made: debiased
    against the reference model over ``window`` s before the epoch
    (:func:`debias_drag_coefficient`), except the models whose Cd ``cds`` gives
    ({model name: Cd}, dimensionless, > 0).

    Example:
        >>> import rhoprop as rp
        >>> rp.Debias(cds={"JB2008": 2.3}).window
        28800.0
    """

    window: float = DEBIAS_WINDOW
    cds: Mapping[str, float] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "window", _validate.positive("window", self.window))
        if self.cds is not None:
            if not isinstance(self.cds, Mapping):
                raise TypeError(
                    f"cds must be a mapping {{model name: Cd}}, got {type(self.cds).__name__}"
                )
            for name, cd in self.cds.items():
                _validate.positive(f"cds[{name!r}]", cd)


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
    window: float = DEBIAS_WINDOW,
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
