"""TLE debiasing in LEO: does the along-track bias between an object's own element sets
foresee SGP4's error after the start?

On every second day of ``$RHOPROP_TEST_DATA/history_2026`` (2026-03-05..04-24), for every
LEO object (perigee above 200 km, apogee below 700 km) without an orbit raise whose newest
element set is at most 2 days old: the "TLE-based error metric" of Hallgarten La Casta &
Amato (2024, arXiv:2412.15793), each element set's SGP4 prediction at a later set's epoch
less that set's position, along-track (m), for every pair of the sets of the
``--lookback`` days before the start at most ``--max-lag`` days apart, fitted per object
as b tau^2 (a drag-rate bias) or a tau + b tau^2. The newest set's SGP4 prediction at 1,
3 and 7 days (the truth: the later element set nearest each horizon, within half a day)
is then debiased by it, by half of it, and by the two-term fit. Printed: per start the
objects and the medians; pooled the plain median |along-track error| and each debiased
one's ratio to it, the share of objects it makes better, and of starts whose median it
does not raise.

Run:  RHOPROP_TEST_DATA=../shared/data python benches/tle_debias_leo.py \
          [--lookback 10] [--max-lag 3]        # about 10 s
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
from catalog_realism import altitudes_km
from history_days import HISTORY, jd, manoeuvres, read_history
from sgp4.api import Satrec

from machine import describe

HORIZONS = (1, 3, 7)


def along(older: Satrec, newer: Satrec, at: float) -> float | None:
    """``older``'s SGP4 position less ``newer``'s at the Julian date ``at``, along
    ``newer``'s velocity, m (None where SGP4 fails)."""
    e1, r1, _ = older.sgp4(np.floor(at), at - np.floor(at))
    e2, r2, v2 = newer.sgp4(np.floor(at), at - np.floor(at))
    if e1 or e2:
        return None
    v = np.array(v2)
    return float(np.dot(np.subtract(r1, r2), v / np.linalg.norm(v))) * 1e3


def bias_fits(before: list[tuple[Satrec, float]], max_lag: float) -> tuple[float, float, float]:
    """(b, a2, b2): the pairs' along-track differences fitted as b tau^2 and as
    a2 tau + b2 tau^2 (tau in days, m); NaNs with fewer than 3 pairs."""
    taus, diffs = [], []
    for k, (old, t_old) in enumerate(before):
        for new, t_new in before[k + 1 :]:
            tau = t_new - t_old
            d = along(old, new, t_new) if 0.1 <= tau <= max_lag else None
            if d is not None:
                taus.append(tau)
                diffs.append(d)
    if len(taus) < 3:
        return np.nan, np.nan, np.nan
    tau, d = np.array(taus), np.array(diffs)
    b = float(np.sum(d * tau**2) / np.sum(tau**4))
    a2, b2 = np.linalg.lstsq(np.c_[tau, tau**2], d, rcond=None)[0]
    return b, float(a2), float(b2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lookback", type=float, default=10.0, help="days of sets used")
    parser.add_argument("--max-lag", type=float, default=3.0, help="longest pair, days")
    args = parser.parse_args()
    print(describe())
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data"))
    history = read_history(data / HISTORY)
    sets = {
        n: [(Satrec.twoline2rv(s[1], s[2]), s[3]) for s in v]
        for n, v in history.items()
        if len(v) > 5 and not manoeuvres(v)
    }
    kinds = ("plain", "b tau^2", "half of it", "a tau + b tau^2")
    pooled: dict[int, dict[str, list[float]]] = {h: {k: [] for k in kinds} for h in HORIZONS}
    per_start: dict[int, list[float]] = {h: [] for h in HORIZONS}
    print("| start | objects at 1 / 3 / 7 d | plain median km | debiased (b tau^2) median km |")
    print("| --- | --- | --- | --- |")
    for day in range(26):
        t0 = jd(np.datetime64("2026-03-05") + np.timedelta64(2 * day, "D"))
        here: dict[int, dict[str, list[float]]] = {h: {k: [] for k in kinds} for h in HORIZONS}
        for obj in sets.values():
            before = [s for s in obj if t0 - args.lookback <= s[1] < t0]
            if len(before) < 4 or before[-1][1] < t0 - 2:
                continue
            lo, hi = altitudes_km(before[-1][0])
            if lo < 200 or hi > 700:
                continue
            b, a2, b2 = bias_fits(before, args.max_lag)
            if not np.isfinite(b):
                continue
            newest, t_newest = before[-1]
            for h in HORIZONS:
                later = [s for s in obj if abs(s[1] - (t0 + h)) <= 0.5]
                if not later:
                    continue
                truth, t_truth = min(later, key=lambda s: abs(s[1] - (t0 + h)))
                e = along(newest, truth, t_truth)
                if e is None:
                    continue
                tau = t_truth - t_newest
                for kind, fix in zip(
                    kinds, (0.0, b * tau**2, 0.5 * b * tau**2, a2 * tau + b2 * tau**2), strict=True
                ):
                    here[h][kind].append(abs(e - fix))
                    pooled[h][kind].append(abs(e - fix))
        counts = " / ".join(str(len(here[h]["plain"])) for h in HORIZONS)
        plain = " / ".join(f"{np.median(here[h]['plain']) / 1e3:.1f}" for h in HORIZONS)
        fixed = " / ".join(f"{np.median(here[h]['b tau^2']) / 1e3:.1f}" for h in HORIZONS)
        print(f"| {np.datetime64('2026-03-05') + np.timedelta64(2 * day, 'D')} | {counts} | "
              f"{plain} | {fixed} |", flush=True)  # fmt: skip
        for h in HORIZONS:
            per_start[h].append(float(np.median(here[h]["b tau^2"]) / np.median(here[h]["plain"])))
    print(f"\nlookback {args.lookback:g} days, pairs at most {args.max_lag:g} days apart")
    print(
        "\n| horizon | predictions | plain median km | debiased / plain: b tau^2 / half / "
        "a tau + b tau^2 | better than plain (b tau^2) % | starts not raised % |"
    )
    print("| --- | ---: | ---: | --- | ---: | ---: |")
    for h in HORIZONS:
        r = {k: np.array(v) for k, v in pooled[h].items()}
        p = float(np.median(r["plain"]))
        ratios = " / ".join(f"{np.median(r[k]) / p:.2f}" for k in kinds[1:])
        print(
            f"| {h} d | {len(r['plain'])} | {p / 1e3:.2f} | {ratios} | "
            f"{100 * np.mean(r['b tau^2'] < r['plain']):.0f} | "
            f"{100 * np.mean(np.array(per_start[h]) <= 1.0):.0f} |"
        )


if __name__ == "__main__":
    main()
