"""Catalog throughput: a LEO catalog propagated with the CCSP filter for 3 days through one
NRLMSIS 2.1 atlas (day tiles), locally and (with --dask) on a 2-worker Dask LocalCluster; field
sampling timed separately. The catalog is synthetic (generated here with sgp4's exporter:
circular-ish orbits 350-800 km, inclinations 40-98 deg, B* 1e-5..5e-4, epochs spread over
a day) or, with --real, the CelesTrak snapshot of 2023-11-13 in the reference data
(objects with perigee below 700 km and B* > 0, manoeuvring constellations excluded; with
--below-km 1000 every object whose altitude at its epoch is below 1,000 km, as it comes).
Prints the peak RSS and the atlas's peak tile memory.

With --whole: every element set of that snapshot as published (LEO, MEO, GEO, HEO, stale
epochs) with the library's defaults for 7 days, timed per stage (load, field tiles, fit,
propagation, output) with the peak memory; --dask adds the run on a 2-worker cluster.

Run:  python benches/catalog.py [--objects 2000] [--real [--data ../shared/data]
                                [--below-km 1000]] [--dask]
      python benches/catalog.py --whole [--dask]
"""

from __future__ import annotations

import argparse
import collections
import gzip
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from sgp4 import exporter
from sgp4.api import WGS72, Satrec

import rhoprop as rp
from machine import describe, element_sets, peak_rss_mb, perigee_altitude
from rhoprop import catalog

JD_EPOCH = 2452524.0  # 2002-09-06 12:00 UTC


def synthetic_tle(n: int, seed: int = 0) -> str:
    rng = np.random.default_rng(seed)
    lines = []
    for k in range(n):
        sat = Satrec()
        alt = rng.uniform(350e3, 800e3)
        mean_motion = np.sqrt(3.986004418e14 / (6378137.0 + alt) ** 3) * 60.0
        sat.sgp4init(
            WGS72,
            "i",
            10000 + k,
            JD_EPOCH - 2433281.5 + rng.uniform(0, 1),
            10 ** rng.uniform(-5, np.log10(5e-4)),
            0.0,
            0.0,
            rng.uniform(1e-4, 5e-3),
            rng.uniform(0, 2 * np.pi),
            np.radians(rng.uniform(40, 98)),
            rng.uniform(0, 2 * np.pi),
            mean_motion,
            rng.uniform(0, 2 * np.pi),
        )
        l1, l2 = exporter.export_tle(sat)
        l1 = l1[:9] + "02900A  " + l1[17:68]
        lines += [l1 + str(exporter.compute_checksum(l1)), l2]
    return "\n".join(lines) + "\n"


def leo_subset(text: str, limit: int) -> str:
    """The first ``limit`` 3-line element sets with perigee below 700 km and B* > 0,
    without the manoeuvring constellations (Starlink, OneWeb)."""
    out: list[str] = []
    for name, l1, l2, sat in element_sets(text):
        if any(tag in name.upper() for tag in ("STARLINK", "ONEWEB")):
            continue
        if sat.bstar > 0 and perigee_altitude(sat) < 700e3:
            out += [name, l1, l2]
        if len(out) >= 3 * limit:
            break
    return "\n".join(out) + "\n"


def below_subset(text: str, km: float) -> str:
    """Every 3-line element set whose SGP4 altitude at its own epoch is below ``km`` (the
    selection a user makes first: HEO objects near perigee, stale epochs and manoeuvring
    constellations included)."""
    out: list[str] = []
    for name, l1, l2, sat in element_sets(text):
        err, r, _v = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
        if err == 0 and np.linalg.norm(r) - 6378.137 < km:
            out += [name, l1, l2]
    return "\n".join(out) + "\n"


def fit_all(snapshot: Path) -> None:
    """Fits every element set of a whole snapshot through NRLMSIS 2.1's atlas."""
    model = rp.density.Msis("2.1")
    t0 = time.perf_counter()
    cat = catalog.load(
        snapshot,
        errors="record",
        fit=rp.catalog.FitSettings(model),
    )
    wall = time.perf_counter() - t0
    fitted = sum(o.fit is not None for o in cat)
    notes = collections.Counter(
        "fit failed" if "fit failed" in o.covariance_note else "fitted" if o.fit else "not fitted"
        for o in cat
    )
    memory = rp.density.atlas.field_memory()
    print(
        f"load(fit=True): {len(cat)} objects kept ({fitted} fitted; {dict(notes)}), "
        f"{len(cat.skipped)} skipped, in {wall:.0f} s = {len(cat) / wall:.1f} objects/s"
    )
    print(
        f"peak RSS {peak_rss_mb():.0f} MB; atlas: peak {memory.peak / 1e6:.0f} MB of tiles, "
        f"budget {memory.budget / 1e6:.0f} MB"
    )


def on_dask(objs, model, end, errors="raise"):
    """(result, wall s) of ``propagate_catalog`` on a 2-worker Dask LocalCluster."""
    import distributed

    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        t0 = time.perf_counter()
        run_on = rp.Execution(client=client, progress=False, errors=errors)
        remote = catalog.propagate_catalog(objs, model, end, execution=run_on)
        return remote, time.perf_counter() - t0


def whole(snapshot: Path, days: float, dask: bool) -> None:
    """Every element set of a snapshot as published, with the defaults (near-Earth objects
    below 700 km and deep-space objects fitted, CCSP, NRLMSIS 2.1), ``days`` after the
    newest epoch: the time of each stage and the peak memory; with ``dask`` the same on a
    2-worker LocalCluster."""
    from rhoprop.catalog.objects import fit_catalog_objects
    from rhoprop.io import write_ephemeris, write_oem, write_summary

    model = rp.density.Msis("2.1")
    stages: dict[str, float] = {}
    t0 = time.perf_counter()
    cat = catalog.load(snapshot, errors="record")
    stages["load"] = time.perf_counter() - t0
    epochs = np.array([o.state.epoch for o in cat])
    end = epochs.max() + np.timedelta64(int(days * 86400), "s")
    print(f"{len(cat)} objects ({len(cat.skipped)} skipped by the loader), epochs "
          f"{epochs.min()} to {epochs.max()}, to {end}")  # fmt: skip
    t0 = time.perf_counter()
    model.atlas.field(epochs.min() - np.timedelta64(1, "D"), end)
    stages["field tiles"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    objs = fit_catalog_objects(list(cat), model, "auto", rp.Dynamics(zonal_degree=4))
    stages["fit"] = time.perf_counter() - t0
    fitted = sum(o.fit is not None for o in objs)
    t0 = time.perf_counter()
    local = catalog.propagate_catalog(
        objs,
        model,
        end,
        execution=rp.Execution(progress=False, errors="record"),
    )
    stages["propagation"] = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        write_ephemeris(local, Path(tmp) / "ephemeris.parquet")
        write_summary(local, Path(tmp) / "summary.parquet")
        stages["output (ephemeris, summary)"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        write_oem(local, Path(tmp) / "oem")
        stages["OEM files (--oem)"] = time.perf_counter() - t0
    total = sum(v for k, v in stages.items() if not k.startswith("OEM"))  # the default run
    print(f"{fitted} fitted; statuses: {dict(collections.Counter(local.status.tolist()))}")
    print("| stage | s |\n| --- | ---: |")
    for name, wall in stages.items():
        print(f"| {name} | {wall:.1f} |")
    print(f"| total | {total:.1f} ({len(cat) / total:.0f} objects/s) |")
    memory = rp.density.atlas.field_memory()
    print(f"peak RSS {peak_rss_mb():.0f} MB; atlas peak {memory.peak / 1e6:.0f} MB of tiles")
    if not dask:
        return
    # The local result is kept as a digest only: the Dask run's memory is then its own.
    digest = result_digest(local)
    del local
    remote, wall = on_dask(objs, model, end, errors="record")
    same = result_digest(remote) == digest
    local_wall = stages["propagation"]
    print(f"Dask LocalCluster, 2 workers: propagation {wall:.1f} s (local {local_wall:.1f} s); "
          f"identical to local: {same}")  # fmt: skip
    import resource

    # After the Dask run: this process (its peak over both runs) and its largest finished
    # child process (the LocalCluster's workers, once closed).
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    main_mb = peak_rss_mb()
    print(f"peak RSS after Dask: this process {main_mb:.0f} MB, largest worker {children:.0f} MB")


def result_digest(result) -> str:
    """SHA-256 of a catalog result's means, covariances, validity and statuses: equal
    digests are bit-identical results (NaNs included)."""
    import hashlib

    h = hashlib.sha256()
    for array in (result.mean, result.covariance, result.valid):
        h.update(np.ascontiguousarray(array).tobytes())
    h.update("\n".join(result.status.tolist()).encode())
    return h.hexdigest()


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--objects", type=int, default=2000)
    parser.add_argument("--days", type=float, default=3.0)
    parser.add_argument("--real", action="store_true", help="the real 2023-11-13 snapshot")
    parser.add_argument(
        "--data",
        default=os.environ.get("RHOPROP_TEST_DATA", str(Path(__file__).parents[2] / "shared/data")),
        help="reference data directory (default $RHOPROP_TEST_DATA or ../shared/data)",
    )
    parser.add_argument("--dask", action="store_true", help="also run on a Dask LocalCluster")
    parser.add_argument(
        "--below-km",
        type=float,
        default=None,
        help="with --real: every object whose altitude at its epoch is below this (km), "
        "no other filter (--objects ignored)",
    )
    parser.add_argument(
        "--fit-all",
        action="store_true",
        help="instead: load(fit=True, model=Msis('2.1')) on the whole 2023-11-13 snapshot "
        "(time, objects fitted, peak RSS)",
    )
    parser.add_argument(
        "--whole",
        action="store_true",
        help="instead: every element set of the 2023-11-13 snapshot as published, defaults, "
        "--days (default here 7) after the newest epoch: time per stage, peak RSS (--dask: "
        "also on a LocalCluster)",
    )
    args = parser.parse_args()
    if args.whole:
        snapshot = Path(args.data) / "catalogs" / "celestrak_active_20231113.txt.gz"
        whole(snapshot, 7.0 if args.days == 3.0 else args.days, args.dask)
        return
    if args.fit_all:
        fit_all(Path(args.data) / "catalogs" / "celestrak_active_20231113.txt.gz")
        return
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "catalog.tle"
        if args.real:
            snapshot = Path(args.data) / "catalogs" / "celestrak_active_20231113.txt.gz"
            text = gzip.open(snapshot, "rt").read()
            if args.below_km is not None:
                path.write_text(below_subset(text, args.below_km))
            else:
                path.write_text(leo_subset(text, args.objects))
        else:
            path.write_text(synthetic_tle(args.objects))
        cat = catalog.load(path, errors="record")
    print(f"{len(cat)} objects ({'real snapshot' if args.real else 'synthetic'})")
    epochs = np.array([o.state.epoch for o in cat])
    print(f"epochs from {epochs.min()} to {epochs.max()}")
    end = max(o.state.epoch for o in cat) + np.timedelta64(int(args.days * 86400), "s")
    model = rp.density.Msis("2.1")
    t0 = time.perf_counter()
    catalog.propagate_catalog(
        cat,
        model,
        end,
        execution=rp.Execution(progress=False, errors="record"),
    )
    first = time.perf_counter() - t0
    # The second run finds the field in the disk cache: propagation alone.
    t0 = time.perf_counter()
    local = catalog.propagate_catalog(
        cat,
        model,
        end,
        execution=rp.Execution(progress=False, errors="record"),
    )
    wall = time.perf_counter() - t0
    print(f"first run, field sampling included: {first:.1f} s (field ~{first - wall:.1f} s)")
    memory = rp.density.atlas.field_memory()
    print(
        f"peak RSS {peak_rss_mb():.0f} MB; atlas: peak {memory.peak / 1e6:.0f} MB of tiles, "
        f"{memory.tiles} alive, budget {memory.budget / 1e6:.0f} MB"
    )
    field = model
    print(f"statuses: {dict(collections.Counter(local.status.tolist()))}")
    print(
        f"local (chunks of objects per core call, objects in parallel, each object's sigma "
        f"points in one batch): {len(cat)} objects x "
        f"{args.days:g} days in {wall:.1f} s = {len(cat) / wall:.1f} objects/s"
    )
    if not args.dask:
        return
    remote, wall = on_dask(cat, field, end)
    print(
        f"Dask LocalCluster, 2 workers: {len(cat)} objects in {wall:.1f} s = "
        f"{len(cat) / wall:.1f} objects/s; identical to local: "
        f"{np.array_equal(remote.mean, local.mean)}"
    )


if __name__ == "__main__":
    main()
