"""Solar radiation pressure against precise orbits: BeiDou GEO, IGSO and MEO, 2024-06-16..18.

For every BeiDou satellite in GFZ's multi-GNSS rapid orbits (``$RHOPROP_TEST_DATA/
precise_orbits/gnss``, SP3-d, 5 min, GPS time, Earth-fixed; rotated to GCRS with astropy,
bundled IERS-B), a state is fitted by ``rp.fit_positions`` to the first day's precise
positions (every 15 min), then propagated two more days and compared with the precise
orbit. Fitted twice, with the same dynamics (``rp.Dynamics.precise()``: J2..J6, EGM2008
to degree 40, Sun and Moon; DOP853):

- without radiation pressure: the 6 elements of the state;
- with it (``Spacecraft(cr=...)``): the state and Cr*A/m, the reflectivity the data allow.

Printed per satellite and class (GEO: C01-C05, C59, C60, C62; IGSO: period near a day,
inclined; MEO): the fit's RMS, the fitted Cr*A/m, and the position error (m) 24 h and
47.75 h after the fit window, with and without radiation pressure. A prediction from a
precise state, not from an element set: what the dynamics can do, apart from the fit to
SGP4 a catalog object gets.

Run:  python benches/precise_srp.py
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
from precise_gnss import GEO, GNSS, GPS_MINUS_UTC, SP3, read_sp3, to_gcrs

import rhoprop as rp
from machine import describe

START_GPS = np.datetime64("2024-06-16T00:00", "ns")
FIT_HOURS = 24
STEP = 900.0  # s between fitted and compared positions
SPAN = 3 * 86400.0 - STEP  # the files end at 23:55 of the third day
AREA = 0.01  # m^2/kg: the fitted Cr scales it (Cr*A/m = cr * AREA)


def truth_gcrs(track: dict[np.datetime64, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(seconds from the start, GCRS positions m) of one satellite on the STEP grid."""
    grid = [START_GPS + np.timedelta64(int(s), "s") for s in np.arange(0.0, SPAN + 1, STEP)]
    have = [g for g in grid if g in track]
    t = np.array([(g - START_GPS) / np.timedelta64(1, "s") for g in have])
    return t, to_gcrs([g - GPS_MINUS_UTC for g in have], np.array([track[g] for g in have]))


def predict(t: np.ndarray, r: np.ndarray, fit_cr: bool) -> tuple[np.ndarray, float, float]:
    """Fits the positions ``r`` (m) of the first FIT_HOURS at ``t`` s from the start with
    ``rp.fit_positions`` and predicts all of ``t``: (positions (len(t), 3) m, fit RMS m,
    fitted Cr*A/m m^2/kg)."""
    epochs = START_GPS - GPS_MINUS_UTC + (t * 1e9).astype("timedelta64[ns]")
    inside = t <= FIT_HOURS * 3600.0
    model = rp.scenarios.benchmark_exponential(0.0)  # no drag above 20,000 km
    fit = rp.fit_positions(
        epochs[inside], r[inside], rp.Spacecraft(1.0, AREA), model, fit_cr=fit_cr
    )
    run = rp.propagate(
        fit.state,
        fit.spacecraft,
        model,
        float(t[-1] - t[0]),
        dynamics=rp.Dynamics.precise(),
        output_step=STEP,
    )
    index = np.searchsorted(np.round(run.times), t - t[0])
    return run.positions[index], fit.rms, fit.spacecraft.radiation_parameter


def main() -> None:
    print(describe())
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    from astropy.utils import iers

    iers.conf.auto_download = False
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data")) / GNSS
    truth = read_sp3([data / f for f in SP3])
    print(
        "\n| PRN | class | fit RMS m (no SRP / SRP) | Cr*A/m m^2/kg | 24 h m no SRP | "
        "24 h m SRP | 47.75 h m no SRP | 47.75 h m SRP |"
    )
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    rows: dict[str, list[tuple[float, float, float, float]]] = {}
    for prn in sorted(truth):
        track = truth[prn]
        t, r = truth_gcrs(track)
        if len(t) < 0.9 * (SPAN / STEP) or t[-1] < SPAN or t[0] > 0:
            continue
        rn = np.linalg.norm(r[0])
        vn = np.linalg.norm(r[1] - r[0]) / (t[1] - t[0])
        inverse_a = 2 / rn - vn**2 / rp.constants.MU  # 1 / semi-major axis, 1/m
        period = 2 * np.pi / np.sqrt(rp.constants.MU * inverse_a**3)
        normal = np.cross(r[0], r[1] - r[0])
        incl = np.degrees(np.arccos(normal[2] / np.linalg.norm(normal)))
        kind = "GEO" if prn in GEO else ("IGSO" if period > 80_000 else "MEO")
        errs, rms = [], []
        for radiation in (False, True):
            pos, fit_rms, cram = predict(t, r, radiation)
            miss = np.linalg.norm(pos - r, axis=1)
            rms.append(fit_rms)
            after = (24, 47.75)
            at = [int(np.argmin(abs(t - (FIT_HOURS + hours) * 3600.0))) for hours in after]
            errs.append([miss[i] for i in at])
        row = (errs[0][0], errs[1][0], errs[0][1], errs[1][1])
        rows.setdefault(kind, []).append(row)
        print(
            f"| {prn} | {kind} ({incl:.0f} deg) | {rms[0]:.1f} / {rms[1]:.1f} | {cram:.4f} | "
            + " | ".join(f"{e:.0f}" for e in row)
            + " |",
            flush=True,
        )
    print("\n| class | satellites | median 24 h m no SRP / SRP | median 47.75 h m no SRP / SRP |")
    print("| --- | ---: | ---: | ---: |")
    for kind in ("GEO", "IGSO", "MEO"):
        e = np.array(rows.get(kind, []))
        if len(e):
            m = np.median(e, axis=0)
            print(f"| {kind} | {len(e)} | {m[0]:.0f} / {m[1]:.0f} | {m[2]:.0f} / {m[3]:.0f} |")


if __name__ == "__main__":
    main()
