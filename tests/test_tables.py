"""Tables out as Parquet or CSV (rhoprop.io.tables, the commands' --format): the same
rows and values either way (a CSV's numbers read back to the same bits), the metadata a
CSV cannot hold in a JSON file beside it, and a format that is neither refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.csv as pcsv
import pyarrow.parquet as pq
import pytest

from rhoprop.cli import main
from rhoprop.io import write_table
from rhoprop.io.tables import format_argument, table_name

SAMPLE = Path(__file__).parent / "data" / "sample.tle"


def _csv(path: Path) -> dict[str, list[object]]:
    return pcsv.read_csv(path).to_pydict()


def test_a_table_reads_back_the_same_from_either_format(tmp_path):
    rng = np.random.default_rng(4)
    columns = {
        "norad_id": np.arange(5, dtype=np.int64) + 25544,
        "x": rng.normal(0.0, 7e6, 5),  # full-precision doubles
        "tiny": rng.normal(0.0, 1e-300, 5),
        "name": np.array(["ISS (ZARYA)", "a, b", 'say "hi"', "", "Ä"], dtype=object),
        "epoch": np.array(["2026-03-01T00:00:00.123456789"] * 5, dtype="datetime64[ns]"),
    }
    meta = {"frame": "TEME", "units": {"x": "m"}}
    parquet = write_table(columns, tmp_path / "t.parquet", "parquet", meta)
    csv = write_table(columns, tmp_path / "t.csv", "csv", meta)
    a, b = pq.read_table(parquet).to_pydict(), _csv(csv)
    assert a["norad_id"] == b["norad_id"] and a["name"][:2] == b["name"][:2]
    assert a["x"] == b["x"] and a["tiny"] == b["tiny"]  # the same bits back
    assert b["name"][2] == 'say "hi"' and b["name"][4] == "Ä"
    assert [str(t)[:29] for t in a["epoch"]] == [str(t)[:29] for t in b["epoch"]]
    assert json.loads(pq.read_schema(parquet).metadata[b"rhoprop"]) == meta
    assert json.loads((tmp_path / "t.meta.json").read_text()) == meta
    assert table_name("events", "csv") == "events.csv"
    with pytest.raises(ValueError, match="format must be one of parquet, csv"):
        format_argument("xlsx")


def test_rhoprop_catalog_writes_the_same_tables_as_csv(tmp_path, capsys):
    args = ["catalog", str(SAMPLE), "--end", "2002-09-07T06:00Z", "--model", "exponential"]
    assert main([*args, "--out", str(tmp_path / "p")]) == 0
    assert main([*args, "--out", str(tmp_path / "c"), "--format", "csv"]) == 0
    for stem in ("ephemeris", "summary"):
        parquet = pq.read_table(tmp_path / "p" / f"{stem}.parquet").to_pydict()
        csv = _csv(tmp_path / "c" / f"{stem}.csv")
        assert list(csv) == list(parquet)
        for key in ("x", "cov_vz_vz", "along_track_std_m", "norad_id"):
            if key in parquet:
                assert csv[key] == parquet[key], key
    meta = json.loads((tmp_path / "c" / "ephemeris.meta.json").read_text())
    schema = pq.read_schema(tmp_path / "p" / "ephemeris.parquet")
    assert meta == json.loads(schema.metadata[b"rhoprop"]) and meta["time_scale"] == "UTC"
    listed = json.loads((tmp_path / "c" / "manifest.json").read_text())
    assert listed["files"] == ["ephemeris.csv", "ephemeris.meta.json", "summary.csv"]
    capsys.readouterr()


def test_rhoprop_reentry_and_screen_take_a_format(tmp_path, capsys):
    args = ["reentry", str(SAMPLE), "--horizon", "2", "--members", "10"]
    args += ["--model", "exponential", "--no-fit"]
    assert main([*args, "--out", str(tmp_path / "c")]) == 0  # csv by default
    assert main([*args, "--out", str(tmp_path / "p"), "--format", "parquet"]) == 0
    text = _csv(tmp_path / "c" / "reentry.csv")
    typed = pq.read_table(tmp_path / "p" / "reentry.parquet").to_pydict()
    assert typed["norad_id"] == text["norad_id"]
    assert typed["decayed_fraction"] == text["decayed_fraction"]
    # Typed epochs in Parquet (null beyond the horizon), ISO text in the CSV ("" there).
    schema = pq.read_schema(tmp_path / "p" / "reentry.parquet")
    assert str(schema.field("epoch_q975").type).startswith("timestamp")
    assert [t is None for t in typed["epoch_q975"]] == [t is None for t in text["epoch_q975"]]
    screen = ["screen", str(SAMPLE), "--start", "2002-09-07T00:00", "--end", "2002-09-07T06:00"]
    screen += ["--distance", "2000000", "--model", "exponential", "--no-pc", "--no-cdm"]
    assert main([*screen, "--out", str(tmp_path / "sp")]) == 0
    assert main([*screen, "--out", str(tmp_path / "sc"), "--format", "csv"]) == 0
    parquet = pq.read_table(tmp_path / "sp" / "events.parquet").to_pydict()
    csv = _csv(tmp_path / "sc" / "events.csv")
    assert len(csv["miss_distance"]) >= 1 and csv["miss_distance"] == parquet["miss_distance"]
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main([*screen, "--out", str(tmp_path / "x"), "--format", "xlsx"])
    assert "invalid choice: 'xlsx'" in capsys.readouterr().err
