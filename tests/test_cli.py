"""The command line as a user runs it."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from rhoprop.cli import main


def test_help_lists_commands(capsys):
    assert main([]) == 2
    out = capsys.readouterr().out
    assert "paper" in out and "usage: rhoprop" in out


def test_paper_quick_prints_methods_that_agree(capsys, tmp_path):
    assert main(["paper", "--quick", "--members", "8", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if line.strip().startswith(("rk8", "rk4"))]
    assert len(rows) == 2
    # Last column: distance to the adaptive solution after 6 h, m.
    assert all(float(r[-1]) < 0.1 for r in rows), rows
    # The method comparison wrote its figure and a summary of the fixed shape.
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert set(summary["method_comparison"]) == {
        "white_10s",
        "interpolated_18min",
        "interpolated_180min",
        "gauss_markov_18min",
        "gauss_markov_180min",
    }
    assert (tmp_path / "method_comparison.png").stat().st_size > 10_000
    assert (tmp_path / "ccsp_vs_monte_carlo.png").stat().st_size > 10_000
    assert len(summary["ccsp_vs_monte_carlo"]) == 3
    # What produced the numbers is recorded.
    import rhoprop

    assert summary["software"]["rhoprop"] == rhoprop.__version__
    assert summary["seed"] == 0 and "ccsp_update_interval_s" in summary["kappa"]
    # The conjunction study: one row per model's mean; the mixture is the weighted sum.
    conj = summary["conjunction"]
    assert len(conj["rows"]) == 3
    for row in conj["rows"]:
        pcs = list(row["pc_models"].values())
        assert row["pc_mixture"] == pytest.approx(sum(pcs) / 3, rel=1e-12)
        lo, hi = row["pc_monte_carlo_interval"]
        assert 0 <= lo <= row["pc_monte_carlo"] <= hi <= 1
    # Every file went through a temporary name and is listed in the manifest.
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["complete"] and sorted(manifest["files"]) == [
        "ccsp_vs_monte_carlo.png",
        "conjunction.png",
        "ensembles.png",
        "method_comparison.png",
        "summary.json",
        "summary.md",
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [*manifest["files"], "manifest.json"]
    )


def test_console_script_module_entry():
    done = subprocess.run(
        [sys.executable, "-m", "rhoprop", "--version"], capture_output=True, text=True, check=True
    )
    assert done.stdout.startswith("rhoprop ")
