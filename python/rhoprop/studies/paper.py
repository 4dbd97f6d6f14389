"""The paper's studies as computations (their figures: :mod:`.plots`).
``method_comparison`` is the paper's section 3 / Fig. 4: the same orbit with five kappa
processes; ``case_ensembles`` Fig. 5; ``ccsp_vs_monte_carlo`` Fig. 6."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import frames
from ..density import Msis
from ..density.model import DensityModel, ModelLike
from ..ensemble import debias_drag_coefficient, ensemble
from ..options import Integrator
from ..propagation import (
    Dynamics,
    MonteCarlo,
    MonteCarloResult,
    OrbitState,
    Spacecraft,
    ccsp,
    kappa,
    monte_carlo,
)
from ..propagation.methods import Method, MethodName, method_argument
from ..spaceweather import SpaceWeather
from . import scenarios
from .scenarios import LABELS

#: The five processes of the paper's comparison, keyed as in ``summary.json``.
METHODS: dict[str, kappa.KappaProcess] = {
    "white_10s": kappa.White(10.0),
    "interpolated_18min": kappa.Interpolated(1080.0),
    "interpolated_180min": kappa.Interpolated(10800.0),
    "gauss_markov_18min": kappa.GaussMarkov(1080.0),
    "gauss_markov_180min": kappa.GaussMarkov(10800.0),
}
#: The Monte Carlo process of the paper's Fig. 5 and 6 (frozen, shared as a default).
_GAUSS_MARKOV_18MIN = kappa.GaussMarkov(1080.0)
#: Ratios of 3-day along-track std and their long-time values, sqrt(D1 / D2).
RATIOS = [
    ("gauss_markov_180min", "gauss_markov_18min"),
    ("interpolated_180min", "interpolated_18min"),
    ("gauss_markov_18min", "interpolated_18min"),
    ("gauss_markov_180min", "interpolated_180min"),
    ("gauss_markov_18min", "white_10s"),
]


@dataclass(frozen=True)
class MethodComparison:
    """Results of :func:`method_comparison`.

    Attributes:
        results: the Monte Carlo result per method key.
        traces: per method, (times s, densities (5, nt) kg/m^3) of the first five members
            over the first 3 h; ``mean_trace`` the mean density along the mean orbit.
        along_track_std: 3-day along-track standard deviation per method, m.
        model: label of the density model.
    """

    results: dict[str, MonteCarloResult]
    traces: dict[str, tuple[np.ndarray, np.ndarray]]
    mean_trace: dict[str, np.ndarray]
    along_track_std: dict[str, float]
    model: str = ""

    def ratios(self) -> list[tuple[str, str, float, float]]:
        """(method a, method b, measured std_a / std_b, long-time theory sqrt(D_a / D_b))."""
        out = []
        for a, b in RATIOS:
            if a not in self.results or b not in self.results:
                continue
            da, db = (self.results[k].kappa.correlation_time() for k in (a, b))
            theory = np.sqrt(da / db)
            out.append((a, b, self.along_track_std[a] / self.along_track_std[b], theory))
        return out

    def table(self) -> str:
        """Markdown table of the stds and the ratios next to the long-time theory."""
        days = next(iter(self.results.values())).times[-1] / 86400.0
        lines = [f"| method | {days:g}-day along-track std [m] |", "| --- | --- |"]
        lines += [f"| {LABELS[k]} | {v:.1f} |" for k, v in self.along_track_std.items()]
        lines += ["", "| ratio | measured | long-time theory |", "| --- | --- | --- |"]
        lines += [
            f"| {LABELS[a]} / {LABELS[b]} | {m:.3f} | {t:.3f} |" for a, b, m, t in self.ratios()
        ]
        return "\n".join(lines)

    def figure(self, path: str | Path) -> Path:
        """Density traces of the first five members (mean in bold) per method, and the
        along-track PDFs at the end; saved as PNG (see :mod:`rhoprop.studies.plots`)."""
        from .plots import method_comparison_figure

        return method_comparison_figure(self, path)


def method_comparison(
    state: OrbitState | None = None,
    spacecraft: Spacecraft | None = None,
    model: ModelLike | None = None,
    duration: float = scenarios.PAPER_DURATION,
    *,
    n: int = 1000,
    seed: int = 0,
    methods: dict[str, kappa.KappaProcess] | None = None,
    progress: bool = True,
) -> MethodComparison:
    """Runs the same orbit with each kappa process (default: the paper's five).

    Args:
        state, spacecraft: default the paper's (Case I epoch).
        model: density model with uncertainty (default NRLMSIS 2.1 with the bundled space
            weather).
        duration: span, s (default 3 days).
        n: members per method; seed: the seed (the traces are the first five members).
        methods: {key: process} (default :data:`METHODS`).
        progress: show progress bars.
    """
    state = state or scenarios.paper_state()
    spacecraft = spacecraft or scenarios.paper_spacecraft()
    model = model if model is not None else Msis("2.1", preset="paper")
    methods = methods or METHODS
    results, traces, mean_trace, stds = {}, {}, {}, {}
    for key, process in methods.items():
        # A White process forces steps as short as its own (10 s), where RK8 is wasted:
        # RK4 at 10 s ends within 3 m of the reference over 3 days (docs/conventions.md),
        # far inside the ~100 m spread, and the mean orbit uses the same integrator.
        # RK4 at the White step itself (10 s), not its 5-s default: 3 m is enough here.
        step = process.step if isinstance(process, kappa.White) and process.step <= 30 else None
        integrator: Integrator = "rk8" if step is None else "rk4"
        results[key] = monte_carlo(
            state,
            spacecraft,
            model,
            duration,
            n=n,
            kappa=process,
            seed=seed,
            output_step=None,
            progress=progress,
            dynamics=Dynamics(integrator=integrator, step=step),
        )
        # Over the members still flying at the end (decayed ones are NaN).
        stds[key] = float(results[key].stats().std[-1, 1])
        h = results[key].step
        trace = monte_carlo(
            state,
            spacecraft,
            model,
            min(3 * 3600.0, duration),
            n=5,
            kappa=process,
            seed=seed,
            output_step=h,
            record_density=True,
            progress=False,
            dynamics=Dynamics(integrator=integrator, step=step),
        )
        assert trace.densities is not None  # record_density=True
        traces[key] = (trace.times, trace.densities)
        mean_trace[key] = _mean_density(model, trace)
    return MethodComparison(results, traces, mean_trace, stds, model_label(model))


def _mean_density(model: Any, result: MonteCarloResult) -> np.ndarray:
    """Mean density along the mean orbit at the output times, kg/m^3."""
    orbit = result.mean_orbit
    lla = frames.geodetic(frames.inertial_to_fixed(orbit.epochs, orbit.positions))
    mean, _ = model.mean_std(orbit.epochs, lla[:, 0], lla[:, 1], lla[:, 2])
    return np.asarray(mean)


def model_label(model: ModelLike) -> str:
    """A short human label for a density model."""
    version = getattr(model, "version", None)
    if version is not None:
        return "NRLMSISE-00" if version == "0" else f"NRLMSIS {version}"
    return getattr(model, "name", None) or type(model).__name__


@dataclass(frozen=True)
class CcspComparison:
    """Results of :func:`ccsp_vs_monte_carlo`: per configuration (label), the Monte Carlo
    along-track errors at the end (of the members still flying) and the CCSP along-track
    mean and std, all relative to
    the reference mean orbit (reference model, Cd_ref), m; the Cd used; run times, s;
    the CCSP update interval, s, and the Monte Carlo's kappa process and member count."""

    mc_along: dict[str, np.ndarray]
    ccsp_mean: dict[str, float]
    ccsp_std: dict[str, float]
    cd: dict[str, float]
    seconds: dict[str, tuple[float, float]]
    duration: float
    update_interval: float = 3600.0
    mc_kappa: kappa.KappaProcess = _GAUSS_MARKOV_18MIN
    members: int = 0

    def expected_ratio(self) -> float:
        """CCSP/Monte Carlo along-track std expected at long times: the CCSP is the
        linearised covariance of kappa piecewise constant over each update interval with
        correlation 1/3 between intervals (docs/conventions.md), so the ratio is
        sqrt(D_ccsp / D_mc) of the two processes' correlation times."""
        equivalent = kappa.PiecewiseConstant(self.update_interval, 1.0 / 3.0)
        return float(np.sqrt(equivalent.correlation_time() / self.mc_kappa.correlation_time()))

    def table(self) -> str:
        """Markdown table: Cd, MC and CCSP along-track mean/std, their ratio, timings."""
        lines = [
            "| configuration | Cd | MC mean [m] | MC std [m] | CCSP mean [m] | CCSP std [m] "
            "| CCSP/MC std | MC [s] | CCSP [s] |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for k, at in self.mc_along.items():
            sd = at.std(ddof=1)
            mc_s, cc_s = self.seconds[k]
            cm, cs = self.ccsp_mean[k], self.ccsp_std[k]
            lines.append(
                f"| {k} | {self.cd[k]:.4f} | {at.mean():.1f} | {sd:.1f} | {cm:.1f} | {cs:.1f} "
                f"| {cs / sd:.3f} | {mc_s:.2f} | {cc_s:.2f} |"
            )
        return "\n".join(lines)

    def figure(self, path: str | Path) -> Path:
        """Along-track PDFs per configuration: MC histogram, MC normal fit and the CCSP
        normal; saved as PNG (see :mod:`rhoprop.studies.plots`)."""
        from .plots import ccsp_comparison_figure

        return ccsp_comparison_figure(self, path)


def ccsp_vs_monte_carlo(
    state: OrbitState | None = None,
    spacecraft: Spacecraft | None = None,
    reference: DensityModel | None = None,
    second: DensityModel | None = None,
    duration: float = scenarios.PAPER_DURATION,
    *,
    second_cd: float | None = None,
    n: int = 1000,
    update_interval: float = 3600.0,
    seed: int = 0,
    progress: bool = True,
) -> CcspComparison:
    """The paper's Fig. 6: CCSP vs Monte Carlo GaussMarkov(18 min) for the reference
    model, and for a second model with Cd_ref and with a debiased Cd (``second_cd``, or
    :func:`~rhoprop.debias_drag_coefficient` over 8 h when None). Defaults: the paper's
    state and sphere, NRLMSIS 2.1 as reference and NRLMSISE-00 as second model."""
    import time

    state = state or scenarios.paper_state()
    spacecraft = spacecraft or scenarios.paper_spacecraft()
    if reference is None or second is None:
        sw = SpaceWeather()
        reference = (
            reference if reference is not None else Msis("2.1", space_weather=sw, preset="paper")
        )
        second = second if second is not None else Msis("00", space_weather=sw, preset="paper")
    if second_cd is None:
        second_cd = debias_drag_coefficient(state, spacecraft, reference, second)
    first_name, second_name = model_label(reference), model_label(second)
    if second_name == first_name:
        second_name += " (second)"
    configs = [
        (f"{first_name}, Cd_ref", reference, spacecraft.cd),
        (f"{second_name}, Cd_ref", second, spacecraft.cd),
        (f"{second_name}, debiased Cd", second, float(second_cd)),
    ]
    along, cmean, cstd, cds, seconds = {}, {}, {}, {}, {}
    ref_orbit = None
    for label, model, cd in configs:
        craft = Spacecraft(cd, spacecraft.area_to_mass, spacecraft.cr)
        t0 = time.perf_counter()
        mc = monte_carlo(
            state,
            craft,
            model,
            duration,
            n=n,
            kappa=_GAUSS_MARKOV_18MIN,
            seed=seed,
            output_step=None,
            progress=progress,
        )
        t1 = time.perf_counter()
        cc = ccsp(
            state, craft, model, duration, update_interval=update_interval, scaling=(3.0, 3.0)
        )
        t2 = time.perf_counter()
        if ref_orbit is None:
            ref_orbit = (mc.reference_positions[-1], mc.reference_velocities[-1])
        # The members still flying at the end (decayed ones are NaN there).
        along[label] = frames.to_rtn(mc.positions[mc.alive[:, -1], -1], *ref_orbit)[:, 1]
        cmean[label] = float(frames.to_rtn(cc.mean[-1, :3], *ref_orbit)[1])
        cstd[label] = float(cc.along_track_std[-1])
        cds[label] = cd
        seconds[label] = (t1 - t0, t2 - t1)
    return CcspComparison(
        along,
        cmean,
        cstd,
        cds,
        seconds,
        float(duration),
        update_interval=float(update_interval),
        mc_kappa=_GAUSS_MARKOV_18MIN,
        members=n,
    )


def case_ensembles(
    cases: Sequence[str] | None = None,
    *,
    n: int = 1000,
    duration: float = scenarios.PAPER_DURATION,
    method: Method | MethodName | None = None,
    seed: int = 0,
    progress: bool = True,
    record: SpaceWeather | None = None,
) -> dict[str, Any]:
    """The paper's Fig. 5: the three-model ensemble for each space-weather case (default
    all four), Cd debiased over 8 h against NRLMSIS 2.1, each model run with ``method``:
    None (default) the paper's Monte Carlo, ``rp.MonteCarlo(n=n, seed=seed,
    kappa=GaussMarkov(18 min), output_step=None, progress=progress)``; or a
    :class:`~rhoprop.MonteCarlo` / :class:`~rhoprop.Ccsp` of its own (then ``n``,
    ``seed`` and ``progress`` are its). Returns {case: EnsembleResult}."""
    paper_mc = MonteCarlo(
        n=n, kappa=_GAUSS_MARKOV_18MIN, seed=seed, output_step=None, progress=progress
    )
    chosen = paper_mc if method is None else method_argument(method, "case_ensembles", paper_mc)
    record = record if record is not None else SpaceWeather()
    out = {}
    for case in cases or scenarios.CASE_EPOCHS:
        state = scenarios.paper_state(scenarios.CASE_EPOCHS[case])
        models = scenarios.case_models(case, record, preset="paper")
        out[case] = ensemble(
            state,
            scenarios.paper_spacecraft(),
            models,
            scenarios.REFERENCE_MODEL,
            method=chosen,
            weights=np.ones(len(models)),
            duration=duration,
        )
    return out
