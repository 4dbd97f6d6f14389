"""Peak memory of a 100,000-member Monte Carlo (3 days, GaussMarkov 18 min, benchmark
exponential atmosphere with 20 % sigma) with final-state output only.

Run:  /usr/bin/time -v python benches/memory_100k.py   (read "Maximum resident set size")
"""

from __future__ import annotations

import time

import rhoprop as rp
from machine import describe

print(describe())
state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
t0 = time.perf_counter()
mc = rp.monte_carlo(
    state,
    craft,
    rp.scenarios.benchmark_exponential(0.2),
    259200.0,
    n=100_000,
    output_step=None,
    progress=False,
)
print(
    f"100000 members x 3 days: {time.perf_counter() - t0:.1f} s; "
    f"along-track std {mc.along_track[:, -1].std():.1f} m"
)
