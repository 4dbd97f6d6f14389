"""Observed orbit-averaged densities (accelerometer densities of CHAMP and GRACE-FO averaged
over one orbit, with the orbit rebuilt for each) and a density model averaged over the same
orbits: the truth the density uncertainty is calibrated on (docs/density-calibration.md).

The file format is that of ``orbits.csv`` in the test data's ``density_observed`` folder:
one row per observed orbit with the observation ``acc_effective`` (kg/m^3), the arc
(``arc_s``, ``data_fraction``) and the rebuilt orbit's SGP4 mean elements at ``time``."""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass

import numpy as np

from .. import frames

#: Sample spacing of an observed arc, s (the observation's own 30 s grid).
SAMPLE_STEP = 30.0
#: Rows whose arc had a density for less than this share of its samples are left out: such
#: a value is the average of a part of an orbit whose latitudes are unknown.
MIN_DATA_FRACTION = 0.99
#: Earth's rotation rate, rad/s, of the Picone weights (as the observations were made).
EARTH_RATE = 7.292115e-5


@dataclass(frozen=True)
class ObservedOrbits:
    """Observed orbits and the samples a model is averaged over.

    Attributes:
        storm: (n,) window id of each orbit (e.g. ``"CHAMP_2003-10-29"``).
        satellite: (n,) ``"CHAMP"`` or ``"GRACE-FO-A"``.
        time: (n,) UTC datetime64 of the orbit's midpoint.
        observed: (n,) observed orbit-averaged density, kg/m^3.
        storm_class: (n,) the window's storm class (``"G2"`` .. ``"G5"``).
        sample_time: (m,) UTC datetime64 of every sample of every orbit.
        lat, lon, alt: (m,) geodetic WGS-84 position of the samples, deg, deg, m.
        weight: (m,) Picone weight |v_rel|^2 |v| of each sample, normalised to sum 1 per
            orbit.
        start: (n + 1,) the samples of orbit i are ``start[i]:start[i + 1]``.
    """

    storm: np.ndarray
    satellite: np.ndarray
    time: np.ndarray
    observed: np.ndarray
    storm_class: np.ndarray
    sample_time: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    alt: np.ndarray
    weight: np.ndarray
    start: np.ndarray

    def __len__(self) -> int:
        return len(self.observed)

    def orbit_index(self) -> np.ndarray:
        """(m,) the orbit each sample belongs to."""
        return np.repeat(np.arange(len(self)), np.diff(self.start))

    def average(self, values: np.ndarray) -> np.ndarray:
        """(n,) Picone-weighted orbit average of per-sample ``values`` (m,)."""
        out: np.ndarray = np.add.reduceat(self.weight * values, self.start[:-1])
        return out


def _epoch_days(t: np.datetime64) -> float:
    """Days since 1949-12-31 00:00 UTC, SGP4's epoch."""
    return float((t - np.datetime64("1949-12-31T00:00", "ns")) / np.timedelta64(86_400, "s"))


def load_observed_orbits(
    folder: str | os.PathLike[str], min_data_fraction: float = MIN_DATA_FRACTION
) -> ObservedOrbits:
    """Reads ``orbits.csv`` and ``storms.csv`` of ``folder`` and rebuilds every orbit's
    samples (SGP4 of the rebuilt elements, TEME taken as true-of-date and rotated to the
    Earth by GMST; WGS-84 geodetic positions).

    Args:
        folder: the ``density_observed`` folder.
        min_data_fraction: orbits with less of their arc observed are left out.

    Raises:
        FileNotFoundError: when the folder lacks ``orbits.csv`` or ``storms.csv``.
        ValueError: a row that cannot be read (named by line).
    """
    from sgp4.api import WGS72, Satrec

    root = os.fspath(folder)
    classes = {}
    with open(os.path.join(root, "storms.csv"), newline="") as fh:
        for row in csv.DictReader(fh):
            classes[f"{row['satellite']}_{row['storm_date']}"] = row["kp_category"]
    storms, sats, times, observed, cls = [], [], [], [], []
    s_time, s_pos, s_vel, start = [], [], [], [0]
    with open(os.path.join(root, "orbits.csv"), newline="") as fh:
        for line, row in enumerate(csv.DictReader(fh), start=2):
            try:
                fraction = float(row["data_fraction"])
                if fraction < min_data_fraction:
                    continue
                t = np.datetime64(row["time"].replace(" ", "T"), "ns")
                arc = float(row["arc_s"])
                first, last = float(row["data_first_s"]), float(row["data_last_s"])
                sat = Satrec()
                sat.sgp4init(
                    WGS72,
                    "i",
                    1,
                    _epoch_days(t),
                    0.0,
                    0.0,
                    0.0,
                    float(row["sgp4_ecc"]),
                    math.radians(float(row["sgp4_argp_deg"])),
                    math.radians(float(row["sgp4_incl_deg"])),
                    math.radians(float(row["sgp4_mean_anom_deg"])),
                    float(row["sgp4_n_rev_day"]) * 2 * math.pi / 1440.0,
                    math.radians(float(row["sgp4_raan_deg"])),
                )
                value = float(row["acc_effective"])
                storm = row["storm"]
            except (KeyError, ValueError) as exc:
                raise ValueError(f"orbits.csv line {line}: {exc}") from None
            offsets = -arc / 2 + SAMPLE_STEP * np.arange(round(arc / SAMPLE_STEP))
            offsets = offsets[(offsets >= first - 1e-6) & (offsets <= last + 1e-6)]
            minutes = offsets / 60.0
            jd = np.full(len(minutes), sat.jdsatepoch)
            fr = sat.jdsatepochF + minutes / 1440.0
            err, r, v = sat.sgp4_array(jd, fr)
            if np.any(err) or not value > 0:
                raise ValueError(f"orbits.csv line {line}: SGP4 or the observation failed")
            storms.append(storm)
            sats.append(row["satellite"])
            times.append(t)
            observed.append(value)
            cls.append(classes.get(storm, ""))
            s_time.append(t + (offsets * 1e9).astype("timedelta64[ns]"))
            s_pos.append(r * 1e3)
            s_vel.append(v * 1e3)
            start.append(start[-1] + len(offsets))
    sample_time = np.concatenate(s_time)
    pos = np.concatenate(s_pos)
    vel = np.concatenate(s_vel)
    fixed = frames.inertial_to_fixed(sample_time, pos)
    lla = frames.geodetic(fixed)
    v_rel = vel - np.cross([0.0, 0.0, EARTH_RATE], pos)
    w = np.sum(v_rel**2, axis=1) * np.linalg.norm(vel, axis=1)
    bounds = np.asarray(start)
    w = w / np.repeat(np.add.reduceat(w, bounds[:-1]), np.diff(bounds))
    return ObservedOrbits(
        storm=np.asarray(storms),
        satellite=np.asarray(sats),
        time=np.asarray(times, dtype="datetime64[ns]"),
        observed=np.asarray(observed),
        storm_class=np.asarray(cls),
        sample_time=sample_time,
        lat=lla[:, 0],
        lon=lla[:, 1],
        alt=lla[:, 2],
        weight=w,
        start=bounds,
    )
