"""Calibration of the density uncertainty on observed orbit-averaged densities
(docs/density-calibration.md): per family a correction of the mean, a relative sigma
growing with activity, one kappa process for all, and the mixture weights and spread of
the ensemble.

Everything is judged on orbit averages, because that is what the observations are: a
model's orbit average (Picone-weighted, as the observation) against the observed one,
with the relative sigma of the orbit average under the kappa process (the double sum of
the per-sample sigmas times the process's correlation). Residuals are logarithmic.

``benches/density_calibration.py`` runs it and prints the tables; the results are the
defaults in :mod:`rhoprop.density.calibrated`."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..spaceweather import SpaceWeather
from .jacchia_roberts import JacchiaRoberts
from .jb2008 import Jb2008
from .msis import Msis, ap_sigma
from .observed import ObservedOrbits

#: The families calibrated, in the order of the tables.
FAMILIES = ("NRLMSIS 2.1", "JB2008", "Jacchia-Roberts")
#: ap (3-hourly, 2 nT) from which an orbit is in a storm's main phase (Kp 5-, G1).
STORM_AP = 48.0
#: An orbit within this many hours after a main-phase ap is in the recovery phase.
RECOVERY_HOURS = 48
#: Phases of the coverage tables.
PHASES = ("quiet", "main", "recovery")
#: Central intervals of the coverage tables, in sigmas, and the Gaussian coverage of each.
SIGMAS = (1.0, 2.0, 3.0)
GAUSSIAN_COVERAGE = tuple(math.erf(k / math.sqrt(2.0)) for k in SIGMAS)


def ndtr(x: np.ndarray) -> np.ndarray:
    """The standard normal CDF."""
    return np.asarray(0.5 * (1.0 + np.vectorize(math.erf)(np.asarray(x) / math.sqrt(2.0))))


def _scipy_optimize() -> Any:
    """scipy.optimize, which the fits need (a test dependency, not a runtime one)."""
    try:
        import scipy.optimize
    except ImportError as err:  # pragma: no cover - scipy is in the test extra
        raise ImportError("the density calibration needs scipy: pip install scipy") from err
    return scipy.optimize


#: Bounds of the kappa fit: half-lives, h.
FAST_HALF_LIFE_HOURS = (0.5, 48.0)
SLOW_HALF_LIFE_HOURS = (24.0, 30 * 24.0)
#: Lag bins of the empirical correlation, h; bins with fewer pairs are not fitted.
LAG_EDGES_HOURS = np.arange(0.0, 123.0, 3.0)
MIN_PAIRS = 200


@dataclass(frozen=True)
class FamilySamples:
    """What the calibration needs of one family, on the samples of the observed orbits.

    Attributes:
        name: the family (one of :data:`FAMILIES`).
        mean: (m,) the model's uncorrected mean density at the samples, kg/m^3.
        f107, f107a: (n,) the model's own daily F10.7 and 81-day mean at each orbit, sfu.
        terms: per-sample ingredients of the relative sigma: ``activity`` (the family's
            activity driver) for an activity sigma, and for JB2008 ``ap`` (the 3-hourly
            ap, for the activity max(dTc, ap_weight x ap)); ``f107``, ``ap_scale`` and
            ``ap_relative`` (relative density change for the F10.7 perturbation, for one
            Kp third of ap, and per unit of ``ap_relative``) for NRLMSIS.
        full_at: activity at which the family's default activity sigma reaches its storm
            value (the start of the fit).
    """

    name: str
    mean: np.ndarray
    f107: np.ndarray
    f107a: np.ndarray
    terms: dict[str, np.ndarray]
    full_at: float = 0.0

    @property
    def driver_sigma(self) -> bool:
        """True for NRLMSIS's driver uncertainty, False for an activity sigma."""
        return "ap_scale" in self.terms

    def relative_sigma(self, params: tuple[float, ...]) -> np.ndarray:
        """(m,) relative sigma at the samples: ``params`` are (model_floor, ap_relative) of
        the driver uncertainty, or (quiet, storm, full_at[, ap_weight]) of an activity
        sigma."""
        t = self.terms
        if self.driver_sigma:
            a, b = params
            ap = np.hypot(t["ap_scale"], b * t["ap_relative"])
            driver: np.ndarray = np.sqrt(t["f107"] ** 2 + ap**2 + a**2)
            return driver
        a, b, full_at = params[:3]
        w = np.clip(self.with_ap_weight(params[3:]).terms["activity"] / full_at, 0.0, 1.0)
        return a + (b - a) * w

    def with_ap_weight(self, weight: tuple[float, ...]) -> FamilySamples:
        """These samples with the activity max(activity, weight x ap) (``weight`` empty or
        0: unchanged)."""
        if not weight or not weight[0]:
            return self
        act = np.maximum(self.terms["activity"], weight[0] * self.terms["ap"])
        return FamilySamples(
            self.name, self.mean, self.f107, self.f107a, {"activity": act}, self.full_at
        )

    def sigma_start(self) -> tuple[list[float], list[tuple[float, float]]]:
        """Start and bounds of the sigma parameters' fit."""
        if self.driver_sigma:
            return [0.15, 0.3], [(0.01, 1.5), (0.0, 3.0)]
        return [0.15, 0.3, self.full_at], [
            (0.01, 1.5),
            (0.01, 3.0),
            (0.1 * self.full_at, 3 * self.full_at),
        ]


def _msis_samples(model: Msis, orbits: ObservedOrbits) -> FamilySamples:
    t = orbits.sample_time
    d = model.space_weather.drivers(t)

    def call(f107: np.ndarray, f107a: np.ndarray, ap: np.ndarray) -> np.ndarray:
        return model._calc(t, orbits.lon, orbits.lat, orbits.alt, f107, f107a, ap)

    mean = call(d.f107, d.f107a, d.ap)

    def half_range(hi: np.ndarray, lo: np.ndarray) -> np.ndarray:
        out: np.ndarray = (hi - lo) / 2.0 / mean
        return out

    f = 0.02  # f107_relative, kept from the literature
    rel_f = half_range(
        call(d.f107 * (1 + f), d.f107a * (1 + f), d.ap),
        call(d.f107 * (1 - f), d.f107a * (1 - f), d.ap),
    )
    s = ap_sigma(d.ap)
    rel_s = half_range(
        call(d.f107, d.f107a, d.ap + s), call(d.f107, d.f107a, np.maximum(d.ap - s, 0))
    )
    r = 0.3 * d.ap
    rel_r = half_range(call(d.f107, d.f107a, d.ap + r), call(d.f107, d.f107a, d.ap - r)) / 0.3
    o = model.space_weather.drivers(orbits.time)
    return FamilySamples(
        "NRLMSIS 2.1",
        mean,
        o.f107,
        o.f107a,
        {"f107": np.abs(rel_f), "ap_scale": np.abs(rel_s), "ap_relative": np.abs(rel_r)},
    )


def _point_samples(
    name: str, model: Jb2008 | JacchiaRoberts, orbits: ObservedOrbits
) -> FamilySamples:
    from .point_model import modified_julian_date

    t = orbits.sample_time
    drivers = model.drivers(t)
    mean = model._evaluate(modified_julian_date(t), orbits.lat, orbits.lon, orbits.alt, drivers)
    o = model.drivers(orbits.time)
    terms = {"activity": drivers[:, 8] if isinstance(model, Jb2008) else model._activity(drivers)}
    if isinstance(model, Jb2008):
        terms["ap"] = (model.space_weather or SpaceWeather()).drivers(t).ap[:, 1]
    return FamilySamples(
        name,
        np.asarray(mean),
        o[:, 0],
        o[:, 1],
        terms,
        full_at=model.uncertainty.full_at,
    )


def family_samples(
    orbits: ObservedOrbits, models: dict[str, Msis | Jb2008 | JacchiaRoberts] | None = None
) -> list[FamilySamples]:
    """The three families on the observed orbits (``models`` may give each by name; the
    defaults are NRLMSIS 2.1, JB2008 from ``$RHOPROP_JB2008_DATA`` and Jacchia-Roberts,
    all from the bundled space-weather record). Only the models' uncorrected means and
    drivers are used, so the result does not depend on their presets."""
    models = dict(models or {})
    msis = models.get("NRLMSIS 2.1") or Msis("2.1", preset="paper")
    jb = models.get("JB2008") or Jb2008(preset="paper")
    jr = models.get("Jacchia-Roberts") or JacchiaRoberts(preset="paper")
    if not (isinstance(msis, Msis) and isinstance(jb, Jb2008) and isinstance(jr, JacchiaRoberts)):
        raise TypeError("models: an Msis, a Jb2008 and a JacchiaRoberts by family name")
    return [
        _msis_samples(msis, orbits),
        _point_samples("JB2008", jb, orbits),
        _point_samples("Jacchia-Roberts", jr, orbits),
    ]


def default_family_models() -> list[Msis | Jb2008 | JacchiaRoberts]:
    """The three families with the library's default (calibrated) settings, in the order
    of :data:`FAMILIES`."""
    return [Msis("2.1"), Jb2008(), JacchiaRoberts()]


def orbit_factors(
    orbits: ObservedOrbits, correlation: Callable[[np.ndarray], np.ndarray]
) -> np.ndarray:
    """(n,) the relative sigma of each orbit average over the relative sigma of its
    samples when all are equal: sqrt(sum_jk w_j w_k C(t_j - t_k)) for the process's
    correlation ``correlation(lag_s)`` (vectorised over lags)."""
    out = np.empty(len(orbits))
    secs = (orbits.sample_time - orbits.sample_time[0]) / np.timedelta64(1, "s")
    for i in range(len(orbits)):
        a, b = orbits.start[i], orbits.start[i + 1]
        w, s = orbits.weight[a:b], secs[a:b]
        c = correlation(np.abs(s[:, None] - s[None, :]))
        out[i] = math.sqrt(max(float(w @ c @ w), 0.0))
    return out


def orbit_sigma(
    orbits: ObservedOrbits, mean: np.ndarray, rel: np.ndarray, factors: np.ndarray
) -> np.ndarray:
    """(n,) relative sigma of the orbit averages: the density-weighted average of the
    samples' relative sigma ``rel``, times the process's orbit ``factors``."""
    out: np.ndarray = factors * orbits.average(mean * rel) / orbits.average(mean)
    return out


def phases(orbits: ObservedOrbits, space_weather: SpaceWeather) -> np.ndarray:
    """(n,) ``"main"`` where the 3-hourly ap at the orbit is >= :data:`STORM_AP`,
    ``"recovery"`` within :data:`RECOVERY_HOURS` after such an ap, else ``"quiet"``."""
    steps = np.arange(0, RECOVERY_HOURS + 1, 3)
    ap = np.stack(
        [space_weather.drivers(orbits.time - np.timedelta64(int(h), "h")).ap[:, 1] for h in steps],
        axis=1,
    )
    return np.where(
        ap[:, 0] >= STORM_AP, "main", np.where(ap.max(axis=1) >= STORM_AP, "recovery", "quiet")
    )


@dataclass(frozen=True)
class FamilyFit:
    """One family's calibration: the mean correction (scale, f107_exponent) and the sigma
    parameters ((model_floor, ap_relative) for NRLMSIS, (quiet, storm, full_at, ap_weight)
    for JB2008, (quiet, storm, full_at) for Jacchia-Roberts)."""

    name: str
    scale: float
    f107_exponent: float
    sigma: tuple[float, ...]


def _log_ratio(fs: FamilySamples, orbits: ObservedOrbits) -> np.ndarray:
    out: np.ndarray = np.log(orbits.observed / orbits.average(fs.mean))
    return out


#: The ap weights (K per ap unit) JB2008's sigma is tried with; the one of largest
#: likelihood is kept (0: dTc alone).
AP_WEIGHTS = (0.0, 1.0, 2.0, 3.0, 5.0, 7.0, 10.0, 15.0)


def fit_family(
    fs: FamilySamples, orbits: ObservedOrbits, factors: np.ndarray, rows: np.ndarray | None = None
) -> FamilyFit:
    """Least squares of the log ratio on ln(F10.7 / F10.7a) for the mean correction, then
    maximum likelihood of the sigma parameters (Gaussian log residuals), on ``rows``;
    with ap among the samples' terms (JB2008), for each of :data:`AP_WEIGHTS`, keeping the
    likeliest."""
    rows = np.arange(len(orbits)) if rows is None else rows
    y = _log_ratio(fs, orbits)[rows]
    x = np.log(fs.f107 / fs.f107a)[rows]
    design = np.column_stack([np.ones_like(x), x])
    (c0, c1), *_ = np.linalg.lstsq(design, y, rcond=None)
    r = y - c0 - c1 * x
    best: tuple[float, tuple[float, ...]] | None = None
    for weight in AP_WEIGHTS if "ap" in fs.terms else (None,):
        tried = fs if weight is None else fs.with_ap_weight((weight,))
        nll, params = _sigma_fit(tried, orbits, factors, rows, r)
        params = params if weight is None else (*params, weight)
        if best is None or nll < best[0]:
            best = (nll, params)
    assert best is not None
    return FamilyFit(fs.name, float(math.exp(c0)), float(c1), best[1])


def _sigma_fit(
    fs: FamilySamples,
    orbits: ObservedOrbits,
    factors: np.ndarray,
    rows: np.ndarray,
    r: np.ndarray,
) -> tuple[float, tuple[float, ...]]:
    """Maximum likelihood of the sigma parameters given the residuals ``r`` on ``rows``:
    (negative log likelihood, parameters)."""
    orbit_rel = _orbit_relative_sigma(fs, orbits)

    def sigma(p: np.ndarray) -> np.ndarray:
        out: np.ndarray = (factors * orbit_rel(tuple(float(x) for x in p)))[rows]
        return out

    def nll(p: np.ndarray) -> float:
        s = sigma(p)
        return float(np.sum(np.log(s) + r**2 / (2 * s**2)))

    start, bounds = fs.sigma_start()
    best = _scipy_optimize().minimize(nll, np.array(start), bounds=bounds, method="Nelder-Mead")
    return float(best.fun), tuple(float(x) for x in best.x)


def _orbit_relative_sigma(
    fs: FamilySamples, orbits: ObservedOrbits
) -> Callable[[tuple[float, ...]], np.ndarray]:
    """params -> (n,) density-weighted orbit average of the samples' relative sigma. An
    activity sigma takes a few activity values per orbit: its samples are summed per
    (orbit, value) once, so that each call costs the groups, not the samples (exact)."""
    weight = orbits.weight * fs.mean
    total = np.add.reduceat(weight, orbits.start[:-1])
    if fs.driver_sigma:

        def driver(params: tuple[float, ...]) -> np.ndarray:
            out: np.ndarray = orbits.average(fs.mean * fs.relative_sigma(params))
            out /= orbits.average(fs.mean)
            return out

        return driver
    orbit = orbits.orbit_index()
    act = fs.terms["activity"]
    keys, inverse = np.unique(np.column_stack([orbit, act]), axis=0, return_inverse=True)
    group_weight = np.bincount(inverse.ravel(), weights=weight, minlength=len(keys))
    group_orbit = keys[:, 0].astype(int)
    grouped = FamilySamples(fs.name, fs.mean[:0], fs.f107, fs.f107a, {"activity": keys[:, 1]})

    def activity(params: tuple[float, ...]) -> np.ndarray:
        rel = grouped.relative_sigma(params)
        return np.bincount(group_orbit, weights=group_weight * rel, minlength=len(total)) / total

    return activity


def empirical_correlation(
    z: list[np.ndarray], orbits: ObservedOrbits
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lag h, correlation, pairs) of standardised residuals pooled over the families in
    ``z``, from pairs of orbits of the same storm window, in :data:`LAG_EDGES_HOURS` bins."""
    hours = (orbits.time - orbits.time[0]) / np.timedelta64(1, "h")
    nb = len(LAG_EDGES_HOURS) - 1
    num, cnt = np.zeros(nb), np.zeros(nb)
    var = float(np.mean(np.concatenate(z) ** 2))
    for storm in np.unique(orbits.storm):
        m = np.flatnonzero(orbits.storm == storm)
        i, j = np.triu_indices(len(m), 1)
        lag = np.abs(hours[m][i] - hours[m][j])
        b = np.digitize(lag, LAG_EDGES_HOURS) - 1
        ok = (b >= 0) & (b < nb)
        for zz in z:
            np.add.at(num, b[ok], (zz[m][i] * zz[m][j])[ok])
            np.add.at(cnt, b[ok], 1)
    lags = (LAG_EDGES_HOURS[:-1] + LAG_EDGES_HOURS[1:]) / 2
    with np.errstate(invalid="ignore"):
        return lags, num / cnt / var, cnt


def two_scale_correlation(
    params: tuple[float, float, float],
) -> Callable[[np.ndarray], np.ndarray]:
    """C(lag s) = (1 - w) 2^(-lag / fast) + w 2^(-lag / slow) for (w, fast s, slow s)."""
    w, fast, slow = params

    def c(lag: np.ndarray) -> np.ndarray:
        out: np.ndarray = (1 - w) * np.exp2(-lag / fast) + w * np.exp2(-lag / slow)
        return out

    return c


def fit_kappa(lags: np.ndarray, corr: np.ndarray, pairs: np.ndarray) -> tuple[float, float, float]:
    """(slow_fraction, half_life s, slow_half_life s) of the two-scale process whose
    correlation best matches the empirical one (least squares weighted by sqrt(pairs))."""
    ok = pairs >= MIN_PAIRS

    def resid(p: np.ndarray) -> np.ndarray:
        w, hf, hs = p
        model = (1 - w) * np.exp2(-lags[ok] / hf) + w * np.exp2(-lags[ok] / hs)
        out: np.ndarray = (model - corr[ok]) * np.sqrt(pairs[ok])
        return out

    lo = [0.0, FAST_HALF_LIFE_HOURS[0], SLOW_HALF_LIFE_HOURS[0]]
    hi = [1.0, FAST_HALF_LIFE_HOURS[1], SLOW_HALF_LIFE_HOURS[1]]
    fit = _scipy_optimize().least_squares(resid, [0.5, 6.0, 120.0], bounds=(lo, hi))
    w, hf, hs = fit.x
    return float(w), float(hf * 3600.0), float(hs * 3600.0)


def mixture_weights(
    log_obs: np.ndarray, means: list[np.ndarray], sigmas: list[np.ndarray], iterations: int = 200
) -> np.ndarray:
    """Weights of the families' log-normal predictions that maximise the mixture's log
    score on ``log_obs`` (EM; each family's ``means`` are log densities)."""
    dens = np.stack(
        [np.exp(-0.5 * ((log_obs - m) / s) ** 2) / s for m, s in zip(means, sigmas, strict=True)]
    )
    w = np.full(len(means), 1.0 / len(means))
    for _ in range(iterations):
        resp = w[:, None] * dens
        resp /= resp.sum(axis=0, keepdims=True)
        w = resp.mean(axis=1)
    return w


#: Bounds of the mixture's common spread factor.
SPREAD_BOUNDS = (0.5, 1.5)


def mixture_spread(
    log_obs: np.ndarray, means: list[np.ndarray], sigmas: list[np.ndarray], weights: np.ndarray
) -> float:
    """The factor on every family's sigma that maximises the mixture's log score at the
    given weights: the spread-adjusted linear pool (Gneiting & Ranjan 2013), since a pool
    of calibrated families is over-dispersed where their means differ."""

    def negative(s: float) -> float:
        return -log_score(log_obs, means, [x * s for x in sigmas], weights)

    best = _scipy_optimize().minimize_scalar(
        negative, bounds=SPREAD_BOUNDS, method="bounded", options={"xatol": 1e-4}
    )
    return float(best.x)


def pit(
    log_obs: np.ndarray, means: list[np.ndarray], sigmas: list[np.ndarray], weights: np.ndarray
) -> np.ndarray:
    """Probability integral transform of each observation under the mixture."""
    out = np.zeros_like(log_obs)
    for w, m, s in zip(weights, means, sigmas, strict=True):
        out += w * ndtr((log_obs - m) / s)
    return out


def coverage(p: np.ndarray) -> tuple[float, ...]:
    """Share of PIT values inside the central 1, 2, 3 sigma intervals."""
    return tuple(float(np.mean(np.abs(p - 0.5) < g / 2)) for g in GAUSSIAN_COVERAGE)


def log_score(
    log_obs: np.ndarray, means: list[np.ndarray], sigmas: list[np.ndarray], weights: np.ndarray
) -> float:
    """Mean log predictive density (natural log, of the log density) of the mixture."""
    dens = sum(
        w * np.exp(-0.5 * ((log_obs - m) / s) ** 2) / (s * math.sqrt(2 * math.pi))
        for w, m, s in zip(weights, means, sigmas, strict=True)
    )
    return float(np.mean(np.log(dens)))


@dataclass
class Calibration:
    """The calibration's results: per family its fit, the kappa process (slow_fraction,
    half_life s, slow_half_life s), the mixture weights and spread, and the empirical
    correlation."""

    families: list[FamilyFit]
    kappa: tuple[float, float, float]
    weights: np.ndarray
    spread: float
    lags: np.ndarray = field(repr=False)
    correlation: np.ndarray = field(repr=False)
    pairs: np.ndarray = field(repr=False)

    def values(self) -> dict[str, float]:
        """The calibration in the names of :func:`rhoprop.density.calibrated.values`."""
        msis, jb, jr = self.families
        w, fast, slow = self.kappa
        out = {
            "MSIS_MODEL_FLOOR": msis.sigma[0],
            "MSIS_AP_RELATIVE": msis.sigma[1],
            "MSIS_SCALE": msis.scale,
            "MSIS_F107_EXPONENT": msis.f107_exponent,
        }
        for prefix, fit in (("JB2008", jb), ("JR", jr)):
            quiet, storm, full_at = fit.sigma[:3]
            out.update(
                {
                    f"{prefix}_QUIET": quiet,
                    f"{prefix}_STORM": storm,
                    f"{prefix}_FULL_AT": full_at,
                    **({f"{prefix}_AP_WEIGHT": fit.sigma[3]} if len(fit.sigma) > 3 else {}),
                    f"{prefix}_SCALE": fit.scale,
                    f"{prefix}_F107_EXPONENT": fit.f107_exponent,
                }
            )
        out.update(
            {"KAPPA_HALF_LIFE": fast, "KAPPA_SLOW_HALF_LIFE": slow, "KAPPA_SLOW_FRACTION": w}
        )
        out["ENSEMBLE_SPREAD"] = self.spread
        out.update({f"WEIGHT {n}": float(x) for n, x in zip(FAMILIES, self.weights, strict=True)})
        return out


def _predictions(
    samples: list[FamilySamples], fits: list[FamilyFit], orbits: ObservedOrbits, factors: np.ndarray
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    means, sigmas = [], []
    for fs, fit in zip(samples, fits, strict=True):
        corr = np.log(fit.scale) + fit.f107_exponent * np.log(fs.f107 / fs.f107a)
        means.append(np.log(orbits.average(fs.mean)) + corr)
        sigmas.append(orbit_sigma(orbits, fs.mean, fs.relative_sigma(fit.sigma), factors))
    return means, sigmas


def calibrate(
    orbits: ObservedOrbits,
    samples: list[FamilySamples],
    rows: np.ndarray | None = None,
    rounds: int = 2,
) -> Calibration:
    """Fits every family, the kappa process and the weights on ``rows`` (all by default):
    ``rounds`` alternations of the per-family fits (given the process's orbit factors)
    and the process (given the standardised residuals)."""
    rows = np.arange(len(orbits)) if rows is None else rows
    kappa = (0.5, 6 * 3600.0, 5 * 86400.0)
    lags = corr = pairs = np.zeros(0)
    for _ in range(rounds):
        factors = orbit_factors(orbits, two_scale_correlation(kappa))
        fits = [fit_family(fs, orbits, factors, rows) for fs in samples]
        means, sigmas = _predictions(samples, fits, orbits, factors)
        log_obs = np.log(orbits.observed)
        z = [(log_obs - m) / s for m, s in zip(means, sigmas, strict=True)]
        sub = _subset(orbits, rows)
        lags, corr, pairs = empirical_correlation([zz[rows] for zz in z], sub)
        kappa = fit_kappa(lags, corr, pairs)
    factors = orbit_factors(orbits, two_scale_correlation(kappa))
    fits = [fit_family(fs, orbits, factors, rows) for fs in samples]
    means, sigmas = _predictions(samples, fits, orbits, factors)
    log_obs = np.log(orbits.observed)
    sub_means, sub_sigmas = [m[rows] for m in means], [s[rows] for s in sigmas]
    weights = mixture_weights(log_obs[rows], sub_means, sub_sigmas)
    spread = mixture_spread(log_obs[rows], sub_means, sub_sigmas, weights)
    return Calibration(fits, kappa, weights, spread, lags, corr, pairs)


def _subset(orbits: ObservedOrbits, rows: np.ndarray) -> ObservedOrbits:
    """The orbits of ``rows`` (storm and time only: what the correlation needs)."""
    return ObservedOrbits(
        storm=orbits.storm[rows],
        satellite=orbits.satellite[rows],
        time=orbits.time[rows],
        observed=orbits.observed[rows],
        storm_class=orbits.storm_class[rows],
        sample_time=orbits.sample_time[:0],
        lat=orbits.lat[:0],
        lon=orbits.lon[:0],
        alt=orbits.alt[:0],
        weight=orbits.weight[:0],
        start=np.zeros(1, dtype=int),
    )


def cross_validated(
    orbits: ObservedOrbits, samples: list[FamilySamples], kappa: tuple[float, float, float]
) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray, np.ndarray]:
    """Each storm window predicted by a calibration on the others (the kappa process
    held at ``kappa``): per family the log means and sigmas, and the mixture's PIT, as
    a linear pool and with its spread adjusted (fitted on the other windows too)."""
    factors = orbit_factors(orbits, two_scale_correlation(kappa))
    n = len(orbits)
    means = [np.empty(n) for _ in samples]
    sigmas = [np.empty(n) for _ in samples]
    mix, adjusted = np.empty(n), np.empty(n)
    log_obs = np.log(orbits.observed)
    for storm in np.unique(orbits.storm):
        test = orbits.storm == storm
        train = np.flatnonzero(~test)
        fits = [fit_family(fs, orbits, factors, train) for fs in samples]
        m, s = _predictions(samples, fits, orbits, factors)
        tm, ts = [x[train] for x in m], [x[train] for x in s]
        w = mixture_weights(log_obs[train], tm, ts)
        spread = mixture_spread(log_obs[train], tm, ts, w)
        for k in range(len(samples)):
            means[k][test], sigmas[k][test] = m[k][test], s[k][test]
        held_m, held_s = [x[test] for x in m], [x[test] for x in s]
        mix[test] = pit(log_obs[test], held_m, held_s, w)
        adjusted[test] = pit(log_obs[test], held_m, [x * spread for x in held_s], w)
    return means, sigmas, mix, adjusted
