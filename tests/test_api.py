"""The Python API: types, shapes, epochs, and clear errors on bad input."""

from __future__ import annotations

import dataclasses
import datetime as dt

import numpy as np
import pytest

import rhoprop as rp

#: The attributes of rp.Dynamics (given to a run whole, as dynamics=).
DYNAMICS = {f.name for f in dataclasses.fields(rp.Dynamics)}


def test_trajectory_shapes_and_epochs(paper_state, paper_craft, benchmark_atmosphere):
    tr = rp.propagate(paper_state, paper_craft, benchmark_atmosphere, 7000.0, output_step=3000.0)
    np.testing.assert_array_equal(tr.times, [0.0, 3000.0, 6000.0, 7000.0])
    assert tr.positions.shape == (4, 3) and tr.velocities.shape == (4, 3)
    assert tr.states.shape == (4, 6)
    assert tr.epochs[-1] == np.datetime64("2002-09-07T02:56:40", "ns")
    np.testing.assert_array_equal(tr.positions[0], paper_state.position)
    assert tr.decayed_at is None and tr.clipped == 0 and tr.evaluations > 0
    end = tr.state_at(-1)
    assert isinstance(end, rp.OrbitState) and end.epoch == tr.epochs[-1]
    # Start and end only by default.
    assert rp.propagate(paper_state, paper_craft, benchmark_atmosphere, 60.0).times.tolist() == [
        0.0,
        60.0,
    ]


@pytest.mark.parametrize(
    "epoch",
    [
        "2002-09-07T01:00:00Z",
        "2002-09-07T01:00:00",
        dt.datetime(2002, 9, 7, 1),
        dt.datetime(2002, 9, 7, 3, tzinfo=dt.timezone(dt.timedelta(hours=2))),
        np.datetime64("2002-09-07T01:00"),
    ],
)
def test_epoch_forms(epoch):
    s = rp.OrbitState(epoch, [7e6, 0, 0], [0, 7.5e3, 0])
    assert s.epoch == np.datetime64("2002-09-07T01:00:00", "ns")


def test_seconds_since_j2000():
    # J2000 is 2000-01-01T12:00 TT, 64.184 s before 12:00 UTC (rhoprop.time).
    assert rp.seconds_since_j2000("2000-01-01T12:00:00") == pytest.approx(64.184, abs=1e-9)
    assert rp.seconds_since_j2000("2000-01-02T12:00:00.5") == pytest.approx(86464.684, abs=1e-9)


def test_timedelta_duration(paper_state, paper_craft, benchmark_atmosphere):
    a = rp.propagate(paper_state, paper_craft, benchmark_atmosphere, dt.timedelta(hours=1))
    b = rp.propagate(paper_state, paper_craft, benchmark_atmosphere, 3600.0)
    np.testing.assert_array_equal(a.positions, b.positions)


def test_exponential_mean_std():
    model = rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=0.2)
    # At the equator geodetic and spherical altitude coincide.
    mean, std = model.mean_std(np.datetime64("2002-09-07"), 0.0, [0.0, 90.0], 400e3)
    np.testing.assert_allclose(mean, 3.725e-12, rtol=1e-12)
    np.testing.assert_allclose(std, 0.2 * 3.725e-12, rtol=1e-12)
    # At the pole a geodetic altitude of 400 km is 21.4 km lower in spherical altitude.
    pole, _ = model.mean_std(np.datetime64("2002-09-07"), 90.0, 0.0, 400e3)
    spherical = 6356752.314245 + 400e3 - 6378137.0
    assert pole == pytest.approx(3.725e-12 * np.exp(-(spherical - 400e3) / 58.515e3), rel=1e-9)


def test_decay_is_reported_not_raised(paper_state, paper_craft):
    dense = rp.density.Exponential(1e-9, 400e3, 58.515e3)
    tr = rp.propagate(paper_state, paper_craft, dense, 259200.0, output_step=3600.0)
    assert tr.decayed_at is not None and tr.decayed_at < 259200.0
    assert len(tr.times) < 73 and np.isfinite(tr.positions).all()


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"position": [np.nan, 0, 0]}, ValueError, r"position\[0\] must be finite"),
        ({"velocity": [0, np.inf, 0]}, ValueError, r"velocity\[1\] must be finite"),
        ({"position": [1e6, 0, 0]}, ValueError, "below the Earth's surface"),
        ({"position": [6.45e6, 0, 0]}, ValueError, "below the decay floor"),
        ({"position": [1, 2]}, ValueError, r"shape \(3,\)"),
        ({"cd": 0.0}, ValueError, "cd must be > 0"),
        ({"cd": -3.0}, ValueError, "cd must be > 0"),
        ({"area_to_mass": 0.0}, ValueError, "area_to_mass must be > 0"),
        ({"area_to_mass": "big"}, TypeError, "area_to_mass must be a real number"),
        ({"duration": 0.0}, ValueError, "duration must be > 0"),
        ({"duration": -5.0}, ValueError, "duration must be > 0"),
        ({"duration": np.nan}, ValueError, "duration must be finite"),
        ({"integrator": "euler"}, ValueError, "integrator must be one of"),
        ({"integrator": "rk8", "step": -1.0}, ValueError, "step must be > 0"),
        ({"integrator": "rk8", "rtol": 1e-9}, ValueError, "rtol applies to integrator .dop853."),
        ({"rtol": 0.0}, ValueError, "rtol must be > 0"),
        ({"rtol": 5.0}, ValueError, r"rtol = 5 is outside \[1e-14, 0\.01\]"),
        ({"output_step": 0.0}, ValueError, "output_step must be > 0"),
        ({"epoch": "yesterday"}, ValueError, "not an ISO-8601 UTC time"),
        ({"epoch": 12.0}, TypeError, "epoch must be an ISO string"),
        ({"model": "msis"}, TypeError, "model must be a rhoprop density model"),
        ({"integrator": "rk8", "step": 86400.0}, ValueError, "step = 86400 s is too large"),
        ({"integrator": "rk4", "step": 1e-6}, ValueError, "more than the 10,000,000"),
        ({"output_step": 1e-6}, ValueError, "more than the 10,000,000 a run may have"),
    ],
)
def test_bad_input_raises_clearly(kwargs, error, message):
    state = dict(
        epoch="2002-09-07T01:00:00",
        position=rp.scenarios.PAPER_POSITION,
        velocity=rp.scenarios.PAPER_VELOCITY,
    )
    craft = dict(cd=3.0912, area_to_mass=0.0015)
    call = dict(model=rp.scenarios.benchmark_exponential(), duration=3600.0)
    options = {}
    for key, value in kwargs.items():
        for target in (state, craft, call):
            if key in target:
                target[key] = value
                break
        else:
            options[key] = value
    dynamics = {k: options.pop(k) for k in list(options) if k in DYNAMICS}
    with pytest.raises(error, match=message):
        # Inside the check: a bad integrator, step or rtol is refused by rp.Dynamics itself.
        rp.propagate(
            rp.OrbitState(**state),
            rp.Spacecraft(**craft),
            call["model"],
            call["duration"],
            dynamics=rp.Dynamics(**dynamics),
            **options,
        )


def test_core_errors_are_value_errors():
    assert issubclass(rp.RhopropError, ValueError)
    assert issubclass(rp.DensityFieldError, rp.RhopropError)
    with pytest.raises(rp.RhopropError, match="scale_height = -1 is invalid"):
        rp._core.ExponentialAtmosphere(1e-12, 400e3, -1.0)


def test_bad_exponential_parameters():
    with pytest.raises(ValueError, match="rel_sigma must be >= 0"):
        rp.density.Exponential(1e-12, 400e3, 58e3, rel_sigma=-0.1)
    with pytest.raises(ValueError, match="rho0 must be > 0"):
        rp.density.Exponential(0.0, 400e3, 58e3)


def test_model_is_the_argument_name_and_density_a_deprecated_alias(
    paper_state, paper_craft, benchmark_atmosphere
):
    a = rp.propagate(paper_state, paper_craft, model=benchmark_atmosphere, duration=600.0)
    with pytest.warns(DeprecationWarning, match="density=...\\) is deprecated"):
        b = rp.propagate(paper_state, paper_craft, density=benchmark_atmosphere, duration=600.0)
    np.testing.assert_array_equal(a.positions, b.positions)
    with pytest.raises(TypeError, match="both model and density"), pytest.warns(DeprecationWarning):
        rp.propagate(
            paper_state, paper_craft, benchmark_atmosphere, 600.0, density=benchmark_atmosphere
        )
    with pytest.raises(TypeError, match="missing required argument: 'model'"):
        rp.propagate(paper_state, paper_craft, duration=600.0)
    for call in (rp.monte_carlo, rp.ccsp):
        with pytest.raises(TypeError, match="model must be a rhoprop density model"):
            call(paper_state, paper_craft, "msis", 600.0)


@pytest.mark.parametrize("method", ["rk8", "rk4"])
def test_fixed_step_defaults_meet_one_metre(paper_state, paper_craft, benchmark_atmosphere, method):
    # The per-method default step (RK8 180 s, RK4 5 s) ends 3 days within 1 m of the
    # adaptive DOP853 at rtol 1e-12 (measured 0.06 m and 0.12 m).
    tr = rp.propagate(
        paper_state,
        paper_craft,
        benchmark_atmosphere,
        259200.0,
        dynamics=rp.Dynamics(integrator=method),
    )
    ref = rp.propagate(
        paper_state,
        paper_craft,
        benchmark_atmosphere,
        259200.0,
        dynamics=rp.Dynamics(rtol=1e-12),
    )
    assert np.linalg.norm(tr.positions[-1] - ref.positions[-1]) < 1.0
