"""Where the early bias of benches/reentry.py's "2022<" group comes from: per object of the
reentry/ set (the same choice of element sets), deterministic decay times at the mean
density, against the SATCAT decay day (middle):

* "NRLMSIS": rp.propagate (DOP853) of the state and Cd*A/m fitted with NRLMSIS 2.1
  (fit_objects; the element set's own where the fit fails), 120 km floor; and the extra
  time to an 80 km floor;
* "SGP4 profile": the same state through SGP4's static density (its fourth-power law,
  rhoprop.catalog.fit.sgp4_density, of the geocentric radius) with the B*-derived Cd*A/m:
  SGP4's atmosphere in rhoprop's integrator;
* "SGP4": SGP4's own analytic decay of the element set (benches/reentry.py's sgp4_decay);
* "ndot ratio": the element set's mean-motion derivative (2 x the ndot/2 field, unused by
  SGP4) over the rate its B* gives in SGP4 (SGP4's mean motion differenced over +-0.1 day).

Prints per object and per group (those of benches/reentry.py) the median log(predicted /
actual remaining life) of each.

Run:  RHOPROP_TEST_DATA=../shared/data python benches/reentry_causes.py [--limit N]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from reentry import DAY, GROUPS, choose, in_group, sgp4_decay

import rhoprop as rp
from machine import describe
from rhoprop.catalog.fit import _perigee_km, sgp4_density

WGS84_A, WGS84_E2 = 6378137.0, 6.69437999014e-3
SPAN = 14 * 86400.0


def sgp4_profile(perigee_km: float) -> rp.density.FromFunction:
    """SGP4's static density for an element set of mean perigee ``perigee_km``, as a model
    of geodetic inputs (converted to the geocentric radius SGP4 uses)."""

    def fn(t, lat, lon, alt):
        la = np.radians(lat)
        n = WGS84_A / np.sqrt(1 - WGS84_E2 * np.sin(la) ** 2)
        radius = np.hypot((n + alt) * np.cos(la), (n * (1 - WGS84_E2) + alt) * np.sin(la))
        rho = sgp4_density(radius / 1e3, perigee_km)
        return rho, 0.1 * rho

    return rp.density.FromFunction(fn, name=f"sgp4-static-{perigee_km:.0f}km")


def ndot_ratio(sat) -> float:
    """The element set's dn/dt (2 x ndot/2) over SGP4's at the epoch."""

    def mean_motion(days: float) -> float:
        sat.sgp4(sat.jdsatepoch, sat.jdsatepochF + days)
        return float(sat.nm)

    sgp4_rate = (mean_motion(0.1) - mean_motion(-0.1)) / 0.2 / 1440.0  # rad/min^2
    return 2.0 * sat.ndot / sgp4_rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limit", type=int, default=None, help="first N objects only")
    args = parser.parse_args()
    root = os.environ.get("RHOPROP_TEST_DATA")
    if not root:
        raise SystemExit("set RHOPROP_TEST_DATA to the reference data (../shared/data)")
    print(describe())
    chosen, decay, _ = choose(Path(root) / "reentry")
    chosen = chosen[: args.limit] if args.limit else chosen
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "chosen.tle"
        path.write_text("".join(f"{n}\n{a}\n{b}\n" for n, a, b in chosen))
        objects = rp.catalog.load(path).objects
    t0 = time.perf_counter()
    model = rp.density.Msis("2.1")
    fits = rp.catalog.fit_objects(objects, model)
    print(
        f"{'NORAD':>6} {'group':5} {'fit':3} {'actual d':>8} {'NRLMSIS':>8} {'+to 80km s':>10} "
        f"{'SGP4 prof':>9} {'SGP4':>6} {'ndot ratio':>10}"
    )
    rows = []
    for obj, fit in zip(objects, fits, strict=True):
        fitted = isinstance(fit, rp.catalog.CatalogObject)
        use = fit if fitted else obj
        day = decay[obj.norad_id]
        group = next(g for g in GROUPS[1:] if in_group(day, g))
        actual = float((day.astype("datetime64[ns]") + DAY / 2 - obj.state.epoch) / DAY)
        craft = rp.Spacecraft(1.0, use.drag_parameter)
        msis = rp.propagate(use.state, craft, model, SPAN).decayed_at
        lower = rp.propagate(
            use.state,
            craft,
            model,
            SPAN,
            dynamics=rp.Dynamics(floor_altitude=80e3),
        ).decayed_at
        sat = obj.satrec()
        profile = rp.propagate(
            use.state, rp.Spacecraft(1.0, obj.drag_parameter), sgp4_profile(_perigee_km(sat)), SPAN
        ).decayed_at
        days = [np.inf if x is None else x / 86400.0 for x in (msis, profile, sgp4_decay(obj))]
        extra = np.nan if msis is None or lower is None else lower - msis
        ratio = ndot_ratio(obj.satrec())
        rows.append((group, fitted, [np.log(d / actual) for d in days], ratio))
        print(
            f"{obj.norad_id:>6} {group:5} {'yes' if fitted else 'B*':3} {actual:8.2f} "
            f"{days[0]:8.2f} {extra:10.0f} {days[1]:9.2f} {days[2]:6.2f} {ratio:10.2f}"
        )
    print()
    print("median log(predicted / actual remaining life)")
    print(f"{'group':14} {'objects':>7} {'NRLMSIS':>8} {'SGP4 prof':>9} {'SGP4':>6}")
    for group in GROUPS:
        members = [r for r in rows if in_group_label(r[0], group)]
        parts = {"all": members, "fitted": [r for r in members if r[1]]}
        parts["B*"] = [r for r in members if not r[1]]
        for label, part in parts.items():
            if not part or (label != "all" and len(part) == len(members)):
                continue
            med = np.median(np.array([r[2] for r in part]), axis=0)
            print(
                f"{group + ' ' + label:14} {len(part):7d} {med[0]:8.2f} {med[1]:9.2f} {med[2]:6.2f}"
            )
    low = [r for r in rows if r[3] < 0.85]
    print(
        f"ndot ratio < 0.85: {len(low)} objects ("
        + ", ".join(f"{g} {sum(r[0] == g for r in low)}" for g in GROUPS[1:])
        + ")"
    )
    print(f"time {time.perf_counter() - t0:.0f} s")


def in_group_label(label: str, group: str) -> bool:
    """Whether an object's finest group ``label`` (2022<, 2022>, 2023) is in ``group``."""
    return label == group or (group == "2022" and label.startswith("2022"))


if __name__ == "__main__":
    main()
