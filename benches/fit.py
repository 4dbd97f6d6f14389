"""Fit throughput: states and Cd*A/m fitted to element sets
(``rp.catalog.fit_objects``, what ``load(fit=True)`` runs) for LEO objects of the
2023-11-13 CelesTrak snapshot through NRLMSIS 2.1's atlas, J2..J4, over the day before
each epoch (``fit.DEFAULT_SPAN``). The batched core fit (8 lanes a trial, many objects a
call) is timed against the Python Gauss-Newton it replaced (``tests/reference_fit.py``:
one single-trajectory core propagation per Jacobian column) on a subset, in the same run,
with the tiles warm; prints objects/s of each, their ratio and how far apart their
solutions are in units of the fit's formal sigma. Writes ``benches/results/fit.json``.

Run:  RHOPROP_TEST_DATA=../shared/data python benches/fit.py [--objects 300]
                                                             [--reference 12]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe, info, peak_rss_mb, perigee_altitude
from rhoprop import catalog
from rhoprop.catalog.fit import DEFAULT_SPAN

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from reference_fit import reference_fit


def leo_objects(data: Path, count: int) -> list[catalog.CatalogObject]:
    """``count`` objects spread over the snapshot's LEO element sets (perigee 200-700 km,
    B* > 0, Starlink/OneWeb excluded), as ``load`` makes them."""
    cat = catalog.load(data / "catalogs" / "celestrak_active_20231113.txt.gz", errors="record")
    leo = [
        o
        for o in cat
        if o.bstar > 0
        and not any(t in o.name.upper() for t in ("STARLINK", "ONEWEB"))
        and 200e3 < perigee_altitude(o.satrec()) < 700e3
    ]
    pick = np.linspace(0, len(leo) - 1, min(count, len(leo))).round().astype(int)
    return [leo[i] for i in pick]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--objects", type=int, default=300)
    parser.add_argument("--reference", type=int, default=12, help="objects the baseline fits")
    parser.add_argument("--data", default=os.environ.get("RHOPROP_TEST_DATA", "../shared/data"))
    args = parser.parse_args()
    print(describe())
    objs = leo_objects(Path(args.data), args.objects)
    model = rp.density.Msis("2.1")
    catalog.fit_objects(
        objs[:4],
        model,
        dynamics=rp.Dynamics(zonal_degree=4),
    )  # tiles of the days: warm
    day = np.timedelta64(1, "D")
    for o in objs:
        model.atlas.field(o.state.epoch - day, o.state.epoch + day)
    t0 = time.perf_counter()
    fitted = catalog.fit_objects(
        objs,
        model,
        dynamics=rp.Dynamics(zonal_degree=4),
    )
    core_wall = time.perf_counter() - t0
    failed = sum(isinstance(f, Exception) for f in fitted)
    core_rate = len(objs) / core_wall
    print(f"batched core fit: {len(objs)} objects in {core_wall:.2f} s = {core_rate:.1f} objects/s "
          f"({failed} failed)")  # fmt: skip

    sub = [i for i, f in enumerate(fitted) if not isinstance(f, Exception)][: args.reference]
    t0 = time.perf_counter()
    refs = [reference_fit(objs[i].satrec(), model.atlas, span=DEFAULT_SPAN, zonal=4) for i in sub]
    ref_wall = time.perf_counter() - t0
    ref_rate = len(sub) / ref_wall
    worst = 0.0
    for i, (p_ref, _) in zip(sub, refs, strict=True):
        f = fitted[i].fit
        p = np.concatenate([f.state.state, [f.drag_parameter]])
        worst = max(worst, float(np.max(np.abs(p - p_ref) / np.sqrt(np.diag(f.covariance)))))
    print(f"Python reference fit: {len(sub)} objects in {ref_wall:.2f} s = "
          f"{ref_rate:.1f} objects/s")  # fmt: skip
    print(f"ratio batched / reference: {core_rate / ref_rate:.1f}x; largest difference of the "
          f"solutions: {worst:.3f} formal sigma; peak RSS {peak_rss_mb():.0f} MB")  # fmt: skip
    out = Path(__file__).parent / "results" / "fit.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(
        json.dumps(
            {
                "machine": info(),
                "objects": len(objs),
                "failed": failed,
                "core_objects_per_s": core_rate,
                "reference_objects_per_s": ref_rate,
                "ratio": core_rate / ref_rate,
                "largest_difference_sigma": worst,
            },
            indent=1,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
