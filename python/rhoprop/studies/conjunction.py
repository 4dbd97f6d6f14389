"""When a single-model Pc misleads: the paper's object against a synthetic secondary.

After three days the density models put the paper's object kilometres apart along its
track, each with its own spread. A secondary is placed at the reference model's mean
orbit at the end of the run, crossing it, and moved along the encounter-plane direction
that carries the primary's along-track error. For each offset the Pc is computed from each
model's Gaussian alone (what a one-model tool reports), from the multi-model mixture
(``sum_k w_k Pc_k``) and by Monte Carlo from the members themselves (every member pair,
:func:`rhoprop.conjunction.pc_monte_carlo`), which checks the Gaussians.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..conjunction import pc_2d, pc_monte_carlo
from ..ensemble import EnsembleResult
from ..frames import rtn_basis
from ..propagation import MonteCarloResult


@dataclass(frozen=True)
class ConjunctionStudy:
    """Pc against the secondary's offset, per density model, mixture and Monte Carlo.

    Attributes:
        case: space-weather case; names, weights: the models and their weights;
            reference: the reference model.
        offsets: the secondary's offset from the reference mean orbit along the
            encounter-plane axis x (the primary's along-track direction projected), (nd,),
            m.
        pc_models: the Gaussian Pc per model (k, nd); pc_mixture: the mixture's (nd,).
        pc_mc: Monte Carlo Pc (nd,) with its interval (nd, 2) and hits (nd,), combined
            over the models with their weights.
        member_x: per model, the members' encounter-plane x at the end, m.
        component_x, component_sigma: per model, the Gaussian's mean and sigma along x, m.
        hard_body_radius, relative_speed (m/s), crossing_angle (deg),
        secondary_sigma: (R, T, N) 1-sigma of the secondary, m; members: per model;
        duration: s; seconds: wall time of the Pc computations, s.
    """

    case: str
    names: list[str]
    weights: np.ndarray
    reference: str
    offsets: np.ndarray
    pc_models: np.ndarray
    pc_mixture: np.ndarray
    pc_mc: np.ndarray
    pc_mc_interval: np.ndarray
    pc_mc_hits: np.ndarray
    member_x: dict[str, np.ndarray] = field(repr=False)
    component_x: np.ndarray = field(repr=False)
    component_sigma: np.ndarray = field(repr=False)
    hard_body_radius: float = 20.0
    relative_speed: float = 0.0
    crossing_angle: float = 90.0
    secondary_sigma: tuple[float, float, float] = (50.0, 250.0, 50.0)
    members: int = 0
    duration: float = 0.0
    seconds: dict[str, float] = field(default_factory=dict)

    def rows(self) -> list[tuple[str, int]]:
        """(label, offset index) of the offsets the table reports: each model's mean."""
        out = []
        for name, x in zip(self.names, self.component_x, strict=True):
            out.append((f"at {name}'s mean", int(np.argmin(np.abs(self.offsets - x)))))
        return out

    def table(self) -> str:
        """A Markdown table: Pc per source at the offsets of each model's mean."""
        head = "| secondary offset | " + " | ".join(self.names) + " | mixture | Monte Carlo |"
        rows = [head, "|" + " --- |" * (len(self.names) + 3)]
        for label, i in self.rows():
            mc_lo, mc_hi = self.pc_mc_interval[i]
            cells = [f"{pc:.2e}" for pc in self.pc_models[:, i]]
            rows.append(
                f"| {label}: {self.offsets[i] / 1e3:+.2f} km | "
                + " | ".join(cells)
                + f" | **{self.pc_mixture[i]:.2e}** | {self.pc_mc[i]:.2e} "
                f"[{mc_lo:.1e}, {mc_hi:.1e}] |"
            )
        return "\n".join(rows)

    def understatement(self) -> list[tuple[str, str, float]]:
        """(model, at which model's mean, mixture Pc / that model's Pc) at each other
        model's mean offset: how far a one-model Pc falls below the mixture's there."""
        out = []
        for k, name in enumerate(self.names):
            for label, i in self.rows():
                if label != f"at {name}'s mean":
                    ratio = self.pc_mixture[i] / max(self.pc_models[k, i], 1e-300)
                    out.append((name, label, float(ratio)))
        return out

    def summary(self) -> dict[str, Any]:
        """JSON-ready figures of the study."""
        return {
            "case": self.case,
            "hard_body_radius_m": self.hard_body_radius,
            "crossing_angle_deg": self.crossing_angle,
            "relative_speed_m_s": self.relative_speed,
            "secondary_sigma_rtn_m": list(self.secondary_sigma),
            "members_per_model": self.members,
            "rows": [
                {
                    "where": label,
                    "offset_m": float(self.offsets[i]),
                    "pc_models": dict(
                        zip(self.names, map(float, self.pc_models[:, i]), strict=True)
                    ),
                    "pc_mixture": float(self.pc_mixture[i]),
                    "pc_monte_carlo": float(self.pc_mc[i]),
                    "pc_monte_carlo_interval": [float(v) for v in self.pc_mc_interval[i]],
                }
                for label, i in self.rows()
            ],
            "seconds": self.seconds,
        }

    def figure(self, path: str | Path) -> Path:
        """Pc against offset (left) and the members along x (right); saved as PNG."""
        from .plots import conjunction_figure

        return conjunction_figure(self, path)


def _crossing_velocity(r: np.ndarray, v: np.ndarray, angle_deg: float) -> np.ndarray:
    """``v`` rotated about the radial direction by ``angle_deg``: a secondary on a
    circular-like orbit crossing the primary's at that angle."""
    axis = r / np.linalg.norm(r)
    a = np.radians(angle_deg)
    return np.asarray(
        v * np.cos(a) + np.cross(axis, v) * np.sin(a) + axis * (axis @ v) * (1 - np.cos(a))
    )


def conjunction_study(
    ensemble: EnsembleResult,
    *,
    case: str = "",
    hard_body_radius: float = 20.0,
    crossing_angle: float = 90.0,
    secondary_sigma: tuple[float, float, float] = (50.0, 250.0, 50.0),
    n_offsets: int = 81,
    n_secondary: int = 2000,
    seed: int = 0,
) -> ConjunctionStudy:
    """The study of the module docstring on a Monte Carlo ensemble's last output.

    Args:
        ensemble: a Monte Carlo :class:`~rhoprop.EnsembleResult` (members are needed).
        case: label of the space-weather case.
        hard_body_radius: combined hard-body radius, m.
        crossing_angle: angle between the two velocities, deg.
        secondary_sigma: the secondary's (R, T, N) 1-sigma in its own RTN, m.
        n_offsets: offsets from -5 to +5 mixture sigmas along x.
        n_secondary: Monte Carlo samples of the secondary's Gaussian.
        seed: seed of those samples.
    """
    import time

    results = [
        r
        for r in (ensemble.results[name] for name in ensemble.names)
        if isinstance(r, MonteCarloResult)
    ]
    if len(results) != len(ensemble.names):
        raise ValueError("the conjunction study needs a Monte Carlo ensemble (members)")
    r_ref = ensemble.reference_positions[-1]
    v_ref = ensemble.reference_velocities[-1]
    basis = rtn_basis(r_ref, v_ref)  # rows R, T, N of the primary's reference orbit
    v2 = _crossing_velocity(r_ref, v_ref, crossing_angle)
    y_hat = (v2 - v_ref) / np.linalg.norm(v2 - v_ref)
    along = basis[1] - (basis[1] @ y_hat) * y_hat
    x_hat = along / np.linalg.norm(along)
    mix = ensemble.mixture(-1)
    means = r_ref + mix.means @ basis  # (k, 3) inertial
    covs = np.einsum("ai,kab,bj->kij", basis, mix.covariances, basis)
    comp_x = (means - r_ref) @ x_hat
    comp_sigma = np.sqrt(np.einsum("i,kij,j->k", x_hat, covs, x_hat))
    total = float(np.sqrt(mix.weights @ (comp_sigma**2 + comp_x**2) - (mix.weights @ comp_x) ** 2))
    offsets = np.linspace(-5 * total, 5 * total, n_offsets) + float(mix.weights @ comp_x)
    offsets = np.union1d(offsets, comp_x)  # each model's mean is on the grid
    b2 = rtn_basis(r_ref, v2)
    cov2 = b2.T @ np.diag(np.square(secondary_sigma)) @ b2
    rng = np.random.default_rng(seed)
    noise = rng.multivariate_normal(np.zeros(3), cov2, size=n_secondary)
    k = len(ensemble.names)
    pc_models = np.empty((k, len(offsets)))
    pc_mc = np.empty(len(offsets))
    interval = np.empty((len(offsets), 2))
    hits = np.empty(len(offsets), dtype=int)
    t_gauss = t_mc = 0.0
    w = ensemble.weights
    for j, s in enumerate(offsets):
        r2 = r_ref + s * x_hat
        t0 = time.perf_counter()
        for i in range(k):
            pc_models[i, j] = pc_2d(means[i], v_ref, covs[i], r2, v2, cov2, hard_body_radius).pc
        t1 = time.perf_counter()
        secondary = np.hstack([r2 + noise, np.tile(v2, (n_secondary, 1))])
        parts = [pc_monte_carlo(res, secondary, hard_body_radius) for res in results]
        t_mc += time.perf_counter() - t1
        t_gauss += t1 - t0
        pc_mc[j] = float(w @ [p.pc for p in parts])
        se = float(np.sqrt(sum((wi * p.std_error) ** 2 for wi, p in zip(w, parts, strict=True))))
        hits[j] = sum(p.hits for p in parts)
        if hits[j] > 0:
            interval[j] = (max(pc_mc[j] - 1.96 * se, 0.0), pc_mc[j] + 1.96 * se)
        else:  # no pair hit in any model: the weighted one-sided bounds
            interval[j] = (0.0, float(w @ [p.interval[1] for p in parts]))
    member_x = {}
    for name, res in zip(ensemble.names, results, strict=True):
        alive = res.alive[:, -1]
        member_x[name] = (res.positions[alive, -1] - r_ref) @ x_hat
    return ConjunctionStudy(
        case=case,
        names=list(ensemble.names),
        weights=np.asarray(w),
        reference=ensemble.reference,
        offsets=offsets,
        pc_models=pc_models,
        pc_mixture=w @ pc_models,
        pc_mc=pc_mc,
        pc_mc_interval=interval,
        pc_mc_hits=hits,
        member_x=member_x,
        component_x=comp_x,
        component_sigma=comp_sigma,
        hard_body_radius=hard_body_radius,
        relative_speed=float(np.linalg.norm(v2 - v_ref)),
        crossing_angle=crossing_angle,
        secondary_sigma=secondary_sigma,
        members=int(results[0].positions.shape[0]),
        duration=float(ensemble.times[-1]),
        seconds={"gaussian": t_gauss, "monte_carlo": t_mc},
    )


def most_disputed(ensembles: dict[str, EnsembleResult]) -> str:
    """The case whose models disagree most: largest spread of the component along-track
    means over the mean component sigma at the last output."""

    def score(ens: EnsembleResult) -> float:
        m = ens.component_means[-1, :, 1]
        s = np.sqrt(ens.component_covariances[-1, :, 1, 1])
        return float(np.ptp(m) / np.mean(s))

    return max(ensembles, key=lambda c: score(ensembles[c]))
