"""Figures of your own runs (matplotlib, imported only when a function here is called).

Every function draws on the ``ax`` it is given, or on a new ``matplotlib.figure.Figure``
(no pyplot state, no backend change: importing rhoprop never touches matplotlib's
backend), and returns the axes; save with ``ax.figure.savefig(path)``. Distances are shown
in km, times in hours.

- :func:`along_track`: a Monte Carlo's along-track errors at one output as a histogram
  under its fitted normal, or a CCSP's normal;
- :func:`ensemble_pdf`: an ensemble's members per model, each model's normal and the
  mixture (with its modes);
- :func:`rtn_spread`: radial, along-track and cross-track 1-sigma over time, for any
  result with ``moments()`` (Trajectory, MonteCarloResult, CcspResult);
- :func:`density_traces`: the density each member saw (``record_density=True``);
- :func:`catalog_summary`: a catalog run's along-track 1-sigma at the end per object
  against perigee altitude, coloured by status.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .constants import MU, R_EARTH
from .frames import rtn_basis

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from .catalog import CatalogResult
    from .ensemble import EnsembleResult
    from .propagation import CcspResult, MonteCarloResult


def _axes(ax: Any, figsize: tuple[float, float] = (7.5, 4.8)) -> Any:
    if ax is not None:
        return ax
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained").add_subplot()


def _normal(x: np.ndarray, mu: float, sd: float) -> np.ndarray:
    return np.asarray(np.exp(-0.5 * ((x - mu) / sd) ** 2) / (sd * np.sqrt(2 * np.pi)))


def _hours(times: np.ndarray) -> np.ndarray:
    return np.asarray(times, dtype=float) / 3600.0


def along_track(
    result: MonteCarloResult | CcspResult,
    *,
    time_index: int = -1,
    ax: Axes | None = None,
    bins: int = 40,
    label: str | None = None,
    color: str = "C0",
) -> Any:
    """Along-track error at output ``time_index`` relative to the reference orbit, km:
    the members as a histogram under their fitted normal (Monte Carlo) or the CCSP's
    normal about its mean. Returns the axes."""
    from .propagation import MonteCarloResult

    ax = _axes(ax)
    t = float(result.times[time_index])
    if isinstance(result, MonteCarloResult):
        at = result.along_track[:, time_index]
        at = at[np.isfinite(at)] / 1e3  # decayed members are NaN
        if len(at) < 2:
            raise ValueError(f"fewer than two members are flying at t = {t:g} s")
        mu, sd = float(at.mean()), float(at.std(ddof=1))
        ax.hist(at, bins=bins, density=True, color=color, alpha=0.3)
        what = f"{len(at)} members"
    else:
        # About the CCSP's own mean orbit: its mean is the reference.
        mu = 0.0
        sd = float(result.along_track_std[time_index]) / 1e3
        what = "CCSP"
    x = np.linspace(mu - 4.5 * sd, mu + 4.5 * sd, 600)
    ax.plot(x, _normal(x, mu, sd), color=color, lw=2, label=label or f"{what}, sigma {sd:.3g} km")
    ax.set_xlabel(f"along-track error at {t / 3600:g} h [km]")
    ax.set_ylabel("PDF [1/km]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def ensemble_pdf(ens: EnsembleResult, *, time_index: int = -1, ax: Axes | None = None) -> Any:
    """Along-track PDF of an ensemble at output ``time_index``: each Monte Carlo model's
    members as a histogram under its normal (dashed), the mixture (bold) and its modes
    (triangles), km from the reference model's mean orbit. Returns the axes."""
    ax = _axes(ax)
    mix = ens.along_track_mixture(time_index)
    means = ens.component_means[time_index, :, 1]
    stds = np.sqrt(ens.component_covariances[time_index, :, 1, 1])
    lo, hi = float((means - 4 * stds).min()), float((means + 4 * stds).max())
    x = np.linspace(lo, hi, 1200)
    ref_p = ens.reference_positions[time_index]
    basis = rtn_basis(ref_p, ens.reference_velocities[time_index])
    for i, name in enumerate(ens.names):
        positions = getattr(ens.results[name], "positions", None)
        if positions is not None:
            at = (np.asarray(positions)[:, time_index] - ref_p) @ basis[1]
            at = at[np.isfinite(at)]
            if len(at) > 1:
                ax.hist(
                    at / 1e3,
                    bins=40,
                    range=(lo / 1e3, hi / 1e3),
                    density=True,
                    color=f"C{i}",
                    alpha=0.25,
                )
        ax.plot(
            x / 1e3,
            _normal(x, means[i], stds[i]) * 1e3,
            "--",
            color=f"C{i}",
            lw=1.5,
            label=f"{name} (Cd {ens.cd[name]:.3f})",
        )
    ax.plot(x / 1e3, mix.pdf(x) * 1e3, "k", lw=2.6, label="mixture")
    modes = np.asarray(mix.modes()).reshape(-1)
    ax.plot(
        modes / 1e3,
        mix.pdf(modes) * 1e3,
        "kv",
        ms=9,
        label=f"mixture mode{'s' if len(modes) != 1 else ''} ({len(modes)})",
    )
    ax.set_xlabel(
        f"along-track at {ens.times[time_index] / 3600:g} h vs the {ens.reference} mean orbit [km]"
    )
    ax.set_ylabel("PDF [1/km]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def rtn_spread(
    result: MonteCarloResult | CcspResult, *, ax: Axes | None = None, label: str = ""
) -> Any:
    """Radial, along-track and cross-track 1-sigma over time (log scale), km, of any
    result with ``moments()``. Returns the axes."""
    ax = _axes(ax)
    moments = result.moments()
    sig = np.sqrt(np.maximum(np.diagonal(moments.rtn_covariance, axis1=1, axis2=2), 0.0))
    t = _hours(moments.times)
    prefix = f"{label} " if label else ""
    for k, (name, style) in enumerate(
        zip(("radial", "along-track", "cross-track"), ("-", "-", ":"), strict=True)
    ):
        ax.plot(t[1:], sig[1:, k] / 1e3, style, color=f"C{k}", label=f"{prefix}{name}")
    ax.set_yscale("log")
    ax.set_xlabel("time [h]")
    ax.set_ylabel("1-sigma [km]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return ax


def density_traces(result: MonteCarloResult, *, members: int = 5, ax: Axes | None = None) -> Any:
    """The density the first ``members`` members saw at the outputs, 1e-12 kg/m^3, and
    their mean; needs ``monte_carlo(..., record_density=True)``. Returns the axes."""
    if result.densities is None:
        raise ValueError("no densities recorded: run monte_carlo(..., record_density=True)")
    ax = _axes(ax)
    t = _hours(result.times)
    for row in result.densities[:members]:
        ax.plot(t, row * 1e12, lw=0.8)
    ax.plot(t, np.nanmean(result.densities, axis=0) * 1e12, "k", lw=2, label="member mean")
    ax.set_xlabel("time [h]")
    ax.set_ylabel("density [1e-12 kg/m^3]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def catalog_summary(result: CatalogResult, *, ax: Axes | None = None) -> Any:
    """Along-track 1-sigma at each object's last valid output against its initial
    perigee altitude (log scale), one point per object coloured by status. Returns the
    axes."""
    ax = _axes(ax)
    perigee, sigma, status = [], [], []
    for k, obj in enumerate(result.objects):
        r, v = obj.state.position, obj.state.velocity
        mu = MU
        energy = v @ v / 2 - mu / np.linalg.norm(r)
        a = -mu / (2 * energy)
        h = np.cross(r, v)
        e = np.sqrt(max(0.0, 1 - (h @ h) / (mu * a)))
        valid = np.flatnonzero(result.valid[k])
        if len(valid) == 0:
            continue
        i = valid[-1]
        basis = rtn_basis(result.mean[k, i, :3], result.mean[k, i, 3:])
        cov = basis @ result.covariance[k, i, :3, :3] @ basis.T
        perigee.append((a * (1 - e) - R_EARTH) / 1e3)
        sigma.append(np.sqrt(max(cov[1, 1], 0.0)) / 1e3)
        status.append(str(result.status[k]))
    perigee_a, sigma_a, status_a = np.array(perigee), np.array(sigma), np.array(status)
    for i, s in enumerate(sorted(set(status))):
        pick = status_a == s
        ax.semilogy(
            perigee_a[pick],
            sigma_a[pick],
            "o",
            ms=3.5,
            color=f"C{i}",
            label=f"{s} ({int(pick.sum())})",
        )
    ax.set_xlabel("initial perigee altitude [km]")
    ax.set_ylabel("along-track 1-sigma at the last output [km]")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return ax
