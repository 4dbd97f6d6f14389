"""Time to sample one NRLMSIS density field for the paper's window (3 days + 8 h, Case I),
per model version, with the disk cache off; and the cached reload.

Run:  python benches/field_sampling.py [--repeat 3]
Prints a table and writes benches/results/field_sampling.json.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe, info
from rhoprop.density import altitude_band
from rhoprop.density.msis import Msis


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    sw = rp.SpaceWeather()
    state = rp.scenarios.paper_state()
    start = state.epoch - np.timedelta64(8, "h")
    end = state.epoch + np.timedelta64(3, "D")
    band = altitude_band(state.position, state.velocity)
    rows = []
    for version in ("2.1", "2.0", "00"):
        model = Msis(version, space_weather=sw)
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            field = model.field(start, end, altitude_range=band, cache=False)
            times.append(time.perf_counter() - t0)
        with tempfile.TemporaryDirectory() as tmp:
            import os

            os.environ["RHOPROP_CACHE"] = tmp
            model.field(start, end, altitude_range=band)
            t0 = time.perf_counter()
            model.field(start, end, altitude_range=band)
            cached = time.perf_counter() - t0
            del os.environ["RHOPROP_CACHE"]
        rows.append(
            {
                "version": version,
                "grid": list(field.ln_mean.shape),
                "sample_s_median": float(np.median(times)),
                "cached_reload_s": cached,
            }
        )
        r = rows[-1]
        print(
            f"NRLMSIS {version:>3}: grid {tuple(r['grid'])}  sample {r['sample_s_median']:.2f} s "
            f"(median of {args.repeat})  cached reload {r['cached_reload_s'] * 1e3:.1f} ms"
        )
    out = Path(__file__).parent / "results" / "field_sampling.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps({**info(), "altitude_band_m": band, "rows": rows}, indent=2))


if __name__ == "__main__":
    main()
