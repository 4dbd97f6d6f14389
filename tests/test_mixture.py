"""GaussianMixture against scipy.stats, closed forms, quadrature and sample moments."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats
from scipy.special import logsumexp

from rhoprop.ensemble.mixture import GaussianMixture

EPS = np.finfo(float).eps


def random_spd(rng: np.random.Generator, d: int) -> np.ndarray:
    """A well-conditioned random SPD matrix (d, d)."""
    a = rng.standard_normal((d, d))
    return a @ a.T + d * np.eye(d)


def mixture_2d() -> GaussianMixture:
    return GaussianMixture(
        [0.5, 0.3, 0.2],
        [[0.0, 0.0], [3.0, -1.0], [-2.0, 4.0]],
        [
            [[1.0, 0.3], [0.3, 2.0]],
            [[0.5, -0.2], [-0.2, 0.8]],
            [[2.0, 0.9], [0.9, 1.5]],
        ],
    )


def mixture_1d() -> GaussianMixture:
    return GaussianMixture([0.6, 0.4], [0.0, 3.0], [1.0, 0.25])


# ---------------------------------------------------------------- densities


def test_single_component_matches_scipy_multivariate_normal():
    rng = np.random.default_rng(1)
    mean, cov = rng.standard_normal(3), random_spd(rng, 3)
    g = GaussianMixture([1.0], [mean], [cov])
    x = mean + 2.0 * rng.standard_normal((4, 5, 3))
    ref = stats.multivariate_normal(mean, cov)
    assert g.logpdf(x).shape == (4, 5)
    np.testing.assert_allclose(g.logpdf(x), ref.logpdf(x), rtol=1e-12)
    np.testing.assert_allclose(g.pdf(x), ref.pdf(x), rtol=1e-10)
    assert g.logpdf(mean).shape == ()


def test_single_component_1d_matches_scipy_norm():
    g = GaussianMixture([1.0], [1.5], [4.0])
    ref = stats.norm(1.5, 2.0)
    x = np.linspace(-15.0, 15.0, 61)  # down to -8.25 sigma: the cdf is ~1e-16 there
    np.testing.assert_allclose(g.logpdf(x), ref.logpdf(x), rtol=1e-12)
    np.testing.assert_allclose(g.pdf(x), ref.pdf(x), rtol=1e-10)
    np.testing.assert_allclose(g.cdf(x), ref.cdf(x), rtol=1e-10, atol=1e-16)
    q = np.array([1e-12, 1e-6, 0.01, 0.3, 0.5, 0.77, 0.99, 1.0 - 1e-9])
    np.testing.assert_allclose(g.quantile(q), ref.ppf(q), rtol=1e-10, atol=1e-12)


def test_1d_shapes():
    g = mixture_1d()
    x = np.linspace(-1.0, 1.0, 5)
    assert g.pdf(x).shape == (5,)
    assert g.pdf(x[:, None]).shape == (5,)  # a trailing axis of length d = 1
    assert g.pdf(np.zeros((2, 3))).shape == (2, 3)
    assert g.pdf(0.5).shape == ()
    assert g.cdf(x.reshape(5, 1)).shape == (5,)
    assert g.quantile([[0.1, 0.2]]).shape == (1, 2)
    assert g.means.shape == (2, 1) and g.covariances.shape == (2, 1, 1)


def test_mixture_pdf_is_weighted_sum_of_scipy_components():
    g = mixture_2d()
    x = np.random.default_rng(2).uniform(-5.0, 6.0, size=(200, 2))
    ref = sum(
        w * stats.multivariate_normal(m, c).pdf(x)
        for w, m, c in zip(g.weights, g.means, g.covariances, strict=True)
    )
    np.testing.assert_allclose(g.pdf(x), ref, rtol=1e-10)


def test_logpdf_is_stable_far_in_the_tails():
    # pdf underflows to 0 at these points; logpdf must still be finite and exact.
    g = mixture_2d()
    x = np.array([[80.0, -60.0], [-200.0, 10.0]])
    comps = np.stack(
        [
            np.log(w) + stats.multivariate_normal(m, c).logpdf(x)
            for w, m, c in zip(g.weights, g.means, g.covariances, strict=True)
        ]
    )
    assert np.all(g.pdf(x) == 0.0)
    np.testing.assert_allclose(g.logpdf(x), logsumexp(comps, axis=0), rtol=1e-12)


# ---------------------------------------------------------------- moments and sampling


def test_mean_and_covariance_closed_form():
    g = mixture_2d()
    w, mu, cov = g.weights, g.means, g.covariances
    mean = sum(w[i] * mu[i] for i in range(3))
    second = sum(w[i] * (cov[i] + np.outer(mu[i], mu[i])) for i in range(3))
    np.testing.assert_allclose(g.mean(), mean, rtol=1e-14)
    np.testing.assert_allclose(g.covariance(), second - np.outer(mean, mean), rtol=1e-12)


def test_sample_moments_match_within_standard_errors():
    g = mixture_2d()
    n = 200_000
    x = g.sample(n, seed=3)
    assert x.shape == (n, 2)
    mean, cov = g.mean(), g.covariance()
    # Sample mean: standard error sqrt(C_jj / n); allow 5 standard errors.
    np.testing.assert_array_less(np.abs(x.mean(axis=0) - mean), 5.0 * np.sqrt(np.diag(cov) / n))
    # Sample covariance entry (j, l): standard error std((x_j - m_j)(x_l - m_l)) / sqrt(n),
    # estimated from the sample itself (the mixture is not Gaussian); 5 standard errors.
    dev = x - x.mean(axis=0)
    products = dev[:, :, None] * dev[:, None, :]
    se = products.std(axis=0) / math.sqrt(n)
    np.testing.assert_array_less(np.abs(products.mean(axis=0) - cov), 5.0 * se)


def test_1d_samples_follow_the_cdf():
    # Kolmogorov-Smirnov test of 20k draws against the mixture cdf; the seed is fixed, so
    # this is deterministic, and p > 0.01 holds for 99 % of seeds.
    g = mixture_1d()
    x = g.sample(20_000, seed=4)[:, 0]
    assert stats.kstest(x, g.cdf).pvalue > 0.01


def test_sample_is_reproducible():
    g = mixture_2d()
    np.testing.assert_array_equal(g.sample(100, seed=5), g.sample(100, seed=5))
    assert not np.array_equal(g.sample(100, seed=5), g.sample(100, seed=6))
    assert g.sample(0, seed=1).shape == (0, 2)


# ---------------------------------------------------------------- marginals and projections


def test_marginal_over_axes_is_the_analytic_sub_mixture():
    rng = np.random.default_rng(7)
    means = rng.standard_normal((3, 3))
    covs = np.stack([random_spd(rng, 3) for _ in range(3)])
    g = GaussianMixture([1.0, 2.0, 3.0], means, covs)
    m = g.marginal(axes=[2, 0])
    np.testing.assert_array_equal(m.weights, g.weights)
    np.testing.assert_array_equal(m.means, means[:, [2, 0]])
    np.testing.assert_array_equal(m.covariances, covs[:, [2, 0]][:, :, [2, 0]])
    m1 = g.marginal(axes=-2)
    assert m1.dim == 1
    np.testing.assert_array_equal(m1.covariances[:, 0, 0], covs[:, 1, 1])


def test_marginal_pdf_equals_the_joint_pdf_integrated_over_the_other_axis():
    g = mixture_2d()
    m = g.marginal(axes=1)
    x1 = np.linspace(-4.0, 8.0, 7)
    # Trapezoid rule over x0 in [-20, 20] (> 10 sigma beyond every component), step 0.01:
    # for a smooth, rapidly decaying integrand it is spectrally accurate, so 1e-10.
    x0 = np.linspace(-20.0, 20.0, 4001)
    grid = np.stack(np.meshgrid(x0, x1, indexing="ij"), axis=-1)  # (4001, 7, 2)
    integral = np.trapezoid(g.pdf(grid), x0, axis=0)
    np.testing.assert_allclose(m.pdf(x1), integral, rtol=1e-10)
    assert np.trapezoid(m.pdf(x0), x0) == pytest.approx(1.0, rel=1e-10)


def test_projection_equals_the_marginal_of_the_rotated_mixture():
    rng = np.random.default_rng(8)
    means = 2.0 * rng.standard_normal((4, 3))
    covs = np.stack([random_spd(rng, 3) for _ in range(4)])
    g = GaussianMixture(None, means, covs)
    rot = np.linalg.qr(rng.standard_normal((3, 3)))[0]  # orthogonal, rows orthonormal
    rotated = GaussianMixture(None, means @ rot.T, rot @ covs @ rot.T)
    expected = rotated.marginal(axes=0)
    projected = g.marginal(-3.5 * rot[0])  # unnormalised (and flipped) direction
    np.testing.assert_allclose(projected.means, -expected.means, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(projected.covariances, expected.covariances, rtol=1e-12)
    x = np.linspace(-8.0, 8.0, 33)
    np.testing.assert_allclose(g.marginal(rot[0]).pdf(x), expected.pdf(x), rtol=1e-11)


# ---------------------------------------------------------------- 1-D distribution


def test_quantile_inverts_cdf():
    g = mixture_1d()
    x = np.linspace(-6.0, 5.0, 45)
    # The cdf is accurate to a few eps relative (erfc), so x is determined to about
    # eps * cdf / pdf; add the solver tolerance.
    tol = 1e-12 * (1.0 + np.abs(x)) + 8.0 * EPS * g.cdf(x) / g.pdf(x)
    np.testing.assert_array_less(np.abs(g.quantile(g.cdf(x)) - x), tol)
    q = np.array([1e-10, 1e-3, 0.2, 0.5, 0.6, 0.95, 1.0 - 1e-10])
    np.testing.assert_allclose(g.cdf(g.quantile(q)), q, rtol=1e-12, atol=4 * EPS)


def test_interval_of_a_single_normal():
    mu, sigma = 3.0, 0.5
    g = GaussianMixture([1.0], [mu], [sigma**2])
    low, high = g.interval(0.95)
    assert low == pytest.approx(mu - 1.959964 * sigma, rel=1e-7)
    assert high == pytest.approx(mu + 1.959964 * sigma, rel=1e-7)
    assert high == pytest.approx(stats.norm.ppf(0.975, mu, sigma), rel=1e-12)


def test_interval_of_a_mixture_holds_the_level():
    g = mixture_1d()
    low, high = g.interval(0.9)
    assert g.cdf(low) == pytest.approx(0.05, rel=1e-12)
    assert g.cdf(high) == pytest.approx(0.95, rel=1e-12)


# ---------------------------------------------------------------- modes


def two_normals(separation: float, weights=(1.0, 1.0)) -> GaussianMixture:
    return GaussianMixture(list(weights), [0.0, separation], [1.0, 1.0])


@pytest.mark.parametrize(
    ("separation", "expected"),
    # Equal weights and variances: bimodal iff the separation exceeds 2 sigma.
    [(1.0, 1), (1.5, 1), (1.9, 1), (2.0, 1), (2.1, 2), (3.0, 2), (6.0, 2)],
)
def test_two_equal_normals_are_bimodal_beyond_two_sigma(separation, expected):
    assert two_normals(separation).n_modes() == expected


def test_two_equal_normals_exactly_two_sigma_apart_have_one_flat_mode():
    """Exactly 2 sigma apart the top is quartic (the Hessian vanishes), and rounding
    once decided between 1 and 0 modes (11 of 300 placements gave 0). Any
    placement and scale must give the one mode, at the midpoint."""
    rng = np.random.default_rng(1)
    for _ in range(300):
        low, sigma = rng.uniform(-1e3, 1e3), 10 ** rng.uniform(-3, 3)
        g = GaussianMixture([1.0, 1.0], [low, low + 2 * sigma], [sigma**2, sigma**2])
        (mode,) = g.modes()
        # A quartic top: mean-shift stops ~1e-5 sigma from the midpoint.
        assert mode[0] == pytest.approx(low + sigma, abs=1e-4 * sigma)
        apart = GaussianMixture([1.0, 1.0], [low, low + 2.001 * sigma], [sigma**2] * 2)
        assert apart.n_modes() == 2


def test_modes_of_merged_and_separated_components():
    (single,) = two_normals(1.0).modes()
    assert single == pytest.approx([0.5], abs=1e-9)
    # At 6 sigma each mode sits within 6 exp(-18) ~ 1e-7 sigma of its mean.
    modes = two_normals(6.0, weights=(0.3, 0.7)).modes()
    np.testing.assert_allclose(modes[:, 0], [6.0, 0.0], atol=1e-6)  # highest first


def test_three_well_separated_components_in_3d():
    rng = np.random.default_rng(9)
    means = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 0.0, 12.0]])
    covs = np.stack([random_spd(rng, 3) / 3.0 for _ in range(3)])
    g = GaussianMixture([0.2, 0.5, 0.3], means, covs)
    modes = g.modes()
    assert modes.shape == (3, 3) and g.n_modes() == 3
    np.testing.assert_allclose(modes[np.argsort(modes[:, 0] + modes[:, 2])], means, atol=1e-6)


def test_a_weak_central_component_is_a_minimum_not_a_mode():
    # By symmetry the iteration started at 0 stays at 0; only the Hessian check decides.
    # p''(0) = sum_i w_i N_i(0) (mu_i^2 - 1) changes sign at w_middle ~ 0.074.
    weak = GaussianMixture([0.475, 0.05, 0.475], [-3.0, 0.0, 3.0], [1.0, 1.0, 1.0])
    strong = GaussianMixture([0.45, 0.1, 0.45], [-3.0, 0.0, 3.0], [1.0, 1.0, 1.0])
    assert weak.n_modes() == 2
    assert strong.n_modes() == 3
    assert np.any(np.abs(strong.modes()) < 1e-12)


def test_analytic_hessian_matches_finite_differences():
    g = mixture_2d()
    x, h = np.array([0.7, 1.3]), 1e-4
    steps = h * np.eye(2)
    fd = np.array(
        [
            [
                g.pdf(x + a + b) - g.pdf(x + a - b) - g.pdf(x - a + b) + g.pdf(x - a - b)
                for b in steps
            ]
            for a in steps
        ]
    ) / (4 * h * h)
    # Central differences: O(h^2) truncation plus eps * pdf / h^2 rounding, ~1e-7 relative.
    np.testing.assert_allclose(g.pdf(x) * g._scaled_hessian(x), fd, rtol=1e-5, atol=1e-9)


# ---------------------------------------------------------------- construction


def test_weights_are_normalised_and_equal_by_default():
    g = GaussianMixture([2.0, 6.0], [0.0, 1.0], [1.0, 1.0])
    np.testing.assert_allclose(g.weights, [0.25, 0.75], rtol=1e-15)
    same = GaussianMixture([0.25, 0.75], [0.0, 1.0], [1.0, 1.0])
    np.testing.assert_allclose(g.pdf([0.3, 2.0]), same.pdf([0.3, 2.0]), rtol=1e-15)
    np.testing.assert_allclose(GaussianMixture(None, [0.0, 1.0, 2.0], [1, 1, 1]).weights, 1 / 3)


def test_zero_weight_component_contributes_nothing():
    g = GaussianMixture([1.0, 0.0], [0.0, 10.0], [1.0, 1.0])
    x = np.linspace(-3.0, 13.0, 9)
    np.testing.assert_allclose(g.pdf(x), stats.norm.pdf(x), rtol=1e-12)
    assert g.n_modes() == 1


def test_immutable():
    means = np.array([[0.0, 1.0]])
    g = GaussianMixture([1.0], means, [np.eye(2)])
    for arr in (g.weights, g.means, g.covariances):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 1.0
    with pytest.raises(AttributeError):
        g.weights = np.ones(1)  # type: ignore[misc]
    means[0, 0] = 5.0  # the caller's array stays writeable and is not shared
    assert g.means[0, 0] == 0.0
    assert g.dim == 2 and g.n_components == 1
    assert repr(g) == "GaussianMixture(n_components=1, dim=2)"


@pytest.mark.parametrize(
    ("weights", "means", "covs", "match"),
    [
        ([[1.0, 1.0]], [0.0, 1.0], [1.0, 1.0], r"weights must have shape \(k=2,\)"),
        ([1.0, -0.5], [0.0, 1.0], [1.0, 1.0], r"weights\[1\] must be finite and >= 0"),
        ([1.0, np.nan], [0.0, 1.0], [1.0, 1.0], r"weights\[1\]"),
        ([0.0, 0.0], [0.0, 1.0], [1.0, 1.0], "positive sum"),
        ([1.0], np.zeros((1, 2, 2)), [np.eye(2)], "means must have shape"),
        ([1.0, 1.0], [[0.0, 1.0], [np.nan, 0.0]], [np.eye(2)] * 2, r"means\[1\].*NaN"),
        ([1.0, 1.0], [[0.0, 1.0]] * 2, [np.eye(2)], r"covariances must have shape \(k=2, 2, 2\)"),
        ([1.0], [[0.0, 1.0]], [np.eye(3)], r"covariances\[0\].*shape \(2, 2\)"),
        ([1.0, 1.0], [0.0, 1.0], [1.0, np.inf], r"covariances\[1\].*NaN or inf"),
        (
            [1.0, 1.0],
            [[0.0, 0.0]] * 2,
            [np.eye(2), [[1.0, 0.5], [0.2, 1.0]]],
            r"covariances\[1\] \(component 1\) is not symmetric",
        ),
        (
            [1.0, 1.0, 1.0],
            [[0.0, 0.0]] * 3,
            [np.eye(2), np.eye(2), [[1.0, 2.0], [2.0, 1.0]]],
            r"covariances\[2\] \(component 2\) is not positive definite",
        ),
        ([1.0, 1.0], [0.0, 1.0], [1.0, 0.0], r"covariances\[1\].*not positive definite"),
    ],
)
def test_invalid_construction(weights, means, covs, match):
    with pytest.raises(ValueError, match=match):
        GaussianMixture(weights, means, covs)


@pytest.mark.parametrize(
    ("weights", "means", "covs"),
    [
        (["a"], [0.0], [1.0]),
        ([1.0], "x", [1.0]),
        ([1.0], [0.0], [1j]),
        ([True], [0.0], [1.0]),
        ([1.0], [None], [1.0]),
    ],
)
def test_non_numeric_input_is_a_type_error(weights, means, covs):
    with pytest.raises(TypeError, match="real numbers"):
        GaussianMixture(weights, means, covs)


def test_invalid_calls():
    g1, g2 = mixture_1d(), mixture_2d()
    for q in (0.0, 1.0, -0.1, 1.5, np.nan, [0.5, 1.0]):
        with pytest.raises(ValueError, match=r"\(0, 1\)"):
            g1.quantile(q)
    with pytest.raises(ValueError, match=r"level must be in the open interval \(0, 1\)"):
        g1.interval(1.0)
    for method, arg in ((g2.cdf, [0.0, 0.0]), (g2.quantile, 0.5), (g2.interval, 0.9)):
        with pytest.raises(ValueError, match="1-D mixtures only, this one has dim=2"):
            method(arg)
    with pytest.raises(ValueError, match=r"x must have shape \(\.\.\., 2\)"):
        g2.pdf([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="exactly one"):
        g2.marginal()
    with pytest.raises(ValueError, match="exactly one"):
        g2.marginal([1.0, 0.0], axes=0)
    with pytest.raises(ValueError, match="out of range"):
        g2.marginal(axes=2)
    with pytest.raises(ValueError, match="distinct"):
        g2.marginal(axes=[0, -2])
    with pytest.raises(ValueError, match="non-zero"):
        g2.marginal([0.0, 0.0])
    with pytest.raises(ValueError, match=r"direction must have shape \(2,\)"):
        g2.marginal([1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="tol"):
        g2.modes(tol=-1.0)
    with pytest.raises(ValueError, match="n must be >= 0"):
        g2.sample(-1)
    with pytest.raises(TypeError, match="n must be an integer"):
        g2.sample(2.5)  # type: ignore[arg-type]
