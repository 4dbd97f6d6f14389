"""GEO, IGSO and MEO predictions judged against precise orbits: BeiDou, 2024-06-16..18.

``$RHOPROP_TEST_DATA/precise_orbits/gnss`` holds GFZ's multi-GNSS rapid orbits (SP3-d,
5 min, GPS time, Earth-fixed IGS20) of 2024-06-16..18 and 52 BeiDou element sets
published 2024-06-12..16 (the PRN in each name; C38's name does not match its orbit and
is left out). For every BeiDou satellite with both, the newest element set before
2024-06-16T00:00 UTC is predicted to each whole GPS hour of the three days by

- rhoprop's default: ``catalog.load`` then ``propagate_catalog`` (fitted state and
  Cd*A/m, CCSP, NRLMSIS 2.1 on the space weather known at the start: forecast mode; at
  these heights the Sun's and Moon's pull and the Earth's tesseral field act, drag not);
- SGP4/SDP4 of the same element set (the baseline).

Truth: the SP3 position at that GPS hour (UTC = GPS - 18 s), rotated from ITRS to GCRS
with astropy (bundled IERS-B, no download). Predictions (TEME) are rotated to GCRF with
``rp.frames.teme_to_gcrf``. Printed per class (GEO: the geostationary C01-C05, C59, C60,
C62; IGSO; MEO) and hours after the start: the median position error of each and the
ratio, and the median along-track error (rhoprop - truth, km).

Run:  python benches/precise_gnss.py
"""

from __future__ import annotations

import os
import re
import tempfile
import warnings
from pathlib import Path

import numpy as np
from sgp4.api import Satrec

import rhoprop as rp
from machine import describe
from rhoprop import catalog
from rhoprop.density import Msis

GNSS = "precise_orbits/gnss"
SP3 = (
    "GBM0MGXRAP_20241680000_01D_05M_ORB_SP3.gz",
    "GBM0MGXRAP_20241690000_01D_05M_ORB_SP3.gz",
    "GBM0MGXRAP_20241700000_01D_05M_ORB_SP3.gz",
)
TLES = "beidou_tles_trackthatsatellite_20240617.txt"
START = np.datetime64("2024-06-17T00:00", "ns")
GPS_MINUS_UTC = np.timedelta64(18, "s")
HOURS = (6, 12, 24, 36, 47)
GEO = {"C01", "C02", "C03", "C04", "C05", "C59", "C60", "C62"}


def read_sp3(paths: list[Path]) -> dict[str, dict[np.datetime64, np.ndarray]]:
    """{PRN: {GPS epoch: Earth-fixed position m}} of BeiDou satellites in SP3-d files
    (read by ``rp.io.read_sp3``, whose epochs are UTC: GPS = UTC + 18 s in 2024)."""
    out: dict[str, dict[np.datetime64, np.ndarray]] = {}
    for path in paths:
        sp3 = rp.io.read_sp3(path)
        for prn, pos in sp3.positions.items():
            if prn.startswith("C"):
                track = out.setdefault(prn, {})
                for epoch, r in zip(sp3.epochs + GPS_MINUS_UTC, pos, strict=True):
                    if np.isfinite(r).all():
                        track[epoch] = r
    return out


def to_gcrs(utc: list[np.datetime64], itrs_m: np.ndarray) -> np.ndarray:
    """Earth-fixed positions (n, 3) m at UTC instants to GCRS (n, 3) m."""
    from astropy import units as u
    from astropy.coordinates import GCRS, ITRS, CartesianRepresentation
    from astropy.time import Time

    t = Time([str(x) for x in utc], scale="utc")
    itrs = ITRS(CartesianRepresentation(itrs_m.T * u.m), obstime=t)
    return np.asarray(itrs.transform_to(GCRS(obstime=t)).cartesian.xyz.to(u.m).value).T


def jd(t: np.datetime64) -> tuple[float, float]:
    days = float((t - np.datetime64("2000-01-01T12:00", "ns")) / np.timedelta64(1, "D"))
    whole = np.floor(days)
    return whole + 2451545.0, days - whole


def main() -> None:
    print(describe())
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data")) / GNSS
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    from astropy.utils import iers

    iers.conf.auto_download = False
    truth = read_sp3([data / f for f in SP3])
    lines = (data / TLES).read_text().splitlines()
    newest: dict[str, tuple[str, str, str]] = {}
    for name, l1, l2 in zip(lines[0::3], lines[1::3], lines[2::3], strict=True):
        prn = re.search(r"\((C\d\d)\)", name)
        sat = Satrec.twoline2rv(l1, l2)
        epoch = sat.jdsatepoch + sat.jdsatepochF
        if prn is None or prn.group(1) == "C38" or prn.group(1) not in truth:
            continue
        if epoch < sum(jd(START)):
            old = newest.get(prn.group(1))
            if (
                old is None
                or Satrec.twoline2rv(old[1], old[2]).jdsatepoch
                + Satrec.twoline2rv(old[1], old[2]).jdsatepochF
                < epoch
            ):
                newest[prn.group(1)] = (name.strip(), l1, l2)
    prns = sorted(newest)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "beidou.tle"
        path.write_text("".join(f"{n}\n{a}\n{b}\n" for n, a, b in newest.values()))
        weather = rp.SpaceWeather().as_of(START)
        model = Msis("2.1", space_weather=weather)
        cat = catalog.load(path)
        order = [re.search(r"\((C\d\d)\)", o.name).group(1) for o in cat]  # type: ignore[union-attr]
        gps_hours = [START + np.timedelta64(h, "h") for h in HOURS]
        utc = [g - GPS_MINUS_UTC for g in gps_hours]
        end = utc[-1]
        res = catalog.propagate_catalog(
            cat,
            model,
            end,
            output_step=3600.0,
            start=utc[0] - np.timedelta64(1, "h"),
            execution=rp.Execution(progress=False),
        )
    rows: dict[str, dict[int, list[tuple[float, float, float]]]] = {}
    for i, prn in enumerate(order):
        kind = "GEO" if prn in GEO else ("IGSO" if "IGSO" in cat[i].name else "MEO")
        sat = Satrec.twoline2rv(*[ln for ln in newest[prn][1:]])
        have = [k for k, g in enumerate(gps_hours) if g in truth[prn]]
        true = to_gcrs([utc[k] for k in have], np.array([truth[prn][gps_hours[k]] for k in have]))
        for row, k in enumerate(have):
            j = int(np.flatnonzero(res.epochs == utc[k])[0])
            ours = rp.frames.teme_to_gcrf(cat[i].state.epoch, res.mean[i, j])
            _, r, v = sat.sgp4(*jd(utc[k]))
            theirs = rp.frames.teme_to_gcrf(
                utc[k], np.concatenate([np.array(r), np.array(v)]) * 1e3
            )
            basis = rp.frames.rtn_basis(true[row], ours[3:])
            along = float((ours[:3] - true[row]) @ basis[1]) / 1e3
            rows.setdefault(kind, {}).setdefault(HOURS[k], []).append(
                (
                    float(np.linalg.norm(ours[:3] - true[row])) / 1e3,
                    float(np.linalg.norm(theirs[:3] - true[row])) / 1e3,
                    along,
                )
            )
    print(f"\n{len(prns)} satellites: " + ", ".join(prns))
    print(
        "\n| class | hours after start | satellites | SGP4 median km | rhoprop median km | ratio "
        "| rhoprop along-track median km |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for kind in ("GEO", "IGSO", "MEO"):
        for h in HOURS:
            e = np.array(rows.get(kind, {}).get(h, []))
            if not len(e):
                continue
            med = np.median(e, axis=0)
            print(
                f"| {kind} | {h} | {len(e)} | {med[1]:.2f} | {med[0]:.2f} | "
                f"{med[0] / med[1]:.2f} | {med[2]:+.2f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
