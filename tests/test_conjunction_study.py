"""The conjunction study (rhoprop.studies.conjunction): Pc per density model's Gaussian,
the mixture and the Monte Carlo over the members, which checks the Gaussians."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.studies.conjunction import conjunction_study, most_disputed


@pytest.fixture(scope="module")
def two_model_ensemble():
    state = rp.OrbitState(
        np.datetime64("2024-05-10T00:00"), [6778e3, 0.0, 0.0], [0.0, 5422.0, 5422.0]
    )
    models = {
        "low": rp.density.Exponential.benchmark(rel_sigma=0.15),
        "high": rp.density.Exponential(1.3 * 3.725e-12, 400e3, 58.515e3, rel_sigma=0.15),
    }
    return rp.ensemble(
        state,
        rp.Spacecraft(2.2, 0.01),
        models,
        "low",
        duration=86400.0,
        debias=rp.Debias(cds={"high": 2.2}),
        # The paper's 18-minute process: model means more than 2 sigma apart in a day.
        method=rp.MonteCarlo(
            n=600, kappa=rp.kappa.GaussMarkov(1080.0), seed=3, output_step=None, progress=False
        ),
    )


def test_mixture_is_the_weighted_model_pc_and_monte_carlo_agrees(two_model_ensemble):
    study = conjunction_study(two_model_ensemble, case="test", n_offsets=21, n_secondary=800)
    assert study.names == ["low", "high"]
    np.testing.assert_allclose(study.pc_mixture, study.weights @ study.pc_models, rtol=1e-14)
    # Each model's mean offset is on the grid and the models sit apart along the axis.
    for x in study.component_x:
        assert np.min(np.abs(study.offsets - x)) == 0.0
    assert abs(study.component_x[1] - study.component_x[0]) > 2 * study.component_sigma.max()
    # Where Pc is well resolved, the members' Monte Carlo Pc brackets the Gaussians' Pc:
    # its interval (1.96 standard errors) widened by 15 % for non-Gaussian tails.
    for _, i in study.rows():
        lo, hi = study.pc_mc_interval[i]
        assert study.pc_mc_hits[i] > 100
        assert 0.85 * lo <= study.pc_mixture[i] <= 1.15 * hi, (i, study.pc_mixture[i], lo, hi)
    # At the other model's mean, a single model's Pc falls orders of magnitude below.
    worst = max(ratio for _, _, ratio in study.understatement())
    assert worst > 100
    assert "mixture" in study.table()


def test_most_disputed_picks_the_case_whose_models_disagree(two_model_ensemble):
    calm = rp.ensemble(
        two_model_ensemble.results["low"].mean_orbit.state_at(0),
        rp.Spacecraft(2.2, 0.01),
        {
            "a": rp.density.Exponential.benchmark(rel_sigma=0.15),
            "b": rp.density.Exponential.benchmark(rel_sigma=0.15),
        },
        "a",
        duration=86400.0,
        debias=rp.Debias(cds={"b": 2.2}),
        method=rp.MonteCarlo(n=100, output_step=None, progress=False),
    )
    assert most_disputed({"calm": calm, "stormy": two_model_ensemble}) == "stormy"


def test_the_study_needs_members(two_model_ensemble):
    state = two_model_ensemble.results["low"].mean_orbit.state_at(0)
    ccsp = rp.ensemble(
        state,
        rp.Spacecraft(2.2, 0.01),
        {"a": rp.density.Exponential.benchmark(rel_sigma=0.15)},
        "a",
        method=rp.Ccsp(),
        duration=3600.0,
    )
    with pytest.raises(ValueError, match="Monte Carlo"):
        conjunction_study(ccsp)
