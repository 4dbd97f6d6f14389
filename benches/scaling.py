"""Thread scaling of the stochastic problem: 1000 members x 3 days, GaussMarkov(18 min),
NRLMSIS 2.1 field of Case I (sampled once, excluded), on 1 and 2 threads.

Run:  python benches/scaling.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import rhoprop as rp
from machine import describe


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    end = state.epoch + np.timedelta64(3, "D")
    field = rp.density.Msis("2.1").atlas.field(state.epoch, end)  # the day tiles
    walls = {}
    for threads in (1, 2):
        runs = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            rp.monte_carlo(
                state,
                craft,
                field,
                259200.0,
                n=1000,
                output_step=None,
                progress=False,
                threads=threads,
            )
            runs.append(time.perf_counter() - t0)
        walls[threads] = float(np.median(runs))
        print(
            f"{threads} thread(s): {walls[threads]:.2f} s, "
            f"{3000 / walls[threads]:,.0f} member-days/s"
        )
    print(f"parallel efficiency on 2 threads: {walls[1] / (2 * walls[2]):.0%}")


if __name__ == "__main__":
    main()
