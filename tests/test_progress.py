"""Progress that reaches a log: with stderr not a terminal, plain lines at a fixed
interval (a heartbeat even when nothing is reported), none for a run shorter than it."""

from __future__ import annotations

import time

from rhoprop import progress


def test_plain_lines_when_stderr_is_not_a_terminal(monkeypatch, capsys):
    monkeypatch.setattr(progress, "LINE_INTERVAL", 0.05)
    bar = progress.ProgressBar(10, "catalog", unit="objects")
    bar(3)
    time.sleep(0.3)  # nothing reported meanwhile: the heartbeat still prints
    bar(10)
    bar.close()
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) >= 3, lines
    assert lines[0].startswith("catalog: 3/10 objects (30 %), ")
    assert "s left" in lines[0]
    assert lines[-1].startswith("catalog: 10/10 objects (100 %), ")


def test_a_short_run_prints_nothing(monkeypatch, capsys):
    monkeypatch.setattr(progress, "LINE_INTERVAL", 5.0)
    bar = progress.ProgressBar(4, "Monte Carlo")
    bar(4)
    bar.close()
    assert capsys.readouterr().err == ""
