"""A PCA reduced-order model (ROM) of log10 density with Gaussian coefficients: the output
form of HASDM-ML-DP (Licata & Mehta 2022; section 2.1 of Paul, Licata & Mehta).

The ROM writes log10 density on a fixed spatial grid s = (local solar time, latitude,
altitude) as

    x(s, t) = xbar(s) + sum_j alpha_j(t) U_j(s),

with xbar the spatial mean and U_j orthogonal PCA modes (the paper's eq. 1a-1b). The ML
model predicts, per epoch, the mean mu_j and standard deviation sigma_j of each coefficient
alpha_j, treated as independent Gaussians. The paper decodes by Monte Carlo: it samples
coefficient vectors, decodes each to log density and takes statistics. Because x is linear
in alpha, x at a point is itself Gaussian, so density 10^x is lognormal and its mean and
standard deviation have a closed form (used by default; the Monte Carlo is kept as a check).
"""

from __future__ import annotations

import hashlib
import itertools
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from ..errors import OutsideRecordError
from ..time import EpochsLike, to_datetime64_array
from ._inputs import broadcast_inputs
from .field import FieldResolution, resolution_arg
from .model import SampledModel

#: ln(10): density = 10^x = exp(LN10 x).
LN10 = float(np.log(10.0))
#: Points per block in mean_std (bounds the memory of the mode interpolation).
BLOCK = 1 << 16
#: Largest number of sampled densities held at once by the "sampling" method.
SAMPLE_BLOCK = 1 << 22
METHODS = ("analytic", "sampling")
#: Largest 1-sigma of log10 density the coefficients may give anywhere (a factor 100 at
#: one sigma; HASDM-ML-DP's is about 0.1): beyond it the lognormal moments overflow or
#: mean nothing, and the coefficients are most likely not those of log10 density.
MAX_LOG10_SIGMA = 2.0
_NS_PER_HOUR = 3_600_000_000_000


class PcaRom(SampledModel):
    """Mean and standard deviation of density from a PCA reduced-order model of log10
    density with independent Gaussian coefficients (the HASDM-ML-DP output form).

    The grid is local solar time x latitude x altitude. The public SET HASDM database,
    on which HASDM-ML-DP is trained, has 24 x 19 x 27 nodes: 1 h of local solar time
    (15 deg), 10 deg of latitude and 25 km of altitude from 175 to 825 km (paper section
    2.1; https://spacewx.com/hasdm, Tobiska et al. 2021, Space Weather,
    doi:10.1029/2020SW002682). The axes here are whatever the arrays give.

    Evaluation at UTC time t, geodetic latitude, longitude lon (deg) and altitude (m):

    1. local solar time LST = (UTC hour of day + lon / 15) mod 24, h (mean solar time);
    2. xbar and each U_j are interpolated multilinearly in (LST, lat, alt), periodically in
       LST; the coefficient means mu_j and standard deviations sigma_j linearly in time
       between ``epochs``;
    3. log10 density x = xbar + sum_j U_j alpha_j, alpha_j ~ N(mu_j, sigma_j^2) independent,
       is Gaussian with mean m = xbar + sum_j U_j mu_j and variance s2 = sum_j U_j^2
       sigma_j^2 (this is exactly the distribution of the multilinearly interpolated
       sampled log10 field, so the analytic and sampling methods agree);
    4. density 10^x = exp(L x), L = ln 10, is lognormal with (standard lognormal moments,
       e.g. Johnson, Kotz & Balakrishnan, Continuous Univariate Distributions, ch. 14)

           mean = exp(L m + L^2 s2 / 2),   std = mean sqrt(exp(L^2 s2) - 1).

    With ``method="sampling"`` the paper's Monte Carlo is used instead: ``samples``
    coefficient vectors alpha = mu + sigma z, z ~ N(0, I), are drawn with
    ``numpy.random.default_rng(seed)`` on every call (the same draws for all points of a
    call, like decoding whole sampled grids), each is decoded to density, and the sample
    mean and standard deviation (ddof = 1) are returned. It costs ``samples`` times more
    and is noisy (standard error of the mean about std / sqrt(samples)); it exists to check
    the closed form.

    Args:
        lst: local solar time axis (nlst,), h, uniform and covering the day: nlst steps of
            24 / nlst h (e.g. 0, 1, ..., 23).
        lat: geodetic latitude axis (nlat,), deg, increasing, within [-90, 90]. A sampled
            field (``field``, propagation) needs it to span [-90, 90].
        alt: geodetic altitude axis (nalt,), m, increasing.
        mean_log10: spatial mean of log10(density / (kg/m^3)), shape (nlst, nlat, nalt).
        modes: PCA modes U, shape (nlst, nlat, nalt, r) (log10 units per unit coefficient).
        epochs: UTC epochs of the coefficients (ne,), datetime64 or ISO strings, increasing.
        coeff_mean: coefficient means mu, shape (ne, r).
        coeff_std: coefficient standard deviations sigma, shape (ne, r), >= 0.
        method: ``"analytic"`` (default) or ``"sampling"``.
        samples: number of coefficient samples of the "sampling" method (>= 2).
        seed: seed of ``numpy.random.default_rng`` for the "sampling" method (None: fresh
            entropy each call, which disables the field cache).
        resolution: grid spacing of the field the propagators sample the model into
            (:class:`~rhoprop.density.FieldResolution`; None: its defaults).

    Raises:
        ValueError: for arrays of the wrong shape, non-finite values, axes that are not
            increasing (or an LST axis that is not uniform over 24 h), negative ``coeff_std``;
            from :meth:`mean_std`, :class:`~rhoprop.OutsideRecordError` (a ValueError)
            for points outside the latitude, altitude or epoch range.
    """

    def __init__(
        self,
        lst: Any,
        lat: npt.ArrayLike,
        alt: npt.ArrayLike,
        mean_log10: Any,
        modes: Any,
        epochs: EpochsLike,
        coeff_mean: Any,
        coeff_std: Any,
        *,
        method: Literal["analytic", "sampling"] = "analytic",
        samples: int = 1000,
        seed: int | None = 0,
        resolution: FieldResolution | None = None,
    ) -> None:
        self.lst = _axis("lst", lst)
        self.lat = _axis("lat", lat)
        self.alt = _axis("alt", alt)
        step = float(np.diff(self.lst).mean())
        if np.ptp(np.diff(self.lst)) > 1e-9 * step or abs(step * len(self.lst) - 24.0) > 1e-9:
            raise ValueError(
                "lst must be uniform and cover the day: n nodes 24/n h apart (e.g. 0, 1, ..., "
                f"23); got {len(self.lst)} nodes from {self.lst[0]:g} to {self.lst[-1]:g} h"
            )
        self._lst_step = step
        if self.lat[0] < -90.0 or self.lat[-1] > 90.0:
            raise ValueError(
                f"lat must lie within [-90, 90] deg; got {self.lat[0]:g} to {self.lat[-1]:g}"
            )
        grid = (len(self.lst), len(self.lat), len(self.alt))
        self.mean_log10 = _array("mean_log10", mean_log10, grid, "(nlst, nlat, nalt)")
        u = np.asarray(modes, dtype=float)
        if u.ndim != 4 or u.shape[:3] != grid or u.shape[3] < 1:
            raise ValueError(
                "modes must have shape (nlst, nlat, nalt, r) = "
                f"({grid[0]}, {grid[1]}, {grid[2]}, r) with r >= 1, got {u.shape}"
            )
        self.modes = _array("modes", u, u.shape, "(nlst, nlat, nalt, r)")
        rank = u.shape[3]

        e = to_datetime64_array(epochs, "epochs")
        if e.ndim != 1 or len(e) < 1:
            raise ValueError(f"epochs must be a 1-D array of at least 1 epoch, got shape {e.shape}")
        if (np.diff(e.astype(np.int64)) <= 0).any():
            raise ValueError("epochs must be strictly increasing")
        e.flags.writeable = False
        self.epochs = e
        shape = (len(e), rank)
        self.coeff_mean = _array("coeff_mean", coeff_mean, shape, "(ne, r)")
        self.coeff_std = _array("coeff_std", coeff_std, shape, "(ne, r)")
        if (self.coeff_std < 0).any():
            bad = tuple(int(i) for i in np.argwhere(self.coeff_std < 0)[0])
            raise ValueError(f"coeff_std must be >= 0; got {self.coeff_std[bad]} at index {bad}")
        with np.errstate(over="ignore"):  # an overflow is inf, refused below
            log_sigma = np.sqrt((u.reshape(-1, rank) ** 2) @ (self.coeff_std**2).T)  # (nodes, ne)
        if log_sigma.max() > MAX_LOG10_SIGMA:
            node, epoch = np.unravel_index(int(np.argmax(log_sigma)), log_sigma.shape)
            i_lst, i_lat, i_alt = np.unravel_index(int(node), grid[:3])
            raise ValueError(
                f"coeff_std gives log10 density a 1-sigma of {log_sigma.max():.3g} at epoch "
                f"{e[epoch]} (LST {self.lst[i_lst]:g} h, lat {self.lat[i_lat]:g} deg, alt "
                f"{self.alt[i_alt]:g} m); more than {MAX_LOG10_SIGMA:g} (a factor "
                f"{10**MAX_LOG10_SIGMA:g} at one sigma) is not a density uncertainty: are the "
                "coefficients those of log10 density?"
            )

        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        self.method = method
        if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)):
            raise TypeError(f"samples must be an integer, got {type(samples).__name__}")
        if samples < 2:
            raise ValueError(f"samples must be >= 2, got {samples}")
        self.samples = int(samples)
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer))):
            raise TypeError(f"seed must be an integer or None, got {type(seed).__name__}")
        self.seed = None if seed is None else int(seed)
        self.resolution = resolution_arg(resolution)

        self._mean_flat = self.mean_log10.reshape(-1)
        self._modes_flat = self.modes.reshape(-1, rank)
        self._ns = self.epochs.astype(np.int64)

    @property
    def rank(self) -> int:
        """Number of PCA modes r."""
        return int(self.modes.shape[3])

    def __repr__(self) -> str:
        nlst, nlat, nalt = self.mean_log10.shape
        return (
            f"PcaRom({nlst}x{nlat}x{nalt} grid, {self.rank} modes, {len(self.epochs)} epochs "
            f"{self.epochs[0]} to {self.epochs[-1]}, method={self.method!r})"
        )

    def log10_moments(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean m and variance s2 of the Gaussian log10(density / (kg/m^3)) at the points
        (step 3 of the class doc); arguments as :meth:`mean_std`."""
        m, s2, _ = self._log10_moments(times, lat, lon, alt)
        return m, s2

    def _log10_moments(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(m, s2, U_j sigma_j with shape (..., r)) at the points."""
        t, la, lo, al = broadcast_inputs(times, lat, lon, alt)
        shape = la.shape
        t_ns = t.reshape(-1).astype(np.int64)
        la, lo, al = la.reshape(-1), lo.reshape(-1), al.reshape(-1)
        self._check_range(t_ns, la, al)
        n = t_ns.size
        m = np.empty(n)
        s2 = np.empty(n)
        scaled = np.empty((n, self.rank))
        for a in range(0, n, BLOCK):
            b = slice(a, a + BLOCK)
            m[b], s2[b], scaled[b] = self._moments(t_ns[b], la[b], lo[b], al[b])
        return m.reshape(shape), s2.reshape(shape), scaled.reshape((*shape, self.rank))

    def mean_std(
        self, times: EpochsLike, lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of density, kg/m^3, at UTC ``times`` (datetime64 or
        ISO strings), geodetic ``lat``/``lon`` (deg) and ``alt`` (m, WGS-84), broadcast
        together (see the class doc for the formulas)."""
        m, s2, scaled = self._log10_moments(times, lat, lon, alt)
        if self.method == "analytic":
            # 10^m exp(L^2 s2 / 2) = exp(L m + L^2 s2 / 2); expm1 keeps small s2 accurate
            # and gives std = 0 exactly for s2 = 0.
            v = LN10**2 * s2
            mean = 10.0**m * np.exp(0.5 * v)
            return mean, mean * np.sqrt(np.expm1(v))
        z = np.random.default_rng(self.seed).standard_normal((self.samples, self.rank))
        mf, sf = m.reshape(-1), scaled.reshape(-1, self.rank)
        mean = np.empty(mf.size)
        std = np.empty(mf.size)
        block = max(1, SAMPLE_BLOCK // self.samples)
        for a in range(0, mf.size, block):
            b = slice(a, a + block)
            rho = 10.0 ** (mf[b, None] + sf[b] @ z.T)
            mean[b] = rho.mean(axis=1)
            std[b] = rho.std(axis=1, ddof=1)
        return mean.reshape(m.shape), std.reshape(m.shape)

    @property
    def lowest_altitude(self) -> float:  # type: ignore[override]
        """The ROM's lowest altitude node, m (the atlas grid starts there)."""
        return float(self.alt[0])

    @property
    def highest_altitude(self) -> float:  # type: ignore[override]
        """The ROM's highest altitude node, m (the atlas ceiling; extrapolated above)."""
        return float(self.alt[-1])

    def _coverage(self) -> tuple[np.datetime64, np.datetime64] | None:
        return self.epochs[0].astype("datetime64[ns]"), self.epochs[-1].astype("datetime64[ns]")

    def cache_key(self, start: np.datetime64, end: np.datetime64) -> Any:
        """sha256 of the axes, grid and coefficient arrays, with the method (and samples
        and seed for "sampling"); None for "sampling" with ``seed=None``."""
        if self.method == "sampling" and self.seed is None:
            return None
        digest = hashlib.sha256()
        for a in (
            self.lst,
            self.lat,
            self.alt,
            self.mean_log10,
            self.modes,
            self._ns,
            self.coeff_mean,
            self.coeff_std,
        ):
            digest.update(str(a.shape).encode())
            digest.update(np.ascontiguousarray(a).tobytes())
        key: dict[str, Any] = {"model": "pcarom", "format": 1, "arrays": digest.hexdigest()}
        key["method"] = self.method
        if self.method == "sampling":
            key["samples"] = self.samples
            key["seed"] = self.seed
        return key

    def _breaks(self, start: np.datetime64, end: np.datetime64) -> np.ndarray:
        """The coefficient epochs inside (start, end): the time interpolation has a kink
        there, so the sampled field gets a node at each (the values are continuous, so the
        repeated node holds the same value twice)."""
        e = self.epochs
        return e[(e > start) & (e < end)]

    def _check_range(self, t_ns: np.ndarray, lat: np.ndarray, alt: np.ndarray) -> None:
        for name, values, axis, unit in (
            ("lat", lat, self.lat, "deg"),
            ("alt", alt, self.alt, "m"),
        ):
            out = (values < axis[0]) | (values > axis[-1])
            if out.any():
                raise OutsideRecordError(
                    f"{name} = {values[out][0]:g} {unit} is outside the ROM's {name} range "
                    f"[{axis[0]:g}, {axis[-1]:g}] {unit}"
                )
        out = (t_ns < self._ns[0]) | (t_ns > self._ns[-1])
        if out.any():
            bad = np.datetime64(int(t_ns[out][0]), "ns")
            raise OutsideRecordError(
                f"time {bad} is outside the ROM's epoch range [{self.epochs[0]}, {self.epochs[-1]}]"
            )

    def _moments(
        self, t_ns: np.ndarray, lat: np.ndarray, lon: np.ndarray, alt: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(m, s2, U sigma) for flat in-range points."""
        # Local (mean) solar time, h, and its periodic cell.
        hour = (t_ns % (24 * _NS_PER_HOUR)) / _NS_PER_HOUR
        lst = np.mod(hour + lon / 15.0, 24.0)
        u = np.mod(lst - self.lst[0], 24.0) / self._lst_step
        cell = np.floor(u)
        w_lst = u - cell
        nlst = len(self.lst)
        i_lst = cell.astype(np.int64) % nlst
        lst_nodes = (i_lst, (i_lst + 1) % nlst)
        i_lat, w_lat = _cell(self.lat, lat)
        i_alt, w_alt = _cell(self.alt, alt)
        nlat, nalt = len(self.lat), len(self.alt)

        xbar = np.zeros(t_ns.size)
        modes = np.zeros((t_ns.size, self.rank))
        for a, b, c in itertools.product((0, 1), repeat=3):
            w = (
                (w_lst if a else 1.0 - w_lst)
                * (w_lat if b else 1.0 - w_lat)
                * (w_alt if c else 1.0 - w_alt)
            )
            flat = (lst_nodes[a] * nlat + i_lat + b) * nalt + i_alt + c
            xbar += w * self._mean_flat[flat]
            modes += w[:, None] * self._modes_flat[flat]

        ne = len(self._ns)
        if ne == 1:
            mu = np.broadcast_to(self.coeff_mean[0], modes.shape)
            sigma = np.broadcast_to(self.coeff_std[0], modes.shape)
        else:
            i = np.clip(np.searchsorted(self._ns, t_ns, side="right") - 1, 0, ne - 2)
            wt = ((t_ns - self._ns[i]) / (self._ns[i + 1] - self._ns[i]))[:, None]
            mu = (1.0 - wt) * self.coeff_mean[i] + wt * self.coeff_mean[i + 1]
            sigma = (1.0 - wt) * self.coeff_std[i] + wt * self.coeff_std[i + 1]
        scaled = modes * sigma
        m = xbar + np.sum(modes * mu, axis=1)
        s2 = np.sum(scaled**2, axis=1)
        return m, s2, scaled


def _axis(name: str, values: Any) -> np.ndarray:
    a = np.array(values, dtype=float)
    if a.ndim != 1 or len(a) < 2:
        raise ValueError(f"{name} must be a 1-D axis with at least 2 nodes, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name} must be finite; got {a[~np.isfinite(a)][0]}")
    if (np.diff(a) <= 0).any():
        raise ValueError(f"{name} must be strictly increasing")
    a.flags.writeable = False
    return a


def _array(name: str, values: Any, shape: tuple[int, ...], dims: str) -> np.ndarray:
    a = np.array(values, dtype=float)
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {dims} = {shape}, got {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{name} must be finite; got {a[index]} at index {index}")
    a.flags.writeable = False
    return a


def _cell(axis: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower node index and weight of linear interpolation on a non-periodic axis (x in
    range; the last node belongs to the last cell, weight 1)."""
    i = np.clip(np.searchsorted(axis, x, side="right") - 1, 0, len(axis) - 2)
    return i, (x - axis[i]) / (axis[i + 1] - axis[i])
