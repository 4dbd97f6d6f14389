"""The CCSP filter: an unscented transform when density is certain, the equivalent
piecewise-constant kappa process of docs/conventions.md, "CCSP filter" when it is not."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import rhoprop as rp

#: The attributes of rp.Dynamics (given to a run whole, as dynamics=).
DYNAMICS = {f.name for f in dataclasses.fields(rp.Dynamics)}

DAY3 = 259200.0


@pytest.fixture(scope="module")
def setup():
    return rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()


P0 = np.diag([100.0, 100.0, 100.0, 1e-2, 1e-2, 1e-2])


def test_single_interval_is_the_unscented_transform(setup):
    # Independent UT written here: 13 points from sqrt(3) chol(P0), weights -1 and 1/6 (in
    # Cartesian coordinates, the paper's filter).
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.0)
    r = rp.ccsp(
        state,
        craft,
        model,
        21600.0,
        update_interval=21600.0,
        initial_covariance=P0,
        coordinates="cartesian",
    )
    cols = np.sqrt(3.0) * np.linalg.cholesky(P0)
    points = [state.state] + [state.state + s * cols[:, j] for s in (1, -1) for j in range(6)]
    ends = []
    for p in points:
        tr = rp.propagate(
            rp.OrbitState(state.epoch, p[:3], p[3:]),
            craft,
            model,
            21600.0,
            dynamics=rp.Dynamics(integrator="rk8"),
        )
        ends.append(tr.states[-1])
    ends = np.array(ends)
    w = np.array([-1.0] + [1 / 6] * 12)
    mean = w @ ends
    cov = (w[:, None] * (ends - mean)).T @ (ends - mean)
    np.testing.assert_allclose(r.mean[-1], mean, rtol=0, atol=1e-6)
    np.testing.assert_allclose(r.covariance[-1], cov, rtol=1e-9, atol=1e-9)


def test_certain_density_matches_monte_carlo_of_the_initial_covariance(setup):
    # 6 h with hourly updates; MC of 4000 members: std stderr 1.1 %, tolerance 5 %.
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.0)
    r = rp.ccsp(state, craft, model, 21600.0, initial_covariance=P0)
    mc = rp.monte_carlo(
        state,
        craft,
        model,
        21600.0,
        n=4000,
        initial_covariance=P0,
        output_step=None,
        progress=False,
        seed=2,
    )
    basis = rp.frames.rtn_basis(r.mean[-1, :3], r.mean[-1, 3:])
    sampled = basis @ np.cov(mc.positions[:, -1].T) @ basis.T
    np.testing.assert_allclose(
        np.sqrt(np.diag(sampled)), np.sqrt(np.diag(r.rtn_covariance[-1])), rtol=0.05
    )


@pytest.fixture(scope="module")
def uncertain(setup):
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.2)
    gm18 = (
        rp.monte_carlo(
            state,
            craft,
            model,
            DAY3,
            n=1000,
            output_step=None,
            progress=False,
            kappa=rp.kappa.GaussMarkov(1080.0),
        )
        .along_track[:, -1]
        .std(ddof=1)
    )
    return state, craft, model, gm18


def test_ccsp_equals_the_equivalent_kappa_process(uncertain):
    state, craft, model, gm18 = uncertain
    # The paper's filter, (3, 3): PiecewiseConstant(dt, 1/3).
    hourly = rp.ccsp(state, craft, model, DAY3, update_interval=3600.0, scaling=(3.0, 3.0))
    fine = rp.ccsp(state, craft, model, DAY3, update_interval=300.0, scaling=(3.0, 3.0))
    # Long-time theory: sqrt(2 dt / D_GM18) = 1.52 at 60 min and 0.44 at 5 min.
    assert hourly.along_track_std[-1] / gm18 == pytest.approx(1.52, rel=0.10)
    assert fine.along_track_std[-1] / gm18 == pytest.approx(0.44, rel=0.15)
    pc = rp.monte_carlo(
        state,
        craft,
        model,
        DAY3,
        n=1000,
        output_step=None,
        progress=False,
        kappa=rp.kappa.PiecewiseConstant(3600.0, 1 / 3),
    )
    assert hourly.along_track_std[-1] == pytest.approx(pc.along_track[:, -1].std(ddof=1), rel=0.10)
    # Covariances stay symmetric positive definite throughout.
    for cov in hourly.covariance:
        np.testing.assert_allclose(cov, cov.T, rtol=0, atol=1e-9 * np.abs(cov).max())
        assert np.linalg.eigvalsh(cov).min() > 0
    assert hourly.times[-1] == DAY3 and len(hourly.times) == 73
    assert np.abs(hourly.cross_covariance[1:]).max() > 0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"initial_covariance": np.eye(3)}, r"shape \(6, 6\)"),
        ({"initial_covariance": -np.eye(6)}, "not positive definite"),
        ({"update_interval": 0.0}, "update_interval must be > 0"),
        ({"perturbation": "other"}, "unknown perturbation"),
        ({"scaling": (3.0, 0.0)}, r"scaling\[1\] must be > 0"),
        ({"update_interval": 1e-6}, "more than the 10,000,000 a run may take"),
        ({"step": 3600.0}, "step = 3600 s is too large for this orbit"),
        ({"update_times": [3600.0, 5400.0]}, "disagrees with the last of update_times"),
        ({"update_times": [0.0, 7200.0]}, r"must increase strictly from > 0"),
        ({"coordinates": "keplerian"}, "coordinates must be one of 'equinoctial', 'cartesian'"),
    ],
)
def test_bad_input(setup, kwargs, match):
    state, craft = setup
    dynamics = {k: kwargs.pop(k) for k in list(kwargs) if k in DYNAMICS}
    with pytest.raises(ValueError, match=match):
        rp.ccsp(
            state,
            craft,
            rp.scenarios.benchmark_exponential(0.2),
            7200.0,
            dynamics=rp.Dynamics(**dynamics),
            **kwargs,
        )


def test_step_default_meets_the_documented_accuracy(setup):
    # step=None is RK8's 180 s: the mean after 3 days (certain density, near-zero initial
    # covariance) within 1 m of the adaptive DOP853 at rtol 1e-12 (measured 0.06 m).
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.0)
    r = rp.ccsp(state, craft, model, DAY3)
    reference = rp.propagate(
        state,
        craft,
        model,
        DAY3,
        dynamics=rp.Dynamics(rtol=1e-12),
    ).positions[-1]
    assert np.linalg.norm(r.mean[-1, :3] - reference) < 1.0


def test_duration_is_optional_with_update_times(setup):
    # update_times alone set the span; a duration that agrees is accepted, one that does
    # not is an error (it used to be ignored silently).
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.2)
    times = [1800.0, 3600.0, 7200.0]
    a = rp.ccsp(state, craft, model, update_times=times)
    b = rp.ccsp(state, craft, model, 7200.0, update_times=times)
    np.testing.assert_array_equal(a.covariance, b.covariance)
    np.testing.assert_array_equal(a.times, [0.0, *times])
    with pytest.raises(TypeError, match="duration is required"):
        rp.ccsp(state, craft, model)


def test_equinoctial_elements_are_the_classical_ones():
    # Independent reference: a, e, i and Omega from the vis-viva equation, the
    # eccentricity vector and the angular momentum, written here with numpy.
    rng = np.random.default_rng(3)
    mu = rp.constants.MU
    for _ in range(20):
        r = rng.uniform(6.6e6, 4.2e7) * rng.normal(size=3) / 1.7
        r *= rng.uniform(6.6e6, 4.2e7) / np.linalg.norm(r)
        vc = np.sqrt(mu / np.linalg.norm(r))
        v = rng.normal(size=3)
        v = np.cross(r, v)
        v *= vc * rng.uniform(0.8, 1.2) / np.linalg.norm(v)
        state = np.concatenate([r, v])
        a = 1.0 / (2.0 / np.linalg.norm(r) - v @ v / mu)
        h = np.cross(r, v)
        e = np.linalg.norm(((v @ v - mu / np.linalg.norm(r)) * r - (r @ v) * v) / mu)
        inc = np.arccos(h[2] / np.linalg.norm(h))
        raan = np.arctan2(h[0], -h[1])
        el = rp.frames.to_equinoctial(state)
        assert el[0] == pytest.approx(a, rel=1e-12)
        assert np.hypot(el[1], el[2]) == pytest.approx(e, rel=1e-9, abs=1e-12)
        if h[2] > 0:  # prograde: the direct axes
            assert 2 * np.arctan(np.hypot(el[3], el[4])) == pytest.approx(inc, abs=1e-12)
            assert np.arctan2(el[3], el[4]) == pytest.approx(raan, abs=1e-9)
        back = rp.frames.from_equinoctial(el, state)
        np.testing.assert_allclose(back, state, rtol=0, atol=1e-6 * np.abs(state).max())
    with pytest.raises(ValueError, match="not on an elliptic orbit"):
        rp.frames.to_equinoctial([7e6, 0, 0, 0, 12e3, 0])


def test_the_energy_semi_major_axis_is_the_energy_in_the_j2_field():
    # a = -mu / (2 E), E = v^2 / 2 - mu / r + mu J2 R^2 (3 z^2 / r^2 - 1) / (2 r^3),
    # computed here from the state; the other elements are the osculating ones, and the
    # way back returns the state.
    mu, re, j2 = rp.constants.MU, rp.constants.R_EARTH, rp.constants.J2
    state = rp.scenarios.paper_state().state
    r, v = state[:3], state[3:]
    rn = np.linalg.norm(r)
    energy = v @ v / 2 - mu / rn + mu * j2 * re**2 * (3 * r[2] ** 2 / rn**2 - 1) / (2 * rn**3)
    osc = rp.frames.to_equinoctial(state)
    el = rp.frames.to_equinoctial(state, semi_major="energy")
    assert el[0] == pytest.approx(-mu / (2 * energy), rel=1e-13)
    assert abs(el[0] - osc[0]) > 100.0  # metres to kilometres, with the phase
    np.testing.assert_array_equal(el[1:], osc[1:])
    back = rp.frames.from_equinoctial(el, state, semi_major="energy")
    np.testing.assert_allclose(back, state, rtol=0, atol=1e-6 * np.abs(state).max())
    with pytest.raises(ValueError, match="semi_major must be 'osculating' or 'energy'"):
        rp.frames.to_equinoctial(state, semi_major="mean")  # type: ignore[arg-type]


def test_equinoctial_gaussian_holds_the_monte_carlo_members_at_two_weeks(setup):
    # 1000 members of the process the filter linearises (docs/conventions.md, "CCSP
    # coordinates"): the along-track sigma within 10 % (the sample sigma's own sigma is
    # 2.2 %), and the share inside the filter's along-track 2-sigma interval within
    # 93-97 % (binomial sigma 0.7 % around 95.4 %). The Cartesian filter, the paper's, is
    # 3x too wide by then.
    state, craft = setup
    atm = rp.scenarios.benchmark_exponential(0.2)
    span = 14 * 86400.0
    kwargs = {
        "update_interval": 3600.0,
        "drag_sigma": 0.1,
        "kappa": rp.kappa.PiecewiseConstant(3600.0, 1 / 3),
    }
    cc = rp.ccsp(state, craft, atm, span, **kwargs)
    flat = rp.ccsp(state, craft, atm, span, coordinates="cartesian", **kwargs)
    mc = rp.monte_carlo(
        state,
        craft,
        atm,
        span,
        n=1000,
        kappa=rp.kappa.PiecewiseConstant(3600.0, 1 / 3),
        drag_sigma=0.1,
        seed=5,
        output_step=None,
        output_times=[span],
        progress=False,
    )
    states = np.concatenate([mc.positions[:, -1], mc.velocities[:, -1]], axis=1)
    basis = rp.frames.rtn_basis(cc.mean[-1, :3], cc.mean[-1, 3:])
    spread = ((states[:, :3] - states[:, :3].mean(axis=0)) @ basis[1]).std(ddof=1)
    assert cc.along_track_std[-1] / spread == pytest.approx(1.0, abs=0.10)
    assert flat.along_track_std[-1] / spread > 2.0
    assert cc.element_mean is not None and cc.element_covariance is not None
    assert flat.element_mean is None
    lam = cc.to_elements(states)[:, 5]  # members in GCRF, elements in the run's axes
    dl = (lam - cc.element_mean[-1, 5] + np.pi) % (2 * np.pi) - np.pi
    inside = np.mean(np.abs(dl) <= 2 * np.sqrt(cc.element_covariance[-1, 5, 5]))
    assert 0.93 <= inside <= 0.97
    # The Cartesian mean is the unscented transform of the element Gaussian: inside the
    # arc the members spread over, off the element mean's orbit by the arc's sag (about
    # a sigma_lambda^2, ~2 km here), a small part of the along-track sigma.
    on_orbit = cc.from_elements(cc.element_mean[-1])
    sag = np.linalg.norm(on_orbit[:3] - cc.mean[-1, :3])
    assert 0 < sag < 0.05 * cc.along_track_std[-1]


def test_a_day_of_an_initial_covariance_matches_the_monte_carlo(setup):
    # Density certain, P0 = 10 m and 0.1 m/s per axis, a day of hourly updates: 4000
    # members (sample sigma's own sigma 1.1 %; tolerance 4 %). Re-drawn every hour on a
    # straight line, the Cartesian filter's points put 20 % less along-track and 39 % more
    # radial spread (measured 2026-12-04; in one 24-h update it agrees); the equinoctial
    # one agrees either way.
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.0)
    day = 86400.0
    mc = rp.monte_carlo(
        state,
        craft,
        model,
        day,
        n=4000,
        seed=3,
        initial_covariance=P0,
        progress=False,
        output_step=None,
        output_times=[day],
    )
    x = mc.positions[:, -1]
    for coords, close in (("equinoctial", True), ("cartesian", False)):
        r = rp.ccsp(state, craft, model, day, initial_covariance=P0, coordinates=coords)
        basis = rp.frames.rtn_basis(r.mean[-1, :3], r.mean[-1, 3:])
        sample = np.sqrt(np.diag(basis @ np.cov(x.T) @ basis.T))
        ratio = np.sqrt(np.diag(r.rtn_covariance[-1])) / sample
        assert (np.abs(ratio[:2] - 1) < 0.04).all() == close, (coords, ratio)


@pytest.mark.parametrize("correlation", [0.6, 0.854])
def test_ccsp_equals_its_process_at_any_correlation(setup, correlation):
    # The paper's factor A = l1 P - B^T B held the state covariance only at l1 = l2: at
    # correlation 0.854 (l2 = 1.17) it was 1.68x the Monte Carlo of its own process. 500
    # members: the sigma's standard error is 1/sqrt(2 * 500) = 3.2 %; tolerance 8 %.
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.2)
    process = rp.kappa.PiecewiseConstant(3600.0, correlation)
    mc = rp.monte_carlo(
        state, craft, model, DAY3, n=500, kappa=process, seed=2, output_step=None, progress=False
    )
    cc = rp.ccsp(state, craft, model, DAY3, kappa=process)
    ratio = cc.along_track_std[-1] / mc.along_track[:, -1].std(ddof=1)
    assert ratio == pytest.approx(1.0, abs=0.08)


def test_default_ccsp_stands_for_the_default_monte_carlo(setup):
    # Both default to the calibrated two-scale kappa: the CCSP carries its fast term as
    # kappa and its slow one as a third consider parameter (drag_sigma stays the
    # user's). 500 members: 8 %.
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.2)
    mc = rp.monte_carlo(state, craft, model, DAY3, n=500, seed=4, output_step=None, progress=False)
    cc = rp.ccsp(state, craft, model, DAY3)
    assert cc.drag_sigma == 0.0
    ratio = cc.along_track_std[-1] / mc.along_track[:, -1].std(ddof=1)
    assert ratio == pytest.approx(1.0, abs=0.08)
    # The paper's filter (3, 3): its 60-min PiecewiseConstant, far narrower.
    paper = rp.ccsp(state, craft, model, DAY3, scaling=(3.0, 3.0))
    assert paper.along_track_std[-1] < 0.4 * cc.along_track_std[-1]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"kappa": rp.kappa.GaussMarkov(), "scaling": (3.0, 3.0)}, "give kappa or scaling"),
        ({"kappa": rp.kappa.White(10.0)}, "holds kappa over each update"),
        ({"kappa": rp.kappa.PiecewiseConstant(1800.0, 0.5)}, "updates are 3600 s apart"),
        ({"kappa": rp.kappa.PiecewiseConstant(3600.0, 0.0)}, "correlation between updates"),
    ],
)
def test_kappa_the_ccsp_cannot_stand_for(setup, kwargs, match):
    state, craft = setup
    model = rp.scenarios.benchmark_exponential(0.2)
    with pytest.raises(ValueError, match=match):
        rp.ccsp(state, craft, model, 7200.0, update_interval=3600.0, **kwargs)


def test_default_ccsp_holds_the_default_monte_carlo_at_every_output_of_a_long_run():
    # Both with their default kappa (the calibrated TwoScale): the CCSP carries the slow
    # term as its own consider parameter, decorrelating from update to update as the
    # members' slow term does. Folded into the constant c (before 2026-12-05) a long run's
    # early outputs were narrow (0.82-0.85x the members' along-track sigma at 1-7 days of
    # a 14-day run) until rescaled, and its (a, lambda) region held 57 % of the members at
    # 14 days. 2,000 members: relative standard error of a sigma 1.6 %, 10 % is six of
    # them; binomial 1-sigma of a 95 % share 0.5 %, 92 % is six.
    r = rp.constants.R_EARTH + 400e3
    v = np.sqrt(rp.constants.MU / r)
    inc = np.radians(51.6)
    state = rp.OrbitState(
        "2009-12-02T00:00:00", [r, 0.0, 0.0], [0.0, v * np.cos(inc), v * np.sin(inc)]
    )
    craft = rp.scenarios.paper_spacecraft()
    model = rp.density.Exponential.benchmark(rel_sigma=0.2)
    days = np.array([1.0, 3.0, 7.0, 14.0]) * 86400.0
    mc = rp.monte_carlo(
        state, craft, model, output_times=days, n=2000, drag_sigma=0.1, seed=4, progress=False
    )
    cc = rp.ccsp(state, craft, model, days[-1], drag_sigma=0.1)
    for j, t in enumerate(days):
        k = int(np.flatnonzero(np.isclose(cc.times, t))[0])
        basis = rp.frames.rtn_basis(cc.mean[k, :3], cc.mean[k, 3:])
        along = (mc.positions[:, j] - mc.positions[:, j].mean(axis=0)) @ basis[1]
        assert cc.along_track_std[k] / along.std(ddof=1) == pytest.approx(1.0, abs=0.1), t
        states = np.concatenate([mc.positions[:, j], mc.velocities[:, j]], axis=1)
        el = cc.to_elements(states)
        em, ec = cc.element_mean[k], cc.element_covariance[k]
        d = np.column_stack([el[:, 0] - em[0], (el[:, 5] - em[5] + np.pi) % (2 * np.pi) - np.pi])
        sub = ec[np.ix_([0, 5], [0, 5])]
        inside = np.mean(np.einsum("ni,ij,nj->n", d, np.linalg.inv(sub), d) <= 5.991464547107979)
        assert inside > 0.92, (t, inside)
