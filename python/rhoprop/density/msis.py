"""NRLMSIS (2.1, 2.0, NRLMSISE-00) through pymsis, with a documented uncertainty model.

The drivers are always passed to pymsis explicitly from a :class:`~rhoprop.SpaceWeather`
record (pymsis' own downloader is never used). The storm-time ap mode of the models
(switch 9 = -1) is used, so the full 7-element ap history matters.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..spaceweather import Drivers, SpaceWeather, space_weather_argument
from ..time import EpochsLike
from . import calibrated as cal
from ._inputs import broadcast_inputs
from .calibrated import Preset, preset_argument
from .correction import MeanCorrection
from .field import FieldResolution, resolution_arg
from .model import SampledModel

#: ap values of the 28 Kp levels 0, 0+, 1-, ..., 9 (Bartels' Kp -> ap table).
AP_LEVELS = np.array(
    [
        0,
        2,
        3,
        4,
        5,
        6,
        7,
        9,
        12,
        15,
        18,
        22,
        27,
        32,
        39,
        48,
        56,
        67,
        80,
        94,
        111,
        132,
        154,
        179,
        207,
        236,
        300,
        400,
    ],
    dtype=float,
)
_VERSIONS = {"2.1": "2.1", "2": "2.1", "2.0": "2.0", "00": "0", "0": "0"}
#: Driver sensitivities are sampled on every SENSITIVITY_STRIDE-th latitude/longitude node.
SENSITIVITY_STRIDE = 3
#: Drivers change at most every 3 h, on UT multiples of 3 h (ap) and at 00 UT (F10.7).
DRIVER_CADENCE = np.timedelta64(3, "h")

#: ``call(f107, f107a, ap)`` -> density: the model at perturbed drivers.
_DriverCall = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def ap_sigma(ap: npt.ArrayLike) -> np.ndarray:
    """1-sigma uncertainty of an ap value from the resolution of the index: ap is read from
    Kp, which is given in thirds of a unit, so a value is uncertain by about one Kp third,
    i.e. half the distance between the neighbouring ap levels (averaged over both sides;
    interpolated between levels for averaged ap). Storms get a larger sigma (ap 111 ->
    9.5) than quiet times (ap 7 -> 0.75)."""
    levels = AP_LEVELS
    spacing = np.empty_like(levels)
    spacing[1:-1] = (levels[2:] - levels[:-2]) / 4.0
    spacing[0] = (levels[1] - levels[0]) / 2.0
    spacing[-1] = (levels[-1] - levels[-2]) / 2.0
    # A float for a scalar ap, as np.interp gives.
    sigma: np.ndarray = np.interp(np.asarray(ap, dtype=float), levels, spacing)
    return sigma


@dataclass(frozen=True)
class DriverUncertainty:
    """Density sigma from uncertain drivers plus a model-error floor (the default).

    sigma^2 = (drho/dF * sigma_F)^2 + (drho/dap * sigma_ap)^2 + (floor * rho)^2, with the
    derivatives taken by central differences through the same NRLMSIS version:
    F10.7 and F10.7a perturbed together by +-``f107_relative`` (relative), all seven ap
    entries by +-sigma_ap = sqrt((``ap_scale`` * :func:`ap_sigma`)^2 + (``ap_relative`` *
    ap)^2) (clipped at 0). Predicted drivers (a forecast record) add their lead-time
    sigma to each: the daily flux's (:func:`~rhoprop.spaceweather.forecast_sigma`) to
    F10.7, the 81-day average's, a tenth of it
    (:func:`~rhoprop.spaceweather.f107a_forecast_sigma`), to F10.7a, and ap's to ap.

    Figures and sources:
      * ``f107_relative = 0.02``: the absolute calibration of the Penticton 10.7 cm flux
        is about 1-2 % (Tapping 2013, Space Weather 11, 394, doi:10.1002/swe.20064); we
        take the upper end.
      * ``ap_scale = 1``: one Kp third, the resolution of the index the ap values are read
        from (Bartels' Kp scale; Matzka et al. 2021, Space Weather 19, e2020SW002641).
      * ``ap_relative = 0.3``: ap is a coarse proxy of the storm-time energy input; the
        Joule heating inferred for a given ap scatters by tens of per cent (Knipp et al.
        2004, Solar Phys. 224, 495). 30 % is our assumption, chosen so that the driver
        term grows with activity and storms carry more uncertainty than quiet times.
      * ``model_floor = 0.15``: the observed/model density ratios of NRLMSISE-00 and
        NRLMSIS 2.0 against accelerometer-derived densities scatter by about 10-20 % (1
        sigma) at 400 km (Emmert et al. 2021, Earth Space Sci. 8, e2020EA001321;
        Bruinsma et al. 2018, Adv. Space Res. 61, 2775); we take 15 %.
    These are stated assumptions, configurable; they are not fits.
    """

    f107_relative: float = 0.02
    ap_scale: float = 1.0
    model_floor: float = 0.15
    ap_relative: float = 0.3

    def __post_init__(self) -> None:
        for name in ("f107_relative", "ap_scale", "model_floor", "ap_relative"):
            value = _validate.real(name, getattr(self, name))
            if value < 0:
                raise ValueError(f"{name} must be >= 0, got {value}")
        if self.f107_relative >= 1:
            raise ValueError(f"f107_relative must be < 1, got {self.f107_relative}")


@dataclass(frozen=True)
class RelativeSigma:
    """sigma = ``fraction`` * mean density (e.g. 0.1 for 10 %)."""

    fraction: float

    def __post_init__(self) -> None:
        value = _validate.real("fraction", self.fraction)
        if value < 0:
            raise ValueError(f"fraction must be >= 0, got {value}")


class Msis(SampledModel):
    """NRLMSIS mean density with an uncertainty model, through pymsis.

    Args:
        version: ``"2.1"`` (default), ``"2.0"`` or ``"00"`` (NRLMSISE-00).
        space_weather: the :class:`~rhoprop.SpaceWeather` record giving the drivers, or
            a path to a CelesTrak record file (default: the bundled CelesTrak record).
        uncertainty: :class:`DriverUncertainty` or :class:`RelativeSigma` (default: the
            preset's).
        correction: :class:`~rhoprop.density.MeanCorrection` of the mean (default: the
            preset's).
        preset: ``"calibrated"`` (default): for NRLMSIS 2.1 and 2.0 the driver
            uncertainty and mean correction calibrated on observed orbit-averaged densities
            (:mod:`rhoprop.density.calibrated`: 0.854 x the model, sigma floor 11.4 %,
            ap_relative 0.59); ``"paper"``, and NRLMSISE-00 under either preset: the
            literature :class:`DriverUncertainty` and no correction.
        resolution: grid spacing of the field the propagators sample the model into
            (:class:`~rhoprop.density.FieldResolution`; None: its defaults, 1 h, 25 km,
            6 deg latitude, 15 deg longitude).

    Example:
        >>> import numpy as np, rhoprop as rp
        >>> m = rp.density.Msis("2.1")
        >>> mean, std = m.mean_std(np.datetime64("2002-09-07T12:00"), 10.0, 20.0, 400e3)
    """

    def __init__(
        self,
        version: Literal["2.1", "2", "2.0", "00", "0"] = "2.1",
        space_weather: SpaceWeather | str | os.PathLike[str] | None = None,
        uncertainty: DriverUncertainty | RelativeSigma | None = None,
        *,
        correction: MeanCorrection | None = None,
        preset: Preset = "calibrated",
        resolution: FieldResolution | None = None,
    ) -> None:
        key = str(version)
        if key not in _VERSIONS:
            raise ValueError(f"unknown NRLMSIS version {version!r}; expected '2.1', '2.0' or '00'")
        self.version = _VERSIONS[key]
        self.space_weather = space_weather_argument(space_weather)
        calibrated = preset_argument(preset) == "calibrated" and self.version != "0"
        if uncertainty is None:
            uncertainty = (
                DriverUncertainty(
                    model_floor=cal.MSIS_MODEL_FLOOR, ap_relative=cal.MSIS_AP_RELATIVE
                )
                if calibrated
                else DriverUncertainty()
            )
        self.uncertainty = uncertainty
        if not isinstance(self.uncertainty, (DriverUncertainty, RelativeSigma)):
            raise TypeError("uncertainty must be a DriverUncertainty or RelativeSigma")
        if correction is None:
            correction = (
                MeanCorrection(cal.MSIS_SCALE, cal.MSIS_F107_EXPONENT)
                if calibrated
                else MeanCorrection()
            )
        if not isinstance(correction, MeanCorrection):
            raise TypeError("correction must be a MeanCorrection or None")
        self.correction = correction
        self.resolution = resolution_arg(resolution)

    def __repr__(self) -> str:
        name = "00" if self.version == "0" else self.version
        return f"Msis({name!r}, uncertainty={self.uncertainty!r}, correction={self.correction!r})"

    # -- direct evaluation ---------------------------------------------------------------

    def _calc(
        self,
        dates: np.ndarray,
        lons: np.ndarray,
        lats: np.ndarray,
        alts_m: np.ndarray,
        f107: np.ndarray,
        f107a: np.ndarray,
        ap: np.ndarray,
    ) -> np.ndarray:
        """Total mass density, kg/m^3, from pymsis (fly-through or grid mode)."""
        import pymsis

        out = pymsis.calculate(
            dates,
            lons,
            lats,
            np.asarray(alts_m) / 1e3,
            f107,
            f107a,
            ap,
            version=self.version,
            geomagnetic_activity=-1,
        )
        rho: np.ndarray = out[..., 0].astype(float)
        return rho

    def _driver_variance(
        self, call: _DriverCall, drivers: Drivers
    ) -> tuple[np.ndarray, np.ndarray]:
        """(mean, variance from the drivers) with ``call(f107, f107a, ap)`` -> density, by
        central differences; zero variance under :class:`RelativeSigma`."""
        f107, f107a, ap = drivers.f107, drivers.f107a, drivers.ap
        mean = call(f107, f107a, ap)
        var = np.zeros_like(mean)
        u = self.uncertainty
        if isinstance(u, RelativeSigma):
            return mean, var
        # Predicted drivers (a forecast record) add their lead-time sigma, the daily flux
        # and its 81-day average each their own (the average's a tenth of the daily's);
        # observed ones keep exactly the observed-driver perturbation.
        f_rel: Any = u.f107_relative
        fa_rel: Any = u.f107_relative
        if drivers.f107_forecast_sigma is not None and np.any(drivers.f107_forecast_sigma > 0):
            f_rel = np.minimum(np.hypot(u.f107_relative, drivers.f107_forecast_sigma), 0.9)
            if drivers.f107a_forecast_sigma is not None:
                fa_rel = np.minimum(np.hypot(u.f107_relative, drivers.f107a_forecast_sigma), 0.9)
        if np.any(np.asarray(f_rel) > 0):
            hi = call(f107 * (1 + f_rel), f107a * (1 + fa_rel), ap)
            lo = call(f107 * (1 - f_rel), f107a * (1 - fa_rel), ap)
            var += ((hi - lo) / 2.0) ** 2
        ap_lead = drivers.ap_forecast_sigma
        if u.ap_scale > 0 or u.ap_relative > 0 or (ap_lead is not None and np.any(ap_lead > 0)):
            d = np.hypot(u.ap_scale * ap_sigma(ap), u.ap_relative * ap)
            if ap_lead is not None and np.any(ap_lead > 0):
                d = np.hypot(d, ap_lead[:, None] * ap)
            hi = call(f107, f107a, ap + d)
            lo = call(f107, f107a, np.maximum(ap - d, 0.0))
            var += ((hi - lo) / 2.0) ** 2
        return mean, var

    def _floor(self) -> float:
        """Relative sigma not explained by the drivers."""
        u = self.uncertainty
        return u.fraction if isinstance(u, RelativeSigma) else u.model_floor

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of total mass density, kg/m^3, at UTC ``times``,
        geodetic ``lat``/``lon`` (deg) and ``alt`` (m, >= 0), broadcast together."""
        t, la, lo, al = broadcast_inputs(times, lat, lon, alt)
        shape = la.shape
        t, la, lo, al = (a.ravel() for a in (t, la, lo, al))
        below = al < self.lowest_altitude
        if below.any():
            raise ValueError(
                f"alt = {al[below][0]:g} m is below the ground, where NRLMSIS is not defined "
                "(it returned 0 there)"
            )
        drivers = self.space_weather.drivers(t)
        if len(t) == 0:
            return np.zeros(shape), np.zeros(shape)

        def call(f107: np.ndarray, f107a: np.ndarray, ap: np.ndarray) -> np.ndarray:
            return self._calc(t, lo, la, al, f107, f107a, ap)

        mean, var = self._driver_variance(call, drivers)
        sigma = np.sqrt(var + (self._floor() * mean) ** 2)
        factor = self.correction.factor(drivers.f107, drivers.f107a)
        return (mean * factor).reshape(shape), (sigma * factor).reshape(shape)

    # -- sampling into a field -------------------------------------------------------------

    #: NRLMSIS is defined down to the ground: the atlas grid starts there, so a run that
    #: comes down overshoots into the grid, never below it.
    lowest_altitude = 0.0

    def _coverage(self) -> tuple[np.datetime64, np.datetime64] | None:
        return self.space_weather.span

    def _breaks(self, start: np.datetime64, end: np.datetime64) -> np.ndarray:
        first = start.astype("datetime64[h]") - start.astype("datetime64[h]").astype(int) % 3
        steps = np.arange(first, end + DRIVER_CADENCE, DRIVER_CADENCE).astype("datetime64[ns]")
        return steps[(steps > start) & (steps < end)]

    def cache_key(self, start: np.datetime64, end: np.datetime64) -> Any:
        blocks = np.arange(start - DRIVER_CADENCE, end + 2 * DRIVER_CADENCE, DRIVER_CADENCE).astype(
            "datetime64[ns]"
        )
        first, last = self.space_weather.span
        # The driver blocks around the window, within the record (a window may end at it).
        blocks = np.unique(np.clip(blocks, first, last))
        d = self.space_weather.drivers(blocks)
        digest = hashlib.sha256()
        for a in (d.f107, d.f107a, d.ap):
            digest.update(np.ascontiguousarray(a, dtype=float).tobytes())
        for extra in (d.f107_forecast_sigma, d.ap_forecast_sigma, d.f107a_forecast_sigma):
            if extra is not None and np.any(extra > 0):  # predicted drivers: their sigma
                digest.update(np.ascontiguousarray(extra, dtype=float).tobytes())
        return {
            "model": "nrlmsis",
            "version": self.version,
            "uncertainty": {type(self.uncertainty).__name__: asdict(self.uncertainty)},
            "drivers": digest.hexdigest(),
            **({} if self.correction.is_identity else {"correction": asdict(self.correction)}),
        }

    def _grid_values(
        self,
        epochs: np.ndarray,
        left: np.ndarray,
        alt: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """ln(mean) and sigma/mean on the grid (nt, nalt, nlat, nlon) with pymsis' grid
        mode. A node marked ``left`` takes the drivers just before its epoch. Driver
        sensitivities are smooth in space and are sampled every SENSITIVITY_STRIDE-th latitude and
        longitude node, then interpolated linearly."""
        before = epochs - np.where(left, np.timedelta64(1, "us"), np.timedelta64(0, "us"))
        drivers = self.space_weather.drivers(before)

        def grid(
            la: np.ndarray, lo: np.ndarray, f107: np.ndarray, f107a: np.ndarray, ap: np.ndarray
        ) -> np.ndarray:
            # pymsis makes a grid only when the axis lengths differ.
            lens = {len(epochs), len(lo), len(la), len(alt)}
            if len(lens) == 1:
                parts = [
                    self._calc(
                        epochs[i : i + 1],
                        lo,
                        la,
                        alt,
                        f107[i : i + 1],
                        f107a[i : i + 1],
                        ap[i : i + 1],
                    )
                    for i in range(len(epochs))
                ]
                out = np.concatenate(parts, axis=0)
            else:
                out = self._calc(epochs, lo, la, alt, f107, f107a, ap)
            return np.transpose(out, (0, 3, 2, 1))  # (nt, nalt, nlat, nlon)

        mean = grid(lat, lon, drivers.f107, drivers.f107a, drivers.ap)
        ln_factor = np.log(self.correction.factor(drivers.f107, drivers.f107a))[:, None, None, None]
        if isinstance(self.uncertainty, RelativeSigma):
            return np.log(mean) + ln_factor, np.full(mean.shape, self.uncertainty.fraction)
        # Driver sensitivities vary smoothly in space: sample them on every k-th latitude
        # and longitude node and interpolate (k = 1 when the grid does not divide).
        klat = SENSITIVITY_STRIDE if (len(lat) - 1) % SENSITIVITY_STRIDE == 0 else 1
        klon = SENSITIVITY_STRIDE if len(lon) % SENSITIVITY_STRIDE == 0 else 1
        la_c, lo_c = lat[::klat], lon[::klon]
        sub = mean[:, :, ::klat, ::klon]
        calls = iter([sub])

        def call(f107: np.ndarray, f107a: np.ndarray, ap: np.ndarray) -> np.ndarray:
            # The first call is the unperturbed mean, already computed on the full grid.
            first = next(calls, None)
            return first if first is not None else grid(la_c, lo_c, f107, f107a, ap)

        base, var = self._driver_variance(call, drivers)
        rel = _refine(np.sqrt(var) / base, klat, klon)
        return np.log(mean) + ln_factor, np.sqrt(rel**2 + self._floor() ** 2)


def _refine(coarse: np.ndarray, klat: int, klon: int) -> np.ndarray:
    """Linear interpolation from every k-th (lat, lon) node to all nodes: the last two axes
    go from (n, m) to ((n - 1) klat + 1, m klon), longitude periodic."""
    n, m = coarse.shape[-2:]
    w = np.arange(klat) / klat
    lat_full = (
        coarse[..., :-1, None, :] * (1 - w)[:, None] + coarse[..., 1:, None, :] * w[:, None]
    ).reshape(*coarse.shape[:-2], (n - 1) * klat, m)
    lat_full = np.concatenate([lat_full, coarse[..., -1:, :]], axis=-2)
    v = np.arange(klon) / klon
    nxt = np.roll(lat_full, -1, axis=-1)
    out = lat_full[..., None] * (1 - v) + nxt[..., None] * v
    return out.reshape(*lat_full.shape[:-1], m * klon)
