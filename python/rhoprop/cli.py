"""The ``rhoprop`` command line."""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from . import __version__, density, frames, scenarios, studies
from .orbit import propagate
from .spaceweather import SpaceWeather


def _paper(args: argparse.Namespace) -> int:
    """The paper's orbit, propagated deterministically (the stochastic study builds on it)."""
    state = scenarios.paper_state()
    craft = scenarios.paper_spacecraft()
    model = scenarios.benchmark_exponential()
    duration = 3600.0 * 6 if args.quick else scenarios.PAPER_DURATION
    print("rhoprop paper: the paper's initial state and sphere (Cd 3.0912, A/m 0.0015 m^2/kg)")
    print(f"  epoch {state.epoch}, {duration / 86400:.2f} days, exponential benchmark atmosphere")
    print("  (rho = 3.725e-12 kg/m^3 at 400 km, H = 58.515 km); two-body + J2 + drag")
    print()
    print(
        f"  {'method':<8} {'RHS evals':>10} {'wall [s]':>9}  {'final altitude [km]':>20}"
        f"  {'vs dop853 [m]':>13}"
    )
    reference = None
    for method in ("dop853", "rk8", "rk4"):
        t0 = time.perf_counter()
        tr = propagate(state, craft, model, duration, method=method)
        wall = time.perf_counter() - t0
        alt = frames.geodetic(frames.inertial_to_fixed(tr.epochs[-1], tr.positions[-1]))[2]
        if reference is None:
            reference = tr.positions[-1]
        diff = float(np.linalg.norm(tr.positions[-1] - reference))
        print(f"  {method:<8} {tr.evaluations:>10} {wall:>9.3f}  {alt / 1e3:>20.3f}  {diff:>13.3f}")
    assert reference is not None
    print()
    print(f"  final position [m]: {np.array2string(reference, precision=3)}")
    _paper_models(state, craft, duration)
    _paper_methods(args, state, craft, duration)
    print("The multi-model ensemble stage of the study is not built yet.")
    return 0


def _paper_methods(args: argparse.Namespace, state, craft, duration: float) -> None:
    """The paper's method comparison (Fig. 4 analogue) into --out."""
    members = args.members or (100 if args.quick else 1000)
    out = Path(args.out)
    print()
    print(f"Method comparison (paper Fig. 4): {members} members per method, NRLMSIS 2.1, Case I")
    comparison = studies.method_comparison(state, craft, None, duration, n=members, progress=True)
    figure = comparison.figure(out / "method_comparison.png")
    table = comparison.table()
    print(table)
    summary = {
        "members": members,
        "duration_s": duration,
        "method_comparison": comparison.along_track_std,
        "method_ratios": [
            {"a": a, "b": b, "measured": m, "long_time_theory": t}
            for a, b, m, t in comparison.ratios()
        ],
    }
    print()
    print(f"CCSP vs Monte Carlo (paper Fig. 6): {members} members, NRLMSIS 2.1 and NRLMSISE-00")
    versus = studies.ccsp_vs_monte_carlo(state, craft, None, None, duration, n=members)
    figure2 = versus.figure(out / "ccsp_vs_monte_carlo.png")
    table2 = versus.table()
    print(table2)
    summary["ccsp_vs_monte_carlo"] = {
        k: {
            "cd": versus.cd[k],
            "mc_along_track_mean_m": float(versus.mc_along[k].mean()),
            "mc_along_track_std_m": float(versus.mc_along[k].std(ddof=1)),
            "ccsp_along_track_mean_m": versus.ccsp_mean[k],
            "ccsp_along_track_std_m": versus.ccsp_std[k],
            "mc_seconds": versus.seconds[k][0],
            "ccsp_seconds": versus.seconds[k][1],
        }
        for k in versus.mc_along
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    (out / "summary.md").write_text(
        f"# rhoprop paper study\n\n## Method comparison ({members} members, "
        f"{duration / 86400:g} days)\n\n{table}\n\n## CCSP vs Monte Carlo\n\n{table2}\n"
    )
    print(f"wrote {figure}, {figure2}, {out / 'summary.json'}, {out / 'summary.md'}")


def _paper_models(state, craft, duration: float) -> None:
    """Mean orbits of Case I through the three NRLMSIS stand-ins, along-track vs 2.1."""
    sw = SpaceWeather()
    print()
    print("Mean orbits through NRLMSIS (Case I: 2002-09-07 storm; fields cached on disk)")
    print(f"  {'model':<12} {'field+run [s]':>13}  {'along-track vs 2.1 [m]':>23}")
    ref = None
    for version in ("2.1", "2.0", "00"):
        t0 = time.perf_counter()
        tr = propagate(state, craft, density.Msis(version, space_weather=sw), duration)
        wall = time.perf_counter() - t0
        if ref is None:
            ref = tr
        along = frames.to_rtn(tr.positions[-1], ref.positions[-1], ref.velocities[-1])[1]
        print(f"  {'NRLMSIS ' + version:<12} {wall:>13.2f}  {along:>23.1f}")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``rhoprop`` command."""
    parser = argparse.ArgumentParser(
        prog="rhoprop",
        description="Orbit uncertainty from thermospheric density uncertainty.",
    )
    parser.add_argument("--version", action="version", version=f"rhoprop {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    paper = sub.add_parser(
        "paper",
        help="run the paper study (orbits, method comparison, CCSP vs Monte Carlo so far)",
        description="Run the paper study: the paper's orbit for 3 days with each "
        "integrator and through NRLMSIS 2.1, 2.0 and NRLMSISE-00 (Case I), then the "
        "Monte Carlo method comparison (paper Fig. 4) and CCSP vs Monte Carlo (Fig. 6): "
        "figures, summary.json and summary.md in --out. The ensemble stage is not built "
        "yet.",
    )
    paper.add_argument(
        "--quick",
        action="store_true",
        help="a smoke run: 6 hours and 100 members instead of 3 days and 1000",
    )
    paper.add_argument(
        "--members",
        type=int,
        default=None,
        help="Monte Carlo members per case (default 1000, 100 with --quick)",
    )
    paper.add_argument(
        "--out",
        default="rhoprop-paper",
        help="directory for figures and summaries (default ./rhoprop-paper)",
    )
    paper.set_defaults(run=_paper)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rhoprop`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 2
    try:
        return int(args.run(args))
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
