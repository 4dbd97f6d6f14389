"""A precise-dynamics fit to element-set histories, judged against precise orbits
(Levit & Marshall 2011's method): Jason-1 (2003) and TOPEX/Poseidon (1997).

For each start S of ``benches/precise_orbits.py`` (00:00 UTC of every day with element
sets before it and precise orbit after it): the SGP4 positions of every element set of
the ``--window`` days before S, every 10 min within ``--half`` days of each set's epoch
(and before S), rotated to GCRF, fitted by ``rp.fit_positions`` with
``rp.Dynamics.precise()`` (J2..J6, EGM2008 to degree 40, Sun and Moon; no drag: at
1,336 km it moves these orbits by tens of metres in five days), then predicted to S + 1..5
days and compared with the DORIS orbit. Printed per satellite and horizon: the median
position error of SGP4 (the newest set) and of the fit, km, and their ratio; per start
the number of sets, of positions and the fit's RMS (m): the element sets' own scatter.

Run:  python benches/precise_history_fit.py [--window 3] [--half 0.5]
"""

from __future__ import annotations

import argparse
import os
import warnings
from pathlib import Path

import numpy as np
from precise_orbits import HORIZONS, LEO, SATELLITES, jd, sets_of, truth_gcrs
from sgp4.api import Satrec

import rhoprop as rp
from machine import describe


def pseudo_observations(
    before: list[tuple[str, str, float]], start: np.datetime64, window: float, half: float
) -> tuple[np.ndarray, np.ndarray]:
    """(UTC epochs, GCRF positions m) of the element sets' SGP4 positions near their epochs."""
    found: dict[np.datetime64, np.ndarray] = {}
    first = start - np.timedelta64(int(window * 86400), "s")
    for l1, l2, _ in before:
        sat = Satrec.twoline2rv(l1, l2)
        epoch = rp.time.from_jd(sat.jdsatepoch, sat.jdsatepochF, scale="utc")
        lo = max(epoch - np.timedelta64(int(half * 86400), "s"), first)
        hi = min(epoch + np.timedelta64(int(half * 86400), "s"), start)
        for g in np.arange(lo, hi, np.timedelta64(600, "s")):
            whole = np.floor(jd(g))
            error, r, v = sat.sgp4(whole, jd(g) - whole)
            if not error:  # a later set's position wins where two overlap
                found[g] = rp.frames.teme_to_gcrf(g, np.concatenate([r, v]) * 1e3)[:3]
    epochs = np.array(sorted(found))
    return epochs, np.array([found[e] for e in epochs])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--window", type=float, default=3.0, help="days of element sets")
    parser.add_argument("--half", type=float, default=0.5, help="days either side of a set")
    args = parser.parse_args()
    print(describe())
    from astropy.utils import iers

    iers.conf.auto_download = False
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data")) / LEO
    model = rp.scenarios.benchmark_exponential(0.0)
    print(f"\nwindow {args.window:g} d, {args.half:g} d either side of each set's epoch\n")
    print("| satellite | horizon | starts | SGP4 median km | fit median km | ratio |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for name, (norad, file) in SATELLITES.items():
        sp3 = rp.io.read_sp3(data / file)
        sets = sets_of(data / "tles_jason1_topex.txt", norad)
        rows: dict[int, list[tuple[float, float]]] = {h: [] for h in HORIZONS}
        notes = []
        day = sp3.epochs[0].astype("datetime64[D]") + np.timedelta64(1, "D")
        while day + np.timedelta64(1, "D") <= sp3.epochs[-1]:
            start = day.astype("datetime64[ns]")
            day += np.timedelta64(1, "D")
            before = [s for s in sets if jd(start) - args.window <= s[2] < jd(start)]
            if not before:
                continue
            epochs, positions = pseudo_observations(before, start, args.window, args.half)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
                fit = rp.fit_positions(epochs, positions, rp.Spacecraft(1.0, 0.01), model)
            newest = Satrec.twoline2rv(before[-1][0], before[-1][1])
            notes.append(f"{str(start)[:10]}: {len(before)} sets, {len(epochs)}, {fit.rms:.0f} m")
            for h in HORIZONS:
                end = start + np.timedelta64(h, "D")
                if end > sp3.epochs[-1]:
                    continue
                span = float((end - fit.state.epoch) / np.timedelta64(1, "s"))
                run = rp.propagate(
                    fit.state, fit.spacecraft, model, span, dynamics=rp.Dynamics.precise()
                )
                true = truth_gcrs(sp3, end)
                whole = np.floor(jd(end))
                _, r, v = newest.sgp4(whole, jd(end) - whole)
                sgp4 = rp.frames.teme_to_gcrf(end, np.concatenate([r, v]) * 1e3)[:3]
                rows[h].append(
                    (
                        float(np.linalg.norm(sgp4 - true)) / 1e3,
                        float(np.linalg.norm(run.positions[-1] - true)) / 1e3,
                    )
                )
        for h in HORIZONS:
            if rows[h]:
                m = np.median(np.array(rows[h]), axis=0)
                print(
                    f"| {name} | {h} d | {len(rows[h])} | {m[0]:.2f} | {m[1]:.2f} | "
                    f"{m[1] / m[0]:.2f} |",
                    flush=True,
                )
        print(f"\n{name}: " + "; ".join(notes) + "\n")


if __name__ == "__main__":
    main()
