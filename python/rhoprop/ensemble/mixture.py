"""Gaussian mixtures: the ensemble PDF of orbit positions over several density models.

Each density model gives a Gaussian PDF of the orbit position (mean and covariance); the
ensemble PDF is their mixture, with equal weights by default (paper) or user weights.
:class:`GaussianMixture` evaluates it, samples it, marginalises/projects it, gives 1-D
cdf/quantiles/intervals and counts the modes of the mixture density.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .. import _validate

_LOG_2PI = math.log(2.0 * math.pi)
_erfc = np.vectorize(math.erfc, otypes=[float])


def _float_array(name: str, value: object) -> np.ndarray:
    """``value`` as a new float64 array; TypeError if it is not real numbers."""
    try:
        arr = np.asarray(value)
    except ValueError as err:  # ragged nested sequences
        raise ValueError(f"{name} must be a rectangular array of numbers: {err}") from err
    if arr.dtype.kind == "O":  # e.g. Fractions, Decimals, None
        if not all(_validate.is_real(v) for v in arr.flat):
            raise TypeError(f"{name} must be real numbers, got {value!r}")
        arr = arr.astype(float)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be real numbers, got dtype {arr.dtype}")
    return np.array(arr, dtype=float)


def _read_only(arr: np.ndarray) -> np.ndarray:
    arr.flags.writeable = False
    return arr


def _solve_lower(chol: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Forward substitution ``chol @ z.T = rhs.T`` for lower-triangular ``chol`` (d, d)
    and many right-hand sides ``rhs`` (n, d); returns z (n, d)."""
    z = np.empty_like(rhs)
    for j in range(chol.shape[0]):
        z[:, j] = (rhs[:, j] - z[:, :j] @ chol[j, :j]) / chol[j, j]
    return z


def _check_probability(name: str, value: object) -> np.ndarray:
    """Finite probabilities strictly inside (0, 1) as a float array."""
    p = _float_array(name, value)
    if not np.all((p > 0.0) & (p < 1.0)):
        bad = p[~((p > 0.0) & (p < 1.0))].flat[0]
        raise ValueError(f"{name} must be in the open interval (0, 1), got {bad}")
    return p


class GaussianMixture:
    """Mixture ``p(x) = sum_i w_i N(x; mu_i, C_i)`` of k Gaussians in d >= 1 dimensions.

    Parameters
    ----------
    weights : (k,) or None
        Finite, >= 0, with a positive sum; normalised to sum 1. Zero weights are allowed
        (the component is kept but contributes nothing). None gives equal weights (the
        paper's default ensemble).
    means : (k, d), or (k,) for d = 1
    covariances : (k, d, d), or variances (k,) for d = 1
        Symmetric positive definite (checked with a Cholesky factorisation; symmetric to
        a relative 1e-10, then symmetrised).

    Raises TypeError for non-numeric input and ValueError naming the component for wrong
    shapes, NaN/inf, non-symmetric or non-positive-definite covariances. The object is
    immutable: all stored arrays are read-only.
    """

    __slots__ = (
        "_chol",
        "_covariances",
        "_log_det",
        "_log_weights",
        "_means",
        "_precisions",
        "_weights",
    )

    def __init__(self, weights: object, means: object, covariances: object) -> None:
        self._means = _read_only(self._check_means(means))
        k, d = self._means.shape
        if weights is None:
            weights = np.ones(k)
        self._weights = _read_only(self._check_weights(weights, k))
        self._covariances = _read_only(self._check_covariances(covariances, k, d))
        self._chol = _read_only(self._factorise(self._covariances))
        self._precisions = _read_only(self._inverse(self._chol))
        diag = np.diagonal(self._chol, axis1=1, axis2=2)
        self._log_det = _read_only(2.0 * np.log(diag).sum(axis=1))
        with np.errstate(divide="ignore"):
            self._log_weights = _read_only(np.log(self._weights))

    # ------------------------------------------------------------------ validation

    @staticmethod
    def _check_weights(weights: object, k: int) -> np.ndarray:
        w = _float_array("weights", weights)
        if w.shape != (k,):
            raise ValueError(f"weights must have shape (k={k},) like means, got {w.shape}")
        for i, wi in enumerate(w):
            if not math.isfinite(wi) or wi < 0.0:
                raise ValueError(f"weights[{i}] must be finite and >= 0, got {wi}")
        total = w.sum()
        if not total > 0.0 or not math.isfinite(total):
            raise ValueError(f"weights must have a finite positive sum, got {total}")
        return np.asarray(w / total)

    @staticmethod
    def _check_means(means: object) -> np.ndarray:
        mu = _float_array("means", means)
        if mu.ndim == 1:
            mu = mu[:, None]
        if mu.ndim != 2 or mu.shape[0] == 0 or mu.shape[1] == 0:
            raise ValueError(f"means must have shape (k, d) or (k,), k, d >= 1, got {mu.shape}")
        for i, row in enumerate(mu):
            if not np.all(np.isfinite(row)):
                raise ValueError(f"means[{i}] (component {i}) contains NaN or inf: {row}")
        return mu

    @staticmethod
    def _check_covariances(covariances: object, k: int, d: int) -> np.ndarray:
        cov = _float_array("covariances", covariances)
        if cov.ndim == 1 and d == 1:
            cov = cov[:, None, None]
        if cov.ndim != 3 or cov.shape[0] != k:
            expected = f"(k={k}, {d}, {d})" + (f" or (k={k},)" if d == 1 else "")
            raise ValueError(f"covariances must have shape {expected}, got {cov.shape}")
        for i, c in enumerate(cov):
            if c.shape != (d, d):
                raise ValueError(
                    f"covariances[{i}] (component {i}) must have shape ({d}, {d}), got {c.shape}"
                )
            if not np.all(np.isfinite(c)):
                raise ValueError(f"covariances[{i}] (component {i}) contains NaN or inf")
            asym = np.max(np.abs(c - c.T))
            if asym > 1e-10 * np.max(np.abs(c)):
                raise ValueError(
                    f"covariances[{i}] (component {i}) is not symmetric "
                    f"(max |C - C^T| = {asym:.3g})"
                )
        return np.asarray(0.5 * (cov + np.swapaxes(cov, 1, 2)))

    @staticmethod
    def _inverse(chol: np.ndarray) -> np.ndarray:
        """Inverse covariances (k, d, d) from the lower Cholesky factors (k, d, d)."""
        eye = np.eye(chol.shape[1])
        inv_chol = np.stack([_solve_lower(c, eye).T for c in chol])  # L^-1
        return np.asarray(np.einsum("kji,kjl->kil", inv_chol, inv_chol))  # L^-T L^-1

    @staticmethod
    def _factorise(cov: np.ndarray) -> np.ndarray:
        """Lower Cholesky factors (k, d, d); ValueError naming the first non-SPD component."""
        chol = np.empty_like(cov)
        for i, c in enumerate(cov):
            try:
                chol[i] = np.linalg.cholesky(c)
            except np.linalg.LinAlgError as err:
                raise ValueError(
                    f"covariances[{i}] (component {i}) is not positive definite"
                ) from err
        return chol

    # ------------------------------------------------------------------ properties

    @property
    def dim(self) -> int:
        """Dimension d of the space."""
        return int(self._means.shape[1])

    @property
    def n_components(self) -> int:
        """Number k of components (including zero-weight ones)."""
        return int(self._weights.shape[0])

    @property
    def weights(self) -> np.ndarray:
        """Normalised weights (k,), read-only."""
        return self._weights

    @property
    def means(self) -> np.ndarray:
        """Component means (k, d), read-only (also for d = 1)."""
        return self._means

    @property
    def covariances(self) -> np.ndarray:
        """Component covariances (k, d, d), read-only (also for d = 1)."""
        return self._covariances

    def __repr__(self) -> str:
        return f"GaussianMixture(n_components={self.n_components}, dim={self.dim})"

    # ------------------------------------------------------------------ density

    def _points(self, x: object) -> tuple[np.ndarray, tuple[int, ...]]:
        """Points ``x`` (..., d) as (n, d) plus the batch shape (...). For d = 1 a trailing
        axis of length 1 is read as the coordinate axis, otherwise x (...) is elementwise."""
        arr = _float_array("x", x)
        d = self.dim
        if d == 1 and (arr.ndim == 0 or arr.shape[-1] != 1):
            arr = arr[..., None]
        if arr.ndim == 0 or arr.shape[-1] != d:
            raise ValueError(f"x must have shape (..., {d}), got {arr.shape}")
        return arr.reshape(-1, d), arr.shape[:-1]

    def _component_logpdf(self, x: np.ndarray) -> np.ndarray:
        """log N(x_n; mu_i, C_i) for points x (n, d): (n, k), by Cholesky solves."""
        out = np.empty((x.shape[0], self.n_components))
        for i in range(self.n_components):
            z = _solve_lower(self._chol[i], x - self._means[i])
            out[:, i] = -0.5 * (self.dim * _LOG_2PI + self._log_det[i] + np.sum(z * z, axis=1))
        return out

    def _log_joint(self, x: np.ndarray) -> np.ndarray:
        """log(w_i N_i(x_n)) (n, k)."""
        return np.asarray(self._component_logpdf(x) + self._log_weights)

    @staticmethod
    def _logsumexp(a: np.ndarray) -> np.ndarray:
        """log(sum(exp(a), axis=1)) for a (n, k), stable; -inf rows stay -inf."""
        top = np.max(a, axis=1)
        top = np.where(np.isfinite(top), top, 0.0)
        with np.errstate(divide="ignore"):
            return np.asarray(top + np.log(np.sum(np.exp(a - top[:, None]), axis=1)))

    def _responsibilities(self, x: np.ndarray) -> np.ndarray:
        """Posterior component probabilities p(i | x_n) (n, k)."""
        log_joint = self._log_joint(x)
        return np.asarray(np.exp(log_joint - self._logsumexp(log_joint)[:, None]))

    def logpdf(self, x: object) -> np.ndarray:
        """Log density at x (..., d) (or (...,) for d = 1) -> (...)."""
        pts, shape = self._points(x)
        return self._logsumexp(self._log_joint(pts)).reshape(shape)

    def pdf(self, x: object) -> np.ndarray:
        """Density at x (..., d) (or (...,) for d = 1) -> (...)."""
        # A numpy float for a single point, as np.exp of a 0-d array gives.
        density: np.ndarray = np.exp(self.logpdf(x))
        return density

    # ------------------------------------------------------------------ moments, sampling

    def mean(self) -> np.ndarray:
        """Mixture mean (d,): ``sum_i w_i mu_i``."""
        return np.asarray(self._weights @ self._means)

    def covariance(self) -> np.ndarray:
        """Mixture covariance (d, d) by the law of total covariance:
        ``sum_i w_i C_i + sum_i w_i (mu_i - m)(mu_i - m)^T``."""
        dev = self._means - self.mean()
        within = np.einsum("k,kij->ij", self._weights, self._covariances)
        between = (self._weights[:, None] * dev).T @ dev
        return np.asarray(within + between)

    def sample(
        self, n: int, seed: int | np.random.SeedSequence | np.random.Generator | None = None
    ) -> np.ndarray:
        """``n`` independent draws (n, d). Components are chosen by weight with
        ``numpy.random.default_rng(seed)``, then ``mu_i + L_i z`` with z standard normal;
        the same seed gives the same samples."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
            raise TypeError(f"n must be an integer, got {type(n).__name__}")
        if n < 0:
            raise ValueError(f"n must be >= 0, got {n}")
        rng = np.random.default_rng(seed)
        comp = rng.choice(self.n_components, size=int(n), p=self._weights)
        z = rng.standard_normal((int(n), self.dim))
        return np.asarray(self._means[comp] + np.einsum("nij,nj->ni", self._chol[comp], z))

    # ------------------------------------------------------------------ marginals

    def marginal(
        self, direction: object = None, *, axes: int | Sequence[int] | None = None
    ) -> GaussianMixture:
        """Marginal mixture, same weights. Give exactly one of:

        ``axes`` : int or sequence of ints
            Coordinates to keep (in that order): a mixture of dimension len(axes).
        ``direction`` : (d,)
            Project onto this direction, **normalised to unit length first**: the 1-D
            mixture of ``u . x`` with ``u = direction / |direction|`` (means ``u . mu_i``,
            variances ``u^T C_i u``).
        """
        if (direction is None) == (axes is None):
            raise ValueError("give exactly one of direction and axes")
        if axes is not None:
            return self._marginal_axes(axes)
        return self._projection(direction)

    def _marginal_axes(self, axes: int | Sequence[int]) -> GaussianMixture:
        idx = [axes] if isinstance(axes, (int, np.integer)) else list(axes)
        for a in idx:
            if isinstance(a, bool) or not isinstance(a, (int, np.integer)):
                raise TypeError(f"axes must be integers, got {a!r}")
            if not -self.dim <= a < self.dim:
                raise ValueError(f"axis {a} out of range for dim {self.dim}")
        idx = [int(a) % self.dim for a in idx]
        if not idx or len(set(idx)) != len(idx):
            raise ValueError(f"axes must be non-empty and distinct, got {axes!r}")
        sub = self._covariances[:, idx][:, :, idx]
        return GaussianMixture(self._weights, self._means[:, idx], sub)

    def _projection(self, direction: object) -> GaussianMixture:
        u = _float_array("direction", direction)
        if u.shape != (self.dim,):
            raise ValueError(f"direction must have shape ({self.dim},), got {u.shape}")
        norm = np.linalg.norm(u)
        if not np.isfinite(norm) or norm == 0.0:
            raise ValueError(f"direction must be finite and non-zero, got {u}")
        u = u / norm
        variances = np.einsum("i,kij,j->k", u, self._covariances, u)
        return GaussianMixture(self._weights, self._means @ u, variances)

    # ------------------------------------------------------------------ 1-D distribution

    def _require_1d(self, what: str) -> None:
        if self.dim != 1:
            raise ValueError(
                f"{what} is defined for 1-D mixtures only, this one has dim={self.dim}; "
                "use marginal() first"
            )

    def _sigmas(self) -> np.ndarray:
        """Component standard deviations (k,) of a 1-D mixture."""
        return np.asarray(np.sqrt(self._covariances[:, 0, 0]))

    def _cdf_flat(self, x: np.ndarray) -> np.ndarray:
        """cdf at x (n,) of a 1-D mixture: ``sum_i w_i Phi((x - mu_i) / s_i)``."""
        t = (x[:, None] - self._means[:, 0]) / self._sigmas()
        return np.asarray((0.5 * _erfc(-t / math.sqrt(2.0))) @ self._weights)

    def cdf(self, x: object) -> np.ndarray:
        """Cumulative distribution at x (...) (or (..., 1)) -> (...); 1-D mixtures only.
        Uses ``Phi(t) = erfc(-t / sqrt 2) / 2`` (math.erfc), accurate in the lower tail."""
        self._require_1d("cdf")
        pts, shape = self._points(x)
        return self._cdf_flat(pts[:, 0]).reshape(shape)

    def quantile(self, q: object) -> np.ndarray:
        """Inverse cdf at probabilities q (...) in (0, 1) -> (...); 1-D mixtures only.

        Safeguarded Newton iteration on the cdf inside a bracket that is guaranteed to hold
        the root (bisection whenever Newton leaves it), to ~1e-13 relative accuracy in x
        (limited by the accuracy of the cdf, ~1e-16 absolute)."""
        self._require_1d("quantile")
        p = _check_probability("q", q)
        shape, p = p.shape, p.ravel()
        lo, hi = self._quantile_bracket(p)
        x = 0.5 * (lo + hi)
        scale = float(np.min(self._sigmas()[self._weights > 0]))
        for _ in range(200):
            f = self._cdf_flat(x) - p
            lo = np.where(f < 0.0, x, lo)
            hi = np.where(f > 0.0, x, hi)
            dens = np.exp(self._component_logpdf(x[:, None])) @ self._weights
            with np.errstate(divide="ignore", invalid="ignore"):
                newton = x - f / dens
            ok = np.isfinite(newton) & (newton > lo) & (newton < hi)
            new = np.where(ok, newton, 0.5 * (lo + hi))
            new = np.where(f == 0.0, x, new)
            step = np.abs(new - x)
            x = new
            if np.all(step <= 1e-14 * (np.abs(x) + scale)):
                break
        return np.asarray(x.reshape(shape))

    def _quantile_bracket(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) with cdf(lo) <= p <= cdf(hi): the standard normal tail bound
        ``P(Z > t) <= exp(-t^2 / 2)`` with ``t = sqrt(2 ln(1 / min(p, 1 - p)))``."""
        sig = self._sigmas()
        mu = self._means[:, 0]
        t = np.sqrt(2.0 * np.log(1.0 / np.minimum(p, 1.0 - p))) + 1.0
        lo = np.min(mu - sig * t[:, None], axis=1)
        hi = np.max(mu + sig * t[:, None], axis=1)
        return lo, hi

    def interval(self, level: float = 0.95) -> tuple[float, float]:
        """Central interval ``(quantile((1 - level) / 2), quantile((1 + level) / 2))`` of a
        1-D mixture; ``level`` in (0, 1)."""
        self._require_1d("interval")
        lev = float(_check_probability("level", level))
        low, high = self.quantile([0.5 * (1.0 - lev), 0.5 * (1.0 + lev)])
        return float(low), float(high)

    # ------------------------------------------------------------------ modes

    def modes(self, tol: float = 1e-4, *, max_iter: int = 1000) -> np.ndarray:
        """Distinct local maxima (m, d) of the mixture density, highest density first.

        This is the honest multimodality indicator: it counts modes of the mixture
        *density*, not components -- two (or more) overlapping components can merge into
        a single mode (e.g. two equal-weight, equal-variance 1-D normals are bimodal only
        when their means are more than 2 sigma apart).

        Method: the fixed-point (mean-shift) iteration for Gaussian mixtures of
        Carreira-Perpinan (2000, IEEE TPAMI 22(11)),
        ``x <- (sum_i r_i(x) C_i^-1)^-1 sum_i r_i(x) C_i^-1 mu_i`` with ``r_i(x)`` the
        posterior component probabilities, started from every (positive-weight) component
        mean and run until the step is below ``1e-3 tol s`` (at most ``max_iter`` steps);
        ``s`` is the smallest component standard deviation (square root of the smallest
        covariance eigenvalue), and merged (below). Single stops are then polished by
        Newton steps with the analytic gradient and Hessian while the Hessian is negative
        definite (this only matters at nearly degenerate modes, where mean-shift converges
        slowly). Points
        closer than ``tol s`` are merged, and a point is kept only if the analytic Hessian
        of the density is negative definite there, or, at a flat top whose curvature
        vanishes to rounding, if the density falls ``s / 100`` away along the flat
        directions (the iteration can also stop at a saddle or minimum, e.g. by symmetry).
        A mode not reached from any component mean is missed; this is rare, but in d >= 2
        a mixture can have more modes than components (Carreira-Perpinan & Williams 2003).
        """
        tol = float(tol)
        if not (math.isfinite(tol) and tol > 0.0):
            raise ValueError(f"tol must be finite and > 0, got {tol}")
        active = self._weights > 0.0
        scale = float(np.sqrt(np.min(np.linalg.eigvalsh(self._covariances[active]))))
        step_tol = 1e-3 * tol * scale
        points = self._mean_shift(self._means[active].copy(), step_tol, max_iter)
        # Merged before the polish too: stops on both sides of a flat top average to its
        # middle, which a Newton step from either side would overshoot.
        points, sizes = self._merge(points, tol * scale)
        polish = [n == 1 for n in sizes]
        points = np.array(
            [
                self._newton_polish(p, step_tol, scale) if k else p
                for p, k in zip(points, polish, strict=True)
            ]
        )
        candidates, _ = self._merge(points, tol * scale)
        keep = [self._is_local_maximum(c, scale) for c in candidates]
        return np.asarray(candidates[np.array(keep, dtype=bool)])

    def n_modes(self, tol: float = 1e-4) -> int:
        """Number of distinct local maxima of the mixture density: ``len(modes(tol))``."""
        return len(self.modes(tol))

    def _mean_shift(self, x: np.ndarray, step_tol: float, max_iter: int) -> np.ndarray:
        """Fixed-point iteration from the points x (m, d) until every step < step_tol."""
        prec = self._precisions
        prec_mu = np.einsum("kij,kj->ki", prec, self._means)
        for _ in range(max_iter):
            r = self._responsibilities(x)
            lhs = np.einsum("mk,kij->mij", r, prec)
            new = np.linalg.solve(lhs, (r @ prec_mu)[:, :, None])[:, :, 0]
            step = np.linalg.norm(new - x, axis=1)
            x = new
            if np.all(step < step_tol):
                break
        return x

    def _newton_polish(
        self, x: np.ndarray, step_tol: float, max_step: float, max_iter: int = 100
    ) -> np.ndarray:
        """Newton steps ``x <- x - H^-1 grad`` from x (d,) towards a local maximum, while
        the Hessian is negative definite, the step is shorter than ``max_step`` and the
        density does not fall (at a flat top gradient and Hessian are rounding, and a
        step would only wander off the middle)."""
        for _ in range(max_iter):
            hess = self._scaled_hessian(x)
            if not self._negative_definite(hess):
                break
            step = np.linalg.solve(hess, self._scaled_gradient(x))
            size = float(np.linalg.norm(step))
            if not size < max_step:
                break
            if self.logpdf((x - step)[None, :])[0] < self.logpdf(x[None, :])[0]:
                break
            x = x - step
            if size < step_tol:
                break
        return x

    def _merge(self, points: np.ndarray, radius: float) -> tuple[np.ndarray, list[int]]:
        """Points (m, d) merged greedily, highest density first, within ``radius`` or with
        no dip of the density between them (two stops of the iteration on one flat,
        nearly degenerate mode, where mean-shift and Newton converge slowly). Each mode is
        the mean of the stops merged into it whose density equals the highest's to 1e-12
        (relative): on a flat top, where rounding cannot tell them apart, stops from
        either side average to its middle (not polished then: a Newton step there follows
        rounding). Also returns how many stops each mode merged."""
        dens = self.logpdf(points)
        order = np.argsort(-dens, kind="stable")
        groups: list[list[int]] = []
        for i in order:
            p = points[i]
            for group in groups:
                q = points[group[0]]
                if np.linalg.norm(p - q) < radius or not self._dip(p, q):
                    group.append(int(i))
                    break
            else:
                groups.append([int(i)])
        modes = [
            np.mean([points[i] for i in g if dens[i] >= dens[g[0]] - 1e-12], axis=0) for g in groups
        ]
        return np.array(modes), [len(g) for g in groups]

    def _dip(self, p: np.ndarray, q: np.ndarray, samples: int = 33) -> bool:
        """Whether the log-density falls below both ends somewhere on the segment p-q."""
        f = np.linspace(0.0, 1.0, samples)[1:-1, None]
        inner = self.logpdf(p[None, :] + f * (q - p)[None, :])
        ends = self.logpdf(np.stack([p, q]))
        return bool(np.min(inner) < np.min(ends) - 1e-12)

    def _scaled_gradient(self, x: np.ndarray) -> np.ndarray:
        """Gradient of the density divided by the density at x (d,):
        ``-sum_i r_i g_i`` with ``g_i = C_i^-1 (x - mu_i)``."""
        r = self._responsibilities(x[None, :])[0]
        g = np.einsum("kij,kj->ki", self._precisions, x - self._means)
        return np.asarray(-(r @ g))

    def _scaled_hessian(self, x: np.ndarray) -> np.ndarray:
        """Analytic Hessian of the density divided by the density at x (d,) -> (d, d):
        ``sum_i r_i (g_i g_i^T - C_i^-1)`` with ``g_i = C_i^-1 (x - mu_i)``."""
        prec = self._precisions
        r = self._responsibilities(x[None, :])[0]
        g = np.einsum("kij,kj->ki", prec, x - self._means)
        return np.asarray(np.einsum("k,ki,kj->ij", r, g, g) - np.einsum("k,kij->ij", r, prec))

    @staticmethod
    def _negative_definite(matrix: np.ndarray) -> bool:
        """True if the symmetric ``matrix`` is negative definite (Cholesky of its negative)."""
        try:
            np.linalg.cholesky(-matrix)
        except np.linalg.LinAlgError:
            return False
        return True

    def _is_local_maximum(self, x: np.ndarray, scale: float) -> bool:
        """True if x (d,) is a local maximum of the density: its Hessian is negative
        definite or, where it is degenerate (a flat top, e.g. two equal normals exactly
        2 sigma apart, whose Hessian vanishes to rounding), negative semidefinite with the
        density lower ``scale / 100`` away along every direction of vanishing curvature
        (``scale``: the smallest component sigma; a quartic top falls by ~1e-9 there, far
        above the rounding of the log-density)."""
        hess = self._scaled_hessian(x)
        if self._negative_definite(hess):
            return True
        eigval, eigvec = np.linalg.eigh(hess)
        # Curvature indistinguishable from rounding of the Hessian's O(1/s^2) terms
        # (s = scale, the smallest component sigma): below sqrt(eps) / s^2.
        flat = 1.5e-8 / scale**2
        if np.any(eigval > flat):
            return False
        probes = eigvec[:, np.abs(eigval) <= flat].T * (0.01 * scale)
        centre = float(self.logpdf(x[None, :])[0])
        around = self.logpdf(np.concatenate([x + probes, x - probes]))
        return bool(np.all(around < centre))
