"""The ``rhoprop paper`` run: every study of the paper with its figures, printed tables,
``summary.json`` and ``summary.md``."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from .. import frames
from ..density import Msis
from ..ensemble import EnsembleResult
from ..io import OutputFolder, command_line
from ..propagation import Dynamics, OrbitState, Spacecraft, propagate
from ..spaceweather import SpaceWeather
from . import scenarios
from .conjunction import ConjunctionStudy, conjunction_study, most_disputed
from .paper import case_ensembles, ccsp_vs_monte_carlo, method_comparison
from .plots import days_text, ensemble_figure


def _stage(title: str, start: float) -> None:
    print(f"\n== {title}  (t = {time.perf_counter() - start:.0f} s)", flush=True)


def run_paper(
    out: str | Path,
    *,
    quick: bool = False,
    members: int | None = None,
    overwrite: bool = False,
    command: str | None = None,
    seed: int = 0,
) -> list[Path]:
    """The paper's study: deterministic orbits, Fig. 4, Fig. 5 (four cases), Fig. 6.

    Args:
        out: output directory (created; an earlier run's folder is refused unless
            ``overwrite``, which clears it first).
        quick: a smoke run, 1 day and 100 members instead of 3 days and 1000.
        members: Monte Carlo members per run (default 1000, 100 with ``quick``).
        overwrite: clear ``out`` if it holds an earlier run's files.
        command: the command recorded in ``manifest.json`` (default: this process's).
        seed: seed of every Monte Carlo run (and of the conjunction study's secondary).

    Returns:
        The paths written: four PNG figures, ``summary.json``, ``summary.md`` and
        ``manifest.json``, each written to a temporary name and renamed.
    """
    start = time.perf_counter()
    members = members or (100 if quick else 1000)
    duration = 86400.0 if quick else scenarios.PAPER_DURATION
    folder = OutputFolder(out, command=command or command_line(), overwrite=overwrite)
    out = folder.directory
    record = SpaceWeather()
    state, craft = scenarios.paper_state(), scenarios.paper_spacecraft()
    print(f"rhoprop paper: {members} members per run, {duration / 86400:g} days, output in {out}")

    _stage("Mean orbits, Case I (2002-09-07 storm)", start)
    _paper_orbits(state, craft, duration, record)

    _stage("Method comparison (paper Fig. 4), NRLMSIS 2.1, Case I", start)
    comparison = method_comparison(
        state,
        craft,
        Msis("2.1", space_weather=record, preset="paper"),
        duration,
        n=members,
        seed=seed,
    )
    with folder.path("method_comparison.png") as tmp:
        comparison.figure(tmp)
    figures = [out / "method_comparison.png"]
    print(comparison.table())

    _stage("Ensembles for the four space-weather cases (paper Fig. 5)", start)
    model_names, model_reason, _ = scenarios.model_choice()
    print(f"models: {', '.join(model_names)}: {model_reason}")
    ensembles = case_ensembles(n=members, duration=duration, record=record, seed=seed)
    with folder.path("ensembles.png") as tmp:
        ensemble_figure(ensembles, tmp)
    figures.append(out / "ensembles.png")
    case_table = _case_table(ensembles)
    print(case_table)

    disputed = most_disputed(ensembles)
    _stage(f"Conjunction: Pc per model, mixture and Monte Carlo ({disputed})", start)
    conj = conjunction_study(ensembles[disputed], case=disputed, seed=seed)
    with folder.path("conjunction.png") as tmp:
        conj.figure(tmp)
    figures.append(out / "conjunction.png")
    print(conj.table())

    _stage("CCSP vs Monte Carlo (paper Fig. 6)", start)
    sw = record
    versus = ccsp_vs_monte_carlo(
        state,
        craft,
        Msis("2.1", space_weather=sw, preset="paper"),
        Msis("00", space_weather=sw, preset="paper"),
        duration,
        n=members,
        seed=seed,
    )
    with folder.path("ccsp_vs_monte_carlo.png") as tmp:
        versus.figure(tmp)
    figures.append(out / "ccsp_vs_monte_carlo.png")
    print(versus.table())

    settings = _settings(members, duration, record, seed)
    summary = {
        **settings,
        "members": members,
        "duration_s": duration,
        "method_comparison": comparison.along_track_std,
        "method_ratios": [
            {"a": a, "b": b, "measured": m, "long_time_theory": t}
            for a, b, m, t in comparison.ratios()
        ],
        "models": {
            "names": list(model_names),
            "reference": scenarios.REFERENCE_MODEL,
            "why": model_reason,
        },
        "cases": {
            case: {"epoch": str(scenarios.CASE_EPOCHS[case]) + "Z", **ens.summary()}
            for case, ens in ensembles.items()
        },
        "conjunction": conj.summary(),
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
    folder.write_text("summary.json", json.dumps(summary, indent=2))
    days = f"{duration / 86400:g}"
    folder.write_text(
        "summary.md",
        f"# rhoprop paper study\n\n{members} members per Monte Carlo run, "
        f"{days_text(duration)}.\n\n"
        f"{_settings_text(settings)}\n\n"
        f"## Method comparison (Fig. 4)\n\n{comparison.table()}\n\n"
        f"## Ensembles (Fig. 5): along-track at {days} days\n\n"
        f"Models: {', '.join(model_names)} (reference {scenarios.REFERENCE_MODEL}): "
        f"{model_reason}.\n\n{case_table}\n\n"
        f"## Conjunction ({disputed}): Pc from each model, the mixture and Monte Carlo\n\n"
        f"{_conjunction_text(conj)}\n\n"
        f"## CCSP vs Monte Carlo (Fig. 6)\n\n{versus.table()}\n",
    )
    manifest = folder.finish()
    _stage("Done", start)
    written = [*figures, out / "summary.json", out / "summary.md", manifest]
    for path in written:
        print(f"  wrote {path}")
    return written


def _settings(members: int, duration: float, record: SpaceWeather, seed: int) -> dict[str, Any]:
    """What produced the numbers: versions, seeds, processes, models, state."""
    from importlib import metadata

    from .._core import simd_path
    from .._version import __version__
    from .paper import METHODS

    def version(package: str) -> str:
        try:
            return metadata.version(package)
        except metadata.PackageNotFoundError:
            return "not installed"

    state, craft = scenarios.paper_state(), scenarios.paper_spacecraft()
    return {
        "software": {
            "rhoprop": __version__,
            "simd_path": simd_path(),
            **{p: version(p) for p in ("numpy", "pymsis", "spaceweather", "matplotlib")},
        },
        "seed": seed,
        "space_weather": record.source,
        "spacecraft": {
            "cd_ref": craft.cd,
            "area_to_mass_m2_kg": craft.area_to_mass,
            "cr": craft.cr,
        },
        "initial_state_case_i": {
            "epoch": str(state.epoch) + "Z",
            "position_m": [float(x) for x in state.position],
            "velocity_m_s": [float(x) for x in state.velocity],
        },
        "kappa": {
            "method_comparison": {k: repr(v) for k, v in METHODS.items()},
            "ensembles_and_ccsp_comparison_monte_carlo": "GaussMarkov(half_life=1080.0)",
            "ccsp_update_interval_s": 3600.0,
            "perturbation": "additive (rho = mean + kappa sigma)",
        },
        "integrator": "RK8, 180 s step (White 10 s: RK4 at 10 s); J2 only",
        "members": members,
        "duration_s": duration,
    }


def _settings_text(settings: dict[str, Any]) -> str:
    sw = settings["software"]
    versions = ", ".join(f"{k} {v}" for k, v in sw.items() if k != "simd_path")
    return (
        f"Settings: {versions}; SIMD path {sw['simd_path']}; seed {settings['seed']}; "
        f"integrator {settings['integrator']}; Monte Carlo kappa "
        f"{settings['kappa']['ensembles_and_ccsp_comparison_monte_carlo']} (ensembles, Fig. 6), "
        f"CCSP update interval {settings['kappa']['ccsp_update_interval_s']:g} s; space "
        f"weather {settings['space_weather']}; Cd_ref {settings['spacecraft']['cd_ref']}, A/m "
        f"{settings['spacecraft']['area_to_mass_m2_kg']:g} m^2/kg."
    )


def _conjunction_text(conj: ConjunctionStudy) -> str:
    """What the conjunction study shows, in words and a table."""
    sigma = "/".join(f"{s:g}" for s in conj.secondary_sigma)
    lines = [
        f"The paper's object after {conj.duration / 86400:g} days against a synthetic "
        f"secondary crossing at {conj.crossing_angle:g} deg ({conj.relative_speed / 1e3:.1f} "
        f"km/s; secondary sigma R/T/N {sigma} m; HBR {conj.hard_body_radius:g} m), placed at "
        "each model's mean position along the encounter-plane track axis.",
        "",
        conj.table(),
        "",
    ]
    for model, where, ratio in conj.understatement():
        if ratio > 10:
            lines.append(
                f"- {where}, {model} alone gives a Pc {ratio:.2g} times below the mixture."
            )
    return "\n".join(lines)


def _case_table(ensembles: dict[str, EnsembleResult]) -> str:
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


def _paper_orbits(
    state: OrbitState, craft: Spacecraft, duration: float, record: SpaceWeather
) -> None:
    """Each integrator on the benchmark atmosphere, then the three NRLMSIS mean orbits."""
    model = scenarios.benchmark_exponential()
    print(f"  {'method':<8} {'RHS evals':>10} {'wall [s]':>9}  {'vs dop853 [m]':>13}")
    reference = None
    for method in ("dop853", "rk8", "rk4"):
        t0 = time.perf_counter()
        tr = propagate(state, craft, model, duration, dynamics=Dynamics(integrator=method))
        wall = time.perf_counter() - t0
        reference = tr.positions[-1] if reference is None else reference
        diff = float(np.linalg.norm(tr.positions[-1] - reference))
        print(f"  {method:<8} {tr.evaluations:>10} {wall:>9.3f}  {diff:>13.3f}")
    print(f"  {'model':<12} {'field+run [s]':>13}  {'along-track vs 2.1 [m]':>23}")
    ref = None
    for version in ("2.1", "2.0", "00"):
        t0 = time.perf_counter()
        tr = propagate(state, craft, Msis(version, space_weather=record, preset="paper"), duration)
        wall = time.perf_counter() - t0
        ref = tr if ref is None else ref
        along = frames.to_rtn(tr.positions[-1], ref.positions[-1], ref.velocities[-1])[1]
        print(f"  {'NRLMSIS ' + version:<12} {wall:>13.2f}  {along:>23.1f}")
