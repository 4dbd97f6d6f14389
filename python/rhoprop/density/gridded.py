"""A density model given on a grid by the user (arrays or an xarray Dataset)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..errors import DensityFieldError
from ..time import EpochLike, EpochsLike, to_datetime64, to_datetime64_array, to_seconds
from ._inputs import StateLike
from .field import DensityField, FieldResolution, sample_field
from .model import SampledModel

if TYPE_CHECKING:
    import xarray


class Gridded(SampledModel):
    """Mean and standard deviation of density on a (time, altitude, latitude, longitude)
    grid, interpolated like every sampled field (multilinear in ln(mean) and sigma/mean,
    periodic in longitude, an error outside).

    Args:
        times: UTC node epochs (nt,), non-decreasing; an epoch given twice marks a step.
        alt: geodetic altitudes (nalt,), m, uniform.
        lat: geodetic latitudes (nlat,), deg, uniform, within [-90, 90].
        lon: longitudes (nlon,), deg: nlon equal steps around the globe (e.g. 0..345).
        mean: mean density (nt, nalt, nlat, nlon), kg/m^3, > 0.
        std: standard deviation, same shape, kg/m^3, >= 0.
    """

    def __init__(
        self,
        times: EpochsLike,
        alt: npt.ArrayLike,
        lat: npt.ArrayLike,
        lon: npt.ArrayLike,
        mean: npt.ArrayLike,
        std: npt.ArrayLike,
    ) -> None:
        epochs = to_datetime64_array(times, "times")
        if epochs.ndim != 1 or len(epochs) < 2:
            raise ValueError("times must be a 1-D array of at least 2 valid UTC epochs")
        back = np.flatnonzero(epochs[1:] < epochs[:-1])
        if back.size:
            i = int(back[0]) + 1
            raise ValueError(
                f"times[{i}] ({epochs[i]}) is before times[{i - 1}] ({epochs[i - 1]}): times "
                "must not decrease (a time given twice marks a step)"
            )
        m = np.asarray(mean, dtype=float)
        s = np.asarray(std, dtype=float)
        shape = (len(epochs), np.size(alt), np.size(lat), np.size(lon))
        for name, a in (("mean", m), ("std", s)):
            if a.shape != shape:
                raise ValueError(
                    f"{name} must have shape (time, alt, lat, lon) = {shape}, got {a.shape}"
                )
        if not (np.isfinite(m).all() and (m > 0).all()):
            raise ValueError("mean must be finite and > 0 everywhere")
        if not (np.isfinite(s).all() and (s >= 0).all()):
            raise ValueError("std must be finite and >= 0 everywhere")
        offsets = to_seconds(epochs, epochs[0])
        self._field = DensityField.from_arrays(epochs[0], offsets, alt, lat, lon, np.log(m), s / m)

    @classmethod
    def from_dataset(cls, dataset: xarray.Dataset, mean: str = "mean", std: str = "std") -> Gridded:
        """From an xarray Dataset with variables ``mean`` and ``std`` (kg/m^3) on the
        dimensions ``time``, ``alt`` (m), ``lat``, ``lon`` (deg), in any order."""
        order = ("time", "alt", "lat", "lon")
        try:
            m = dataset[mean].transpose(*order)
            s = dataset[std].transpose(*order)
        except (KeyError, ValueError) as err:
            raise ValueError(
                f"dataset needs variables {mean!r} and {std!r} on dims {order}: {err}"
            ) from err
        times, alt, lat, lon = (np.asarray(dataset[name].values) for name in order)
        return cls(times, alt, lat, lon, m.values, s.values)

    @property
    def native_field(self) -> DensityField:
        """The field as given."""
        return self._field

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Interpolated mean and standard deviation, kg/m^3 (see the class doc)."""
        return self._field.mean_std(times, lat, lon, alt)

    def field(
        self,
        start: EpochLike,
        end: EpochLike,
        *,
        altitude_range: tuple[float, float] | None = None,
        resolution: FieldResolution | None = None,
        cache: bool = False,
    ) -> DensityField:
        """The native grid when no ``resolution`` is given (it must cover [start, end],
        else ``DensityFieldError``); otherwise resampled at ``resolution`` over
        ``altitude_range``."""
        if resolution is None:
            f = self._field
            s, e = to_datetime64(start, "start"), to_datetime64(end, "end")
            if s < f.start or e > f.end:
                raise DensityFieldError(f"the grid covers {f.start} to {f.end}, not {s} to {e}")
            return f
        if altitude_range is None:
            raise ValueError("altitude_range is needed to resample at a resolution")
        return sample_field(
            self, start, end, altitude_range=altitude_range, resolution=resolution, cache=cache
        )

    def served_by(self) -> None:
        """None: the native grid itself reaches the core (an error outside it)."""
        return None

    def atmosphere(self, state: StateLike, duration: float) -> Any:
        """The native field."""
        return self._field.core
