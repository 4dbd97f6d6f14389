"""Catalog throughput: a LEO catalog propagated with the CCSP filter for 3 days through one
NRLMSIS 2.1 field, locally and (with --dask) on a 2-worker Dask LocalCluster; field
sampling timed separately. The catalog is synthetic (generated here with sgp4's exporter:
circular-ish orbits 350-800 km, inclinations 40-98 deg, B* 1e-5..5e-4, epochs spread over
a day) or, with --real, the CelesTrak snapshot of 2023-11-13 in the reference data
(objects with perigee below 700 km and B* > 0, manoeuvring constellations excluded).

Run:  python benches/catalog.py [--objects 2000] [--real [--data ../shared/data]] [--dask]
"""

from __future__ import annotations

import argparse
import gzip
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from sgp4 import exporter
from sgp4.api import WGS72, Satrec

import rhoprop as rp
from machine import describe
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
    lines = [ln.rstrip() for ln in text.splitlines() if ln.strip()]
    out: list[str] = []
    for k in range(0, len(lines) - 2, 3):
        name, l1, l2 = lines[k : k + 3]
        if not (l1.startswith("1 ") and l2.startswith("2 ")):
            continue
        if any(tag in name.upper() for tag in ("STARLINK", "ONEWEB")):
            continue
        sat = Satrec.twoline2rv(l1, l2)
        a = (3.986004418e14 / (sat.no_kozai / 60.0) ** 2) ** (1 / 3)
        if sat.bstar > 0 and a * (1 - sat.ecco) - 6378137.0 < 700e3:
            out += [name, l1, l2]
        if len(out) >= 3 * limit:
            break
    return "\n".join(out) + "\n"


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
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "catalog.tle"
        if args.real:
            snapshot = Path(args.data) / "catalogs" / "celestrak_active_20231113.txt.gz"
            path.write_text(leo_subset(gzip.open(snapshot, "rt").read(), args.objects))
        else:
            path.write_text(synthetic_tle(args.objects))
        cat = catalog.load(path, errors="skip")
    print(f"{len(cat)} objects ({'real snapshot' if args.real else 'synthetic'})")
    end = max(o.state.epoch for o in cat) + np.timedelta64(int(args.days * 86400), "s")
    model = rp.density.Msis("2.1")
    t0 = time.perf_counter()
    catalog.propagate_catalog(cat, model, end, progress=False, errors="record")
    first = time.perf_counter() - t0
    # The second run finds the field in the disk cache: propagation alone.
    t0 = time.perf_counter()
    local = catalog.propagate_catalog(cat, model, end, progress=False, errors="record")
    wall = time.perf_counter() - t0
    print(f"first run, field sampling included: {first:.1f} s (field ~{first - wall:.1f} s)")
    field = model
    print(
        f"local (chunks of objects per core call, objects in parallel, each object's sigma "
        f"points in one batch): {len(cat)} objects x "
        f"{args.days:g} days in {wall:.1f} s = {len(cat) / wall:.1f} objects/s"
    )
    if not args.dask:
        return
    import distributed

    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        t0 = time.perf_counter()
        remote = catalog.propagate_catalog(cat, field, end, client=client, progress=False)
        wall = time.perf_counter() - t0
    print(
        f"Dask LocalCluster, 2 workers: {len(cat)} objects in {wall:.1f} s = "
        f"{len(cat) / wall:.1f} objects/s; identical to local: "
        f"{np.array_equal(remote.mean, local.mean)}"
    )


if __name__ == "__main__":
    main()
