"""Processes of the normalised density offset kappa(t) (docs/conventions.md, "The kappa
processes"): the density a member sees is rho = mean + kappa * sigma (additive) or
mean * exp(kappa s - s^2/2) (lognormal). Each member draws its own kappa path from its own
random stream."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import ClassVar

from .. import _validate
from ..density import calibrated as _CAL


class KappaProcess:
    """Base of the kappa processes. Each process is a frozen dataclass whose fields are
    its parameters (s, or dimensionless for a correlation); ``kind`` is the name the core
    and scenario files know it by (one of ``rhoprop._core.KAPPA_KINDS``)."""

    kind: ClassVar[str] = ""

    def _spec(self) -> tuple[str, list[float]]:
        """(kind, parameters) for the core: the kind and its parameters in field order."""
        values = [float(getattr(self, f.name)) for f in fields(self)]  # type: ignore[arg-type]
        return (self.kind, values)

    def correlation_time(self) -> float:
        """Integral of the autocorrelation, D (s): the long-time along-track variance grows
        as 3 D T^3 (eps a_D)^2 (docs/conventions.md, "The kappa processes"); infinite for
        :class:`Constant`."""
        raise TypeError(f"{type(self).__name__} is not a kappa process")  # pragma: no cover

    def node_spacing(self) -> float | None:
        """Spacing of the process's own nodes, s, which the integration step must divide;
        None when there are none after t = 0 (Constant)."""
        return None


@dataclass(frozen=True)
class White(KappaProcess):
    """i.i.d. N(0,1) drawn every ``step`` s and held over the step (the paper's
    "traditional" Monte Carlo; the integration step becomes ``step`` or a divisor)."""

    kind: ClassVar[str] = "white"

    step: float = 10.0

    def __post_init__(self) -> None:
        _validate.positive("step", self.step)

    def node_spacing(self) -> float:
        return float(self.step)

    def correlation_time(self) -> float:
        return float(self.step)


@dataclass(frozen=True)
class Interpolated(KappaProcess):
    """i.i.d. N(0,1) nodes every ``interval`` s, linear in between (paper's method 1)."""

    kind: ClassVar[str] = "interpolated"

    interval: float

    def __post_init__(self) -> None:
        _validate.positive("interval", self.interval)

    def node_spacing(self) -> float:
        return float(self.interval)

    def correlation_time(self) -> float:
        # The integral of kappa over a long span is the trapezoid sum of i.i.d. nodes, whose
        # variance grows as T * interval.
        return float(self.interval)


@dataclass(frozen=True)
class GaussMarkov(KappaProcess):
    """First-order Gauss-Markov with ``half_life`` s (beta = ln 2 / half_life), unit
    variance, exact discretisation on nodes every ``interval`` s, linear between them
    (paper's method 2; 18 min = 1080 s is the default).

    The nodes are the process's own (default ``interval``: ``min(180 s, half_life / 6)``,
    180 s for the default), so a member's path depends on its seed and the time only, not
    on the integrator: the integration step becomes the largest one <= the integrator's
    that divides ``interval`` (RK8's 180 s stays, ABM's 80 s becomes 60 s). Until 0.1 the
    nodes were the integration steps, and RK4, RK8 and ABM gave different paths for one
    seed (3.1 km apart after 3 days)."""

    kind: ClassVar[str] = "gauss_markov"

    half_life: float = 1080.0
    interval: float | None = None

    def __post_init__(self) -> None:
        half_life = _validate.positive("half_life", self.half_life)
        interval = min(180.0, half_life / 6.0) if self.interval is None else self.interval
        object.__setattr__(self, "interval", _validate.positive("interval", interval))

    def node_spacing(self) -> float:
        return float(self.interval)  # type: ignore[arg-type]

    def correlation_time(self) -> float:
        # The integral of kappa over a long span is the trapezoid sum of AR(1) nodes with
        # lag-one correlation a = exp(-beta d): variance T d (1 + a) / (1 - a), which tends
        # to 2 / beta = 2 half_life / ln 2 as d -> 0 (3119 s against 3116 s at 18 min/180 s).
        d = float(self.interval)  # type: ignore[arg-type]
        # 1 - a through expm1: it cancels to 0 for half-lives far beyond the interval.
        one_minus_a = -math.expm1(-math.log(2.0) / self.half_life * d)
        if one_minus_a == 0.0:
            return math.inf
        return d * (2.0 - one_minus_a) / one_minus_a


@dataclass(frozen=True)
class Constant(KappaProcess):
    """One N(0,1) draw per member held for the whole run: a pure density-scale bias."""

    kind: ClassVar[str] = "constant"

    def correlation_time(self) -> float:
        return float("inf")


@dataclass(frozen=True)
class PiecewiseConstant(KappaProcess):
    """N(0,1) held over each ``interval`` s, AR(1) with ``correlation`` between
    consecutive intervals: the process the CCSP filter is equivalent to."""

    kind: ClassVar[str] = "piecewise_constant"

    interval: float
    correlation: float = 0.0

    def __post_init__(self) -> None:
        _validate.positive("interval", self.interval)
        rho = _validate.real("correlation", self.correlation)
        if not -1 < rho < 1:
            raise ValueError(f"correlation must lie in (-1, 1), got {rho}")

    def node_spacing(self) -> float:
        return float(self.interval)

    def correlation_time(self) -> float:
        return self.interval * (1 + self.correlation) / (1 - self.correlation)


@dataclass(frozen=True)
class TwoScale(KappaProcess):
    """Sum of two independent unit Gauss-Markov terms, sqrt(1 - w) f + sqrt(w) s: f with
    ``half_life`` s, s with ``slow_half_life`` s, w = ``slow_fraction``; exact
    discretisation on nodes every ``interval`` s (default ``min(180 s, half_life / 6)``),
    linear between them. Unit variance, correlation (1 - w) 2^(-lag / half_life) +
    w 2^(-lag / slow_half_life).

    The default is the process calibrated on observed orbit-averaged densities of CHAMP
    and GRACE-FO in 34 storms (docs/density-calibration.md,
    ``benches/density_calibration.py``): model errors that decorrelate within hours in
    part and persist through a storm window in part, where the paper's 18-minute process
    decorrelated within an orbit. It is the Monte Carlo's default; the paper study keeps
    ``GaussMarkov(1080)``."""

    kind: ClassVar[str] = "two_scale"

    half_life: float = _CAL.KAPPA_HALF_LIFE
    slow_half_life: float = _CAL.KAPPA_SLOW_HALF_LIFE
    slow_fraction: float = _CAL.KAPPA_SLOW_FRACTION
    interval: float | None = None

    def __post_init__(self) -> None:
        half_life = _validate.positive("half_life", self.half_life)
        _validate.positive("slow_half_life", self.slow_half_life)
        w = _validate.real("slow_fraction", self.slow_fraction)
        if not 0 <= w <= 1:
            raise ValueError(f"slow_fraction must lie in [0, 1], got {w}")
        interval = min(180.0, half_life / 6.0) if self.interval is None else self.interval
        object.__setattr__(self, "interval", _validate.positive("interval", interval))

    def node_spacing(self) -> float:
        return float(self.interval)  # type: ignore[arg-type]

    def correlation_time(self) -> float:
        w = self.slow_fraction
        fast = GaussMarkov(self.half_life, self.interval).correlation_time()
        slow = GaussMarkov(self.slow_half_life, self.interval).correlation_time()
        return (1 - w) * fast + w * slow

    def correlation(self, lag: float) -> float:
        """Correlation of kappa at a lag of ``lag`` s (of the continuous process)."""
        w = self.slow_fraction
        return float(
            (1 - w) * 2.0 ** (-abs(lag) / self.half_life)
            + w * 2.0 ** (-abs(lag) / self.slow_half_life)
        )


#: The processes by kind name.
KINDS: dict[str, type[KappaProcess]] = {
    cls.kind: cls
    for cls in (White, Interpolated, GaussMarkov, Constant, PiecewiseConstant, TwoScale)
}

__all__ = [
    "KINDS",
    "Constant",
    "GaussMarkov",
    "Interpolated",
    "KappaProcess",
    "PiecewiseConstant",
    "TwoScale",
    "White",
]
