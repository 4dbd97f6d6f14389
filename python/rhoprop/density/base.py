"""What the propagator needs from a density model.

A stochastic density model answers ``mean_std(times, lat, lon, alt)`` (UTC datetime64,
geodetic WGS-84 degrees and metres) with mean and standard deviation in kg/m^3, and gives
the core an atmosphere it can evaluate without calling back into Python through
``atmosphere(epoch, duration)``: an analytic core atmosphere or a sampled density field.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from .. import _core

#: Core atmosphere objects the propagator evaluates directly.
CoreAtmosphere = (_core.ExponentialAtmosphere, _core.GriddedAtmosphere)


@runtime_checkable
class DensityModel(Protocol):
    """A density model with uncertainty."""

    def mean_std(self, times: Any, lat: Any, lon: Any, alt: Any) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of density, kg/m^3, broadcast over the inputs."""
        ...

    def atmosphere(self, epoch: np.datetime64, duration: float) -> Any:
        """The core atmosphere covering ``duration`` s from ``epoch``."""
        ...


def as_atmosphere(model: Any, epoch: np.datetime64, duration: float) -> Any:
    """The core atmosphere of ``model`` for ``duration`` s from ``epoch``."""
    if isinstance(model, CoreAtmosphere):
        return model
    make = getattr(model, "atmosphere", None)
    if callable(make):
        return make(epoch, duration)
    raise TypeError(
        "density must be a rhoprop density model (e.g. rhoprop.density.Exponential), "
        f"got {type(model).__name__}"
    )


def broadcast_inputs(
    times: Any, lat: Any, lon: Any, alt: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Broadcasts and checks ``mean_std`` inputs: datetime64[ns] times, finite latitude
    in [-90, 90] deg, finite longitude (deg) and altitude (m)."""
    t = np.asarray(times)
    if not np.issubdtype(t.dtype, np.datetime64):
        try:
            t = t.astype("datetime64[ns]")
        except (TypeError, ValueError) as err:
            raise TypeError("times must be UTC datetime64 values or ISO strings") from err
    t = t.astype("datetime64[ns]")
    arrays = []
    for name, value in (("lat", lat), ("lon", lon), ("alt", alt)):
        a = np.asarray(value, dtype=float)
        bad = ~np.isfinite(a)
        if bad.any():
            raise ValueError(f"{name} must be finite; got {a[bad].flat[0]}")
        arrays.append(a)
    la, lo, al = arrays
    if (np.abs(la) > 90.0).any():
        raise ValueError(f"lat must lie in [-90, 90] deg; got {la[np.abs(la) > 90].flat[0]}")
    if np.isnat(t).any():
        raise ValueError("times contain NaT")
    t, la, lo, al = np.broadcast_arrays(t, la, lo, al)
    return t, la, lo, al
