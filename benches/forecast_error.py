"""How far a persistence forecast of F10.7 errs with lead time, on the bundled record.

For each lead L (days), the RMS of log(F(t + L) / F(t)) over the observed days of the
chosen years: the relative 1-sigma of holding the last observed daily F10.7 for L days,
the forecast ``SpaceWeather.as_of`` makes. ``rhoprop.spaceweather.record.
F107_FORECAST_SIGMA`` takes its nodes from this (docs/catalog-realism.md, "Forecast mode").
The same for the centred 81-day average (F10.7a), whose held value errs by the change of
the average over the lead: ``F107A_FORECAST_SIGMA``.

Then ap: from every ``--ap-every``-th day at 00:00, ``SpaceWeather.as_of`` with each
``ap_target``, the forecast daily Ap of the k-th day after against the observed one:
the median of (observed - forecast) / forecast (a bias: negative, the forecast runs high)
and the 68th percentile of its size (what ``AP_FORECAST_SIGMA`` stands for).

Last, the 27-day recurrence (the Sun's rotation brings back active regions and coronal
holes): persistence adjusted by the change of one rotation earlier, log F(t) + w
log(F(t + L - 27) / F(t - 27)), and ap relaxing to a target moved from the 27 days'
median day towards the mean daily Ap of days t + L - 28..26, by a weight w in log(Ap + 4).
The weights are fitted on one half of the years and scored on the other (both ways): the
out-of-sample RMS log error against persistence's (docs/catalog-realism.md, "Forecast
mode").

Run:  python benches/forecast_error.py [--first 1995-01-01] [--last 2023-12-31]
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

import rhoprop as rp
from rhoprop.spaceweather import f107a_forecast_sigma, forecast_sigma
from rhoprop.spaceweather.record import AP_RECURRENCE_OFFSET, AS_OF_AP_RELAX_DAYS

LEADS = (1, 2, 3, 5, 7, 10, 14, 27, 45)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--first", default="1995-01-01")
    parser.add_argument("--last", default="2023-12-31")
    parser.add_argument("--ap-every", type=int, default=3, help="days between ap starts")
    args = parser.parse_args()
    sw = rp.SpaceWeather()
    rows = (
        (sw.section == 0)
        & (sw.date >= np.datetime64(args.first))
        & (sw.date <= np.datetime64(args.last))
    )
    f, fa = sw.f107_obs[rows], sw.f107_obs_ctr81[rows]
    print(f"observed F10.7, {args.first} to {args.last}: {len(f)} days")
    print(
        "| lead, days | F10.7: RMS log error of persistence | forecast_sigma | F10.7a: RMS "
        "log error of persistence | f107a_forecast_sigma |"
    )
    print("| ---: | ---: | ---: | ---: | ---: |")
    for lead in LEADS:
        rms = []
        for series in (f, fa):
            r = np.log(series[lead:] / series[:-lead])
            rms.append(float(np.sqrt(np.mean(r[np.isfinite(r)] ** 2))))
        sigma, sigma_a = float(forecast_sigma(lead)[0]), float(f107a_forecast_sigma(lead))
        print(f"| {lead} | {rms[0]:.3f} | {sigma:.3f} | {rms[1]:.4f} | {sigma_a:.4f} |")
    ap_bias(sw, args)
    recurrence(sw, args)


def ap_bias(sw: rp.SpaceWeather, args: argparse.Namespace) -> None:
    """The as_of forecast of the daily Ap against the observed one, per ap_target."""
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    days = np.arange(
        np.datetime64(args.first, "D"), np.datetime64(args.last, "D") - 7, args.ap_every
    )
    leads = np.array([1, 2, 3, 5, 7])
    print(f"\nforecast daily Ap, {len(days)} starts every {args.ap_every} days")
    print(
        "| ap_target | day after the start | median (obs - forecast) / forecast | 68 % of "
        "its size |"
    )
    print("| --- | ---: | ---: | ---: |")
    for target in ("median", "mean"):
        rel = []
        for day in days:
            start = np.datetime64(day, "ns")
            middles = start + ((leads - 0.5) * 86400e9).astype("timedelta64[ns]")
            fc = sw.as_of(start, ap_target=target).drivers(middles).ap[:, 0]
            obs = sw.drivers(middles).ap[:, 0]
            rel.append((obs - fc) / np.maximum(fc, 1.0))
        r = np.array(rel)
        for j, k in enumerate(leads):
            size = np.percentile(np.abs(r[:, j]), 68.3)
            print(f"| {target} | {k} | {np.median(r[:, j]):+.2f} | {size:.2f} |")


AP_LOG_OFFSET = AP_RECURRENCE_OFFSET
RECURRENCE_WEIGHTS = np.round(np.arange(0.0, 1.01, 0.05), 2)


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e**2)))


def recurrence(sw: rp.SpaceWeather, args: argparse.Namespace) -> None:
    """Out-of-sample gain of a 27-day recurrence term, for F10.7 and for the daily Ap.

    The ap forecast mirrors ``SpaceWeather.as_of`` at 00:00 with its defaults (the last
    day's Ap relaxing in 2 days to the 27 days' median day; each day's keep factor at its
    centre); the recurrence moves the relaxation's target."""
    rows = (
        (sw.section == 0)
        & (sw.date >= np.datetime64(args.first))
        & (sw.date <= np.datetime64(args.last))
    )
    f = np.log(sw.f107_obs[rows].astype(float))
    ap = np.asarray(sw.ap)[rows].mean(axis=1)
    years = sw.date[rows].astype("datetime64[Y]").astype(int) + 1970
    t = np.arange(81, len(f) - 15)
    split = years[t] < int(np.median(years[t]))
    halves = ((split, ~split), (~split, split))
    median = np.array([np.median(ap[i - 26 : i + 1]) for i in t])
    print(
        f"\n27-day recurrence, {len(t)} days; weights fitted on one half of the years, "
        "scored on the other (both ways)"
    )
    print(
        "| lead, days | F10.7: weight | RMS log error / persistence's | daily Ap: weight | "
        "RMS log(Ap + 4) error / as_of's |"
    )
    print("| ---: | --- | ---: | --- | ---: |")
    for lead in (1, 2, 3, 5, 7, 10, 14):
        err = f[t + lead] - f[t]
        change = f[t + lead - 27] - f[t - 27]
        ok = np.isfinite(err) & np.isfinite(change)
        f_weights, f_scored = [], []
        for fit, score in halves:
            a, b = fit & ok, score & ok
            w = float(np.sum(err[a] * change[a]) / np.sum(change[a] ** 2))
            f_weights.append(w)
            f_scored.append((_rms(err[b] - w * change[b]), _rms(err[b])))
        keep = np.exp(-(lead - 0.5) / AS_OF_AP_RELAX_DAYS)
        seen = np.log(ap[t + lead] + AP_LOG_OFFSET)
        back = np.mean([ap[t + lead - 27 + k] for k in (-1, 0, 1)], axis=0)
        target = np.log(median + AP_LOG_OFFSET)
        shift = np.log(back + AP_LOG_OFFSET) - target

        def forecast(
            w: float, target: np.ndarray = target, shift: np.ndarray = shift, keep: float = keep
        ) -> np.ndarray:
            level = np.exp(target + w * shift) - AP_LOG_OFFSET
            return np.log(level + (ap[t] - level) * keep + AP_LOG_OFFSET)

        a_weights, a_scored = [], []
        for fit, score in halves:
            w = min(RECURRENCE_WEIGHTS, key=lambda w: _rms((seen - forecast(w))[fit]))
            a_weights.append(float(w))
            a_scored.append((_rms((seen - forecast(w))[score]), _rms((seen - forecast(0))[score])))
        ratio_f = np.mean([s / p for s, p in f_scored])
        ratio_a = np.mean([s / p for s, p in a_scored])
        print(
            f"| {lead} | {f_weights[0]:.2f}, {f_weights[1]:.2f} | {ratio_f:.3f} | "
            f"{a_weights[0]:.2f}, {a_weights[1]:.2f} | {ratio_a:.3f} |"
        )


if __name__ == "__main__":
    main()
