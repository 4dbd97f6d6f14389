"""Reentry windows over objects whose epochs spread across months: the low-perigee objects
of several real CelesTrak snapshots of 2023 (July, August, November; the reference data's
catalogs/history), one element set per object and file, through NRLMSIS 2.1's atlas.
Before the atlas this sampled one field over the union of every epoch to the horizon
(months of days times the whole altitude band); now each object gets the day tiles of its
own span. Prints the time, peak RSS and the atlas's peak tile memory.

Run:  python benches/reentry_spread.py [--perigee-km 300] [--members 40] [--horizon-days 12]
"""

from __future__ import annotations

import argparse
import gzip
import os
import tempfile
import time
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe, element_sets, peak_rss_mb, perigee_altitude

FILES = (
    "history/celestrak_active_20230704.txt.gz",
    "history/celestrak_active_20230807.txt.gz",
    "history/celestrak_active_20230820.txt.gz",
    "celestrak_active_20231113.txt.gz",
)


def low_perigee(text: str, km: float) -> list[str]:
    """The 3-line element sets whose mean perigee is below ``km``."""
    out: list[str] = []
    for name, l1, l2, sat in element_sets(text):
        if perigee_altitude(sat) < km * 1e3:
            out += [name, l1, l2]
    return out


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--perigee-km", type=float, default=300.0)
    parser.add_argument("--members", type=int, default=40)
    parser.add_argument("--horizon-days", type=float, default=12.0)
    parser.add_argument(
        "--data",
        default=os.environ.get("RHOPROP_TEST_DATA", str(Path(__file__).parents[2] / "shared/data")),
    )
    args = parser.parse_args()
    lines: list[str] = []
    for name in FILES:
        lines += low_perigee(
            gzip.open(Path(args.data) / "catalogs" / name, "rt").read(), args.perigee_km
        )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "low.tle"
        path.write_text("\n".join(lines) + "\n")
        cat = rp.catalog.load(path, errors="record")
    epochs = np.array([o.state.epoch for o in cat])
    print(
        f"{len(cat)} element sets with perigee < {args.perigee_km:g} km, "
        f"epochs {epochs.min()} to {epochs.max()}"
    )
    model = rp.density.Msis("2.1")
    t0 = time.perf_counter()
    res = rp.catalog.reentry(
        cat,
        model,
        method=rp.MonteCarlo(n=args.members),
        duration=args.horizon_days * 86400.0,
        groups=4,
    )
    wall = time.perf_counter() - t0
    predicted = int(np.count_nonzero(~np.isnat(res.epoch_median)))
    memory = rp.density.field_memory()
    print(
        f"reentry: {len(cat)} objects x {args.members} members x {args.horizon_days:g} days in "
        f"{wall:.0f} s; {predicted} predicted to come down within the horizon"
    )
    print(
        f"peak RSS {peak_rss_mb():.0f} MB; atlas: peak {memory.peak / 1e6:.0f} MB of tiles, "
        f"budget {memory.budget / 1e6:.0f} MB"
    )


if __name__ == "__main__":
    main()
