"""The short-encounter check and the Pc over the encounter interval: against an
independent two-body Monte Carlo (each sampled object flown by Kepler's equation through
equinoctial elements, no Clohessy-Wiltshire), and in screen_all's events."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.conjunction import encounter_check, pc_2d, pc_interval, screen_all
from rhoprop.conjunction.encounter import SHORT_ENCOUNTER_SHARE
from rhoprop.constants import MU, R_EARTH


def _chief(altitude: float = 500e3) -> tuple[np.ndarray, np.ndarray]:
    """A circular 51.6-deg orbit's state and its RTN basis (rows R, T, N)."""
    r = R_EARTH + altitude
    v = math.sqrt(MU / r)
    inc = math.radians(51.6)
    x = np.array([r, 0.0, 0.0, 0.0, v * math.cos(inc), v * math.sin(inc)])
    return x, rp.frames.rtn_basis(x[:3], x[3:])


def _inertial(rtn_cov: np.ndarray, basis: np.ndarray) -> np.ndarray:
    b6 = np.zeros((6, 6))
    b6[:3, :3] = b6[3:, 3:] = basis
    return b6.T @ rtn_cov @ b6


def _two_body_pc(x1, c1, x2, c2, hbr, span, n, seed):
    """Share of n independent pairs (each object drawn from its own Gaussian) passing
    within hbr over [-span/2, span/2], both flown by two-body motion (lambda advanced by
    the mean motion)."""
    rng = np.random.default_rng(seed)
    s1 = x1 + rng.standard_normal((n, 6)) @ np.linalg.cholesky(c1).T
    s2 = x2 + rng.standard_normal((n, 6)) @ np.linalg.cholesky(c2).T
    times = np.linspace(-span / 2, span / 2, 1601)
    e1, e2 = rp.frames.to_equinoctial(s1, x1), rp.frames.to_equinoctial(s2, x1)
    best = np.full(n, np.inf)
    for t in times:
        p = []
        for e in (e1, e2):
            f = e.copy()
            f[:, 5] += np.sqrt(MU / e[:, 0] ** 3) * t
            p.append(rp.frames.from_equinoctial(f, x1)[:, :3])
        best = np.minimum(best, np.linalg.norm(p[1] - p[0], axis=1))
    return float(np.mean(best <= hbr))


def test_a_slow_encounter_is_not_short_and_its_interval_pc_matches_two_body_flights():
    # Object 2 5 m above object 1, drifting 5 cm/s along-track and 2 cm/s across, both
    # with 20-60 m and 2-3 cm/s 1-sigma: the encounter lasts hours, not seconds.
    x1, basis = _chief()
    x2 = x1.copy()
    x2[:3] += 5.0 * basis[0]
    x2[3:] += 0.05 * basis[1] + 0.02 * basis[2]
    cov = _inertial(np.diag([30.0**2, 60.0**2, 20.0**2, 0.03**2, 0.03**2, 0.02**2]), basis)
    hbr = 30.0
    check = encounter_check(x1[:3], x1[3:], cov, x2[:3], x2[3:], cov, hbr)
    assert not check.short and check.duration > 10 * check.period * SHORT_ENCOUNTER_SHARE
    span = min(check.duration, check.period / 2)
    got = pc_interval(x1[:3], x1[3:], cov, x2[:3], x2[3:], cov, hbr, span=span, seed=3)
    ref = _two_body_pc(x1, cov, x2, cov, hbr, span, 4000, seed=5)
    # Binomial standard errors: 4,000 pairs and 50,000 samples at Pc ~ 0.2: 0.0065
    # combined; 4 of them (Clohessy-Wiltshire's own error is second order in 100 m over
    # 6,900 km).
    se = math.sqrt(ref * (1 - ref) / 4000 + got.pc * (1 - got.pc) / got.samples)
    assert 0.05 < ref < 0.5
    assert got.pc == pytest.approx(ref, abs=4 * se)
    assert got.hits == round(got.pc * got.samples) and got.span == span
    # Same seed, same number.
    again = pc_interval(x1[:3], x1[3:], cov, x2[:3], x2[3:], cov, hbr, span=span, seed=3)
    assert again.pc == got.pc


def _numpy_hits(states: np.ndarray, n: float, span: float, hbr: float) -> int:
    """The count as pc_interval made it in numpy before it moved to the core: CW
    positions on 101 coarse times, states that cannot come within hbr set aside (minimum
    distance - 0.55 x the largest chord), the rest on 801 times with the parabola
    through the grid minimum."""

    def cw(q: np.ndarray, t: np.ndarray) -> np.ndarray:
        nt = n * t
        c, s = np.cos(nt), np.sin(nt)
        x0, y0, z0, u0, v0, w0 = (q[:, i, None] for i in range(6))
        x = (4 - 3 * c) * x0 + s / n * u0 + 2 / n * (1 - c) * v0
        y = 6 * (s - nt) * x0 + y0 - 2 / n * (1 - c) * u0 + (4 * s - 3 * nt) / n * v0
        return np.stack([x, y, c * z0 + s / n * w0], axis=-1)

    first = cw(states, np.linspace(-span / 2, span / 2, 101))
    chord = np.linalg.norm(np.diff(first, axis=1), axis=2).max(axis=1)
    near = states[np.linalg.norm(first, axis=2).min(axis=1) - 0.55 * chord <= hbr]
    d2 = (cw(near, np.linspace(-span / 2, span / 2, 801)) ** 2).sum(axis=2)
    k = np.argmin(d2, axis=1)
    rows = np.arange(len(d2))
    low = d2[rows, k]
    inner = (k > 0) & (k < d2.shape[1] - 1)
    a, b, c = d2[rows[inner], k[inner] - 1], low[inner], d2[rows[inner], k[inner] + 1]
    curve = a - 2 * b + c
    with np.errstate(divide="ignore", invalid="ignore"):
        low[inner] = np.where(curve > 0, np.minimum(b - (c - a) ** 2 / (8 * curve), b), b)
    return int(np.count_nonzero(np.maximum(low, 0.0) <= hbr * hbr))


def test_the_core_counts_the_interval_hits_as_the_numpy_reference_does():
    # Relative states of a slow encounter (tens of m, cm/s to dm/s) over a quarter orbit:
    # the core's count equals the numpy implementation's, the coarse pass included.
    rng = np.random.default_rng(11)
    states = rng.normal(0.0, 1.0, (20_000, 6)) * [40, 80, 30, 0.05, 0.1, 0.04]
    n = math.sqrt(MU / (R_EARTH + 500e3) ** 3)
    for span, hbr in ((1400.0, 20.0), (300.0, 5.0), (20.0, 30.0)):
        got = rp._core.interval_hits(states, n, span, hbr, 101, 801)
        assert got == _numpy_hits(states, n, span, hbr) > 0
    with pytest.raises(ValueError, match="span"):
        rp._core.interval_hits(states, n, -1.0, 5.0, 101, 801)
    with pytest.raises(ValueError, match="states"):
        rp._core.interval_hits(states[:, :5].copy(), n, 10.0, 5.0, 101, 801)


def test_a_crossing_at_orbital_speed_is_short():
    x1, basis = _chief()
    x2 = x1.copy()
    x2[3:] = np.linalg.norm(x1[3:]) * basis[2]  # crossing at right angles, 7.6 km/s
    x2[:3] += 40.0 * basis[0]
    cov = _inertial(np.diag([100.0**2, 1000.0**2, 50.0**2, 1.0, 1.0, 1.0]), basis)
    check = encounter_check(x1[:3], x1[3:], cov, x2[:3], x2[3:], cov, 10.0)
    assert check.short and check.duration < 2.0
    assert check.relative_speed == pytest.approx(np.linalg.norm(x2[3:] - x1[3:]))
    # The interval Pc agrees with the 2-D Pc where the 2-D model holds (binomial 4 sigma).
    pc2 = pc_2d(x1[:3], x1[3:], cov, x2[:3], x2[3:], cov, 10.0).pc
    got = pc_interval(x1[:3], x1[3:], cov, x2[:3], x2[3:], cov, 10.0, span=20.0, samples=200_000)
    assert got.pc == pytest.approx(pc2, abs=4 * math.sqrt(pc2 / got.samples) + 1e-6)


def test_pc_interval_refuses_bad_input_naming_it():
    x1, _ = _chief()
    cov = np.eye(6)
    args = (x1[:3], x1[3:], cov, x1[:3] + 10.0, x1[3:], cov, 5.0)
    with pytest.raises(ValueError, match="span"):
        pc_interval(*args, span=0.0)
    with pytest.raises(ValueError, match="cov2"):
        pc_interval(*args[:5], np.eye(3), 5.0, span=10.0)
    with pytest.raises(ValueError, match="samples"):
        pc_interval(*args, span=10.0, samples=10)


def _co_orbiting(start: np.datetime64, along: float) -> list[tuple]:
    """Two circular 400 km orbits in one plane, object b ``along`` m behind a and 1 m
    lower (it drifts forward at about 1.7 mm/s)."""
    r = R_EARTH + 400e3
    v = math.sqrt(MU / r)
    craft = rp.Spacecraft(2.2, 0.01)
    out = []
    for name, dr, ahead in (("a", 0.0, 0.0), ("b", -1.0, -along)):
        phi = ahead / r
        rr = r + dr
        vv = math.sqrt(MU / rr)
        pos = rr * np.array([math.cos(phi), math.sin(phi) * 0.6, math.sin(phi) * 0.8])
        vel = vv * np.array([-math.sin(phi), math.cos(phi) * 0.6, math.cos(phi) * 0.8])
        out.append((rp.OrbitState(start, pos, vel), craft, name))
    assert v > 0
    return out


def test_screen_all_counts_a_co_orbiting_pair_over_its_encounter_not_in_2d():
    # The reported case: objects 1 m apart radially and a few metres along-track, co-orbiting
    # at mm/s. The 2-D Pc assumed a straight pass and gave each minimum a Pc with no word;
    # now each event says its Pc is counted over the encounter.
    start = np.datetime64("2024-03-01T00:00")
    objs = _co_orbiting(start, 3.0)
    model = rp.density.Exponential.benchmark()
    res = screen_all(objs, model, start=start, end=start + np.timedelta64(3, "h"), distance=5e3)
    inside = [i for i, e in enumerate(res.events) if e.edge is None]
    assert inside, res.events
    for i in inside:
        assert res.pc_method[i] == "interval", res.pc_notes[i]
        assert "not a short encounter" in res.pc_notes[i]
        assert 0.0 <= res.pc[i] <= 1.0
    assert res.table()["pc_method"][inside[0]] == "interval"


def test_pc_max_and_dilution_against_the_small_radius_formula():
    # Isotropic combined covariance: Pc ~ HBR^2 / (2 s^2) exp(-m^2 / (2 s^2)) for a small
    # hard body, largest at s^2 = m^2 / 2: HBR^2 / (m^2 e) (Alfano 2005). The maximum is
    # found on a grid of covariance scalings 26 % apart: within 2 % of the formula.
    hbr, miss = 10.0, 700.0
    for sigma, diluted in ((150.0, False), (400.0, False), (600.0, True), (3000.0, True)):
        c = np.eye(3) * sigma**2 / 2  # each object half: combined sigma^2 per axis
        res = pc_2d([0, 0, 0], [7000, 0, 0], c, [0, 0, miss], [0, 7000, 0], c, hbr)
        top = res.maximum()
        assert top.pc_max == pytest.approx(hbr**2 / (miss**2 * math.e), rel=0.02)
        assert top.pc_max >= res.pc
        assert top.dilution is diluted, (sigma, top)
        assert top.covariance_scale == pytest.approx(miss**2 / 2 / sigma**2, rel=0.3)
    # A miss inside the hard body: a covariance shrunk to nothing hits.
    inside = pc_2d([0, 0, 0], [7000, 0, 0], c, [0, 0, 5.0], [0, 7000, 0], c, hbr).maximum()
    assert inside.pc_max == 1.0 and inside.dilution
