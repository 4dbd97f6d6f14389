"""The ``rhoprop`` command line."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

import numpy as np

from . import __version__, density, frames, scenarios
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
    print("The Monte Carlo, CCSP and ensemble stages of the study are not built yet.")
    return 0


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
        help="run the paper study (for now: the deterministic 3-day propagations)",
        description="Run the paper study. For now this propagates the paper's orbit for 3 "
        "days with each integrator (benchmark atmosphere) and through NRLMSIS 2.1, 2.0 and "
        "NRLMSISE-00 for Case I, and prints the results.",
    )
    paper.add_argument("--quick", action="store_true", help="propagate 6 hours instead of 3 days")
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
