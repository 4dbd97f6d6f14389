"""The settings records of the screening functions, checked when made: :class:`Search`
(how finely a window is searched and which objects are in it) and :class:`PcSettings`
(the probability of collision of each event of ``screen_all``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .. import _validate
from ..catalog.run import MAX_SPAN
from .approach import DEFAULT_FINE_STEP

__all__ = ["DEFAULT_GRID_STEP", "PcSettings", "Search"]

#: Spacing of the coarse common grid of a screening, s.
DEFAULT_GRID_STEP = 60.0


@dataclass(frozen=True)
class Search:
    """How a screening searches its window.

    Attributes:
        grid_step: spacing of the coarse common grid, s (> 0; at most 1/20 of an
            object's period, and at most 300 s in ``screen_all``).
        fine_step: output step of the refinement around each candidate, s (> 0).
        max_span: an object whose epoch lies more than this (s) before ``start`` or
            after ``end`` is not screened and is listed in ``skipped`` (default
            :data:`~rhoprop.catalog.run.MAX_SPAN`, 60 days: a propagation holds the
            density tiles of every day it flies through); None: no limit.

    Example:
        >>> import rhoprop as rp
        >>> rp.conjunction.Search(grid_step=30.0).fine_step
        1.0
    """

    grid_step: float = DEFAULT_GRID_STEP
    fine_step: float = DEFAULT_FINE_STEP
    max_span: float | None = MAX_SPAN

    def __post_init__(self) -> None:
        object.__setattr__(self, "grid_step", _validate.positive("grid_step", self.grid_step))
        object.__setattr__(self, "fine_step", _validate.positive("fine_step", self.fine_step))
        if self.max_span is not None:
            object.__setattr__(self, "max_span", _validate.positive("max_span", self.max_span))


@dataclass(frozen=True)
class PcSettings:
    """The probability of collision of each event of
    :func:`~rhoprop.conjunction.screen_all` (``pc=PcSettings(...)``; ``pc=True`` is
    ``PcSettings()``).

    Attributes:
        weights: mixture weights {model name: weight}; None (default): as
            ``rp.ensemble``'s (the calibrated weights and spread when every model is a
            calibrated family, else equal weights and each model's own sigma).
        hard_body_radius: m, for every event (None: the sum of both objects' radii from
            ``radii``, else the rule of :data:`~rhoprop.conjunction.event_pc.RADII` by
            object kind).
        radii: {NORAD id: radius m} of objects whose size is known.
        monte_carlo_events: also give the events of largest mixture Pc, this many, the
            member Monte Carlo's Pc (default 0: none).
        members: members per object and model of that Monte Carlo (>= 2).
        seed: its seed (object i seeded ``seed + i``).

    Example:
        >>> import rhoprop as rp
        >>> rp.conjunction.PcSettings(hard_body_radius=20.0).members
        200
    """

    weights: Mapping[str, float] | None = None
    hard_body_radius: float | None = None
    radii: Mapping[int, float] | None = None
    monte_carlo_events: int = 0
    members: int = 200
    seed: int = 0

    def __post_init__(self) -> None:
        if self.weights is not None and not isinstance(self.weights, Mapping):
            raise TypeError(
                f"weights must be a mapping {{model name: weight}}, got "
                f"{type(self.weights).__name__}"
            )
        hbr = self.hard_body_radius
        if hbr is not None and not (_validate.is_real(hbr) and np.isfinite(hbr) and hbr > 0):
            raise ValueError(f"hard_body_radius must be a number > 0 m, got {hbr!r}")
        if self.radii is not None and not isinstance(self.radii, Mapping):
            raise TypeError(
                f"radii must be a mapping {{NORAD id: m}}, got {type(self.radii).__name__}"
            )
        for key, r in (self.radii or {}).items():
            if not (_validate.is_real(r) and np.isfinite(r) and r > 0):
                raise ValueError(f"radii[{key!r}] must be > 0 m, got {r!r}")
        object.__setattr__(
            self,
            "monte_carlo_events",
            _validate.count("monte_carlo_events", self.monte_carlo_events, minimum=0),
        )
        object.__setattr__(self, "members", _validate.count("members", self.members, minimum=2))
        object.__setattr__(self, "seed", _validate.seed(self.seed, limit=2**63))
