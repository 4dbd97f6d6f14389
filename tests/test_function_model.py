"""A user's density function wrapped as a model (FromFunction): values, checks of what the
function returns, sampling into a field and propagation against the analytic atmosphere."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.density.field import FieldResolution
from rhoprop.density.function import FromFunction

RHO0, H0, SCALE, REL = 3.725e-12, 400e3, 58.515e3, 0.1
#: WGS-84 semi-major axis (m) and first eccentricity squared.
A_WGS84 = 6378137.0
E2_WGS84 = 6.69437999014e-3


def spherical_altitude(lat, alt):
    """|r| - a for geodetic latitude (deg) and altitude (m) on WGS-84 (closed form: the
    point is ((N + h) cos(lat), (N (1 - e^2) + h) sin(lat)) in the meridian plane, with
    N = a / sqrt(1 - e^2 sin^2(lat)))."""
    phi = np.radians(lat)
    n = A_WGS84 / np.sqrt(1.0 - E2_WGS84 * np.sin(phi) ** 2)
    rho = (n + alt) * np.cos(phi)
    z = (n * (1.0 - E2_WGS84) + alt) * np.sin(phi)
    return np.hypot(rho, z) - A_WGS84


def exponential(times, lat, lon, alt):
    """The benchmark exponential atmosphere written by a user (spherical altitude)."""
    mean = RHO0 * np.exp(-(spherical_altitude(lat, alt) - H0) / SCALE)
    return mean, REL * mean


def test_lambda_matches_exponential_at_the_equator():
    model = FromFunction(
        lambda t, la, lo, h: (
            RHO0 * np.exp(-(h - H0) / SCALE),
            REL * RHO0 * np.exp(-(h - H0) / SCALE),
        ),
        name="exp",
    )
    reference = rp.density.Exponential(RHO0, H0, SCALE, rel_sigma=REL)
    t = np.array(["2002-09-07T01:00", "2002-09-08T13:30"], "datetime64[ns]")
    lon = np.array([-120.0, 0.0, 45.0, 300.0])[:, None]
    alt = np.array([250e3, 400e3, 700e3])[:, None, None]
    mean, std = model.mean_std(t, 0.0, lon, alt)
    ref_mean, ref_std = reference.mean_std(t, 0.0, lon, alt)
    assert mean.shape == (3, 4, 2)
    np.testing.assert_allclose(mean, ref_mean, rtol=1e-9)
    np.testing.assert_allclose(std, ref_std, rtol=1e-9)
    assert repr(model) == "FromFunction(name='exp')"
    assert repr(FromFunction(exponential)) == "FromFunction(name='exponential')"


def test_function_with_spherical_altitude_matches_everywhere():
    model = FromFunction(exponential)
    reference = rp.density.Exponential(RHO0, H0, SCALE, rel_sigma=REL)
    lat = np.linspace(-90, 90, 13)
    args = ("2002-09-07T01:00", lat, 10.0, np.array([300e3, 500e3])[:, None])
    np.testing.assert_allclose(model.mean_std(*args), reference.mean_std(*args), rtol=1e-9)


def test_function_receives_broadcast_checked_inputs():
    seen = {}

    def fn(t, la, lo, h):
        seen.update(t=t, la=la, lo=lo, h=h)
        return np.full(la.shape, 1e-12), 0.0  # a scalar std broadcasts

    mean, std = FromFunction(fn).mean_std(["2002-09-07T01:00", "2002-09-07T02:00"], 0.0, 5, 4e5)
    assert seen["t"].dtype == np.dtype("datetime64[ns]")
    assert all(seen[k].shape == (2,) and seen[k].dtype == float for k in ("la", "lo", "h"))
    assert mean.shape == std.shape == (2,)
    np.testing.assert_array_equal(std, 0.0)


def test_bad_returns_raise_clear_errors():
    t, lat, lon, alt = "2002-09-07T01:00", np.array([0.0, 10.0, 20.0]), 0.0, 400e3

    def returning(mean, std):
        return FromFunction(lambda *_: (mean, std), name="net")

    good = np.full(3, 1e-12)
    with pytest.raises(
        ValueError,
        match=r"FromFunction\(name='net'\): fn returned mean = -1e-12 kg/m\^3 at index \(1\) "
        r"\(time 2002-09-07T01:00:00.000000000, lat 10 deg, lon 0 deg, alt 400000 m\); "
        r"it must be finite and > 0",
    ):
        returning(np.array([1e-12, -1e-12, 1e-12]), good).mean_std(t, lat, lon, alt)
    with pytest.raises(ValueError, match=r"fn returned mean = 0.0 kg/m\^3 at index \(0\)"):
        returning(np.zeros(3), good).mean_std(t, lat, lon, alt)
    with pytest.raises(
        ValueError, match=r"fn returned std = nan kg/m\^3 at index \(2\).*finite and >= 0"
    ):
        returning(good, np.array([0.0, 1e-13, np.nan])).mean_std(t, lat, lon, alt)
    with pytest.raises(ValueError, match=r"std = -1e-13 kg/m\^3 at index \(0\)"):
        returning(good, np.full(3, -1e-13)).mean_std(t, lat, lon, alt)
    with pytest.raises(
        ValueError, match=r"fn returned mean of shape \(2,\) for inputs of shape \(3,\)"
    ):
        returning(np.full(2, 1e-12), good).mean_std(t, lat, lon, alt)
    with pytest.raises(ValueError, match=r"fn returned std of shape \(3, 3\)"):
        returning(good, np.zeros((3, 3))).mean_std(t, lat, lon, alt)
    # Index of the first bad value in a multi-dimensional result.
    bad = np.full((2, 3), 1e-12)
    bad[1, 2] = np.inf
    with pytest.raises(ValueError, match=r"mean = inf kg/m\^3 at index \(1, 2\).*lat 20 deg"):
        returning(bad, 0.0).mean_std(t, lat, lon, np.array([[400e3], [500e3]]))
    with pytest.raises(TypeError, match=r"must return a tuple \(mean, std\).*got a list"):
        FromFunction(lambda *_: [good, good]).mean_std(t, lat, lon, alt)
    with pytest.raises(TypeError, match=r"got a ndarray"):
        FromFunction(lambda *_: good).mean_std(t, lat, lon, alt)
    with pytest.raises(TypeError, match=r"got a tuple of 3 items"):
        FromFunction(lambda *_: (good, good, good)).mean_std(t, lat, lon, alt)
    with pytest.raises(TypeError, match=r"mean that is not numeric"):
        returning("dense", good).mean_std(t, lat, lon, alt)
    with pytest.raises(TypeError, match="fn must be callable"):
        FromFunction(3.0)
    with pytest.raises(TypeError, match="cache_key must be a string"):
        FromFunction(exponential, cache_key=1)


def test_cache_key_is_the_users():
    t0, t1 = np.datetime64("2002-09-07T00:00", "ns"), np.datetime64("2002-09-07T01:00", "ns")
    assert FromFunction(exponential).cache_key(t0, t1) is None
    assert FromFunction(exponential, cache_key="exp v1").cache_key(t0, t1) == "exp v1"


def test_field_matches_function():
    model = FromFunction(exponential, name="exp")
    res = FieldResolution(time=1800.0, altitude=25e3, latitude=5.0, longitude=15.0)
    start, end = "2002-09-07T01:00", "2002-09-07T03:00"
    field = model.field(start, end, altitude_range=(350e3, 450e3), resolution=res, cache=False)
    rng = np.random.default_rng(3)
    n = 50
    t = np.datetime64(start, "ns") + rng.integers(0, 7200 * 10**9, n).astype("timedelta64[ns]")
    lat, lon, alt = rng.uniform(-90, 90, n), rng.uniform(-180, 180, n), rng.uniform(35e4, 45e4, n)
    direct = model.mean_std(t, lat, lon, alt)
    grid = field.mean_std(t, lat, lon, alt)
    worst = np.abs(grid[0] / direct[0] - 1).max()
    print(f"field vs function: max mean error {worst:.2e}")
    assert worst < 2e-3  # spherical altitude is not linear in latitude between 5 deg nodes
    np.testing.assert_allclose(grid[1] / grid[0], REL, rtol=1e-9)


def test_propagation_matches_analytic_exponential():
    state = rp.scenarios.paper_state()
    craft = rp.scenarios.paper_spacecraft()
    wrapped = rp.propagate(state, craft, FromFunction(exponential), 3600.0)
    analytic = rp.propagate(
        state, craft, rp.density.Exponential(RHO0, H0, SCALE, rel_sigma=REL), 3600.0
    )
    # Drag alone moves the orbit by far more than the difference (vacuum comparison).
    vacuum = rp.propagate(state, craft, rp.density.Exponential(1e-30, H0, SCALE), 3600.0)
    diff = np.linalg.norm(wrapped.positions[-1] - analytic.positions[-1])
    drag = np.linalg.norm(vacuum.positions[-1] - analytic.positions[-1])
    print(f"FromFunction vs Exponential after 1 h: {diff:.3e} m (drag effect {drag:.1f} m)")
    assert diff < 1.0
