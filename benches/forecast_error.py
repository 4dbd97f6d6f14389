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

Run:  python benches/forecast_error.py [--first 1995-01-01] [--last 2023-12-31]
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

import rhoprop as rp
from rhoprop.spaceweather import f107a_forecast_sigma, forecast_sigma

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


if __name__ == "__main__":
    main()
