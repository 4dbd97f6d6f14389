"""Realism of catalog predictions on real data: the CelesTrak "active" catalog of
2023-11-13 predicted forward and compared with the same objects' element sets of
2023-11-19 (``$RHOPROP_TEST_DATA/catalogs``, default ``../shared/data/catalogs``).

Selection: objects in both snapshots, perigee and apogee altitude 200-700 km, a newer
element set in the second snapshot (epochs more than 4 days apart), manoeuvring
constellations and crewed stations excluded by name (Starlink, OneWeb, Iridium,
Globalstar, Orbcomm, Kuiper, ISS, CSS modules, crew/cargo vehicles), and objects whose
mean motion fell between the two snapshots (an orbit raise: drag only raises it). The
first ``--objects`` of them in NORAD order (every k-th, so the whole range is sampled).

Truth: the 11-19 element set's own state at its epoch (SGP4 at t = 0, its most accurate
point); each object is predicted from its 11-13 epoch to that epoch. Compared there:
SGP4 of the 11-13 element set (the baseline), and rhoprop's mean and covariance
(``propagate_catalog``, CCSP, NRLMSIS 2.1 with the observed space weather of the bundled
record: a hindcast, no driver-forecast error). Errors are in the truth's RTN frame. The
truth is itself a TLE state: its published accuracy (``rp.catalog.tle_covariance``) is
added to the predicted covariance for the sigma tests (``--truth-covariance none`` leaves
it out).

Printed per configuration: median and 90th percentile of |along-track error| for
rhoprop's mean and for SGP4; the predicted along-track sigma (median); the fractions of
objects inside 1, 2 and 3 sigma along-track (|dT| / sigma_T <= k) and by the RTN-position
Mahalanobis distance (d^T P^-1 d <= the chi-square(3) quantile of the 1-D k-sigma
probability: 68.3 / 95.4 / 99.7 %); the mean squared Mahalanobis distance (3 for a
consistent covariance). Goals (issue 16): mean no worse than SGP4; 85-98 % inside 2 sigma
and 95-100 % inside 3 sigma.

Configurations (``--configs``, comma-separated):
  baseline  state and Cd*A/m from B* (SGP4 at the epoch), the paper's near-zero initial
            covariance: the method before issue 16.
  tle       B* state, initial covariance from the published TLE accuracy (``"tle"``).
  fit       state and Cd*A/m fitted to SGP4 pseudo-observations (``load(fit=True)``),
            initial covariance from the fit, floored at the TLE accuracy (the default
            with ``fit=True``).

Run:  python benches/catalog_realism.py [--objects 200] [--configs baseline,tle,fit]
      python benches/catalog_realism.py --objects 0       # every selected object
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import gzip
import json
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import chi2, norm
from sgp4.api import Satrec

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


def select(first: dict, second: dict, limit: int) -> list[int]:
    """NORAD ids of the benchmark objects (see the module docstring)."""
    ids = []
    for norad in sorted(set(first) & set(second)):
        name = first[norad][0].upper()
        if any(word in name for word in EXCLUDE):
            continue
        s1 = Satrec.twoline2rv(*first[norad][1:])
        s2 = Satrec.twoline2rv(*second[norad][1:])
        lo, hi = altitudes_km(s1)
        if lo < 200 or hi > 700:
            continue
        span = (s2.jdsatepoch - s1.jdsatepoch) + (s2.jdsatepochF - s1.jdsatepochF)
        if span < 4.0:
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
    path: Path,
    field: Any,
    truth: dict[int, dict[str, Any]],
    threads: int,
    update_interval: float,
    fit_span: tuple[float, float] | None = None,
    drag_sigma: Any = "auto",
    zonal_degree: int = 2,
) -> tuple[dict[int, dict[str, Any]], float, float]:
    """Predicted mean and covariance at each object's truth epoch; the load (and fit)
    time and the propagation time, s."""
    t0 = time.perf_counter()
    if config == "fit":
        cat = catalog.load(
            path,
            fit=True,
            model=field,
            errors="record",
            span=fit_span,
            zonal_degree=zonal_degree,
        )
        cov: Any = "object"
    else:
        cat = catalog.load(path)
        cov = "paper" if config == "baseline" else "tle"
    t_load = time.perf_counter() - t0

    def one(obj: Any) -> tuple[int, dict[str, Any]]:
        end = truth[obj.norad_id]["epoch"]
        res = catalog.propagate_catalog(
            [obj],
            field,
            end,
            output_step=1e9,
            update_interval=update_interval,
            progress=False,
            errors="record",
            drag_sigma=drag_sigma,
            zonal_degree=zonal_degree,
            **({} if cov is None else {"initial_covariance": cov}),
        )
        return obj.norad_id, {
            "mean": res.mean[0, -1],
            "cov": res.covariance[0, -1],
            "status": str(res.status[0]),
        }

    t0 = time.perf_counter()
    with cf.ThreadPoolExecutor(threads) as pool:
        out = dict(pool.map(one, cat.objects))
    return out, t_load, time.perf_counter() - t0


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


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--objects", type=int, default=200, help="0: every selected object")
    parser.add_argument("--configs", default="baseline,tle,fit")
    parser.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    parser.add_argument(
        "--fit-span",
        default=None,
        help="fit span, s from the epoch: START,END (default 1 day either side)",
    )
    parser.add_argument(
        "--update-interval", type=float, default=3600.0, help="CCSP update interval, s"
    )
    parser.add_argument(
        "--drag-sigma",
        default="auto",
        help="relative 1-sigma of Cd*A/m propagated by the CCSP: 'auto' (default: the fit's, "
        "at least 0.08; 0.15 without a fit) or a number (0: none, as before issue 16 item 3)",
    )
    parser.add_argument(
        "--zonal-degree",
        type=int,
        default=2,
        help="zonal harmonics of the fit and the propagation: 2 (J2, default) to 6; 4 is "
        "SGP4's own J2..J4",
    )
    parser.add_argument(
        "--truth-covariance",
        choices=("tle", "none"),
        default="tle",
        help="add the truth's own error (the published TLE accuracy of the second element "
        "set's state) to the predicted covariance before comparing (default), or not",
    )
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = parser.parse_args()
    folder = data_dir()
    first = read_snapshot(folder / "celestrak_active_20231113.txt.gz")
    second = read_snapshot(folder / "celestrak_active_20231119.txt.gz")
    ids = select(first, second, args.objects)
    truth: dict[int, dict[str, Any]] = {}
    for norad in ids:
        s1 = Satrec.twoline2rv(*first[norad][1:])
        s2 = Satrec.twoline2rv(*second[norad][1:])
        truth[norad] = {
            "epoch": rp.time.from_jd(s2.jdsatepoch, s2.jdsatepochF),
            "state": sgp4_state(s2, s2.jdsatepoch, s2.jdsatepochF),
            "sgp4": sgp4_state(s1, s2.jdsatepoch, s2.jdsatepochF),
        }
    print(f"{len(ids)} objects selected (perigee/apogee 200-700 km, no manoeuvring names)")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "first.tle"
        path.write_text("".join(f"{first[i][0]}\n{first[i][1]}\n{first[i][2]}\n" for i in ids))
        cat = catalog.load(path)
        start = min(o.state.epoch for o in cat) - np.timedelta64(3, "D")
        end = max(t["epoch"] for t in truth.values()) + np.timedelta64(1, "h")
        t0 = time.perf_counter()
        field = Msis("2.1")
        field.atlas.field(start, end)  # the day tiles, sampled (or read) once
        print(f"NRLMSIS 2.1 atlas {start} .. {end}: {time.perf_counter() - t0:.1f} s")
        span = None
        if args.fit_span:
            start_s, end_s = (float(x) for x in args.fit_span.split(","))
            span = (start_s, end_s)
        results = {}
        drag_sigma = args.drag_sigma if args.drag_sigma == "auto" else float(args.drag_sigma)
        print(f"Cd*A/m relative sigma: {drag_sigma}")
        for config in args.configs.split(","):
            pred, t_load, t_run = run_config(
                config,
                path,
                field,
                truth,
                args.threads,
                args.update_interval,
                span,
                drag_sigma,
                args.zonal_degree,
            )
            results[config] = figures(pred, truth, args.truth_covariance == "tle")
            results[config]["seconds"] = {"load": t_load, "propagation": t_run}
            show(config, results[config], t_load, t_run)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = (
        f"catalog_realism_{int(args.update_interval)}s_drag_{args.drag_sigma}"
        f"_j{args.zonal_degree}.json"
    )
    (out / name).write_text(
        json.dumps(
            {
                "machine": info(),
                "objects": len(ids),
                "drag_sigma": args.drag_sigma,
                "zonal_degree": args.zonal_degree,
                "truth_covariance": args.truth_covariance,
                "results": results,
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
