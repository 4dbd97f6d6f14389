"""Calibration of the density uncertainty on observed orbit-averaged densities (CHAMP and
GRACE-FO in 34 storm windows): recomputes the defaults of rhoprop.density.calibrated and
prints how the paper's settings and the calibrated ones cover the observations.

    RHOPROP_JB2008_DATA=../shared/data/jb2008/release_20260604 \\
        python benches/density_calibration.py ../shared/data/density_observed

Tables (docs/density-calibration.md): the fitted values beside the library's; the
empirical correlation of the standardised errors against the fitted two-scale process;
per family and for the mixture (spread-adjusted; the linear pool beside it), the share of
orbits inside mean +- 1/2/3 sigma and the
median observed/model ratio, in quiet, main-phase and recovery orbits, for the paper's
settings (18-minute Gauss-Markov kappa, literature sigmas, no mean correction, equal
weights) and the calibrated ones, cross-validated by storm window (each window predicted by
a calibration on the other 33); last, the library's defaults evaluated exactly (the
models' own mean_std, not the fit's linearisation) on all windows. Takes about a minute.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

import rhoprop as rp
from rhoprop.density import calibrated
from rhoprop.density import calibration as cal
from rhoprop.density.observed import load_observed_orbits

#: The paper's (literature) sigma parameters in the calibration's terms.
PAPER_SIGMA = {
    "NRLMSIS 2.1": (0.15, 0.3),
    "JB2008": (0.12, 0.27, 150.0),
    "Jacchia-Roberts": (0.15, 0.30, 7.0),
}
PAPER_KAPPA_HALF_LIFE = 1080.0


def _row(label: str, p: np.ndarray, ratio: float | None, phase: np.ndarray) -> str:
    cells = []
    for which in ("all", *cal.PHASES):
        sel = p if which == "all" else p[phase == which]
        cells.append("/".join(f"{100 * c:3.0f}" for c in cal.coverage(sel)))
    r = "" if ratio is None else f"{ratio:6.3f}"
    return f"  {label:<18} " + "  ".join(f"{c:>11}" for c in cells) + f"  {r:>6}"


def coverage_table(
    title: str,
    log_obs: np.ndarray,
    means: list[np.ndarray],
    sigmas: list[np.ndarray],
    mixture_pit: np.ndarray,
    phase: np.ndarray,
) -> None:
    """Prints the coverage of each family and of the mixture."""
    counts = {q: int(np.sum(phase == q)) for q in cal.PHASES}
    print(f"\n{title}")
    head = ["all", *(f"{q} ({counts[q]})" for q in cal.PHASES)]
    print(f"  {'':<18} " + "  ".join(f"{h:>11}" for h in head) + "  obs/model")
    for k, name in enumerate(cal.FAMILIES):
        p = cal.pit(log_obs, [means[k]], [sigmas[k]], np.ones(1))
        ratio = float(np.exp(np.median(log_obs - means[k])))
        print(_row(name, p, ratio, phase))
    print(_row("mixture", mixture_pit, None, phase))
    print("  (inside mean +- 1/2/3 sigma, %; Gaussian: 68/95/100)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = os.environ.get("RHOPROP_TEST_DATA")
    parser.add_argument(
        "folder",
        nargs="?",
        default=str(Path(default) / "density_observed") if default else None,
        help="the density_observed folder (default: $RHOPROP_TEST_DATA/density_observed)",
    )
    parser.add_argument("--json", help="write the calibrated values to this file")
    args = parser.parse_args(argv)
    if args.folder is None:
        parser.error("give the density_observed folder or set RHOPROP_TEST_DATA")
    t0 = time.perf_counter()
    orbits = load_observed_orbits(args.folder)
    samples = cal.family_samples(orbits)
    print(
        f"{len(orbits)} observed orbits in {len(np.unique(orbits.storm))} storm windows "
        f"({time.perf_counter() - t0:.0f} s to sample the models)"
    )
    c = cal.calibrate(orbits, samples)
    values = c.values()
    stored = calibrated.values()
    print(f"\n  {'setting':<30} {'calibrated':>12} {'library':>12}")
    for key, value in values.items():
        print(f"  {key:<30} {value:12.4g} {stored[key]:12.4g}")
    w, fast, slow = c.kappa
    process = cal.two_scale_correlation(c.kappa)
    print(
        f"\nkappa: two Gauss-Markov terms, half-lives {fast / 3600:.1f} h and "
        f"{slow / 86400:.1f} d, {100 * w:.0f} % of the variance in the slow one; "
        f"integral time scale {2 * ((1 - w) * fast + w * slow) / np.log(2) / 3600:.0f} h "
        "(the paper's 18-min process: 0.87 h)"
    )
    print("  lag h        " + " ".join(f"{x:5.0f}" for x in c.lags[::3]))
    print("  observed     " + " ".join(f"{x:5.2f}" for x in c.correlation[::3]))
    print("  fitted       " + " ".join(f"{float(process(x * 3600.0)):5.2f}" for x in c.lags[::3]))

    log_obs = np.log(orbits.observed)
    phase = cal.phases(orbits, rp.SpaceWeather())
    # The paper's settings: literature sigmas, the 18-minute process, no correction.
    paper_factors = cal.orbit_factors(orbits, lambda lag: np.exp2(-lag / PAPER_KAPPA_HALF_LIFE))
    p_means = [np.log(orbits.average(fs.mean)) for fs in samples]
    p_sigmas = [
        cal.orbit_sigma(orbits, fs.mean, fs.relative_sigma(PAPER_SIGMA[fs.name]), paper_factors)
        for fs in samples
    ]
    equal = np.full(len(samples), 1.0 / len(samples))
    coverage_table(
        "Paper settings (18-min Gauss-Markov, literature sigma, no correction, equal weights)",
        log_obs,
        p_means,
        p_sigmas,
        cal.pit(log_obs, p_means, p_sigmas, equal),
        phase,
    )
    print(
        f"  orbit-averaged sigma / point sigma under the 18-min process: median "
        f"{np.median(paper_factors):.2f}; under the calibrated one: "
        f"{np.median(cal.orbit_factors(orbits, process)):.2f}"
    )
    means, sigmas, mix, adjusted = cal.cross_validated(orbits, samples, c.kappa)
    coverage_table(
        "Calibrated, cross-validated by storm window (each predicted by the other 33)",
        log_obs,
        means,
        sigmas,
        adjusted,
        phase,
    )
    print(_row("linear pool", mix, None, phase))
    cv_score = cal.log_score(log_obs, means, [x * c.spread for x in sigmas], c.weights)
    pool_score = cal.log_score(log_obs, means, sigmas, c.weights)
    print(
        f"  mixture: spread-adjusted (every family's sigma x {c.spread:.3f} inside it); "
        "'linear pool': the families' own sigmas\n"
        f"  mixture log score (mean ln density of the log density): paper "
        f"{cal.log_score(log_obs, p_means, p_sigmas, equal):.3f}, calibrated {cv_score:.3f} "
        f"(linear pool {pool_score:.3f})"
    )
    # The library's defaults, evaluated exactly through the models.
    models = cal.default_family_models()
    factors = cal.orbit_factors(orbits, process)
    d_means, d_sigmas = [], []
    for model in models:
        mean, std = model.mean_std(orbits.sample_time, orbits.lat, orbits.lon, orbits.alt)
        d_means.append(np.log(orbits.average(mean)))
        d_sigmas.append(cal.orbit_sigma(orbits, mean, std / mean, factors))
    weights = np.array([calibrated.ENSEMBLE_WEIGHTS[n] for n in cal.FAMILIES])
    spread = calibrated.ENSEMBLE_SPREAD
    coverage_table(
        "Library defaults (models' own mean_std, TwoScale kappa), all windows, in sample",
        log_obs,
        d_means,
        d_sigmas,
        cal.pit(log_obs, d_means, [x * spread for x in d_sigmas], weights),
        phase,
    )
    if args.json:
        Path(args.json).write_text(json.dumps(values, indent=1))
    print(f"\n{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
