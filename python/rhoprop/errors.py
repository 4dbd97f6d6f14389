"""The whole exception tree of rhoprop. Every rhoprop error is a :class:`RhopropError`,
itself a ``ValueError``, so ``except ValueError`` catches bad input. Each error of the Rust
core has its own class here, raised by the extension with the values as attributes (so no
caller ever parses a message).

::

    ValueError
    └── RhopropError
        ├── NonFiniteError       an input is NaN or infinite (core): .name, .value
        ├── InvalidValueError    an input is out of its range (core): .name, .value, .reason
        ├── RejectedInputError   an input is wrong as a whole (core): .name, .reason
        ├── UnknownNameError     not one of the known names (core): .what, .name, .expected
        ├── ShapeError           an array of the wrong shape (core): .name, .reason
        ├── DensityFieldError    a lookup outside a density field (core): .axis, .value,
        │                        .min, .max, .time
        ├── CovarianceError      a CCSP covariance that is not positive definite (core):
        │                        .time, .min_eigenvalue
        ├── IntegrationError     the integrator could not complete (core)
        │   ├── StepUnderflowError   .time, .step
        │   └── TooManyStepsError    .max_steps, .time, .end
        ├── OutsideRecordError   a lookup outside a data record (space weather, PcaRom)
        ├── DecayError           the object decayed where a result needs it in orbit
        └── ScenarioError        an invalid scenario file

    RuntimeWarning
    ├── CacheWarning             the disk cache could not be used (the result is kept)
    └── PredictedDriversWarning  predicted (not observed) space weather is in use

The core's attributes are None on an instance made by Python code (a message only).
"""

from __future__ import annotations


class RhopropError(ValueError):
    """Base of all rhoprop errors (a ValueError)."""


class NonFiniteError(RhopropError):
    """An input value is NaN or infinite. ``name``: which; ``value``: the value."""

    name: str | None = None
    value: float | None = None


class InvalidValueError(RhopropError):
    """An input value is outside its valid range. ``name``, ``value`` and ``reason``."""

    name: str | None = None
    value: float | None = None
    reason: str | None = None


class RejectedInputError(RhopropError):
    """An input is wrong as a whole (no one value to quote). ``name`` and ``reason``."""

    name: str | None = None
    reason: str | None = None


class UnknownNameError(RhopropError):
    """A name that is not one of the known choices. ``what`` (the kind of name),
    ``name`` and ``expected`` (tuple of the known names)."""

    what: str | None = None
    name: str | None = None
    expected: tuple[str, ...] | None = None


class ShapeError(RhopropError):
    """An array has the wrong length or shape. ``name`` and ``reason``."""

    name: str | None = None
    reason: str | None = None


class DensityFieldError(RhopropError):
    """A density lookup fell outside a field: ``axis`` (e.g. "altitude (m)"), ``value``,
    the covered range ``min``..``max`` (the axis's units) and ``time`` (s from the run's
    epoch)."""

    axis: str | None = None
    value: float | None = None
    min: float | None = None
    max: float | None = None
    time: float | None = None


class CovarianceError(RhopropError):
    """A CCSP covariance stopped being positive definite (near decay, or an initial
    covariance that is not one): ``time`` (s from the run's epoch; 0 for the initial one)
    and ``min_eigenvalue`` (of the matrix that failed, in its units)."""

    time: float | None = None
    min_eigenvalue: float | None = None


class IntegrationError(RhopropError):
    """The integrator could not complete (step underflow, too many steps)."""


class StepUnderflowError(IntegrationError):
    """The adaptive step fell below its floor: ``time`` (s) and ``step`` (s)."""

    time: float | None = None
    step: float | None = None


class TooManyStepsError(IntegrationError):
    """More than ``max_steps`` steps before ``time`` (s) of a run to ``end`` (s)."""

    max_steps: int | None = None
    time: float | None = None
    end: float | None = None


class OutsideRecordError(RhopropError):
    """A lookup fell outside a data record: an epoch outside the space-weather record (or
    on days whose values are missing), or a point outside a PCA ROM's epochs, latitudes
    or altitudes. The message names the value and the range the record covers."""


class DecayError(RhopropError):
    """The object decayed (fell below the floor altitude) before an epoch where a result
    needs it in orbit; the message gives the decay epoch."""


class ScenarioError(RhopropError):
    """A scenario file is invalid; the message names the key."""


class CacheWarning(RuntimeWarning):
    """The on-disk cache could not be read or written (corrupt entry, unwritable or
    vanished directory); the value was computed and is used from memory."""


class PredictedDriversWarning(RuntimeWarning):
    """Space-weather drivers after the last observed day are predictions (a forecast
    record, :meth:`~rhoprop.SpaceWeather.with_forecast`); the message gives the lead time
    and how to refresh the record (``rhoprop data refresh``)."""


__all__ = [
    "CacheWarning",
    "CovarianceError",
    "DecayError",
    "DensityFieldError",
    "IntegrationError",
    "InvalidValueError",
    "NonFiniteError",
    "OutsideRecordError",
    "PredictedDriversWarning",
    "RejectedInputError",
    "RhopropError",
    "ScenarioError",
    "ShapeError",
    "StepUnderflowError",
    "TooManyStepsError",
    "UnknownNameError",
]
