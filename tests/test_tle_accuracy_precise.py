"""The TLE accuracy rhoprop assumes at 800-2000 km against real precise orbits: SGP4 of
Jason-1's (2003) and TOPEX/Poseidon's (1997) element sets against their DORIS orbits
around each element set's epoch (docs/catalog-realism.md, "The covariance against
precise orbits"). The DORIS orbits are Earth-fixed; astropy rotates them to GCRS, SGP4's
TEME states go through ``rp.frames.teme_to_gcrf``."""

from __future__ import annotations

import numpy as np
import pytest
from sgp4.api import Satrec

import rhoprop as rp
from rhoprop import catalog
from rhoprop.frames import rtn_basis

astropy_coordinates = pytest.importorskip("astropy.coordinates")

LEO = "precise_orbits/leo"
SATELLITES = {  # NORAD id, DORIS orbit file
    "Jason-1": (26997, "ssaja102.b03007.e03017.DGS.sp3.gz"),
    "TOPEX/Poseidon": (22076, "grgtop03.b97344.e97348.D_S.sp3.gz"),
}
#: Samples within 3 h (one and a half revolutions) of each epoch, every 5 min.
HALF, EVERY = 180, 5


def _gcrs(utc: np.ndarray, itrs_m: np.ndarray) -> np.ndarray:
    """Earth-fixed positions (m) at UTC instants, rotated to GCRS by astropy (its bundled
    IERS-B table, no download)."""
    from astropy import units as u
    from astropy.time import Time
    from astropy.utils import iers

    iers.conf.auto_download = False
    t = Time([str(x) for x in utc], scale="utc")
    itrs = astropy_coordinates.ITRS(
        astropy_coordinates.CartesianRepresentation(itrs_m.T * u.m), obstime=t
    )
    gcrs = itrs.transform_to(astropy_coordinates.GCRS(obstime=t))
    return np.asarray(gcrs.cartesian.xyz.to(u.m).value).T


def _errors(test_data, norad: int, file: str) -> tuple[np.ndarray, np.ndarray, list[float]]:
    """SGP4's RTN position errors (m) at the DORIS epochs within 3 h of each element set's
    epoch, the RTN sigmas ``tle_accuracy`` assumes there, and each epoch's argument of
    latitude (deg)."""
    sp3 = rp.io.read_sp3(test_data / LEO / file)
    truth = next(iter(sp3.positions.values()))
    lines = (test_data / LEO / "tles_jason1_topex.txt").read_text().splitlines()
    errors, sigmas, latitudes = [], [], []
    for l1, l2 in zip(lines[0::2], lines[1::2], strict=True):
        sat = Satrec.twoline2rv(l1, l2)
        if sat.satnum != norad:
            continue
        epoch = rp.time.from_jd(sat.jdsatepoch, sat.jdsatepochF)
        near = np.flatnonzero(np.abs(sp3.epochs - epoch) <= np.timedelta64(HALF, "m"))[::EVERY]
        if len(near) < 2 * HALF // EVERY:  # the element set's window is not all inside
            continue
        _, r, v = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
        h = np.cross(r, v)
        node = np.cross([0.0, 0.0, 1.0], h)
        cos_u = np.dot(node, r) / np.linalg.norm(node) / np.linalg.norm(r)
        latitudes.append(float(np.degrees(np.arccos(np.clip(cos_u, -1, 1)))))
        true = _gcrs(sp3.epochs[near], truth[near])
        for t, p in zip(sp3.epochs[near], true, strict=True):
            days = float((t - np.datetime64("2000-01-01T12:00")) / np.timedelta64(1, "D"))
            err, r, v = sat.sgp4(2451545.0, days)  # a Julian date as whole + fraction
            assert err == 0
            state = rp.frames.teme_to_gcrf(t, np.array(r + v) * 1e3)
            errors.append(rtn_basis(state[:3], state[3:]) @ (state[:3] - p))
            acc = catalog.tle_accuracy(rp.OrbitState(t, state[:3], state[3:]))
            sigmas.append([acc.radial, acc.along_track, acc.cross_track])
    return np.array(errors), np.array(sigmas), latitudes


def test_the_800_to_2000_km_tle_accuracy_is_sgp4_s_error_against_precise_orbits(test_data):
    # Measured (2026-12-06): RMS R / T / N within 3 h of the epochs 318 / 833 / 269 m
    # (Jason-1, 10 sets) and 221 / 515 / 426 m (TOPEX, 3 sets), the two weighted equally
    # 273 / 693 / 357 m, against the regime's 300 / 700 / 350 m (150 / 600 / 250 before,
    # when the predicted covariances held the radial errors at 2.3-2.9 sigmas). Bands: the
    # equally weighted RMS within 20 % of the regime's sigma (a sigma estimated from 13
    # element sets whose errors are shared within each satellite is good to about that).
    mean_squares, sigma = [], None
    for name, (norad, file) in SATELLITES.items():
        errors, sigmas, latitudes = _errors(test_data, norad, file)
        assert len(latitudes) >= 3, name
        # Every epoch at the ascending node: why the errors at the epochs alone looked
        # like an offset. Around the orbit there is none radially.
        assert all(min(u, 360 - u) < 1.0 for u in latitudes), (name, latitudes)
        assert abs(errors[:, 0].mean()) < 50.0, name
        assert np.all(sigmas == sigmas[0]), name  # one regime all along
        sigma = sigmas[0]
        mean_squares.append(np.mean(errors**2, axis=0))
    measured = np.sqrt(np.mean(mean_squares, axis=0))
    print("RMS R / T / N m:", measured.round(0), "assumed:", sigma)
    assert np.all(np.abs(measured / sigma - 1.0) < 0.2), (measured, sigma)
