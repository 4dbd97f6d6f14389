"""Peak memory of long runs through a sampled model against the atlas's tile budget: a
365-day propagation of one object and a 90-day reentry run (100 members) through
NRLMSIS 2.1 at the default resolution, each in its own process with
``RHOPROP_FIELD_MEMORY`` (default here 2e8 bytes). A run longer than ``STREAM_TILES``
days streams its tiles (``Atlas.streamed``), so the peak should stay within the budget
plus the process's own size, whatever the run's length.

Run:  RHOPROP_TEST_DATA=../shared/data python benches/memory_long.py [--budget 2e8]
      [--case year|reentry|both] [--no-stream]
The first run samples the tiles (about a second a day) and caches them on disk
(about 17 MB a day); later runs read them back.
"""

from __future__ import annotations

import argparse
import csv
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from machine import describe
from rhoprop import MonteCarlo


def peak_mb() -> float:
    """Peak resident set size of this process, MB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def baseline_mb() -> float:
    """RSS after importing rhoprop and loading NRLMSIS and the space weather, MB."""
    import rhoprop as rp

    rp.density.Msis("2.1").mean_std(np.datetime64("2023-01-02"), 0.0, 0.0, 400e3)
    return peak_mb()


def year() -> str:
    """One object at 550 km, 365 days from 2023-01-01."""
    import rhoprop as rp

    base = baseline_mb()
    r = 6378137.0 + 550e3
    v = np.sqrt(3.986004418e14 / r)
    inc = np.radians(53.0)
    state = rp.OrbitState(
        np.datetime64("2023-01-01T00:00"), [r, 0.0, 0.0], [0.0, v * np.cos(inc), v * np.sin(inc)]
    )
    model = rp.density.Msis("2.1")
    t0 = time.perf_counter()
    out = rp.propagate(state, rp.Spacecraft(2.2, 0.01), model, 365 * 86400.0)
    alt = (np.linalg.norm(out.positions[-1]) - 6378137.0) / 1e3
    return (
        f"year: 365 days of one object, {time.perf_counter() - t0:.0f} s, final altitude "
        f"{alt:.0f} km; baseline {base:.0f} MB, peak RSS {peak_mb():.0f} MB"
    )


def reentry() -> str:
    """The reentry element set with the longest lead to its SATCAT decay within 90 days,
    100 members over 90 days."""
    import rhoprop as rp

    base = baseline_mb()
    data = Path(os.environ["RHOPROP_TEST_DATA"]) / "reentry"
    with open(data / "satcat_decay_2022_2023.csv") as f:
        decay = {int(r["NORAD_CAT_ID"]): np.datetime64(r["DECAY_DATE"]) for r in csv.DictReader(f)}
    catalog = rp.catalog.load(data / "reentry_tles_2022_2023.txt", fit=False)
    best, lead = None, 0.0
    for obj in catalog:
        days = (decay[obj.norad_id] - obj.state.epoch) / np.timedelta64(1, "D")
        if lead < days <= 90.0:
            best, lead = obj, float(days)
    assert best is not None
    t0 = time.perf_counter()
    result = rp.catalog.reentry(
        [best],
        rp.density.Msis("2.1"),
        duration=90 * 86400.0,
        method=MonteCarlo(n=100),
    )
    return (
        f"reentry: NORAD {best.norad_id}, SATCAT decay {lead:.0f} days after its epoch, "
        f"100 members over 90 days, {time.perf_counter() - t0:.0f} s, median decay "
        f"{result.epoch_median[0]}, decayed {result.decayed_fraction[0]:.2f}; "
        f"baseline {base:.0f} MB, peak RSS {peak_mb():.0f} MB"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--budget", type=float, default=2e8, help="RHOPROP_FIELD_MEMORY, bytes")
    parser.add_argument("--case", choices=["year", "reentry", "both"], default="both")
    parser.add_argument(
        "--no-stream", action="store_true", help="every run holds all its tiles (the old way)"
    )
    parser.add_argument("--child", choices=["year", "reentry"], help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        if args.no_stream:
            from rhoprop.density import atlas

            atlas.STREAM_TILES = 10**9
        print({"year": year, "reentry": reentry}[args.child]())
        return
    print(describe())
    print(f"RHOPROP_FIELD_MEMORY = {args.budget:.3g} bytes ({args.budget / 2**20:.0f} MB)")
    env = dict(os.environ, RHOPROP_FIELD_MEMORY=str(int(args.budget)))
    cases = ["year", "reentry"] if args.case == "both" else [args.case]
    for case in cases:
        child = [sys.executable, __file__, "--child", case] + ["--no-stream"] * args.no_stream
        subprocess.run(child, env=env, check=True)


if __name__ == "__main__":
    main()
