"""The density atlas: day tiles against single fields and the model itself, the ceiling's
extrapolation, the memory budget, tile order, the disk cache and bounded sampling."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import _core
from rhoprop.density import atlas as atlas_module
from rhoprop.time import ut1_seconds

#: A coarse grid, so that a day tile of NRLMSIS samples in a fraction of a second.
COARSE = rp.density.FieldResolution(time=3600.0, altitude=50e3, latitude=15.0, longitude=30.0)


def exp_function(t, lat, lon, h):
    """A smooth analytic density (diurnal and latitudinal terms, a slow trend in time)."""
    hours = (t - np.datetime64("2002-09-07T00:00", "ns")) / np.timedelta64(1, "h")
    shape = 1.0 + 0.3 * np.cos(np.radians(lon) + 0.26 * hours) * np.cos(np.radians(lat))
    mean = 3e-12 * np.exp(-(h - 400e3) / 60e3) * shape * (1.0 + 0.002 * hours)
    return mean, 0.1 * mean


def points(n: int, start: str, hours: float, seed: int = 1):
    rng = np.random.default_rng(seed)
    t = np.datetime64(start, "ns") + (rng.uniform(0, hours * 3600e9, n)).astype("timedelta64[ns]")
    return t, rng.uniform(-89, 89, n), rng.uniform(0, 360, n), rng.uniform(150e3, 1400e3, n)


def inertial(t, lat, lon, alt):
    fixed = _core.geodetic_to_fixed(np.stack([lat, lon, alt], axis=1))
    theta = _core.gmst(ut1_seconds(t))
    c, s = np.cos(theta), np.sin(theta)
    return np.stack(
        [c * fixed[:, 0] - s * fixed[:, 1], s * fixed[:, 0] + c * fixed[:, 1], fixed[:, 2]],
        axis=1,
    )


def test_tiles_and_a_single_field_on_the_same_nodes_agree():
    # NRLMSIS over 2 days from 00:00: the single field (altitude nodes on multiples of the
    # spacing, time nodes hourly and on every 3-hourly driver step, as the day tiles) has
    # the tiles' nodes, so the two agree to rounding; the tiles join at midnight.
    model = rp.density.Msis("2.1", resolution=COARSE)
    atlas = rp.density.Atlas(model)
    field = atlas.field("2002-09-07T00:00", "2002-09-09T00:00")
    single = model.field(
        "2002-09-07T00:00", "2002-09-09T00:00", altitude_range=(0.0, 1500e3), cache=False
    )
    t, lat, lon, alt = points(400, "2002-09-07T00:00", 47.0)
    ut1 = ut1_seconds(t)
    m_tiles, s_tiles = field.mean_sigma(ut1, inertial(t, lat, lon, alt))
    m_one, s_one = single.core.mean_sigma(ut1, inertial(t, lat, lon, alt))
    np.testing.assert_allclose(m_tiles, m_one, rtol=1e-9)
    np.testing.assert_allclose(s_tiles, s_one, rtol=1e-9)


def test_tiles_follow_the_model_within_the_interpolation_tolerance():
    # At the default resolution the atlas follows the model itself as the single fields
    # did (FieldResolution's documented 1 % RMS, 3 % max), over two days and all
    # altitudes up to the ceiling.
    model = rp.density.FromFunction(exp_function, name="analytic")
    field = model.atlas.field("2002-09-07T05:00", "2002-09-08T20:00")
    t, lat, lon, alt = points(2000, "2002-09-07T05:00", 39.0, seed=2)
    mean, sigma = field.mean_sigma(ut1_seconds(t), inertial(t, lat, lon, alt))
    want, _want_sigma = exp_function(t, lat, lon, alt)
    rel = mean / want - 1.0
    assert np.sqrt(np.mean(rel**2)) < 0.01 and np.max(np.abs(rel)) < 0.03
    np.testing.assert_allclose(sigma / mean, 0.1, rtol=1e-9)


def test_above_the_ceiling_density_is_continuous_and_keeps_falling():
    model = rp.density.Msis("2.1", resolution=COARSE)
    field = model.atlas.field("2002-09-07T00:00", "2002-09-07T06:00")
    t = np.full(7, np.datetime64("2002-09-07T03:30", "ns"))
    alt = np.array([1499.9e3, 1500e3, 1500.1e3, 2000e3, 5000e3, 20000e3, 36000e3])
    mean, sigma = field.mean_sigma(
        ut1_seconds(t), inertial(t, np.full(7, 20.0), np.full(7, 40.0), alt)
    )
    assert abs(mean[2] / mean[0] - 1) < 1e-3  # continuous at the ceiling
    assert np.all(np.diff(mean) < 0) and np.all(mean > 0) and np.all(np.isfinite(mean))
    # sigma/mean held at its ceiling value
    np.testing.assert_allclose((sigma / mean)[1:], (sigma / mean)[1], rtol=1e-9)
    # The local scale height continued: ln density falls linearly above the ceiling.
    ln = np.log(mean[3:6])
    slope1 = (ln[1] - ln[0]) / (alt[4] - alt[3])
    slope2 = (ln[2] - ln[1]) / (alt[5] - alt[4])
    assert slope1 == pytest.approx(slope2, rel=1e-9)


def test_a_heo_object_whose_sigma_points_pass_the_ceiling_propagates():
    # A GTO-like orbit: perigee 300 km, apogee 35,800 km (its sigma points and members
    # spend most of the day far above the 1,500 km ceiling).
    rp_, ra = 6378137.0 + 300e3, 6378137.0 + 35_800e3
    a = (rp_ + ra) / 2
    v = np.sqrt(rp.constants.MU * (2 / rp_ - 1 / a))
    state = rp.OrbitState("2002-09-07T00:00:00Z", [rp_, 0, 0], [0, v * 0.5, v * 0.866])
    model = rp.density.Msis("2.1", resolution=COARSE)
    craft = rp.Spacecraft(2.2, 0.01)
    res = rp.ccsp(state, craft, model, 86400.0)
    assert np.isfinite(res.covariance).all() and res.decayed_at is None
    mc = rp.monte_carlo(state, craft, model, 86400.0, n=16, seed=3)
    assert np.isfinite(mc.positions).all()


def run_ccsp(model):
    state = rp.scenarios.paper_state()
    return rp.ccsp(state, rp.scenarios.paper_spacecraft(), model, 2 * 86400.0)


def test_a_budget_smaller_than_one_run_and_another_tile_order_give_the_same_bits(
    tmp_path, monkeypatch
):
    model = rp.density.Msis("2.1", resolution=COARSE)
    reference = run_ccsp(model)
    try:
        # No tile kept between runs, and a fresh cache: every tile is sampled again, the
        # last day first.
        rp.density.set_memory_budget(0)
        monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path))
        other = rp.density.Msis("2.1", resolution=COARSE)
        other.atlas.field("2002-09-09T00:00", "2002-09-09T12:00")
        again = run_ccsp(other)
    finally:
        rp.density.set_memory_budget(None)
    np.testing.assert_array_equal(again.mean, reference.mean)
    np.testing.assert_array_equal(again.covariance, reference.covariance)
    # The tiles went to the disk cache, one file per day, listed by model and day.
    info = rp.cache.cache_info(tmp_path)
    (entry,) = info["tiles"]
    assert entry["days"] == ["2002-09-07", "2002-09-08", "2002-09-09"]
    assert "Msis" in entry["model"]


def test_tiles_come_back_from_disk_and_sampling_is_chunked(tmp_path, monkeypatch):
    calls = []

    def counted(t, lat, lon, h):
        calls.append(np.size(t))
        return exp_function(t, lat, lon, h)

    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path))
    model = rp.density.FromFunction(counted, name="counted", cache_key="counted v1")
    first = model.atlas.field("2002-09-07T01:00", "2002-09-08T01:00")
    assert calls and max(calls) <= atlas_module.SAMPLE_POINTS
    sampled = len(calls)
    try:
        rp.density.set_memory_budget(0)  # nothing kept: the next atlas reads the disk
        again = rp.density.FromFunction(counted, name="counted", cache_key="counted v1")
        second = again.atlas.field("2002-09-07T01:00", "2002-09-08T01:00")
    finally:
        rp.density.set_memory_budget(None)
    assert len(calls) == sampled  # no new sampling
    t, lat, lon, alt = points(50, "2002-09-07T01:00", 24.0)
    args = (ut1_seconds(t), inertial(t, lat, lon, alt))
    np.testing.assert_array_equal(first.mean_sigma(*args)[0], second.mean_sigma(*args)[0])


def test_an_atlas_pickles_as_a_reference():
    model = rp.density.Msis("2.1", resolution=COARSE)
    atlas = model.atlas
    before = len(pickle.dumps(atlas))
    atlas.field("2002-09-10T00:00", "2002-09-13T00:00")
    field = atlas.field("2002-09-07T00:00", "2002-09-07T12:00")
    blob = pickle.dumps(atlas)
    assert len(blob) == before  # the model and grid, not the tiles it has made
    back = pickle.loads(blob)
    t, lat, lon, alt = points(50, "2002-09-07T00:00", 12.0)
    args = (ut1_seconds(t), inertial(t, lat, lon, alt))
    np.testing.assert_array_equal(
        back.field("2002-09-07T00:00", "2002-09-07T12:00").mean_sigma(*args)[0],
        field.mean_sigma(*args)[0],
    )


def test_a_time_outside_the_drivers_is_a_clear_error():
    model = rp.density.Msis("2.1", resolution=COARSE)
    _first, last = model.space_weather.span
    # Past the record the message says how to go on (it named no way before).
    with pytest.raises(rp.OutsideRecordError, match=r"drivers from.*with_forecast.*data refresh"):
        model.atlas.field(last - np.timedelta64(1, "h"), last + np.timedelta64(1, "h"))
    # The last day is cut to the record: a run up to its end works (its last days are the
    # record's daily predicted rows: with the forecast's warning).
    with pytest.warns(rp.errors.PredictedDriversWarning):
        field = model.atlas.field(last - np.timedelta64(3, "h"), last)
    assert field.nbytes > 0


def test_memory_is_reported_and_bad_budgets_are_refused(monkeypatch):
    model = rp.density.Msis("2.1", resolution=COARSE)
    model.atlas.field("2002-09-07T00:00", "2002-09-07T12:00")
    memory = rp.density.field_memory()
    assert memory.peak >= memory.live > 0 and memory.tiles >= 1
    with pytest.raises(ValueError, match="nbytes"):
        rp.density.set_memory_budget(-1)
    for bad in ("x", "1e9", object()):  # a string said "could not convert string to float"
        with pytest.raises(TypeError, match="nbytes must be a number of bytes"):
            rp.density.set_memory_budget(bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="too fine"):
        rp.density.Atlas(model, rp.density.FieldResolution(latitude=1e-3))


def test_dask_workers_sample_or_read_tiles_and_give_the_same_bits(tmp_path, monkeypatch):
    # The workers get the atlas as a reference (model and grid); with a cache directory of
    # their own they sample the tiles themselves, and the results equal the local run's
    # bit for bit.
    distributed = pytest.importorskip("distributed")
    from test_catalog import END, SAMPLE

    model = rp.density.Msis("2.1", resolution=COARSE)
    cat = rp.catalog.load(SAMPLE)
    local = rp.catalog.propagate_catalog(
        cat,
        model,
        END,
        output_step=1800.0,
        execution=rp.Execution(progress=False),
    )
    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path))
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote = rp.catalog.propagate_catalog(
            cat,
            model,
            END,
            output_step=1800.0,
            execution=rp.Execution(client=client, chunk_size=2, progress=False),
        )
    np.testing.assert_array_equal(remote.mean, local.mean)
    np.testing.assert_array_equal(remote.covariance, local.covariance)
    assert rp.cache.cache_info(tmp_path)["tiles"], "the workers wrote their own tiles"


def test_a_floor_below_the_atlas_is_refused_and_stages_below_the_bottom_read_it():
    # JB2008-like models start at 90 km: a floor below that is refused up front. In an
    # open field a lookup below the bottom reads the bottom level (only stages of a step
    # that crosses the floor get there).
    model = rp.density.FromFunction(exp_function, name="analytic")  # lowest 50 km
    state = rp.scenarios.paper_state()
    with pytest.raises(ValueError, match="lowest altitude"):
        rp.propagate(
            state,
            rp.Spacecraft(2.2, 0.01),
            model,
            3600.0,
            dynamics=rp.Dynamics(floor_altitude=30e3),
        )
    field = model.atlas.field("2002-09-07T00:00", "2002-09-07T06:00")
    t = np.full(2, np.datetime64("2002-09-07T03:00", "ns"))
    mean, _ = field.mean_sigma(
        ut1_seconds(t), inertial(t, np.full(2, 10.0), np.full(2, 20.0), np.array([50e3, 20e3]))
    )
    assert mean[1] == pytest.approx(mean[0], rel=1e-9)  # 50 km is the bottom node


def test_a_long_run_streams_its_tiles_and_gives_the_bits_of_the_whole_field(monkeypatch):
    # A 12-day Monte Carlo (more than STREAM_TILES day tiles) gets a streamed field that
    # holds STREAM_KEEP tiles besides those in use, not all twelve: the members, the mean
    # orbit and the densities are those of the field of every tile, bit for bit.
    model = rp.density.FromFunction(exp_function, name="analytic", resolution=COARSE)
    state = rp.scenarios.paper_state()
    days = 12.0
    streamed = model.atmosphere(state, days * 86400.0)
    assert isinstance(streamed, _core.StreamedAtmosphere)
    assert len(streamed) == 13  # the paper's epoch is mid-day: 13 day tiles
    whole = model.atlas.field(state.epoch, rp.time.add_seconds(state.epoch, days * 86400.0))
    assert isinstance(whole, _core.GriddedAtmosphere)

    def run(atmosphere):
        return rp.monte_carlo(
            state,
            rp.scenarios.paper_spacecraft(),
            atmosphere,
            days * 86400.0,
            n=40,
            seed=3,
            output_step=6 * 3600.0,
            record_density=True,
            progress=False,
            drag_sigma=0.1,
        )

    a, b = run(whole), run(streamed)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.velocities, b.velocities)
    np.testing.assert_array_equal(a.densities, b.densities)
    np.testing.assert_array_equal(a.mean_orbit.positions, b.mean_orbit.positions)
    assert streamed.loads >= 13
    assert streamed.nbytes <= atlas_module.STREAM_KEEP * max(
        t.nbytes
        for t in [model.atlas.tile(*w) for w in model.atlas.windows(state.epoch, state.epoch)]
    )
    # Through the model (the path every propagator takes): the same bits again.
    c = run(model)
    np.testing.assert_array_equal(a.positions, c.positions)


def test_a_tile_that_fails_in_a_streamed_run_raises_its_own_error():
    # The source runs on a worker thread inside the core; its exception reaches the
    # caller as itself (here the model's ZeroDivisionError on day 10), not as a core
    # message.
    state = rp.scenarios.paper_state()
    start = np.datetime64(state.epoch, "ns")

    def failing(t, lat, lon, h):
        if (np.asarray(t) > start + np.timedelta64(10, "D")).any():
            raise ZeroDivisionError("the model broke on day 10")
        return exp_function(t, lat, lon, h)

    model = rp.density.FromFunction(failing, name="failing", resolution=COARSE)
    with pytest.raises(ZeroDivisionError, match="broke on day 10"):
        rp.propagate(state, rp.scenarios.paper_spacecraft(), model, 12 * 86400.0)


def test_runs_over_the_same_days_share_one_streamed_field():
    # ccsp_many groups its runs by atmosphere object: a new streamed field per run split
    # objects with the same span into separate core calls.
    model = rp.density.FromFunction(exp_function, name="analytic", resolution=COARSE)
    state = rp.scenarios.paper_state()
    a = model.atmosphere(state, 12 * 86400.0)
    b = model.atmosphere(state, 12 * 86400.0 - 60.0)  # the same day tiles
    assert isinstance(a, _core.StreamedAtmosphere) and a is b
