"""The whole exception tree of rhoprop. Every rhoprop error is a :class:`RhopropError`,
itself a ``ValueError``, so ``except ValueError`` catches bad input; the core's errors
are raised by the extension as these same classes.

::

    ValueError
    └── RhopropError
        ├── DensityFieldError    a lookup outside a sampled density field (core)
        ├── IntegrationError     the integrator could not complete (core)
        ├── OutsideRecordError   a lookup outside a data record (space weather, PcaRom)
        ├── DecayError           the object decayed where a result needs it in orbit
        └── ScenarioError        an invalid scenario file

    RuntimeWarning
    ├── CacheWarning             the disk cache could not be used (the result is kept)
    └── PredictedDriversWarning  predicted (not observed) space weather is in use
"""

from __future__ import annotations

from ._core import DensityFieldError, IntegrationError, RhopropError


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
    "DecayError",
    "DensityFieldError",
    "IntegrationError",
    "OutsideRecordError",
    "PredictedDriversWarning",
    "RhopropError",
    "ScenarioError",
]
