"""Realism of catalog predictions on real data, week by week: CelesTrak "active" snapshots
of 2023 (``$RHOPROP_TEST_DATA/catalogs`` and ``catalogs/history``, default
``../shared/data``) predicted forward and compared with the same objects' element sets
of a later snapshot.

Development weeks (start snapshot -> truth snapshot): 2023-07-04 -> 07-07,
2023-08-07 -> 08-13, 2023-08-13 -> 08-20, 2023-11-13 -> 11-19 (``--weeks`` picks some by
start date). Other weeks are kept apart to judge the project: settings are chosen on
these four together, never on one.

Selection per week: objects in both snapshots with perigee and apogee altitude 200-700 km
whose truth element set is at least ``--min-gap`` days (default 2) newer; manoeuvring
constellations and crewed stations excluded by name (Starlink, OneWeb, Iridium,
Globalstar, Orbcomm, Kuiper, ISS, CSS modules, crew/cargo vehicles), and objects whose
mean motion fell between the two snapshots (an orbit raise: drag only raises it). Then
``--objects`` of them spread evenly over the NORAD-ordered list.

Truth: the later element set's own state at its epoch (SGP4 at t = 0, its most accurate
point); each object is predicted from its start epoch to that epoch. Compared there:
SGP4 of the start element set (the baseline) and rhoprop's mean and covariance
(``propagate_catalog`` with its defaults: CCSP, NRLMSIS 2.1). Drivers (``--drivers``):
``forecast`` (default) runs each object as a forecaster would, on the bundled record as
of its start element set's epoch (``SpaceWeather.as_of`` at the start of its 3-hour ap
interval: observed before it, persistence after; ``--as-of-at start``: as of the start
snapshot's day for every object, as before 2026-12-06, when most element sets of a
snapshot are later than its day's 00:00);
``hindcast`` on the record as observed through the prediction (no driver-forecast error,
flattering); ``both`` prints the hindcast beside the forecast, its configurations
suffixed ``/hindcast``. Errors are in the
truth's RTN frame. The truth is itself a TLE state: its published accuracy
(``rp.catalog.tle_covariance``) is added to the predicted covariance for the sigma tests
(``--truth-covariance none`` leaves it out).

Configurations (``--configs``, comma-separated):
  default  ``load(path)`` and ``propagate_catalog`` as they come: state and Cd*A/m from
           the element set (B*), the library's defaults otherwise.
  fit      ``load(path, fit=True, model=...)``: state and Cd*A/m fitted to the start
           element set's SGP4 positions.
  history  the same, given every snapshot up to the start
           (``load([files], fit=True, history="fit")``):
           each object's element sets of the last ``rp.catalog.HISTORY_DAYS`` fitted
           together (Levit & Marshall 2011).

Printed per week and configuration, and over all weeks: median and 90th percentile of
|along-track error| for rhoprop's mean and for SGP4; the predicted along-track sigma
(median); the fractions inside 1, 2 and 3 sigma along-track (|dT| / sigma_T <= k) and by
the RTN-position Mahalanobis distance (d^T P^-1 d <= the chi-square(3) quantile of the 1-D
k-sigma probability: 68.3 / 95.4 / 99.7 %). Goals (every week): median <=
SGP4's (with a history <= 0.7 x SGP4's); along-track inside 2 sigma 85-98 %, inside
3 sigma >= 95 %; RTN Mahalanobis inside 2 sigma >= 85 %.

Diagnosis (of the 08-07 week): ``--per-object`` also writes
``catalog_realism_objects.json``: per week, configuration and object the signed RTN errors
of rhoprop's mean and of SGP4 at the truth epoch (along-track > 0: ahead of the truth, as
too much drag puts it), perigee, span, the Cd*A/m run and the fit's over its prior, the
element sets' decay (SGP4's mean motion, its along-track drag displacement) and NRLMSIS
2.1's mean density along the orbit in the fit window and over the prediction.
``--fit-span START,END`` (days) sets the fit and history configurations' span;
``--space-weather FILE`` drives NRLMSIS 2.1 with another CelesTrak record. None of them
changes the default run or its output.

Run:  python benches/catalog_realism.py [--objects 150] [--weeks 2023-08-13,...]
          [--configs default,fit,history] [--per-object] [--fit-span -1,0]
          [--space-weather FILE]
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import gzip
import json
import os
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import chi2, norm
from sgp4.api import Satrec
from tables import slashed

import rhoprop as rp
from machine import describe, info
from rhoprop import catalog
from rhoprop.density import Msis
from rhoprop.frames import rtn_basis

EXCLUDE = (
    "STARLINK",
    "ONEWEB",
    "IRIDIUM",
    "GLOBALSTAR",
    "ORBCOMM",
    "KUIPER",
    "ISS ",
    "ISS(",
    "CSS ",
    "TIANHE",
    "WENTIAN",
    "MENGTIAN",
    "SHENZHOU",
    "TIANZHOU",
    "PROGRESS",
    "SOYUZ",
    "CREW DRAGON",
    "DRAGON",
    "CYGNUS",
)
EARTH_RADIUS_KM = 6378.135


def data_dir() -> Path:
    root = os.environ.get("RHOPROP_TEST_DATA", str(Path(__file__).parents[2] / "shared/data"))
    return Path(root) / "catalogs"


def read_snapshot(path: Path) -> dict[int, tuple[str, str, str]]:
    """{NORAD id: (name, line 1, line 2)} of a gzipped 3-line TLE file."""
    lines = [ln.rstrip() for ln in gzip.open(path, "rt") if ln.strip()]
    out = {}
    for k in range(0, len(lines) - 2, 3):
        name, l1, l2 = lines[k : k + 3]
        out[int(l1[2:7])] = (name.strip(), l1, l2)
    return out


def altitudes_km(sat: Any) -> tuple[float, float]:
    a = sat.a * EARTH_RADIUS_KM  # sat.a in Earth radii
    return a * (1 - sat.ecco) - EARTH_RADIUS_KM, a * (1 + sat.ecco) - EARTH_RADIUS_KM


#: Perigee and apogee altitudes of the objects selected, km (``--altitudes``).
ALTITUDES_KM = (200.0, 700.0)


def select(first: dict, second: dict, limit: int, min_gap: float) -> list[int]:
    """NORAD ids of one week's objects (see the module docstring)."""
    ids = []
    for norad in sorted(set(first) & set(second)):
        name = first[norad][0].upper()
        if any(word in name for word in EXCLUDE):
            continue
        s1 = Satrec.twoline2rv(*first[norad][1:])
        s2 = Satrec.twoline2rv(*second[norad][1:])
        lo, hi = altitudes_km(s1)
        if lo < ALTITUDES_KM[0] or hi > ALTITUDES_KM[1]:
            continue
        span = (s2.jdsatepoch - s1.jdsatepoch) + (s2.jdsatepochF - s1.jdsatepochF)
        if span < min_gap:
            continue
        if s2.no_kozai < s1.no_kozai * (1 - 1e-6):  # raised: a manoeuvre
            continue
        ids.append(norad)
    if limit and len(ids) > limit:
        pick = np.linspace(0, len(ids) - 1, limit).round().astype(int)
        ids = [ids[i] for i in pick]
    return ids


def sgp4_state(sat: Any, jd: float, jdf: float) -> np.ndarray:
    err, r, v = sat.sgp4(jd, jdf)
    if err:
        return np.full(6, np.nan)
    return np.concatenate([r, v]) * 1e3


def run_config(
    config: str,
    paths: list[Path],
    model: Any,
    truth: dict[int, dict[str, Any]],
    threads: int,
    span: tuple[float, float] | None = None,
) -> tuple[dict[int, dict[str, Any]], float, float, list[Any]]:
    """Predicted mean and covariance at each object's truth epoch with the library's
    defaults (``span``: the fit's, s from the epoch; None the library's); the load (and
    fit) time, the propagation time (s) and the loaded objects."""
    t0 = time.perf_counter()
    if config == "default":
        cat = catalog.load(paths[-1], errors="record")
    elif config == "fit":
        cat = catalog.load(
            paths[-1],
            fit=rp.catalog.FitSettings(model, span=span, threads=threads),
            errors="record",
        )
    else:
        cat = catalog.load(
            paths,
            fit=rp.catalog.FitSettings(model, span=span, threads=threads),
            errors="record",
            history="fit",
        )
    t_load = time.perf_counter() - t0
    objects = [o for o in cat.objects if o.norad_id in truth]

    def one(obj: Any) -> tuple[int, dict[str, Any]]:
        res = catalog.propagate_catalog(
            [obj],
            model,
            truth[obj.norad_id]["epoch"],
            output_step=1e9,
            execution=rp.Execution(progress=False, errors="record"),
        )
        ran = res.objects[0]
        fitted = ran.fit if ran.fit is not None else obj.fit
        return obj.norad_id, {
            "mean": res.mean[0, -1],
            "cov": res.covariance[0, -1],
            "status": str(res.status[0]),
            "drag_parameter": float(ran.drag_parameter),
            "fit": None
            if fitted is None
            else {
                "drag_parameter": float(fitted.drag_parameter),
                "prior": float(fitted.prior),
                "drag_sigma": float(fitted.drag_sigma),
            },
        }

    t0 = time.perf_counter()
    with cf.ThreadPoolExecutor(threads) as pool:
        out = dict(pool.map(one, objects))
    return out, t_load, time.perf_counter() - t0, objects


def figures(
    pred: dict[int, dict[str, Any]],
    truth: dict[int, dict[str, Any]],
    truth_covariance: bool = True,
) -> dict[str, Any]:
    """The realism figures of one configuration (see the module docstring). With
    ``truth_covariance`` the truth's own error (the second element set is a TLE too: the
    published TLE accuracy of its state, ``tle_covariance``) is added to the predicted
    covariance, as the difference of two uncertain states requires."""
    d_t, d_sgp4, sig_t, maha, along, ratios = [], [], [], [], [], []
    invalid: list[str] = []
    for norad, p in pred.items():
        t = truth[norad]
        if not (np.all(np.isfinite(p["mean"])) and np.all(np.isfinite(p["cov"]))):
            invalid.append(f"{norad} {p['status']}")
            continue
        basis = rtn_basis(t["state"][:3], t["state"][3:])
        d = basis @ (p["mean"][:3] - t["state"][:3])
        d_s = basis @ (t["sgp4"][:3] - t["state"][:3])
        cov = p["cov"][:3, :3]
        if truth_covariance:
            state = rp.OrbitState(t["epoch"], t["state"][:3], t["state"][3:])
            cov = cov + catalog.tle_covariance(state)[:3, :3]
        c = basis @ cov @ basis.T
        d_t.append(d[1])
        d_sgp4.append(d_s[1])
        sig_t.append(np.sqrt(c[1, 1]))
        along.append(abs(d[1]) / np.sqrt(c[1, 1]))
        ratios.append(np.abs(d) / np.sqrt(np.diag(c)))
        maha.append(float(d @ np.linalg.solve(c, d)))
    d_t_a, d_s_a = np.abs(d_t), np.abs(d_sgp4)
    along_a, maha_a = np.array(along), np.array(maha)
    out: dict[str, Any] = {
        "objects": len(d_t),
        "without_valid_prediction": invalid,
        "along_track_error_km": {
            "rhoprop_median": float(np.median(d_t_a) / 1e3),
            "rhoprop_p90": float(np.percentile(d_t_a, 90) / 1e3),
            "sgp4_median": float(np.median(d_s_a) / 1e3),
            "sgp4_p90": float(np.percentile(d_s_a, 90) / 1e3),
        },
        "along_track_sigma_km_median": float(np.median(sig_t) / 1e3),
        "better_than_sgp4": float(np.mean(d_t_a < d_s_a)) if len(d_t_a) else float("nan"),
        "mean_squared_mahalanobis": float(np.mean(maha_a)),
        "median_error_over_sigma_rtn": np.median(ratios, axis=0).tolist(),
    }
    for k in (1, 2, 3):
        p = 2 * norm.cdf(k) - 1
        out[f"inside_{k}sigma"] = {
            "along_track": float(np.mean(along_a <= k)),
            "mahalanobis_rtn": float(np.mean(maha_a <= chi2.ppf(p, 3))),
        }
    return out


def show(config: str, f: dict[str, Any], t_load: float, t_run: float) -> None:
    e = f["along_track_error_km"]
    print(f"\n[{config}] {f['objects']} objects; load {t_load:.1f} s, propagation {t_run:.1f} s")
    if f["without_valid_prediction"]:
        print(
            f"  no valid prediction at the truth epoch (decayed or CCSP stopped), left out: "
            f"{len(f['without_valid_prediction'])}: {', '.join(f['without_valid_prediction'])}"
        )
    print(
        f"  |along-track error| km: rhoprop median {e['rhoprop_median']:.1f}, "
        f"p90 {e['rhoprop_p90']:.1f}; SGP4 median {e['sgp4_median']:.1f}, "
        f"p90 {e['sgp4_p90']:.1f}"
    )
    print(f"  predicted along-track sigma, median: {f['along_track_sigma_km_median']:.2f} km")
    for k in (1, 2, 3):
        i = f[f"inside_{k}sigma"]
        print(
            f"  inside {k} sigma: along-track {100 * i['along_track']:.1f} %, "
            f"RTN Mahalanobis {100 * i['mahalanobis_rtn']:.1f} %"
        )
    print(f"  mean squared Mahalanobis distance: {f['mean_squared_mahalanobis']:.3g} (ideal 3)")
    r = f["median_error_over_sigma_rtn"]
    print(f"  median |error| / sigma: radial {r[0]:.2g}, along {r[1]:.2g}, cross {r[2]:.2g}")


#: Snapshots in time order: (median epoch date, path under catalogs/).
SNAPSHOTS = (
    ("2023-07-04", "history/celestrak_active_20230704.txt.gz"),
    ("2023-07-07", "history/celestrak_active_20230707.txt.gz"),
    ("2023-08-07", "history/celestrak_active_20230807.txt.gz"),
    ("2023-08-13", "history/celestrak_active_20230813.txt.gz"),
    ("2023-08-20", "history/celestrak_active_20230820.txt.gz"),
    ("2023-11-13", "celestrak_active_20231113.txt.gz"),
    ("2023-11-18", "history/celestrak_active_20231118.txt.gz"),
    ("2023-11-19", "celestrak_active_20231119.txt.gz"),
)
#: Development weeks: (start snapshot, truth snapshot).
WEEKS = (
    ("2023-07-04", "2023-07-07"),
    ("2023-08-07", "2023-08-13"),
    ("2023-08-13", "2023-08-20"),
    ("2023-11-13", "2023-11-19"),
)
CONFIGS = ("default", "fit", "history")


def week_paths(start: str, truth: str) -> tuple[list[Path], Path]:
    """The snapshots up to ``start`` (the last is the start) and the truth snapshot."""
    folder = data_dir()
    up_to = [folder / p for d, p in SNAPSHOTS if d <= start]
    return up_to, folder / dict(SNAPSHOTS)[truth]


def as_of_options(text: str | None) -> dict[str, Any]:
    """``SpaceWeather.as_of`` keywords from "F107_DAYS,AP_DAYS,AP_RELAX_DAYS[,AP_TARGET
    [,recurrence]]" (None: the library's defaults)."""
    if not text:
        return {}
    f, a, r, *rest = text.split(",")
    out: dict[str, Any] = {"f107_days": int(f), "ap_days": int(a), "ap_relax_days": float(r)}
    if rest:
        out["ap_target"] = rest[0]
    if rest[1:]:
        if rest[1] != "recurrence":
            raise ValueError(f"the fifth field of --as-of is 'recurrence', got {rest[1]!r}")
        out["recurrence"] = True
    return out


def as_of_bin(epoch: np.datetime64) -> np.datetime64:
    """The forecast's as-of time for an element set of ``epoch``: the 3-hour ap interval's
    start at or before it (what had been observed by then; the run of objects that share
    it is one)."""
    hour = epoch.astype("datetime64[h]")
    return hour - np.timedelta64(int(hour.astype(int)) % 3, "h")


def run_week(
    start: str, stop: str, args: argparse.Namespace, model_at: Any
) -> tuple[dict[str, Any], dict[str, dict[int, dict[str, Any]]], dict[int, dict[str, Any]]]:
    """One development week: its figures per configuration, the raw predictions and the
    truth (for the pooled figures). ``model_at(epoch)`` is the density model of an object
    whose start element set has that epoch (forecast mode: the record as of it)."""
    paths, truth_path = week_paths(start, stop)
    first, second = read_snapshot(paths[-1]), read_snapshot(truth_path)
    ids = select(first, second, args.objects, args.min_gap)
    truth: dict[int, dict[str, Any]] = {}
    groups: dict[Any, list[int]] = {}
    for norad in ids:
        s1 = Satrec.twoline2rv(*first[norad][1:])
        s2 = Satrec.twoline2rv(*second[norad][1:])
        model = model_at(rp.time.from_jd(s1.jdsatepoch, s1.jdsatepochF))
        groups.setdefault(model, []).append(norad)
        truth[norad] = {
            "epoch": rp.time.from_jd(s2.jdsatepoch, s2.jdsatepochF),
            "state": sgp4_state(s2, s2.jdsatepoch, s2.jdsatepochF),
            "sgp4": sgp4_state(s1, s2.jdsatepoch, s2.jdsatepochF),
        }
        if args.per_object:
            truth[norad].update(decay(first[norad], s1, s2))
    print(
        f"\n=== week {start} -> {stop}: {len(ids)} objects; history: "
        f"{', '.join(p.name for p in paths[:-1]) or 'none'}; density models (drivers as "
        f"of): {len(groups)}"
    )
    figs: dict[str, Any] = {}
    raw: dict[str, dict[int, dict[str, Any]]] = {}
    if args.per_object:
        sats = {n: Satrec.twoline2rv(*first[n][1:]) for n in ids}
        density_ratios(truth, sats, model_at(None).space_weather)
    span = None
    if args.fit_span:
        span = tuple(86400.0 * float(x) for x in args.fit_span.split(","))
    with tempfile.TemporaryDirectory() as tmp:
        snaps = [first if p == paths[-1] else read_snapshot(p) for p in paths]
        for config in args.configs.split(","):
            pred, objects, t_load, t_run = {}, [], 0.0, 0.0
            for g, (model, members) in enumerate(groups.items()):
                # Only the group's objects, from every snapshot up to the start.
                chosen = []
                for k, (p, snap) in enumerate(zip(paths, snaps, strict=True)):
                    out = Path(tmp) / f"{g}_{k}_{p.name.removesuffix('.gz')}"
                    out.write_text(
                        "".join(
                            f"{snap[i][0]}\n{snap[i][1]}\n{snap[i][2]}\n"
                            for i in members
                            if i in snap
                        )
                    )
                    chosen.append(out)
                got, load_s, run_s, loaded = run_config(
                    config, chosen, model, truth, args.threads, span
                )
                pred.update(got)
                objects += loaded
                t_load += load_s
                t_run += run_s
            figs[config] = figures(pred, truth, args.truth_covariance == "tle")
            figs[config]["seconds"] = {"load": t_load, "propagation": t_run}
            if config == "fit":
                figs[config]["prior"] = prior_scatter(objects)
                print(
                    f"  fitted / B*-scaled prior Cd*A/m ({figs[config]['prior']['objects']} "
                    f"with drag seen to < 10 %): median {figs[config]['prior']['median']:.3f}, "
                    f"log scatter {figs[config]['prior']['log_std']:.3f}"
                )
            if config == "history":
                used = [len(o.fit.element_sets) if o.fit is not None else 1 for o in objects]
                figs[config]["element_sets_used_mean"] = float(np.mean(used)) if used else 0.0
            raw[config] = pred
            if args.per_object:
                figs[config]["per_object"] = per_object(pred, truth)
            show(f"{start} {config}", figs[config], t_load, t_run)
    return figs, raw, truth


def _without_drag(sat: Any) -> Any:
    """The element set ``sat`` with B* = 0 (SGP4's drag-free orbit)."""
    free = Satrec()
    free.sgp4init(
        0,  # WGS72, as twoline2rv
        "i",
        sat.satnum,
        sat.jdsatepoch + sat.jdsatepochF - 2433281.5,
        0.0,
        sat.ndot,
        sat.nddot,
        sat.ecco,
        sat.argpo,
        sat.inclo,
        sat.mo,
        sat.no_kozai,
        sat.nodeo,
    )
    return free


def decay(entry: tuple[str, str, str], s1: Any, s2: Any) -> dict[str, Any]:
    """What the element sets say about one object's drag between the start epoch and the
    truth epoch (``--per-object``): perigee/apogee of the start set, the span, B*, the
    secular mean motion (SGP4's ``nm``, rad/min) of each set at its own epoch and of the
    start set at the truth epoch, and SGP4's along-track drag displacement there (the
    start set with its B* minus the same set with B* = 0, m, in the truth's RTN frame).
    ``1 - SGP4's along-track error / displacement`` is then the drag the truth saw over
    the drag SGP4 assumed, ``1 + (rhoprop's - SGP4's error) / displacement`` rhoprop's
    (:func:`signed_summary`)."""
    lo, hi = altitudes_km(s1)
    jd, jdf = s2.jdsatepoch, s2.jdsatepochF
    state = sgp4_state(s2, jd, jdf)
    basis = rtn_basis(state[:3], state[3:])
    with_drag = sgp4_state(s1, jd, jdf)
    # SGP4's secular mean motion (``nm``, rad/min) is the one of the last call
    mean_motion_sgp4 = float(s1.nm)
    sgp4_state(s1, s1.jdsatepoch, s1.jdsatepochF)
    mean_motion_start = float(s1.nm)
    mean_motion_truth = float(s2.nm)  # after sgp4_state(s2) at its epoch above
    free = sgp4_state(_without_drag(s1), jd, jdf)
    return {
        "name": entry[0],
        "perigee_km": lo,
        "apogee_km": hi,
        "span_days": (s2.jdsatepoch - s1.jdsatepoch) + (s2.jdsatepochF - s1.jdsatepochF),
        "start_epoch": str(rp.time.from_jd(s1.jdsatepoch, s1.jdsatepochF)),
        "bstar": float(s1.bstar),
        "mean_motion_start": mean_motion_start,
        "mean_motion_truth": mean_motion_truth,
        "mean_motion_sgp4_at_truth": mean_motion_sgp4,
        "sgp4_drag_displacement_m": (basis @ (with_drag[:3] - free[:3])).tolist(),
    }


#: Windows of the NRLMSIS mean density along each orbit (``--per-object``), days from the
#: start epoch: the fit's span (``fit.DEFAULT_SPAN``) and the three days before the epoch
#: (where the element set's B* was fitted by its owner); the prediction runs from the
#: start epoch to the truth epoch.
DENSITY_WINDOWS = {"fit": (-1.0, 0.0), "before": (-3.0, 0.0)}


def density_ratios(
    truth: dict[int, dict[str, Any]], sats: dict[int, Any], space_weather: Any
) -> None:
    """Adds to each truth entry NRLMSIS 2.1's mean density (``space_weather``, no driver
    variance) along the start element set's SGP4 orbit, every 10 min, over the
    prediction (start epoch -> truth epoch) and over :data:`DENSITY_WINDOWS`, kg/m^3."""
    from rhoprop.density.msis import RelativeSigma
    from rhoprop.frames import geodetic, inertial_to_fixed

    msis = Msis("2.1", space_weather=space_weather, uncertainty=RelativeSigma(0.0))
    for norad, t in truth.items():
        sat = sats[norad]
        windows = dict(DENSITY_WINDOWS, prediction=(0.0, t["span_days"]))
        densities = {}
        for key, (a, b) in windows.items():
            days = np.arange(a, b, 600.0 / 86400.0)
            jd = sat.jdsatepoch + np.zeros_like(days)
            err, r, _ = sat.sgp4_array(jd, sat.jdsatepochF + days)
            ok = err == 0
            times = rp.time.offsets_to_epochs(
                rp.time.from_jd(sat.jdsatepoch, sat.jdsatepochF), days[ok] * 86400.0
            )
            lla = geodetic(inertial_to_fixed(times, r[ok] * 1e3))
            mean = msis.mean_std(times, lla[:, 0], lla[:, 1], lla[:, 2])[0]
            densities[key] = float(np.mean(mean))
        t["msis21_mean_density"] = densities


def per_object(pred: dict[int, dict[str, Any]], truth: dict[int, dict[str, Any]]) -> list[dict]:
    """One row per object (``--per-object``): the signed RTN errors (m) of rhoprop's mean
    and of SGP4 at the truth epoch (positive along-track: ahead of the truth, as too much
    drag puts it), the Cd*A/m run (m^2/kg) and the fit's (over its prior), with
    :func:`decay`'s and :func:`density_ratios`' figures."""
    rows = []
    for norad, p in pred.items():
        t = truth[norad]
        basis = rtn_basis(t["state"][:3], t["state"][3:])
        row = {
            "norad": norad,
            "status": p["status"],
            "rhoprop_rtn_error_m": (basis @ (p["mean"][:3] - t["state"][:3])).tolist(),
            "sgp4_rtn_error_m": (basis @ (t["sgp4"][:3] - t["state"][:3])).tolist(),
            "drag_parameter": p["drag_parameter"],
            "fit": p["fit"],
        }
        row.update({k: v for k, v in t.items() if k not in ("epoch", "state", "sgp4")})
        row["truth_epoch"] = str(t["epoch"])
        rows.append(row)
    return rows


#: Perigee bands (km) of :func:`signed_summary`.
BANDS = ((200, 700), (200, 400), (400, 500), (500, 600), (600, 700))


def signed_summary(rows: dict[str, dict[str, list[dict]]]) -> None:
    """Prints, per week, configuration and perigee band, from the ``--per-object`` rows:
    the median signed along-track error (km) of rhoprop and SGP4 and the share ahead of
    the truth (too much drag), and the drag over the prediction relative to SGP4's as the
    truth implies it (``obs``), as rhoprop's error implies it (``rhoprop``; medians of
    :func:`decay`'s ratios, objects with a drag displacement over 1 km) and as NRLMSIS
    2.1's mean density along the orbit changes from the fit window (-1..0 d) to the
    prediction (``msis``)."""
    print(
        "\n| week | config | perigee km | objects | signed along-track median km "
        "rhoprop (% ahead) | SGP4 (% ahead) | drag / SGP4's: obs | rhoprop | msis |"
    )
    print("| --- | --- | --- | ---: | --- | --- | ---: | ---: | ---: |")
    for week, by_config in rows.items():
        for config, objs in by_config.items():
            for lo, hi in BANDS:
                sel = [
                    r
                    for r in objs
                    if lo <= r["perigee_km"] < hi and np.isfinite(r["rhoprop_rtn_error_m"][1])
                ]
                if not sel:
                    continue
                rho = np.array([r["rhoprop_rtn_error_m"][1] for r in sel]) / 1e3
                sgp = np.array([r["sgp4_rtn_error_m"][1] for r in sel]) / 1e3
                disp = np.array([r["sgp4_drag_displacement_m"][1] for r in sel]) / 1e3
                seen = disp > 1.0
                dens = [r["msis21_mean_density"] for r in sel]
                msis = np.median([d["prediction"] / d["fit"] for d in dens])
                k_obs = np.median(1 - sgp[seen] / disp[seen]) if seen.any() else np.nan
                k_rho = np.median(1 + (rho - sgp)[seen] / disp[seen]) if seen.any() else np.nan
                band = "all" if (lo, hi) == BANDS[0] else f"{lo}-{hi}"
                print(
                    f"| {week} | {config} | {band} | {len(sel)} | {np.median(rho):+.2f} "
                    f"({100 * np.mean(rho > 0):.0f}) | {np.median(sgp):+.2f} "
                    f"({100 * np.mean(sgp > 0):.0f}) | {k_obs:.3f} | {k_rho:.3f} | {msis:.3f} |"
                )


def prior_scatter(objects: list[Any]) -> dict[str, Any]:
    """How the fit's B*-derived prior (``fit.bstar_prior``) compares with the fitted Cd*A/m
    where the fit sees the drag well (formal sigma < 10 %): the ratios' median and the
    standard deviation of their logarithm (robust: 1.4826 x the median absolute
    deviation), which calibrates ``fit.BSTAR_PRIOR_SIGMA``."""
    ratios = [
        o.fit.drag_parameter / o.fit.prior
        for o in objects
        if o.fit is not None and o.fit.drag_sigma < 0.1 * o.fit.drag_parameter
    ]
    logs = np.log(ratios) if ratios else np.array([np.nan])
    return {
        "objects": len(ratios),
        "median": float(np.exp(np.median(logs))),
        "log_std": float(1.4826 * np.median(np.abs(logs - np.median(logs)))),
        "log_ratios": [float(x) for x in logs],
    }


def week_models(record: Any, mode: str, start: str, args: argparse.Namespace) -> Any:
    """``model_at(epoch)``: NRLMSIS 2.1 on the drivers of ``mode`` for an element set of
    ``epoch`` (None: the week's start day), one model per as-of time."""
    models: dict[Any, Any] = {}

    def model_at(epoch: Any) -> Any:
        if mode == "hindcast":
            key = None
        elif epoch is None or args.as_of_at == "start":
            key = np.datetime64(f"{start}T00:00")
        else:
            key = as_of_bin(epoch)
        if key not in models:
            weather = record
            if key is not None:
                weather = record.as_of(key, **as_of_options(args.as_of))
            models[key] = Msis("2.1", space_weather=weather)
        return models[key]

    return model_at


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--objects", type=int, default=150, help="per week; 0: every one")
    parser.add_argument(
        "--weeks",
        default=",".join(w[0] for w in WEEKS),
        help="start dates of the development weeks to run, comma-separated",
    )
    parser.add_argument("--configs", default=",".join(CONFIGS))
    parser.add_argument(
        "--min-gap",
        type=float,
        default=2.0,
        help="least days between the start and the truth element set",
    )
    parser.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    parser.add_argument(
        "--history-days",
        type=float,
        default=None,
        help="element sets fitted together reach back this far (default: the library's "
        "rp.catalog.HISTORY_DAYS)",
    )
    parser.add_argument(
        "--truth-covariance",
        choices=("tle", "none"),
        default="tle",
        help="add the truth's own error (the published TLE accuracy of the second element "
        "set's state) to the predicted covariance before comparing (default), or not",
    )
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    parser.add_argument(
        "--fit-span",
        default=None,
        help="START,END days from the epoch: the span of the fit and history "
        "configurations' pseudo-observations (default: the library's, -1,1); the default "
        "configuration fits inside propagate_catalog with the library's span",
    )
    parser.add_argument(
        "--space-weather",
        default=None,
        help="a CelesTrak space-weather file for NRLMSIS 2.1 instead of the bundled record "
        "(to try other drivers)",
    )
    parser.add_argument(
        "--drivers",
        choices=("forecast", "hindcast", "both"),
        default="forecast",
        help="space weather as known at each week's start, then a forecast (default); as "
        "observed through the prediction (a hindcast); or both",
    )
    parser.add_argument(
        "--altitudes",
        default="200,700",
        help="LOW,HIGH km: perigee and apogee altitudes of the objects selected (default "
        "200,700, the development regime; e.g. 700,2000 for the orbits above it)",
    )
    parser.add_argument(
        "--as-of",
        default=None,
        help="F107_DAYS,AP_DAYS,AP_RELAX_DAYS[,AP_TARGET[,recurrence]] of the forecast "
        "mode's SpaceWeather.as_of (default: the library's)",
    )
    parser.add_argument(
        "--as-of-at",
        choices=("epoch", "start"),
        default="epoch",
        help="forecast mode: the drivers as known at each start element set's epoch "
        "(default; the start of its 3-hour ap interval), or at the start day's 00:00 for "
        "every object (before 2026-12-06: most element sets of a snapshot are later)",
    )
    parser.add_argument(
        "--per-object",
        action="store_true",
        help="also write catalog_realism_objects.json in --out: per week, configuration "
        "and object the signed RTN errors of rhoprop and SGP4, perigee, span, Cd*A/m "
        "fitted and its prior, the element sets' decay and NRLMSIS 2.1's mean density "
        "along the orbit in the fit window and the prediction (for diagnosis)",
    )
    args = parser.parse_args()
    global ALTITUDES_KM
    low, high = (float(x) for x in args.altitudes.split(","))
    ALTITUDES_KM = (low, high)
    for c in args.configs.split(","):
        if c not in CONFIGS:
            parser.error(f"unknown configuration {c!r}; choose from {', '.join(CONFIGS)}")
    if args.history_days is not None:
        catalog.elements.HISTORY_DAYS = args.history_days
    print(f"history fits reach back {catalog.elements.HISTORY_DAYS:g} days")
    weeks = [w for w in WEEKS if w[0] in args.weeks.split(",")]
    if not weeks:
        parser.error(f"no development week starts on {args.weeks}")
    record = rp.SpaceWeather(args.space_weather) if args.space_weather else rp.SpaceWeather()
    modes = ("forecast", "hindcast") if args.drivers == "both" else (args.drivers,)
    configs = [
        c if mode == "forecast" else f"{c}/hindcast"
        for mode in modes
        for c in args.configs.split(",")
    ]
    results: dict[str, Any] = {}
    pooled: dict[str, tuple[dict, dict]] = {c: ({}, {}) for c in configs}
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    for start, stop in weeks:
        results[start] = {}
        for mode in modes:
            model_at = week_models(record, mode, start, args)
            where = {
                "hindcast": "observed through the prediction",
                "forecast": "as of each start element set's epoch (its 3-hour ap interval)"
                if args.as_of_at == "epoch"
                else f"as of {start}T00:00",
            }[mode]
            print(f"\n--- drivers: {mode}, {where} ({record.source})")
            figs, raw, truth = run_week(start, stop, args, model_at)
            suffix = "" if mode == "forecast" else "/hindcast"
            results[start].update({c + suffix: f for c, f in figs.items()})
            for config, pred in raw.items():
                pooled[config + suffix][0].update({(start, k): v for k, v in pred.items()})
                pooled[config + suffix][1].update({(start, k): v for k, v in truth.items()})
    print("\n=== all weeks")
    results["all"] = {}
    for config, (pred, truth) in pooled.items():
        results["all"][config] = figures(pred, truth, args.truth_covariance == "tle")
        if config == "fit":
            logs = np.concatenate([results[w]["fit"]["prior"]["log_ratios"] for w, _ in weeks])
            print(
                f"  fitted / prior Cd*A/m over all weeks ({len(logs)}): median "
                f"{np.exp(np.median(logs)):.3f}, log scatter "
                f"{1.4826 * np.median(np.abs(logs - np.median(logs))):.3f}, "
                f"log std {np.std(logs):.3f}"
            )
        show(f"all {config}", results["all"][config], 0.0, 0.0)
    summary(results, [w[0] for w in weeks], configs)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.per_object:
        rows = {w: {c: results[w][c].pop("per_object") for c in configs} for w, _ in weeks}
        signed_summary(rows)
        (out / "catalog_realism_objects.json").write_text(
            json.dumps({"machine": info(), "weeks": rows}, indent=1)
        )
    (out / "catalog_realism_weeks.json").write_text(
        json.dumps(
            {
                "machine": info(),
                "objects_per_week": args.objects,
                "drivers": args.drivers,
                "truth_covariance": args.truth_covariance,
                "results": results,
            },
            indent=2,
        )
    )


def summary(results: dict[str, Any], weeks: list[str], configs: list[str]) -> None:
    """One markdown table: a row per week and configuration, and the pooled rows."""
    print(
        "\n| week | config | objects | along-track median / p90 km | SGP4 median / p90 km "
        "| ratio | inside 1/2/3 sigma along-track % | RTN Mahalanobis 1/2/3 sigma % |"
    )
    print("| --- | --- | ---: | --- | --- | ---: | --- | --- |")
    for week in [*weeks, "all"]:
        for config in configs:
            f = results[week][config]
            e = f["along_track_error_km"]
            inside = [f[f"inside_{k}sigma"] for k in (1, 2, 3)]
            along = slashed((100 * i["along_track"] for i in inside), ".0f")
            rtn = slashed((100 * i["mahalanobis_rtn"] for i in inside), ".0f")
            print(
                f"| {week} | {config} | {f['objects']} | {e['rhoprop_median']:.2f} / "
                f"{e['rhoprop_p90']:.1f} | {e['sgp4_median']:.2f} / {e['sgp4_p90']:.1f} | "
                f"{e['rhoprop_median'] / e['sgp4_median']:.2f} | {along} | {rtn} |"
            )


if __name__ == "__main__":
    main()
