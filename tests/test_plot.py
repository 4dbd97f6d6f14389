"""rhoprop.plot: figures of one's own runs, drawn without pyplot or a backend change."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import rhoprop as rp


@pytest.fixture(scope="module")
def runs():
    state = rp.OrbitState(
        np.datetime64("2024-05-10T00:00"), [6778e3, 0.0, 0.0], [0.0, 5422.0, 5422.0]
    )
    craft = rp.Spacecraft(2.2, 0.01)
    model = rp.density.Exponential.benchmark(rel_sigma=0.2)
    mc = rp.monte_carlo(
        state, craft, model, 21600.0, n=300, seed=1, record_density=True, progress=False
    )
    cc = rp.ccsp(state, craft, model, 21600.0)
    ens = rp.ensemble(
        state,
        craft,
        {"a": model, "b": rp.density.Exponential(4.5e-12, 400e3, 58.515e3, rel_sigma=0.2)},
        "a",
        duration=21600.0,
        debias=rp.Debias(cds={"b": 2.2}),
        method=rp.MonteCarlo(n=200, output_step=None, progress=False),
    )
    return mc, cc, ens


def test_figures_show_the_numbers_of_the_run(runs, tmp_path):
    mc, cc, ens = runs
    ax = rp.plot.along_track(mc)
    # The fitted normal is the members' own: its peak is 1/(sqrt(2 pi) sigma).
    at = mc.along_track[:, -1] / 1e3
    line = ax.get_lines()[0]
    assert line.get_ydata().max() == pytest.approx(
        1 / (np.sqrt(2 * np.pi) * at.std(ddof=1)), rel=1e-3
    )
    assert len(ax.patches) == 40  # the histogram's bars
    ax.figure.savefig(tmp_path / "a.png")
    assert (tmp_path / "a.png").stat().st_size > 5_000

    ax = rp.plot.along_track(cc)
    sd = cc.along_track_std[-1] / 1e3
    assert ax.get_lines()[0].get_ydata().max() == pytest.approx(
        1 / (np.sqrt(2 * np.pi) * sd), rel=1e-3
    )
    ax = rp.plot.rtn_spread(cc, label="CCSP")
    along = ax.get_lines()[1]
    np.testing.assert_allclose(along.get_ydata(), cc.along_track_std[1:] / 1e3, rtol=1e-12)
    rp.plot.rtn_spread(mc, ax=ax, label="MC")
    assert len(ax.get_lines()) == 6
    ax = rp.plot.density_traces(mc, members=3)
    assert len(ax.get_lines()) == 4
    ax = rp.plot.ensemble_pdf(ens)
    assert [t.get_text() for t in ax.get_legend().get_texts()][-2] == "mixture"


def test_density_traces_need_recorded_densities(runs):
    mc, _, _ = runs
    import dataclasses

    with pytest.raises(ValueError, match="record_density"):
        rp.plot.density_traces(dataclasses.replace(mc, densities=None))


def test_importing_rhoprop_and_its_plots_leaves_matplotlib_alone():
    code = (
        "import sys, rhoprop as rp; rp.plot; "
        "print('matplotlib' in sys.modules, 'matplotlib.pyplot' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
