"""A density model corrected by the drag the catalog measured (docs/density-calibration.md,
"The catalog as a density sensor"): the base model's density times exp(c(t, h)), where
c is a level and an altitude gradient per day estimated from the decay of many objects'
orbits (:func:`rhoprop.catalog.estimate_density_correction`), held after the last day it
was measured (persistence: on the development history, relaxing to the mean with the
calibrated 4.1-day half-life predicted the next 3-7 days no better)."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..time import EpochsLike, to_datetime64_array
from .model import SampledModel

#: Altitude of the gradient's zero, m: the middle of the LEO objects that measure.
REFERENCE_ALTITUDE = 480e3
#: Altitude unit of the gradient, m.
GRADIENT_UNIT = 100e3
#: Altitudes the gradient is applied over, m (the measuring objects' range); outside,
#: the factor of the nearer end: a gradient is not extrapolated to 2,000 km or the ground.
GRADIENT_ALTITUDES = (250e3, 700e3)


@dataclass(frozen=True)
class DensityCorrection:
    """ln of the factor on a base model's density, per day: ``level`` + ``gradient`` x
    (altitude - 480 km) / 100 km (the altitude held within 250-700 km), linear in time
    between the days' middles and held before the first and after the last.

    Attributes:
        days: UTC days (datetime64[D]) of the estimates, ascending.
        level: ln factor at 480 km per day.
        gradient: change of the ln factor per 100 km of altitude per day.
        sigma: 1-sigma of ``level`` per day (the scatter of the objects over their count).
        objects: objects that measured each day.
        as_of: the epoch the correction was estimated at (UTC); after it, persistence.
        calibration_ids: the NORAD ids of the objects that measured it.
    """

    days: np.ndarray
    level: np.ndarray
    gradient: np.ndarray
    sigma: np.ndarray
    objects: np.ndarray
    as_of: np.datetime64
    calibration_ids: tuple[int, ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        days = np.asarray(self.days, dtype="datetime64[D]")
        if days.ndim != 1 or len(days) == 0 or np.any(np.diff(days) <= np.timedelta64(0, "D")):
            raise ValueError("days must be a non-empty ascending 1-D array of dates")
        for name in ("level", "gradient", "sigma", "objects"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.shape != days.shape or not np.all(np.isfinite(a)):
                raise ValueError(f"{name} must be finite with one value per day ({len(days)})")
        if np.any(np.abs(self.level) > 3.0):
            raise ValueError("level must lie within +-3 (a factor of 20 on the density)")
        object.__setattr__(self, "days", days)

    def log_factor(self, times: EpochsLike, alt: npt.ArrayLike) -> np.ndarray:
        """ln of the factor at UTC ``times`` and altitudes ``alt`` (m), broadcast."""
        t = to_datetime64_array(times).astype("datetime64[ns]")
        mid = self.days.astype("datetime64[ns]") + np.timedelta64(12, "h")
        x = ((t - mid[0]) / np.timedelta64(1, "s")).astype(float)
        nodes = ((mid - mid[0]) / np.timedelta64(1, "s")).astype(float)
        level = np.interp(x, nodes, self.level)
        gradient = np.interp(x, nodes, self.gradient)
        h = (np.clip(alt, *GRADIENT_ALTITUDES) - REFERENCE_ALTITUDE) / GRADIENT_UNIT
        out: np.ndarray = level + gradient * h
        return out

    def digest(self) -> str:
        """A hash of the values (for the field cache's key)."""
        d = hashlib.sha256()
        for a in (self.days.astype("int64"), self.level, self.gradient):
            d.update(np.ascontiguousarray(a).tobytes())
        return d.hexdigest()


class CatalogCorrected(SampledModel):
    """``base``'s density times exp(:meth:`DensityCorrection.log_factor`); the base's
    relative sigma is kept (the calibrated sigma of the base's error: conservative near
    the epoch, where the correction has removed part of it).

    Args:
        base: a sampled density model (e.g. :class:`~rhoprop.density.Msis`), the one the
            correction was estimated with.
        correction: the :class:`DensityCorrection`.
    """

    def __init__(self, base: SampledModel, correction: DensityCorrection) -> None:
        if not isinstance(base, SampledModel):
            raise TypeError(f"base must be a sampled density model, got {type(base).__name__}")
        if not isinstance(correction, DensityCorrection):
            raise TypeError("correction must be a DensityCorrection")
        self.base = base
        self.correction = correction
        self.resolution = base.resolution
        self.lowest_altitude = base.lowest_altitude
        self.highest_altitude = base.highest_altitude
        _validate.real("correction level", float(correction.level[-1]))

    def __repr__(self) -> str:
        c = self.correction
        return (
            f"CatalogCorrected({self.base!r}, {len(c.days)} days to {c.days[-1]}, "
            f"last level {c.level[-1]:+.3f})"
        )

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of density, kg/m^3 (the base's, times the factor)."""
        mean, std = self.base.mean_std(times, lat, lon, alt)
        factor = np.exp(self.correction.log_factor(times, np.asarray(alt, dtype=float)))
        return mean * factor, std * factor

    def _coverage(self) -> tuple[np.datetime64, np.datetime64] | None:
        return self.base._coverage()

    def _breaks(self, start: np.datetime64, end: np.datetime64) -> np.ndarray:
        return self.base._breaks(start, end)

    def cache_key(self, start: np.datetime64, end: np.datetime64) -> Any:
        key = self.base.cache_key(start, end)
        if key is None:
            return None
        return {"base": key, "catalog_correction": self.correction.digest()}

    def _grid_values(
        self,
        epochs: np.ndarray,
        left: np.ndarray,
        alt: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        ln_mean, rel = self.base._grid_values(epochs, left, alt, lat, lon)
        c = self.correction.log_factor(epochs[:, None], alt[None, :])
        return ln_mean + c[:, :, None, None], rel
