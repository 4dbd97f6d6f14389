"""CCSP vs Monte Carlo cost: 3 days through the NRLMSIS 2.1 field of Case I, CCSP with
60-min updates vs a 1000-member GaussMarkov(18 min) Monte Carlo, same run, all cores; the
CCSP in equinoctial elements (the default) against the Cartesian one (the paper's), 3 and
7 days; and the cost of the slow density term's own sigma point: a catalog's default run
(two-scale kappa and a Cd*A/m sigma: 17 sigma points) against the same without the slow
term (16, the lanes of the filter before it had its own point), 7 days, 64 objects in one
``ccsp_many`` call.

Run:  python benches/ccsp.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe, info


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    duration = rp.scenarios.PAPER_DURATION
    end = state.epoch + np.timedelta64(7 * 86400, "s")
    field = rp.density.Msis("2.1").atlas.field(state.epoch, end)  # the day tiles
    results = {}
    for name, atmosphere in (
        ("exponential", rp.scenarios.benchmark_exponential(0.2)),
        ("NRLMSIS 2.1 atlas", field),
    ):
        cc = median_time(lambda a=atmosphere: rp.ccsp(state, craft, a, duration), args.repeat)
        mc = median_time(
            lambda a=atmosphere: rp.monte_carlo(
                state, craft, a, duration, n=1000, output_step=None, progress=False
            ),
            args.repeat,
        )
        results[name] = {"ccsp_s": cc, "monte_carlo_s": mc, "ratio": mc / cc}
        for days in (3, 7):
            span = days * 86400.0
            timed = {
                coords: median_time(
                    lambda a=atmosphere, c=coords, s=span: rp.ccsp(
                        state, craft, a, s, coordinates=c
                    ),
                    args.repeat,
                )
                for coords in ("equinoctial", "cartesian")
            }
            ratio = timed["equinoctial"] / timed["cartesian"]
            results[name][f"equinoctial_over_cartesian_{days}d"] = ratio
            print(
                f"  {days} days: CCSP equinoctial {timed['equinoctial']:.4f} s, Cartesian "
                f"{timed['cartesian']:.4f} s: {ratio:.2f}x"
            )
        print(
            f"{name}: CCSP (60 min updates, 16 sigma points) {cc:.4f} s; Monte Carlo (1000 "
            f"members, GaussMarkov 18 min) {mc:.3f} s; Monte Carlo / CCSP = {mc / cc:.1f}x"
        )
    results["slow_point"] = slow_point_cost(field, state, craft, args.repeat)
    out = Path(__file__).parent / "results" / "ccsp.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps({**info(), **results}, indent=2))


def slow_point_cost(field, state, craft, repeat: int) -> dict[str, float]:
    """Seconds of 64 seven-day CCSP runs (ccsp_many, drag_sigma 0.1) with the default
    kappa (17 sigma points) and without its slow term (16), and their ratio."""
    from rhoprop.propagation.ccsp import CcspRun, ccsp_many

    rng = np.random.default_rng(0)
    hours = np.arange(1, 7 * 24 + 1) * 3600.0
    states = [
        rp.OrbitState(
            state.epoch, state.position * (1 + 1e-3 * rng.standard_normal()), state.velocity
        )
        for _ in range(64)
    ]

    def run(kappa):
        runs = [CcspRun(s, craft, hours, drag_sigma=0.1, kappa=kappa) for s in states]
        out = ccsp_many(runs, field)
        assert not any(isinstance(r, Exception) for r in out), out

    default = median_time(lambda: run(None), repeat)
    without = median_time(lambda: run(rp.kappa.TwoScale(slow_fraction=0.0)), repeat)
    print(
        f"slow term's own point, 64 objects x 7 days: 17 points {default:.3f} s, 16 points "
        f"{without:.3f} s: {default / without:.2f}x"
    )
    return {"seventeen_s": default, "sixteen_s": without, "ratio": default / without}


if __name__ == "__main__":
    main()
