"""The names the commands know, in one registry: the density models of ``--model``
(``rhoprop catalog``, ``reentry``, ``screen``, and what their jobs take), the
uncertainty methods of ``--method`` and the table formats of ``--format``."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal, cast

import numpy as np

from ..density import DensityModel, Exponential, Msis
from ..io.tables import FORMATS as TABLE_FORMATS
from ..propagation.methods import NAMES as METHOD_NAMES
from ..propagation.methods import Method
from ..propagation.methods import from_name as _method_from_name
from ..spaceweather import SpaceWeather
from ..time import EpochLike, to_datetime64

#: The ``--model`` names of one model: NRLMSIS versions and the benchmark exponential.
MODEL_NAMES = ("2.1", "2.0", "00", "exponential")


def as_of_text(text: str) -> str:
    """``text`` checked as the UTC ISO epoch of ``--as-of`` (a ValueError saying what it
    should look like otherwise), before a job starts."""
    to_datetime64(text, "epoch")
    return text


def as_of_note(epochs: Sequence[np.datetime64], as_of: str | None) -> str | None:
    """A note (for stderr) when element sets of ``epochs`` are newer than ``as_of``: a
    forecaster then had neither them nor the space weather of their days (the run goes
    on: the days after ``as_of`` take its forecast). None when none is, or no ``as_of``."""
    if as_of is None or not len(epochs):
        return None
    limit = to_datetime64(as_of, "--as-of")
    newer = [e for e in epochs if e > limit]
    if not newer:
        return None
    newest = np.datetime_as_string(max(newer), unit="m")
    return (
        f"note: {len(newer)} of {len(epochs)} element sets are newer than --as-of {as_of} "
        f"(the newest {newest}Z): a forecaster then had neither them nor the space weather "
        "of their days, which take the as-of record's forecast"
    )


def record_as_of(as_of: EpochLike | None = None) -> SpaceWeather:
    """The space weather of the commands: the last refreshed record (else the bundled
    one) with its predictions usable as forecast drivers (uncertainty growing with lead
    time, PredictedDriversWarning); with ``as_of`` (UTC) the record as a forecaster had
    it then (:meth:`~rhoprop.SpaceWeather.as_of`: observed before it, the library's
    forecast after), to run a past epoch as it could have been run."""
    record = SpaceWeather.cached()
    return record.with_forecast() if as_of is None else record.as_of(as_of)


def model_by_name(name: str, as_of: EpochLike | None = None) -> DensityModel:
    """An NRLMSIS version ("2.1", "2.0", "00") on :func:`record_as_of`'s space weather or
    the benchmark exponential atmosphere with 20 % relative sigma ("exponential", which
    reads none: ``as_of`` is then a ValueError)."""
    if name == "exponential":
        if as_of is not None:
            raise ValueError(
                "--as-of applies to the NRLMSIS models; 'exponential' reads no space weather"
            )
        return Exponential.benchmark(0.2)
    if name not in MODEL_NAMES:
        raise ValueError(f"unknown model {name!r}; expected one of {', '.join(MODEL_NAMES)}")
    version = cast(Literal["2.1", "2.0", "00"], name)  # checked against MODEL_NAMES above
    return Msis(version, space_weather=record_as_of(as_of))


#: The name of the default density-model families (``rhoprop screen``'s default).
FAMILIES = "families"
#: Every name :func:`models_by_name` takes.
SCREEN_MODEL_NAMES = (FAMILIES, *MODEL_NAMES)


def models_by_name(name: str, as_of: EpochLike | None = None) -> dict[str, DensityModel]:
    """{model name: model} for ``name``: :data:`FAMILIES`, the default families (NRLMSIS
    2.1, JB2008 or NRLMSISE-00, Jacchia-Roberts 1971; :func:`rhoprop.scenarios.default_models`
    on :func:`record_as_of`'s space weather, JB2008's indices as of ``as_of`` too), or one
    of :data:`MODEL_NAMES` (:func:`model_by_name`)."""
    if name == FAMILIES:
        from ..studies.scenarios import default_models

        if as_of is None:
            return default_models(record_as_of())
        return default_models(SpaceWeather.cached(), as_of=as_of)
    return {name: model_by_name(name, as_of)}


def method_by_name(name: str, **settings: object) -> Method:
    """The uncertainty method called ``name`` (one of :data:`METHOD_NAMES`) with those of
    ``settings`` it has (None: its default); :func:`rhoprop.propagation.methods.from_name`."""
    return _method_from_name(name, **settings)


def method_takes(name: str, setting: str) -> bool:
    """Whether the uncertainty method called ``name`` has the setting ``setting`` (a
    field of its class: ``n``, ``seed``, ``update_interval``, ...)."""
    import dataclasses

    return setting in {f.name for f in dataclasses.fields(type(method_by_name(name)))}


__all__ = [
    "FAMILIES",
    "METHOD_NAMES",
    "MODEL_NAMES",
    "SCREEN_MODEL_NAMES",
    "TABLE_FORMATS",
    "as_of_note",
    "as_of_text",
    "method_by_name",
    "method_takes",
    "model_by_name",
    "models_by_name",
    "record_as_of",
]
