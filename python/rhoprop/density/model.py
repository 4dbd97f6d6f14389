"""What the propagator needs from a density model.

A stochastic density model answers ``mean_std(times, lat, lon, alt)`` (UTC datetime64,
geodetic WGS-84 degrees and metres) with mean and standard deviation in kg/m^3, and gives
the core an atmosphere it can evaluate without calling back into Python through
``atmosphere(state, duration)``: an analytic core atmosphere or a field of the model's
density atlas (:mod:`rhoprop.density.atlas`).
"""

from __future__ import annotations

import abc
from typing import Any, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from .. import _core
from ..time import EpochLike, EpochsLike
from ._inputs import StateLike
from .atlas import Atlas
from .field import DensityField, FieldResolution, sample_field

#: Core atmosphere objects the propagator evaluates directly.
CoreAtmosphere = (
    _core.ExponentialAtmosphere,
    _core.GriddedAtmosphere,
    _core.StreamedAtmosphere,
)


@runtime_checkable
class DensityModel(Protocol):
    """What the propagators accept as ``model``: a density model with uncertainty
    (docs/density-models.md). Every model of :mod:`rhoprop.density` satisfies it; a user's
    own model usually derives from :class:`SampledModel` or wraps a function in
    :class:`~rhoprop.density.FromFunction`."""

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of density, kg/m^3, broadcast over the inputs."""
        ...

    def atmosphere(self, state: StateLike, duration: float) -> Any:
        """The core atmosphere covering ``duration`` s of the orbit from ``state``."""
        ...


#: The core's atmospheres (what a model's ``atmosphere`` gives the propagators).
AtmosphereLike = _core.ExponentialAtmosphere | _core.GriddedAtmosphere | _core.StreamedAtmosphere
#: What the propagators accept as ``model``: a density model or a core atmosphere.
ModelLike = DensityModel | AtmosphereLike


def as_atmosphere(model: ModelLike, state: StateLike, duration: float) -> Any:
    """The core atmosphere of ``model`` for ``duration`` s of the orbit from ``state``."""
    if isinstance(model, CoreAtmosphere):
        return model
    make = getattr(model, "atmosphere", None)
    if callable(make):
        return make(state, duration)
    raise TypeError(
        "density must be a rhoprop density model (e.g. rhoprop.density.Exponential), "
        f"got {type(model).__name__}"
    )


#: Largest mean density a model may give, kg/m^3: ten times sea level. A model giving more
#: is broken (units, a wrong formula), and the propagators would only fail later with a
#: step-size underflow.
MAX_DENSITY = 12.0


class SampledModel(abc.ABC):
    """Base of density models that the core evaluates through a sampled field.

    Subclasses implement :meth:`mean_std`; they may override ``_grid_values`` (faster
    grid sampling), ``_breaks`` (epochs where drivers jump) and ``cache_key`` (enables the
    on-disk field cache).
    """

    #: Grid resolution of :meth:`field` (when none is passed) and :meth:`atmosphere`;
    #: the models set it from their ``resolution`` keyword (None: the defaults of
    #: :class:`~rhoprop.density.FieldResolution`).
    resolution: FieldResolution | None = None

    @abc.abstractmethod
    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of density, kg/m^3, at UTC ``times``, geodetic
        ``lat``/``lon`` (deg) and ``alt`` (m), broadcast together."""

    def field(
        self,
        start: EpochLike,
        end: EpochLike,
        *,
        altitude_range: tuple[float, float],
        resolution: FieldResolution | None = None,
        cache: bool = True,
    ) -> DensityField:
        """Samples the model over [start, end] (UTC) and ``altitude_range`` (geodetic, m)
        on a (time, altitude, latitude, longitude) grid for the core (see
        :class:`~rhoprop.density.field.FieldResolution` for the defaults)."""
        return sample_field(
            self,
            start,
            end,
            altitude_range=altitude_range,
            resolution=resolution or self.resolution,
            cache=cache,
        )

    #: Lowest altitude of the model's atlas grid, m (below any decay floor; a model that
    #: is not defined that low sets its own: 90 km for JB2008 and Jacchia-Roberts).
    lowest_altitude: float = 50e3
    #: Highest altitude the model is defined at, m; the atlas ceiling is the lower of this
    #: and :data:`~rhoprop.density.atlas.DEFAULT_CEILING` (above it: extrapolated).
    highest_altitude: float = float("inf")

    @property
    def atlas(self) -> Atlas:
        """The model's :class:`~rhoprop.density.atlas.Atlas` (made once per model)."""
        atlas = self.__dict__.get("_atlas")
        if atlas is None or atlas.resolution != (self.resolution or FieldResolution()):
            atlas = Atlas(self)
            self.__dict__["_atlas"] = atlas
        return atlas

    def served_by(self) -> Atlas | None:
        """The atlas that serves the model to the core (None: the model gives its own
        field, as :class:`~rhoprop.density.Gridded` does)."""
        return self.atlas

    def __getstate__(self) -> dict[str, Any]:
        # The atlas (locks, weak references) is made again where the model arrives.
        state = dict(self.__dict__)
        state.pop("_atlas", None)
        return state

    def atmosphere(self, state: StateLike, duration: float) -> Any:
        """The core field of the atlas's day tiles covering ``duration`` s from ``state``
        (negative: backwards), every altitude included."""
        return self.atlas.atmosphere(state, duration)

    def _coverage(self) -> tuple[np.datetime64, np.datetime64] | None:
        """(first, last) UTC epochs the model's drivers cover, or None (every time)."""
        return None

    def cache_key(self, start: np.datetime64, end: np.datetime64) -> Any:
        """A JSON-able description identifying the sampled values, or None (no caching)."""
        return None

    def _breaks(self, start: np.datetime64, end: np.datetime64) -> np.ndarray:
        """Epochs in (start, end) where the model's drivers change in a step."""
        return np.array([], dtype="datetime64[ns]")

    def _grid_values(
        self,
        epochs: np.ndarray,
        left: np.ndarray,
        alt: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """ln(mean) and sigma/mean on the grid (nt, nalt, nlat, nlon) from ``mean_std``."""
        mean, std = self.mean_std(
            epochs[:, None, None, None],
            lat[None, None, :, None],
            lon[None, None, None, :],
            alt[None, :, None, None],
        )
        shape = (len(epochs), len(alt), len(lat), len(lon))
        mean = np.broadcast_to(mean, shape)
        std = np.broadcast_to(std, mean.shape)
        model = type(self).__name__
        for what, bad in (
            ("a non-positive or NaN mean", ~(np.isfinite(mean) & (mean > 0))),
            (
                f"a mean above {MAX_DENSITY:g} kg/m^3 (sea level is 1.2)",
                np.isfinite(mean) & (mean > MAX_DENSITY),
            ),
            ("a negative or NaN std", ~(np.isfinite(std) & (std >= 0))),
        ):
            if bad.any():
                it, ia, jl, kl = np.unravel_index(int(np.flatnonzero(bad)[0]), shape)
                raise ValueError(
                    f"{model}.mean_std gave {what}: {mean[it, ia, jl, kl]:g} +- "
                    f"{std[it, ia, jl, kl]:g} at {epochs[it]}, altitude {alt[ia]:g} m, "
                    f"latitude {lat[jl]:g} deg, longitude {lon[kl]:g} deg"
                )
        return np.log(mean), std / mean
