"""Time: elapsed SI seconds across leap seconds, J2000 in TT,
the core's UT1 argument unchanged, astropy Time and Julian dates, zone offsets, 23:59:60,
and epochs that numpy cannot hold."""

from __future__ import annotations

import datetime as dt
import subprocess
import sys

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import time as rt

#: The UTC days ending in a positive leap second, from IERS Bulletin C (hand-copied from
#: https://hpiers.obspm.fr/iers/bul/bulc/Leap_Second.dat); TAI - UTC was 10 s on
#: 1972-01-01 and grew by 1 s after each.
LEAP_DAYS = [
    "1972-06-30", "1972-12-31", "1973-12-31", "1974-12-31", "1975-12-31", "1976-12-31",
    "1977-12-31", "1978-12-31", "1979-12-31", "1981-06-30", "1982-06-30", "1983-06-30",
    "1985-06-30", "1987-12-31", "1989-12-31", "1990-12-31", "1992-06-30", "1993-06-30",
    "1994-06-30", "1995-12-31", "1997-06-30", "1998-12-31", "2005-12-31", "2008-12-31",
    "2012-06-30", "2015-06-30", "2016-12-31",
]  # fmt: skip


def ns(text: str) -> np.datetime64:
    return np.datetime64(text, "ns")


# -- elapsed time across leap seconds ----------------------------------------------------


def test_the_issue_example_counts_the_leap_second():
    # 86401 SI seconds elapse from noon to noon across 2016-12-31T23:59:60 (was 86400).
    assert rt.seconds_between("2016-12-31T12:00", "2017-01-01T12:00") == 86401.0
    assert rt.seconds_between("2017-01-01T12:00", "2016-12-31T12:00") == -86401.0
    assert rt.seconds_between("2017-01-02T12:00", "2017-01-03T12:00") == 86400.0


@pytest.mark.parametrize("day", LEAP_DAYS)
def test_every_bulletin_c_leap_second(day):
    start = ns(day) + np.timedelta64(12, "h")
    end = start + np.timedelta64(1, "D")
    assert rt.seconds_between(start, end) == 86401.0
    assert rt.is_leap_second_day(day)
    k = LEAP_DAYS.index(day)
    assert rt.tai_minus_utc(start) == 10.0 + k
    assert rt.tai_minus_utc(end) == 11.0 + k
    # The day before has none.
    assert not rt.is_leap_second_day(ns(day) - np.timedelta64(1, "D"))


def test_no_other_leap_days_from_1972_to_2030():
    days = np.arange(np.datetime64("1972-01-01"), np.datetime64("2030-01-01"))
    midnights = (days + 1).astype("datetime64[ns]")
    step = rt.tai_minus_utc(midnights) - rt.tai_minus_utc(midnights - np.timedelta64(1, "ns"))
    found = [str(d) for d in days[step > 0.5]]
    assert found == LEAP_DAYS


def test_elapsed_seconds_match_astropy():
    time = pytest.importorskip("astropy.time")
    # Avoid leap-second days: astropy's UTC Julian dates stretch them, ours do not.
    epochs = np.array(
        [
            "1961-03-01T00:00",
            "1965-07-04T06:00:00.25",
            "1971-12-31T23:00",
            "1972-01-01T01:00",
            "1999-12-31T00:00",
            "2002-09-07T01:00",
            "2017-01-01T00:00:00",
            "2024-02-29T13:14:15.123456",
        ],
        dtype="datetime64[ns]",
    )
    t = time.Time(epochs, scale="utc")
    ours = rt.to_seconds(epochs, epochs[0])
    theirs = (t - t[0]).sec
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=2e-6)
    # TT - UTC - 32.184 = TAI - UTC
    tt_minus_utc = (t.tt.jd1 - t.jd1 + t.tt.jd2 - t.jd2) * 86400.0
    # (Not on 1971-12-31: astropy stretches the UTC Julian day before a step of UTC.)
    keep = np.arange(len(epochs)) != 2
    np.testing.assert_allclose(
        rt.tai_minus_utc(epochs[keep]) + 32.184, tt_minus_utc[keep], rtol=0, atol=2e-5
    )


def test_round_trips_across_leap_seconds():
    base = ns("2016-12-31T06:00")
    epochs = base + np.array([0, 3, 17.99, 18.5, 19, 30], dtype=float).__mul__(3600e9).astype(
        "timedelta64[ns]"
    )
    seconds = rt.to_seconds(epochs, base)
    # After the leap second every offset is 1 s longer than the calendar says.
    calendar = (epochs - base) / np.timedelta64(1, "s")
    np.testing.assert_array_equal(seconds - calendar, [0, 0, 0, 1, 1, 1])
    np.testing.assert_array_equal(rt.offsets_to_epochs(base, seconds), epochs)
    back = rt.to_seconds(rt.offsets_to_epochs(base, seconds), base)
    np.testing.assert_array_equal(back, seconds)
    assert rt.add_seconds(base, 30 * 3600.0 + 1.0) == epochs[-1]
    assert rt.add_seconds("2016-12-31T12:00", 86401.0) == ns("2017-01-01T12:00")
    # Backwards too, and through several leap seconds (2005-06 to 2017-06: five).
    assert rt.add_seconds("2017-01-01T12:00", -86401.0) == ns("2016-12-31T12:00")
    span = rt.seconds_between("2005-06-01", "2017-06-01")
    assert span == (ns("2017-06-01") - ns("2005-06-01")) / np.timedelta64(1, "s") + 5
    assert rt.add_seconds("2005-06-01", span) == ns("2017-06-01")


def test_an_offset_inside_the_leap_second_gives_its_end():
    out = rt.offsets_to_epochs("2016-12-31T23:59:59", [0.0, 0.5, 1.0, 1.5, 2.0, 3.0])
    expected = ["2016-12-31T23:59:59", "2016-12-31T23:59:59.5", *["2017-01-01T00:00:00"] * 3]
    np.testing.assert_array_equal(out, np.array([*expected, "2017-01-01T00:00:01"], "M8[ns]"))


def test_offsets_keep_shape_and_reject_bad_seconds():
    out = rt.offsets_to_epochs("2002-09-07", np.zeros((2, 3)))
    assert out.shape == (2, 3) and out.dtype == np.dtype("M8[ns]")
    with pytest.raises(ValueError, match="finite"):
        rt.offsets_to_epochs("2002-09-07", [np.nan])
    with pytest.raises(ValueError, match="1678-2261"):
        rt.offsets_to_epochs("2002-09-07", [1e11])
    with pytest.raises(ValueError, match="1678-2261"):
        rt.add_seconds("2261-12-31", 2 * 86400.0)


# -- J2000 (TT) and the core's UT1 -------------------------------------------------------


def test_j2000_is_noon_tt():
    assert rt.seconds_since_j2000("2000-01-01T11:58:55.816") == 0.0
    assert rt.seconds_since_j2000("2000-01-01T12:00:00") == pytest.approx(64.184, abs=1e-9)
    assert rt.seconds_since_j2000("2000-01-02T12:00:00.5") == pytest.approx(86464.684, abs=1e-9)
    assert rp.seconds_since_j2000 is rt.seconds_since_j2000


def test_j2000_against_astropy():
    time = pytest.importorskip("astropy.time")
    j2000 = time.Time("J2000")  # 2000-01-01T12:00:00 TT
    for epoch in ("2002-09-07T01:00:00", "2017-01-01T00:00:00", "1980-01-06T00:00:00"):
        expected = (time.Time(epoch, scale="utc") - j2000).sec
        assert rt.seconds_since_j2000(epoch) == pytest.approx(expected, abs=1e-6)


def test_ut1_seconds_keep_the_cores_time_argument():
    # UTC seconds since 2000-01-01T12:00 UTC, 86400 per day, exactly as before.
    assert rt.ut1_seconds("2000-01-01T12:00:00") == 0.0
    assert rt.ut1_seconds("2000-01-02T12:00:00.5") == 86400.5
    epochs = np.array(["2016-12-31T12:00", "2017-01-01T12:00"], dtype="M8[ns]")
    np.testing.assert_array_equal(np.diff(rt.ut1_seconds(epochs)), [86400.0])
    legacy = (epochs - np.datetime64("2000-01-01T12:00", "ns")).astype(np.int64) * 1e-9
    np.testing.assert_array_equal(rt.ut1_seconds(epochs), legacy)
    assert isinstance(rt.ut1_seconds(np.datetime64("2002-09-07")), float)
    # The core's time for a run from an origin: + elapsed SI seconds (1 s more after a leap).
    np.testing.assert_array_equal(
        rt.core_times(epochs, "2016-12-31T00:00") - rt.ut1_seconds(epochs), [0.0, 1.0]
    )
    later = epochs + np.timedelta64(1, "D")  # no leap second between these two
    np.testing.assert_array_equal(rt.core_times(later, later[0]), rt.ut1_seconds(later))


def test_gmst_still_matches_vallado():
    # Vallado, Fundamentals of Astrodynamics (4th ed.), Example 3-5: 1992-08-20 12:14 UT1
    # -> GMST 152.578787810 deg (UT1 = UTC).
    g = np.degrees(rp.frames.gmst("1992-08-20T12:14:00"))
    assert g == pytest.approx(152.578787810, abs=1e-6)


# -- accepted forms --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("2002-09-07T03:00:00+02:00", "2002-09-07T01:00:00"),
        ("2002-09-07T03:00:00+0200", "2002-09-07T01:00:00"),
        ("2002-09-07T03:00+02", "2002-09-07T01:00:00"),
        ("2002-09-06T19:30:00.25-05:30", "2002-09-07T01:00:00.25"),
        ("2002-09-07T01:00:00Z", "2002-09-07T01:00:00"),
        ("2002-09-07 01:00z", "2002-09-07T01:00:00"),
        ("  2002-09-07T01:00:00+00:00 ", "2002-09-07T01:00:00"),
        ("2002-09-07", "2002-09-07T00:00:00"),
    ],
)
def test_zone_offsets_convert_without_warnings(text, expected):
    # pytest turns warnings into errors: numpy's "no explicit representation of
    # timezones" warning would fail here.
    assert rt.to_datetime64(text) == ns(expected)


def test_pandas_timestamps_keep_nanoseconds():
    pd = pytest.importorskip("pandas")
    assert rt.to_datetime64(pd.Timestamp("2002-09-07T01:00:00.123456789")) == ns(
        "2002-09-07T01:00:00.123456789"
    )
    berlin = pd.Timestamp("2002-09-07T03:00", tz="Europe/Berlin")  # CEST, UTC+2
    assert rt.to_datetime64(berlin) == ns("2002-09-07T01:00")
    with pytest.raises(ValueError, match="epoch is NaT"):
        rt.to_datetime64(pd.NaT)


def test_aware_datetimes_and_dates():
    zone = dt.timezone(dt.timedelta(hours=-3))
    assert rt.to_datetime64(dt.datetime(2002, 9, 6, 22, tzinfo=zone)) == ns("2002-09-07T01:00")
    assert rt.to_datetime64(dt.date(2002, 9, 7)) == ns("2002-09-07")
    assert rt.to_datetime64(np.datetime64("2002-09-07T01:00", "m")) == ns("2002-09-07T01:00")


@pytest.mark.parametrize(
    "text",
    [
        "2016-12-31T23:59:60",
        "2016-12-31T23:59:60Z",
        "2016-12-31T23:59:60.75",
        "2017-01-01T00:59:60+01:00",
    ],
)
def test_leap_second_strings(text):
    # datetime64 has no second 60: the leap second stands for its end, the next midnight.
    assert rt.to_datetime64(text) == ns("2017-01-01T00:00:00")


def test_leap_second_elsewhere_is_an_error():
    with pytest.raises(ValueError, match="2015-12-31 has no leap second"):
        rt.to_datetime64("2015-12-31T23:59:60")
    with pytest.raises(ValueError, match="second 60 exists only"):
        rt.to_datetime64("2016-12-31T12:00:60")
    # 2015-06-30 had one: accepted.
    assert rt.to_datetime64("2015-06-30T23:59:60") == ns("2015-07-01")


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ("", "start is an empty string"),
        ("   ", "start is an empty string"),
        ("NaT", "start is 'NaT'"),
        ("nat", "start is 'NaT'"),
        (np.datetime64("NaT"), "start is NaT"),
        ("2500-01-01", "start = 2500-01-01 is out of range.*1678-2261"),
        ("1677-12-31T23:00", "start = 1677-12-31T23:00:00 is out of range"),
        (np.datetime64("2500-01-01"), "start = 2500-01-01 is out of range"),
        (np.datetime64(10**6, "Y"), "out of range"),
        (dt.datetime(1, 1, 1), "start = 0001-01-01T00:00:00 is out of range"),
        (dt.date(9999, 1, 1), "out of range"),
        ("yesterday", "start 'yesterday' is not an ISO-8601 UTC time"),
        ("2002-13-01", "not an ISO-8601 UTC time"),
        ("2002-09-07T01:00+25:00", "invalid UTC offset"),
    ],
)
def test_bad_epochs_raise_naming_the_argument(value, match):
    with pytest.raises(ValueError, match=match):
        rt.to_datetime64(value, "start")


def test_out_of_range_epoch_no_longer_wraps():
    # '2500-01-01' used to become 1915-06-14 silently.
    with pytest.raises(ValueError, match="epoch = 2500-01-01 is out of range"):
        rp.OrbitState("2500-01-01", [7e6, 0, 0], [0, 7.5e3, 0])
    for text in ("", "NaT"):
        with pytest.raises(ValueError, match="epoch"):
            rp.OrbitState(text, [7e6, 0, 0], [0, 7.5e3, 0])


def test_numbers_are_not_epochs():
    with pytest.raises(TypeError, match="from_jd"):
        rt.to_datetime64(2451545.0)
    with pytest.raises(TypeError, match="from_jd"):
        rt.to_datetime64_array(np.array([2451545.0]))
    with pytest.raises(TypeError, match="epoch must be an ISO string"):
        rt.to_datetime64(None)  # type: ignore[arg-type]


def test_arrays_name_the_bad_element():
    out = rt.to_datetime64_array([["2002-09-07", "2002-09-08T00:00+01:00"]])
    assert out.shape == (1, 2) and out[0, 1] == ns("2002-09-07T23:00")
    with pytest.raises(ValueError, match=r"times\[1\] is an empty string"):
        rt.to_datetime64_array(["2002-09-07", ""], "times")
    with pytest.raises(ValueError, match=r"times is NaT .* at index 1"):
        rt.to_datetime64_array(np.array(["2002-09-07", "NaT"], "M8[s]"), "times")
    with pytest.raises(ValueError, match=r"times\[1\] = 2500-01-01 is out of range"):
        rt.to_datetime64_array(np.array(["2002-09-07", "2500-01-01"], "M8[D]"), "times")


# -- astropy Time and Julian dates -------------------------------------------------------


def test_astropy_time_any_scale():
    time = pytest.importorskip("astropy.time")
    expected = ns("2002-09-07T01:00:00")
    assert rt.to_datetime64(time.Time("2002-09-07T01:00:00", scale="utc")) == expected
    # TT - UTC = 32.184 + 32 s in 2002.
    tt = time.Time("2002-09-07T01:01:04.184", scale="tt")
    assert rt.to_datetime64(tt) == expected
    tai = time.Time("2002-09-07T01:00:32", scale="tai")
    assert rt.to_datetime64(tai) == expected
    tdb = time.Time("2002-09-07T01:01:04.184", scale="tdb")  # TDB - TT < 2 ms
    assert abs((rt.to_datetime64(tdb) - expected) / np.timedelta64(1, "ms")) < 2
    # A leap second, like the strings.
    leap = time.Time("2016-12-31T23:59:60.5", scale="utc")
    assert rt.to_datetime64(leap) == ns("2017-01-01T00:00:00")
    # Arrays wherever several epochs go, e.g. a state's epoch, frames and density models.
    many = time.Time(["2002-09-07T01:00", "2009-12-02T00:00"], scale="utc")
    np.testing.assert_array_equal(
        rt.to_datetime64_array(many), np.array(["2002-09-07T01:00", "2009-12-02"], "M8[ns]")
    )
    np.testing.assert_array_equal(
        rp.frames.gmst(many), rp.frames.gmst(np.array(["2002-09-07T01:00", "2009-12-02"], "M8[ns]"))
    )
    state = rp.OrbitState(time.Time("2002-09-07T01:00", scale="utc"), [7e6, 0, 0], [0, 7.5e3, 0])
    assert state.epoch == expected
    with pytest.raises(ValueError, match="must be one epoch"):
        rt.to_datetime64(many)


def test_rhoprop_does_not_import_astropy():
    code = (
        "import sys, rhoprop as rp; "
        "rp.OrbitState('2002-09-07T01:00+02:00', [7e6, 0, 0], [0, 7.5e3, 0]); "
        "rp.time.seconds_between('2016-12-31', '2017-01-01'); "
        "print('astropy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_from_jd():
    assert rt.from_jd(2451545.0) == ns("2000-01-01T12:00")
    assert rt.from_jd(2451545.0, scale="tt") == ns("2000-01-01T11:58:55.816")
    assert rt.from_jd(2451545.0, scale="tai") == ns("2000-01-01T11:59:28")
    # Modified Julian dates, two-part for precision; arrays keep their shape.
    out = rt.from_jd(2400000.5, np.array([[52524.0416666666667, 57754.0]]))
    assert out.shape == (1, 2)
    assert abs(out[0, 0] - ns("2002-09-07T01:00")) < np.timedelta64(1, "us")
    assert out[0, 1] == ns("2017-01-01")
    with pytest.raises(ValueError, match="scale must be one of"):
        rt.from_jd(2451545.0, scale="tdb")
    with pytest.raises(ValueError, match="jd must be finite"):
        rt.from_jd(np.nan)
    with pytest.raises(TypeError, match="jd must be a number"):
        rt.from_jd("2451545")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="out of range"):
        rt.from_jd(2451545.0 + 400 * 365.25)


def test_from_jd_against_astropy_and_sgp4():
    time = pytest.importorskip("astropy.time")
    for scale in ("tt", "tai"):
        jd = 2458000.123456789
        expected = rt.to_datetime64(time.Time(jd, format="jd", scale=scale))
        assert abs(rt.from_jd(jd, scale=scale) - expected) < np.timedelta64(1, "us")
    # A TLE epoch: sgp4's JD counts 86400-s UTC days, and so does scale="utc".
    from sgp4.api import Satrec
    from sgp4.conveniences import sat_epoch_datetime

    sat = Satrec.twoline2rv(
        "1 25544U 98067A   08264.51782528 -.00002182  00000-0 -11606-4 0  2927",
        "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537",
    )
    epoch = rt.from_jd(sat.jdsatepoch, sat.jdsatepochF)
    # (sat_epoch_datetime rounds to whole microseconds.)
    assert abs(epoch - rt.to_datetime64(sat_epoch_datetime(sat))) <= np.timedelta64(1, "us")


def test_astropy_formats_and_scales_match_astropys_own_utc():
    time = pytest.importorskip("astropy.time")
    rng = np.random.default_rng(17)
    mjd = rng.uniform(41317.0, 62000.0, 500)  # 1972 .. 2028
    for scale in ("utc", "tai", "tt", "tcg", "tcb", "tdb"):
        t = time.Time(mjd, format="mjd", scale=scale)
        np.testing.assert_array_equal(rt.to_datetime64_array(t), t.utc.datetime64, err_msg=scale)
    for fmt, values in (
        ("gps", rng.uniform(0.0, 1.3e9, 50)),  # TAI seconds since 1980-01-06
        ("unix", rng.uniform(0.0, 1.8e9, 50)),
        ("cxcsec", rng.uniform(0.0, 6e8, 50)),  # TT seconds since 1998
        ("decimalyear", rng.uniform(1975.0, 2020.0, 50)),
        ("jd", rng.uniform(2441317.5, 2462000.5, 50)),
    ):
        t = time.Time(values, format=fmt)
        np.testing.assert_array_equal(rt.to_datetime64_array(t), t.utc.datetime64, err_msg=fmt)
    # UT1 from the IERS tables astropy ships (offline), 2-D shapes kept.
    ut1 = time.Time("2002-09-07T01:00:00", scale="ut1")
    assert rt.to_datetime64(ut1) == ut1.utc.datetime64
    grid = time.Time([["2002-09-07T01:00", "2003-01-01"], ["2004-02-29T12:00", "2017-01-01"]])
    out = rt.to_datetime64_array(grid)
    assert out.shape == (2, 2)
    np.testing.assert_array_equal(out, grid.datetime64)
    # A scale that has no UTC is a ValueError naming the argument.
    with pytest.raises(ValueError, match="start: an astropy Time of scale 'local'"):
        rt.to_datetime64(time.Time(51544.5, format="mjd", scale="local"), "start")


def test_astropy_time_goes_wherever_an_epoch_does():
    time = pytest.importorskip("astropy.time")
    tt = time.Time("2002-09-07T01:01:04.184", scale="tt")  # 01:00:00 UTC
    state = rp.OrbitState(tt, [7e6, 0, 0], [0, 7.5e3, 0])
    assert state.epoch == ns("2002-09-07T01:00:00")
    end = time.Time(2452525.5, format="jd", scale="tai")  # 2002-09-08T00:00:00 TAI
    assert rt.seconds_between(tt, end) == pytest.approx(23 * 3600.0 - 32.0, abs=1e-6)


def test_from_jd_against_pyerfa():
    erfa = pytest.importorskip("erfa")
    rng = np.random.default_rng(3)
    whole = np.floor(rng.uniform(2441317.5, 2462000.5, 400)) + 0.5  # midnights, 1972..2028
    frac = rng.uniform(0.0, 1.0, 400)

    def calendar(scale, d1, d2):
        iy, im, iday, hmsf = erfa.d2dtf(scale, 9, d1, d2)
        return np.array(
            [
                np.datetime64(f"{y:04d}-{m:02d}-{d:02d}", "ns")
                + np.timedelta64(int(h[0]) * 3600 + int(h[1]) * 60 + int(h[2]), "s")
                + np.timedelta64(int(h[3]), "ns")
                for y, m, d, h in zip(iy, im, iday, hmsf, strict=True)
            ]
        )

    # TT and TAI Julian dates: ERFA's own chain TT -> TAI -> UTC, to the nanosecond (its
    # stretched UTC quasi-JD and calendar agree with each other on leap-second days too).
    # Some dates just before a leap second (TAI - UTC steps there) are added.
    steps = np.array([2457754.5, 2457204.5, 2454832.5]) - 1.0  # days before 2017/2015/2009
    whole_tt, frac_tt = np.concatenate([whole, steps]), np.concatenate([frac, [0.9999] * 3])
    utc1, utc2 = erfa.taiutc(*erfa.tttai(whole_tt, frac_tt))
    got = rt.from_jd(whole_tt, frac_tt, scale="tt")
    assert np.abs((got - calendar("UTC", utc1, utc2)) / np.timedelta64(1, "ns")).max() <= 2
    utc1, utc2 = erfa.taiutc(whole, frac)
    got = rt.from_jd(whole, frac, scale="tai")
    assert np.abs((got - calendar("UTC", utc1, utc2)) / np.timedelta64(1, "ns")).max() <= 2
    # UTC Julian dates: 86400-s days, as ERFA's on every day without a leap second.
    days = np.array([rt.is_leap_second_day(d) for d in rt.from_jd(whole)])
    got = rt.from_jd(whole[~days], frac[~days])
    expected = calendar("UTC", whole[~days], frac[~days])
    assert np.abs((got - expected) / np.timedelta64(1, "ns")).max() <= 2  # ns: rounding


# -- through the package ---------------------------------------------------------------


def test_propagation_counts_the_leap_second():
    # 86401 s from noon to noon across 2016-12-31T23:59:60: the trajectory's last epoch is
    # the next noon (it was 1 s later, ~7.5 km along-track).
    state = rp.scenarios.paper_state("2016-12-31T12:00")
    craft = rp.scenarios.paper_spacecraft()
    model = rp.scenarios.benchmark_exponential()
    tr = rp.propagate(state, craft, model, 86401.0, output_step=43200.0)
    np.testing.assert_array_equal(
        tr.epochs,
        np.array(
            ["2016-12-31T12:00", "2017-01-01T00:00", "2017-01-01T11:59:59", "2017-01-01T12:00"],
            "M8[ns]",
        ),
    )


def test_sampled_field_across_a_leap_second():
    # Nodes after the leap second sit at elapsed SI seconds from the field epoch, and a
    # lookup at a node's UTC epoch finds exactly the value sampled there.
    def fn(t, lat, lon, alt):
        hours = (t - np.datetime64("2016-12-31", "ns")) / np.timedelta64(1, "h")
        mean = 1e-12 * np.exp(-(alt - 4e5) / 6e4) * (1 + 0.05 * hours)
        return mean, 0.1 * mean

    model = rp.density.FromFunction(fn)
    res = rp.density.FieldResolution(time=3600.0, altitude=50e3, latitude=30.0, longitude=60.0)
    field = model.field(
        "2016-12-31T22:00", "2017-01-01T02:00", altitude_range=(350e3, 450e3), resolution=res
    )
    assert field.times[-1] == 4 * 3600.0 + 1.0
    assert field.end == ns("2017-01-01T02:00")
    nodes = rt.offsets_to_epochs(field.epoch, field.times)
    assert nodes[3] == ns("2017-01-01T00:23:59.6")  # 8640.6 s after 22:00, one a leap second
    grid, _ = field.mean_std(nodes, 0.0, 0.0, 400e3)
    direct, _ = fn(nodes, 0.0, 0.0, 400e3)
    np.testing.assert_allclose(grid, direct, rtol=1e-12, atol=0)


@pytest.mark.parametrize(
    ("text", "expect"),
    [
        # 10-18 fractional digits round to whole ns (they once wrapped: 1969-12-12T19:38:51.87).
        ("2002-09-07T01:00:00.0000000004Z", "2002-09-07T01:00:00.000000000"),
        ("2002-09-07T01:00:00.123456789012345678Z", "2002-09-07T01:00:00.123456789"),
        ("2002-09-07T01:00:00.0000000005Z", "2002-09-07T01:00:00.000000001"),
        ("2002-09-07T23:59:59.9999999996Z", "2002-09-08T00:00:00.000000000"),
        ("2002-09-07T01:00:00.25000000000+01:00", "2002-09-07T00:00:00.250000000"),
    ],
)
def test_epoch_strings_with_10_to_18_fractional_digits_round_to_the_nanosecond(text, expect):
    assert rp.time.to_datetime64(text) == np.datetime64(expect, "ns")
    state = rp.OrbitState(text, [7e6, 0.0, 0.0], [0.0, 7.5e3, 0.0])
    assert state.epoch == np.datetime64(expect, "ns")


def test_a_skyfield_time_is_an_epoch():
    # skyfield's Time (its UTC fields, leap seconds as 23:59:60) is accepted like
    # astropy's; it was refused with "got Time".
    skyfield = pytest.importorskip("skyfield.api")
    ts = skyfield.load.timescale(builtin=True)
    assert rp.time.to_datetime64(ts.utc(2026, 3, 15, 6, 30, 12.25)) == np.datetime64(
        "2026-03-15T06:30:12.250"
    )
    many = rp.time.to_datetime64_array(ts.utc(2026, 3, 15, 6, [0, 30]))
    np.testing.assert_array_equal(
        many, np.array(["2026-03-15T06:00", "2026-03-15T06:30"], dtype="datetime64[ns]")
    )
    # 2016-12-31T23:59:60.5, inside the leap second: its end, as rhoprop's strings.
    leap = rp.time.to_datetime64(ts.utc(2016, 12, 31, 23, 59, 60.5))
    assert leap == rp.time.to_datetime64("2016-12-31T23:59:60.5Z")
    with pytest.raises(ValueError, match="skyfield Time of shape"):
        rp.time.to_datetime64(ts.utc(2026, 3, 15, 6, [0, 30]))
