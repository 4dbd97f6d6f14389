"""Progress that reaches a log: with stderr not a terminal, plain lines at a fixed
interval (a heartbeat even when nothing is reported), none for a run shorter than it."""

from __future__ import annotations

import time

import numpy as np

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


def test_runs_reporting_at_once_keep_their_lines_whole(monkeypatch):
    # Two models sampled in parallel printed "... 12 ssampling ...": print() wrote each
    # line's text and its newline apart. Every write is now a whole line.
    import io
    import sys

    writes: list[str] = []

    class Recorder(io.StringIO):
        def write(self, text: str) -> int:
            writes.append(text)
            time.sleep(0.001)  # widen the window another thread could write into
            return len(text)

    monkeypatch.setattr(progress, "LINE_INTERVAL", 0.01)
    monkeypatch.setattr(sys, "stderr", Recorder())
    bars = [progress.ProgressBar(8, f"sampling model {k}", unit="days") for k in range(4)]
    time.sleep(0.2)
    for bar in bars:
        bar(8)
        bar.close()
    assert len(writes) >= 8
    assert all(w.endswith("\n") and w.count("\n") == 1 for w in writes), writes[:5]


def test_a_short_run_prints_nothing(monkeypatch, capsys):
    monkeypatch.setattr(progress, "LINE_INTERVAL", 5.0)
    bar = progress.ProgressBar(4, "Monte Carlo")
    bar(4)
    bar.close()
    assert capsys.readouterr().err == ""


def test_sampling_tiles_and_a_grown_cache_are_said(monkeypatch, capsys, tmp_path):
    # Sampling a model into the cache (about a second a day) printed nothing before the
    # run's own progress; the paper study filled the cache with a gigabyte without a word.
    import numpy as np

    import rhoprop as rp
    from rhoprop import cli

    monkeypatch.setattr(progress, "LINE_INTERVAL", 0.0)
    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path))

    def slow(t, lat, lon, h):
        time.sleep(0.01)
        mean = 3e-12 * np.exp(-(np.asarray(h) - 400e3) / 60e3)
        return mean, 0.1 * mean

    resolution = rp.density.FieldResolution(
        time=3600.0, altitude=50e3, latitude=15.0, longitude=30.0
    )
    model = rp.density.FromFunction(slow, name="slow", cache_key="slow v1", resolution=resolution)
    model.atlas.field("2002-09-07T00:00", "2002-09-09T12:00")
    err = capsys.readouterr().err
    assert "sampling FromFunction into the cache: 3/3 days" in err, err
    model.atlas.field("2002-09-07T00:00", "2002-09-09T12:00")  # from memory: no word
    assert capsys.readouterr().err == ""
    # A model without a cache key is sampled into memory, and says so.
    unkeyed = rp.density.FromFunction(slow, name="slow", resolution=resolution)
    unkeyed.atlas.field("2002-09-07T00:00", "2002-09-09T12:00")
    err = capsys.readouterr().err
    assert "sampling FromFunction into memory: 3/3 days" in err, err

    before = cli._cache_bytes()
    (tmp_path / "tiles" / "big.npz").write_bytes(b"0" * 60_000_000)
    cli._say_cache_growth(before)
    err = capsys.readouterr().err
    assert "the cache grew by 60 MB" in err and "rhoprop cache clear" in err, err
    cli._say_cache_growth(cli._cache_bytes())
    assert capsys.readouterr().err == ""


def test_a_log_hears_from_the_process_every_interval_across_stages(monkeypatch):
    # Stage b starts 0.3 intervals after stage a's last line: its first line comes one
    # interval after that line, not one interval after its own start (a whole-catalog
    # screen left 12 s between a stage's last line and the next one's first).
    import sys

    interval = 0.4
    monkeypatch.setattr(progress, "LINE_INTERVAL", interval)
    monkeypatch.setattr(progress, "_POLL", 0.01)
    monkeypatch.setattr(progress, "_LAST_LINE", [0.0])
    stamps: list[float] = []

    class Log:
        def write(self, text: str) -> None:
            stamps.append(time.monotonic())

        def flush(self) -> None:
            pass

        def isatty(self) -> bool:
            return False

    monkeypatch.setattr(sys, "stderr", Log())
    a = progress._Lines(1, "a", "x")
    time.sleep(1.1 * interval)
    a._stop.set()
    a._thread.join()  # a's last line is its heartbeat at one interval
    time.sleep(0.3 * interval)
    b = progress._Lines(1, "b", "x")
    time.sleep(1.5 * interval)
    b.close()
    gaps = np.diff(stamps)
    assert len(stamps) >= 3 and gaps.max() < 1.2 * interval, gaps
