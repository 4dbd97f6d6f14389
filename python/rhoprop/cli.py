"""The ``rhoprop`` command line: ``rhoprop paper`` (the paper's study), ``rhoprop run
SCENARIO.toml`` (a user's own ensemble study), ``rhoprop catalog FILE`` (a TLE/OMM
catalog), ``rhoprop reentry FILE`` (reentry windows) and ``rhoprop data refresh``.
Argument parsing only: each command calls one function of the package. Exit codes: 0 ok,
1 failure, 2 usage."""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any

from ._version import __version__
from .jobs.models import (
    METHOD_NAMES,
    MODEL_NAMES,
    SCREEN_MODEL_NAMES,
    TABLE_FORMATS,
    method_takes,
)


def _paper(args: argparse.Namespace) -> int:
    from .jobs import PaperJob

    out = args.out or ("rhoprop-paper-quick" if args.quick else "rhoprop-paper")
    PaperJob(
        out,
        quick=args.quick,
        members=args.members,
        seed=args.seed,
        overwrite=args.overwrite,
        command=args.command_line,
    ).run()
    return 0


def _catalog(args: argparse.Namespace) -> int:
    from .jobs import CatalogJob
    from .jobs.models import method_by_name

    CatalogJob(
        args.file,
        args.end,
        args.out,
        method=method_by_name(
            args.method,
            n=100 if args.members is None else args.members,
            seed=args.seed or 0,
            update_interval=args.update_interval or 3600.0,
        ),
        model=args.model,
        output_step=args.output_step,
        scheduler=args.scheduler,
        skip_bad=args.skip_bad,
        overwrite=args.overwrite,
        duplicates=args.duplicates,
        command=args.command_line,
        fit=args.fit,
        initial_covariance=args.initial_covariance,
        zonal_degree=args.zonal_degree,
        drag_file=args.drag_file,
        cd=args.cd,
        drag_sigma=args.drag_sigma,
        max_span_days=args.max_span,
        frame=args.frame,
        start=args.start,
        oem=args.oem,
        table_format=args.format,
        as_of=args.as_of,
    ).run()
    return 0


def _non_negative(text: str) -> float:
    """An argparse type: a finite number >= 0 (``--max-span``: 0 means no limit)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be a number >= 0, got {text}")
    return value


def _positive(text: str) -> float:
    """An argparse type: a finite number > 0 (argparse names the option in its error, and
    the run stops before its output folder is made)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return value


def _probability(text: str) -> float:
    """An argparse type: a number in [0, 1]."""
    value = _non_negative(text)
    if value > 1:
        raise argparse.ArgumentTypeError(f"must be a probability in [0, 1], got {text}")
    return value


def _reentry(args: argparse.Namespace) -> int:
    from .jobs import ReentryJob

    ReentryJob(
        args.file,
        args.out,
        horizon_days=args.horizon,
        members=args.members,
        model=args.model,
        fit=args.fit,
        history=args.history,
        drag_sigma=args.drag_sigma,
        skip_bad=args.skip_bad,
        overwrite=args.overwrite,
        command=args.command_line,
        table_format=args.format,
        as_of=args.as_of,
    ).run()
    return 0


def _screen(args: argparse.Namespace) -> int:
    from .jobs import ScreenJob

    ScreenJob(
        args.file,
        args.out,
        end=args.end,
        start=args.start,
        distance=args.distance,
        model=args.model,
        pc=args.pc,
        hard_body_radius=args.hbr,
        radii_file=args.radii,
        monte_carlo_events=args.monte_carlo,
        members=200 if args.members is None else args.members,
        skip_bad=not args.strict,
        overwrite=args.overwrite,
        command=args.command_line,
        max_span_days=args.max_span,
        cdm_min_pc=None if args.no_cdm else args.cdm_min_pc,
        scheduler=args.scheduler,
        table_format=args.format,
    ).run()
    return 0


def _data_refresh(args: argparse.Namespace) -> int:
    from .jobs.catalog import refresh_data

    for line in refresh_data(timeout=args.timeout):
        print(line)
    return 0


def _run(args: argparse.Namespace) -> int:
    from .jobs import ScenarioJob

    return ScenarioJob(
        args.scenario,
        out=args.out,
        overwrite=args.overwrite,
        command=args.command_line,
        seed=args.seed,
    ).run()


def _conjunction(args: argparse.Namespace) -> int:
    from .jobs import ConjunctionJob
    from .jobs.models import method_by_name

    ConjunctionJob(
        args.file,
        hard_body_radius=args.hbr,
        lead_time=args.lead,
        method=method_by_name(args.method, n=args.members or 200, progress=False, output_step=None),
        drag_parameters=tuple(args.drag) if args.drag else (None, None),
        json_path=args.json,
    ).run()
    return 0


def _seed(parser: argparse.ArgumentParser, default: int | None = 0) -> None:
    parser.add_argument(
        "--seed",
        type=_seed_value,
        default=default,
        help="seed of the Monte Carlo members (default 0)",
    )


def _seed_value(text: str) -> int:
    """An argparse type: a whole number 0 .. 2**64 - 1 (the core's 64-bit streams)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None
    if not 0 <= value < 2**64:
        raise argparse.ArgumentTypeError(f"must lie in 0 .. 2**64 - 1, got {text}")
    return value


_MC = "--method monte_carlo"
#: Options that act only with another's value: (command, option, its dest, the condition
#: as a predicate on the arguments, what it needs). Given without it they are refused,
#: never ignored.
_NEEDS: tuple[tuple[str, str, str, Callable[[argparse.Namespace], bool], str], ...] = (
    ("catalog", "--members", "members", lambda a: method_takes(a.method, "n"), _MC),
    ("catalog", "--seed", "seed", lambda a: method_takes(a.method, "seed"), _MC),
    (
        "catalog",
        "--update-interval",
        "update_interval",
        lambda a: method_takes(a.method, "update_interval"),
        "--method ccsp",
    ),
    ("conjunction", "--members", "members", lambda a: method_takes(a.method, "n"), _MC),
    ("screen", "--members", "members", lambda a: a.monte_carlo > 0, "--monte-carlo N (N > 0)"),
)


def _refuse_unused(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """A parser error for an option given where it does nothing (``_NEEDS``) or against
    another (a history fit without fits)."""
    for command, option, dest, applies, needs in _NEEDS:
        if args.command == command and getattr(args, dest) is not None and not applies(args):
            parser.error(f"{option} acts only with {needs}")
    if args.command == "catalog" and args.duplicates == "fit" and args.fit is False:
        parser.error("--duplicates fit fits each object's element sets: not with --no-fit")


def _cache(args: argparse.Namespace) -> int:
    from .cache import cache_info, clear_cache, owned_files

    if args.cache_command == "clear":
        files, n_bytes = clear_cache(everything=args.all)
        what = "cached files" if args.all else "sampled density fields and atlas tiles"
        print(f"deleted {files} {what} ({n_bytes / 1e6:.1f} MB)")
        _, rest = owned_files(everything=True)
        if rest:
            shown = ", ".join(str(p) for p in rest[:3]) + (", ..." if len(rest) > 3 else "")
            print(f"left {len(rest)} files rhoprop did not write there: {shown}")
        return 0
    info = cache_info()
    print(f"cache: {info['directory']}")
    print(
        f"size cap per folder: {info['max_bytes_per_folder'] / 1e9:g} GB "
        "($RHOPROP_CACHE_MAX_BYTES; least recently used entries go first)"
    )
    for name, part in sorted(info["parts"].items()):
        label = "(top level)" if name == "." else name
        print(f"  {label}: {part['files']} files, {part['bytes'] / 1e6:.1f} MB")
    print(f"total: {info['total_bytes'] / 1e6:.1f} MB")
    for entry in info["tiles"]:
        days = entry["days"]
        span = days[0] if len(days) == 1 else f"{days[0]} .. {days[-1]}"
        print(
            f"  atlas tiles of {entry['model']}: {len(days)} days ({span}), "
            f"{entry['files']} files, {entry['bytes'] / 1e6:.1f} MB"
        )
        if 1 < len(days) <= 31:
            print(f"    days: {', '.join(days)}")
    return 0


def _table_format(parser: argparse.ArgumentParser, default: str, tables: str) -> None:
    parser.add_argument(
        "--format",
        choices=TABLE_FORMATS,
        default=default,
        help=f"format of {tables}: parquet (typed columns, compressed) or csv (any spreadsheet)",
    )


def _utc_epoch(text: str) -> str:
    """An argparse type: a UTC ISO epoch (argparse names the option in its error)."""
    from .jobs.models import as_of_text

    try:
        return as_of_text(text)
    except (TypeError, ValueError) as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _as_of(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--as-of",
        type=_utc_epoch,
        default=None,
        metavar="EPOCH",
        help="run as a forecaster would have at EPOCH (UTC ISO): the space weather observed "
        "before it, the library's forecast after (persistence of F10.7, ap relaxing to the "
        "last 27 days' typical day, with their forecast sigmas). Default: the record as "
        "refreshed, observed and then its predictions; for past epochs that is a "
        "hindcast, which flatters the density model",
    )


def _overwrite(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="delete an earlier run's files from the output folder first: only the files "
        "its rhoprop manifest lists (without it such a folder is refused; a folder that "
        "also holds other files always is, naming them)",
    )


class _Formatter(argparse.HelpFormatter):
    """Help that names each option's default, unless its text already speaks of it."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            not action.option_strings
            or "default" in text.lower()
            or default is None
            or isinstance(default, bool)
            or default is argparse.SUPPRESS
        ):
            return action.help
        return f"{text} (default: %(default)s)" if text else "default: %(default)s"


class _Parser(argparse.ArgumentParser):
    """Every (sub)command's parser: the same help formatter throughout."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``rhoprop`` command."""
    parser = _Parser(
        prog="rhoprop",
        description="Orbit uncertainty of LEO objects from thermospheric density uncertainty: "
        "correlated-density Monte Carlo, the CCSP filter and multi-model ensembles.",
        epilog="Start with 'rhoprop paper --quick' (about half a minute). "
        "Exit codes: 0 ok, 1 failure, 2 usage.",
    )
    parser.add_argument("--version", action="version", version=f"rhoprop {__version__}")
    parser.add_argument(
        "--threads",
        type=int,
        default=None,
        help="worker threads for every command (default: all cores); results do not depend on it",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    paper = sub.add_parser(
        "paper",
        help="reproduce the paper's study: figures and summary tables",
        description="Reproduce the paper's study (Paul, Licata & Mehta): mean orbits, the "
        "Monte Carlo method comparison (Fig. 4), the three-model ensembles for the four "
        "space-weather cases (Fig. 5) and CCSP vs Monte Carlo (Fig. 6). Writes PNG figures, "
        "summary.json and summary.md to --out. The paper's ML density models are replaced "
        "by three model families, each with a documented uncertainty model: NRLMSIS 2.1 "
        "(reference), JB2008 (when its index files are found: RHOPROP_JB2008_DATA or "
        "'rhoprop data refresh') and Jacchia-Roberts 1971; without JB2008 indices, "
        "NRLMSISE-00 takes its place. A full run takes about two minutes on 2 cores.",
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
        default=None,
        help="directory for figures and summaries (default ./rhoprop-paper, "
        "./rhoprop-paper-quick with --quick)",
    )
    _seed(paper)
    _overwrite(paper)
    paper.set_defaults(run=_paper)
    run = sub.add_parser(
        "run",
        help="run your own ensemble study from a TOML scenario file",
        description="Run an ensemble study described by a TOML file (epoch, state, "
        "spacecraft, models, method, duration, outputs). See examples/scenario.toml.",
    )
    run.add_argument("scenario", help="path of the TOML scenario file")
    run.add_argument(
        "--out",
        default=None,
        help="output directory (overrides the file's output.directory, which is relative "
        "to the scenario file and must stay inside its folder)",
    )
    run.add_argument(
        "--seed",
        type=int,
        default=None,
        help="Monte Carlo seed (overrides the file's method.seed)",
    )
    _overwrite(run)
    run.set_defaults(run=_run)
    cat = sub.add_parser(
        "catalog",
        help="propagate a TLE/OMM catalog with density uncertainty",
        description="Propagate every element set of a TLE (2/3-line) or CCSDS OMM "
        "(JSON/CSV/XML) file from its epoch to --end with the CCSP filter (default) or a "
        "Monte Carlo; write the ephemeris (mean and covariance) as one Parquet table, "
        "ephemeris.parquet (with --oem also one CCSDS OEM file per object), and a "
        "Parquet summary. --scheduler runs it on a Dask cluster.",
    )
    cat.add_argument("file", help="TLE or OMM file")
    cat.add_argument(
        "--end", required=True, help="common end epoch, UTC ISO (e.g. 2002-09-10T00:00Z)"
    )
    cat.add_argument(
        "--start",
        default=None,
        help="first output epoch at or after it, UTC ISO (default: the epoch 99 %% of the "
        "element sets are not after; the newer few have no output before their epoch)",
    )
    cat.add_argument("--out", default="rhoprop-catalog", help="output directory")
    cat.add_argument(
        "--method",
        choices=METHOD_NAMES,
        default="ccsp",
        help="the sigma-point filter or a Monte Carlo per object",
    )
    cat.add_argument(
        "--members",
        type=int,
        default=None,
        help="Monte Carlo members per object (default 100; only with --method monte_carlo)",
    )
    cat.add_argument("--output-step", type=_positive, default=3600.0, help="output spacing, s")
    cat.add_argument(
        "--frame",
        choices=("TEME", "GCRF", "EME2000"),
        default="TEME",
        help="frame of the ephemeris and REF_FRAME of the OEM files (default TEME, SGP4's "
        "frame, as computed); GCRF or EME2000 rotates states and covariances from TEME "
        "(about 43 km in LEO)",
    )
    cat.add_argument(
        "--update-interval",
        type=_positive,
        default=None,
        help="CCSP update interval, s (default 3600, the paper's tuning; only with --method "
        "ccsp); eccentric orbits (e >= 0.1) update once per revolution, at apogee",
    )
    _seed(cat, default=None)
    cat.add_argument(
        "--drag-file",
        default=None,
        metavar="CSV",
        help="per-object drag instead of B*: a CSV with a norad_id column and either "
        "drag_parameter (Cd*A/m, m^2/kg) or area_to_mass (A/m, m^2/kg; times --cd)",
    )
    cat.add_argument(
        "--cd",
        type=_positive,
        default=None,
        help="drag coefficient for a --drag-file that gives area_to_mass (default 2.2)",
    )
    cat.add_argument(
        "--drag-sigma",
        default="auto",
        metavar="auto|S",
        help="relative 1-sigma of each object's Cd*A/m propagated with the density "
        "uncertainty (CCSP consider parameter, Monte Carlo samples): 'auto' (default: the "
        "fit's, at least 0.08, at most 1; 0.5 for objects not fitted, where B* is scaled to "
        "the model's density) or a number (0: none)",
    )
    cat.add_argument(
        "--model",
        default="2.1",
        choices=MODEL_NAMES,
        help="NRLMSIS version (default 2.1) or the benchmark exponential",
    )
    cat.add_argument("--scheduler", default=None, help="Dask scheduler address")
    cat.add_argument(
        "--skip-bad",
        action="store_true",
        help="skip malformed element sets and record objects whose propagation fails "
        "(status 'failed' in the summary; all reported on stderr) instead of stopping "
        "(orbits beyond 10 Earth radii, such as TESS's, are always set aside and listed)",
    )
    cat.add_argument(
        "--duplicates",
        choices=("newest", "fit", "error", "suffix"),
        default="newest",
        help="NORAD ids occurring more than once (a history): one object, the newest "
        "element set (default); 'fit': one object fitted to the newest and the others of "
        "its last day (better over one day on a dense history, not over two or more: "
        "docs/catalogs.md); an error; or objects of their own (with --oem in OEM files "
        "named <id>_2.oem, <id>_3.oem, ...)",
    )
    cat.add_argument(
        "--oem",
        action="store_true",
        help="also write one CCSDS OEM file per object, OUT/oem/<NORAD id>.oem (the "
        "default output, OUT/ephemeris.parquet, holds every object's mean and covariance "
        "in one table)",
    )
    cat.add_argument(
        "--fit",
        dest="fit",
        action="store_const",
        const=True,
        default="auto",
        help="fit every object's state and Cd*A/m to its SGP4 positions over the day "
        "before its epoch (deep-space orbits: three days either side, one if eccentric) "
        "with rhoprop's "
        "dynamics and the model (over 100 objects/s on 2 cores). Default: every object "
        "whose drag comes from the element set, at any altitude",
    )
    cat.add_argument(
        "--no-fit",
        dest="fit",
        action="store_const",
        const=False,
        help="fit no object: states and B* as published (B* scaled to the model)",
    )
    cat.add_argument(
        "--initial-covariance",
        default=None,
        metavar="KIND|FILE",
        help="initial covariance: 'object' (default: published TLE accuracy by regime, plus "
        "the fit's for fitted objects), 'tle', 'paper' (near-zero, 1 mm / 1 um/s) or a text file "
        "with a 6x6 inertial covariance in m^2, m^2/s, m^2/s^2",
    )
    cat.add_argument(
        "--zonal-degree",
        type=int,
        default=4,
        choices=range(2, 7),
        metavar="N",
        help="highest zonal harmonic of the gravity field: 4 (default, J2..J4 as SGP4 "
        "carries), 2 (J2 only, the paper's model) to 6 (J2..J6, EGM2008)",
    )
    cat.add_argument(
        "--max-span",
        type=_non_negative,
        default=60.0,
        metavar="DAYS",
        help="objects whose epoch lies more days than this before --end are not run "
        "(status 'stale': a run holds its days of density tiles in memory); 0: no limit",
    )
    _table_format(
        cat,
        "parquet",
        "the ephemeris and the summary (csv: the ephemeris's metadata in ephemeris.meta.json)",
    )
    _overwrite(cat)
    _as_of(cat)
    cat.set_defaults(run=_catalog)
    reentry = sub.add_parser(
        "reentry",
        help="reentry windows of a TLE/OMM catalog",
        description="Monte Carlo over density and ballistic-coefficient uncertainty for "
        "every element set of FILE (each member's density off the model's by one draw of "
        "the model's sigma for its whole run): the 2.5 %, median and 97.5 % decay epochs "
        "within --horizon days and the fraction of members decayed; printed and written "
        "to OUT/reentry.csv.",
    )
    reentry.add_argument("file", help="TLE or OMM file")
    reentry.add_argument("--horizon", type=_positive, default=30.0, help="days after each epoch")
    reentry.add_argument("--members", type=int, default=100, help="Monte Carlo members")
    reentry.add_argument(
        "--model",
        default="2.1",
        choices=MODEL_NAMES,
        help="NRLMSIS version or the benchmark exponential",
    )
    reentry.add_argument(
        "--fit",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="fit each object's state and Cd*A/m to its element set with the model first "
        "(default; --no-fit takes them from the element set and B* as published)",
    )
    reentry.add_argument(
        "--history",
        choices=("auto", "newest", "fit", "each"),
        default="auto",
        help="several element sets of one object: predict from the newest with the fit "
        "taking the earlier ones of its last day too (fit; the default, auto, with "
        "fitting, newest with --no-fit), from the newest alone (newest), or from each on "
        "its own",
    )
    reentry.add_argument(
        "--drag-sigma",
        type=_non_negative,
        default=None,
        help="relative 1-sigma of Cd*A/m (default: the fit's, at least 0.15; else 0.15)",
    )
    reentry.add_argument("--out", default="rhoprop-reentry", help="output directory")
    reentry.add_argument(
        "--skip-bad",
        action="store_true",
        help="skip malformed element sets (listed on stderr; orbits beyond 10 Earth radii "
        "are always set aside and listed)",
    )
    _table_format(reentry, "csv", "the reentry table (csv: epochs as ISO text)")
    _overwrite(reentry)
    _as_of(reentry)
    reentry.set_defaults(run=_reentry)
    conj = sub.add_parser(
        "conjunction",
        help="a CDM's Pc with density-model uncertainty added",
        description="Read a CCSDS conjunction data message (KVN or XML; needs the "
        "ccsds-ndm package: pip install ccsds-ndm), propagate both objects from "
        "--lead before TCA through the default density-model families (Cd debiased per "
        "model) and print the Pc from the message's own covariances, from each model and "
        "from their mixture.",
    )
    conj.add_argument("file", help="CDM file (KVN or XML)")
    conj.add_argument(
        "--hbr", type=_positive, default=None, help="hard-body radius, m (default: the CDM's)"
    )
    conj.add_argument(
        "--lead",
        type=_positive,
        default=None,
        help="s before TCA the density uncertainty starts (default: TCA - CREATION_DATE)",
    )
    conj.add_argument(
        "--method",
        choices=METHOD_NAMES,
        default="ccsp",
        help="the sigma-point filter or a Monte Carlo",
    )
    conj.add_argument("--members", type=int, default=None, help="Monte Carlo members (200)")
    conj.add_argument(
        "--drag",
        type=_positive,
        nargs=2,
        metavar=("BETA1", "BETA2"),
        default=None,
        help="Cd*A/m of the two objects, m^2/kg (default: the CDM's CD_AREA_OVER_MASS)",
    )
    conj.add_argument("--json", default=None, help="also write the figures to this JSON file")
    conj.set_defaults(run=_conjunction)
    scr = sub.add_parser(
        "screen",
        help="screen a whole TLE/OMM catalog against itself, with Pc per density model",
        description="Propagate every element set of FILE once from --start to --end, find "
        "every pair coming within --distance (spatial grid and distance bounds, then the "
        "minima), and give each event its probability of collision per density model and "
        "for their mixture (CCSP of the objects in events, each object's own covariance). "
        "Writes OUT/events.parquet (every event), a CCSDS CDM in OUT/cdm for each event "
        "with Pc >= --cdm-min-pc (with the [cdm] extra) and prints the most probable. "
        "Element sets that cannot be read or propagated (e.g. orbits beyond 10 Earth "
        "radii) are skipped and listed (--strict stops "
        "instead). B* <= 0 objects load with an assumed "
        "Cd*A/m of 0.022 m^2/kg and 100 % drag uncertainty.",
    )
    scr.add_argument("file", help="TLE or OMM file")
    scr.add_argument("--end", required=True, help="end of the window, UTC ISO")
    scr.add_argument(
        "--start",
        default=None,
        help="start of the window, UTC ISO (default: the epoch 99 %% of the element sets are "
        "not after; later ones are propagated back to it)",
    )
    scr.add_argument("--distance", type=_positive, default=5e3, help="screening distance, m")
    scr.add_argument(
        "--model",
        default="families",
        choices=SCREEN_MODEL_NAMES,
        help="'families' (default: NRLMSIS 2.1, JB2008 or NRLMSISE-00, Jacchia-Roberts "
        "1971, Cd debiased per model) or one model",
    )
    scr.add_argument(
        "--hbr", type=_positive, default=None, help="combined hard-body radius for every event, m"
    )
    scr.add_argument(
        "--radii",
        default=None,
        metavar="CSV",
        help="per-object radii (columns norad_id, radius_m); others by kind: payload and "
        "rocket body 5 m, debris 1 m; an event's hard-body radius is the sum",
    )
    scr.add_argument(
        "--pc",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="compute each event's Pc (default; --no-pc lists the close approaches only)",
    )
    scr.add_argument(
        "--cdm-min-pc",
        type=_probability,
        default=1e-7,
        metavar="PC",
        help="write a CDM for each event whose mixture Pc is at least PC (default 1e-7; 0: "
        "every event, with --no-pc too); the event table holds every event",
    )
    scr.add_argument("--no-cdm", action="store_true", help="write no CDM, the event table only")
    scr.add_argument(
        "--monte-carlo",
        type=int,
        default=0,
        metavar="N",
        help="also the member Monte Carlo's Pc of the N most probable events (default 0)",
    )
    scr.add_argument(
        "--members",
        type=int,
        default=None,
        help="Monte Carlo members per object and model (default 200; only with --monte-carlo)",
    )
    scr.add_argument(
        "--max-span",
        type=_non_negative,
        default=60.0,
        metavar="DAYS",
        help="element sets whose epoch lies more days than this before --start (or after "
        "--end) are skipped and listed: a propagation holds its days of density tiles in "
        "memory; 0: no limit",
    )
    scr.add_argument("--out", default="rhoprop-screen", help="output directory")
    scr.add_argument(
        "--scheduler",
        default=None,
        help="Dask scheduler address: every stage runs on that cluster (same events)",
    )
    scr.add_argument(
        "--strict",
        action="store_true",
        help="stop at the first element set that cannot be read or propagated (default: "
        "skip it, listed on stderr, and screen the rest, as a published catalog needs)",
    )
    _table_format(scr, "parquet", "the event table")
    _overwrite(scr)
    _as_of(scr)
    scr.set_defaults(run=_screen)
    data = sub.add_parser("data", help="manage data files (space weather, JB2008 indices)")
    data_sub = data.add_subparsers(dest="data_command", metavar="ACTION")
    refresh = data_sub.add_parser(
        "refresh",
        help="download the current space-weather record and JB2008 indices into the cache",
        description="Download CelesTrak's SW-All.csv (observed and predicted F10.7, Kp, ap) "
        "and SET's JB2008 index files into the user cache ($RHOPROP_CACHE, else "
        "$XDG_CACHE_HOME/rhoprop or ~/.cache/rhoprop), where rhoprop reads them next.",
    )
    refresh.add_argument("--timeout", type=_positive, default=60.0, help="per download, s")
    refresh.set_defaults(run=_data_refresh)
    cache = sub.add_parser(
        "cache",
        help="show or clear the user cache (density atlas tiles, sampled fields, downloads)",
        description="The cache ($RHOPROP_CACHE, else $XDG_CACHE_HOME/rhoprop or "
        "~/.cache/rhoprop) holds the density atlas's day tiles (one folder per model and "
        "grid; sampled again when missing), sampled density fields and downloaded "
        "space-weather and JB2008 files. Each folder is kept under "
        "$RHOPROP_CACHE_MAX_BYTES (default 2 GB) by deleting the least recently used "
        "entries; tiles in memory stay under $RHOPROP_FIELD_MEMORY (default 1 GB).",
    )
    cache_sub = cache.add_subparsers(dest="cache_command", metavar="ACTION")
    cache_sub.add_parser("info", help="where the cache is and what it holds")
    clear = cache_sub.add_parser("clear", help="delete the sampled density fields and atlas tiles")
    clear.add_argument(
        "--all",
        action="store_true",
        help="also delete the downloaded space-weather record and JB2008 indices",
    )
    cache.set_defaults(run=_cache, cache_command="info")
    return parser


#: Growth of the cache (bytes) from which a command says so when it ends.
CACHE_NOTICE_BYTES = 50_000_000


def _cache_bytes() -> int | None:
    """Bytes in the cache now (None where it cannot be read)."""
    from .cache import cache_info

    try:
        return int(cache_info()["total_bytes"])
    except (OSError, ValueError):
        return None


def _say_cache_growth(before: int | None) -> None:
    """One line on stderr when the command grew the cache by :data:`CACHE_NOTICE_BYTES`
    or more (the paper study fills it with a gigabyte of density tiles): where it is,
    how big, and the commands that list and empty it."""
    from .cache import cache_dir, max_bytes

    after = _cache_bytes()
    if before is None or after is None or after - before < CACHE_NOTICE_BYTES:
        return
    print(
        f"rhoprop: the cache grew by {(after - before) / 1e6:,.0f} MB to {after / 1e6:,.0f} MB "
        f"({cache_dir()}; at most {max_bytes() / 1e9:g} GB a folder, least recently used "
        "dropped first): 'rhoprop cache info' lists it, 'rhoprop cache clear' empties it",
        file=sys.stderr,
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rhoprop`` console script."""
    parser = build_parser()
    words = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(words)
    args.command_line = " ".join(["rhoprop", *words])
    if not getattr(args, "run", None):
        parser.print_help()
        return 2
    _refuse_unused(parser, args)
    from .cache import check_environment

    try:
        check_environment()
    except ValueError as err:
        parser.error(str(err))
    if getattr(args, "members", None) is not None and args.members < 2:
        parser.error("--members must be at least 2")
    if args.threads is not None:
        from .parallel import set_threads

        try:
            set_threads(args.threads)
        except ValueError as err:
            parser.error(f"--threads: {err}")
    before = _cache_bytes()
    plain = warnings.formatwarning
    warnings.formatwarning = _format_warning
    try:
        with warnings.catch_warnings():
            # The commands list each element set they set aside on stderr themselves.
            warnings.filterwarnings("ignore", r".* Earth radii set aside", RuntimeWarning)
            # Said once per run, not once per place in the library that meets it.
            warnings.filterwarnings("once", r"predicted space-weather drivers in use")
            code = int(args.run(args))
        _say_cache_growth(before)
        return code
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading
        return 0
    except (ValueError, TypeError, OSError, ImportError) as err:
        print(f"rhoprop: error: {err}", file=sys.stderr)
        return 1
    finally:
        warnings.formatwarning = plain


def _format_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    line: str | None = None,
) -> str:
    """A warning as the command line shows it: its kind and message, not the library's
    source line."""
    return f"rhoprop: warning ({category.__name__}): {message}\n"


if __name__ == "__main__":
    sys.exit(main())
