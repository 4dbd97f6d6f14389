"""The method comparison study on the analytic atmosphere (fast), against the long-time
theory of DESIGN.md section 4."""

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
