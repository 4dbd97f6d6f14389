"""JB2008 and Jacchia-Roberts point-evaluation time (µs/point, wall, on the rayon
pool: set RAYON_NUM_THREADS=1 for one thread) and the time to sample each default
model's density field over the paper's
window (3 days + 8 h before Case I's epoch, disk cache off).

Needs the JB2008 index files: RHOPROP_JB2008_DATA=../shared/data/jb2008 (or the cache).
Run:  RHOPROP_JB2008_DATA=../shared/data/jb2008 python benches/density_models.py [--repeat 3]
Prints a table and writes benches/results/density_models.json.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

import rhoprop as rp
from machine import describe, info
from rhoprop import _core
from rhoprop.density import altitude_band
from rhoprop.density.point_model import modified_julian_date


def _best(f: Any, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--points", type=int, default=200_000)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    n = args.points
    state = rp.scenarios.paper_state()
    t = state.epoch + (rng.uniform(0, 3 * 86400, n) * 1e9).astype("timedelta64[ns]")
    mjd = modified_julian_date(t)
    lat, lon = rng.uniform(-90, 90, n), rng.uniform(-180, 180, n)
    alt = rng.uniform(150e3, 800e3, n)
    indices = rp.density.Jb2008Indices.default()
    jb_ix = indices.at(t)
    jr_dr = rp.density.JacchiaRoberts().drivers(t)
    points = {}
    threads = os.environ.get("RAYON_NUM_THREADS") or str(os.cpu_count())
    for name, call in (
        ("JB2008", lambda: _core.jb2008_geodetic(mjd, lat, lon, alt, jb_ix)),
        ("Jacchia-Roberts", lambda: _core.jacchia_roberts_geodetic(mjd, lat, lon, alt, jr_dr)),
    ):
        s = _best(call, args.repeat)
        points[name] = s / n * 1e6
        print(f"{name:16s} {s / n * 1e6:7.3f} µs/point wall on {threads} thread(s) ({n} points)")
    start = state.epoch - np.timedelta64(8, "h")
    end = state.epoch + np.timedelta64(3, "D")
    band = altitude_band(state.position, state.velocity)
    sw = rp.SpaceWeather()
    models = {
        "NRLMSIS 2.1": rp.density.Msis("2.1", space_weather=sw),
        "JB2008": rp.density.Jb2008(indices),
        "Jacchia-Roberts 1971": rp.density.JacchiaRoberts(sw),
        "NRLMSISE-00": rp.density.Msis("00", space_weather=sw),
    }
    fields = {}
    for name, model in models.items():
        field = model.field(start, end, altitude_range=band, cache=False)
        s = _best(
            lambda m=model: m.field(start, end, altitude_range=band, cache=False), args.repeat
        )
        fields[name] = {"grid": list(field.ln_mean.shape), "sample_s": s}
        print(
            f"field {name:22s} grid {tuple(field.ln_mean.shape)}  {s:.2f} s (best of {args.repeat})"
        )
    out = Path(__file__).parent / "results" / "density_models.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(
        json.dumps(
            {
                **info(),
                "threads": threads,
                "points": n,
                "us_per_point": points,
                "fields": fields,
                "band_m": band,
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
