"""A density model given as a Python function: the route for a user's own model (e.g. a
machine-learned local model such as CHAMP-ML-DP or MSIS-UQ-DP in the paper's section 2)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

from ..time import EpochsLike
from ._inputs import broadcast_inputs
from .field import FieldResolution, resolution_arg
from .model import SampledModel


class FromFunction(SampledModel):
    """Wraps ``fn(times, lat, lon, alt) -> (mean, std)`` as a density model.

    ``fn`` receives the inputs of :meth:`mean_std` already checked and broadcast to one
    shape: UTC ``datetime64[ns]`` times, geodetic latitude and longitude (deg) and geodetic
    altitude (m, WGS-84) as float arrays. It returns a tuple (mean, std) of density in
    kg/m^3 whose shapes equal (or broadcast to) that shape, with mean finite and > 0 and
    std finite and >= 0. The propagator samples the function into a field (see
    :meth:`~rhoprop.density.base.SampledModel.field`), so it is called on whole grids, a
    few times per propagation, never inside the integrator.

    Args:
        fn: the callable.
        name: a label for ``repr`` and error messages (default: ``fn.__name__``).
        cache_key: a string identifying the function's values (e.g. "my-net v3,
            weights sha256 ..."); it enables the on-disk field cache, so it must change
            whenever the function's output changes. None (default): no caching.
        resolution: grid spacing of the field the propagators sample the function into
            (:class:`~rhoprop.density.FieldResolution`; None: its defaults). A function
            with sharp features may need a finer grid.

    Example:
        >>> import numpy as np
        >>> m = FromFunction(lambda t, la, lo, h: (1e-12 * np.exp(-(h - 4e5) / 6e4),
        ...                                        1e-13 * np.exp(-(h - 4e5) / 6e4)),
        ...                  name="exp")
        >>> m
        FromFunction(name='exp')
        >>> float(m.mean_std("2002-09-07T01:00", 0.0, 0.0, 400e3)[0])
        1e-12
    """

    def __init__(
        self,
        fn: Callable[..., Any],
        *,
        name: str | None = None,
        cache_key: str | None = None,
        resolution: FieldResolution | None = None,
    ) -> None:
        if not callable(fn):
            raise TypeError(f"fn must be callable, got {type(fn).__name__}")
        if name is not None and not isinstance(name, str):
            raise TypeError(f"name must be a string or None, got {type(name).__name__}")
        if cache_key is not None and not isinstance(cache_key, str):
            raise TypeError(f"cache_key must be a string or None, got {type(cache_key).__name__}")
        self.fn = fn
        self.name = name if name is not None else getattr(fn, "__name__", type(fn).__name__)
        self._key = cache_key
        self.resolution = resolution_arg(resolution)

    def __repr__(self) -> str:
        return f"FromFunction(name={self.name!r})"

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of density, kg/m^3, from ``fn`` at UTC ``times``,
        geodetic ``lat``/``lon`` (deg) and ``alt`` (m), broadcast together.

        Raises:
            TypeError: ``fn`` did not return a (mean, std) tuple of numbers.
            ValueError: a returned array has a shape that does not broadcast to the inputs'
                shape, or a mean that is not finite and > 0 or a std that is not finite
                and >= 0 (the message gives the value, its index and the input point).
        """
        t, la, lo, al = broadcast_inputs(times, lat, lon, alt)
        shape = la.shape
        out = self.fn(t, la, lo, al)
        if not isinstance(out, tuple) or len(out) != 2:
            got = (
                f"a tuple of {len(out)} items"
                if isinstance(out, tuple)
                else f"a {type(out).__name__}"
            )
            raise TypeError(
                f"{self!r}: fn must return a tuple (mean, std) of arrays in kg/m^3, got {got}"
            )
        arrays = []
        for what, value in zip(("mean", "std"), out, strict=True):
            if np.iscomplexobj(value):
                raise TypeError(f"{self!r}: fn returned a complex {what}; it must be real (kg/m^3)")
            try:
                a = np.asarray(value, dtype=float)
            except (TypeError, ValueError) as err:
                raise TypeError(
                    f"{self!r}: fn returned a {what} that is not numeric "
                    f"({type(value).__name__}): {err}"
                ) from err
            try:
                a = np.broadcast_to(a, shape)
            except ValueError:
                raise ValueError(
                    f"{self!r}: fn returned {what} of shape {a.shape} for inputs of shape "
                    f"{shape} (it must equal or broadcast to the inputs' shape)"
                ) from None
            arrays.append(np.array(a))
        mean, std = arrays
        for what, a, bad, rule in (
            ("mean", mean, ~(np.isfinite(mean) & (mean > 0)), "finite and > 0"),
            ("std", std, ~(np.isfinite(std) & (std >= 0)), "finite and >= 0"),
        ):
            if bad.any():
                index = np.unravel_index(int(np.flatnonzero(bad)[0]), shape)
                where = ", ".join(str(int(i)) for i in index)
                raise ValueError(
                    f"{self!r}: fn returned {what} = {float(a[index])!r} kg/m^3 at index ({where}) "
                    f"(time {t[index]}, lat {la[index]:g} deg, lon {lo[index]:g} deg, "
                    f"alt {al[index]:g} m); it must be {rule} "
                    f"({int(bad.sum())} bad value(s) of {bad.size})"
                )
        return mean, std

    def cache_key(self, start: np.datetime64, end: np.datetime64) -> Any:
        """The user's ``cache_key`` string (None: the field is not cached)."""
        return self._key
