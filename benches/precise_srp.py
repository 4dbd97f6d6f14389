"""Solar radiation pressure against precise orbits: BeiDou GEO, IGSO and MEO, 2024-06-16..18.

For every BeiDou satellite in GFZ's multi-GNSS rapid orbits (``$RHOPROP_TEST_DATA/
precise_orbits/gnss``, SP3-d, 5 min, GPS time, Earth-fixed; rotated to GCRS with astropy,
bundled IERS-B), a state is fitted by least squares (scipy) to the first day's precise
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
from scipy.optimize import least_squares

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


def first_state(track: dict[np.datetime64, np.ndarray]) -> np.ndarray:
    """GCRS position and velocity at the start: the velocity from a 4th-order central
    difference of the 5-min positions around it (a guess the fit refines)."""
    h = np.timedelta64(300, "s")
    at = [START_GPS + k * h for k in (-2, -1, 0, 1, 2)]
    if not all(a in track for a in at):
        at = [START_GPS + k * h for k in (0, 1, 2, 3, 4)]
    r = to_gcrs([a - GPS_MINUS_UTC for a in at], np.array([track[a] for a in at]))
    if at[0] == START_GPS:  # one-sided: a quartic through five points, slope at the first
        v = (-25 * r[0] + 48 * r[1] - 36 * r[2] + 16 * r[3] - 3 * r[4]) / (12 * 300.0)
        return np.concatenate([r[0], v])
    v = (r[0] - 8 * r[1] + 8 * r[3] - r[4]) / (12 * 300.0)
    return np.concatenate([r[2], v])


def run(x: np.ndarray, t: np.ndarray, radiation: bool) -> np.ndarray:
    """Positions (len(t), 3) m at ``t`` s from the start for parameters ``x``: position
    offsets (m), velocity offsets (mm/s) and, with radiation, Cr."""
    state = rp.OrbitState(
        START_GPS - GPS_MINUS_UTC, x[6:9] + x[:3], x[9:12] + x[3:6] * 1e-3, frame="GCRF"
    )
    craft = rp.Spacecraft(1.0, AREA, cr=float(x[12]) if radiation else None)
    out = rp.propagate(
        state,
        craft,
        rp.scenarios.benchmark_exponential(0.0),  # no drag above 20,000 km
        float(t[-1]),
        dynamics=rp.Dynamics.precise(),
        output_step=STEP,
    )
    index = np.searchsorted(np.round(out.times), t)
    return out.positions[index]


def fit(t: np.ndarray, r: np.ndarray, guess: np.ndarray, radiation: bool) -> np.ndarray:
    """Least-squares parameters (see :func:`run`) fitted to positions ``r`` at ``t``."""
    inside = t <= FIT_HOURS * 3600.0

    def residual(p: np.ndarray) -> np.ndarray:
        x = np.concatenate([p[:6], guess, p[6:]])
        return ((run(x, t[inside], radiation) - r[inside]) / 1e3).ravel()

    p0 = np.zeros(7 if radiation else 6)
    lower, upper = np.full(p0.size, -np.inf), np.full(p0.size, np.inf)
    if radiation:
        p0[6], lower[6], upper[6] = 1.5, 0.0, 5.0
    sol = least_squares(residual, p0, bounds=(lower, upper), x_scale=1.0, diff_step=1e-6)
    return np.concatenate([sol.x[:6], guess, sol.x[6:]])


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
        guess = first_state(track)
        rn, vn = np.linalg.norm(guess[:3]), np.linalg.norm(guess[3:])
        inverse_a = 2 / rn - vn**2 / rp.constants.MU  # 1 / semi-major axis, 1/m
        period = 2 * np.pi / np.sqrt(rp.constants.MU * inverse_a**3)
        incl = np.degrees(np.arccos(np.cross(guess[:3], guess[3:])[2] / (rn * vn)))
        kind = "GEO" if prn in GEO else ("IGSO" if period > 80_000 else "MEO")
        errs, rms = [], []
        for radiation in (False, True):
            x = fit(t, r, guess, radiation)
            pos = run(x, t, radiation)
            miss = np.linalg.norm(pos - r, axis=1)
            inside = t <= FIT_HOURS * 3600.0
            rms.append(float(np.sqrt(np.mean(miss[inside] ** 2))))
            at = [int(np.argmin(abs(t - (FIT_HOURS + h) * 3600.0))) for h in (24, 47.75)]
            errs.append([miss[i] for i in at])
            cram = x[12] * AREA if radiation else 0.0
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
