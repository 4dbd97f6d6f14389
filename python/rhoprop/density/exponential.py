"""The exponential atmosphere, as a stochastic density model."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from .. import _core, _validate
from ..constants import R_EARTH
from ..time import EpochsLike
from ._inputs import StateLike, broadcast_inputs


class Exponential:
    """rho = rho0 * exp(-(h - h0) / H) with h = |r| - Re the spherical altitude, and
    standard deviation ``rel_sigma * rho``. A standard analytic benchmark atmosphere.

    Args:
        rho0: density at ``h0``, kg/m^3 (> 0).
        h0: reference altitude, m.
        scale_height: H, m (> 0).
        rel_sigma: relative 1-sigma uncertainty (>= 0, dimensionless).

    Example:
        >>> Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=0.2).scale_height
        58515.0
    """

    def __init__(self, rho0: float, h0: float, scale_height: float, rel_sigma: float = 0.0) -> None:
        self.rho0 = _validate.positive("rho0", rho0)
        self.h0 = _validate.real("h0", h0)
        self.scale_height = _validate.positive("scale_height", scale_height)
        self.rel_sigma = _validate.real("rel_sigma", rel_sigma)
        if self.rel_sigma < 0:
            raise ValueError(f"rel_sigma must be >= 0, got {self.rel_sigma}")
        self._core = _core.ExponentialAtmosphere(rho0, h0, scale_height, rel_sigma)

    @classmethod
    def benchmark(cls, rel_sigma: float = 0.0) -> Exponential:
        """The analytic benchmark atmosphere: rho = 3.725e-12 kg/m^3 at 400 km, scale height
        58.515 km, with ``rel_sigma`` relative 1-sigma uncertainty."""
        return cls(3.725e-12, 400e3, 58.515e3, rel_sigma=rel_sigma)

    def __reduce__(self) -> tuple[Any, ...]:
        # The core object does not pickle; the parameters rebuild it (e.g. on Dask workers).
        return (Exponential, (self.rho0, self.h0, self.scale_height, self.rel_sigma))

    def __repr__(self) -> str:
        return (
            f"Exponential(rho0={self.rho0!r}, h0={self.h0!r}, "
            f"scale_height={self.scale_height!r}, rel_sigma={self.rel_sigma!r})"
        )

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of density (kg/m^3) at UTC ``times`` and geodetic
        ``lat``/``lon`` (deg) and ``alt`` (m, WGS-84), broadcast together. The model uses
        the spherical altitude |r| - Re of that point."""
        _, la, lo, al = broadcast_inputs(times, lat, lon, alt)
        lla = np.stack([la.ravel(), lo.ravel(), al.ravel()], axis=1)
        r = np.linalg.norm(_core.geodetic_to_fixed(lla), axis=1).reshape(la.shape)
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):  # checked below
            mean = self.rho0 * np.exp(-(r - R_EARTH - self.h0) / self.scale_height)
            std = self.rel_sigma * mean
        bad = ~(np.isfinite(mean) & np.isfinite(std))
        if bad.any():
            h = float(np.broadcast_to(r - R_EARTH, bad.shape)[bad].flat[0])
            raise ValueError(
                f"{self!r} overflows at spherical altitude {h:g} m (density or its sigma "
                "beyond the float range)"
            )
        return mean, std

    def atmosphere(self, state: StateLike, duration: float) -> Any:
        """The analytic core atmosphere (valid at every time and place)."""
        return self._core
