"""Close-approach screening throughput: one LEO primary against the real CelesTrak
snapshot of 2023-11-13 (``$RHOPROP_TEST_DATA/catalogs``; objects with B* <= 0 cannot be
loaded without a fit and are left out) over 3 days, with ``rp.conjunction.screen``.
Prints the counts after each stage, the time per stage (thread-seconds: the stages run
interleaved, object by object, on the worker threads) and objects per second per stage
(objects entering the stage / (thread-seconds / threads)) and for the whole screen
(secondaries / wall-clock time). Writes ``benches/results/screening.json``.

Run:  RHOPROP_TEST_DATA=/work/shared/data python benches/screening.py
      [--norad 25544] [--days 3] [--distance 5000] [--model exponential|msis]

``--all`` screens the whole snapshot against itself instead
(``rp.conjunction.screen_all``; B* <= 0 objects load with the assumed Cd*A/m,
``nonpositive_bstar="prior"``) through the default model families
(``rhoprop.studies.scenarios.default_models``: NRLMSIS 2.1, Jacchia-Roberts 1971 and
NRLMSISE-00 unless JB2008 index files covering 2023 are found), with the
per-model and mixture Pc of every event. It prints the time per stage (wall clock),
the pairs and pair-intervals after each filter, the events and the peak memory (RSS),
and writes ``benches/results/screening_all.json``:

      RHOPROP_TEST_DATA=/work/shared/data python benches/screening.py --all
      [--days 3] [--distance 5000] [--limit N] [--no-pc]

``--catalog`` screens another file instead (absolute, or under the data directory),
e.g. the whole Space-Track catalog of 2022-01-25 (23,939 objects) over 1 day:

      RHOPROP_TEST_DATA=/work/shared/data python benches/screening.py --all --days 1 \
      --catalog catalogs/full/spacetrack_full_3le_20220125.txt.gz

``--dask 1,2,4`` runs the same all-on-all screen (``--limit`` objects, default 1,500)
locally and then with every stage on a ``distributed.LocalCluster`` of 1, 2 and 4
single-threaded worker processes, checks that each gives the local run's events, and
prints the wall time per stage for each and a fitted model of how a stage's time splits
between work that divides among workers and a part that does not (the client's own work,
transfers, scheduling): t(N) = a + b / N, least squares over the runs. With N machines
of this one's speed the model extrapolates b / N; on one 2-core machine, 4 workers only
show the overhead of the split. Writes ``benches/results/screening_dask.json``:

      RHOPROP_TEST_DATA=/work/shared/data python benches/screening.py --dask 1,2,4
      [--limit 1500] [--days 1] [--no-pc]
"""

from __future__ import annotations

import argparse
import gzip
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe, info
from rhoprop import catalog
from rhoprop.conjunction import screen
from rhoprop.conjunction.screening import STAGES

#: The snapshot ``--all`` screens unless ``--catalog`` names another file.
SNAPSHOT = "catalogs/celestrak_active_20231113.txt.gz"
#: The stage each count feeds, and the timing that measures it.
RATES = (
    ("radial", "secondaries", "radial"),
    ("propagation", "radial", "propagation"),
    ("coarse grid", "propagated", "coarse_grid"),
    ("interpolated", "coarse_grid", "interpolated"),
    ("refinement", "interpolated", "refinement"),
)


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--norad", type=int, action="append", help="primary (default ISS 25544)")
    parser.add_argument("--days", type=float, default=3.0)
    parser.add_argument("--distance", type=float, default=5e3, help="screening distance, m")
    parser.add_argument("--model", choices=("exponential", "msis"), default="exponential")
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument(
        "--data",
        default=os.environ.get("RHOPROP_TEST_DATA", str(Path(__file__).parents[2] / "shared/data")),
        help="reference data directory (default $RHOPROP_TEST_DATA or ../shared/data)",
    )
    parser.add_argument("--all", action="store_true", help="all-on-all (screen_all)")
    parser.add_argument("--limit", type=int, default=None, help="--all: first N objects only")
    parser.add_argument("--no-pc", action="store_true", help="--all: skip the Pc stage")
    parser.add_argument(
        "--catalog",
        default=SNAPSHOT,
        help=f"--all: catalog file, absolute or under --data (default {SNAPSHOT})",
    )
    parser.add_argument("--dask", default=None, help="worker counts, e.g. 1,2,4 (see docs)")
    args = parser.parse_args()
    if args.dask:
        dask_scaling(args)
        return
    if args.all:
        all_on_all(args)
        return
    snapshot = Path(args.data) / "catalogs" / "celestrak_active_20231113.txt.gz"
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "active.tle"
        path.write_text(gzip.open(snapshot, "rt").read())
        t0 = time.perf_counter()
        cat = catalog.load(path, errors="record")
        load = time.perf_counter() - t0
    print(f"{len(cat)} objects loaded in {load:.2f} s ({len(cat.skipped)} skipped: B* <= 0)")
    start = max(o.state.epoch for o in cat)
    end = start + np.timedelta64(int(args.days * 86400), "s")
    model = rp.density.Exponential.benchmark() if args.model == "exponential" else rp.density.Msis()
    runs = []
    for norad in args.norad or [25544]:
        prim = next(o for o in cat if o.norad_id == norad)
        others = [o for o in cat if o.norad_id != norad]
        res = screen(
            prim,
            others,
            model,
            start=start,
            end=end,
            distance=args.distance,
            execution=rp.Execution(threads=args.threads, progress=False),
        )
        print(
            f"\nprimary {prim.name} ({norad}), {start} + {args.days:g} days, distance "
            f"{args.distance:g} m, {args.model}, grid {res.grid_step:g} s, {res.threads} threads"
        )
        print("counts: " + ", ".join(f"{s} {res.counts[s]}" for s in STAGES))
        rates = {}
        for label, fed, timing in RATES:
            seconds = res.timings[timing]
            n = res.counts[fed]
            wall = seconds / (1 if timing == "radial" else res.threads)
            rate = n / wall if wall > 0 else float("inf")
            rates[label] = rate
            print(
                f"  {label:<13} {n:>6} objects in {seconds:7.2f} thread-s -> "
                f"{rate:>10,.0f} objects/s"
            )
        print(
            f"  primary (field, propagation) {res.timings['primary']:.2f} s; survivors' "
            f"density fields {res.timings['field']:.2f} s"
        )
        total = res.counts["secondaries"] / res.wall
        print(
            f"  whole screen  {res.counts['secondaries']} objects in {res.wall:.2f} s -> "
            f"{total:,.0f} objects/s; {len(res.events)} events"
        )
        for e in res.events[:10]:
            print(
                f"    {e.tca} {e.name2:<24} miss {e.miss_distance:8.1f} m  "
                f"v_rel {e.relative_speed:8.1f} m/s"
            )
        runs.append(
            {
                "primary": norad,
                "name": prim.name,
                "days": args.days,
                "distance": args.distance,
                "model": args.model,
                "counts": res.counts,
                "timings": res.timings,
                "wall": res.wall,
                "threads": res.threads,
                "objects_per_second": rates,
                "whole_objects_per_second": total,
                "events": len(res.events),
            }
        )
    out = Path(__file__).parent / "results" / "screening.json"
    out.write_text(json.dumps({"machine": info(), "runs": runs}, indent=2, default=str) + "\n")


def all_on_all(args: argparse.Namespace) -> None:
    """The whole snapshot screened against itself (see the module docs)."""
    import resource

    from rhoprop.conjunction import screen_all
    from rhoprop.conjunction.all_on_all import ALL_ON_ALL_STAGES

    snapshot = Path(args.data) / args.catalog
    t0 = time.perf_counter()
    cat = catalog.load(snapshot, errors="record", nonpositive_bstar="prior")
    load = time.perf_counter() - t0
    objs = cat.objects[: args.limit] if args.limit else cat.objects
    print(f"{len(objs)} objects loaded in {load:.1f} s ({len(cat.skipped)} skipped)")
    start = max(o.state.epoch for o in objs)
    end = start + np.timedelta64(int(args.days * 86400), "s")
    from rhoprop.studies.scenarios import default_models

    models = default_models()
    res = screen_all(
        objs,
        models,
        start=start,
        end=end,
        distance=args.distance,
        pc=not args.no_pc,
        execution=rp.Execution(threads=args.threads, errors="record", progress=False),
    )
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"\n{start} + {args.days:g} days, distance {args.distance:g} m, models "
        f"{', '.join(res.models)}, grid {res.grid_step:g} s, {res.threads} threads, "
        f"{res.chunks} time chunk(s)"
    )
    print("| stage | seconds |\n| --- | ---: |")
    print(f"| load | {load:.1f} |")
    for key, seconds in res.timings.items():
        print(f"| {key} | {seconds:.1f} |")
    print(f"| **screen_all wall** | **{res.wall:.1f}** |")
    print("\n| filter | count |\n| --- | ---: |")
    for key in ALL_ON_ALL_STAGES:
        print(f"| {key} | {res.counts[key]:,} |")
    finite = np.isfinite(res.pc)
    print(
        f"\n{len(res.events)} events, {int(finite.sum())} with a mixture Pc; "
        f"{int((res.pc > 1e-4).sum())} above 1e-4, {int((res.pc > 1e-6).sum())} above 1e-6; "
        f"peak RSS {peak:,.0f} MB; skipped {len(res.skipped)}, partly screened {len(res.notes)}"
    )
    for name, why in res.skipped[:8]:
        print(f"  skipped {name}: {why[:110]}")
    for e, pc, pcm in list(zip(res.events, res.pc, res.pc_models, strict=True))[:10]:
        per = ", ".join(f"{p:.2g}" for p in pcm)
        print(
            f"  {e.tca} {e.name1[:20]:<20} {e.name2[:20]:<20} miss {e.miss_distance:7.0f} m "
            f"Pc {pc:.2g} ({per})"
        )
    name = "screening_all" + ("" if args.catalog == SNAPSHOT else f"_{Path(args.catalog).name}")
    out = Path(__file__).parent / "results" / f"{name.removesuffix('.gz')}.json"
    out.parent.mkdir(exist_ok=True)
    record = {
        "machine": info(),
        "catalog": args.catalog,
        "objects": len(objs),
        "days": args.days,
        "distance": args.distance,
        "models": res.models,
        "timings": {"load": load, **res.timings},
        "wall": res.wall,
        "counts": res.counts,
        "events": len(res.events),
        "peak_rss_mb": peak,
        "threads": res.threads,
        "chunks": res.chunks,
    }
    out.write_text(json.dumps(record, indent=2, default=str) + "\n")


def dask_scaling(args: argparse.Namespace) -> None:
    """The all-on-all screen locally and on LocalClusters of ``--dask`` workers."""
    import distributed

    from rhoprop.conjunction import screen_all
    from rhoprop.studies.scenarios import default_models

    snapshot = Path(args.data) / "catalogs" / "celestrak_active_20231113.txt.gz"
    cat = catalog.load(snapshot, errors="record", nonpositive_bstar="prior")
    objs = cat.objects[: args.limit or 1500]
    start = max(o.state.epoch for o in objs)
    days = args.days if args.days != 3.0 else 1.0
    end = start + np.timedelta64(int(days * 86400), "s")
    models = default_models()
    kw = dict(start=start, end=end, distance=args.distance, pc=not args.no_pc)
    quiet = rp.Execution(errors="record", progress=False)
    screen_all(objs, models, execution=quiet, **kw)  # warm: the atlas tiles sampled and cached
    local = screen_all(objs, models, execution=quiet, **kw)
    key = [(e.id1, e.id2, e.tca) for e in local.events]
    runs = {"local": local}
    for n in (int(x) for x in args.dask.split(",")):
        with (
            distributed.LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0"
            ) as cluster,
            distributed.Client(cluster) as client,
        ):
            on_dask = rp.Execution(client=client, errors="record", progress=False)
            res = screen_all(objs, models, execution=on_dask, **kw)
        same = [(e.id1, e.id2, e.tca) for e in res.events] == key and np.array_equal(
            res.pc_models, local.pc_models, equal_nan=True
        )
        print(f"{n} worker(s): {len(res.events)} events, same as local: {same}", flush=True)
        runs[f"{n} workers"] = res
    stages = [k for k in local.timings if max(r.timings[k] for r in runs.values()) > 0.05]
    print(
        f"\n{len(objs)} objects, {days:g} day(s), {args.distance:g} m, "
        f"{len(local.events)} events; wall seconds per stage"
    )
    print("| stage | " + " | ".join(runs) + " | a (s) | b (s) |")
    print("| --- |" + " ---: |" * (len(runs) + 2))
    counts = np.array([int(k.split()[0]) for k in runs if k != "local"], dtype=float)
    cores = os.cpu_count() or 1
    fit = counts <= cores  # more workers than cores measure only the split's overhead
    model = {}
    for stage in [*stages, "wall"]:
        times = [r.wall if stage == "wall" else r.timings[stage] for r in runs.values()]
        y = np.array(times[1:])[fit]
        design = np.column_stack([np.ones(fit.sum()), 1 / counts[fit]])
        a, b = np.linalg.lstsq(design, y)[0]
        model[stage] = {
            "a": float(a),
            "b": float(b),
            "seconds": dict(zip(runs, times, strict=True)),
        }
        row = " | ".join(f"{t:.1f}" for t in times)
        print(f"| {stage} | {row} | {a:.1f} | {b:.1f} |")
    wall = model["wall"]
    print(
        f"a + b / N fitted on the runs with at most {cores} workers (this machine's cores); "
        "a: what does not divide (client work: the density fields, the per-event Pc, "
        "transfers), b: what does"
    )
    for n in (8, 32):
        print(f"extrapolated to {n} machines like this one: {wall['a'] + wall['b'] / n:.0f} s")
    out = Path(__file__).parent / "results" / "screening_dask.json"
    out.parent.mkdir(exist_ok=True)
    record = {"machine": info(), "objects": len(objs), "days": days, "model": model}
    out.write_text(json.dumps(record, indent=2, default=str) + "\n")


if __name__ == "__main__":
    main()
