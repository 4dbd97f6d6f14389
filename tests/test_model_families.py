"""The study's three model families: case_models picks NRLMSIS 2.1, JB2008 and
Jacchia-Roberts 1971 when JB2008 index files are available (else the offline fallback),
the simulated cases hold each family's geomagnetic driver at its mean, and the debiased
Cd of the three differ."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.studies import scenarios


def test_fallback_without_index_files(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("RHOPROP_JB2008_DATA", raising=False)
    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path))
    names, why, indices = scenarios.model_choice()
    assert names == ("NRLMSIS 2.1", "Jacchia-Roberts 1971", "NRLMSISE-00")
    assert indices is None and "not found" in why
    models = scenarios.case_models("solar-min")
    assert list(models) == list(names)
    assert isinstance(models["Jacchia-Roberts 1971"], rp.density.JacchiaRoberts)


def test_three_families_with_index_files(monkeypatch: pytest.MonkeyPatch, test_data: Path) -> None:
    monkeypatch.setenv("RHOPROP_JB2008_DATA", str(test_data / "jb2008"))
    names, why, indices = scenarios.model_choice()
    assert names == ("NRLMSIS 2.1", "JB2008", "Jacchia-Roberts 1971")
    assert indices is not None and "three model families" in why
    observed = scenarios.case_models("solar-max-storm")
    simulated = scenarios.case_models("solar-max-simulated")
    assert list(observed) == list(names) == list(simulated)
    jb_obs, jb_sim = observed["JB2008"], simulated["JB2008"]
    assert isinstance(jb_obs, rp.density.Jb2008) and isinstance(jb_sim, rp.density.Jb2008)
    assert jb_obs.dtc is None
    # The mean dTc of 2000-2018 is a few tens of K.
    assert jb_sim.dtc is not None and 20.0 < jb_sim.dtc < 100.0
    # The simulated JR holds Kp at its long-term mean: the storm's Kp is gone.
    t = np.array(["2002-09-07T21:00"], dtype="datetime64[ns]")
    jr_obs = observed["Jacchia-Roberts 1971"]
    jr_sim = simulated["Jacchia-Roberts 1971"]
    assert isinstance(jr_obs, rp.density.JacchiaRoberts)
    assert isinstance(jr_sim, rp.density.JacchiaRoberts)
    assert jr_obs.drivers(t)[0, 2] > 5.0 > jr_sim.drivers(t)[0, 2]


def test_debiased_cd_of_three_families_differ(
    monkeypatch: pytest.MonkeyPatch, test_data: Path
) -> None:
    monkeypatch.setenv("RHOPROP_JB2008_DATA", str(test_data / "jb2008"))
    state, craft = scenarios.paper_state(), scenarios.paper_spacecraft()
    spread = {}
    for preset in ("paper", "calibrated"):
        ens = rp.ensemble(
            state,
            craft,
            scenarios.case_models("solar-max-storm", preset=preset),
            scenarios.REFERENCE_MODEL,
            duration=6 * 3600.0,
            method=rp.MonteCarlo(n=20, seed=1, progress=False),
        )
        cd = ens.cd
        assert cd["NRLMSIS 2.1"] == pytest.approx(scenarios.PAPER_CD)
        values = sorted(cd.values())
        spread[preset] = values[-1] - values[0]
        if preset == "paper":
            # The paper's families (no mean correction) differ by > 5 % in Cd.
            assert min(np.diff(values)) > 0.05, cd
    # Corrected by the observed densities, the families' means agree better.
    assert spread["calibrated"] < spread["paper"], spread
