"""JB2008 against the reference Fortran (shared data, read through RHOPROP_TEST_DATA):
432 direct calls of the core routine to 1e-6 relative, and the two 7,714-point grids of
the reference driver to their printed precision (5 significant digits, ~2e-4)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import _core
from rhoprop.density.point_model import modified_julian_date

COLUMNS = ("F10", "F10B", "S10", "S10B", "M10", "M10B", "Y10", "Y10B", "DSTDTC")
#: Epochs of the two grid files (headers: 2017 196 19 6 19.500; 2009 138 7 19 56.500).
GRIDS = {
    "JB2008_AUTO_OUTPUT_01.DAT": "2017-07-15T19:06:19.500",
    "JB2008_AUTO_OUTPUT_02.DAT": "2009-05-18T07:19:56.500",
}


@pytest.fixture(scope="module")
def jb_dir(test_data: Path) -> Path:
    return test_data / "jb2008"


@pytest.fixture(scope="module")
def indices(jb_dir: Path) -> rp.density.Jb2008Indices:
    return rp.density.Jb2008Indices(jb_dir / "SOLFSMY.TXT", jb_dir / "DTCFILE.TXT")


def test_core_matches_432_reference_calls(jb_dir: Path) -> None:
    d = np.genfromtxt(jb_dir / "jb2008_fortran_core_cases.csv", delimiter=",", names=True)
    assert len(d) == 432
    geometry = np.column_stack(
        [d[k] for k in ("sun_ra_rad", "sun_dec_rad", "sat_ra_rad", "sat_lat_rad", "alt_km")]
    )
    ix = np.column_stack([d[k] for k in COLUMNS])
    out = _core.jb2008_core(d["AMJD"], geometry, ix)
    tinf, temp, rho = out.exospheric_temperature, out.temperature, out.density
    np.testing.assert_allclose(rho, d["rho_kg_m3"], rtol=1e-6)
    np.testing.assert_allclose(tinf, d["tinf_K"], rtol=1e-9)
    np.testing.assert_allclose(temp, d["temp_K"], rtol=1e-9)


def _grid(path: Path) -> np.ndarray:
    lines = path.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("#"))
    return np.array([line.split() for line in lines[start + 1 :] if line.strip()], float)


@pytest.mark.parametrize("name", sorted(GRIDS))
def test_model_matches_reference_grids(
    jb_dir: Path, indices: rp.density.Jb2008Indices, name: str
) -> None:
    grid = _grid(jb_dir / name)
    assert grid.shape == (7714, 6)
    epoch = np.datetime64(GRIDS[name], "ns")
    alt_km, lon, lat, tinf_ref, temp_ref, rho_ref = grid.T
    model = rp.density.Jb2008(indices, preset="paper")
    mean, std = model.mean_std(epoch, lat, lon, alt_km * 1e3)
    np.testing.assert_allclose(mean, rho_ref, rtol=2e-4)
    assert (std > 0).all()
    # Temperatures are printed to 0.1 K.
    t = np.full(len(grid), epoch)
    out = _core.jb2008_geodetic(modified_julian_date(t), lat, lon, alt_km * 1e3, indices.at(t))
    tinf, temp = out.exospheric_temperature, out.temperature
    np.testing.assert_allclose(tinf, tinf_ref, atol=0.051)
    np.testing.assert_allclose(temp, temp_ref, atol=0.051)


def test_indices_match_the_reference_driver(
    test_data: Path, indices: rp.density.Jb2008Indices
) -> None:
    meta = json.loads((test_data / "reference" / "density_reference_values.json").read_text())
    for name, epoch in GRIDS.items():
        used = meta["jb2008"][name]["indices_used"]
        got = indices.at(np.array([np.datetime64(epoch, "ns")]))[0]
        np.testing.assert_array_equal(got, [used[k] for k in COLUMNS])


def test_index_lags_and_midnight_rule(indices: rp.density.Jb2008Indices) -> None:
    sol = indices._sol
    first = indices._sol_first
    t = np.array(["2009-12-02T00:00", "2009-12-02T00:00:01"], dtype="datetime64[ns]")
    row = (np.datetime64("2009-12-02") - first).astype(int)
    got = indices.at(t)
    # 00:00 belongs to the day it starts, as in the reference driver
    # (INDX = INT(T1950 - FS1950)): F10 of t - 1 day -> 2009-12-01, at 00:00 as at 00:00:01.
    # The day before differs in all three (so the test tells the rules apart).
    assert got[0, 0] == got[1, 0] == sol[row - 1, 0] != sol[row - 2, 0]
    assert got[0, 4] == got[1, 4] == sol[row - 2, 4] != sol[row - 3, 4]
    assert got[0, 6] == got[1, 6] == sol[row - 5, 6] != sol[row - 6, 6]
    just_before = indices.at(t[:1] - np.timedelta64(1, "ns"))
    assert just_before[0, 0] == sol[row - 2, 0]
    # dTc interpolated between hours then rounded: 2009-336 has 0 at 12 h, 17 at 13 h.
    t = np.array(["2009-12-02T12:00", "2009-12-02T12:29", "2009-12-02T12:31"], "datetime64[ns]")
    np.testing.assert_array_equal(indices.at(t)[:, 8], [0.0, 8.0, 9.0])


def test_outside_span_names_the_span(indices: rp.density.Jb2008Indices) -> None:
    with pytest.raises(rp.OutsideRecordError, match="outside the JB2008 index files' span"):
        indices.at(np.array(["2019-01-01"], dtype="datetime64[ns]"))
    first, last = indices.span
    # 1997-001 is the first record: Y10 (5-day lag) exists from 1997-01-06 00:00.
    assert first == np.datetime64("1997-01-06T00:00:00")
    got = indices.at(np.array([first, last]))
    np.testing.assert_array_equal(got[0, 6:8], indices._sol[0, 6:8])
    assert np.isfinite(got).all()
    with pytest.raises(rp.OutsideRecordError, match="1997-01-06"):
        indices.at(np.array([first - np.timedelta64(1, "ns")]))


def test_file_errors_name_file_and_line(tmp_path: Path, jb_dir: Path) -> None:
    with pytest.raises(FileNotFoundError, match="SOLFSMY"):
        rp.density.Jb2008Indices(tmp_path / "SOLFSMY.TXT", jb_dir / "DTCFILE.TXT")
    bad = tmp_path / "SOLFSMY.TXT"
    lines = (jb_dir / "SOLFSMY.TXT").read_text().splitlines()[:10]
    lines[7] = "  1997   4   2450453.0  72.x"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=r"SOLFSMY.TXT, line 8"):
        rp.density.Jb2008Indices(bad, jb_dir / "DTCFILE.TXT")
    dtc = tmp_path / "DTCFILE.TXT"
    dtc.write_text("DTC 1997   1   31  50\n")
    with pytest.raises(ValueError, match=r"DTCFILE.TXT, line 1"):
        rp.density.Jb2008Indices(jb_dir / "SOLFSMY.TXT", dtc)


def test_locate_env_cache_and_refresh(
    tmp_path: Path, jb_dir: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("RHOPROP_JB2008_DATA", str(jb_dir))
    found = rp.density.Jb2008Indices.locate()
    assert found is not None and found.solfsmy.parent == jb_dir
    monkeypatch.setenv("RHOPROP_JB2008_DATA", str(tmp_path))
    with pytest.raises(FileNotFoundError, match="RHOPROP_JB2008_DATA"):
        rp.density.Jb2008Indices.locate()
    monkeypatch.delenv("RHOPROP_JB2008_DATA")
    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path / "cache"))
    assert rp.density.Jb2008Indices.locate() is None
    with pytest.raises(FileNotFoundError, match="refresh"):
        rp.density.Jb2008()
    got = rp.density.Jb2008Indices.refresh(
        (jb_dir / "SOLFSMY.TXT").as_uri(), (jb_dir / "DTCFILE.TXT").as_uri()
    )
    assert got.solfsmy == tmp_path / "cache" / "jb2008" / "SOLFSMY.TXT"
    again = rp.density.Jb2008Indices.locate()
    assert again is not None and again.span == got.span
    assert not [p for p in os.listdir(tmp_path / "cache" / "jb2008") if p.endswith(".part")]


def test_bad_input_raises_naming_the_argument(indices: rp.density.Jb2008Indices) -> None:
    m = rp.density.Jb2008(indices)
    t = np.datetime64("2010-01-01T00:00")
    with pytest.raises(ValueError, match="alt"):
        m.mean_std(t, 0.0, 0.0, 80e3)
    with pytest.raises(ValueError, match="lat"):
        m.mean_std(t, 91.0, 0.0, 400e3)
    with pytest.raises(ValueError, match="lon"):
        m.mean_std(t, 0.0, np.nan, 400e3)
    geometry = np.array([[0.0, 0.0, 0.0, 0.0, 80.0]])
    with pytest.raises(ValueError, match="altitude"):
        _core.jb2008_core(np.array([55000.0]), geometry, np.full((1, 9), 100.0))
    with pytest.raises(ValueError, match="latitude"):
        _core.jb2008_geodetic(
            np.array([55000.0]),
            np.array([95.0]),
            np.zeros(1),
            np.array([4e5]),
            np.full((1, 9), 100.0),
        )


def test_sigma_grows_with_dtc_and_field_samples(indices: rp.density.Jb2008Indices) -> None:
    quiet = rp.density.Jb2008(indices, dtc=0.0, preset="paper")
    storm = rp.density.Jb2008(indices, dtc=300.0, preset="paper")
    t = np.datetime64("2003-10-29T12:00")
    mq, sq = quiet.mean_std(t, 0.0, 0.0, 400e3)
    ms, ss = storm.mean_std(t, 0.0, 0.0, 400e3)
    assert ms > 1.5 * mq
    assert sq / mq == pytest.approx(0.12) and ss / ms == pytest.approx(0.27)
    field = quiet.field("2003-10-29T00:00", "2003-10-29T06:00", altitude_range=(380e3, 420e3))
    assert np.isfinite(field.ln_mean).all()


def test_the_calibrated_sigma_follows_ap_where_dtc_lags_a_storm(indices) -> None:
    # 2003-10-29 01:30 UTC, the first hours of the Halloween storm: the 3-hourly ap is 39
    # (SW-All.txt's row, copied by hand: 39 27 400 207 179 179 300 300) while dTc is still
    # 94 K. The calibrated sigma grows with max(dTc, 5 K x ap): 195 K here, not 94.
    t = np.datetime64("2003-10-29T01:30")
    model = rp.density.Jb2008(indices)
    s = model.uncertainty
    assert s.ap_weight == 5.0
    assert indices.at(np.array([t], dtype="datetime64[ns]"))[0, 8] == 94.0
    mean, std = model.mean_std(t, 0.0, 0.0, 400e3)
    expected = s.quiet + (s.storm - s.quiet) * (5.0 * 39.0) / s.full_at
    assert std / mean == pytest.approx(expected, rel=1e-12)
    # Without the ap term the sigma is dTc's alone; the paper's preset reads no ap.
    dtc_only = rp.density.Jb2008(
        indices, rp.density.ActivitySigma(s.quiet, s.storm, s.full_at), correction=model.correction
    )
    m2, s2 = dtc_only.mean_std(t, 0.0, 0.0, 400e3)
    assert m2 == mean and s2 / m2 == pytest.approx(s.quiet + (s.storm - s.quiet) * 94.0 / s.full_at)
    assert rp.density.Jb2008(indices, preset="paper").space_weather is None
    with pytest.raises(ValueError, match="ap_weight is JB2008's"):
        rp.density.JacchiaRoberts(uncertainty=rp.density.ActivitySigma(0.1, 0.2, 5.0, 1.0))
    with pytest.raises(ValueError, match="ap_weight must be >= 0"):
        rp.density.ActivitySigma(0.1, 0.2, 150.0, -1.0)


def test_indices_as_of_an_epoch_read_nothing_after_it(indices, tmp_path: Path) -> None:
    # The forecast rules of SpaceWeather.as_of, applied to JB2008's own indices: rows of
    # the days before the epoch's day as observed, then the last observed day's F10, S10,
    # M10 and Y10 held, the centred 81-day means that reach past the epoch replaced by the
    # mean of the last 81 observed days, dTc relaxing from the epoch's hour to the last 27
    # days' typical level (e-folding 2 days). Checked from the raw files' numbers, and by
    # scrambling every value after the epoch, which must change nothing.
    epoch = np.datetime64("2009-05-18T07:19")
    ahead = indices.as_of(epoch)
    times = epoch + np.arange(-24, 24 * 10, 6) * np.timedelta64(1, "h")
    seen = ahead.at(times)
    before = times < np.datetime64("2009-05-18")  # lagged F10 rows: observed days only
    observed = indices.at(times)
    np.testing.assert_array_equal(seen[before, 0], observed[before, 0])
    # The raw file's row of 2009-05-17 (year, day of year 137) and the 80 before it.
    rows = {
        (int(f[0]), int(f[1])): [float(v) for v in f[3:11]]
        for f in (ln.split() for ln in indices.solfsmy.read_text().splitlines())
        if f and f[0].isdigit()
    }
    last = rows[(2009, 137)]
    window = np.array([rows[(2009, 137 - k)] for k in range(81)])
    later = times >= np.datetime64("2009-05-20")  # F10 lag 1, Y10 lag 5 within the forecast
    np.testing.assert_allclose(seen[later, 0], last[0])  # F10 held
    np.testing.assert_allclose(seen[later, 2], last[2])  # S10 held
    np.testing.assert_allclose(seen[later, 1], window[:, 0].mean())  # F10B: trailing mean
    np.testing.assert_allclose(seen[later, 3], window[:, 2].mean())  # S10B likewise
    # F10B of a day whose centred window reached past the epoch: no longer the file's.
    assert abs(seen[before, 1][-1] - observed[before, 1][-1]) > 0.01
    # dTc: the epoch's hour observed, then the relaxation.
    hour = np.datetime64("2009-05-18T07")
    dtc = indices.at(np.array([hour]))[0, 8]
    assert ahead.at(np.array([hour]))[0, 8] == dtc
    # ... relaxing towards the median of the 27 days' daily means (as ap's), read here
    # from the observed indices of the 27 * 24 hours up to the epoch's.
    past = hour - np.arange(27 * 24)[::-1] * np.timedelta64(1, "h")
    level = np.median(indices.at(past)[:, 8].reshape(27, 24).mean(axis=1))
    three = hour + np.timedelta64(72, "h")
    expected = level + (dtc - level) * np.exp(-72 / 48)  # 28.09 K; to the mean: 29.49
    assert ahead.at(np.array([three]))[0, 8] == np.round(expected)  # at() rounds dTc
    row_before = int((np.datetime64("2009-05-17") - indices._sol_first).astype(int))
    scrambled = rp.density.Jb2008Indices._from_arrays(
        indices,
        indices._sol_first,
        np.where(np.arange(len(indices._sol))[:, None] > row_before, 999.0, indices._sol),
        indices._dtc_first,
        np.where(
            np.arange(len(indices._dtc)) > int((hour - indices._dtc_first).astype(int)),
            777.0,
            indices._dtc,
        ),
        "scrambled",
    )
    np.testing.assert_array_equal(scrambled.as_of(epoch).at(times), seen)
    assert "as of 2009-05-18T07:19:00" in repr(ahead)
    with pytest.raises(rp.OutsideRecordError, match="81 observed days"):
        indices.as_of(indices._sol_first.astype("datetime64[ns]") + np.timedelta64(30, "D"))
    with pytest.raises(ValueError, match="days must be"):
        indices.as_of(epoch, days=0.0)
    # The other rules of SpaceWeather.as_of: to the 27 days' mean of the hours, or held.
    to_mean = indices.as_of(epoch, dtc_target="mean").at(np.array([three]))[0, 8]
    mean_level = indices.at(past)[:, 8].mean()
    assert to_mean == np.round(mean_level + (dtc - mean_level) * np.exp(-72 / 48))
    held = indices.as_of(epoch, dtc_relax_days=float("inf"))
    assert held.at(np.array([hour + np.timedelta64(24 * 9, "h")]))[0, 8] == dtc
    slow = indices.as_of(epoch, dtc_relax_days=6.0).at(np.array([three]))[0, 8]
    assert slow == np.round(level + (dtc - level) * np.exp(-72 / 144))
    with pytest.raises(ValueError, match="dtc_target must be one of"):
        indices.as_of(epoch, dtc_target="mode")
    with pytest.raises(ValueError, match="dtc_relax_days must lie"):
        indices.as_of(epoch, dtc_relax_days=-1.0)
    with pytest.raises(TypeError, match="dtc_relax_days must be a number of days"):
        indices.as_of(epoch, dtc_relax_days="2")


def test_indices_as_of_with_the_27_day_recurrence(indices) -> None:
    # recurrence=True, from the raw file's rows: F10 of forecast day 2009-05-20 (3 days
    # after the last observed, 05-17) is 05-17's times (F10 of 04-23 / F10 of 04-20) ** w(3)
    # (F10.7's weight, 0.16 at 3 days); dTc relaxes to the 27 days' typical
    # level moved 0.4 of the way towards the mean of the days 27 +- 1 before the hour's.
    from rhoprop.spaceweather.record import AP_RECURRENCE_WEIGHT, F107_RECURRENCE_WEIGHT

    epoch = np.datetime64("2009-05-18T07:19")
    ahead = indices.as_of(epoch, recurrence=True)
    rows = {
        (int(f[0]), int(f[1])): [float(v) for v in f[3:11]]
        for f in (ln.split() for ln in indices.solfsmy.read_text().splitlines())
        if f and f[0].isdigit()
    }
    weight = dict(F107_RECURRENCE_WEIGHT)[3.0]
    expected = rows[(2009, 137)][0] * (rows[(2009, 113)][0] / rows[(2009, 110)][0]) ** weight
    f10 = ahead.at(np.array([np.datetime64("2009-05-21T12:00")]))[0, 0]  # F10 lags a day
    assert f10 == pytest.approx(expected, rel=1e-12)
    assert (
        indices.as_of(epoch).at(np.array([np.datetime64("2009-05-21T12:00")]))[0, 0]
        == (rows[(2009, 137)][0])
    )
    hour = np.datetime64("2009-05-18T07")
    dtc = indices.at(np.array([hour]))[0, 8]
    past = hour - np.arange(27 * 24)[::-1] * np.timedelta64(1, "h")
    typical = np.median(indices.at(past)[:, 8].reshape(27, 24).mean(axis=1))
    back = np.datetime64("2009-04-23T00") + np.arange(72) * np.timedelta64(1, "h")
    level = typical + AP_RECURRENCE_WEIGHT * (indices.at(back)[:, 8].mean() - typical)
    three = hour + np.timedelta64(72, "h")
    want = np.round(level + (dtc - level) * np.exp(-72 / 48))
    assert ahead.at(np.array([three]))[0, 8] == want
    assert want != indices.as_of(epoch).at(np.array([three]))[0, 8]  # 29 K against 28 K
    with pytest.raises(TypeError, match="recurrence must be a bool"):
        indices.as_of(epoch, recurrence=1)
    # dTc files that start later than the solar ones: 27 days of dTc are enough without
    # the recurrence, which needs the 28 days before the epoch's day.
    late = indices._dtc_first + np.timedelta64(60 * 24, "h")
    later = rp.density.Jb2008Indices._from_arrays(
        indices, indices._sol_first, indices._sol, late, indices._dtc[60 * 24 :], "late dTc"
    )
    when = late + np.timedelta64(27 * 24 + 5, "h")
    later.as_of(when)
    with pytest.raises(rp.OutsideRecordError, match="recurrence needs the 28 days of dTc"):
        later.as_of(when, recurrence=True)
