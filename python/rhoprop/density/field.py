"""Sampling a density model into the gridded field the Rust core interpolates.

A field holds ln(mean density) and sigma/mean on a (time, geodetic altitude, geodetic
latitude, longitude) grid. ln-density is smooth, so a coarse grid suffices; the time axis
may repeat a node where the model's drivers jump (3-hourly ap, daily F10.7), so the field
represents those steps exactly instead of smearing them over a cell. Sampled fields are
cached on disk, keyed by the model's own description (version, drivers, uncertainty), the
window and the resolution, so a rerun is instant. The cache stores a checksum with each
entry, recomputes a corrupt one, keeps the field in memory when the cache cannot be
written (both with a :class:`~rhoprop.errors.CacheWarning`) and stays under a size cap
(``$RHOPROP_CACHE_MAX_BYTES``, default 2 GB; see :mod:`rhoprop.cache`).
"""

from __future__ import annotations

import collections
import hashlib
import itertools
import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from .. import _core, _validate
from ..cache import cache_dir, entry_lock, load_entry, store_entry
from ..time import (
    EpochLike,
    EpochsLike,
    add_seconds,
    core_times,
    offsets_to_epochs,
    seconds_between,
    to_datetime64,
    to_seconds,
    ut1_seconds,
)
from ._inputs import StateLike, broadcast_inputs

if TYPE_CHECKING:
    from .model import SampledModel


@dataclass(frozen=True)
class FieldResolution:
    """Grid spacing of a sampled field.

    Attributes:
        time: largest spacing of time nodes, s (nodes also fall on every driver change).
        altitude: altitude spacing, m.
        latitude: latitude spacing, deg (must divide 180).
        longitude: longitude spacing, deg (must divide 360).

    The defaults keep gridded vs direct NRLMSIS 2.1 within 1 % RMS and 3 % max along the
    paper's orbit in the 2002-09-07 storm, for mean and sigma (measured 0.32 % RMS, 1.5 %
    max; ``tests/test_field.py``), and sample the paper's 3 days + 8 h in about 2 s.
    Longitude matters more than latitude (the diurnal bulge); time nodes also fall on every
    3-hourly driver change, so 1 h between nodes is plenty.
    """

    time: float = 3600.0
    altitude: float = 25e3
    latitude: float = 6.0
    longitude: float = 15.0

    def __post_init__(self) -> None:
        for name in ("time", "altitude", "latitude", "longitude"):
            _validate.positive(f"resolution.{name}", getattr(self, name))
        for name, span in (("latitude", 180.0), ("longitude", 360.0)):
            step = getattr(self, name)
            if abs(span / step - round(span / step)) > 1e-9:
                raise ValueError(f"resolution.{name} = {step} deg must divide {span:g} deg")


def resolution_arg(value: object, name: str = "resolution") -> FieldResolution | None:
    """``value`` checked as a model's ``resolution`` keyword: a :class:`FieldResolution`
    or None (the default resolution)."""
    if value is not None and not isinstance(value, FieldResolution):
        raise TypeError(
            f"{name} must be a rhoprop.density.FieldResolution or None, got {type(value).__name__}"
        )
    return value


@dataclass(frozen=True)
class DensityField:
    """A sampled density field (what the core propagates through).

    Attributes:
        epoch: UTC epoch of the first time node.
        times: time nodes, s from ``epoch`` (repeated node = step in the drivers).
        altitudes: geodetic altitude nodes, m.
        latitudes: geodetic latitude nodes, deg.
        longitudes: longitude nodes, deg (periodic).
        ln_mean: ln(mean density / (kg/m^3)), shape (nt, nalt, nlat, nlon).
        rel_sigma: sigma / mean, same shape.
        core: the core object (``rhoprop._core.GriddedAtmosphere``).
    """

    epoch: np.datetime64
    times: np.ndarray
    altitudes: np.ndarray
    latitudes: np.ndarray
    longitudes: np.ndarray
    ln_mean: np.ndarray
    rel_sigma: np.ndarray
    core: Any

    @classmethod
    def from_arrays(
        cls,
        epoch: EpochLike,
        times: EpochsLike,
        altitudes: npt.ArrayLike,
        latitudes: npt.ArrayLike,
        longitudes: npt.ArrayLike,
        ln_mean: npt.ArrayLike,
        rel_sigma: npt.ArrayLike,
    ) -> DensityField:
        """Builds a field from uniform altitude/latitude/longitude axes (m, deg, deg;
        longitude spanning the globe: nodes lon0 + k 360/n) and time nodes (s from
        ``epoch``)."""
        e = to_datetime64(epoch)
        t = np.ascontiguousarray(times, dtype=float)
        axes = []
        for name, a in (("altitudes", altitudes), ("latitudes", latitudes)):
            arr = np.asarray(a, dtype=float)
            axes.append(arr)
            _uniform(name, arr)
        alt, lat = axes
        lon = np.asarray(longitudes, dtype=float)
        step = _uniform("longitudes", lon)
        if abs(step * len(lon) - 360.0) > 1e-6:
            raise ValueError(
                f"longitudes must be n equal steps around the globe (360/n deg); got {len(lon)} "
                f"nodes {step:g} deg apart"
            )
        lnm = np.ascontiguousarray(ln_mean, dtype=float)
        rs = np.ascontiguousarray(rel_sigma, dtype=float)
        core = _core.GriddedAtmosphere(
            ut1_seconds(e),
            t,
            (float(alt[0]), float(alt[1] - alt[0]), len(alt)),
            (float(lat[0]), float(lat[1] - lat[0]), len(lat)),
            float(lon[0]),
            lnm,
            rs,
        )
        return cls(e, t, alt, lat, lon, lnm, rs, core)

    def __reduce__(self) -> tuple[Any, ...]:
        # The core object does not pickle; the arrays rebuild it (e.g. on Dask workers).
        return (
            DensityField.from_arrays,
            (
                self.epoch,
                self.times,
                self.altitudes,
                self.latitudes,
                self.longitudes,
                self.ln_mean,
                self.rel_sigma,
            ),
        )

    @property
    def start(self) -> np.datetime64:
        """First epoch covered."""
        return add_seconds(self.epoch, float(self.times[0]))

    @property
    def end(self) -> np.datetime64:
        """Last epoch covered."""
        return add_seconds(self.epoch, float(self.times[-1]))

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Interpolated mean and standard deviation (kg/m^3) at UTC ``times``, geodetic
        ``lat``/``lon`` (deg) and ``alt`` (m); raises ``DensityFieldError`` outside."""
        t, la, lo, al = broadcast_inputs(times, lat, lon, alt)
        shape = la.shape
        fixed = _core.geodetic_to_fixed(np.stack([la.ravel(), lo.ravel(), al.ravel()], axis=1))
        # The core's time as a run from the field epoch sees it (elapsed SI seconds on the
        # field's axis), and the same angle for the rotation, so the lookup is exact also
        # across a leap second.
        ut1 = core_times(t.ravel(), self.epoch)
        theta = _core.gmst(ut1)
        c, s = np.cos(theta), np.sin(theta)
        inertial = np.stack(
            [c * fixed[:, 0] - s * fixed[:, 1], s * fixed[:, 0] + c * fixed[:, 1], fixed[:, 2]],
            axis=1,
        )
        mean, sigma = self.core.mean_sigma(ut1, inertial)
        return mean.reshape(shape), sigma.reshape(shape)

    def atmosphere(self, state: StateLike, duration: float) -> Any:
        """The core atmosphere (the field itself); it must cover the propagation."""
        return self.core


def _uniform(name: str, arr: np.ndarray) -> float:
    if arr.ndim != 1 or len(arr) < 2:
        raise ValueError(f"{name} must be a 1-D axis with at least 2 nodes")
    d = np.diff(arr)
    if not np.isfinite(arr).all() or (d <= 0).any() or np.ptp(d) > 1e-9 * max(abs(d[0]), 1.0):
        raise ValueError(f"{name} must be finite, increasing and uniformly spaced")
    return float(d[0])


def time_nodes(span: float, step: float, breaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Time nodes over [0, span] s no more than ``step`` apart, with every break (s, inside
    the span) present twice. Returns (nodes, left) where ``left`` marks the first copy of
    a break, to be sampled with the drivers in force just before it."""
    inner = np.unique(breaks[(breaks > 0) & (breaks < span)])
    edges = np.concatenate([[0.0], inner, [span]])
    nodes: list[float] = []
    left: list[bool] = []
    for k, (a, b) in enumerate(itertools.pairwise(edges)):
        n = max(1, int(np.ceil((b - a) / step - 1e-9)))
        seg = a + (b - a) * np.arange(n + 1) / n
        seg[-1] = b  # exactly: a + (b - a) may round above b, and the next segment starts at b
        nodes.extend(seg)
        left.extend([False] * n + [k < len(edges) - 2])
    return np.array(nodes), np.array(left)


def grid_axes(
    altitude_range: tuple[float, float], resolution: FieldResolution
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Altitude (m), latitude and longitude (deg) nodes. Altitude nodes are aligned to
    multiples of the spacing and cover the range."""
    lo, hi = (
        _validate.real("altitude_range[0]", altitude_range[0]),
        _validate.real("altitude_range[1]", altitude_range[1]),
    )
    if not hi > lo:
        raise ValueError(
            f"altitude_range must be (low, high) with high > low, got {altitude_range}"
        )
    if lo < 0:
        raise ValueError(f"altitude_range must be above the surface, got low = {lo} m")
    da = resolution.altitude
    alt = np.arange(np.floor(lo / da), np.ceil(hi / da) + 1) * da
    if len(alt) < 2:
        alt = np.array([alt[0], alt[0] + da])
    nlat = round(180.0 / resolution.latitude) + 1
    nlon = round(360.0 / resolution.longitude)
    return alt, np.linspace(-90.0, 90.0, nlat), np.arange(nlon) * resolution.longitude


#: Largest sampled grid (a field, or a day tile of an atlas), bytes of its ln(mean) and
#: sigma/mean: a resolution that needs more is refused before anything is allocated.
MAX_GRID_BYTES = 2_000_000_000
#: Grid points per call of a model's sampler: bounds its working memory (pymsis needs
#: about 300 bytes per point with the driver perturbations).
SAMPLE_POINTS = 1 << 18


def check_grid_size(points: float, resolution: FieldResolution, what: str) -> None:
    """ValueError if a grid of ``points`` nodes (times x altitudes x latitudes x
    longitudes) at ``resolution`` would exceed :data:`MAX_GRID_BYTES`; ``what`` names the
    grid ("a day tile", "the field")."""
    if 16 * points > MAX_GRID_BYTES:
        raise ValueError(
            f"resolution {resolution} is too fine: {what} would hold about "
            f"{16 * points / 1e9:.1f} GB (at most {MAX_GRID_BYTES / 1e9:g} GB); use a "
            "coarser resolution or a shorter span"
        )


def sample_grid(
    model: SampledModel,
    epochs: np.ndarray,
    left: np.ndarray,
    alt: np.ndarray,
    lat: np.ndarray,
    lon: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``model._grid_values`` over the grid, in chunks of time nodes of at most
    :data:`SAMPLE_POINTS` points each (at least one node): (ln_mean, rel_sigma) arrays
    (nt, nalt, nlat, nlon)."""
    per_node = len(alt) * len(lat) * len(lon)
    step = max(1, SAMPLE_POINTS // per_node)
    ln_mean = np.empty((len(epochs), len(alt), len(lat), len(lon)))
    rel_sigma = np.empty_like(ln_mean)
    for i in range(0, len(epochs), step):
        part = slice(i, i + step)
        ln_mean[part], rel_sigma[part] = model._grid_values(epochs[part], left[part], alt, lat, lon)
    return ln_mean, rel_sigma


def sample_field(
    model: SampledModel,
    start: EpochLike,
    end: EpochLike,
    *,
    altitude_range: tuple[float, float],
    resolution: FieldResolution | None = None,
    cache: bool = True,
) -> DensityField:
    """Samples ``model`` over [start, end] (UTC) in ``altitude_range`` (m, geodetic).

    The model provides ``_grid_values(epochs, left, alt, lat, lon)`` -> (ln_mean, rel_sigma)
    arrays (nt, nalt, nlat, nlon), ``_breaks(start, end)`` -> epochs where its drivers
    jump, and ``cache_key(start, end)`` -> a JSON-able description (or None: no caching).
    """
    res = resolution_arg(resolution) or FieldResolution()
    t0, t1 = to_datetime64(start, "start"), to_datetime64(end, "end")
    span = seconds_between(t0, t1)
    if not span > 0:
        raise ValueError(f"end ({t1}) must be after start ({t0})")
    alt, lat, lon = grid_axes(altitude_range, res)
    breaks = np.asarray(model._breaks(t0, t1), dtype="datetime64[ns]")
    offsets = to_seconds(breaks, t0)
    nodes, left = time_nodes(span, res.time, offsets)
    check_grid_size(len(nodes) * len(alt) * len(lat) * len(lon), res, "the field")

    key = model.cache_key(t0, t1) if cache else None
    if key is None:
        ln_mean, rel_sigma = sample_grid(model, offsets_to_epochs(t0, nodes), left, alt, lat, lon)
        return DensityField.from_arrays(t0, nodes, alt, lat, lon, ln_mean, rel_sigma)
    blob = json.dumps(
        {
            "model": key,
            "start": str(t0),
            "end": str(t1),
            "alt": [alt[0], alt[-1]],
            "res": asdict(res),
            "format": FIELD_FORMAT,
        },
        sort_keys=True,
        default=str,
    )
    path = cache_dir() / "fields" / (hashlib.sha256(blob.encode()).hexdigest()[:32] + ".npz")
    shape = (len(nodes), len(alt), len(lat), len(lon))
    # One thread computes a field the others of this process wait for and then read.
    with entry_lock(path):
        recent = _RECENT.get(blob)
        if recent is not None and recent[0] == _stamp(path):
            _RECENT.move_to_end(blob)
            return recent[1]
        saved = load_entry(path)
        if saved is not None and _entry_matches(saved, blob, shape):
            ln_mean, rel_sigma = saved["ln_mean"], saved["rel_sigma"]
        else:
            ln_mean, rel_sigma = sample_grid(
                model, offsets_to_epochs(t0, nodes), left, alt, lat, lon
            )
            store_entry(path, {"ln_mean": ln_mean, "rel_sigma": rel_sigma, "key": np.array(blob)})
        field = DensityField.from_arrays(t0, nodes, alt, lat, lon, ln_mean, rel_sigma)
        stamp = _stamp(path)
        if stamp is not None:
            _remember(blob, stamp, field)
    return field


#: The fields this process read or wrote last, by cache key, with the stamp (mtime, size)
#: of their disk entry: a rerun over the same window (a catalog run after run) skips
#: reading, checking and copying a possibly large file while that entry is unchanged.
#: Fields are immutable, so sharing them is safe.
_RECENT: collections.OrderedDict[str, tuple[tuple[int, int], DensityField]] = (
    collections.OrderedDict()
)
#: Bounds of that memory: entries and bytes (ln_mean and rel_sigma).
RECENT_FIELDS = 4
RECENT_BYTES = 2**30


def _stamp(path: Path) -> tuple[int, int] | None:
    """(mtime in ns, size) of a cache entry, or None when there is none."""
    try:
        st = path.stat()
    except OSError:
        return None
    return (st.st_mtime_ns, st.st_size)


def _remember(key: str, stamp: tuple[int, int], field: DensityField) -> None:
    _RECENT[key] = (stamp, field)
    while len(_RECENT) > RECENT_FIELDS or (
        len(_RECENT) > 1
        and sum(f.ln_mean.nbytes + f.rel_sigma.nbytes for _, f in _RECENT.values()) > RECENT_BYTES
    ):
        _RECENT.popitem(last=False)


#: Version of the cached field format (2: with checksum and key); part of the key, so
#: entries of another format are misses, never corrupt.
FIELD_FORMAT = 2


def _entry_matches(saved: dict[str, np.ndarray], blob: str, shape: tuple[int, ...]) -> bool:
    """Whether a (checksum-verified) entry holds this key's field."""
    try:
        return (
            str(saved["key"]) == blob
            and saved["ln_mean"].shape == shape
            and saved["rel_sigma"].shape == shape
        )
    except KeyError:
        return False
