"""Catalog throughput: a synthetic LEO catalog (generated here with sgp4's exporter:
circular-ish orbits 350-800 km, inclinations 40-98 deg, B* 1e-5..5e-4, epochs spread over
a day) propagated with the CCSP filter for 3 days through one NRLMSIS 2.1 field, locally
and on a 2-worker Dask LocalCluster. Field sampling is timed separately.

Run:  python benches/catalog.py [--objects 2000]
"""

from __future__ import annotations

import argparse
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


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--objects", type=int, default=2000)
    parser.add_argument("--days", type=float, default=3.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "synthetic.tle"
        path.write_text(synthetic_tle(args.objects))
        cat = catalog.load(path)
    end = max(o.state.epoch for o in cat) + np.timedelta64(int(args.days * 86400), "s")
    t0 = time.perf_counter()
    payload = catalog._payload(rp.density.Msis("2.1"), cat.objects, end)
    field = catalog._model_from_payload(payload)
    print(f"field sampling over the catalog's altitude band: {time.perf_counter() - t0:.1f} s")
    t0 = time.perf_counter()
    local = catalog.propagate_catalog(cat, field, end, progress=False)
    wall = time.perf_counter() - t0
    print(
        f"local (objects on threads, sigma points on rayon): {len(cat)} objects in {wall:.1f} s = "
        f"{len(cat) / wall:.1f} objects/s"
    )
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
