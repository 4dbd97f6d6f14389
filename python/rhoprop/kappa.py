"""Processes of the normalised density offset kappa(t) (DESIGN.md section 4): the density
a member sees is rho = mean + kappa * sigma (additive) or mean * exp(kappa s - s^2/2)
(lognormal). Each member draws its own kappa path from its own random stream."""

from __future__ import annotations

from dataclasses import dataclass

from . import _validate


class KappaProcess:
    """Base of the kappa processes."""

    def _spec(self) -> tuple[str, float, float]:
        """(kind, a, b) for the core."""
        raise TypeError(f"{type(self).__name__} is not a kappa process")  # pragma: no cover

    def correlation_time(self) -> float:
        """Integral of the autocorrelation, D (s): the long-time along-track variance grows
        as 3 D T^3 (eps a_D)^2 (DESIGN.md section 4); infinite for :class:`Constant`."""
        raise TypeError(f"{type(self).__name__} is not a kappa process")  # pragma: no cover


@dataclass(frozen=True)
class White(KappaProcess):
    """i.i.d. N(0,1) drawn every ``step`` s and held over the step (the paper's
    "traditional" Monte Carlo; the integration step becomes ``step`` or a divisor)."""

    step: float = 10.0

    def __post_init__(self) -> None:
        _validate.positive("step", self.step)

    def _spec(self) -> tuple[str, float, float]:
        return ("white", float(self.step), 0.0)

    def correlation_time(self) -> float:
        return float(self.step)


@dataclass(frozen=True)
class Interpolated(KappaProcess):
    """i.i.d. N(0,1) nodes every ``interval`` s, linear in between (paper's method 1)."""

    interval: float

    def __post_init__(self) -> None:
        _validate.positive("interval", self.interval)

    def _spec(self) -> tuple[str, float, float]:
        return ("interpolated", float(self.interval), 0.0)

    def correlation_time(self) -> float:
        # The integral of kappa over a long span is the trapezoid sum of i.i.d. nodes, whose
        # variance grows as T * interval.
        return float(self.interval)


@dataclass(frozen=True)
class GaussMarkov(KappaProcess):
    """First-order Gauss-Markov with ``half_life`` s (beta = ln 2 / half_life), unit
    variance, exact discretisation at the integration step, linear between nodes (paper's
    method 2; 18 min = 1080 s is the default)."""

    half_life: float = 1080.0

    def __post_init__(self) -> None:
        _validate.positive("half_life", self.half_life)

    def _spec(self) -> tuple[str, float, float]:
        return ("gauss_markov", float(self.half_life), 0.0)

    def correlation_time(self) -> float:
        return 2.0 * self.half_life / 0.6931471805599453


@dataclass(frozen=True)
class Constant(KappaProcess):
    """One N(0,1) draw per member held for the whole run: a pure density-scale bias."""

    def _spec(self) -> tuple[str, float, float]:
        return ("constant", 0.0, 0.0)

    def correlation_time(self) -> float:
        return float("inf")


@dataclass(frozen=True)
class PiecewiseConstant(KappaProcess):
    """N(0,1) held over each ``interval`` s, AR(1) with ``correlation`` between
    consecutive intervals: the process the CCSP filter is equivalent to."""

    interval: float
    correlation: float = 0.0

    def __post_init__(self) -> None:
        _validate.positive("interval", self.interval)
        rho = _validate.real("correlation", self.correlation)
        if not -1 < rho < 1:
            raise ValueError(f"correlation must lie in (-1, 1), got {rho}")

    def _spec(self) -> tuple[str, float, float]:
        return ("piecewise_constant", float(self.interval), float(self.correlation))

    def correlation_time(self) -> float:
        return self.interval * (1 + self.correlation) / (1 - self.correlation)


__all__ = ["Constant", "GaussMarkov", "Interpolated", "KappaProcess", "PiecewiseConstant", "White"]
