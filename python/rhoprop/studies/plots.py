"""Figures of the studies (matplotlib, loaded only when a figure is drawn). The studies
compute; this module only draws. A library never selects a matplotlib backend for its
user: figures are drawn on a ``Figure`` object and saved, without pyplot state."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..plot import ensemble_pdf
from .scenarios import LABELS

if TYPE_CHECKING:
    from ..ensemble import EnsembleResult
    from .conjunction import ConjunctionStudy
    from .paper import CcspComparison, MethodComparison


def method_comparison_figure(self: MethodComparison, path: str | Path) -> Path:
    """Density traces of the first members (mean in bold) per method on one density
    scale, and each method's along-track members at the end as a histogram under its
    fitted normal; saved as PNG. The title names the model, epoch, members and span."""
    from matplotlib.figure import Figure

    keys = list(self.results)
    first = self.results[keys[0]]
    fig = Figure(figsize=(16, 9.5), layout="constrained")
    grid = fig.add_gridspec(2, len(keys), height_ratios=[1, 1.25])
    top = [fig.add_subplot(grid[0, 0])]
    top += [fig.add_subplot(grid[0, i], sharey=top[0]) for i in range(1, len(keys))]
    for i, (k, ax) in enumerate(zip(keys, top, strict=True)):
        t, rho = self.traces[k]
        # A white process at 10 s is a blur with five members: two, thin, show its nature.
        shown = rho[:2] if self.results[k].kappa.kind == "white" else rho
        for member in shown:
            ax.plot(t / 3600.0, member * 1e12, lw=0.6 if len(shown) == 2 else 0.8, alpha=0.8)
        ax.plot(t / 3600.0, self.mean_trace[k] * 1e12, "k", lw=2.2, label="mean density")
        ax.set_title(f"{LABELS[k]}: {len(shown)} members", fontsize=10)
        ax.set_xlabel("time [h]")
        ax.grid(alpha=0.3)
        if i == 0:
            ax.set_ylabel("density seen [1e-12 kg/m^3]")
            ax.legend(fontsize=8)
        else:
            ax.tick_params(labelleft=False)
    ax = fig.add_subplot(grid[1, :])
    stds = sorted(self.along_track_std.values())
    x = np.linspace(-4 * stds[-1], 4 * stds[-1], 4001)
    for i, k in enumerate(keys):
        at = self.results[k].along_track[:, -1]
        at = at[np.isfinite(at)]  # decayed members are NaN
        mu, sd = float(np.mean(at)), self.along_track_std[k]
        note = " (peak off scale)" if len(stds) > 1 and sd < stds[1] / 2 else ""
        bins = max(10, min(60, int(40 * sd / stds[-1]) + 10))
        ax.hist(at / 1e3, bins=bins, density=True, color=f"C{i}", alpha=0.18)
        ax.plot(
            x / 1e3,
            _normal(x, mu, sd) * 1e3,
            color=f"C{i}",
            lw=2,
            label=f"{LABELS[k]} (std {sd:,.0f} m){note}",
        )
    if len(stds) > 1:
        # Scale to the second narrowest PDF: a very narrow one would flatten the rest.
        ax.set_ylim(0, 1.25e3 / (stds[1] * np.sqrt(2 * np.pi)))
    ax.set_xlim(x[0] / 1e3, x[-1] / 1e3)
    ax.set_xlabel(f"along-track error after {days_text(first.times[-1])} vs the mean orbit [km]")
    ax.set_ylabel("PDF [1/km]: members (histograms), fitted normals (lines)")
    ax.legend()
    ax.grid(alpha=0.3)
    epoch = str(first.epoch)[:16].replace("T", " ")
    fig.suptitle(
        f"Density perturbation methods (paper Fig. 4): {self.model or 'density model'}, the "
        f"paper's object from {epoch} UTC, Monte Carlo, {first.positions.shape[0]} members "
        f"per method, {days_text(first.times[-1])}\ntop: densities the first members see over "
        "the first hours (one scale); bottom: along-track errors at the end"
    )
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    return out


def ccsp_comparison_figure(self: CcspComparison, path: str | Path) -> Path:
    """Along-track PDFs per configuration: MC histogram, MC normal fit (dashed) and the
    CCSP normal (solid); saved as PNG."""
    from matplotlib.figure import Figure

    keys = list(self.mc_along)
    fig = Figure(figsize=(5.2 * len(keys), 4.4), layout="constrained")
    axes = fig.subplots(1, len(keys), squeeze=False)
    for ax, k in zip(axes[0], keys, strict=True):
        at = self.mc_along[k] / 1e3
        mu, sd = at.mean(), at.std(ddof=1)
        cm, cs = self.ccsp_mean[k] / 1e3, self.ccsp_std[k] / 1e3
        lo, hi = min(mu - 4 * sd, cm - 4 * cs), max(mu + 4 * sd, cm + 4 * cs)
        x = np.linspace(lo, hi, 600)
        ax.hist(at, bins=40, density=True, alpha=0.3, color="C0", label="Monte Carlo")
        ax.plot(x, _normal(x, mu, sd), "--", color="C0", lw=2, label=f"MC normal ({sd:.2f} km)")
        ax.plot(x, _normal(x, cm, cs), color="C3", lw=2, label=f"CCSP ({cs:.2f} km)")
        mc_s, cc_s = self.seconds[k]
        ax.set_title(
            f"{k}, Cd = {self.cd[k]:.4f}\nCCSP/MC std {cs / sd:.2f} (expected "
            f"{self.expected_ratio():.2f}); MC {mc_s:.2f} s, CCSP {cc_s:.3f} s",
            fontsize=10,
        )
        ax.set_xlabel(f"along-track after {days_text(self.duration)} vs reference [km]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0][0].set_ylabel("PDF [1/km]")
    minutes = self.update_interval / 60.0
    fig.suptitle(
        f"CCSP (update {minutes:g} min) vs Monte Carlo ({kappa_text(self.mc_kappa)}, "
        f"{self.members} members), the paper's object, "
        f"{days_text(self.duration)}.\nThe CCSP is wider by design: it is the covariance of "
        f"kappa held over each {minutes:g}-min interval with correlation 1/3 between "
        f"intervals, expected {self.expected_ratio():.2f}x the Monte Carlo's std "
        "(docs/conventions.md)",
        fontsize=10,
    )
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    return out


def method_text(ens: EnsembleResult) -> str:
    """'Monte Carlo, Gauss-Markov 18 min, 1000 members' or 'CCSP, update 60 min'."""
    result = ens.results[ens.reference]
    process = getattr(result, "kappa", None)
    if process is not None:
        n = np.asarray(getattr(result, "positions", np.empty((0,)))).shape[0]
        return f"Monte Carlo, {kappa_text(process)}, {n} members per model"
    steps = np.diff(np.asarray(result.times))
    if len(steps) and np.allclose(steps[:-1], steps[0]):
        return f"CCSP, update {steps[0] / 60:g} min"
    return "CCSP"


def kappa_text(process: object) -> str:
    """'Gauss-Markov 18 min', 'White 10 s', ... for titles."""
    kind = str(getattr(process, "kind", type(process).__name__))
    for attr, unit in (("half_life", 60.0), ("interval", 60.0), ("step", 1.0)):
        value = getattr(process, attr, None)
        if value is not None:
            text = f"{value / unit:g} {'min' if unit == 60.0 else 's'}"
            return (
                f"{kind.replace('_', ' ').title().replace('Gauss Markov', 'Gauss-Markov')} {text}"
            )
    return kind


def _normal(x: np.ndarray, mu: float, sd: float) -> np.ndarray:
    return np.asarray(np.exp(-0.5 * ((x - mu) / sd) ** 2) / (sd * np.sqrt(2 * np.pi)))


def days_text(seconds: float) -> str:
    """'1 day', '3 days', '0.25 days'."""
    days = seconds / 86400.0
    return "1 day" if days == 1 else f"{days:g} days"


def ensemble_figure(ensembles: dict[str, EnsembleResult], path: str | Path) -> Path:
    """Along-track PDFs per case: each model's members as a histogram under its fitted
    normal (dashed), the mixture (bold) and the mixture's modes (triangles); titles give
    the case, epoch, models and member count."""
    from matplotlib.figure import Figure

    cases = list(ensembles)
    cols = 2 if len(cases) > 1 else 1
    rows = int(np.ceil(len(cases) / cols))
    fig = Figure(figsize=(7.5 * cols, 5.0 * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False)
    for ax, case in zip(axes.ravel(), cases, strict=False):
        ens = ensembles[case]
        ensemble_pdf(ens, ax=ax)
        members = max(
            (
                np.asarray(getattr(r, "positions", np.empty(0))).shape[0]
                for r in ens.results.values()
            ),
            default=0,
        )
        epoch = str(ens.results[ens.reference].epoch)[:16].replace("T", " ")
        count = f", {members} members per model" if members else ""
        ax.set_title(f"{case} ({epoch} UTC){count}\n{', '.join(ens.names)}", fontsize=9)
        ax.set_xlabel(
            f"along-track after {days_text(ens.times[-1])} vs the {ens.reference} mean orbit [km]"
        )
    for ax in axes.ravel()[len(cases) :]:
        ax.set_visible(False)
    fig.suptitle(f"Ensemble along-track PDFs ({method_text(ensembles[cases[0]])})")
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    return out


def conjunction_figure(self: ConjunctionStudy, path: str | Path) -> Path:
    """Left: Pc against the secondary's offset, per model's Gaussian (dashed), the
    mixture (bold) and Monte Carlo over the members (dots, 95 % interval). Right: the
    members along the same axis under each model's normal; saved as PNG."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(15, 5.6), layout="constrained")
    ax, hx = fig.subplots(1, 2, width_ratios=[1.35, 1])
    x = self.offsets / 1e3
    floor = 1e-12
    for i, name in enumerate(self.names):
        ax.semilogy(
            x,
            np.maximum(self.pc_models[i], floor),
            "--",
            color=f"C{i}",
            lw=1.6,
            label=f"{name} Gaussian only",
        )
        ax.axvline(self.component_x[i] / 1e3, color=f"C{i}", lw=0.8, alpha=0.5)
    ax.semilogy(x, np.maximum(self.pc_mixture, floor), "k", lw=2.6, label="mixture of the models")
    hit = self.pc_mc_hits > 0
    err = np.abs(self.pc_mc_interval[hit].T - self.pc_mc[hit])
    ax.errorbar(
        x[hit],
        self.pc_mc[hit],
        yerr=err,
        fmt="o",
        color="k",
        ms=3.5,
        capsize=2,
        label="Monte Carlo over members (95 %)",
    )
    ax.semilogy(
        x[~hit],
        self.pc_mc_interval[~hit, 1],
        "v",
        color="0.5",
        ms=4,
        label="Monte Carlo: no hit, 95 % upper bound",
    )
    ax.set_ylim(floor, 1.0)
    ax.set_xlabel("secondary's offset along the encounter-plane track axis [km]")
    ax.set_ylabel("probability of collision")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3)
    ax.set_title(
        f"Pc per density model vs the mixture: HBR {self.hard_body_radius:g} m, crossing "
        f"{self.crossing_angle:g} deg ({self.relative_speed / 1e3:.1f} km/s), secondary "
        f"sigma R/T/N {'/'.join(f'{s:g}' for s in self.secondary_sigma)} m",
        fontsize=9,
    )
    lo, hi = x.min(), x.max()
    grid = np.linspace(lo, hi, 1200)
    for i, name in enumerate(self.names):
        hx.hist(
            self.member_x[name] / 1e3,
            bins=50,
            range=(lo, hi),
            density=True,
            color=f"C{i}",
            alpha=0.3,
        )
        hx.plot(
            grid,
            _normal(grid * 1e3, self.component_x[i], self.component_sigma[i]) * 1e3,
            "--",
            color=f"C{i}",
            label=f"{name} (sigma {self.component_sigma[i] / 1e3:.2f} km)",
        )
    mix = sum(
        w * _normal(grid * 1e3, m, s) * 1e3
        for w, m, s in zip(self.weights, self.component_x, self.component_sigma, strict=True)
    )
    hx.plot(grid, mix, "k", lw=2.4, label="mixture")
    hx.set_xlabel("primary's members along the same axis [km]")
    hx.set_ylabel("PDF [1/km]")
    hx.grid(alpha=0.3)
    hx.legend(fontsize=8)
    hx.set_title("where the primary may be at TCA (members: histograms)", fontsize=9)
    fig.suptitle(
        f"Conjunction after {days_text(self.duration)}, {self.case}: the paper's object "
        f"(Monte Carlo, Gauss-Markov 18 min, {self.members} members per model, reference "
        f"{self.reference}) against a synthetic secondary"
    )
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    return out
