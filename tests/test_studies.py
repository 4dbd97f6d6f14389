"""The method comparison study on the analytic atmosphere (fast), against the long-time
theory of docs/conventions.md, "The kappa processes"."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import studies


def test_method_comparison_ratios_and_figure(tmp_path):
    model = rp.scenarios.benchmark_exponential(0.2)
    methods = {k: studies.METHODS[k] for k in ("gauss_markov_18min", "interpolated_18min")}
    mc = studies.method_comparison(model=model, n=400, methods=methods, progress=False)
    ratio = mc.along_track_std["gauss_markov_18min"] / mc.along_track_std["interpolated_18min"]
    # sqrt(2 / ln 2) = 1.70; with 400 members each the ratio of stds has ~5 % error.
    assert ratio == pytest.approx(np.sqrt(2 / np.log(2)), rel=0.15)
    t, rho = mc.traces["gauss_markov_18min"]
    assert rho.shape == (5, len(t)) and t[-1] == 3 * 3600.0
    # Traces are the first five members of the full run (same seed, same member index).
    assert np.all(rho > 0)
    assert "| Gauss-Markov 18 min / Interpolated 18 min |" in mc.table()
    path = mc.figure(tmp_path / "fig.png")
    assert path.stat().st_size > 10_000


def test_ccsp_vs_monte_carlo_on_analytic_models(tmp_path):
    ref = rp.scenarios.benchmark_exponential(0.2)
    second = rp.density.Exponential(1.2 * 3.725e-12, 400e3, 58.515e3, rel_sigma=0.2)
    c = studies.ccsp_vs_monte_carlo(
        reference=ref, second=second, duration=86400.0, n=200, progress=False
    )
    keys = list(c.mc_along)
    # Debiasing recovers Cd_ref / 1.2 exactly for a constant density ratio.
    assert c.cd[keys[2]] == pytest.approx(3.0912 / 1.2, rel=1e-12)
    # Debiased, the second model's orbit stays with the reference; with Cd_ref it runs ahead.
    assert abs(c.ccsp_mean[keys[2]]) < 0.1 * abs(c.ccsp_mean[keys[1]])
    assert c.ccsp_mean[keys[1]] > 0
    # The CCSP spread is ~1.5x the Gauss-Markov 18 min Monte Carlo (docs/conventions.md,
    # "CCSP filter").
    ratio = c.ccsp_std[keys[0]] / c.mc_along[keys[0]].std(ddof=1)
    assert 1.2 < ratio < 1.9, ratio
    # The figure states the long-time ratio sqrt(D_ccsp / D_mc): D_ccsp = 2 dt for
    # correlation 1/3, D_mc = d (1 + a) / (1 - a) for AR(1) nodes d = 180 s apart with
    # a = exp(-ln 2 d / 1080 s) (-> 2 x 1080 s / ln 2 as d -> 0).
    a = np.exp(-np.log(2) * 180.0 / 1080.0)
    d_mc = 180.0 * (1 + a) / (1 - a)
    assert c.expected_ratio() == pytest.approx(np.sqrt(7200.0 / d_mc), rel=1e-12)
    assert c.members == 200 and c.update_interval == 3600.0
    assert "| CCSP/MC std |" in c.table()
    assert c.figure(tmp_path / "fig6.png").stat().st_size > 10_000
