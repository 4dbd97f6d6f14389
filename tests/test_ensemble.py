"""Multi-model ensembles: debiasing, the mixture, the paper's four cases end to end, and
TOML scenario files."""

from __future__ import annotations

import json

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import scenarios, studies
from rhoprop.cli import main
from rhoprop.studies.scenario_file import ScenarioError, load_scenario


@pytest.fixture(scope="module")
def analytic():
    state, craft = scenarios.paper_state(), scenarios.paper_spacecraft()
    models = {
        "ref": rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=0.2),
        "denser": rp.density.Exponential(1.2 * 3.725e-12, 400e3, 58.515e3, rel_sigma=0.2),
    }
    return state, craft, models


def test_monte_carlo_ensemble_on_analytic_models(analytic):
    state, craft, models = analytic
    ens = rp.ensemble(
        state,
        craft,
        models,
        "ref",
        duration=86400.0,
        method=rp.MonteCarlo(n=300, progress=False),
    )
    assert ens.cd["ref"] == 3.0912
    assert ens.cd["denser"] == pytest.approx(3.0912 / 1.2, rel=1e-12)
    # Debiased with a constant ratio, both models give the same drag: same mean offsets
    # (within 3 standard errors of the MC means) and the mixture mean is their average.
    m = ens.component_means[-1]
    s = np.sqrt(ens.component_covariances[-1, :, 1, 1])
    assert abs(m[0, 1] - m[1, 1]) < 3 * np.hypot(*s) / np.sqrt(300)
    mix = ens.along_track_mixture()
    assert mix.mean()[0] == pytest.approx(m[:, 1].mean(), abs=1e-9)
    x = np.linspace(-8 * s.max(), 8 * s.max(), 4001) + m[:, 1].mean()
    assert np.trapezoid(ens.along_track_pdf(x), x) == pytest.approx(1.0, abs=1e-4)
    summary = ens.summary()
    assert set(summary["models"]) == {"ref", "denser"}
    assert (
        summary["mixture"]["q025_m"] < summary["mixture"]["mean_m"] < summary["mixture"]["q975_m"]
    )


def test_ccsp_ensemble_and_weights(analytic):
    state, craft, models = analytic
    ens = rp.ensemble(
        state,
        craft,
        models,
        "ref",
        method=rp.Ccsp(),
        duration=86400.0,
        weights=[3.0, 1.0],
        debias=rp.Debias(cds={"denser": 3.0912}),
    )
    np.testing.assert_allclose(ens.weights, [0.75, 0.25])
    # Undebiased, the denser model's orbit runs ahead of the reference.
    assert ens.component_means[-1, 1, 1] > ens.component_means[-1, 0, 1] + 10.0
    assert abs(ens.component_means[-1, 0, 1]) < 1e-6  # the reference is the mean orbit
    with pytest.raises(ValueError, match="reference 'nope'"):
        rp.ensemble(state, craft, models, "nope", method=rp.Ccsp(), duration=3600.0)
    with pytest.raises(ValueError, match="weights must be 2"):
        rp.ensemble(state, craft, models, "ref", method=rp.Ccsp(), duration=3600.0, weights=[1.0])


def test_a_spread_narrows_every_component_as_a_scaled_model_would(analytic):
    # spread s runs each model as SigmaScaled(model, s): an exponential model's sigma
    # scaled by 0.5 is the model with half the relative sigma, bit for bit (the core
    # multiplies 0.2 x 0.5 = 0.1 exactly), so each component equals a plain ensemble of
    # those halved models.
    state, craft, models = analytic
    run = dict(method=rp.Ccsp(), duration=86400.0, debias=rp.Debias(cds={"denser": 3.0912}))
    ens = rp.ensemble(state, craft, models, "ref", spread=0.5, **run)
    halved = {
        name: rp.density.Exponential(m.rho0, m.h0, m.scale_height, rel_sigma=0.1)
        for name, m in models.items()
    }
    plain = rp.ensemble(state, craft, halved, "ref", **run)
    assert ens.spread == 0.5 and plain.spread == 1.0  # analytic models: no calibrated spread
    np.testing.assert_array_equal(ens.component_covariances, plain.component_covariances)
    np.testing.assert_array_equal(ens.component_means, plain.component_means)
    wide = rp.ensemble(state, craft, models, "ref", **run)
    assert (wide.component_covariances[-1, :, 1, 1] > ens.component_covariances[-1, :, 1, 1]).all()
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="spread must be"):
            rp.ensemble(state, craft, models, "ref", spread=bad, **run)


def test_the_calibrated_families_pool_with_their_calibrated_spread(test_data):
    # The spread fitted with the calibrated weights applies with them only: the default
    # weights of calibrated NRLMSIS 2.1 and JB2008 (not their paper presets, nor other
    # models) and no weights given.
    from rhoprop.density import calibrated
    from rhoprop.ensemble.combine import default_spread

    jb = test_data / "jb2008"
    indices = rp.density.Jb2008Indices(jb / "SOLFSMY.TXT", jb / "DTCFILE.TXT")
    families = {"msis": rp.density.Msis("2.1"), "jb": rp.density.Jb2008(indices)}
    assert default_spread(families) == calibrated.ENSEMBLE_SPREAD < 1
    assert default_spread({"msis": rp.density.Msis("2.1", preset="paper")}) == 1.0
    assert default_spread({"exp": rp.density.Exponential.benchmark()}) == 1.0
    # screen_all's Pc stage mixes them alike: the calibrated weights, not equal ones.
    from rhoprop.conjunction.event_pc import _weights

    np.testing.assert_allclose(_weights(families, None), [0.849, 0.151])
    np.testing.assert_allclose(_weights(families, {"msis": 1.0, "jb": 1.0}), [0.5, 0.5])
    scaled = rp.density.SigmaScaled(families["msis"], 0.5)
    where = ("2003-10-30T12:00", 10.0, 20.0, 400e3)
    (m0, s0), (m1, s1) = families["msis"].mean_std(*where), scaled.mean_std(*where)
    assert m1 == m0 and s1 == pytest.approx(0.5 * s0, rel=1e-15)
    with pytest.raises(ValueError, match="factor must be finite and >= 0"):
        rp.density.SigmaScaled(families["msis"], -0.1)
    with pytest.raises(TypeError, match="model must be a rhoprop density model"):
        rp.density.SigmaScaled("msis", 0.5)


def test_four_cases_end_to_end_solar_max_spreads_more():
    ens = studies.case_ensembles(n=40, duration=86400.0, progress=False)
    assert list(ens) == list(scenarios.CASE_EPOCHS)
    std = {case: e.summary()["mixture"]["std_m"] for case, e in ens.items()}
    print(std)
    # The paper's finding: solar maximum (denser, more uncertain) spreads more.
    assert std["solar-max-storm"] > std["solar-min"]
    assert std["solar-max-simulated"] > std["solar-min-simulated"]
    # Three distinct model families (NRLMSIS 2.0, which duplicated 2.1's mass
    # density, left the default): their debiased Cd differ by more than 0.05.
    cds = sorted(ens["solar-min"].cd.values())
    assert len(cds) == 3 and min(np.diff(cds)) > 0.05, cds


GOOD = """
[scenario]
name = "tiny"
epoch = "2002-09-07T01:00:00Z"
duration = 7200.0
[state]
position = [3782900.7032, -5441600.6779, -1420075.1327]
velocity = [-606.6600, 1539.2559, -7488.3946]
[spacecraft]
cd = 3.0912
area_to_mass = 0.0015
[[models]]
name = "a"
type = "exponential"
rho0 = 3.725e-12
h0 = 400e3
scale_height = 58515.0
rel_sigma = 0.2
reference = true
[[models]]
name = "b"
type = "exponential"
rho0 = 4e-12
h0 = 400e3
scale_height = 58515.0
rel_sigma = 0.2
[method]
kind = "monte_carlo"
members = 20
kappa = { type = "gauss_markov", half_life = 1080.0 }
"""


def test_scenario_file_runs(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(GOOD)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert set(summary["models"]) == {"a", "b"} and summary["mixture"]["modes"] >= 1
    assert (tmp_path / "out" / "ensemble.png").stat().st_size > 10_000
    # One OEM per model (validated by the oem library) and the dataset, all in the manifest.
    from oem import OrbitEphemerisMessage

    files = json.loads((tmp_path / "out" / "manifest.json").read_text())["files"]
    assert {"oem/a.oem", "oem/b.oem", "ensemble.nc"} <= set(files)
    assert len(OrbitEphemerisMessage.open(str(tmp_path / "out" / "oem" / "a.oem")).states) > 1


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda s: s.replace("cd = 3.0912", 'cd = "big"'), r"spacecraft\.cd must be a float"),
        (lambda s: s.replace("duration = 7200.0\n", ""), r"scenario\.duration is missing"),
        (lambda s: s.replace("reference = true\n", ""), "exactly one model must have reference"),
        (
            lambda s: s.replace(
                'type = "exponential"\nrho0 = 4e-12', 'type = "hasdm"\nrho0 = 4e-12'
            ),
            r"models\[1\]\.type must be 'msis' or 'exponential'",
        ),
        (
            lambda s: s.replace("members = 20", "members = 20\ncolour = 3"),
            r"method has unknown key",
        ),
        (lambda s: s.replace("gauss_markov", "brownian"), r"method\.kappa\.type must be one of"),
        (lambda s: s.replace("half_life = 1080.0", "half_life = -5.0"), "half_life must be > 0"),
        (lambda s: s.replace("rho0 = 4e-12", "rho0 = -4e-12"), r"models\[1\]: rho0 must be > 0"),
        (lambda s: s + "\n[extra]\n", "unknown key"),
        (lambda s: s.replace("[spacecraft]", "[spacecraft"), "not valid TOML"),
        (lambda s: s.replace("[spacecraft]", "[spacecraft]\ncr = 7.0"), r"\[spacecraft\]: cr = 7"),
        (lambda s: s.replace("[spacecraft]", '[spacecraft]\ncr = "high"'), "cr must be a float"),
    ],
)
def test_scenario_errors_name_the_key(tmp_path, edit, match):
    path = tmp_path / "s.toml"
    path.write_text(edit(GOOD))
    with pytest.raises(ScenarioError, match=match):
        load_scenario(path)
    assert main(["run", str(path)]) == 1


def test_example_scenario_is_valid():
    from pathlib import Path

    sc = load_scenario(Path(__file__).parents[1] / "examples" / "scenario.toml")
    assert sc["reference"] == "NRLMSIS 2.1" and sc["method"].n == 500


def test_a_scenario_may_give_the_radiation_pressure_coefficient(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(GOOD.replace("[spacecraft]", "[spacecraft]\ncr = 1.3"))
    assert load_scenario(path)["spacecraft"].cr == 1.3
    path.write_text(GOOD)
    assert load_scenario(path)["spacecraft"].cr is None


def test_example_scenario_switches_method_with_one_word(tmp_path):
    from pathlib import Path

    text = (Path(__file__).parents[1] / "examples" / "scenario.toml").read_text()
    path = tmp_path / "ccsp.toml"
    path.write_text(text.replace('kind = "monte_carlo"', 'kind = "ccsp"'))
    sc = load_scenario(path)
    assert sc["method"] == rp.Ccsp(perturbation="additive", update_interval=3600.0, drag_sigma=0.0)
    # The sub-tables are checked for their own method's keys.
    path.write_text(text.replace("update_interval = 3600.0", "members = 3"))
    with pytest.raises(ScenarioError, match=r"method\.ccsp has unknown key"):
        load_scenario(path)


def test_a_scenario_after_the_record_runs_on_the_forecast_drivers(tmp_path):
    # The example's models on "observed" drivers cannot run past the record's last
    # observed day; space_weather = "forecast" takes its predicted rows (with the
    # forecast's lead time and sigma), as the catalog commands do by themselves.
    from pathlib import Path

    text = (Path(__file__).parents[1] / "examples" / "scenario.toml").read_text()
    text = text.replace('version = "2.1"\n', 'version = "2.1"\nspace_weather = "forecast"\n')
    path = tmp_path / "forecast.toml"
    path.write_text(text)
    sc = load_scenario(path)
    model = sc["models"]["NRLMSIS 2.1"]
    last = rp.SpaceWeather.cached().observed_end
    later = last + np.timedelta64(90, "D")  # past the daily predicted rows too
    with pytest.warns(rp.errors.PredictedDriversWarning):
        mean, sigma = model.mean_std(later, 0.0, 0.0, 400e3)
    assert np.isfinite(mean) and mean > 0 and sigma > 0
    with pytest.raises(rp.OutsideRecordError):
        rp.density.Msis("2.1").mean_std(later, 0.0, 0.0, 400e3)
