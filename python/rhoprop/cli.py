"""The ``rhoprop`` command line: ``rhoprop paper`` (the paper's study) and ``rhoprop run
SCENARIO.toml`` (a user's own ensemble study). Exit codes: 0 ok, 1 failure, 2 usage."""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__, density, frames, scenarios, studies
from .orbit import propagate
from .spaceweather import SpaceWeather


def _stage(title: str, start: float) -> None:
    print(f"\n== {title}  (t = {time.perf_counter() - start:.0f} s)", flush=True)


def _paper(args: argparse.Namespace) -> int:
    """The paper's study: deterministic orbits, Fig. 4, Fig. 5 (four cases), Fig. 6."""
    start = time.perf_counter()
    members = args.members or (100 if args.quick else 1000)
    duration = 86400.0 if args.quick else scenarios.PAPER_DURATION
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    record = SpaceWeather()
    state, craft = scenarios.paper_state(), scenarios.paper_spacecraft()
    print(f"rhoprop paper: {members} members per run, {duration / 86400:g} days, output in {out}")

    _stage("Mean orbits, Case I (2002-09-07 storm)", start)
    _paper_orbits(state, craft, duration, record)

    _stage("Method comparison (paper Fig. 4), NRLMSIS 2.1, Case I", start)
    comparison = studies.method_comparison(
        state, craft, density.Msis("2.1", space_weather=record), duration, n=members
    )
    figures = [comparison.figure(out / "method_comparison.png")]
    print(comparison.table())

    _stage("Ensembles for the four space-weather cases (paper Fig. 5)", start)
    ensembles = studies.case_ensembles(n=members, duration=duration, record=record)
    figures.append(studies.ensemble_figure(ensembles, out / "ensembles.png"))
    case_table = _case_table(ensembles)
    print(case_table)

    _stage("CCSP vs Monte Carlo (paper Fig. 6)", start)
    sw = record
    versus = studies.ccsp_vs_monte_carlo(
        state,
        craft,
        density.Msis("2.1", space_weather=sw),
        density.Msis("00", space_weather=sw),
        duration,
        n=members,
    )
    figures.append(versus.figure(out / "ccsp_vs_monte_carlo.png"))
    print(versus.table())

    summary = {
        "members": members,
        "duration_s": duration,
        "method_comparison": comparison.along_track_std,
        "method_ratios": [
            {"a": a, "b": b, "measured": m, "long_time_theory": t}
            for a, b, m, t in comparison.ratios()
        ],
        "cases": {
            case: {"epoch": str(scenarios.CASE_EPOCHS[case]) + "Z", **ens.summary()}
            for case, ens in ensembles.items()
        },
        "ccsp_vs_monte_carlo": {
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
        },
        "wall_seconds": time.perf_counter() - start,
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    days = f"{duration / 86400:g}"
    (out / "summary.md").write_text(
        f"# rhoprop paper study\n\n{members} members per Monte Carlo run, {days} days.\n\n"
        f"## Method comparison (Fig. 4)\n\n{comparison.table()}\n\n"
        f"## Ensembles (Fig. 5): along-track at {days} days\n\n{case_table}\n\n"
        f"## CCSP vs Monte Carlo (Fig. 6)\n\n{versus.table()}\n"
    )
    _stage("Done", start)
    for path in [*figures, out / "summary.json", out / "summary.md"]:
        print(f"  wrote {path}")
    return 0


def _case_table(ensembles: dict[str, Any]) -> str:
    """Markdown table of the ensembles: per case and model Cd, along-track mean and std;
    mixture mean, std, 95 % interval and number of modes."""
    lines = [
        "| case | model | Cd | along-track mean [m] | along-track std [m] |",
        "| --- | --- | --- | --- | --- |",
    ]
    for case, ens in ensembles.items():
        s = ens.summary()
        for name, m in s["models"].items():
            lines.append(
                f"| {case} | {name} | {m['cd']:.4f} | {m['along_track_mean_m']:.1f} "
                f"| {m['along_track_std_m']:.1f} |"
            )
        x = s["mixture"]
        lines.append(
            f"| {case} | **mixture** ({x['modes']} mode{'s' if x['modes'] != 1 else ''}, 95 %: "
            f"{x['q025_m']:.0f} to {x['q975_m']:.0f}) | | {x['mean_m']:.1f} | {x['std_m']:.1f} |"
        )
    return "\n".join(lines)


def _paper_orbits(state, craft, duration: float, record: SpaceWeather) -> None:
    """Each integrator on the benchmark atmosphere, then the three NRLMSIS mean orbits."""
    model = scenarios.benchmark_exponential()
    print(f"  {'method':<8} {'RHS evals':>10} {'wall [s]':>9}  {'vs dop853 [m]':>13}")
    reference = None
    for method in ("dop853", "rk8", "rk4"):
        t0 = time.perf_counter()
        tr = propagate(state, craft, model, duration, method=method)
        wall = time.perf_counter() - t0
        reference = tr.positions[-1] if reference is None else reference
        diff = float(np.linalg.norm(tr.positions[-1] - reference))
        print(f"  {method:<8} {tr.evaluations:>10} {wall:>9.3f}  {diff:>13.3f}")
    print(f"  {'model':<12} {'field+run [s]':>13}  {'along-track vs 2.1 [m]':>23}")
    ref = None
    for version in ("2.1", "2.0", "00"):
        t0 = time.perf_counter()
        tr = propagate(state, craft, density.Msis(version, space_weather=record), duration)
        wall = time.perf_counter() - t0
        ref = tr if ref is None else ref
        along = frames.to_rtn(tr.positions[-1], ref.positions[-1], ref.velocities[-1])[1]
        print(f"  {'NRLMSIS ' + version:<12} {wall:>13.2f}  {along:>23.1f}")


def _catalog(args: argparse.Namespace) -> int:
    """Propagate a TLE/OMM catalog to a common end epoch; OEM files and a Parquet summary."""
    from . import catalog, io

    cat = catalog.load(args.file, errors="skip" if args.skip_bad else "raise")
    for where, message in cat.skipped:
        print(f"skipped {where}: {message}", file=sys.stderr)
    model = (
        scenarios.benchmark_exponential(0.2)
        if args.model == "exponential"
        else density.Msis(args.model)
    )
    client = None
    if args.scheduler:
        from distributed import Client

        client = Client(args.scheduler)
    t0 = time.perf_counter()
    result = catalog.propagate_catalog(
        cat,
        model,
        args.end,
        method=args.method,
        n=args.members,
        client=client,
        output_step=args.output_step,
    )
    wall = time.perf_counter() - t0
    out = Path(args.out)
    paths = io.write_oem(result, out / "oem")
    summary = io.write_summary(result, out / "summary.parquet")
    decayed = int(np.count_nonzero(~np.isnat(result.decay_epoch)))
    print(
        f"{len(cat)} objects ({len(cat.skipped)} skipped), {args.method}, to {args.end}: "
        f"{wall:.1f} s ({len(cat) / wall:.1f} objects/s); {decayed} decay within the window"
    )
    print(f"wrote {len(paths)} OEM files to {out / 'oem'} and {summary}")
    return 0


def _run(args: argparse.Namespace) -> int:
    from .scenario_file import run_scenario_file

    return run_scenario_file(args.scenario, out=args.out)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``rhoprop`` command."""
    parser = argparse.ArgumentParser(
        prog="rhoprop",
        description="Orbit uncertainty of LEO objects from thermospheric density uncertainty: "
        "correlated-density Monte Carlo, the CCSP filter and multi-model ensembles.",
        epilog="Start with 'rhoprop paper --quick' (about half a minute). "
        "Exit codes: 0 ok, 1 failure, 2 usage.",
    )
    parser.add_argument("--version", action="version", version=f"rhoprop {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    paper = sub.add_parser(
        "paper",
        help="reproduce the paper's study: figures and summary tables",
        description="Reproduce the paper's study (Paul, Licata & Mehta): mean orbits, the "
        "Monte Carlo method comparison (Fig. 4), the three-model ensembles for the four "
        "space-weather cases (Fig. 5) and CCSP vs Monte Carlo (Fig. 6). Writes PNG figures, "
        "summary.json and summary.md to --out. The paper's ML density models are replaced "
        "by NRLMSIS 2.1 (reference), NRLMSIS 2.0 and NRLMSISE-00 with a documented "
        "uncertainty model. A full run takes about two minutes on 2 cores.",
    )
    paper.add_argument(
        "--quick",
        action="store_true",
        help="a smoke run: 1 day and 100 members instead of 3 days and 1000",
    )
    paper.add_argument(
        "--members",
        type=int,
        default=None,
        help="Monte Carlo members per run (default 1000, 100 with --quick)",
    )
    paper.add_argument(
        "--out",
        default="rhoprop-paper",
        help="directory for figures and summaries (default ./rhoprop-paper)",
    )
    paper.set_defaults(run=_paper)
    run = sub.add_parser(
        "run",
        help="run your own ensemble study from a TOML scenario file",
        description="Run an ensemble study described by a TOML file (epoch, state, "
        "spacecraft, models, method, duration, outputs). See examples/scenario.toml.",
    )
    run.add_argument("scenario", help="path of the TOML scenario file")
    run.add_argument("--out", default=None, help="output directory (overrides the file's)")
    run.set_defaults(run=_run)
    cat = sub.add_parser(
        "catalog",
        help="propagate a TLE/OMM catalog with density uncertainty",
        description="Propagate every element set of a TLE (2/3-line) or CCSDS OMM "
        "(JSON/CSV/XML) file from its epoch to --end with the CCSP filter (default) or a "
        "Monte Carlo; write one CCSDS OEM file per object (mean and covariance) and a "
        "Parquet summary. --scheduler runs it on a Dask cluster.",
    )
    cat.add_argument("file", help="TLE or OMM file")
    cat.add_argument(
        "--end", required=True, help="common end epoch, UTC ISO (e.g. 2002-09-10T00:00Z)"
    )
    cat.add_argument("--out", default="rhoprop-catalog", help="output directory")
    cat.add_argument("--method", choices=("ccsp", "monte_carlo"), default="ccsp")
    cat.add_argument("--members", type=int, default=100, help="Monte Carlo members per object")
    cat.add_argument("--output-step", type=float, default=3600.0, help="output spacing, s")
    cat.add_argument(
        "--model",
        default="2.1",
        choices=("2.1", "2.0", "00", "exponential"),
        help="NRLMSIS version (default 2.1) or the benchmark exponential",
    )
    cat.add_argument("--scheduler", default=None, help="Dask scheduler address")
    cat.add_argument(
        "--skip-bad",
        action="store_true",
        help="skip malformed element sets (reported) instead of failing",
    )
    cat.set_defaults(run=_catalog)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rhoprop`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 2
    if getattr(args, "members", None) is not None and args.members < 2:
        parser.error("--members must be at least 2")
    try:
        return int(args.run(args))
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        return 130
    except (ValueError, TypeError, OSError) as err:
        print(f"rhoprop: error: {err}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
