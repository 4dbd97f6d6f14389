"""Jacchia-Roberts 1971 through the Rust core, driven by the bundled CelesTrak record
(works offline), with an uncertainty model growing with Kp.

Drivers: F10.7 and its 81-day centred mean as the NRLMSIS drivers of the record take them
(:meth:`~rhoprop.SpaceWeather.drivers`), and the 3-hourly Kp of the interval containing
t - 3 h (the usual lag of Jacchia's geomagnetic term, as GMAT and GTDS apply it).
The core evaluates heights >= 90 km (Roberts' closed forms; note the reference
formulation's jump at 100 km, docs/density-models.md).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import asdict
from typing import Any

import numpy as np

from .. import _core
from ..errors import OutsideRecordError
from ..spaceweather import SpaceWeather, space_weather_argument
from . import calibrated as cal
from .calibrated import Preset
from .correction import MeanCorrection
from .field import FieldResolution, resolution_arg
from .point_model import ActivitySigma, PointModel

#: Jacchia-Roberts' default: 15 % quiet, 30 % in storms, full at Kp = 7 (sources in
#: docs/density-models.md).
JR_SIGMA = ActivitySigma(quiet=0.15, storm=0.30, full_at=7.0)
#: The calibrated default (``preset="calibrated"``): sigma and mean correction fitted on
#: observed orbit-averaged densities (docs/density-calibration.md).
JR_CALIBRATED = (
    ActivitySigma(quiet=cal.JR_QUIET, storm=cal.JR_STORM, full_at=cal.JR_FULL_AT),
    MeanCorrection(cal.JR_SCALE, cal.JR_F107_EXPONENT),
)
_KP_LAG = np.timedelta64(3, "h")
_CADENCE = np.timedelta64(3, "h")


class JacchiaRoberts(PointModel):
    """Jacchia-Roberts 1971 mean density with :class:`ActivitySigma` in Kp.

    Args:
        space_weather: the record giving F10.7, F10.7a and Kp, or a path to a CelesTrak
            record file (default: the bundled CelesTrak record; a
            :meth:`~rhoprop.SpaceWeather.mean_geomagnetic` record holds Kp at its
            long-term mean).
        uncertainty: :class:`ActivitySigma` in Kp (default: the preset's).
        correction: :class:`~rhoprop.density.MeanCorrection` (default: the preset's).
        preset: ``"calibrated"`` (default): sigma and mean correction calibrated on
            observed orbit-averaged densities (:data:`JR_CALIBRATED`: 0.728 x the model x
            (F10.7 / F10.7a) ** -2.17, the model overshooting when the daily flux runs
            above its mean); ``"paper"``: :data:`JR_SIGMA` and no correction.
        resolution: grid spacing of the sampled field (see :class:`FieldResolution`).

    Example:
        >>> import numpy as np, rhoprop as rp
        >>> m = rp.density.JacchiaRoberts()
        >>> mean, std = m.mean_std(np.datetime64("2002-09-07T12:00"), 10.0, 20.0, 400e3)
    """

    NAME = "Jacchia-Roberts"

    def __init__(
        self,
        space_weather: SpaceWeather | str | os.PathLike[str] | None = None,
        uncertainty: ActivitySigma | None = None,
        *,
        correction: MeanCorrection | None = None,
        preset: Preset = "calibrated",
        resolution: FieldResolution | None = None,
    ) -> None:
        self.space_weather = space_weather_argument(space_weather)
        self._set_uncertainty(uncertainty, correction, preset, JR_SIGMA, JR_CALIBRATED)
        if self.uncertainty.ap_weight:
            raise ValueError(
                "uncertainty.ap_weight is JB2008's (its dTc lags a storm); Jacchia-Roberts' "
                "activity is Kp itself: leave it 0"
            )
        self.resolution = resolution_arg(resolution)

    def __repr__(self) -> str:
        return f"JacchiaRoberts(uncertainty={self.uncertainty!r}, correction={self.correction!r})"

    def drivers(self, times: np.ndarray) -> np.ndarray:
        """(n, 3) F10.7, F10.7a (sfu) and Kp (of t - 3 h) at UTC ``times``."""
        t = np.asarray(times, dtype="datetime64[ns]").ravel()
        d = self.space_weather.drivers(t)
        lagged = t - _KP_LAG
        day = lagged.astype("datetime64[D]")
        sw = self.space_weather
        row = np.searchsorted(sw.date, day)
        bad = (row >= len(sw.date)) | (sw.date[np.minimum(row, len(sw.date) - 1)] != day)
        if bad.any():
            raise OutsideRecordError(f"no Kp for {lagged[bad][0]} in the space-weather record")
        slot = ((lagged - day).astype("timedelta64[h]").astype(int)) // 3
        kp = sw.kp[row, slot]
        if not np.isfinite(kp).all():
            raise OutsideRecordError(
                f"Kp missing at {lagged[~np.isfinite(kp)][0]} in the space-weather record"
            )
        return np.column_stack([d.f107, d.f107a, kp])

    def _evaluate(
        self,
        mjd: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
        drivers: np.ndarray,
    ) -> np.ndarray:
        return np.asarray(_core.jacchia_roberts_geodetic(mjd, lat, lon, alt, drivers).density)

    def _activity(self, drivers: np.ndarray) -> np.ndarray:
        return drivers[:, 2]  # Kp

    def _breaks(self, start: np.datetime64, end: np.datetime64) -> np.ndarray:
        first = start.astype("datetime64[h]") - start.astype("datetime64[h]").astype(int) % 3
        steps = np.arange(first, end + _CADENCE, _CADENCE).astype("datetime64[ns]")
        return steps[(steps > start) & (steps < end)]

    def _grid_values(
        self,
        epochs: np.ndarray,
        left: np.ndarray,
        alt: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`SampledModel._grid_values`, a node marked ``left`` sampled 1 µs
        before its epoch (the drivers before a jump)."""
        before = epochs - np.where(left, np.timedelta64(1, "us"), np.timedelta64(0, "us"))
        return super()._grid_values(before, left, alt, lat, lon)

    def _coverage(self) -> tuple[np.datetime64, np.datetime64]:
        first, last = self.space_weather.span
        return first + _KP_LAG, last  # Kp of t - 3 h

    def cache_key(self, start: np.datetime64, end: np.datetime64) -> Any:
        blocks = np.arange(start - _CADENCE, end + 2 * _CADENCE, _CADENCE).astype("datetime64[ns]")
        first, last = self._coverage()
        blocks = np.unique(np.clip(blocks, first, last))  # a window may end at the record's end
        digest = hashlib.sha256(np.ascontiguousarray(self.drivers(blocks)).tobytes())
        return {
            "model": "jacchia-roberts-1971",
            "uncertainty": asdict(self.uncertainty),
            "drivers": digest.hexdigest(),
            **({} if self.correction.is_identity else {"correction": asdict(self.correction)}),
        }
