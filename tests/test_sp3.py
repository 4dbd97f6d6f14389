"""``rp.io.read_sp3`` on real precise orbits: the records as printed in the files, and
the epochs on the UTC scale as astropy converts the files' GPS and TAI time."""

from __future__ import annotations

import gzip

import numpy as np
import pytest

import rhoprop as rp

astropy_time = pytest.importorskip("astropy.time")


def _utc(text: str, scale: str) -> np.datetime64:
    """astropy: an instant on ``scale`` ("gps": TAI - 19 s, so TAI = GPS + 19 s) as UTC."""
    if scale == "gps":
        t = astropy_time.Time(text, scale="tai") + astropy_time.TimeDelta(19.0, format="sec")
    else:
        t = astropy_time.Time(text, scale=scale)
    return np.datetime64(t.utc.isot, "ns")


def test_a_multi_gnss_file_in_gps_time(test_data):
    path = test_data / "precise_orbits/gnss/GBM0MGXRAP_20241680000_01D_05M_ORB_SP3.gz"
    sp3 = rp.io.read_sp3(path)
    assert (sp3.time_system, sp3.frame) == ("GPS", "IGS20")
    assert len(sp3.epochs) == 288  # 5 min over the day, as the header says
    # GPS = TAI - 19 s and TAI - UTC = 37 s in 2024: UTC = GPS - 18 s (astropy agrees).
    assert sp3.epochs[0] == _utc("2024-06-16T00:00:00", "gps")
    assert sp3.epochs[0] == np.datetime64("2024-06-15T23:59:42", "ns")
    # The first record of C01, km in the file.
    np.testing.assert_array_equal(
        sp3.positions["C01"][0], np.array([-34301.309016, 24527.616770, -587.805360]) * 1e3
    )
    assert {"G01", "E02", "R01", "C59", "J07"} <= set(sp3.positions)
    # A satellite missing at some epoch has NaN there, not 0 or 999999.
    lines = gzip.decompress(path.read_bytes()).decode().splitlines()
    zeros = [ln[1:4] for ln in lines if ln.startswith("P") and float(ln[4:18]) == 0.0]
    for sat in set(zeros) & set(sp3.positions):
        assert np.isnan(sp3.positions[sat]).any()


def test_a_doris_file_in_tai(test_data):
    sp3 = rp.io.read_sp3(test_data / "precise_orbits/leo/ssaja102.b03007.e03017.DGS.sp3.gz")
    assert (sp3.time_system, sp3.frame, list(sp3.positions)) == ("TAI", "ITRF", ["L08"])
    # TAI - UTC = 32 s in 2003.
    assert sp3.epochs[0] == np.datetime64("2003-01-07T04:13:28", "ns")
    assert sp3.epochs[0] == _utc("2003-01-07T04:14:00", "tai")
    assert np.all(np.diff(sp3.epochs) == np.timedelta64(60, "s"))
    radius = np.linalg.norm(sp3.positions["L08"], axis=1)
    assert np.all((7_650e3 < radius) & (radius < 7_780e3))  # Jason-1 at 1,336 km


def test_what_is_not_sp3_is_refused(tmp_path):
    bad = tmp_path / "x.sp3"
    bad.write_text("hello\n")
    with pytest.raises(ValueError, match="not an SP3 file"):
        rp.io.read_sp3(bad)
    odd = tmp_path / "y.sp3"
    odd.write_text(
        "#dP2024  6 16  0  0  0.00000000       1 ORBIT IGS20 FIT  GFZ\n"
        "%c M  cc GLO ccc\n*  2024  6 16  0  0  0.00000000\n"
    )
    with pytest.raises(ValueError, match="time system 'GLO' is not supported"):
        rp.io.read_sp3(odd)
