"""Predictions judged against precise orbits: Jason-1 (2003) and TOPEX/Poseidon (1997).

``$RHOPROP_TEST_DATA/precise_orbits/leo`` holds CNES/CLS DORIS orbits of both satellites
(SP3-c, 60 s, Earth-fixed, time system TAI) and 28 element sets of the same days. For each
start S (00:00 UTC of every day with an element set before it and precise orbit after it):

- rhoprop's default: the newest element set before S, ``catalog.load`` then
  ``propagate_catalog`` with the library's defaults (fitted state and Cd*A/m, CCSP,
  NRLMSIS 2.1) on the space weather as known at S (forecast mode);
- rhoprop from the history: ``load(history="fit")`` of every element set of the 3 days
  before S: the newest fitted with the others of its last ``rp.catalog.HISTORY_DAYS``
  (each near its own epoch);
- SGP4 of the newest element set (the baseline).

Each prediction at S + 1..5 days (where the precise orbit reaches) is compared with the
precise position there: the DORIS orbit interpolated (Lagrange through 10 samples) to the
UTC instant (TAI - UTC: 31 s in 1997, 32 s in 2003), rotated from ITRS to GCRS with astropy
(IERS-B bundled with it, no download). The predictions are in TEME (SGP4's frame):
rhoprop's of the element set's epoch, SGP4's of each instant; both rotated to GCRF with
``rp.frames.teme_to_gcrf``. Printed: per satellite and horizon the median and
largest position error (km) of each configuration and its ratio to SGP4's; the default's
covariance judged on the same errors (the precise orbit's own error, centimetres, is
left out): RMS of each RTN error over its predicted sigma (1 for a calibrated Gaussian)
and the share of predictions inside the RTN 1/2/3-sigma ellipsoids; and SGP4's own error
within 3 h of each element set's epoch (every phase of the orbit) against the TLE
accuracy rhoprop assumes there (``catalog.tle_accuracy``).

Run:  python benches/precise_orbits.py
"""

from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path

import numpy as np
from scipy import stats
from sgp4.api import Satrec
from tables import slashed

import rhoprop as rp
from machine import describe
from rhoprop import catalog
from rhoprop.density import Msis

LEO = "precise_orbits/leo"
SATELLITES = {
    "Jason-1": (26997, "ssaja102.b03007.e03017.DGS.sp3.gz"),
    "TOPEX/Poseidon": (22076, "grgtop03.b97344.e97348.D_S.sp3.gz"),
}
HORIZONS = (1, 2, 3, 4, 5)


def truth_gcrs(sp3: rp.io.Sp3, utc: np.datetime64) -> np.ndarray:
    """The precise position (m, GCRS) at the UTC instant ``utc`` (``rp.io.read_sp3`` puts
    the file's TAI epochs on the UTC scale)."""
    from astropy import units as u
    from astropy.coordinates import GCRS, ITRS, CartesianRepresentation
    from astropy.time import Time

    epochs, pos = sp3.epochs, next(iter(sp3.positions.values()))
    # Lagrange through the 10 samples around it (60 s apart: sub-millimetre in LEO). The
    # velocities are not read: TOPEX's file gives them in m/s where SP3 says dm/s.
    k = int(np.clip(np.searchsorted(epochs, utc) - 5, 0, len(epochs) - 10))
    x = (epochs[k : k + 10] - utc) / np.timedelta64(60, "s")
    weights = np.array(
        [np.prod([-x[m] / (x[j] - x[m]) for m in range(10) if m != j]) for j in range(10)]
    )
    p = weights @ pos[k : k + 10]
    t = Time(str(utc), scale="utc")
    itrs = ITRS(CartesianRepresentation(p * u.m), obstime=t)
    return np.asarray(itrs.transform_to(GCRS(obstime=t)).cartesian.xyz.to(u.m).value)


def sets_of(path: Path, norad: int) -> list[tuple[str, str, float]]:
    lines = path.read_text().splitlines()
    out = []
    for l1, l2 in zip(lines[0::2], lines[1::2], strict=True):
        sat = Satrec.twoline2rv(l1, l2)
        if sat.satnum == norad:
            out.append((l1, l2, sat.jdsatepoch + sat.jdsatepochF))
    return sorted(out, key=lambda s: s[2])


def jd(t: np.datetime64) -> float:
    return float((t - np.datetime64("2000-01-01T12:00")) / np.timedelta64(1, "D")) + 2451545.0


def predict(
    sets: list[tuple[str, str, float]],
    start: np.datetime64,
    ends: list[np.datetime64],
    history: bool,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """rhoprop's GCRF states (m, m/s) and position covariances (m^2) at ``ends`` from the
    element sets before ``start``."""
    before = [s for s in sets if s[2] < jd(start)]
    if history:
        before = [s for s in before if s[2] >= jd(start) - 3.0]
    else:
        before = before[-1:]
    weather = rp.SpaceWeather().as_of(start)
    model = Msis("2.1", space_weather=weather)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "sets.tle"
        path.write_text("".join(f"{s[0]}\n{s[1]}\n" for s in before))
        cat = catalog.load(
            path, fit=rp.catalog.FitSettings(model), history="fit" if history else "newest"
        )
    obj = cat.objects[0]
    out = []
    for end in ends:
        res = catalog.propagate_catalog(
            [obj],
            model,
            end,
            output_step=1e9,
            execution=rp.Execution(progress=False),
        )
        turn = rp.frames.teme_to_gcrf_matrix(obj.state.epoch)
        cov = turn @ res.covariance[0, -1, :3, :3] @ turn.T
        out.append((rp.frames.teme_to_gcrf(obj.state.epoch, res.mean[0, -1]), cov))
    return out


def rtn_ratios(state: np.ndarray, cov: np.ndarray, true: np.ndarray) -> np.ndarray:
    """The RTN error of ``state`` from the position ``true`` over its sigmas (3 values)
    and its squared Mahalanobis distance."""
    basis = rp.frames.rtn_basis(state[:3], state[3:])
    d = basis @ (state[:3] - true)
    c = basis @ cov @ basis.T
    return np.append(d / np.sqrt(np.diag(c)), d @ np.linalg.solve(c, d))


#: SGP4's error near an element set's epoch is sampled every ``EPOCH_STEP`` s within
#: ``EPOCH_HALF`` s either side (one and a half revolutions): every epoch of these element
#: sets lies at the ascending node, so their errors at the epoch alone show one phase of a
#: once-per-revolution error as if it were an offset.
EPOCH_HALF, EPOCH_STEP = 3 * 3600, 300


def epoch_errors(sets: list[tuple[str, str, float]], sp3: rp.io.Sp3) -> np.ndarray:
    """SGP4's RTN position error (m) near each element set's epoch within the precise
    orbit (:data:`EPOCH_HALF`), against the precise position, and the RTN 1-sigma rhoprop
    assumes there (``catalog.tle_accuracy``), and the time from the epoch (s): rows of 7."""
    rows = []
    for l1, l2, _ in sets:
        sat = Satrec.twoline2rv(l1, l2)
        epoch = rp.time.from_jd(sat.jdsatepoch, sat.jdsatepochF)
        for dt in range(-EPOCH_HALF, EPOCH_HALF + 1, EPOCH_STEP):
            t = epoch + np.timedelta64(dt, "s")
            if not sp3.epochs[5] <= t <= sp3.epochs[-6]:
                continue
            whole = np.floor(jd(t))
            _, r, v = sat.sgp4(whole, jd(t) - whole)
            state = rp.frames.teme_to_gcrf(t, np.array(r + v) * 1e3)
            basis = rp.frames.rtn_basis(state[:3], state[3:])
            acc = catalog.tle_accuracy(rp.OrbitState(t, state[:3], state[3:]))
            error = basis @ (state[:3] - truth_gcrs(sp3, t))
            rows.append([*error, acc.radial, acc.along_track, acc.cross_track, dt])
    return np.array(rows)


def main() -> None:
    print(describe())
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data")) / LEO
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    from astropy.utils import iers

    iers.conf.auto_download = False
    print(
        "\n| satellite | horizon | starts | SGP4 median / max km | rhoprop default median / max "
        "km | ratio | rhoprop history median / max km | ratio |"
    )
    print("| --- | ---: | ---: | --- | --- | ---: | --- | ---: |")
    ratios: dict[str, dict[int, list[np.ndarray]]] = {}
    at_epoch: dict[str, np.ndarray] = {}
    for name, (norad, file) in SATELLITES.items():
        sp3 = rp.io.read_sp3(data / file)
        sets = sets_of(data / "tles_jason1_topex.txt", norad)
        first_utc, last_utc = sp3.epochs[0], sp3.epochs[-1]
        errors: dict[int, list[tuple[float, float, float]]] = {h: [] for h in HORIZONS}
        ratios[name] = {h: [] for h in HORIZONS}
        at_epoch[name] = epoch_errors(sets, sp3)
        day = first_utc.astype("datetime64[D]") + np.timedelta64(1, "D")
        while day + np.timedelta64(1, "D") <= last_utc:
            start = day.astype("datetime64[ns]")
            horizons = [h for h in HORIZONS if start + np.timedelta64(h, "D") <= last_utc]
            ends = [start + np.timedelta64(h, "D") for h in horizons]
            newest = [s for s in sets if s[2] < jd(start)][-1]
            sat = Satrec.twoline2rv(newest[0], newest[1])
            default = predict(sets, start, ends, history=False)
            hist = predict(sets, start, ends, history=True)
            for h, end, p_def, p_hist in zip(horizons, ends, default, hist, strict=True):
                whole = np.floor(jd(end))
                _, r, _ = sat.sgp4(whole, jd(end) - whole)
                p_sgp4 = rp.frames.teme_to_gcrf(
                    end, np.concatenate([np.array(r) * 1e3, np.zeros(3)])
                )[:3]
                true = truth_gcrs(sp3, end)
                errors[h].append(
                    tuple(
                        float(np.linalg.norm(p - true)) / 1e3
                        for p in (p_sgp4, p_def[0][:3], p_hist[0][:3])
                    )
                )
                ratios[name][h].append(rtn_ratios(p_def[0], p_def[1], true))
            day += np.timedelta64(1, "D")
        for h in HORIZONS:
            if not errors[h]:
                continue
            e = np.array(errors[h])
            med, top = np.median(e, axis=0), e.max(axis=0)
            print(
                f"| {name} | {h} d | {len(e)} | {med[0]:.2f} / {top[0]:.2f} | {med[1]:.2f} / "
                f"{top[1]:.2f} | {med[1] / med[0]:.2f} | {med[2]:.2f} / {top[2]:.2f} | "
                f"{med[2] / med[0]:.2f} |",
                flush=True,
            )
    show_covariance(ratios, at_epoch)


def show_covariance(
    ratios: dict[str, dict[int, list[np.ndarray]]], at_epoch: dict[str, np.ndarray]
) -> None:
    """The default's covariance against the precise orbits, and SGP4's error at epoch."""
    print(
        "\nThe default's covariance (CCSP): RMS error / sigma radial, along-track, "
        "cross-track (1 if calibrated) and inside the RTN 1/2/3-sigma ellipsoids"
    )
    print(
        "\n| satellite | horizon | starts | RMS R / T / N error over sigma | inside 1/2/3 sigma |"
    )
    print("| --- | ---: | ---: | --- | --- |")
    bounds = [stats.chi2.ppf(2 * stats.norm.cdf(k) - 1, 3) for k in (1, 2, 3)]
    for name, per in ratios.items():
        for h, rows in per.items():
            if not rows:
                continue
            r = np.array(rows)
            rms = np.sqrt(np.mean(r[:, :3] ** 2, axis=0))
            inside = [100 * np.mean(r[:, 3] <= b) for b in bounds]
            print(
                f"| {name} | {h} d | {len(r)} | {slashed(rms, '.2f')} | {slashed(inside, '.0f')} |"
            )
    print(
        f"\nSGP4 within {EPOCH_HALF / 3600:g} h of each element set's epoch (every "
        f"{EPOCH_STEP} s) against the precise orbit, m; at the epochs alone (all at the "
        "ascending node) in brackets"
    )
    print(
        "\n| satellite | sets | mean R / T / N | RMS R / T / N | at the epochs: mean R / T / N "
        "| assumed 1-sigma R / T / N |"
    )
    print("| --- | ---: | --- | --- | --- | --- |")
    for name, e in at_epoch.items():
        if not len(e):
            continue
        own = e[e[:, 6] == 0]  # at the epochs themselves
        print(
            f"| {name} | {len(own)} | {slashed(e[:, :3].mean(axis=0), '+.0f')} | "
            f"{slashed(np.sqrt(np.mean(e[:, :3] ** 2, axis=0)), '.0f')} | "
            f"({slashed(own[:, :3].mean(axis=0), '+.0f')}) | "
            f"{slashed(np.median(e[:, 3:6], axis=0), '.0f')} |"
        )


if __name__ == "__main__":
    main()
