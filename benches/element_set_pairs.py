"""How closely consecutive element sets of one object agree: what a truth made of element
sets can see of a set's error.

For every LEO object of ``$RHOPROP_TEST_DATA/history_2026`` that ``history_days`` judges
(perigee and apogee 200-700 km, not excluded by name, no manoeuvre), each pair of
consecutive element sets: both propagated with SGP4 to the midpoint of their epochs and
differenced in the newer set's RTN frame. Printed per gap between the epochs: the number
of pairs and the RMS and median |difference| radial / along-track / cross-track (m).

If two sets' errors were independent, each of 1-sigma s at the midpoint, the RMS
difference would be sqrt(2) s; an error both sets share (the same tracking, the same
model) cancels. Against precise orbits, SGP4's own offset at epoch is hundreds of metres
(``precise_orbits.py``): the difference here measures only the part that changes from one
set to the next.

Run:  python benches/element_set_pairs.py   (a few seconds)
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path

import numpy as np
from catalog_realism import EXCLUDE, altitudes_km
from history_days import HISTORY, manoeuvres, read_history
from sgp4.api import Satrec
from tables import slashed

from machine import describe
from rhoprop.frames import rtn_basis

#: Bins of the gap between consecutive epochs, days.
GAPS = ((0.0, 0.15), (0.15, 0.3), (0.3, 0.5), (0.5, 1.0), (1.0, 2.0))


def differences(sets: list[tuple[str, str, str, float]]) -> list[tuple[float, np.ndarray]]:
    """(gap in days, RTN difference newer - older at the midpoint, m) of each pair of
    consecutive sets SGP4 propagates without error."""
    out = []
    for old, new in itertools.pairwise(sets):
        gap = new[3] - old[3]
        if gap <= 0.0:
            continue
        mid = (old[3] + new[3]) / 2
        whole = float(np.floor(mid))
        states = []
        for s in (old, new):
            err, r, v = Satrec.twoline2rv(s[1], s[2]).sgp4(whole, mid - whole)
            if err:
                break
            states.append(np.array(r + v) * 1e3)
        if len(states) == 2:
            basis = rtn_basis(states[1][:3], states[1][3:])
            out.append((gap, basis @ (states[1][:3] - states[0][:3])))
    return out


def main() -> None:
    print(describe())
    data = Path(os.environ.get("RHOPROP_TEST_DATA", "../shared/data"))
    history = read_history(data / HISTORY)
    pairs: list[tuple[float, np.ndarray]] = []
    objects = 0
    for sets in history.values():
        lo, hi = altitudes_km(Satrec.twoline2rv(sets[-1][1], sets[-1][2]))
        if any(w in sets[-1][0].upper() for w in EXCLUDE) or manoeuvres(sets):
            continue
        if not (lo >= 200 and hi <= 700):
            continue
        objects += 1
        pairs += differences(sets)
    gaps = np.array([p[0] for p in pairs])
    diff = np.array([p[1] for p in pairs])
    print(f"\n{len(pairs)} pairs of consecutive element sets of {objects} LEO objects")
    print("\n| gap, days | pairs | RMS difference R / T / N m | median abs R / T / N m |")
    print("| --- | ---: | --- | --- |")
    for lo, hi in GAPS:
        m = (gaps > lo) & (gaps <= hi)
        if m.sum() < 10:
            continue
        rms = np.sqrt(np.mean(diff[m] ** 2, axis=0))
        med = np.median(np.abs(diff[m]), axis=0)
        print(f"| {lo:g}-{hi:g} | {m.sum()} | {slashed(rms, '.0f')} | {slashed(med, '.0f')} |")


if __name__ == "__main__":
    main()
