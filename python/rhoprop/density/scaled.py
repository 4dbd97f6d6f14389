"""A density model whose uncertainty is scaled: :class:`SigmaScaled`. Why: an ensemble
of several calibrated models is a linear pool, and a linear pool of calibrated forecasts
is over-dispersed (Gneiting & Ranjan 2013, "Combining predictive distributions"): the
spread-adjusted pool narrows every component by one common factor. The scaled model shares
its base model's field (no second sampling): the core atmosphere is the base's, its sigma
times the factor."""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..time import EpochsLike
from ._inputs import StateLike
from .atlas import Atlas
from .model import DensityModel, SampledModel, as_atmosphere

#: Base atmospheres (and their scaled copies) a :class:`SigmaScaled` holds at most.
HELD_FIELDS = 4


@dataclass(frozen=True)
class SigmaScaled:
    """``model`` with its standard deviation times ``factor`` (finite, >= 0; the mean
    unchanged): ``mean_std`` gives (mean, factor x std) and the core atmosphere is the
    model's with every sigma times ``factor``.

    Example:
        >>> import rhoprop as rp
        >>> base = rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=0.2)
        >>> narrow = rp.density.SigmaScaled(base, 0.5)
        >>> m, s = narrow.mean_std("2023-01-01", 0.0, 0.0, 400e3)
        >>> float(s / base.mean_std("2023-01-01", 0.0, 0.0, 400e3)[1])
        0.5
    """

    model: DensityModel
    factor: float
    #: The last few base atmospheres given out and their scaled copies, by identity:
    #: objects that share a field (a catalog's atlas hands the same one to a chunk of
    #: objects in one window) share its scaled copy, so they still run in one core call.
    _scaled: Any = field(default_factory=OrderedDict, init=False, compare=False, repr=False)
    _lock: Any = field(default_factory=threading.Lock, init=False, compare=False, repr=False)

    def __reduce__(self) -> tuple[Any, ...]:
        return (SigmaScaled, (self.model, self.factor))

    def __post_init__(self) -> None:
        if not isinstance(self.model, DensityModel):
            raise TypeError(
                f"model must be a rhoprop density model, got {type(self.model).__name__}"
            )
        factor = _validate.real("factor", self.factor)
        if not (math.isfinite(factor) and factor >= 0):
            raise ValueError(f"factor must be finite and >= 0, got {self.factor!r}")
        object.__setattr__(self, "factor", factor)

    @property
    def name(self) -> str:
        """The base model's name (its class name if it has none)."""
        return str(getattr(self.model, "name", type(self.model).__name__))

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of density, kg/m^3: the model's mean and its
        standard deviation times ``factor``."""
        mean, std = self.model.mean_std(times, lat, lon, alt)
        return mean, np.asarray(std) * self.factor

    def atmosphere(self, state: StateLike, duration: float) -> Any:
        """The model's core atmosphere over ``duration`` s from ``state``, every sigma
        times ``factor``."""
        base = as_atmosphere(self.model, state, duration)
        with self._lock:
            held = self._scaled.get(id(base))
            if held is not None and held[0] is base:
                self._scaled.move_to_end(id(base))
                return held[1]
            scaled = base.with_sigma_scale(self.factor)
            # The base is held too: its identity keys the entry, and while held the
            # atlas hands the same field to the next object of its window.
            self._scaled[id(base)] = (base, scaled)
            while len(self._scaled) > HELD_FIELDS:
                self._scaled.popitem(last=False)
        return scaled

    def served_by(self) -> Atlas | None:
        """The atlas that serves the base model (None for a model that is not sampled)."""
        if isinstance(self.model, Atlas):
            return self.model
        return self.model.served_by() if isinstance(self.model, SampledModel) else None
