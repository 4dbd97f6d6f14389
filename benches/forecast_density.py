"""The forecast's density error after the epoch, measured by the catalog itself.

For start days S (every ``--every`` days of ``$RHOPROP_TEST_DATA/history_2026``), NRLMSIS
2.1 is run on the space weather as known at S (``SpaceWeather.as_of(S, ...)``, one rule
per ``--rules`` entry). The decay of every LEO object's element sets from S - 10 days to
S + 3.5 days (``rhoprop.catalog.decay_intervals``; hindsight after S) measures that
model's daily error c(d) = ln(observed / model) (``estimate_density_correction``). A
prediction from S carries the density ratio of the days before S in each object's fitted
Cd*A/m, so what hurts it is the change after S: delta_k = c(day k after S) - c(the day
before S), k = 1, 2, 3. Printed per start and over all starts: mean (a bias of the
forecast) and RMS of delta_k, per rule, and beside them the change of the drag itself
(ln of each object's decay, day k after S against the day before: what holding the drag
misses, as SGP4's static density does). The rule with the smallest RMS forecasts the
density's level best for predictions started at S.

Last, whether the error known at S foresees its change: the first rule's c estimated from
the intervals that ended by S alone (what a forecaster has), its last day's departure from
its mean over those days, against delta_k: the correlation and the RMS of delta_k left
after the best line, beside its standard deviation (a correction relaxing to the model
would use the slope).

Run:  python benches/forecast_density.py [--rules "1,1,2;1,1,1"] [--every 2]
"""

from __future__ import annotations

import argparse
import json
import os
import time
import warnings
from pathlib import Path

import numpy as np
from catalog_realism import as_of_options
from tables import slashed

import rhoprop as rp
from machine import describe, info
from rhoprop import catalog
from rhoprop.density import Msis

HISTORY = "history_2026/celestrak_stations_weather_amateur_20260228-20260430.txt.gz"


def held(iv: catalog.DecayIntervals, start: np.datetime64) -> np.ndarray | None:
    """The change of the drag itself (what holding it, as SGP4's static density does,
    misses): per object ln(decay) of day k after the start minus that of the day before,
    the median over objects, k = 1..3."""
    day = np.floor((iv.middle - start) / np.timedelta64(1, "D")).astype(int)
    ok = iv.decay > 0
    per: list[list[float]] = [[], [], []]
    for o in np.unique(iv.norad_id):
        before = (iv.norad_id == o) & (day == -1) & ok
        if not before.any():
            continue
        ref = np.log(iv.decay[before]).mean()
        for k in range(3):
            after = (iv.norad_id == o) & (day == k) & ok
            if after.any():
                per[k].append(float(np.log(iv.decay[after]).mean() - ref))
    if not all(per):
        return None
    return np.array([np.median(p) for p in per])


def departure(iv: catalog.DecayIntervals, start: np.datetime64) -> float | None:
    """The model's error on the day before ``start`` less its mean over the days before,
    from the intervals that ended by ``start`` (known then; the estimate takes only
    those), or None where it lacks."""
    c = catalog.estimate_density_correction(iv, start)
    last = start.astype("datetime64[D]") - np.timedelta64(1, "D")
    if len(c.days) < 4 or c.days[-1] != last:
        return None
    return float(c.level[-1] - c.level.mean())


def deltas(
    sets: list, start: np.datetime64, rule: dict
) -> tuple[np.ndarray, np.ndarray, float | None] | None:
    """(delta_k, held change, departure known at the start) (k = 1..3) of one start under
    one as_of rule, or None where a day lacks."""
    model = Msis("2.1", space_weather=rp.SpaceWeather().as_of(start, **rule))
    later = start + np.timedelta64(3 * 86400 + 43200, "s")
    since = start - np.timedelta64(10, "D")
    iv = catalog.decay_intervals(sets, model, through=later, since=since)
    c = catalog.estimate_density_correction(iv, later)
    day0 = start.astype("datetime64[D]")
    level = dict(zip(c.days, c.level, strict=True))
    want = [day0 - np.timedelta64(1, "D")] + [day0 + np.timedelta64(k, "D") for k in range(3)]
    hold = held(iv, start)
    if not all(d in level for d in want) or hold is None:
        return None
    change = np.array([level[d] - level[want[0]] for d in want[1:]])
    return change, hold, departure(iv, start)


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--first", default="2026-03-06")
    parser.add_argument("--last", default="2026-04-22")
    parser.add_argument("--every", type=int, default=2)
    parser.add_argument(
        "--rules",
        default="1,1,2",
        help="as_of rules F107_DAYS,AP_DAYS,AP_RELAX_DAYS[,AP_TARGET[,recurrence]] "
        "separated by ';' (1,1,2: the library's default)",
    )
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = parser.parse_args()
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data"))
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    sets = catalog.load(data / HISTORY, history="each", errors="record").objects
    rules = {}
    for text in args.rules.split(";"):
        rules[text] = as_of_options(text)
    starts = np.arange(
        np.datetime64(args.first, "D"), np.datetime64(args.last, "D") + 1, args.every
    )
    print(
        "\n| start | rule | delta day 1 / 2 / 3 | drag change day 1 / 2 / 3 |\n"
        "| --- | --- | --- | --- |"
    )
    found: dict[str, list[np.ndarray]] = {k: [] for k in rules}
    kept: list[np.ndarray] = []
    known: list[tuple[float, np.ndarray]] = []
    for start in starts:
        t0 = time.perf_counter()
        for name, rule in rules.items():
            got = deltas(sets, np.datetime64(start, "ns"), rule)
            if got is not None:
                d, hold, dep = got
                found[name].append(d)
                if name == next(iter(rules)):
                    kept.append(hold)
                    if dep is not None:
                        known.append((dep, d))
                print(f"| {start} | {name} | {slashed(d, '+.3f')} | {slashed(hold, '+.3f')} |")
        print(f"<!-- {start}: {time.perf_counter() - t0:.0f} s -->", flush=True)
    print("\n| rule | starts | mean delta day 1 / 2 / 3 | RMS delta day 1 / 2 / 3 |")
    print("| --- | ---: | --- | --- |")
    summary = {}
    for name, rows in found.items():
        a = np.array(rows)
        mean, rms = a.mean(axis=0), np.sqrt(np.mean(a**2, axis=0))
        summary[name] = {"starts": len(a), "mean": mean.tolist(), "rms": rms.tolist()}
        print(
            f"| {name} | {len(a)} | "
            + " / ".join(f"{x:+.3f}" for x in mean)
            + " | "
            + " / ".join(f"{x:.3f}" for x in rms)
            + " |"
        )
    h = np.array(kept)
    rms_hold = np.sqrt(np.mean(h**2, axis=0))
    summary["held drag"] = {
        "starts": len(h),
        "mean": h.mean(axis=0).tolist(),
        "rms": rms_hold.tolist(),
    }
    print(
        f"| the drag held (SGP4's static density) | {len(h)} | "
        + " / ".join(f"{x:+.3f}" for x in h.mean(axis=0))
        + " | "
        + " / ".join(f"{x:.3f}" for x in rms_hold)
        + " |"
    )
    x = np.array([k[0] for k in known])
    y = np.array([k[1] for k in known])
    print(
        f"\nthe error known at the start ({len(x)} starts, rule {next(iter(rules))}): its "
        "departure from its mean over the days before, against delta_k"
    )
    print("| day | correlation | best slope | SD delta_k | SD left after the slope |")
    print("| ---: | ---: | ---: | ---: | ---: |")
    reversion = []
    for k in range(3):
        slope = float(np.polyfit(x, y[:, k], 1)[0])
        left = y[:, k] - np.polyval(np.polyfit(x, y[:, k], 1), x)
        r = float(np.corrcoef(x, y[:, k])[0, 1])
        rms, rms_left = float(np.std(y[:, k])), float(np.sqrt(np.mean(left**2)))
        reversion.append({"correlation": r, "slope": slope, "sd": rms, "sd_left": rms_left})
        print(f"| {k + 1} | {r:+.2f} | {slope:+.2f} | {rms:.3f} | {rms_left:.3f} |")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "forecast_density.json").write_text(
        json.dumps({**info(), "rules": summary, "known_error": reversion}, indent=1)
    )


if __name__ == "__main__":
    main()
