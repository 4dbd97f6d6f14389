"""Deep-space and eccentric orbits against their next element sets: objects of the
CelesTrak snapshot of 2023-11-13 predicted to the epoch of their element set of
2023-11-19 (``$RHOPROP_TEST_DATA/catalogs``), truth = that element set's SGP4 state.

1. Fitted states (``fit_objects``, the library's deep-space span) propagated with the
   deep-space dynamics (Sun, Moon, tesserals to degree 8, J2..J4), per class: GEO
   (0.99-1.01 rev/day), GPS (1.9-2.1) and other MEO (2.1-6), near-circular (e < 0.02),
   the first ``--per-class`` of each in NORAD order: median |position error| against
   SGP4's own prediction of the earlier element set (docs/catalog-realism.md,
   "Deep space").
2. Every eccentric object (e >= 0.1) in both snapshots through ``propagate_catalog`` with
   its defaults (NRLMSIS 2.1): position error, along-track error / sigma and the 3-D
   Mahalanobis distance with the truth's TLE covariance added; summaries over all and
   over those that SGP4 itself predicts within 100 km (the others manoeuvred)
   (docs/catalog-realism.md, "Eccentric orbits").

Run:  RHOPROP_TEST_DATA=../shared/data python benches/deep_space.py [--per-class 40]
        [--weeks all|2023-07-04,...] (default 2023-11-13, the pair the earlier figures used)
"""

from __future__ import annotations

import argparse
import gzip
import os
import tempfile
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe, element_sets
from rhoprop.catalog.covariance import tle_covariance
from rhoprop.frames import rtn_basis

CLASSES = {"GEO": (0.99, 1.01), "GPS": (1.9, 2.1), "MEO": (2.1, 6.0)}
#: Chi-square(3) quantile of the 1-D 2-sigma probability (95.45 %).
CHI2_3_2SIGMA = 8.02


def snapshot(path: Path) -> dict[int, tuple]:
    """NORAD id -> (name, line 1, line 2, Satrec) of a gzipped 3-line file."""
    text = gzip.open(path, "rt").read()
    return {sat.satnum: (n, l1, l2, sat) for n, l1, l2, sat in element_sets(text)}


def write(sets: list[tuple], folder: Path, name: str) -> Path:
    path = folder / name
    path.write_text("".join(f"{n}\n{l1}\n{l2}\n" for n, l1, l2, _ in sets))
    return path


def sgp4_error_km(first, later) -> float:
    """|SGP4 of ``first`` at ``later``'s epoch - ``later``'s own state|, km."""
    _, r0, _ = first.sgp4(later.jdsatepoch, later.jdsatepochF)
    _, r1, _ = later.sgp4(later.jdsatepoch, later.jdsatepochF)
    return float(np.linalg.norm(np.subtract(r0, r1)))


def deep_space_classes(
    first: dict, second: dict, per_class: int, folder: Path, catalog_runs: bool = False
) -> None:
    model = rp.density.Msis("2.1")
    for name, (lo, hi) in CLASSES.items():
        picked = []
        for norad, entry in first.items():
            sat = entry[3]
            rev = sat.no_kozai * 1440 / (2 * np.pi)
            if norad in second and lo < rev < hi and sat.ecco < 0.02:
                later = second[norad][3]
                gap = later.jdsatepoch + later.jdsatepochF - sat.jdsatepoch - sat.jdsatepochF
                if gap >= 3:
                    picked.append((entry, second[norad]))
            if len(picked) == per_class:
                break
        objs = list(rp.catalog.load(write([p[0] for p in picked], folder, f"{name}.tle")))
        fitted = rp.catalog.fit_objects(
            objs,
            model,
            dynamics=rp.Dynamics(zonal_degree=4),
        )
        errors, sgp4 = [], []
        for obj, (entry, later_entry) in zip(fitted, picked, strict=True):
            if isinstance(obj, Exception):
                continue
            later = later_entry[3]
            _, r, _ = later.sgp4(later.jdsatepoch, later.jdsatepochF)
            when = rp.time.from_jd(later.jdsatepoch, later.jdsatepochF, scale="utc")
            span = float((when - obj.state.epoch) / np.timedelta64(1, "s"))
            run = rp.propagate(
                obj.state,
                rp.Spacecraft(1.0, obj.drag_parameter),
                rp.scenarios.benchmark_exponential(0.0),
                span,
                dynamics=rp.Dynamics(zonal_degree=4, integrator="rk8", step=600.0),
            )
            errors.append(np.linalg.norm(run.positions[-1] - np.array(r) * 1e3) / 1e3)
            sgp4.append(sgp4_error_km(entry[3], later))
        print(
            f"{name}: {len(errors)} of {len(picked)} fitted; median |error| "
            f"{np.median(errors):.2f} km, SGP4 {np.median(sgp4):.2f} km"
        )
        if catalog_runs:
            ids = [p[0][3].satnum for p in picked]
            realism(f"{name} through propagate_catalog", ids, first, second, folder)


def eccentric(first: dict, second: dict, folder: Path) -> None:
    ids = [k for k, e in first.items() if k in second and e[3].ecco >= 0.1]
    realism("eccentric", ids, first, second, folder, split=True)


def realism(
    label: str, ids: list[int], first: dict, second: dict, folder: Path, split: bool = False
) -> None:
    """``propagate_catalog`` with its defaults for each of ``ids`` to its later element
    set's epoch: median error and the covariance's coverage of the truth (``split``: also
    over the objects that SGP4 itself predicts within 100 km)."""
    start = {
        o.norad_id: o
        for o in rp.catalog.load(write([first[k] for k in ids], folder, "e1.tle"), errors="record")
    }
    truth = {
        o.norad_id: o
        for o in rp.catalog.load(write([second[k] for k in ids], folder, "e2.tle"), errors="record")
    }
    model = rp.density.Msis("2.1")
    rows = []
    for k in ids:
        if k not in start or k not in truth:
            continue
        obj, later = start[k], truth[k]
        if later.state.epoch <= obj.state.epoch + np.timedelta64(86400, "s"):
            continue
        res = rp.catalog.propagate_catalog(
            [obj],
            model,
            later.state.epoch,
            execution=rp.Execution(progress=False, errors="record"),
        )
        if res.status[0] != "propagated":
            print(f"{k} {obj.name.strip()}: {res.status[0]}: {res.reason[0]}")
            continue
        mean, cov = res.mean[0, -1], res.covariance[0, -1] + tle_covariance(later.state)
        d = later.state.position - mean[:3]
        basis = rtn_basis(mean[:3], mean[3:])
        sigma_t = float(np.sqrt(basis[1] @ cov[:3, :3] @ basis[1]))
        rows.append(
            (
                np.linalg.norm(d) / 1e3,
                sgp4_error_km(first[k][3], second[k][3]),
                abs(float(basis[1] @ d)) / sigma_t,
                float(d @ np.linalg.solve(cov[:3, :3], d)),
            )
        )
    table = np.array(rows)
    groups = [("all", np.ones(len(table), bool))]
    if split:
        groups.append(("SGP4 within 100 km", table[:, 1] < 100.0))
    for group, keep in groups:
        t = table[keep]
        inside = " / ".join(f"{100 * np.mean(t[:, 2] < k):.0f}" for k in (1, 2, 3))
        print(
            f"{label}, {group}: {len(t)} objects; median |error| {np.median(t[:, 0]):.1f} km "
            f"(SGP4 {np.median(t[:, 1]):.1f} km); along-track inside 1/2/3 sigma "
            f"{inside} %; "
            f"3-D Mahalanobis inside 2 sigma {100 * np.mean(t[:, 3] < CHI2_3_2SIGMA):.0f} %"
        )


#: The development pairs of docs/catalog-realism.md (start snapshot, later snapshot).
PAIRS = {
    "2023-07-04": ("history/celestrak_active_20230704", "history/celestrak_active_20230707"),
    "2023-08-07": ("history/celestrak_active_20230807", "history/celestrak_active_20230813"),
    "2023-08-13": ("history/celestrak_active_20230813", "history/celestrak_active_20230820"),
    "2023-11-13": ("celestrak_active_20231113", "celestrak_active_20231119"),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--per-class", type=int, default=40)
    parser.add_argument(
        "--weeks", default="2023-11-13", help=f"comma-separated, or 'all' ({', '.join(PAIRS)})"
    )
    parser.add_argument(
        "--covariance",
        action="store_true",
        help="also run each class through propagate_catalog: coverage of the truth",
    )
    args = parser.parse_args()
    weeks = list(PAIRS) if args.weeks == "all" else args.weeks.split(",")
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data")) / "catalogs"
    print(describe())
    for week in weeks:
        a, b = PAIRS[week]
        first = snapshot(data / f"{a}.txt.gz")
        second = snapshot(data / f"{b}.txt.gz")
        print(f"-- {week}: {a} -> {b}")
        with tempfile.TemporaryDirectory() as tmp:
            deep_space_classes(first, second, args.per_class, Path(tmp), args.covariance)
            eccentric(first, second, Path(tmp))


if __name__ == "__main__":
    main()
