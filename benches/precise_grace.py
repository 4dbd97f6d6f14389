"""A day of GRACE-A and GRACE-B from a precise state, judged against their precise orbits.

``$RHOPROP_TEST_DATA/precise_orbits/leo/grc{a,b}_truth_LEOGPS.csv.gz`` hold CODE's
precise orbits (Bernese GNSS software) of the two GRACE satellites on 2010-07-27, every
10 s, Earth-fixed (km, dm/s), in GPS time (GPS - UTC = 15 s in 2010). Both fly at about
455 km, near the solar minimum, 220 km apart on one orbit. From the precise state at
00:01 GPS (00:00:45 UTC) each is propagated to the end of the day by ``rp.propagate``
and by ``rp.ccsp`` and compared with the precise orbit (rotated ITRS -> GCRS by
``rp.frames.convert``, astropy) every minute:

- **Dynamics** (NRLMSIS 2.1, forecast drivers): the near-Earth default (J2 only, as the
  paper), J2..J6, and ``Dynamics(field_degree=...)``: the EGM2008 field to degree and
  order 8, 20 and 40 with the Sun and the Moon (40: ``rp.Dynamics.precise()``).
- **Density models** (the field to degree 40): no drag, NRLMSIS 2.1, NRLMSISE-00,
  JB2008 and Jacchia-Roberts, each on the space weather as known at the start (forecast
  mode: ``SpaceWeather.as_of``, ``Jb2008Indices.as_of``) and as observed (hindcast); the
  CCSP's along-track 1-sigma at 24 h and the error in sigmas.

The spacecraft: Cd*A/m = 3.2 x 1.0 m^2 / 480 kg (a diffuse-reflection Cd for a flat
plate at these heights; the 0.955 m^2 front panel and the K-band horn; 487 kg at launch,
less spent gas), uncertain by 15 % (``drag_sigma``). No element sets: the start is the
precise state itself, so the figures measure dynamics and density, not orbit
determination.

Printed per satellite and configuration: the along-track error (propagated - precise, m;
negative: behind) at 6, 12, 18 and 24 h, the 3-D error at 24 h, and for the density rows
the CCSP's along-track sigma at 24 h and the 24-h error in sigmas.

Run:  RHOPROP_TEST_DATA=../shared/data RHOPROP_JB2008_DATA=... python benches/precise_grace.py
"""

from __future__ import annotations

import argparse
import gzip
import os
import time
import warnings
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe
from rhoprop.density import JacchiaRoberts, Jb2008, Jb2008Indices, Msis
from rhoprop.density.model import as_atmosphere
from rhoprop.propagation.propagate import core_propagate

LEO = "precise_orbits/leo"
SATELLITES = {"GRACE-A": "grca_truth_LEOGPS.csv.gz", "GRACE-B": "grcb_truth_LEOGPS.csv.gz"}
GPS_MINUS_UTC = np.timedelta64(15, "s")  # 2010
DURATION = 86_340.0  # s: from 00:01 GPS to the day's last sample
HOURS = (6, 12, 18, 24)
#: Cd * A / m, m^2/kg, and its relative 1-sigma.
DRAG_PARAMETER = 3.2 * 1.0 / 480.0
DRAG_SIGMA = 0.15
#: The dynamics of the density rows: the whole field to degree 40, the Sun and the Moon.
PRECISE = rp.Dynamics.precise()


def read_truth(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(UTC epochs datetime64[ns], Earth-fixed states (n, 6) m and m/s) of a LEOGPS truth
    file: "d/m/yyyy,hh:mm:ss,x,y,z,vx,vy,vz" in GPS time, km and dm/s."""
    epochs, states = [], []
    with gzip.open(path, "rt") as text:
        for line in text:
            if not line.strip():
                continue
            date, clock, *values = line.strip().split(",")
            day, month, year = (int(v) for v in date.split("/"))
            epochs.append(np.datetime64(f"{year:04d}-{month:02d}-{day:02d}T{clock}", "ns"))
            states.append([float(v) for v in values])
    x = np.array(states)
    x[:, :3] *= 1e3
    x[:, 3:] *= 0.1
    return np.array(epochs) - GPS_MINUS_UTC, x


def truth_gcrf(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(UTC epochs, GCRF states (n, 6)) of the truth file every minute from 00:01 GPS
    (00:00:45 UTC: the start lies in the day whose space weather it is)."""
    epochs, fixed = read_truth(path)
    keep = np.arange(6, len(epochs), 6)
    return epochs[keep], rp.frames.convert(epochs[keep], fixed[keep], "ITRF", "GCRF")


def along_track(positions: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Along-track component (m) of positions - truth positions, on the truth's velocity."""
    n = len(positions)
    unit = truth[:n, 3:] / np.linalg.norm(truth[:n, 3:], axis=1)[:, None]
    return np.einsum("ij,ij->i", positions - truth[:n, :3], unit)


def models(start: np.datetime64) -> list[tuple[str, str, object]]:
    """(name, drivers, model) of every density row: forecast and hindcast."""
    record = rp.SpaceWeather()
    weather = record.as_of(start)
    indices = Jb2008Indices.default()
    out: list[tuple[str, str, object]] = []
    for drivers, sw, jb in (
        ("forecast", weather, indices.as_of(start)),
        ("hindcast", record, indices),
    ):
        out += [
            ("NRLMSIS 2.1", drivers, Msis("2.1", space_weather=sw)),
            ("NRLMSISE-00", drivers, Msis("00", space_weather=sw)),
            ("JB2008", drivers, Jb2008(jb, space_weather=sw)),
            ("Jacchia-Roberts", drivers, JacchiaRoberts(space_weather=sw)),
        ]
    return out


def cost(start: rp.OrbitState, dyn: rp.Dynamics) -> float:
    """Microseconds per force evaluation of ``dyn`` (one lane): a day of RK8 at 30 s through
    the exponential atmosphere (cheap, so the forces dominate), best of three."""
    atmosphere = as_atmosphere(rp.scenarios.benchmark_exponential(0.0), start, DURATION)
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        *_, evaluations, _ = core_propagate(
            atmosphere,
            start,
            DRAG_PARAMETER,
            np.array([0.0, DURATION]),
            integrator="rk8",
            step=30.0,
            floor_altitude=dyn.floor_altitude,
            zonal_degree=dyn.zonal_degree,
            forces=dyn.forces(),
        )
        best = min(best, (time.perf_counter() - t0) / evaluations * 1e6)
    return best


def row(name: str, positions: np.ndarray, truth: np.ndarray, extra: str = "") -> str:
    at = along_track(positions, truth)
    k = [60 * h if 60 * h < len(at) else len(at) - 1 for h in HOURS]
    err = np.linalg.norm(positions[k[-1]] - truth[k[-1], :3])
    cells = " | ".join(f"{at[i]:+.0f}" for i in k)
    return f"| {name} | {cells} | {err:.0f} |{extra}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.parse_args()
    data = os.environ.get("RHOPROP_TEST_DATA")
    if not data:
        raise SystemExit("set RHOPROP_TEST_DATA to the shared data directory")
    print(describe())
    warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
    craft = rp.Spacecraft(1.0, DRAG_PARAMETER)
    head = " | ".join(f"{h} h" for h in HOURS)
    for sat, name in SATELLITES.items():
        epochs, truth = truth_gcrf(Path(data) / LEO / name)
        start = rp.OrbitState(epochs[0], truth[0, :3], truth[0, 3:], frame="GCRF")
        forecast = Msis("2.1", space_weather=rp.SpaceWeather().as_of(epochs[0]))
        print(f"\n{sat}, from {epochs[0]} UTC, along-track error m (propagated - precise)")
        print(
            f"\n| dynamics (NRLMSIS 2.1, forecast) | {head} | 3-D at 24 h "
            "| µs per force evaluation |"
        )
        print("| --- |" + " ---: |" * (len(HOURS) + 2))
        for label, dyn in (
            ("J2 (the near-Earth default)", rp.Dynamics()),
            ("J2..J6", rp.Dynamics(zonal_degree=6)),
            (
                "field 8x8, Sun, Moon",
                rp.Dynamics(zonal_degree=6, field_degree=8, third_bodies=True),
            ),
            (
                "field 20x20, Sun, Moon",
                rp.Dynamics(zonal_degree=6, field_degree=20, third_bodies=True),
            ),
            ("field 40x40, Sun, Moon", PRECISE),
        ):
            tr = rp.propagate(start, craft, forecast, DURATION, output_step=60.0, dynamics=dyn)
            print(row(label, tr.positions, truth, f" {cost(start, dyn):.2f} |"))
        print(
            f"\n| density model (field 40x40) | drivers | {head} | 3-D at 24 h "
            "| CCSP sigma at 24 h | error / sigma |"
        )
        print("| --- | --- |" + " ---: |" * (len(HOURS) + 3))
        none = rp.propagate(
            start, rp.Spacecraft(1.0, 1e-12), forecast, DURATION, output_step=60.0, dynamics=PRECISE
        )
        print(row("no drag | -", none.positions, truth, " - | - |"))
        for model_name, drivers, model in models(epochs[0]):
            run = rp.ccsp(
                start,
                craft,
                model,
                DURATION,
                output_times=np.arange(60.0, DURATION - 1.0, 60.0),
                drag_sigma=DRAG_SIGMA,
                dynamics=PRECISE,
            )
            times = run.times
            mean = run.mean[:, :3]
            on_grid = np.isin(np.round(times), 60.0 * np.arange(len(epochs)))
            grid = np.full((len(epochs), 3), np.nan)
            grid[(np.round(times[on_grid]) // 60).astype(int)] = mean[on_grid]
            sigma = run.along_track_std[-1]
            at = along_track(grid, truth)[-1]
            print(
                row(f"{model_name} | {drivers}", grid, truth, f" {sigma:.0f} | {at / sigma:+.2f} |")
            )
        fitted_cd(epochs, truth)


def fitted_cd(epochs: np.ndarray, truth: np.ndarray) -> None:
    """Cd fitted by ``rp.fit_positions`` to the first 12 h (every 2 min) per density
    model and driver set, against Cd 3.2 held: the 3-D error at the last sample, m."""
    seconds = (epochs - epochs[0]) / np.timedelta64(1, "s")
    pick = np.arange(0, len(epochs), 2)
    half = pick[seconds[pick] <= 12 * 3600.0]
    craft = rp.Spacecraft(3.2, DRAG_PARAMETER / 3.2)
    print(
        "\n| density model | drivers | fitted Cd | fit RMS m, Cd held / fitted "
        "| 24 h m, Cd held / fitted |"
    )
    print("| --- | --- | ---: | --- | --- |")
    for model_name, drivers, model in models(epochs[0]):
        held, fit = (
            rp.fit_positions(epochs[half], truth[half, :3], craft, model, fit_cd=fit_cd)
            for fit_cd in (False, True)
        )
        ends = []
        for f in (held, fit):
            run = rp.propagate(f.state, f.spacecraft, model, float(seconds[-1]), dynamics=PRECISE)
            ends.append(float(np.linalg.norm(run.positions[-1] - truth[-1, :3])))
        print(
            f"| {model_name} | {drivers} | {fit.spacecraft.cd:.2f} | {held.rms:.1f} / "
            f"{fit.rms:.1f} | {ends[0]:.0f} / {ends[1]:.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
