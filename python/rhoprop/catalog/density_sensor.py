"""The catalog as a density sensor (docs/density-calibration.md, "The catalog as a density
sensor"): every pair of element sets of a decaying object a day apart measures the drag
between them, and many objects together measure the density model's error day by day.

- **Measurement** (:func:`decay_intervals`): for element sets i, j of one object 1-1.6 days
  apart, the fall of the mean semi-major axis a (from SGP4's mean motion) against what the
  model gives per unit Cd*A/m along the older set's SGP4 orbit,
  da/dt = -(a^2 / mu) rho |v_rel| (v_rel . v) Cd*A/m (v_rel: the velocity relative to the
  co-rotating atmosphere). Their log ratio is ln(Cd*A/m) + ln(rho_true / rho_model),
  averaged over the interval.
- **Estimate** (:func:`estimate_density_correction`): per day, a level and an altitude
  gradient of ln(rho_true / rho_model), common to the calibration objects, estimated with
  each object's ln(Cd*A/m) by alternating robust (3-sigma clipped, weighted) fits over the
  :data:`WINDOW_DAYS` before the epoch. The level's mean over the window is zero: each
  object's Cd*A/m carries the model's mean bias, and the correction its changes.
- **Drag of any object** (:func:`drag_parameters`): its own intervals against the corrected
  model give its Cd*A/m (the median) and the relative sigma of that median.

On the 2026-03/04 development history, the common part of the error is 10x the scatter of
one object's day (0.15-0.39 against 0.069 in ln), and the level grows with altitude
(its day-to-day spread 0.15 at 300-470 km, 0.21 at 520-720 km).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..constants import MU, OMEGA_EARTH
from ..density.catalog_corrected import (
    GRADIENT_UNIT,
    REFERENCE_ALTITUDE,
    CatalogCorrected,
    DensityCorrection,
)
from ..density.model import SampledModel
from ..time import EpochLike, from_jd, to_datetime64, ut1_seconds
from .elements import CatalogObject

#: Shortest and longest time between the two element sets of a measurement, days: a day
#: lets the decay stand well above the element sets' noise (about 0.07 in ln at 300-520 km).
INTERVAL_DAYS = (1.0, 1.6)
#: Spacing of the density samples along an interval's orbit, s (47 per orbit).
SAMPLE_STEP = 120.0
#: Days of measurements before the epoch that a correction is estimated from.
WINDOW_DAYS = 27
#: Fewest calibration objects a correction needs (below: ValueError).
MIN_CALIBRATION_OBJECTS = 10
#: Fewest measurements a day needs to get its own value (else interpolated).
MIN_PER_DAY = 5
#: Perigee and apogee (km) an object needs to measure: drag above the element sets' noise,
#: below the heights the model floors matter; and at most this eccentricity.
MEASURE_ALTITUDES_KM = (200.0, 700.0)
MEASURE_MAX_ECCENTRICITY = 0.02
#: A fall of the mean motion between element sets beyond this (rev/day) is an orbit raise,
#: not drag: such an interval is not a measurement.
RAISE_REV_PER_DAY = 5e-4
#: Least scatter (ln) an object's measurements are weighted with.
MIN_SCATTER = 0.03


@dataclass(frozen=True)
class DecayIntervals:
    """Decay measurements, one row per interval.

    Attributes:
        norad_id: object (int).
        start, end: UTC epochs of the two element sets (datetime64[ns]).
        decay: fall of the mean semi-major axis over the interval, m (noise: can be <= 0).
        unit: the fall the model gives per unit Cd*A/m, m per m^2/kg.
        altitude: mean altitude of the interval's orbit, m.
    """

    norad_id: np.ndarray
    start: np.ndarray
    end: np.ndarray
    decay: np.ndarray
    unit: np.ndarray
    altitude: np.ndarray

    def __len__(self) -> int:
        return len(self.norad_id)

    @property
    def log_ratio(self) -> np.ndarray:
        """ln(decay / unit): ln(Cd*A/m) + the model's ln error (NaN where decay <= 0)."""
        out = np.full(len(self), np.nan)
        ok = (self.decay > 0) & (self.unit > 0)
        out[ok] = np.log(self.decay[ok] / self.unit[ok])
        return out

    @property
    def middle(self) -> np.ndarray:
        """Middle epoch of each interval (datetime64[ns])."""
        out: np.ndarray = self.start + (self.end - self.start) // 2
        return out


def _semi_major_axis(sat: object) -> float:
    n = float(sat.no_kozai) / 60.0  # type: ignore[attr-defined]
    return float((MU / n**2) ** (1.0 / 3.0))


def _measures(sat: object) -> bool:
    a = float(sat.a) * 6378.135  # type: ignore[attr-defined]
    e = float(sat.ecco)  # type: ignore[attr-defined]
    lo, hi = MEASURE_ALTITUDES_KM
    return bool(
        e <= MEASURE_MAX_ECCENTRICITY
        and a * (1 - e) - 6378.135 >= lo
        and a * (1 + e) - 6378.135 <= hi
    )


def _pairs(sats: list[object], jd: np.ndarray) -> list[tuple[int, int]]:
    """Consecutive (i, j) with j the first set at least INTERVAL_DAYS[0] after i."""
    out, i = [], 0
    while i < len(sats) - 1:
        j = int(np.searchsorted(jd, jd[i] + INTERVAL_DAYS[0] - 1e-9))
        if j >= len(sats):
            break
        if jd[j] - jd[i] <= INTERVAL_DAYS[1]:
            n0 = float(sats[i].no_kozai) * 1440 / (2 * np.pi)  # type: ignore[attr-defined]
            n1 = float(sats[j].no_kozai) * 1440 / (2 * np.pi)  # type: ignore[attr-defined]
            if (n1 - n0) / (jd[j] - jd[i]) > -RAISE_REV_PER_DAY and _measures(sats[i]):
                out.append((i, j))
        i = j
    return out


def decay_intervals(
    objects: Iterable[CatalogObject],
    model: SampledModel,
    *,
    through: EpochLike | None = None,
    since: EpochLike | None = None,
) -> DecayIntervals:
    """The decay measurements of every object of ``objects`` (several element sets per
    NORAD id: a history, e.g. ``catalog.load(path, history="each")``) with ``model``'s
    mean density, read from its atlas (the densities a run sees).

    Args:
        objects: catalog objects carrying their element sets.
        model: the sampled density model to measure against.
        through: only intervals that end at or before this UTC epoch (default: all).
        since: only intervals that start at or after this UTC epoch (default: all).

    Returns:
        :class:`DecayIntervals`, ordered by start.
    """
    if not isinstance(model, SampledModel):
        raise TypeError(f"model must be a sampled density model, got {type(model).__name__}")
    limit = None if through is None else to_datetime64(through, "through")
    first = None if since is None else to_datetime64(since, "since")
    by_id: dict[int, list[object]] = {}
    for obj in objects:
        sat = obj.satrec()
        if sat is not None:
            by_id.setdefault(int(obj.norad_id), []).append(sat)
    rows = []
    for norad, sats in by_id.items():
        jd = np.array([s.jdsatepoch + s.jdsatepochF for s in sats])  # type: ignore[attr-defined]
        order = np.argsort(jd, kind="stable")
        sats, jd = [sats[k] for k in order], jd[order]
        keep = np.concatenate([[True], np.diff(jd) > 1e-6])
        sats, jd = [s for s, k in zip(sats, keep, strict=True) if k], jd[keep]
        for i, j in _pairs(sats, jd):
            rows.append(
                (
                    norad,
                    sats[i],
                    jd[i],
                    jd[j],
                    _semi_major_axis(sats[i]) - _semi_major_axis(sats[j]),
                )
            )
    if limit is not None:
        rows = [r for r in rows if from_jd(r[3]) <= limit]
    if first is not None:
        rows = [r for r in rows if from_jd(r[2]) >= first]
    rows.sort(key=lambda r: r[2])
    units = _units(rows, model) if rows else np.zeros((0, 2))
    return DecayIntervals(
        norad_id=np.array([r[0] for r in rows], dtype=np.int64),
        start=np.array([from_jd(r[2]) for r in rows], dtype="datetime64[ns]"),
        end=np.array([from_jd(r[3]) for r in rows], dtype="datetime64[ns]"),
        decay=np.array([r[4] for r in rows], dtype=float),
        unit=units[:, 0],
        altitude=units[:, 1],
    )


#: Longest span of intervals (days) whose densities are read from one field.
_CHUNK_DAYS = 3.0


def _units(rows: list[tuple[int, Any, float, float, float]], model: SampledModel) -> np.ndarray:
    """(unit, mean altitude) per row, the rows ordered by start."""
    out = np.zeros((len(rows), 2))
    atlas = model.atlas
    k = 0
    while k < len(rows):
        first = rows[k][2]
        m = k
        while m < len(rows) and rows[m][2] < first + _CHUNK_DAYS:
            m += 1
        last = max(r[3] for r in rows[k:m])
        t0 = from_jd(np.floor(first), first - np.floor(first))
        t1 = from_jd(np.floor(last), last - np.floor(last))
        field = atlas.field(t0, t1)
        for q in range(k, m):
            _, sat, j0, j1, _ = rows[q]
            tau = np.arange(0.0, (j1 - j0) * 86400.0, SAMPLE_STEP)
            jd = j0 + tau / 86400.0
            whole = np.floor(jd)
            err, r, v = sat.sgp4_array(whole, jd - whole)
            r, v = np.asarray(r) * 1e3, np.asarray(v) * 1e3
            if np.any(np.asarray(err) != 0):
                out[q] = np.nan
                continue
            times = from_jd(whole, jd - whole)
            rho = np.asarray(field.mean_sigma(ut1_seconds(times), r)[0])
            out[q, 0] = decay_per_drag(r, v, rho, _semi_major_axis(sat), SAMPLE_STEP)
            out[q, 1] = float(np.mean(np.linalg.norm(r, axis=1))) - 6371008.8
        k = m
    return out


def decay_per_drag(
    positions: np.ndarray, velocities: np.ndarray, density: np.ndarray, a: float, step: float
) -> float:
    """Fall of the mean semi-major axis (m) per unit Cd*A/m (m^2/kg) along an orbit
    sampled every ``step`` s: the sum of (a^2 / mu) rho |v_rel| (v_rel . v) dt, with
    ``positions`` (m) and ``velocities`` (m/s) inertial (n, 3), ``density`` (kg/m^3) and
    ``a`` the mean semi-major axis (m); v_rel is relative to the co-rotating atmosphere."""
    v_rel = velocities - np.cross([0.0, 0.0, OMEGA_EARTH], positions)
    speed = np.linalg.norm(v_rel, axis=1)
    rate = (a**2 / MU) * density * speed * np.sum(v_rel * velocities, axis=1)
    return float(np.sum(rate) * step)


def _day_fit(r: np.ndarray, h: np.ndarray, w: np.ndarray) -> tuple[float, float, float]:
    """(level, gradient, sigma of level) of r ~ level + gradient h, weights w, clipped at
    3 robust sigmas once; the gradient 0 when the altitudes spread under 30 km."""
    keep = np.ones(len(r), bool)
    for _ in range(2):
        hh, rr, ww = h[keep], r[keep], w[keep]
        if np.std(hh) >= 0.3 and len(rr) >= 2 * MIN_PER_DAY:
            x = np.stack([np.ones_like(hh), hh], axis=1)
            sw = np.sqrt(ww)
            coef = np.linalg.lstsq(x * sw[:, None], rr * sw, rcond=None)[0]
        else:
            coef = np.array([np.sum(ww * rr) / np.sum(ww), 0.0])
        res = r - coef[0] - coef[1] * h
        scatter = 1.4826 * float(np.median(np.abs(res[keep]))) or MIN_SCATTER
        keep = np.abs(res) <= 3 * scatter
    n = int(keep.sum())
    return float(coef[0]), float(coef[1]), scatter / np.sqrt(max(n, 1))


def estimate_density_correction(
    intervals: DecayIntervals,
    as_of: EpochLike,
    *,
    calibration_ids: Sequence[int] | None = None,
    window_days: float = WINDOW_DAYS,
) -> DensityCorrection:
    """The model's daily error (level and altitude gradient) from the decay of the
    calibration objects over the ``window_days`` before ``as_of`` (UTC).

    Args:
        intervals: :func:`decay_intervals` measured with the base model.
        as_of: the epoch; only intervals ending by then are used.
        calibration_ids: the NORAD ids that measure (default: every object in
            ``intervals``).
        window_days: days of measurements used.

    Returns:
        :class:`~rhoprop.density.DensityCorrection`. ValueError with fewer than
        :data:`MIN_CALIBRATION_OBJECTS` objects measuring.
    """
    epoch = to_datetime64(as_of, "as_of").astype("datetime64[ns]")
    y = intervals.log_ratio
    sel = (
        np.isfinite(y)
        & (intervals.end <= epoch)
        & (intervals.start >= epoch - np.timedelta64(int(window_days * 86400), "s"))
    )
    if calibration_ids is not None:
        sel &= np.isin(intervals.norad_id, np.asarray(list(calibration_ids), dtype=np.int64))
    ids, y = intervals.norad_id[sel], y[sel]
    h = (intervals.altitude[sel] - REFERENCE_ALTITUDE) / GRADIENT_UNIT
    day = intervals.middle[sel].astype("datetime64[D]")
    objects = np.unique(ids)
    if len(objects) < MIN_CALIBRATION_OBJECTS:
        raise ValueError(
            f"a catalog density correction needs decay measurements of at least "
            f"{MIN_CALIBRATION_OBJECTS} objects in the {window_days:g} days before {epoch}; "
            f"got {len(objects)}"
        )
    which = np.searchsorted(objects, ids)
    days = np.unique(day)
    at = np.searchsorted(days, day)
    c = np.zeros(len(y))
    ln_b = np.array([np.median(y[which == o]) for o in range(len(objects))])
    scatter = np.full(len(objects), 0.1)
    fits = np.zeros((len(days), 3))
    counts = np.zeros(len(days))
    for _ in range(6):
        r = y - ln_b[which]
        w = 1.0 / scatter[which] ** 2
        for d in range(len(days)):
            m = at == d
            counts[d] = len(np.unique(ids[m]))
            fits[d] = _day_fit(r[m], h[m], w[m]) if m.sum() >= MIN_PER_DAY else np.nan
        good = np.isfinite(fits[:, 0])
        if not good.any():
            raise ValueError(
                f"a catalog density correction needs a day with at least {MIN_PER_DAY} "
                f"decay measurements in the {window_days:g} days before {epoch}; none has"
            )
        fits[good, 0] -= np.mean(fits[good, 0])
        level = np.interp(np.arange(len(days)), np.flatnonzero(good), fits[good, 0])
        grad = np.interp(np.arange(len(days)), np.flatnonzero(good), fits[good, 1])
        c = level[at] + grad[at] * h
        for o in range(len(objects)):
            rr = y[which == o] - c[which == o]
            ln_b[o] = np.median(rr)
            scatter[o] = max(1.4826 * float(np.median(np.abs(rr - ln_b[o]))), MIN_SCATTER)
    good = np.isfinite(fits[:, 0])
    return DensityCorrection(
        days=days[good],
        level=fits[good, 0],
        gradient=fits[good, 1],
        sigma=fits[good, 2],
        objects=counts[good],
        as_of=epoch,
        calibration_ids=tuple(int(o) for o in objects),
    )


def drag_parameters(
    intervals: DecayIntervals,
    correction: DensityCorrection,
    *,
    window_days: float = WINDOW_DAYS,
    min_intervals: int = 3,
) -> dict[int, tuple[float, float, int]]:
    """Each object's Cd*A/m (m^2/kg) against the corrected model from its own intervals
    in the ``window_days`` before the correction's epoch: {NORAD id: (Cd*A/m, relative
    1-sigma, intervals used)}, for objects with at least ``min_intervals``."""
    epoch = correction.as_of
    y = intervals.log_ratio
    sel = (
        np.isfinite(y)
        & (intervals.end <= epoch)
        & (intervals.start >= epoch - np.timedelta64(int(window_days * 86400), "s"))
    )
    c = correction.log_factor(intervals.middle[sel], intervals.altitude[sel])
    r, ids = y[sel] - c, intervals.norad_id[sel]
    out: dict[int, tuple[float, float, int]] = {}
    for o in np.unique(ids):
        rr = r[ids == o]
        if len(rr) < min_intervals:
            continue
        med = float(np.median(rr))
        spread = max(1.4826 * float(np.median(np.abs(rr - med))), MIN_SCATTER)
        out[int(o)] = (float(np.exp(med)), 1.25 * spread / np.sqrt(len(rr)), len(rr))
    return out


def corrected_model(
    objects: Iterable[CatalogObject],
    model: SampledModel,
    as_of: EpochLike,
    *,
    calibration_ids: Sequence[int] | None = None,
) -> tuple[CatalogCorrected, DecayIntervals]:
    """``model`` corrected by the decay of ``objects``' element-set histories up to
    ``as_of`` (UTC), and the measurements (for :func:`drag_parameters`)."""
    intervals = decay_intervals(objects, model, through=as_of)
    correction = estimate_density_correction(intervals, as_of, calibration_ids=calibration_ids)
    return CatalogCorrected(model, correction), intervals
