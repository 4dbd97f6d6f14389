"""Correction of a density model's mean calibrated on observed densities: a scale and a
dependence on how far the daily F10.7 runs from its 81-day mean (docs/density-calibration.md)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _validate


@dataclass(frozen=True)
class MeanCorrection:
    """The model's density is multiplied by ``scale * (F10.7 / F10.7a) ** f107_exponent``,
    with the model's own daily F10.7 and its 81-day mean (sfu). ``MeanCorrection()`` is no
    correction."""

    scale: float = 1.0
    f107_exponent: float = 0.0

    def __post_init__(self) -> None:
        scale = _validate.real("scale", self.scale)
        if not 0.1 <= scale <= 10.0:
            raise ValueError(f"scale must lie in [0.1, 10], got {scale}")
        exponent = _validate.real("f107_exponent", self.f107_exponent)
        if abs(exponent) > 5.0:
            raise ValueError(f"f107_exponent must lie in [-5, 5], got {exponent}")

    @property
    def is_identity(self) -> bool:
        """True when the correction changes nothing."""
        return self.scale == 1.0 and self.f107_exponent == 0.0

    def factor(self, f107: np.ndarray, f107a: np.ndarray) -> np.ndarray:
        """The factor at daily F10.7 ``f107`` and its 81-day mean ``f107a`` (sfu)."""
        f, fa = np.asarray(f107, dtype=float), np.asarray(f107a, dtype=float)
        if self.f107_exponent == 0.0:
            return np.full(np.broadcast(f, fa).shape, self.scale)
        out: np.ndarray = self.scale * (f / fa) ** self.f107_exponent
        return out
