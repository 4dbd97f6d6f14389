"""Probability of collision: NASA CARA's 2-D Pc unit-test cases, independent references
(the analytic isotropic case, scipy's dblquad), mixtures against pc_2d, the Monte Carlo
pair count against pc_2d and pc_mixture, and bad input."""

from __future__ import annotations

import itertools
import json
import math
import warnings

import numpy as np
import pytest
from scipy import integrate, special

import rhoprop as rp
from rhoprop.conjunction import pc_2d, pc_mixture, pc_monte_carlo
from rhoprop.conjunction.probability import SHAPES
from rhoprop.ensemble import GaussianMixture

CARA_SHAPES = {"circle": "circle", "square": "square", "squareEquArea": "square_equal_area"}


def _cara_cases(test_data):
    path = test_data / "conjunction" / "cara_2d_pc_cases.json"
    return json.loads(path.read_text())["cases"]


def _within(case, pc):
    tol = case["tolerance"]
    expected = case["expected_pc"]
    if tol["type"] == "rel":
        return abs(pc - expected) <= tol["value"] * abs(expected)
    assert tol["type"] == "abs"
    return abs(pc - expected) <= tol["value"]


def _rtn_rows(r, v):
    r, v = np.asarray(r, float), np.asarray(v, float)
    rh = r / np.linalg.norm(r)
    nh = np.cross(r, v) / np.linalg.norm(np.cross(r, v))
    return np.array([rh, np.cross(nh, rh), nh])


def _case_inputs(case):
    """(inertial covariances, RTN covariances) of both objects, 3x3 or 6x6."""
    c1, c2 = np.array(case["cov1"]), np.array(case["cov2"])
    if case["cov1_frame"].startswith("RTN"):
        assert case["cov2_frame"].startswith("RTN")
        return (np.array(case["cov1_eci_derived"]), np.array(case["cov2_eci_derived"])), (c1, c2)
    # Inertial cases: their RTN form, C_rtn = M^T C M with M = [R T N] (columns).
    m1, m2 = _rtn_rows(case["r1"], case["v1"]), _rtn_rows(case["r2"], case["v2"])
    return (c1, c2), (m1 @ c1 @ m1.T, m2 @ c2 @ m2.T)


def test_cara_cases_at_their_tolerances(test_data):
    cases = _cara_cases(test_data)
    assert len(cases) == 10
    for case in cases:
        (e1, e2), (t1, t2) = _case_inputs(case)
        common = {"shape": CARA_SHAPES[case["hbr_shape"]]}
        args = (case["r1"], case["v1"]), (case["r2"], case["v2"])
        inertial = pc_2d(*args[0], e1, *args[1], e2, case["hbr_m"], **common)
        rtn = pc_2d(*args[0], t1, *args[1], t2, case["hbr_m"], frame="rtn", **common)
        for out in (inertial, rtn):
            assert _within(case, out.pc), (case["name"], out.pc, case["expected_pc"])
            assert 0.0 <= out.pc <= 1.0
        # Both frames describe the same covariances.
        assert rtn.pc == pytest.approx(inertial.pc, rel=1e-9, abs=1e-15), case["name"]
        # Our quadrature agrees with the data file's independent dblquad far below the
        # CARA tolerance (its epsrel was 1e-11).
        check = case["my_pc_check"]["dblquad_epsrel1e-11"]
        assert inertial.pc == pytest.approx(check, rel=1e-8, abs=1e-15), case["name"]
        miss = np.linalg.norm(case["my_pc_check"]["encounter_plane_miss_m"])
        assert inertial.miss_distance == pytest.approx(miss, rel=1e-9)


def test_cara_npd_case_repaired_or_refused(test_data):
    (case,) = [c for c in _cara_cases(test_data) if "NonPD" in c["name"]]
    (e1, e2), (t1, t2) = _case_inputs(case)
    out = pc_2d(case["r1"], case["v1"], t1, case["r2"], case["v2"], t2, 20.0, frame="rtn")
    assert out.repaired
    assert abs(out.pc - 0.0) <= 1e-10
    np.linalg.cholesky(out.encounter_covariance)  # positive definite as repaired
    assert np.linalg.eigvalsh(out.projected_covariance)[0] < 0.0
    with pytest.raises(ValueError, match="not positive definite"):
        pc_2d(case["r1"], case["v1"], e1, case["r2"], case["v2"], e2, 20.0, npd="raise")


# ---------------------------------------------------------------------- references

LEO_R1 = np.array([7000e3, 0.0, 0.0])
LEO_V1 = np.array([0.0, 7500.0, 0.0])


def test_isotropic_zero_miss_is_analytic():
    # Pc = 1 - exp(-R^2 / (2 sigma^2)) (a Rayleigh-distributed radius).
    for sigma, hbr in [(50.0, 10.0), (3.0, 10.0), (2000.0, 5.0)]:
        cov = np.eye(3) * sigma**2 / 2.0  # two objects, half each
        out = pc_2d(LEO_R1, LEO_V1, cov, LEO_R1, [0.0, 100.0, 7400.0], cov, hbr)
        assert out.miss_distance == 0.0
        assert out.pc == pytest.approx(-math.expm1(-(hbr**2) / (2 * sigma**2)), rel=1e-9)


def _dblquad_circle(miss, cov, hbr):
    inv = np.linalg.inv(cov)
    norm = 1.0 / (2 * np.pi * math.sqrt(np.linalg.det(cov)))

    def density(z, x):
        u = np.array([x, z])
        return norm * math.exp(-0.5 * u @ inv @ u)

    def half(x):
        return math.sqrt(max(hbr**2 - (x - miss[0]) ** 2, 0.0))

    value, _ = integrate.dblquad(
        density,
        miss[0] - hbr,
        miss[0] + hbr,
        lambda x: miss[1] - half(x),
        lambda x: miss[1] + half(x),
        epsabs=0.0,
        epsrel=1e-11,
    )
    return value


def test_random_anisotropic_case_against_dblquad():
    rng = np.random.default_rng(18)
    for _ in range(3):
        a = rng.normal(size=(3, 3)) * [[300.0], [40.0], [90.0]]
        cov1 = a @ a.T
        b = rng.normal(size=(3, 3)) * 60.0
        cov2 = b @ b.T + np.eye(3)
        r2 = LEO_R1 + rng.normal(size=3) * 150.0
        v2 = np.array([-200.0, 3000.0, 6800.0]) + rng.normal(size=3)
        out = pc_2d(LEO_R1, LEO_V1, cov1, r2, v2, cov2, 25.0)
        reference = _dblquad_circle([out.miss_distance, 0.0], out.encounter_covariance, 25.0)
        assert reference > 1e-10
        assert out.pc == pytest.approx(reference, rel=1e-6)
        # The projection is what the definition says: P C P^T with P = [x; z].
        p = out.encounter_axes[[0, 2]]
        assert np.allclose(out.encounter_covariance, p @ (cov1 + cov2) @ p.T, rtol=1e-12)


def _conditional_reference(miss, cov, hbr, shape):
    """Pc by scipy quad over the encounter z axis with the conditional normal of x given
    z in closed form (the other axis and another parametrisation than the core's)."""
    (a, b), (_, c) = cov
    mx, mz = miss
    sz, sc, k = math.sqrt(c), math.sqrt((a * c - b * b) / c), b / c

    def prob(lo, hi):
        if lo > 0:
            return special.ndtr(-lo) - special.ndtr(-hi)
        return special.ndtr(hi) - special.ndtr(lo)

    def density(z):
        return math.exp(-0.5 * (z / sz) ** 2) / (sz * math.sqrt(2 * math.pi))

    if shape == "circle":

        def f(t):
            z = mz + hbr * math.sin(t)
            h = hbr * math.cos(t)
            return h * density(z) * prob((mx - h - k * z) / sc, (mx + h - k * z) / sc)

        lo, hi = max(-1.0, (-40 * sz - mz) / hbr), min(1.0, (40 * sz - mz) / hbr)
        if lo >= hi:
            return 0.0
        edges = np.linspace(math.asin(lo), math.asin(hi), 101)
    else:
        half = hbr if shape == "square" else math.sqrt(math.pi) / 2 * hbr

        def f(z):
            return density(z) * prob((mx - half - k * z) / sc, (mx + half - k * z) / sc)

        lo, hi = max(mz - half, -40 * sz), min(mz + half, 40 * sz)
        if lo >= hi:
            return 0.0
        edges = np.linspace(lo, hi, 101)
    return sum(
        integrate.quad(f, x0, x1, epsabs=0.0, epsrel=1e-13, limit=200)[0]
        for x0, x1 in itertools.pairwise(edges)
    )


def test_random_geometries_against_an_independent_quadrature():
    rng = np.random.default_rng(5)
    checked = 0
    for _ in range(40):
        l1 = 10 ** rng.uniform(-2, 6)
        l2 = l1 * 10 ** rng.uniform(-5, 0)
        th = rng.uniform(0, np.pi)
        e = np.array([math.cos(th), math.sin(th)])
        f = np.array([-e[1], e[0]])
        cov2d = l1 * np.outer(e, e) + l2 * np.outer(f, f)
        hbr = 10 ** rng.uniform(-1, 2)
        miss = rng.uniform(0.01, 6) * math.sqrt(l1) * rng.choice([0.05, 0.3, 1.0])
        # Relative velocity along Y and miss along X: encounter axes x = X, z = Z.
        cov = np.zeros((3, 3))
        cov[np.ix_([0, 2], [0, 2])] = cov2d
        cov[1, 1] = 1.0
        r2, v2 = np.array([miss, 0.0, 0.0]), np.array([0.0, 1000.0, 0.0])
        for shape in SHAPES:
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", integrate.IntegrationWarning)
                reference = _conditional_reference([miss, 0.0], cov2d, hbr, shape)
            out = pc_2d(np.zeros(3), np.zeros(3), cov, r2, v2, np.zeros((3, 3)), hbr, shape=shape)
            assert np.allclose(out.encounter_covariance, cov2d, rtol=1e-12, atol=1e-12 * l1)
            if reference > 1e-10:
                checked += 1
                assert out.pc == pytest.approx(reference, rel=1e-9), (shape, l1, l2, hbr, miss)
    assert checked > 60


def test_square_uncorrelated_is_a_product_of_erfs():
    # Covariance aligned with the encounter axes: x = -X(ECI) here, z = +Z... check via
    # the returned axes rather than assuming them.
    cov = np.diag([400.0, 900.0, 100.0])
    r2 = LEO_R1 + np.array([0.0, 0.0, 30.0])
    out = pc_2d(LEO_R1, LEO_V1, cov, r2, [7500.0, 0.0, 0.0], np.zeros((3, 3)), 12.0, shape="square")
    c = out.encounter_covariance
    assert abs(c[0, 1]) < 1e-9
    sx, sz = math.sqrt(c[0, 0]), math.sqrt(c[1, 1])
    m, h = out.miss_distance, 12.0
    fx = 0.5 * (
        special.erf((m + h) / (sx * math.sqrt(2))) - special.erf((m - h) / (sx * math.sqrt(2)))
    )
    fz = special.erf(h / (sz * math.sqrt(2)))
    assert out.pc == pytest.approx(fx * fz, rel=1e-12)
    eq = pc_2d(
        LEO_R1,
        LEO_V1,
        cov,
        r2,
        [7500.0, 0.0, 0.0],
        np.zeros((3, 3)),
        12.0,
        shape="square_equal_area",
    )
    h = math.sqrt(math.pi) / 2 * 12.0
    fx = 0.5 * (
        special.erf((m + h) / (sx * math.sqrt(2))) - special.erf((m - h) / (sx * math.sqrt(2)))
    )
    fz = special.erf(h / (sz * math.sqrt(2)))
    assert eq.pc == pytest.approx(fx * fz, rel=1e-12)


def test_six_by_six_and_float():
    cov3 = np.diag([100.0, 400.0, 50.0])
    cov6 = np.zeros((6, 6))
    cov6[:3, :3] = cov3
    cov6[3:, 3:] = np.eye(3) * 1e-4
    r2 = LEO_R1 + np.array([5.0, 0.0, 20.0])
    a = pc_2d(LEO_R1, LEO_V1, cov3, r2, [7500.0, 0.0, 0.0], cov3, 10.0)
    b = pc_2d(LEO_R1, LEO_V1, cov6, r2, [7500.0, 0.0, 0.0], cov6, 10.0)
    assert a.pc == b.pc and float(a) == a.pc
    assert a.relative_speed == pytest.approx(math.hypot(7500.0, 7500.0))
    assert a.miss_distance == pytest.approx(math.hypot(5.0, 20.0) * 1.0, rel=0.5)


# ---------------------------------------------------------------------- mixtures


def _state_gaussian(r, v, pos_cov):
    cov = np.zeros((6, 6))
    cov[:3, :3] = pos_cov
    cov[3:, 3:] = np.eye(3) * 1e-6
    return np.concatenate([r, v]), cov


def test_one_component_mixture_equals_pc_2d_exactly():
    r2, v2 = LEO_R1 + np.array([10.0, 0.0, 25.0]), np.array([0.0, 0.0, 7500.0])
    c1, c2 = np.diag([300.0, 2500.0, 80.0]), np.diag([150.0, 900.0, 60.0])
    g1, g2 = _state_gaussian(LEO_R1, LEO_V1, c1), _state_gaussian(r2, v2, c2)
    expected = pc_2d(LEO_R1, LEO_V1, c1, r2, v2, c2, 15.0).pc
    m1 = GaussianMixture(None, g1[0][None], g1[1][None])
    m2 = GaussianMixture(None, g2[0][None], g2[1][None])
    assert pc_mixture(m1, m2, 15.0).pc == expected
    assert pc_mixture(g1, g2, 15.0).pc == expected  # (mean, covariance) pairs
    # 3-D position mixtures with the velocities given.
    p1 = GaussianMixture(None, LEO_R1[None], c1[None])
    p2 = GaussianMixture(None, r2[None], c2[None])
    out = pc_mixture(p1, p2, 15.0, velocity1=LEO_V1, velocity2=v2)
    assert out.pc == expected
    assert out.pair_pc.shape == (1, 1) and float(out) == expected


def test_two_component_mixture_is_the_weighted_sum():
    # Object 1's position is bimodal along-track (two density models disagree).
    v2 = np.array([0.0, 0.0, 7500.0])
    r2 = LEO_R1 + np.array([0.0, 40.0, 0.0])
    c1 = [np.diag([100.0, 900.0, 50.0]), np.diag([200.0, 1600.0, 60.0])]
    means1 = [LEO_R1 + np.array([0.0, -150.0, 0.0]), LEO_R1 + np.array([0.0, 60.0, 0.0])]
    c2 = np.diag([80.0, 400.0, 40.0])
    g = [_state_gaussian(m, LEO_V1, c) for m, c in zip(means1, c1, strict=True)]
    mix1 = GaussianMixture([0.3, 0.7], [x[0] for x in g], [x[1] for x in g])
    mix2 = _state_gaussian(r2, v2, c2)
    out = pc_mixture(mix1, mix2, 10.0)
    parts = [pc_2d(m, LEO_V1, c, r2, v2, c2, 10.0).pc for m, c in zip(means1, c1, strict=True)]
    assert out.pair_pc[:, 0] == pytest.approx(parts, rel=1e-14)
    assert out.pc == pytest.approx(0.3 * parts[0] + 0.7 * parts[1], rel=1e-14)
    # The single Gaussian fitted to the mixture gives a different answer.
    fitted = pc_2d(mix1.mean()[:3], LEO_V1, mix1.covariance()[:3, :3], r2, v2, c2, 10.0).pc
    assert abs(fitted - out.pc) > 0.05 * out.pc


# ---------------------------------------------------------------------- Monte Carlo


def _sample_states(rng, r, v, pos_cov, n):
    pos = rng.multivariate_normal(r, pos_cov, size=n)
    return np.concatenate([pos, np.broadcast_to(v, (n, 3))], axis=1)


def test_monte_carlo_agrees_with_pc_2d_within_its_interval():
    rng = np.random.default_rng(2024)
    r2, v2 = LEO_R1 + np.array([0.0, 0.0, 30.0]), np.array([7500.0, 0.0, 7500.0])
    c1, c2 = np.diag([200.0, 800.0, 150.0]), np.diag([100.0, 300.0, 250.0])
    exact = pc_2d(LEO_R1, LEO_V1, c1, r2, v2, c2, 8.0).pc
    m1 = _sample_states(rng, LEO_R1, LEO_V1, c1, 2000)
    m2 = _sample_states(rng, r2, v2, c2, 2000)
    mc = pc_monte_carlo(m1, m2, 8.0)
    assert mc.pairs == 4_000_000 and mc.n1 == mc.n2 == 2000
    assert mc.interval[0] <= exact <= mc.interval[1], (mc, exact)
    assert not mc.one_sided
    # The interval is the normal one from the stated standard error.
    z = 1.959963984540054
    assert mc.interval[1] - mc.pc == pytest.approx(z * mc.std_error, rel=1e-12)
    # Its width follows from the sample size: 4x fewer members, ~2x wider.
    small = pc_monte_carlo(m1[:500], m2[:500], 8.0)
    assert 1.5 < small.std_error / mc.std_error < 2.7
    assert float(mc) == mc.pc


def test_monte_carlo_standard_error_matches_replicates():
    rng = np.random.default_rng(7)
    r2, v2 = LEO_R1 + np.array([0.0, 0.0, 15.0]), np.array([7500.0, 0.0, 0.0])
    c = np.diag([150.0, 150.0, 150.0])
    estimates, errors = [], []
    for _ in range(60):
        mc = pc_monte_carlo(
            _sample_states(rng, LEO_R1, LEO_V1, c, 300), _sample_states(rng, r2, v2, c, 300), 6.0
        )
        estimates.append(mc.pc)
        errors.append(mc.std_error)
    spread = np.std(estimates, ddof=1)
    # 60 replicates know the spread to ~ +-9 % (1 sigma).
    assert 0.7 < np.mean(errors) / spread < 1.4, (np.mean(errors), spread)
    exact = pc_2d(LEO_R1, LEO_V1, c, r2, v2, c, 6.0).pc
    assert abs(np.mean(estimates) - exact) < 4 * spread / math.sqrt(60)


def test_monte_carlo_agrees_with_mixture():
    rng = np.random.default_rng(99)
    v2 = np.array([0.0, 0.0, 7500.0])
    r2 = LEO_R1 + np.array([0.0, 20.0, 5.0])
    means1 = [LEO_R1 + np.array([0.0, -40.0, 0.0]), LEO_R1 + np.array([0.0, 30.0, 0.0])]
    covs1 = [np.diag([100.0, 400.0, 50.0]), np.diag([150.0, 600.0, 80.0])]
    g = [_state_gaussian(m, LEO_V1, c) for m, c in zip(means1, covs1, strict=True)]
    mix1 = GaussianMixture([0.5, 0.5], [x[0] for x in g], [x[1] for x in g])
    c2 = np.diag([60.0, 200.0, 90.0])
    mix2 = _state_gaussian(r2, v2, c2)
    expected = pc_mixture(mix1, mix2, 10.0).pc
    m1 = mix1.sample(2000, seed=1)
    m2 = _sample_states(rng, r2, v2, c2, 2000)
    mc = pc_monte_carlo(m1, m2, 10.0)
    assert mc.interval[0] <= expected <= mc.interval[1], (mc, expected)


def test_monte_carlo_without_hits_gives_an_upper_bound():
    m1 = np.tile(np.concatenate([LEO_R1, LEO_V1]), (400, 1))
    m1[:, 0] += np.linspace(0.0, 10.0, 400)
    m2 = m1.copy()
    m2[:, 2] += 1000.0
    m2[:, 3] += 7500.0
    mc = pc_monte_carlo(m1, m2[:300], 5.0, level=0.95)
    assert mc.hits == 0 and mc.pc == 0.0 and mc.one_sided
    assert mc.interval == (0.0, pytest.approx(1 - 0.05 ** (1 / 300)))


def test_monte_carlo_from_monte_carlo_results(paper_state, paper_craft, benchmark_atmosphere):
    run = rp.monte_carlo(
        paper_state,
        paper_craft,
        benchmark_atmosphere,
        1200.0,
        n=40,
        seed=1,
        output_step=600.0,
        progress=False,
    )
    states = np.concatenate([run.positions[:, -1], run.velocities[:, -1]], axis=1)
    # A crossing secondary 3 m off the first member's track.
    other = states[:25].copy()
    other[:, :3] = states[0, :3] + [0.0, 0.0, 3.0]
    other[:, 3:] = states[0, 3:][[1, 0, 2]]
    from_run = pc_monte_carlo(run, other, 20.0)
    from_array = pc_monte_carlo(states, other, 20.0)
    assert from_run == from_array
    assert from_run.n1 == 40 and from_run.hits > 0
    early = pc_monte_carlo(run, other, 20.0, index=1)
    assert early.n1 == 40
    with pytest.raises(ValueError, match="index"):
        pc_monte_carlo(run, other, 20.0, index=99)
    shorter = rp.monte_carlo(
        paper_state,
        paper_craft,
        benchmark_atmosphere,
        600.0,
        n=5,
        seed=1,
        output_step=600.0,
        progress=False,
    )
    with pytest.raises(ValueError, match="same epoch"):
        pc_monte_carlo(run, shorter, 20.0)


# ---------------------------------------------------------------------- bad input


def test_bad_input_is_refused_clearly():
    c = np.eye(3) * 100.0
    r2, v2 = LEO_R1 + np.array([0.0, 0.0, 10.0]), np.array([7500.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="relative speed"):
        pc_2d(LEO_R1, LEO_V1, c, r2, LEO_V1, c, 10.0)
    for hbr in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="hard_body_radius"):
            pc_2d(LEO_R1, LEO_V1, c, r2, v2, c, hbr)
    with pytest.raises(TypeError, match="hard_body_radius"):
        pc_2d(LEO_R1, LEO_V1, c, r2, v2, c, "10")
    bad = c.copy()
    bad[1, 1] = np.nan
    with pytest.raises(ValueError, match=r"cov2\[1, 1\]"):
        pc_2d(LEO_R1, LEO_V1, c, r2, v2, bad, 10.0)
    with pytest.raises(ValueError, match="cov1 must have shape"):
        pc_2d(LEO_R1, LEO_V1, np.eye(4), r2, v2, c, 10.0)
    with pytest.raises(ValueError, match="r2"):
        pc_2d(LEO_R1, LEO_V1, c, [1.0, np.inf, 0.0], v2, c, 10.0)
    with pytest.raises(ValueError, match="v1 must have shape"):
        pc_2d(LEO_R1, [1.0, 2.0], c, r2, v2, c, 10.0)
    with pytest.raises(ValueError, match="symmetric"):
        pc_2d(LEO_R1, LEO_V1, c + np.triu(np.ones((3, 3)), 1), r2, v2, c, 10.0)
    with pytest.raises(ValueError, match="frame"):
        pc_2d(LEO_R1, LEO_V1, c, r2, v2, c, 10.0, frame="ecef")
    with pytest.raises(ValueError, match="shape"):
        pc_2d(LEO_R1, LEO_V1, c, r2, v2, c, 10.0, shape="disc")
    with pytest.raises(ValueError, match="npd"):
        pc_2d(LEO_R1, LEO_V1, c, r2, v2, c, 10.0, npd="ignore")
    with pytest.raises(ValueError, match="RTN frame is undefined"):
        pc_2d(LEO_R1, [7500.0, 0.0, 0.0], c, r2, v2, c, 10.0, frame="rtn")
    # Mixtures.
    g = _state_gaussian(LEO_R1, LEO_V1, c)
    p = GaussianMixture(None, LEO_R1[None], c[None])
    with pytest.raises(ValueError, match="velocity1"):
        pc_mixture(p, g, 10.0)
    with pytest.raises(ValueError, match="velocity2"):
        pc_mixture(g, g, 10.0, velocity2=LEO_V1)
    with pytest.raises(TypeError, match="mix1"):
        pc_mixture("x", g, 10.0)
    with pytest.raises(ValueError, match=r"component pair \(0, 0\).*relative speed"):
        pc_mixture(g, g, 10.0)
    # Monte Carlo.
    m = np.tile(np.concatenate([LEO_R1, LEO_V1]), (10, 1))
    with pytest.raises(ValueError, match=r"members1 must be member states of shape \(n, 6\)"):
        pc_monte_carlo(m[:, :3], m, 1.0)
    nan = m.copy()
    nan[3, 0] = np.nan
    with pytest.raises(ValueError, match=r"members2\[3\] is not finite"):
        pc_monte_carlo(m, nan, 1.0)
    with pytest.raises(ValueError, match="at least 2"):
        pc_monte_carlo(m[:1], m, 1.0)
    with pytest.raises(ValueError, match="level"):
        pc_monte_carlo(m, m, 1.0, level=1.0)
    with pytest.raises(ValueError, match="hard_body_radius"):
        pc_monte_carlo(m, m, 0.0)


def test_never_nan_in_extreme_geometry():
    # Far miss with a tiny covariance: Pc underflows to 0, not NaN.
    out = pc_2d(
        LEO_R1,
        LEO_V1,
        np.eye(3) * 1e-6,
        LEO_R1 + np.array([0, 0, 5e4]),
        [7500.0, 0, 0],
        np.eye(3) * 1e-6,
        1.0,
    )
    assert out.pc == 0.0
    # Zero covariance: repaired (clipped to a point mass) and reported.
    inside = pc_2d(
        LEO_R1,
        LEO_V1,
        np.zeros((3, 3)),
        LEO_R1 + np.array([0, 0, 3.0]),
        [7500.0, 0, 0],
        np.zeros((3, 3)),
        10.0,
    )
    assert inside.repaired and inside.pc == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(ValueError, match="not positive definite"):
        pc_2d(
            LEO_R1,
            LEO_V1,
            np.zeros((3, 3)),
            LEO_R1 + np.array([0, 0, 3.0]),
            [7500.0, 0, 0],
            np.zeros((3, 3)),
            10.0,
            npd="raise",
        )
