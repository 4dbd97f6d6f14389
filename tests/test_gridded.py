"""User-gridded density models and their use in propagation."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp


def exponential_grid(rel_sigma: float = 0.1):
    """The benchmark exponential atmosphere on a grid (exact in ln(mean) along altitude,
    which is where the two models differ only by spherical vs geodetic altitude)."""
    times = np.arange(
        np.datetime64("2002-09-07T00:00"), np.datetime64("2002-09-08T01:00"), np.timedelta64(1, "h")
    ).astype("datetime64[ns]")
    alt = np.arange(300e3, 560e3, 20e3)
    lat = np.linspace(-90, 90, 37)
    lon = np.arange(0, 360, 30.0)
    model = rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=rel_sigma)
    mean, std = model.mean_std(
        times[:, None, None, None],
        lat[None, None, :, None],
        lon[None, None, None, :],
        alt[None, :, None, None],
    )
    shape = (len(times), len(alt), len(lat), len(lon))
    return rp.density.Gridded(
        times, alt, lat, lon, np.broadcast_to(mean, shape), np.broadcast_to(std, shape)
    ), model


def test_gridded_reproduces_nodes_and_interpolates():
    grid, model = exponential_grid()
    t = np.datetime64("2002-09-07T05:00")
    m, s = grid.mean_std(t, 40.0, 60.0, 400e3)
    m0, s0 = model.mean_std(t, 40.0, 60.0, 400e3)
    assert m == pytest.approx(m0, rel=1e-12)
    assert s == pytest.approx(s0, rel=1e-12)
    # Between latitude nodes the spherical altitude is not linear in latitude: < 0.2 %.
    m, _ = grid.mean_std(t, 42.5, 75.0, 410e3)
    m0, _ = model.mean_std(t, 42.5, 75.0, 410e3)
    assert m == pytest.approx(m0, rel=2e-3)


def test_gridded_propagation_close_to_analytic():
    grid, model = exponential_grid(0.0)
    state = rp.scenarios.paper_state("2002-09-07T00:00")
    craft = rp.scenarios.paper_spacecraft()
    a = rp.propagate(state, craft, grid, 86400.0)
    b = rp.propagate(state, craft, model, 86400.0)
    assert np.linalg.norm(a.positions[-1] - b.positions[-1]) < 1.0


def test_gridded_errors():
    grid, _ = exponential_grid()
    with pytest.raises(rp.DensityFieldError, match="time"):
        grid.mean_std(np.datetime64("2002-09-09T00:00"), 0.0, 0.0, 400e3)
    t = np.array(["2002-09-07", "2002-09-08"], "datetime64[ns]")
    ones = np.ones((2, 2, 3, 4))
    with pytest.raises(ValueError, match="must have shape"):
        rp.density.Gridded(t, [0, 1e3], [-10, 0, 10], [0, 90, 180, 270], ones[:, :1], ones)
    with pytest.raises(ValueError, match="mean must be finite and > 0"):
        rp.density.Gridded(t, [0, 1e3], [-10, 0, 10], [0, 90, 180, 270], -ones, ones)
    with pytest.raises(ValueError, match="around the globe"):
        rp.density.Gridded(t, [0, 1e3], [-10, 0, 10], [0, 30, 60, 90], ones, ones)
    with pytest.raises(ValueError, match="uniformly spaced"):
        rp.density.Gridded(t, [0, 1e3], [-10, 0, 15], [0, 90, 180, 270], ones, ones)
    # Unsorted times named the core's seconds ("time node 1 = -86400"), not the epochs.
    with pytest.raises(ValueError, match=r"times\[1\] \(2002-09-07T00:00:00.000000000\) is before"):
        rp.density.Gridded(t[::-1], [0, 1e3], [-10, 0, 10], [0, 90, 180, 270], ones, ones)


def test_gridded_from_xarray():
    xr = pytest.importorskip("xarray")
    grid, _ = exponential_grid()
    f = grid.native_field
    times = f.epoch + (f.times * 1e9).astype("timedelta64[ns]")
    ds = xr.Dataset(
        {
            "mean": (("time", "alt", "lat", "lon"), np.exp(f.ln_mean)),
            "std": (("time", "alt", "lat", "lon"), np.exp(f.ln_mean) * f.rel_sigma),
        },
        coords={"time": times, "alt": f.altitudes, "lat": f.latitudes, "lon": f.longitudes},
    ).transpose("lat", "time", "lon", "alt")
    again = rp.density.Gridded.from_dataset(ds)
    np.testing.assert_allclose(again.native_field.ln_mean, f.ln_mean)
