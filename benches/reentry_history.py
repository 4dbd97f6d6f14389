"""Reentry windows from element-set histories, run as a forecaster runs them and judged on
hour-level reentry times where they exist.

Cases (``$RHOPROP_TEST_DATA``):

- ``history_2026``: the natural reentries of ``natural_reentries_20260301-20260430.csv``
  (8 objects, 7-112 element sets each). For each lead L of ``--leads`` (days) the start is
  S = reference - L; the input is every element set of the object in the 2 days before S
  (a user's history file), none later; objects without one are skipped at that lead.
- ``2022-2023``: the objects of ``reentry/`` with an element set 1-7 days before their
  SATCAT decay day (as ``benches/reentry.py``): the earliest such set, with the object's
  earlier sets as its history; S is that set's epoch.

Reference: the CORDS time (``reentry/cords_reentry_times_2022_2023.jsonl``, the 2026 CSV's
"CORDS ... +-Nh") with its uncertainty, else the SATCAT decay day (the reference is its
middle, the truth interval the whole UTC day).

Settings: "fitted" (the newest element set, state and Cd*A/m fitted), "history"
(``history="fit"``, what ``rp.catalog.reentry``'s default "auto" does with a history: the
fit also takes the earlier sets within ``rp.catalog.HISTORY_DAYS``) and, for the 2026
cases only, "sensor" (``--settings history,sensor``): "history" with NRLMSIS corrected by
the catalog density sensor (``rp.catalog.corrected_model``), measured from the decay of
every other object of ``history_2026`` up to S (the reentering object left out);
drivers: "forecast" (``SpaceWeather.as_of(S)``, the library's forecast with its sigma)
and/or "hindcast" (the record as observed).

Scored per case, for each window probability of ``--levels`` (default 95 % and 80 %,
``ReentryResult.window``): held = the window overlaps the truth interval, a window still
open at the horizon (its end beyond it) or never opened is a miss; width = window /
remaining life (closed windows); and error = |median - reference| / remaining life
(reference - the element set's epoch). Printed per case (the first level's window), then
per source, setting and drivers: held %, median width and open windows per level, median
error, median log(predicted / actual remaining life). The goals set for these windows:
held >= 80 %, median width <= 60 %, median error <= 15 %.

Run:  RHOPROP_TEST_DATA=../shared/data python benches/reentry_history.py
          [--leads 1,2,3,5,7] [--members 200] [--horizon-days 12]
          [--settings fitted,history] [--drivers forecast|hindcast|both]
          [--sources 2026,2022-2023] [--levels 0.95,0.8]
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import os
import re
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from history_days import HISTORY, jd, read_history
from reentry import choose

import rhoprop as rp
from machine import describe, peak_rss_mb

HOUR = np.timedelta64(3600, "s")
DAY = 24 * HOUR


@dataclasses.dataclass
class Case:
    """One prediction: the element sets given (3-line text, oldest first), the start S
    (ns, UTC), the reference time and the half-width of its truth interval."""

    source: str
    norad: int
    lead_days: float
    start: np.datetime64
    sets: list[tuple[str, str, str]]
    reference: np.datetime64
    half_width: np.timedelta64
    truth: str


def cases_2026(root: Path, leads: list[float]) -> list[Case]:
    """The natural reentries of the 2026 history at each lead."""
    history = read_history(root / HISTORY)
    out = []
    with open(root / "history_2026" / "natural_reentries_20260301-20260430.csv") as f:
        for row in csv.DictReader(f):
            norad = int(row["norad"])
            m = re.match(r"CORDS (\S+)Z \+-(\d+)h", row["decay_source"])
            if m:
                ref = np.datetime64(m.group(1), "ns")
                half, truth = int(m.group(2)) * HOUR, "CORDS"
            else:
                ref = np.datetime64(row["decay_day"], "ns") + DAY / 2
                half, truth = DAY / 2, "SATCAT day"
            for lead in leads:
                start = ref - np.timedelta64(int(lead * 86400), "s")
                t0 = jd(start)
                sets = [s[:3] for s in history[norad] if t0 - 2.0 <= s[3] < t0]
                if sets:
                    out.append(Case("2026", norad, lead, start, sets, ref, half, truth))
    return out


def cases_2022_2023(root: Path) -> list[Case]:
    """The reentry/ objects from their earliest element set 1-7 days before the decay day,
    with their earlier sets."""
    chosen, decay, history = choose(root / "reentry")
    cords = {}
    with open(root / "reentry" / "cords_reentry_times_2022_2023.jsonl") as f:
        for line in f:
            rec = json.loads(line)
            cords[int(rec["norad"])] = rec
    out = []
    for name, l1, l2 in chosen:
        norad = int(l1[2:7])
        epoch = element_epoch(l1)
        day = decay[norad].astype("datetime64[ns]")
        rec = cords.get(norad)
        if rec is not None and day <= np.datetime64(rec["time"][:-1], "ns") < day + DAY:
            ref = np.datetime64(rec["time"][:-1], "ns")
            half, truth = int(rec["uncertaintyHours"]) * HOUR, "CORDS"
        else:
            ref, half, truth = day + DAY / 2, DAY / 2, "SATCAT day"
        lead = float((ref - epoch) / DAY)
        sets = [*history[norad], (name, l1, l2)]
        out.append(Case("2022-2023", norad, lead, epoch, sets, ref, half, truth))
    return out


def element_epoch(line1: str) -> np.datetime64:
    """A TLE line 1's epoch (UTC, ns)."""
    year = int(line1[18:20])
    year += 2000 if year < 57 else 1900
    days = float(line1[20:32])
    return np.datetime64(f"{year}-01-01", "ns") + np.timedelta64(
        round((days - 1.0) * 86400e9), "ns"
    )


def run_case(
    case: Case,
    record: rp.SpaceWeather,
    setting: str,
    drivers: str,
    args: argparse.Namespace,
    catalog_sets: list[Any] | None = None,
) -> dict[str, Any]:
    """One case's window and its score; ``catalog_sets``: every element set of the 2026
    history as catalog objects, for the "sensor" setting."""
    weather = record.as_of(case.start) if drivers == "forecast" else record
    model: Any = rp.density.Msis("2.1", space_weather=weather)
    if setting == "sensor":
        others = sorted({o.norad_id for o in catalog_sets or []} - {case.norad})
        model, _ = rp.catalog.corrected_model(
            catalog_sets or [], model, case.start, calibration_ids=others
        )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "case.tle"
        path.write_text("".join(f"{n}\n{a}\n{b}\n" for n, a, b in case.sets))
        objects = rp.catalog.load(path, history="each").objects
    res = rp.catalog.reentry(
        objects,
        model,
        method=rp.MonteCarlo(n=args.members),
        duration=args.horizon_days * 86400.0,
        history="newest" if setting == "fitted" else "fit",
    )
    epoch = res.objects[0].state.epoch
    lo, med, hi = res.epoch_q025[0], res.epoch_median[0], res.epoch_q975[0]
    remaining = float((case.reference - epoch) / DAY)
    truth_lo, truth_hi = case.reference - case.half_width, case.reference + case.half_width
    levels = {}
    for level in args.levels:
        a, b = (x[0] for x in res.window(level))
        closed = not (np.isnat(a) or np.isnat(b))
        levels[level] = {
            "held": closed and bool(a <= truth_hi) and bool(b >= truth_lo),
            "open": not closed,
            "width": float((b - a) / DAY) / remaining if closed else None,
        }
    down = not np.isnat(med)
    return {
        **levels[args.levels[0]],
        "levels": levels,
        "error": abs(float((med - case.reference) / DAY)) / remaining if down else None,
        "log_bias": float(np.log(float((med - epoch) / DAY) / remaining)) if down else None,
        "window": (lo, med, hi),
    }


def short(t: np.datetime64) -> str:
    return "-" if np.isnat(t) else str(t.astype("datetime64[m]"))


def summary(rows: list[dict[str, Any]], levels: list[float]) -> str:
    """Cases, then per window level held % / median width % / open, then median error
    and bias."""
    errors = [r["error"] for r in rows if r["error"] is not None]
    biases = [r["log_bias"] for r in rows if r["log_bias"] is not None]

    def med(v: list[float]) -> str:
        return f"{100 * np.median(v):.0f} %" if v else "-"

    cells = [str(len(rows))]
    for level in levels:
        part = [r["levels"][level] for r in rows]
        widths = [p["width"] for p in part if p["width"] is not None]
        cells.append(
            f"{100 * np.mean([p['held'] for p in part]):.0f} % / {med(widths)} / "
            f"{sum(p['open'] for p in part)}"
        )
    cells += [med(errors), f"{np.median(biases) if biases else float('nan'):+.2f}"]
    return " | ".join(cells)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--leads", default="1,2,3,5,7", help="days before the reference (2026)")
    parser.add_argument("--members", type=int, default=200)
    parser.add_argument("--horizon-days", type=float, default=12.0)
    parser.add_argument("--settings", default="fitted,history")
    parser.add_argument("--drivers", choices=("forecast", "hindcast", "both"), default="both")
    parser.add_argument("--sources", default="2026,2022-2023")
    parser.add_argument(
        "--levels", default="0.95,0.8", help="window probabilities scored (first: per case)"
    )
    args = parser.parse_args()
    args.levels = [float(x) for x in args.levels.split(",")]
    root = os.environ.get("RHOPROP_TEST_DATA")
    if not root:
        raise SystemExit("set RHOPROP_TEST_DATA to the reference data (../shared/data)")
    print(describe())
    leads = [float(x) for x in args.leads.split(",")]
    sources = args.sources.split(",")
    cases = (cases_2026(Path(root), leads) if "2026" in sources else []) + (
        cases_2022_2023(Path(root)) if "2022-2023" in sources else []
    )
    modes = ("forecast", "hindcast") if args.drivers == "both" else (args.drivers,)
    settings = args.settings.split(",")
    record = rp.SpaceWeather()
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    catalog_sets = None
    if "sensor" in settings:
        catalog_sets = rp.catalog.load(
            Path(root) / HISTORY, history="each", errors="record"
        ).objects
    print(
        f"{len(cases)} cases; {args.members} members, horizon {args.horizon_days:g} days, "
        "NRLMSIS 2.1\n"
    )
    print(
        "| source | NORAD | lead d | sets | truth | reference | setting, drivers | 2.5 % | "
        "median | 97.5 % | held | error % | width % |"
    )
    print("| --- | ---: | ---: | ---: | --- | --- | --- | --- | --- | --- | --- | ---: | ---: |")
    scored: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    t0 = time.perf_counter()
    for case in cases:
        for setting in settings:
            if setting == "sensor" and case.source != "2026":
                continue
            for drivers in modes:
                r = run_case(case, record, setting, drivers, args, catalog_sets)
                r["case"] = case
                scored.setdefault((case.source, setting, drivers), []).append(r)
                lo, med, hi = r["window"]
                err = "-" if r["error"] is None else f"{100 * r['error']:.0f}"
                wid = "-" if r["width"] is None else f"{100 * r['width']:.0f}"
                print(
                    f"| {case.source} | {case.norad} | {case.lead_days:.2f} | {len(case.sets)} | "
                    f"{case.truth} | {short(case.reference)} | {setting}, {drivers} | "
                    f"{short(lo)} | {short(med)} | {short(hi)} | "
                    f"{'yes' if r['held'] else 'no'} | {err} | {wid} |",
                    flush=True,
                )
    print(f"\n{time.perf_counter() - t0:.0f} s, peak RSS {peak_rss_mb():.0f} MB\n")
    windows = " | ".join(f"{100 * v:g} % window: held / width / open" for v in args.levels)
    print(f"| source, setting, drivers | group | cases | {windows} | median error | bias (log) |")
    print("| --- | --- | ---: | " + "--- | " * len(args.levels) + "---: | ---: |")
    for (source, setting, drivers), rows in scored.items():
        label = f"{source}, {setting}, {drivers}"
        print(f"| {label} | all | {summary(rows, args.levels)} |")
        cords = [r for r in rows if r["case"].truth == "CORDS"]
        if cords and len(cords) < len(rows):
            print(f"| {label} | CORDS | {summary(cords, args.levels)} |")
        for lo, hi in ((0, 2), (2, 4), (4, 8)):
            part = [r for r in rows if lo < r["case"].lead_days <= hi]
            if part:
                print(f"| {label} | lead {lo}-{hi} d | {summary(part, args.levels)} |")


if __name__ == "__main__":
    main()
