"""The whole exception tree of rhoprop. Every rhoprop error is a :class:`RhopropError`,
itself a ``ValueError``, so ``except ValueError`` catches bad input; the core's errors
are raised by the extension as these same classes."""

from __future__ import annotations

from ._core import DensityFieldError, IntegrationError, RhopropError


class ScenarioError(RhopropError):
    """A scenario file is invalid; the message names the key."""


__all__ = ["DensityFieldError", "IntegrationError", "RhopropError", "ScenarioError"]
