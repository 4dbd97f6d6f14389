"""A conjunction's Pc with density-model uncertainty added.

A CDM's covariances come from one orbit determination and one atmosphere. Between the
message's creation and TCA the objects fly through a thermosphere that several density
models describe differently, and each model has its own uncertainty. For each object
this module finds the state ``lead`` seconds before TCA that reaches the message's TCA
state under the reference model's mean density (a shooting solve), runs the multi-model
ensemble (:func:`rhoprop.ensemble`: Cd debiased per model, Monte Carlo or CCSP) forward
to TCA, and adds each model's position offset and spread at TCA to the message's
Gaussian.

Both objects fly through the same atmosphere: if model k is the truth, it is the truth
for both. The Pc with model uncertainty is therefore ``sum_k w_k Pc_k``, with ``Pc_k``
the 2-D Pc of object 1's and object 2's model-k Gaussians (not the double sum over
component pairs of two independent mixtures, which would let the two objects fly through
different atmospheres). The density perturbations along the two orbits are taken as
independent within a model: over hours to days they accumulate along different tracks.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..constants import MU
from ..density.model import ModelLike
from ..ensemble import EnsembleResult
from ..ensemble import ensemble as run_ensemble
from ..ensemble.debias import Debias
from ..frames import rtn_basis
from ..options import HardBodyShape
from ..propagation import Ccsp, Dynamics, MonteCarlo, OrbitState, Spacecraft, propagate
from ..propagation.methods import Method, MethodName, method_argument, with_keywords
from .cdm import CdmObject, ConjunctionMessage

if TYPE_CHECKING:
    from typing_extensions import Unpack

#: Cd of the reference model when a CDM gives only Cd*A/m: the ensemble debiases the
#: other models' Cd against it; only the product enters the reference model's dynamics.
REFERENCE_CD = 2.2

#: The lead time is rounded to this grid (s) so it is a whole number of integration steps.
LEAD_GRID = 60.0

#: Longest lead time, s (30 days): the state that far before TCA is found by shooting
#: back a day at a time, and conjunction messages are issued days, not months, ahead.
MAX_LEAD = 30 * 86400.0


class EnsembleOptions(TypedDict, total=False):
    """The keywords of :func:`rhoprop.ensemble` that :func:`density_pc` passes on."""

    spread: float | None
    debias: Debias | None
    dynamics: Dynamics | None
    # Deprecated: in ``debias`` (``window``, ``cds``), folded in with a warning.
    debias_window: float
    cds: dict[str, float] | None
    # Deprecated: the method's settings, folded into ``method`` with a warning.
    n: int
    seed: int
    kappa: object
    output_step: float | None
    update_interval: float | None
    drag_sigma: float
    progress: bool


#: The method settings among :class:`EnsembleOptions` (deprecated there).
_METHOD_KEYS = ("n", "seed", "kappa", "output_step", "update_interval", "drag_sigma", "progress")


@dataclass(frozen=True)
class DensityPc:
    """Pc of a conjunction with density-model uncertainty.

    Attributes:
        names: the density models, in order; weights: their mixture weights.
        pc_message: the 2-D Pc of the message's own Gaussians (recomputed).
        pc_models: per model, the 2-D Pc with that model's offset and spread added to
            both objects (k,).
        pc: the Pc with density-model uncertainty: ``sum_k weights[k] * pc_models[k]``.
        lead_time: how long before TCA the density uncertainty starts acting, s.
        hard_body_radius: m.
        offsets1, offsets2: per model, each object's mean position offset at TCA from the
            message's state, inertial (k, 3), m.
        covariances1, covariances2: per model, each object's position covariance at TCA,
            message plus density, inertial (k, 3, 3), m^2.
        ensembles: the two :class:`~rhoprop.EnsembleResult` (object 1, object 2).
        pc_max_message, pc_max_models: the largest Pc any scaling of the message's / each
            model's combined covariance gives (:meth:`PcResult.maximum`): what the Pc
            could reach were the states known better or worse.
        dilution_models: per model, whether its Pc lies in the dilution region (a
            smaller covariance would raise it): density uncertainty that lowers a Pc
            there says the states are too uncertain to tell, not that they miss.
    """

    names: list[str]
    weights: np.ndarray
    pc_message: float
    pc_models: np.ndarray
    pc: float
    lead_time: float
    hard_body_radius: float
    offsets1: np.ndarray
    offsets2: np.ndarray
    covariances1: np.ndarray
    covariances2: np.ndarray
    ensembles: tuple[EnsembleResult, EnsembleResult]
    pc_max_message: float = float("nan")
    pc_max_models: np.ndarray = field(default_factory=lambda: np.empty(0))
    dilution_models: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=bool))

    @property
    def dilution(self) -> bool:
        """Whether any model of positive weight has its Pc in the dilution region."""
        return bool(np.any(self.dilution_models & (self.weights > 0)))

    def table(self) -> str:
        """A Markdown table of the Pc per model, the mixture and the message's own, with
        each one's maximum Pc and dilution flag."""
        rows = [
            "| source | weight | Pc | Pc max | dilution |",
            "| --- | ---: | ---: | ---: | --- |",
        ]
        rows.append(
            f"| message covariances only | | {self.pc_message:.4g} | {self.pc_max_message:.4g} | |"
        )
        maxima = self.pc_max_models if len(self.pc_max_models) else [np.nan] * len(self.names)
        flags = self.dilution_models if len(self.dilution_models) else [False] * len(self.names)
        for name, w, pc, top, flag in zip(
            self.names, self.weights, self.pc_models, maxima, flags, strict=True
        ):
            rows.append(f"| {name} | {w:.3g} | {pc:.4g} | {top:.4g} | {'yes' if flag else 'no'} |")
        rows.append(
            f"| **mixture (density-model uncertainty)** | 1 | **{self.pc:.4g}** | | "
            f"{'yes' if self.dilution else 'no'} |"
        )
        return "\n".join(rows)


def _inertial_covariance(obj: CdmObject) -> np.ndarray:
    """The position block of ``obj``'s RTN covariance rotated to inertial, m^2."""
    basis = rtn_basis(obj.position, obj.velocity)  # rows R, T, N
    return np.asarray(basis.T @ obj.covariance[:3, :3] @ basis)


def _plane(p: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    """The equinoctial frame's in-plane unit vectors f, g (Broucke & Cefola 1972)."""
    s = 1.0 + p * p + q * q
    f = np.array([1.0 - p * p + q * q, 2.0 * p * q, -2.0 * p]) / s
    g = np.array([2.0 * p * q, 1.0 + p * p - q * q, 2.0 * q]) / s
    return f, g


def equinoctial(x: np.ndarray) -> np.ndarray:
    """Equinoctial elements (a m, h, k, p, q, mean longitude rad) of the inertial state
    ``x`` (6,) m, m/s. Non-singular for circular and equatorial (prograde) orbits, and
    nearly linear in time: the shooting below converges in them where it does not in
    Cartesian coordinates (a phase shift along the orbit is a rotation there)."""
    r, v = x[:3], x[3:]
    rn = np.linalg.norm(r)
    hv = np.cross(r, v)
    w = hv / np.linalg.norm(hv)
    p, q = w[0] / (1.0 + w[2]), -w[1] / (1.0 + w[2])
    f, g = _plane(p, q)
    a = 1.0 / (2.0 / rn - v @ v / MU)
    ecc = np.cross(v, hv) / MU - r / rn
    h, k = ecc @ g, ecc @ f
    big_x, big_y = r @ f, r @ g
    beta = 1.0 / (1.0 + np.sqrt(1.0 - h * h - k * k))
    root = a * np.sqrt(1.0 - h * h - k * k)
    sin_f = h + ((1.0 - h * h * beta) * big_y - h * k * beta * big_x) / root
    cos_f = k + ((1.0 - k * k * beta) * big_x - h * k * beta * big_y) / root
    ecc_lon = np.arctan2(sin_f, cos_f)
    return np.array([a, h, k, p, q, ecc_lon + h * np.cos(ecc_lon) - k * np.sin(ecc_lon)])


def cartesian(e: np.ndarray) -> np.ndarray:
    """The inertial state (6,) m, m/s of equinoctial elements ``e`` (inverse of
    :func:`equinoctial`; Kepler's equation solved by Newton's method)."""
    a, h, k, p, q, lam = e
    ecc_lon = lam
    for _ in range(50):
        step = (ecc_lon + h * np.cos(ecc_lon) - k * np.sin(ecc_lon) - lam) / (
            1.0 - h * np.sin(ecc_lon) - k * np.cos(ecc_lon)
        )
        ecc_lon -= step
        if abs(step) < 1e-15:
            break
    f, g = _plane(p, q)
    beta = 1.0 / (1.0 + np.sqrt(1.0 - h * h - k * k))
    c, s = np.cos(ecc_lon), np.sin(ecc_lon)
    big_x = a * ((1.0 - h * h * beta) * c + h * k * beta * s - k)
    big_y = a * ((1.0 - k * k * beta) * s + h * k * beta * c - h)
    speed = a * a * np.sqrt(MU / a**3) / (a * (1.0 - k * c - h * s))
    dx = speed * (h * k * beta * c - (1.0 - h * h * beta) * s)
    dy = speed * ((1.0 - k * k * beta) * c - h * k * beta * s)
    return np.concatenate([big_x * f + big_y * g, dx * f + dy * g])


#: A drag parameter small enough to switch drag off (Spacecraft needs Cd, A/m > 0).
NO_DRAG = Spacecraft(1e-12, 1e-12)


def _wrap(angle: float) -> float:
    """``angle`` wrapped to [-pi, pi), rad."""
    return float((angle + np.pi) % (2.0 * np.pi) - np.pi)


def state_before(
    target: OrbitState,
    spacecraft: Spacecraft,
    model: ModelLike,
    lead: float,
    *,
    tol: float = 0.5,
    max_iter: int = 12,
) -> OrbitState:
    """The state ``lead`` s before ``target`` that reaches it under ``model``'s mean
    density (``rp.propagate``, RK8 at its default step, as the Monte Carlo's mean orbit).

    Leads longer than :data:`SHOOTING_CHUNK` are solved a chunk at a time, each chunk's
    start the next chunk's target (:func:`_shoot`), then polished over the whole lead.
    ``tol`` (m) bounds the end position's miss: far below any CDM's position sigma.

    Raises:
        ValueError: no convergence, or the object decays.
    """
    at = target
    remaining = float(lead)
    while remaining > SHOOTING_CHUNK:
        at = _shoot(at, spacecraft, model, SHOOTING_CHUNK, tol=tol, max_iter=max_iter)
        remaining -= SHOOTING_CHUNK
    if at is target:
        return _shoot(target, spacecraft, model, remaining, tol=tol, max_iter=max_iter)
    at = _shoot(at, spacecraft, model, remaining, tol=tol, max_iter=max_iter)
    return _shoot(target, spacecraft, model, lead, tol=tol, max_iter=max_iter, guess=at)


#: Longest lead solved in one shooting solve, s (a whole number of 180-s RK8 steps).
SHOOTING_CHUNK = 86400.0


def _shoot(
    target: OrbitState,
    spacecraft: Spacecraft,
    model: Any,
    lead: float,
    *,
    tol: float = 0.5,
    max_iter: int = 12,
    guess: OrbitState | None = None,
) -> OrbitState:
    """One shooting solve for :func:`state_before`, from ``guess`` if given.

    A shooting solve in equinoctial elements. The first guess propagates the target with
    its velocity reversed, once with drag and once without: without drag that is the
    exact backward orbit, and drag changes the elements by about the same amount in
    either direction of time but with the opposite sign of what going back needs, so
    ``2 * without - with_drag`` (element-wise) cancels it to first order. Newton steps
    with a finite-difference Jacobian follow until the end position misses ``target`` by
    less than ``tol`` m.

    Raises:
        ValueError: no convergence in ``max_iter`` steps, or the object decays.
    """
    epoch0 = target.epoch - np.timedelta64(round(lead * 1e9), "ns")
    goal = target.state

    def run(epoch: np.datetime64, x: np.ndarray, craft: Spacecraft = spacecraft) -> np.ndarray:
        out = propagate(
            OrbitState(epoch, x[:3], x[3:]), craft, model, lead, dynamics=Dynamics(integrator="rk8")
        )
        if out.decayed_at is not None:
            raise ValueError(
                f"the object decays within {lead:g} s before TCA under the reference model"
            )
        return np.asarray(out.states[-1])

    flip = np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0])
    if guess is not None:
        elements = equinoctial(guess.state)
    else:
        elements = _backward_guess(run, target, flip)
    scale = np.array([1.0, 1e-7, 1e-7, 1e-7, 1e-7, 1e-7])

    def miss_of(e: np.ndarray) -> np.ndarray | None:
        """End state minus the target, or None where ``e`` is no closed orbit."""
        if not (e[0] > 0 and e[1] ** 2 + e[2] ** 2 < 1):
            return None
        return np.asarray(run(epoch0, cartesian(e)) - goal)

    miss = miss_of(elements)
    if miss is None:
        raise ValueError("the backward guess before TCA is not an orbit")
    for _ in range(max_iter):
        if np.linalg.norm(miss[:3]) < tol:
            x0 = cartesian(elements)
            return OrbitState(epoch0, x0[:3], x0[3:])
        jac = np.empty((6, 6))
        for j in range(6):
            d = np.zeros(6)
            d[j] = scale[j]
            jac[:, j] = (run(epoch0, cartesian(elements + d)) - goal - miss) / scale[j]
        step = np.linalg.solve(jac, miss)
        # Backtracking: far from the solution a full Newton step can overshoot.
        for fraction in (1.0, 0.5, 0.25, 0.125, 0.0625):
            trial = elements - fraction * step
            trial_miss = miss_of(trial)
            if trial_miss is not None and np.linalg.norm(trial_miss[:3]) < np.linalg.norm(miss[:3]):
                elements, miss = trial, trial_miss
                break
        else:
            break
    raise ValueError(
        f"could not find the state {lead:g} s before TCA that reaches the message's state "
        f"(miss {np.linalg.norm(miss[:3]):.3g} m after {max_iter} Newton steps)"
    )


def _backward_guess(run: Any, target: OrbitState, flip: np.ndarray) -> np.ndarray:
    """Equinoctial elements of the first guess (see :func:`_shoot`)."""
    goal = target.state
    with_drag = equinoctial(run(target.epoch, goal * flip) * flip)
    without = equinoctial(run(target.epoch, goal * flip, NO_DRAG) * flip)
    elements = 2.0 * without - with_drag
    elements[5] = without[5] + _wrap(without[5] - with_drag[5])
    return np.asarray(elements)


def _drag_parameter(obj: CdmObject, given: float | None, k: int) -> float:
    beta = given if given is not None else obj.drag_parameter
    if beta is None:
        raise ValueError(
            f"object {k} ({obj.name!r}) has no CD_AREA_OVER_MASS in the message: pass "
            f"drag_parameters=(beta1, beta2) in m^2/kg"
        )
    if not (np.isfinite(beta) and beta > 0):
        raise ValueError(f"drag parameter of object {k} must be > 0 m^2/kg, got {beta!r}")
    return float(beta)


def _object_mixture(
    obj: CdmObject,
    beta: float,
    models: dict[str, Any],
    reference: str,
    lead: float,
    tca: np.datetime64,
    method: Method,
    options: Mapping[str, Any],
) -> tuple[EnsembleResult, np.ndarray, np.ndarray]:
    """One object's ensemble from ``lead`` before TCA; its per-model inertial offsets
    (k, 3) and position covariances (k, 3, 3) at TCA, the message's covariance added."""
    craft = Spacecraft(REFERENCE_CD, beta / REFERENCE_CD)
    start = state_before(
        OrbitState(tca, obj.position, obj.velocity), craft, models[reference], lead
    )
    result = run_ensemble(start, craft, models, reference, method=method, duration=lead, **options)
    if abs(result.times[-1] - lead) > 1e-6:
        raise ValueError(f"the {method.name} run stopped at {result.times[-1]:g} s, before TCA")
    mix = result.mixture(-1)  # RTN of the reference mean orbit at TCA
    basis = rtn_basis(result.reference_positions[-1], result.reference_velocities[-1])
    offsets = mix.means @ basis
    covs = np.einsum("ai,kab,bj->kij", basis, mix.covariances, basis)
    return result, offsets, covs + _inertial_covariance(obj)


def density_pc(
    message: ConjunctionMessage,
    models: dict[str, Any],
    reference: str,
    *,
    hard_body_radius: float | None = None,
    lead_time: float | None = None,
    drag_parameters: tuple[float | None, float | None] = (None, None),
    method: Method | MethodName = Ccsp(),
    weights: npt.ArrayLike | None = None,
    shape: HardBodyShape = "circle",
    **ensemble_options: Unpack[EnsembleOptions],
) -> DensityPc:
    """The Pc of ``message`` with density-model uncertainty added (module docstring).

    Args:
        message: a :class:`ConjunctionMessage` (:func:`read_cdm`); LEO objects.
        models: {name: density model}; ``reference`` names the model the message's
            states are taken to follow.
        hard_body_radius: m (default: the message's ``COMMENT HBR``).
        lead_time: s before TCA at which the density uncertainty starts acting (default:
            TCA minus the message's CREATION_DATE), 1 minute to 30 days (:data:`MAX_LEAD`),
            rounded to whole minutes.
        drag_parameters: Cd*A/m of object 1 and 2, m^2/kg (default: each object's
            CD_AREA_OVER_MASS in the message).
        method: :class:`~rhoprop.Ccsp` (default ``rp.Ccsp()``) or
            :class:`~rhoprop.MonteCarlo` (the strings ``"ccsp"`` / ``"monte_carlo"`` are
            deprecated; ``"monte_carlo"`` is ``rp.MonteCarlo(output_step=None)``, outputs
            at the start and TCA only), run per model and object.
        weights: model weights, as :func:`rhoprop.ensemble` takes them (default: its
            default, the calibrated weights and spread when every model is a calibrated
            family, else equal weights; given weights run every model with its own
            sigma).
        shape: hard-body shape, as :func:`~rhoprop.conjunction.pc_2d`.
        **ensemble_options: passed on to :func:`rhoprop.ensemble` (``spread``,
            ``debias``, ``dynamics``; ``debias_window`` and ``cds`` are deprecated: give
            them in ``debias``); the method's settings (``n``,
            ``seed``, ``update_interval``, ...) are deprecated here: give them in
            ``method``.

    Returns:
        :class:`DensityPc`.
    """
    from .probability import pc_2d

    hbr = message._hbr(hard_body_radius)
    if lead_time is None:
        lead = message.lead_time
        where = f"TCA minus the message's creation date ({message.lead_time:g} s)"
    else:
        lead = _validate.seconds("lead_time", lead_time)
        where = f"lead_time ({lead:g} s)"
    if not LEAD_GRID <= lead <= MAX_LEAD:
        raise ValueError(
            f"{where} must lie in {LEAD_GRID:g}-{MAX_LEAD:g} s (1 minute to 30 days): "
            "density uncertainty needs time to act, and the state before TCA is found by "
            "shooting back from it"
        )
    lead = round(lead / LEAD_GRID) * LEAD_GRID
    a, b = message.object1, message.object2
    betas = [
        _drag_parameter(obj, given, k)
        for k, (obj, given) in enumerate(zip((a, b), drag_parameters, strict=True), start=1)
    ]
    chosen = method_argument(method, "density_pc", MonteCarlo(output_step=None))
    options: dict[str, Any] = dict(ensemble_options)
    settings = {k: options.pop(k) for k in _METHOD_KEYS if k in options}
    chosen = with_keywords(chosen, "density_pc", settings)
    if weights is not None:
        options["weights"] = weights
    ens1, off1, cov1 = _object_mixture(
        a, betas[0], models, reference, lead, message.tca, chosen, options
    )
    ens2, off2, cov2 = _object_mixture(
        b, betas[1], models, reference, lead, message.tca, chosen, options
    )
    w = ens1.weights
    results = [
        pc_2d(
            a.position + off1[k],
            a.velocity,
            cov1[k],
            b.position + off2[k],
            b.velocity,
            cov2[k],
            hbr,
            shape=shape,
        )
        for k in range(len(ens1.names))
    ]
    per_model = np.array([_pc(r) for r in results])
    highest = [r.maximum() for r in results]
    own = message.pc(hbr, shape=shape)
    return DensityPc(
        names=list(ens1.names),
        weights=w,
        pc_message=_pc(own),
        pc_models=per_model,
        pc=float(w @ per_model),
        lead_time=lead,
        hard_body_radius=hbr,
        offsets1=off1,
        offsets2=off2,
        covariances1=cov1,
        covariances2=cov2,
        ensembles=(ens1, ens2),
        pc_max_message=own.maximum().pc_max,
        pc_max_models=np.array([m.pc_max for m in highest]),
        dilution_models=np.array([m.dilution for m in highest]),
    )


def _pc(result: Any) -> float:
    """The Pc of what ``pc_2d`` returns (a result object or a float)."""
    return float(getattr(result, "pc", result))
