"""How far a persistence forecast of F10.7 errs with lead time, on the bundled record.

For each lead L (days), the RMS of log(F(t + L) / F(t)) over the observed days of the
chosen years: the relative 1-sigma of holding the last observed daily F10.7 for L days,
the forecast ``SpaceWeather.as_of`` makes. ``rhoprop.spaceweather.record.
F107_FORECAST_SIGMA`` takes its nodes from this (docs/catalog-realism.md, "Forecast mode").

Run:  python benches/forecast_error.py [--first 1995-01-01] [--last 2023-12-31]
"""

from __future__ import annotations

import argparse

import numpy as np

import rhoprop as rp
from rhoprop.spaceweather import forecast_sigma

LEADS = (1, 2, 3, 5, 7, 10, 14, 27, 45)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--first", default="1995-01-01")
    parser.add_argument("--last", default="2023-12-31")
    args = parser.parse_args()
    sw = rp.SpaceWeather()
    rows = (
        (sw.section == 0)
        & (sw.date >= np.datetime64(args.first))
        & (sw.date <= np.datetime64(args.last))
    )
    f = sw.f107_obs[rows]
    print(f"observed F10.7, {args.first} to {args.last}: {len(f)} days")
    print("| lead, days | RMS log error of persistence | forecast_sigma |")
    print("| ---: | ---: | ---: |")
    for lead in LEADS:
        r = np.log(f[lead:] / f[:-lead])
        r = r[np.isfinite(r)]
        sigma = float(forecast_sigma(lead)[0])
        print(f"| {lead} | {np.sqrt(np.mean(r**2)):.3f} | {sigma:.3f} |")


if __name__ == "__main__":
    main()
