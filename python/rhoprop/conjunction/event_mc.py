"""The member Monte Carlo's Pc of the most probable events of an all-on-all screen (on
request: ``screen_all(monte_carlo_events=N)``).

Per model k, both objects are run as Monte Carlos from their epochs to TCA
(:func:`rhoprop.monte_carlo`: ``members`` members each, the Gauss-Markov kappa process,
the object's own initial covariance, its Cd*A/m debiased for model k with the
relative sigma of ``drag_sigma="auto"``); the Pc per model is the fraction of member
pairs passing within the hard-body radius (:func:`~rhoprop.conjunction.pc_monte_carlo`)
and the mixture's is sum_k w_k Pc_k, as for the Gaussian Pc. Object i of the screen is
seeded with ``seed + i`` for every model (common random numbers across models)."""

from __future__ import annotations

import numpy as np

from ..catalog.objects import object_drag_sigma
from ..density.scaled import SigmaScaled
from ..propagation import Dynamics, Spacecraft
from ..propagation.montecarlo import monte_carlo
from ..time import seconds_between
from .event_pc import EventPcs
from .kernel import EventPlan, catalog_object
from .probability import pc_monte_carlo

__all__ = ["event_monte_carlo"]


def event_monte_carlo(
    plan: EventPlan, pcs: EventPcs, chosen: list[int], members: int, seed: int
) -> tuple[np.ndarray, np.ndarray]:
    """Monte Carlo Pc per model (events, models) and the mixture's (events,) for the
    events ``chosen`` of ``plan`` (NaN elsewhere, and where an object's epoch is after
    TCA), ``members`` members per object, object i seeded ``seed + i``. From ``pcs`` (the
    CCSP Pc stage's result): each object's debiased Cd*A/m per model
    (``pcs.drag[k][pcs.index[i]]``), the weights, the hard-body radii and the spread
    (each model's density sigma times it, as in the CCSP Pc)."""
    events, pairs, objs, models = plan.events, plan.pairs, plan.objects, plan.models
    drag, index, weights, hbr, spread = (
        pcs.drag,
        pcs.index,
        pcs.weights,
        pcs.hard_body_radius,
        pcs.spread,
    )
    dyn = plan.window.dynamics
    degree, floor, step = dyn.zonal_degree, dyn.floor_altitude, dyn.step
    per_model = np.full((len(events), len(models)), np.nan)
    for e in chosen:
        ev, (i, j) = events[e], pairs[e]
        for k, (name, model) in enumerate(models.items()):
            runs = []
            for obj in (i, j):
                cat = catalog_object(objs[obj])
                lead = seconds_between(cat.state.epoch, ev.tca)
                if lead <= 0:
                    break
                beta = float(drag[name][index[obj]])
                runs.append(
                    monte_carlo(
                        cat.state,
                        Spacecraft(1.0, beta),
                        model if spread == 1.0 else SigmaScaled(model, spread),
                        output_times=np.array([lead]),
                        n=members,
                        seed=seed + obj,
                        initial_covariance=cat.covariance,
                        drag_sigma=object_drag_sigma(cat, "auto"),
                        dynamics=Dynamics(zonal_degree=degree, floor_altitude=floor, step=step),
                        progress=False,
                    )
                )
            if len(runs) == 2:
                per_model[e, k] = pc_monte_carlo(runs[0], runs[1], float(hbr[e])).pc
    mixture = np.where(np.isfinite(per_model).all(axis=1), per_model @ weights, np.nan)
    return per_model, mixture
