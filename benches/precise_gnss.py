"""GEO, IGSO and MEO predictions judged against precise orbits: BeiDou, 2024-06-16..18.

``$RHOPROP_TEST_DATA/precise_orbits/gnss`` holds GFZ's multi-GNSS rapid orbits (SP3-d,
5 min, GPS time, Earth-fixed IGS20) of 2024-06-16..18 and 52 BeiDou element sets
published 2024-06-12..16 (the PRN in each name; C38's name does not match its orbit and
is left out). For every BeiDou satellite with both, the newest element set before
2024-06-17T00:00 UTC is predicted to each whole GPS hour of the two days after it by

- rhoprop's default: ``catalog.load(fit=FitSettings(model))`` then ``propagate_catalog``
  (fitted state and Cd*A/m, SGP4's positions debiased along-track by the regime's
  ``rp.catalog.fit.ALONG_TRACK_BIAS``, CCSP, NRLMSIS 2.1 on the space weather known at
  the start: forecast mode; at these heights the Sun's and Moon's pull and the Earth's
  tesseral field act, drag not);
- the same without debiasing (``FitSettings(model, along_track_bias={})``);
- SGP4/SDP4 of the same element set (the baseline).

Truth: the SP3 position at that GPS hour (UTC = GPS - 18 s), rotated from ITRS to GCRS
with astropy (bundled IERS-B, no download). Predictions (TEME) are rotated to GCRF with
``rp.frames.teme_to_gcrf``. Printed per class (GEO: the geostationary C01-C05, C59, C60,
C62; IGSO; MEO) and hours after the start: the median position error of each and the
ratio, and the median along-track error (rhoprop - truth, km). Then the debiasing per
TLE-accuracy regime (MEO; "GEO": the geostationary and inclined geosynchronous ones):
each satellite's mean along-track error over the hours without debiasing, their median
(what ``ALONG_TRACK_BIAS`` holds), and the median position error over every hour 0-47
without debiasing, with the library's table, and cross-validated: each satellite
debiased by the median of the others (and for MEO of the other two orbital planes). The
fit follows a shift of its positions one to one (the debiased run's median along-track
error is printed beside the table's value), so the cross-validated errors are the
undebiased run's, shifted.

Run:  python benches/precise_gnss.py
"""

from __future__ import annotations

import os
import re
import tempfile
import warnings
from pathlib import Path
from typing import Any

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


def newest_sets(data: Path) -> dict[str, tuple[str, str, str]]:
    """{PRN: (name, line 1, line 2)}: each BeiDou satellite's newest element set before
    :data:`START` that the precise orbits hold (C38 left out)."""
    truth = read_sp3([data / f for f in SP3])
    lines = (data / TLES).read_text().splitlines()
    newest: dict[str, tuple[str, str, str, float]] = {}
    for name, l1, l2 in zip(lines[0::3], lines[1::3], lines[2::3], strict=True):
        prn = re.search(r"\((C\d\d)\)", name)
        sat = Satrec.twoline2rv(l1, l2)
        epoch = sat.jdsatepoch + sat.jdsatepochF
        if prn is None or prn.group(1) == "C38" or prn.group(1) not in truth:
            continue
        old = newest.get(prn.group(1))
        if epoch < sum(jd(START)) and (old is None or old[3] < epoch):
            newest[prn.group(1)] = (name.strip(), l1, l2, epoch)
    return {p: v[:3] for p, v in sorted(newest.items())}


def rtn_errors(
    newest: dict[str, tuple[str, str, str]],
    truth: dict[str, dict[np.datetime64, np.ndarray]],
    hours: list[int],
    bias: dict[str, float] | None,
) -> dict[str, tuple[list[int], np.ndarray, np.ndarray]]:
    """Per PRN: the hours the truth holds, rhoprop's and SDP4's RTN errors (n, 3) m there,
    rhoprop fitted with ``along_track_bias=bias`` (None: the library's)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "beidou.tle"
        path.write_text("".join(f"{n}\n{a}\n{b}\n" for n, a, b in newest.values()))
        model = Msis("2.1", space_weather=rp.SpaceWeather().as_of(START))
        cat = catalog.load(path, fit=catalog.FitSettings(model, along_track_bias=bias))
    order = [re.search(r"\((C\d\d)\)", o.name).group(1) for o in cat]  # type: ignore[union-attr]
    gps_hours = [START + np.timedelta64(h, "h") for h in hours]
    utc = [g - GPS_MINUS_UTC for g in gps_hours]
    res = catalog.propagate_catalog(
        cat,
        model,
        utc[-1],
        output_step=3600.0,
        start=utc[0] - np.timedelta64(1, "h"),
        execution=rp.Execution(progress=False),
    )
    out = {}
    for i, prn in enumerate(order):
        sat = Satrec.twoline2rv(*newest[prn][1:])
        have = [k for k, g in enumerate(gps_hours) if g in truth[prn]]
        true = to_gcrs([utc[k] for k in have], np.array([truth[prn][gps_hours[k]] for k in have]))
        ours, theirs = [], []
        for row, k in enumerate(have):
            j = int(np.flatnonzero(res.epochs == utc[k])[0])
            mine = rp.frames.teme_to_gcrf(cat[i].state.epoch, res.mean[i, j])
            _, r, v = sat.sgp4(*jd(utc[k]))
            sdp4 = rp.frames.teme_to_gcrf(utc[k], np.concatenate([np.array(r), np.array(v)]) * 1e3)
            basis = rp.frames.rtn_basis(true[row], sdp4[3:])
            ours.append(basis @ (mine[:3] - true[row]))
            theirs.append(basis @ (sdp4[:3] - true[row]))
        out[prn] = ([hours[k] for k in have], np.array(ours), np.array(theirs))
    return out


def kind_of(prn: str, name: str) -> str:
    return "GEO" if prn in GEO else ("IGSO" if "IGSO" in name else "MEO")


def main() -> None:
    print(describe())
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data")) / GNSS
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    from astropy.utils import iers

    iers.conf.auto_download = False
    truth = read_sp3([data / f for f in SP3])
    newest = newest_sets(data)
    print(f"\n{len(newest)} satellites: " + ", ".join(newest))
    every = list(range(48))
    runs = {"default": rtn_errors(newest, truth, every, None)}
    runs["none"] = rtn_errors(newest, truth, every, {})
    print(
        "\n| class | hours after start | satellites | SGP4 median km | rhoprop median km | ratio "
        "| rhoprop along-track median km |"
    )
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for kind in ("GEO", "IGSO", "MEO"):
        for h in HOURS:
            e = [
                (np.linalg.norm(o[hs.index(h)]), np.linalg.norm(t[hs.index(h)]), o[hs.index(h), 1])
                for prn, (hs, o, t) in runs["default"].items()
                if kind_of(prn, newest[prn][0]) == kind and h in hs
            ]
            if not e:
                continue
            med = np.median(np.array(e) / 1e3, axis=0)
            print(
                f"| {kind} | {h} | {len(e)} | {med[1]:.2f} | {med[0]:.2f} | "
                f"{med[0] / med[1]:.2f} | {med[2]:+.2f} |",
                flush=True,
            )
    debiasing(newest, runs)


def debiasing(newest: dict[str, tuple[str, str, str]], runs: dict[str, Any]) -> None:
    """The table of TLE debiasing per regime (module docstring)."""
    print(
        "\n| regime | satellites | mean along-track without, median m (SDP4's) | table m "
        "| debiased run's median m | median error 0-47 h m: without / table / left out "
        "by satellite / by plane | better than without, by satellite / plane % |"
    )
    print("| --- | ---: | --- | ---: | ---: | --- | --- |")
    for regime, kinds in (("MEO", ("MEO",)), ("GEO", ("GEO", "IGSO"))):
        prns = [p for p in newest if kind_of(p, newest[p][0]) in kinds]
        own = {p: float(runs["none"][p][1][:, 1].mean()) for p in prns}
        sdp4 = np.median([runs["none"][p][2][:, 1].mean() for p in prns])
        after = np.median([runs["default"][p][1][:, 1].mean() for p in prns])
        planes = {p: round(Satrec.twoline2rv(*newest[p][1:]).nodeo / (np.pi / 3)) for p in prns}
        errors = {"without": [], "table": [], "satellite": [], "plane": []}
        for p in prns:
            base = runs["none"][p][1]
            keep = {
                "satellite": [q for q in prns if q != p],
                "plane": [
                    q for q in prns if q != p and (regime != "MEO" or planes[q] != planes[p])
                ],
            }
            errors["without"].append(np.linalg.norm(base, axis=1))
            errors["table"].append(np.linalg.norm(runs["default"][p][1], axis=1))
            for fold, others in keep.items():
                shifted = base - np.array([0.0, np.median([own[q] for q in others]), 0.0])
                errors[fold].append(np.linalg.norm(shifted, axis=1))
        med = {k: np.median(np.concatenate(v)) for k, v in errors.items()}
        better = {
            k: 100
            * np.mean(
                [
                    np.median(a) < np.median(b)
                    for a, b in zip(errors[k], errors["without"], strict=True)
                ]
            )
            for k in ("satellite", "plane")
        }
        print(
            f"| {regime} | {len(prns)} | {np.median(list(own.values())):+.0f} ({sdp4:+.0f}) | "
            f"{catalog.fit.ALONG_TRACK_BIAS.get(regime, 0.0):+.0f} | {after:+.0f} | "
            + " / ".join(f"{med[k]:.0f}" for k in ("without", "table", "satellite", "plane"))
            + " | "
            f"{better['satellite']:.0f} / {better['plane']:.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
