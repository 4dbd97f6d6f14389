"""The density atlas: a sampled model served as tiles of one UTC day on one altitude grid.

Every sampled model (NRLMSIS, JB2008, Jacchia-Roberts, a ROM, a user function) reaches the
core through its :class:`Atlas`. A tile is the model sampled over one UTC day (00:00 to
00:00, so every run, object and process shares it) on the model's whole altitude grid,
from its lowest altitude (:attr:`SampledModel.lowest_altitude`: 0 km for NRLMSIS, 90 km
for JB2008 and Jacchia-Roberts, below any decay floor) up to the ceiling
(:data:`DEFAULT_CEILING`, 1,500 km). A run gets a core field made of the tiles of the days
it flies through (shared, not copied), so its cost does not depend on the other objects of
a catalog, their epochs or their orbits.

* Above the ceiling the core continues ln(mean) along the top cell's slope (an exponential
  with the local scale height of the top levels) and holds sigma/mean: continuous, and
  drag is negligible there. HEO and GEO objects need no taller grid.
* Below the lowest altitude the core holds the bottom level's values. Only an integrator
  stage of a step that crosses the decay floor (default 120 km) goes there, and such a step
  is cut at the crossing, so those values never enter a result; a run whose floor is below
  the model's lowest altitude is refused (:func:`~rhoprop.propagation.propagate.run_in_field`).
* A time outside the model's drivers (:meth:`SampledModel._coverage`) is an
  :class:`~rhoprop.OutsideRecordError` naming the span; tiles at the ends of the drivers
  are cut to them.

Tiles are sampled on demand in bounded chunks (:data:`SAMPLE_POINTS` grid points per model
call, so sampling a day stays near 100 MB whatever the resolution), stored on disk one file
per tile (``<cache>/tiles/<model>/<day>_<key>.npz``, keyed by the model's description and
drivers, the resolution and the grid; see :mod:`rhoprop.cache`) and kept in memory under a
budget (``$RHOPROP_FIELD_MEMORY`` bytes, default 1 GB; :func:`set_memory_budget`), least
recently used first. A tile in use by a running propagation stays alive beyond the budget
until that run ends; :func:`field_memory` reports the peak. Results do not depend on the
budget, the thread count or the order tiles were made in: a tile's values depend on its
day alone, and its time nodes are absolute (UT1 seconds since J2000, UT1 = UTC as
everywhere in the core), so a lookup reads the same numbers in every field that holds it.

An :class:`Atlas` pickles as its model and resolution (Dask workers get a reference, not
arrays) and each worker reads tiles from its cache directory (set ``$RHOPROP_CACHE`` to a
shared directory for a cluster) or samples them itself: the same bits either way.
"""

from __future__ import annotations

import collections
import hashlib
import json
import os
import secrets
import threading
import weakref
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import _core
from ..cache import (
    FIELD_MEMORY_ENV,
    bytes_from_env,
    cache_dir,
    entry_lock,
    load_entry,
    store_entry,
)
from ..errors import OutsideRecordError
from ..progress import ProgressBar
from ..time import EpochLike, EpochsLike, add_seconds, to_datetime64, ut1_seconds
from ._inputs import StateLike
from .field import (
    MAX_GRID_BYTES,
    FieldResolution,
    _entry_matches,
    check_grid_size,
    sample_grid,
    time_nodes,
)
from .field import (
    SAMPLE_POINTS as SAMPLE_POINTS,
)

#: Top of every atlas grid, m (above it: the exponential extrapolation of the module doc).
#: 1,500 km holds every LEO orbit's density with its own shape; higher, drag on any object
#: is below 1e-6 of its value at 500 km.
DEFAULT_CEILING = 1_500e3
#: Length of a tile: one UTC day.
TILE_DAY = np.timedelta64(1, "D")
#: Environment variable of the in-memory tile budget, bytes.
MEMORY_ENV = FIELD_MEMORY_ENV
#: Default in-memory tile budget, bytes (1 GB: about 40 days of NRLMSIS at the default
#: resolution).
DEFAULT_MEMORY = 1_000_000_000
#: Largest tile, bytes (the limit of every sampled grid, ``field.MAX_GRID_BYTES``); tiles
#: are sampled ``field.SAMPLE_POINTS`` grid points per model call.
MAX_TILE_BYTES = MAX_GRID_BYTES
#: Runs over more day tiles than this get a streamed field (:meth:`Atlas.streamed`): a
#: 150-day run held every tile at once (2.65 GB at the default resolution, whatever the
#: budget).
STREAM_TILES = 8
#: Tiles a streamed field holds besides those the running batches are in.
STREAM_KEEP = 2
#: Version of the tile format; part of the key, so tiles of another format are misses.
TILE_FORMAT = 1
_NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class FieldMemory:
    """What the atlas holds in memory.

    Attributes:
        budget: bytes of tiles kept between runs (least recently used dropped first).
        held: bytes of the tiles kept now.
        live: bytes of every tile alive now (kept, or in use by a run).
        peak: the largest ``live`` since the process started or :func:`reset_peak`.
        tiles: number of tiles alive now.
    """

    budget: int
    held: int
    live: int
    peak: int
    tiles: int


class _TileMemory:
    """The process's tiles: the kept ones (an LRU under the budget) and, weakly, every
    one alive, so that a tile a run still holds is found again, never made twice."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.kept: collections.OrderedDict[str, Any] = collections.OrderedDict()
        self.alive: weakref.WeakValueDictionary[str, Any] = weakref.WeakValueDictionary()
        self.budget: int | None = None
        self.peak = 0

    def _budget(self) -> int:
        if self.budget is None:
            self.budget = bytes_from_env(MEMORY_ENV, DEFAULT_MEMORY)
        return self.budget

    def get(self, key: str) -> Any:
        with self.lock:
            tile = self.kept.get(key)
            if tile is not None:
                self.kept.move_to_end(key)
                return tile
            tile = self.alive.get(key)
            if tile is not None:
                self._keep(key, tile)
            return tile

    def put(self, key: str, tile: _core.FieldTile) -> None:
        with self.lock:
            self.alive[key] = tile
            self._keep(key, tile)
            self.peak = max(self.peak, self._live())

    def _keep(self, key: str, tile: Any) -> None:
        self.kept[key] = tile
        self.kept.move_to_end(key)
        budget = self._budget()
        held = sum(t.nbytes for t in self.kept.values())
        while len(self.kept) > 1 and held > budget:
            _, old = self.kept.popitem(last=False)
            held -= old.nbytes

    def _live(self) -> int:
        return sum(t.nbytes for t in list(self.alive.values()))

    def report(self) -> FieldMemory:
        with self.lock:
            tiles = list(self.alive.values())
            return FieldMemory(
                budget=self._budget(),
                held=sum(t.nbytes for t in self.kept.values()),
                live=sum(t.nbytes for t in tiles),
                peak=self.peak,
                tiles=len(tiles),
            )


_MEMORY = _TileMemory()


def set_memory_budget(nbytes: float | None) -> None:
    """Sets the bytes of tiles kept in memory between runs (None: ``$RHOPROP_FIELD_MEMORY``
    or 1 GB). 0 keeps none (every run reads its tiles from disk). Results are the same
    whatever the budget."""
    if nbytes is not None:
        if isinstance(nbytes, (bool, str, bytes)):
            raise TypeError(f"nbytes must be a number of bytes >= 0 or None, got {nbytes!r}")
        try:
            value = float(nbytes)
        except (TypeError, ValueError):
            raise TypeError(
                f"nbytes must be a number of bytes >= 0 or None, got {nbytes!r}"
            ) from None
        if not value >= 0 or value == float("inf"):
            raise ValueError(f"nbytes must be a number of bytes >= 0 or None, got {nbytes!r}")
    with _MEMORY.lock:
        _MEMORY.budget = None if nbytes is None else int(nbytes)
        _MEMORY.kept.clear()


def field_memory() -> FieldMemory:
    """The atlas's memory now and its peak (bytes of tile values), for reports."""
    return _MEMORY.report()


def reset_peak() -> None:
    """Starts a new peak of :func:`field_memory` (for example before a long run)."""
    with _MEMORY.lock:
        _MEMORY.peak = _MEMORY._live()


def _day(epoch: np.datetime64) -> np.datetime64:
    """00:00 UTC of ``epoch``'s day."""
    return np.datetime64(epoch.astype("datetime64[D]"), "ns")


class Atlas:
    """A sampled model served as day tiles (see the module doc).

    Args:
        model: a :class:`~rhoprop.density.SampledModel`.
        resolution: grid spacing (None: the model's ``resolution`` or the defaults).
        ceiling: top of the altitude grid, m (None: :data:`DEFAULT_CEILING`, or the
            model's ``highest_altitude`` when lower).
    """

    def __init__(
        self,
        model: Any,
        resolution: FieldResolution | None = None,
        ceiling: float | None = None,
    ) -> None:
        self.model = model
        self.resolution = resolution or getattr(model, "resolution", None) or FieldResolution()
        if not isinstance(self.resolution, FieldResolution):
            raise TypeError("resolution must be a rhoprop.density.FieldResolution or None")
        top = DEFAULT_CEILING if ceiling is None else float(ceiling)
        top = min(top, float(getattr(model, "highest_altitude", np.inf)))
        bottom = float(getattr(model, "lowest_altitude", 50e3))
        if not (np.isfinite(bottom) and np.isfinite(top) and 0 <= bottom < top):
            raise ValueError(
                f"the atlas needs 0 <= lowest altitude < ceiling, got {bottom} m and {top} m"
            )
        self.ceiling = top
        res = self.resolution
        n_alt = max(2, int(np.ceil((top - bottom) / res.altitude - 1e-9)) + 1)
        self.altitude = (bottom, res.altitude, n_alt)
        n_lat = round(180.0 / res.latitude) + 1
        self.latitude = (-90.0, 180.0 / (n_lat - 1), n_lat)
        self.n_lon = round(360.0 / res.longitude)
        points = n_alt * n_lat * self.n_lon
        # Time nodes of a day: the spacing and at most one driver step per 3 hours, twice.
        nodes = 86400.0 / res.time + 2 * 8 + 2
        check_grid_size(points * nodes, res, "a day tile")
        self._lock = threading.Lock()
        self._keys: dict[np.datetime64, tuple[str, str | None]] = {}
        self._fields: weakref.WeakValueDictionary[tuple[Any, ...], Any] = (
            weakref.WeakValueDictionary()
        )
        self._token = secrets.token_hex(8)

    def __repr__(self) -> str:
        return f"Atlas({self.model!r}, resolution={self.resolution}, ceiling={self.ceiling:g})"

    def __reduce__(self) -> tuple[Any, ...]:
        # A reference: the model and the grid; the tiles come from the receiver's cache.
        return (Atlas, (self.model, self.resolution, self.ceiling))

    # -- the protocol of a density model ---------------------------------------------------

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """The model's own mean and standard deviation, kg/m^3 (not the tiles')."""
        result: tuple[np.ndarray, np.ndarray] = self.model.mean_std(times, lat, lon, alt)
        return result

    def atmosphere(self, state: StateLike, duration: float) -> Any:
        """The core field for ``duration`` s from ``state`` (negative: backwards): the
        tiles' field, or for a run over more than :data:`STREAM_TILES` tiles a streamed
        one (:meth:`streamed`), so that memory follows the budget, not the run's length."""
        edge = add_seconds(state.epoch, duration, round_up=duration > 0)
        start, end = min(state.epoch, edge), max(state.epoch, edge)
        windows = self.windows(start, end)
        if len(windows) > STREAM_TILES:
            return self.streamed(windows)
        return self.field(start, end)

    def streamed(self, windows: list[tuple[np.datetime64, np.datetime64]]) -> Any:
        """A core field of the tiles over ``windows`` (consecutive, from :meth:`windows`)
        that takes each tile when the run reaches it and holds :data:`STREAM_KEEP` of them
        besides the one each batch is in (``rhoprop._core.StreamedAtmosphere``): the tiles
        come from memory (under the budget), the disk cache or are sampled then. Results
        are bit-identical to :meth:`field`'s."""
        edges = np.array([w0 for w0, _ in windows] + [windows[-1][1]], dtype="datetime64[ns]")

        def make() -> Any:
            bounds = [float(x) for x in np.asarray(ut1_seconds(edges), dtype=float)]
            return _core.StreamedAtmosphere(
                0.0, bounds, lambda k: self.tile(*windows[k]), True, STREAM_KEEP
            )

        return self._shared(("streamed", *windows), make)

    # -- tiles -------------------------------------------------------------------------------

    def windows(
        self, start: EpochLike, end: EpochLike
    ) -> list[tuple[np.datetime64, np.datetime64]]:
        """The tiles' windows (UTC start, end) covering [start, end]: whole days, cut to
        the model's drivers; OutsideRecordError for a time outside the drivers."""
        t0, t1 = to_datetime64(start, "start"), to_datetime64(end, "end")
        if t1 < t0:
            raise ValueError(f"end ({t1}) must not be before start ({t0})")
        coverage = self.model._coverage()
        if coverage is not None:
            first, last = coverage
            if t0 < first or t1 > last:
                hint = (
                    "; after the record, give the model predicted drivers "
                    "(space_weather=rp.SpaceWeather().with_forecast() for the NRLMSIS and "
                    'Jacchia models; space_weather = "forecast" in a scenario file) or a '
                    "newer record ('rhoprop data refresh'; JB2008: "
                    "rp.density.Jb2008Indices.refresh)"
                    if t1 > last
                    else ""
                )
                raise OutsideRecordError(
                    f"{self.model!r} has drivers from {first} to {last}; the run needs {t0} "
                    f"to {t1}{hint}"
                )
        day = _day(t0)
        last_day = _day(t1)
        if last_day == t1 and last_day > day:
            last_day = last_day - TILE_DAY  # ends at midnight: the day before holds it
        out: list[tuple[np.datetime64, np.datetime64]] = []
        while day <= last_day:
            w0, w1 = day, day + TILE_DAY
            if coverage is not None:
                w0, w1 = max(w0, coverage[0]), min(w1, coverage[1])
            out.append((w0, w1))
            day = day + TILE_DAY
        return out

    def field(self, start: EpochLike, end: EpochLike) -> Any:
        """The core field (``rhoprop._core.GriddedAtmosphere``) over [start, end] UTC: the
        tiles of those days, shared with every other field that holds them."""
        windows = self.windows(start, end)
        return self._shared(
            tuple(windows),
            lambda: _core.GriddedAtmosphere.from_tiles(0.0, self._tiles(windows), True),
        )

    def _shared(self, key: tuple[Any, ...], make: Callable[[], Any]) -> Any:
        """The field of ``key`` while any run holds it (the same object for the same days,
        so runs group by it and share its tiles), else ``make()``'s, kept weakly."""
        with self._lock:
            field = self._fields.get(key)
        if field is None:
            field = make()
            with self._lock:
                self._fields[key] = field
        return field

    def _tiles(self, windows: list[tuple[np.datetime64, np.datetime64]]) -> list[Any]:
        """The tiles of ``windows``, with progress (a bar on a terminal, plain lines in a
        log) when two or more must be sampled: about a second a day, with nothing said
        it looked like a hang before the run's own progress began."""
        fresh = [w for w in windows if self._must_sample(*w)]
        if len(fresh) < 2:
            return [self.tile(w0, w1) for w0, w1 in windows]
        # A model without a disk cache key is sampled into memory only: say where.
        where = "the cache" if all(self._key(*w)[1] for w in fresh) else "memory"
        bar = ProgressBar(
            len(fresh), f"sampling {type(self.model).__name__} into {where}", unit="days"
        )
        tiles, done = [], 0
        try:
            for w in windows:
                tiles.append(self.tile(*w))
                if w in fresh:
                    done += 1
                    bar(done)
        finally:
            bar.close()
        return tiles

    def _must_sample(self, w0: np.datetime64, w1: np.datetime64) -> bool:
        """Whether the tile over [w0, w1] is neither in memory nor in the disk cache."""
        key, name = self._key(w0, w1)
        if _MEMORY.get(key) is not None:
            return False
        return name is None or not (cache_dir() / "tiles" / name).is_file()

    def _key(self, w0: np.datetime64, w1: np.datetime64) -> tuple[str, str | None]:
        """(memory key, disk file name or None) of the tile over [w0, w1]."""
        with self._lock:
            known = self._keys.get(w0)
        if known is not None:
            return known
        description = self.model.cache_key(w0, w1)
        blob = json.dumps(
            {
                "model": description,
                "window": [str(w0), str(w1)],
                "altitude": list(self.altitude),
                "res": asdict(self.resolution),
                "format": TILE_FORMAT,
            },
            sort_keys=True,
            default=str,
        )
        digest = hashlib.sha256(blob.encode()).hexdigest()
        if description is None:
            known = (f"{self._token}:{w0}:{w1}", None)
        else:
            folder = model_folder(description, self.resolution, self.altitude)
            known = (digest, f"{folder}/{str(w0)[:10]}_{digest[:24]}.npz")
        with self._lock:
            self._keys[w0] = known
        return known

    def tile(self, w0: np.datetime64, w1: np.datetime64) -> Any:
        """The tile over [w0, w1] (a ``rhoprop._core.FieldTile``): from memory, from the
        disk cache or sampled now."""
        key, name = self._key(w0, w1)
        tile = _MEMORY.get(key)
        if tile is not None:
            return tile
        path = cache_dir() / "tiles" / name if name is not None else None
        with entry_lock(path if path is not None else Path(key)):
            tile = _MEMORY.get(key)  # made by another thread meanwhile
            if tile is not None:
                return tile
            nodes, epochs, left = self._nodes(w0, w1)
            shape = (len(nodes), self.altitude[2], self.latitude[2], self.n_lon)
            saved = load_entry(path) if path is not None else None
            if saved is not None and _entry_matches(saved, key, shape):
                ln_mean, rel_sigma = saved["ln_mean"], saved["rel_sigma"]
            else:
                ln_mean, rel_sigma = self._sample(epochs, left)
                if path is not None:
                    if not (path.parent / "model.json").exists():
                        _describe(path.parent, self.model.cache_key(w0, w1), self)
                    store_entry(
                        path, {"ln_mean": ln_mean, "rel_sigma": rel_sigma, "key": np.array(key)}
                    )
            tile = _core.FieldTile(nodes, self.altitude, self.latitude, 0.0, ln_mean, rel_sigma)
            _MEMORY.put(key, tile)
        return tile

    def _nodes(
        self, w0: np.datetime64, w1: np.datetime64
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Time nodes of the tile over [w0, w1]: absolute (UT1 s since J2000), their UTC
        epochs and which are sampled just before their epoch (a driver step's first copy
        and the tile's end, where the next day may step)."""
        span = int((w1 - w0).astype(np.int64)) / _NS_PER_S
        breaks = np.asarray(self.model._breaks(w0, w1), dtype="datetime64[ns]")
        offsets = (breaks - w0).astype(np.int64) / _NS_PER_S
        local, left = time_nodes(span, self.resolution.time, offsets)
        ns = np.round(local * _NS_PER_S).astype(np.int64)
        epochs = w0 + ns.astype("timedelta64[ns]")
        epochs[-1] = w1
        left = left.copy()
        left[-1] = True
        return np.asarray(ut1_seconds(epochs), dtype=float), epochs, left

    def _sample(self, epochs: np.ndarray, left: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """ln(mean) and sigma/mean on the tile's grid, in chunks of time nodes of at most
        :data:`SAMPLE_POINTS` grid points each; checks that density falls at the ceiling
        (the extrapolation above it follows that slope)."""
        a0, da, na = self.altitude
        alt = a0 + da * np.arange(na)
        lat = np.linspace(-90.0, 90.0, self.latitude[2])
        lon = np.arange(self.n_lon) * (360.0 / self.n_lon)
        ln_mean, rel_sigma = sample_grid(self.model, epochs, left, alt, lat, lon)
        if (ln_mean[:, -1] > ln_mean[:, -2]).any():
            raise ValueError(
                f"{self.model!r}: density increases with altitude at the atlas ceiling "
                f"({alt[-1]:g} m), so it cannot be extrapolated above"
            )
        return ln_mean, rel_sigma


def model_folder(
    description: object, resolution: FieldResolution, altitude: tuple[float, float, int]
) -> str:
    """Folder name of a model's tiles: its description without the per-window digests of
    its drivers, with the resolution and altitude grid."""
    stable = _stable(description)
    blob = json.dumps(
        {"model": stable, "res": asdict(resolution), "altitude": list(altitude)},
        sort_keys=True,
        default=str,
    )
    name = str(stable.get("model", "model")) if isinstance(stable, dict) else "model"
    safe = "".join(c if c.isalnum() or c in "-." else "-" for c in name)[:40]
    return f"{safe}-{hashlib.sha256(blob.encode()).hexdigest()[:12]}"


def _stable(description: Any) -> Any:
    """The parts of a cache key that do not change from day to day."""
    if isinstance(description, dict):
        return {k: v for k, v in description.items() if k not in ("drivers", "indices")}
    return description


def _describe(folder: Path, description: Any, atlas: Atlas) -> None:
    """Writes ``model.json`` (what the folder's tiles are of) once, for ``cache info``."""
    target = folder / "model.json"
    if target.exists():
        return
    try:
        folder.mkdir(parents=True, exist_ok=True)
        text = json.dumps(
            {
                "model": _stable(description),
                "repr": repr(atlas.model),
                "resolution": asdict(atlas.resolution),
                "altitude_m": list(atlas.altitude),
                "ceiling_m": atlas.ceiling,
            },
            sort_keys=True,
            default=str,
            indent=1,
        )
        temporary = folder / f".model.json.{os.getpid()}.{secrets.token_hex(4)}.tmp"
        temporary.write_text(text)
        os.replace(temporary, target)
    except OSError:
        pass  # only the listing loses its label; store_entry warns about the tile itself
