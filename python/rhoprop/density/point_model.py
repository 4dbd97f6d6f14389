"""Density models the Rust core evaluates point by point (JB2008, Jacchia-Roberts 1971):
the shared evaluation of :meth:`mean_std`, their activity-dependent uncertainty and the
modified Julian date their reference implementations take."""

from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..time import EpochsLike
from ._inputs import broadcast_inputs
from .correction import MeanCorrection
from .model import SampledModel

_MJD_UNIX = 40587.0
_NS_PER_DAY = 86_400 * 10**9


def modified_julian_date(times: np.ndarray) -> np.ndarray:
    """Modified Julian date (UTC, days; leap seconds not counted, as the reference) of
    ``datetime64`` times."""
    ns = np.asarray(times, dtype="datetime64[ns]").astype(np.int64)
    whole, rest = np.divmod(ns, _NS_PER_DAY)
    mjd: np.ndarray = (whole + _MJD_UNIX) + rest / _NS_PER_DAY
    return mjd


@dataclass(frozen=True)
class ActivitySigma:
    """Relative 1-sigma density error growing with geomagnetic activity:
    sigma/mean = ``quiet`` + (``storm`` - ``quiet``) * clip(activity / ``full_at``, 0, 1),
    with activity the family's own geomagnetic driver (dTc in K for JB2008, Kp for
    Jacchia-Roberts). ``ap_weight`` (JB2008 only, K per ap unit; 0: off): the activity is
    max(dTc, ``ap_weight`` x the 3-hourly ap), since dTc lags a storm's onset while the
    density (and the model's error) rises with ap (docs/density-calibration.md).
    Defaults and sources: docs/density-models.md."""

    quiet: float
    storm: float
    full_at: float
    ap_weight: float = 0.0

    def __post_init__(self) -> None:
        for name in ("quiet", "storm", "full_at", "ap_weight"):
            value = _validate.real(name, getattr(self, name))
            if value < 0:
                raise ValueError(f"{name} must be >= 0, got {value}")
        if self.full_at <= 0:
            raise ValueError(f"full_at must be > 0, got {self.full_at}")

    def relative(self, activity: np.ndarray) -> np.ndarray:
        """sigma/mean at the given activity."""
        w = np.clip(np.asarray(activity, dtype=float) / self.full_at, 0.0, 1.0)
        rel: np.ndarray = self.quiet + (self.storm - self.quiet) * w
        return rel


class PointModel(SampledModel):
    """Base of the models the core evaluates at points: a subclass gives its
    :meth:`drivers` at times, :meth:`_evaluate` (the core call, density in kg/m^3) and
    :meth:`_activity` (the storm driver its :class:`ActivitySigma` grows with)."""

    #: Lowest altitude the models accept, m.
    FLOOR: ClassVar[float] = 90e3
    #: Name in error messages.
    NAME: ClassVar[str] = ""
    #: The atlas grid starts at the models' floor.
    lowest_altitude = 90e3
    uncertainty: ActivitySigma
    #: Correction of the mean: density x scale x (F10.7 / F10.7a) ** exponent, with the
    #: first two columns of :meth:`drivers` (the daily F10.7 and its 81-day mean).
    correction: MeanCorrection = MeanCorrection()

    def _set_uncertainty(
        self,
        uncertainty: ActivitySigma | None,
        correction: MeanCorrection | None,
        preset: object,
        paper: ActivitySigma,
        calibrated: tuple[ActivitySigma, MeanCorrection],
    ) -> None:
        """Sets ``uncertainty`` and ``correction``: the given ones, else the preset's
        (``"paper"``: ``paper`` and no correction; ``"calibrated"``: ``calibrated``)."""
        from .calibrated import preset_argument

        paper_preset = preset_argument(preset) == "paper"
        if uncertainty is None:
            uncertainty = paper if paper_preset else calibrated[0]
        if not isinstance(uncertainty, ActivitySigma):
            raise TypeError("uncertainty must be an ActivitySigma")
        if correction is None:
            correction = MeanCorrection() if paper_preset else calibrated[1]
        if not isinstance(correction, MeanCorrection):
            raise TypeError("correction must be a MeanCorrection or None")
        self.uncertainty, self.correction = uncertainty, correction

    @abc.abstractmethod
    def drivers(self, times: np.ndarray) -> np.ndarray:
        """The model's inputs at UTC ``times``, one row per time."""

    @abc.abstractmethod
    def _evaluate(
        self,
        mjd: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
        drivers: np.ndarray,
    ) -> np.ndarray:
        """Mean density (kg/m^3) from the core at flat arrays of points."""

    @abc.abstractmethod
    def _activity(self, drivers: np.ndarray) -> np.ndarray:
        """The geomagnetic activity of each row of ``drivers``."""

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of total mass density, kg/m^3, at UTC ``times``,
        geodetic ``lat``/``lon`` (deg) and ``alt`` (m, >= 90 km), broadcast together."""
        t, la, lo, al = broadcast_inputs(times, lat, lon, alt)
        shape = la.shape
        t, la, lo, al = (np.ascontiguousarray(a.ravel()) for a in (t, la, lo, al))
        if len(t) == 0:
            return np.zeros(shape), np.zeros(shape)
        below = al < self.FLOOR
        if below.any():
            raise ValueError(f"alt = {al[below][0]} m is below {self.NAME}'s floor of 90 km")
        drivers = self.drivers(t)
        rho = self._evaluate(modified_julian_date(t), la, lo, al, drivers)
        rho = rho * self.correction.factor(drivers[:, 0], drivers[:, 1])
        sigma = self.uncertainty.relative(self._activity(drivers)) * rho
        return rho.reshape(shape), sigma.reshape(shape)
