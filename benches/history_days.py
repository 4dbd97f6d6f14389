"""Predictions judged on every day of a dense element-set history, as a forecaster runs them.

``$RHOPROP_TEST_DATA/history_2026`` holds every element set CelesTrak published for its
stations, weather and amateur groups from 2026-02-28 to 2026-04-30 (about one per 6 hours
per object). Each start day S at 00:00 UTC (every ``--every`` days from 2026-03-02):

- objects: LEO (perigee and apogee 200-700 km at S) with an element set in the 2 days
  before S, none of the names of ``catalog_realism.EXCLUDE`` (crewed stations, cargo,
  constellations) and no manoeuvre in the window: no fall of the mean motion between
  consecutive element sets beyond ``RAISE_REV_PER_DAY`` (drag only raises it);
- prediction: every element set of the 2 days before S, run with the library's defaults
  (``catalog.load`` then ``propagate_catalog``: state and Cd*A/m fitted to the newest
  element set, CCSP, NRLMSIS 2.1; ``--history`` adds the fit of the newest with the others
  of its last day, ``load(history="fit")``) on the space weather as known at S
  (``SpaceWeather.as_of(S)``: forecast mode);
  ``--drivers both`` adds the hindcast (the record as observed) beside it;
- truth: for each horizon H (1, 3, 7 days) the object's element set whose epoch is
  nearest S + H (within 12 h), its SGP4 state at its own epoch, the truth's published
  accuracy added to the predicted covariance (as ``catalog_realism``);
- baseline: SGP4 of the same start element set to the truth's epoch.

Printed per start and pooled per horizon: median / p90 along-track error (rhoprop and SGP4)
and their ratio, the share of objects better than SGP4, along-track inside 1/2/3 sigma and
the RTN Mahalanobis inside 1/2/3 sigma, as ``catalog_realism.figures``.

Run:  python benches/history_days.py [--every 1] [--horizons 1,3,7] [--drivers forecast]
      [--initial-covariance object] [--dump FILE.npz]   (``covariance_parts.py`` reads dumps)
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import dataclasses
import gzip
import json
import os
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from catalog_realism import EXCLUDE, altitudes_km, as_of_options, figures, sgp4_state
from sgp4.api import Satrec

import rhoprop as rp
from machine import describe, info
from rhoprop import catalog
from rhoprop.catalog import density_sensor
from rhoprop.density import Msis
from rhoprop.frames import rtn_basis

HISTORY = "history_2026/celestrak_stations_weather_amateur_20260228-20260430.txt.gz"


def read_history(path: Path) -> dict[int, list[tuple[str, str, str, float]]]:
    """Element sets per NORAD id: (name, line 1, line 2, epoch as a Julian date)."""
    lines = gzip.open(path, "rt").read().splitlines()
    out: dict[int, list[tuple[str, str, str, float]]] = {}
    for i in range(0, len(lines) - 2, 3):
        name, l1, l2 = lines[i].strip(), lines[i + 1], lines[i + 2]
        sat = Satrec.twoline2rv(l1, l2)
        out.setdefault(sat.satnum, []).append((name, l1, l2, sat.jdsatepoch + sat.jdsatepochF))
    for sets in out.values():
        sets.sort(key=lambda s: s[3])
    return out


#: A fall of the mean motion between consecutive element sets larger than this (rev/day)
#: is an orbit raise: drag only raises the mean motion, and the element sets' own noise
#: stays within 2e-4 rev/day for the LEO objects of the history (an ISS reboost: -0.007).
RAISE_REV_PER_DAY = 5e-4


def manoeuvres(sets: list[tuple[str, str, str, float]]) -> bool:
    """Whether the mean motion falls between consecutive element sets (an orbit raise)."""
    n = [Satrec.twoline2rv(s[1], s[2]).no_kozai * 1440 / (2 * np.pi) for s in sets]
    return bool(np.any(np.diff(n) < -RAISE_REV_PER_DAY))


def jd(epoch: np.datetime64) -> float:
    return float((epoch - np.datetime64("2000-01-01T12:00")) / np.timedelta64(1, "D")) + 2451545.0


def start_day(
    start: np.datetime64,
    history: dict[int, list[tuple[str, str, str, float]]],
    clean: set[int],
    horizons: list[float],
    model: Any,
    threads: int,
    drags: dict[int, tuple[float, float, int]] | None = None,
    together: bool = False,
    initial: str = "object",
) -> dict[float, tuple[dict, dict]]:
    """Predictions and truths of one start: per horizon (pred, truth) dicts by NORAD id.
    ``drags``: Cd*A/m per object from the catalog density sensor, replacing the fitted one
    (the state stays the fit's). The input is every element set of the 2 days before the
    start, as a user's history file holds them: ``load``'s default predicts from the
    newest; ``together``: from the fit of the newest and the others of its last
    ``rp.catalog.HISTORY_DAYS`` (``load(history="fit")``). ``initial``: the
    initial covariance, :data:`INITIAL_COVARIANCES`."""
    t0 = jd(start)
    chosen: dict[int, tuple[str, str, str, float]] = {}
    for norad in clean:
        before = [s for s in history[norad] if t0 - 2.0 <= s[3] < t0]
        if not before:
            continue
        lo, hi = altitudes_km(Satrec.twoline2rv(before[-1][1], before[-1][2]))
        if lo >= 200 and hi <= 700:
            chosen[norad] = before[-1]
    given = {n: [s for s in history[n] if t0 - 2.0 <= s[3] < t0] for n in chosen}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "start.tle"
        path.write_text("".join(f"{s[0]}\n{s[1]}\n{s[2]}\n" for v in given.values() for s in v))
        # Fitted once here as propagate_catalog's fit="auto" would (every object's
        # Cd*A/m comes from its element set), not again for each horizon.
        cat = catalog.load(
            path,
            fit=rp.catalog.FitSettings(model, threads=threads),
            errors="record",
            history="fit" if together else "newest",
        )
    objects = {o.norad_id: o for o in cat.objects}
    for norad, (value, _, _) in (drags or {}).items():
        if norad in objects:
            objects[norad] = dataclasses.replace(objects[norad], drag_parameter=value)
    out: dict[float, tuple[dict, dict]] = {}
    for h in horizons:
        truth: dict[int, dict[str, Any]] = {}
        for norad, s in chosen.items():
            later = [x for x in history[norad] if abs(x[3] - (t0 + h)) <= 0.5]
            if not later or norad not in objects:
                continue
            tr = min(later, key=lambda x: abs(x[3] - (t0 + h)))
            s1, s2 = Satrec.twoline2rv(s[1], s[2]), Satrec.twoline2rv(tr[1], tr[2])
            truth[norad] = {
                "epoch": rp.time.from_jd(s2.jdsatepoch, s2.jdsatepochF),
                "state": sgp4_state(s2, s2.jdsatepoch, s2.jdsatepochF),
                "sgp4": sgp4_state(s1, s2.jdsatepoch, s2.jdsatepochF),
            }

        def one(norad: int, truth: dict = truth) -> tuple[int, dict[str, Any]]:
            res = catalog.propagate_catalog(
                [objects[norad]],
                model,
                truth[norad]["epoch"],
                output_step=1e9,
                execution=rp.Execution(progress=False, errors="record"),
                initial=rp.catalog.Initial(covariance=INITIAL_COVARIANCES[initial]),
            )
            return norad, {
                "mean": res.mean[0, -1],
                "cov": res.covariance[0, -1],
                "status": str(res.status[0]),
            }

        with cf.ThreadPoolExecutor(threads) as pool:
            pred = dict(pool.map(one, sorted(truth)))
        out[h] = (pred, truth)
    return out


#: ``--initial-covariance``: what each object starts with. "object" is the library's
#: default (a fitted object's TLE accuracy plus its fit's covariance); "fit" the fit's
#: covariance alone; "tle" the TLE accuracy alone, with the regime's whole drift;
#: "nodrift" the TLE accuracy without any drift, plus the fit's; "paper" the near-zero
#: one (what is left is the density's and Cd*A/m's growth). ``covariance_parts.py``
#: compares the ``--dump`` files of such runs.
INITIAL_COVARIANCES: dict[str, Any] = {
    "object": "object",
    "tle": "tle",
    "paper": "paper",
    "fit": lambda obj: obj.fit.covariance[:6, :6] if obj.fit is not None else obj.covariance,
    "nodrift": lambda obj: (
        catalog.tle_covariance(
            obj.state, dataclasses.replace(catalog.tle_accuracy(obj.state), drift_rate=0.0)
        )
        + (obj.fit.covariance[:6, :6] if obj.fit is not None else 0.0)
    ),
}


def row(label: str, f: dict[str, Any]) -> str:
    e = f["along_track_error_km"]
    ins = [f[f"inside_{k}sigma"] for k in (1, 2, 3)]
    ratio = e["rhoprop_median"] / e["sgp4_median"]
    return (
        f"| {label} | {f['objects']} | {e['rhoprop_median']:.2f} / {e['rhoprop_p90']:.1f} | "
        f"{e['sgp4_median']:.2f} / {e['sgp4_p90']:.1f} | {ratio:.2f} | "
        f"{100 * f['better_than_sgp4']:.0f} | "
        + " / ".join(f"{100 * i['along_track']:.0f}" for i in ins)
        + " | "
        + " / ".join(f"{100 * i['mahalanobis_rtn']:.0f}" for i in ins)
        + " |"
    )


def goal_days(per_start: dict[str, Any], suffix: str) -> dict[str, float]:
    """The per-start-day coverage goals over the starts whose key ends with ``suffix``
    (e.g. "forecast 3 d"): the share of days with the along-track share inside 2 sigma
    in 85-98 % (and the days above and below), inside 3 sigma >= 95 %, and RTN 2 sigma
    >= 85 %."""
    days = [v for k, v in per_start.items() if k.endswith(suffix)]
    two = np.array([v["inside_2sigma"]["along_track"] for v in days])
    three = np.array([v["inside_3sigma"]["along_track"] for v in days])
    rtn = np.array([v["inside_2sigma"]["mahalanobis_rtn"] for v in days])
    return {
        "days": len(days),
        "along_2sigma_in_85_98": float(np.mean((two >= 0.85) & (two <= 0.98))),
        "along_2sigma_above_98": int(np.sum(two > 0.98)),
        "along_2sigma_below_85": int(np.sum(two < 0.85)),
        "along_3sigma_at_least_95": float(np.mean(three >= 0.95)),
        "rtn_2sigma_at_least_85": float(np.mean(rtn >= 0.85)),
    }


def common_mode(pred: dict[tuple[str, int], dict], truth: dict[tuple[str, int], dict]) -> dict:
    """How much of the along-track error one density scale per start explains (hindsight:
    fitted to the truths). Per start, the along-track errors of rhoprop and of SGP4 less
    c times each object's predicted along-track sigma (which scales with its drag), c the
    start's median error / sigma; and the mean of rhoprop's and SGP4's predictions (a
    forecast combination). Ratios are medians of |error| over SGP4's."""
    keys = [k for k in pred if np.all(np.isfinite(pred[k]["mean"]))]
    err, err_sgp4, sigma, start = [], [], [], []
    for k in keys:
        t = truth[k]
        basis = rtn_basis(t["state"][:3], t["state"][3:])
        err.append((basis @ (pred[k]["mean"][:3] - t["state"][:3]))[1])
        err_sgp4.append((basis @ (t["sgp4"][:3] - t["state"][:3]))[1])
        sigma.append(np.sqrt((basis @ pred[k]["cov"][:3, :3] @ basis.T)[1, 1]))
        start.append(k[0])
    e, s, sig, st = np.array(err), np.array(err_sgp4), np.array(sigma), np.array(start)

    def less_common(x: np.ndarray) -> np.ndarray:
        out = x.copy()
        for day in np.unique(st):
            m = st == day
            out[m] = x[m] - np.median(x[m] / sig[m]) * sig[m]
        return out

    def med(x: np.ndarray) -> float:
        return float(np.median(np.abs(x)))

    er, sr = less_common(e), less_common(s)
    return {
        "explained_rhoprop": 1 - med(er) / med(e),
        "explained_sgp4": 1 - med(sr) / med(s),
        "residual_ratio": med(er) / med(sr),
        "residual_better": float(np.mean(np.abs(er) < np.abs(sr))),
        "mean_with_sgp4_ratio": med((e + s) / 2) / med(s),
    }


def dump(path: str, pooled: dict[tuple[str, float], tuple[dict, dict]]) -> None:
    """Every valid prediction as arrays: mode, horizon (days), start, NORAD id, RTN error
    of rhoprop and of SGP4 (m, the truth's RTN frame), the predicted RTN position
    covariance and the truth's own (TLE accuracy), m^2."""
    cols: dict[str, list[Any]] = {
        k: [] for k in ("mode", "horizon", "start", "norad", "error", "sgp4", "cov", "truth")
    }
    for (mode, h), (pred, truth) in pooled.items():
        for key, p in pred.items():
            if not (np.all(np.isfinite(p["mean"])) and np.all(np.isfinite(p["cov"]))):
                continue
            t = truth[key]
            basis = rtn_basis(t["state"][:3], t["state"][3:])
            state = rp.OrbitState(t["epoch"], t["state"][:3], t["state"][3:])
            cols["mode"].append(mode)
            cols["horizon"].append(h)
            cols["start"].append(key[0])
            cols["norad"].append(key[1])
            cols["error"].append(basis @ (p["mean"][:3] - t["state"][:3]))
            cols["sgp4"].append(basis @ (t["sgp4"][:3] - t["state"][:3]))
            cols["cov"].append(basis @ p["cov"][:3, :3] @ basis.T)
            cols["truth"].append(basis @ catalog.tle_covariance(state)[:3, :3] @ basis.T)
    np.savez(path, **{k: np.array(v) for k, v in cols.items()})


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--first", default="2026-03-02", help="first start day")
    parser.add_argument("--last", default="2026-04-22", help="last start day")
    parser.add_argument("--every", type=int, default=1, help="days between starts")
    parser.add_argument("--horizons", default="1,3,7", help="days, comma-separated")
    parser.add_argument("--drivers", choices=("forecast", "hindcast", "both"), default="forecast")
    parser.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    parser.add_argument(
        "--as-of",
        default=None,
        help="F107_DAYS,AP_DAYS,AP_RELAX_DAYS[,AP_TARGET[,recurrence]] of SpaceWeather.as_of "
        "(default: the library's)",
    )
    parser.add_argument(
        "--sensor",
        action="store_true",
        help="judge the objects of odd NORAD id only, with and without the catalog density "
        "sensor (corrected by the decay of the history's even-id objects up to the start)",
    )
    parser.add_argument(
        "--oracle",
        action="store_true",
        help="with --sensor: add the hindsight correction (measured through the horizon)",
    )
    parser.add_argument(
        "--sensor-drag",
        action="store_true",
        help="with --sensor: each judged object's Cd*A/m from its own decay against the "
        "corrected model, in place of the one fitted to its element set",
    )
    parser.add_argument(
        "--history",
        action="store_true",
        help="beside the default, each object's element sets of the last "
        "rp.catalog.HISTORY_DAYS fitted together (load(history='fit'))",
    )
    parser.add_argument(
        "--initial-covariance",
        choices=tuple(INITIAL_COVARIANCES),
        default="object",
        help="each object's initial covariance (default: the library's, 'object')",
    )
    parser.add_argument(
        "--dump",
        default=None,
        help="also write every prediction (RTN error, predicted and truth covariance, SGP4's "
        "error) to this .npz, for studies of the covariance",
    )
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = parser.parse_args()
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data"))
    history = read_history(data / HISTORY)
    clean = {
        n
        for n, sets in history.items()
        if not any(w in sets[-1][0].upper() for w in EXCLUDE) and not manoeuvres(sets)
    }
    print(f"{len(history)} objects in the history, {len(clean)} without a manoeuvre")
    configs = ("default",)
    if args.sensor:
        configs = ("default", "sensor", "oracle") if args.oracle else ("default", "sensor")
        clean = {n for n in clean if n % 2 == 1}
        calibration = sorted(n for n in history if n % 2 == 0)
        sets = catalog.load(data / HISTORY, history="each", errors="record").objects
        print(f"{len(calibration)} calibration objects (even NORAD id), {len(clean)} judged")
    if args.history:
        if args.sensor:
            parser.error("--history and --sensor are separate comparisons: give one")
        configs = ("default", "history")
    horizons = [float(x) for x in args.horizons.split(",")]
    modes = ("forecast", "hindcast") if args.drivers == "both" else (args.drivers,)
    record = rp.SpaceWeather()
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    starts = np.arange(
        np.datetime64(args.first, "D"), np.datetime64(args.last, "D") + 1, args.every
    )
    modes = tuple(f"{m} {c}" if len(configs) > 1 else m for m in modes for c in configs)
    pooled = {(m, h): ({}, {}) for m in modes for h in horizons}
    per_start: dict[str, Any] = {}
    print(
        "\n| start, drivers, horizon | objects | along-track median / p90 km | SGP4 median / "
        "p90 km | ratio | better than SGP4 % | inside 1/2/3 sigma along-track % | RTN "
        "Mahalanobis 1/2/3 sigma % |"
    )
    print("| --- | ---: | --- | --- | ---: | ---: | --- | --- |")
    for start in starts:
        t_start = np.datetime64(start, "ns")
        for mode in modes:
            weather = record
            if mode.startswith("forecast"):
                weather = record.as_of(t_start, **as_of_options(args.as_of))
            t0 = time.perf_counter()
            model: Any = Msis("2.1", space_weather=weather)
            drags = None
            if mode.endswith("sensor") or mode.endswith("oracle"):
                # Measured with the start's own model: the forecast record's 81-day means
                # differ from the observed record's before the start too. The oracle
                # measures through the predictions (hindsight): the most a correction of
                # the density's level could give.
                known = t_start
                if mode.endswith("oracle"):
                    known = t_start + np.timedelta64(int(max(horizons) * 86400) + 43200, "s")
                intervals = density_sensor.decay_intervals(sets, model, through=known)
                correction = density_sensor.estimate_density_correction(
                    intervals, known, calibration_ids=calibration
                )
                model = rp.density.CatalogCorrected(model, correction)
                if args.sensor_drag:
                    drags = density_sensor.drag_parameters(intervals, correction)
                    drags = {n: d for n, d in drags.items() if n in clean}
            together = mode.endswith("history")
            res = start_day(
                t_start,
                history,
                clean,
                horizons,
                model,
                args.threads,
                drags,
                together,
                args.initial_covariance,
            )
            for h, (pred, truth) in res.items():
                if not pred:
                    continue
                f = figures(pred, truth)
                key = f"{start} {mode} {h:g} d"
                per_start[key] = f
                print(row(key, f), flush=True)
                pooled[(mode, h)][0].update({(str(start), k): v for k, v in pred.items()})
                pooled[(mode, h)][1].update({(str(start), k): v for k, v in truth.items()})
            print(f"<!-- {start} {mode}: {time.perf_counter() - t0:.1f} s -->", flush=True)
    print("\npooled:")
    summary = {}
    for (mode, h), (pred, truth) in pooled.items():
        if pred:
            f = figures(pred, truth)
            days = [
                v["along_track_error_km"]["rhoprop_median"]
                / v["along_track_error_km"]["sgp4_median"]
                for k, v in per_start.items()
                if k.endswith(f"{mode} {h:g} d")
            ]
            f["start_days_at_most_sgp4"] = float(np.mean(np.array(days) <= 1.0))
            summary[f"{mode} {h:g} d"] = f
            print(row(f"all, {mode}, {h:g} d", f))
            print(
                f"  start days with median <= SGP4's: {100 * f['start_days_at_most_sgp4']:.0f} %"
                f" of {len(days)}"
            )
            g = goal_days(per_start, f"{mode} {h:g} d")
            f["goal_days"] = g
            print(
                f"  start days with along-track inside 2 sigma in 85-98 %: "
                f"{100 * g['along_2sigma_in_85_98']:.0f} % ({g['along_2sigma_above_98']} "
                f"above, {g['along_2sigma_below_85']} below); inside 3 sigma >= 95 %: "
                f"{100 * g['along_3sigma_at_least_95']:.0f} %; RTN 2 sigma >= 85 %: "
                f"{100 * g['rtn_2sigma_at_least_85']:.0f} %; median |error| / sigma "
                "along-track: " + f"{f['median_error_over_sigma_rtn'][1]:.2f} (Gaussian 0.67)"
            )
            c = common_mode(pred, truth)
            f["common_mode"] = c
            print(
                f"  one density scale per start (hindsight) explains "
                f"{100 * c['explained_rhoprop']:.0f} % of rhoprop's median error and "
                f"{100 * c['explained_sgp4']:.0f} % of SGP4's; what is left: "
                f"{c['residual_ratio']:.2f} x SGP4's, better for "
                f"{100 * c['residual_better']:.0f} %; the mean of rhoprop's and SGP4's "
                f"predictions: {c['mean_with_sgp4_ratio']:.2f} x SGP4's"
            )
    if args.dump:
        dump(args.dump, pooled)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "history_days.json").write_text(
        json.dumps({**info(), "per_start": per_start, "pooled": summary}, indent=1)
    )


if __name__ == "__main__":
    main()
