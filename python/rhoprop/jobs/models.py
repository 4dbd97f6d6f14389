"""The names the commands know, in one registry: the density models of ``--model``
(``rhoprop catalog``, ``reentry``, ``screen``, and what their jobs take), the
uncertainty methods of ``--method`` and the table formats of ``--format``."""

from __future__ import annotations

from typing import Literal, cast

from ..density import DensityModel, Exponential, Msis
from ..io.tables import FORMATS as TABLE_FORMATS
from ..propagation.methods import NAMES as METHOD_NAMES
from ..propagation.methods import Method
from ..propagation.methods import from_name as _method_from_name
from ..spaceweather import SpaceWeather

#: The ``--model`` names of one model: NRLMSIS versions and the benchmark exponential.
MODEL_NAMES = ("2.1", "2.0", "00", "exponential")


def model_by_name(name: str) -> DensityModel:
    """An NRLMSIS version ("2.1", "2.0", "00") or the benchmark exponential atmosphere with
    20 % relative sigma ("exponential")."""
    if name == "exponential":
        return Exponential.benchmark(0.2)
    if name not in MODEL_NAMES:
        raise ValueError(f"unknown model {name!r}; expected one of {', '.join(MODEL_NAMES)}")
    # The last refreshed record (else the bundled one), with its predictions usable as
    # forecast drivers (uncertainty growing with lead time, PredictedDriversWarning).
    version = cast(Literal["2.1", "2.0", "00"], name)  # checked against MODEL_NAMES above
    return Msis(version, space_weather=SpaceWeather.cached().with_forecast())


#: The name of the default density-model families (``rhoprop screen``'s default).
FAMILIES = "families"
#: Every name :func:`models_by_name` takes.
SCREEN_MODEL_NAMES = (FAMILIES, *MODEL_NAMES)


def models_by_name(name: str) -> dict[str, DensityModel]:
    """{model name: model} for ``name``: :data:`FAMILIES`, the default families (NRLMSIS
    2.1, JB2008 or NRLMSISE-00, Jacchia-Roberts 1971; :func:`rhoprop.scenarios.default_models`,
    the refreshed record's predictions as forecast drivers), or one of :data:`MODEL_NAMES`
    (:func:`model_by_name`)."""
    if name == FAMILIES:
        from ..studies.scenarios import default_models

        return default_models(SpaceWeather.cached().with_forecast())
    return {name: model_by_name(name)}


def method_by_name(name: str, **settings: object) -> Method:
    """The uncertainty method called ``name`` (one of :data:`METHOD_NAMES`) with those of
    ``settings`` it has (None: its default); :func:`rhoprop.propagation.methods.from_name`."""
    return _method_from_name(name, **settings)


__all__ = [
    "FAMILIES",
    "METHOD_NAMES",
    "MODEL_NAMES",
    "SCREEN_MODEL_NAMES",
    "TABLE_FORMATS",
    "method_by_name",
    "model_by_name",
    "models_by_name",
]
