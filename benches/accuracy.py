"""Final-position error of each integrator setting after 3 days on the paper's orbit
(benchmark exponential atmosphere), against scipy's DOP853 at rtol 1e-13 on an
independent numpy right-hand side (tests/reference.py). Needs scipy.

Run:  python benches/accuracy.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
from reference import reference_orbit

SETTINGS = [
    ("dop853", {"rtol": 1e-9}),
    ("dop853", {"rtol": 1e-10}),
    ("dop853", {"rtol": 1e-12}),
    ("rk8", {"step": 120.0}),
    ("rk8", {"step": 180.0}),
    ("rk8", {"step": 240.0}),
    ("rk4", {"step": 5.0}),
    ("rk4", {"step": 10.0}),
]


def main() -> None:
    print(describe())
    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    model = rp.scenarios.benchmark_exponential()
    duration = rp.scenarios.PAPER_DURATION
    ref = reference_orbit(
        state.state, np.array([0.0, duration]), 3.725e-12, 400e3, 58.515e3, craft.drag_parameter
    )[-1, :3]
    print(f"{'method':<8} {'setting':<14} {'RHS evals':>10} {'final error [m]':>16}")
    for method, options in SETTINGS:
        tr = rp.propagate(
            state, craft, model, duration, dynamics=rp.Dynamics(integrator=method), **options
        )
        err = np.linalg.norm(tr.positions[-1] - ref)
        setting = ", ".join(f"{k}={v:g}" for k, v in options.items())
        print(f"{method:<8} {setting:<14} {tr.evaluations:>10} {err:>16.4f}")


if __name__ == "__main__":
    main()
