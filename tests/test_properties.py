"""Property-based tests of the public API's contract: whatever the
input, a call gives a result or a clear ValueError/TypeError, never another exception, a
crash, a hang or a NaN in a result.

Bounded and deterministic: every test runs at most ``MAX_EXAMPLES`` examples, derandomized
(the same examples on every run, no example database), each example under a time limit.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import math
import signal
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import rhoprop as rp
from rhoprop import time as rt
from rhoprop.constants import MU

MAX_EXAMPLES = 40
#: Seconds one example may take before it counts as a hang.
TIME_LIMIT = 20.0

PROFILE = settings(
    max_examples=MAX_EXAMPLES,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)


class Hang(Exception):
    """An example ran longer than TIME_LIMIT."""


@contextlib.contextmanager
def time_limit(seconds: float = TIME_LIMIT) -> Iterator[None]:
    def alarm(signum: int, frame: Any) -> None:
        raise Hang(f"no answer within {seconds} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def contract(call: Callable[[], Any]) -> Any:
    """The call's result, or None after a ValueError/TypeError with a message. Any other
    exception (and a hang) fails the test."""
    with time_limit():
        try:
            return call()
        except (ValueError, TypeError) as err:
            assert str(err).strip(), f"{type(err).__name__} without a message"
            return None


def finite(*arrays: Any) -> bool:
    return all(np.isfinite(np.asarray(a, dtype=float)).all() for a in arrays)


# -- strategies --------------------------------------------------------------------------

odd_floats = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, 1e-9, 1e300, -1.0, math.nan, math.inf]),
)
any_scalar = st.one_of(
    odd_floats,
    st.integers(min_value=-(2**70), max_value=2**70),
    st.booleans(),
    st.none(),
    st.text(max_size=8),
)


@st.composite
def iso_strings(draw: st.DrawFn) -> str:
    """ISO-like strings around the edges: odd years, seconds 60, zones, junk."""
    year = draw(st.sampled_from([1600, 1677, 1678, 1972, 2002, 2016, 2017, 2261, 2262, 2500]))
    month = draw(st.integers(0, 13))
    day = draw(st.integers(0, 32))
    hour = draw(st.integers(0, 25))
    minute = draw(st.integers(0, 60))
    second = draw(st.integers(0, 61))
    frac = draw(st.sampled_from(["", ".5", ".123456789", ".1234567891234"]))
    zone = draw(st.sampled_from(["", "Z", "z", "+02:00", "-05:30", "+0100", "+14", "+25:00"]))
    text = f"{year:04d}-{month:02d}-{day:02d}T{hour:02d}:{minute:02d}:{second:02d}{frac}{zone}"
    return draw(st.sampled_from([text, text[:10], text[:16], " " + text + " "]))


valid_datetimes = st.datetimes(
    min_value=dt.datetime(1678, 1, 2),
    max_value=dt.datetime(2261, 12, 30),
    timezones=st.sampled_from(
        [None, dt.timezone.utc, dt.timezone(dt.timedelta(hours=5, minutes=45))]
    ),
)
#: Epochs that should mostly be accepted: datetimes and their ISO strings (any zone).
plausible_epochs = st.one_of(
    valid_datetimes,
    valid_datetimes.map(lambda d: d.isoformat()),
    valid_datetimes.map(lambda d: d.isoformat(sep=" ").replace("+00:00", "Z")),
    valid_datetimes.map(lambda d: np.datetime64(d.replace(tzinfo=None), "us")),
)
epoch_inputs = st.one_of(
    plausible_epochs,
    plausible_epochs,
    iso_strings(),
    st.text(max_size=25),
    st.sampled_from(["", "NaT", "nat", "now", "2016-12-31T23:59:60", "2015-12-31T23:59:60"]),
    st.datetimes(
        min_value=dt.datetime(1, 1, 1),
        max_value=dt.datetime(9999, 12, 31),
        timezones=st.sampled_from(
            [None, dt.timezone.utc, dt.timezone(dt.timedelta(hours=-11, minutes=-30))]
        ),
    ),
    st.dates(),
    st.builds(
        lambda value, unit: np.datetime64(value, unit),
        st.integers(-(2**40), 2**40),
        st.sampled_from(["Y", "M", "D", "h", "s", "ms", "us", "ns"]),
    ),
    st.just(np.datetime64("NaT")),
    any_scalar,
)

in_range_epochs = st.integers(
    int(rt.FIRST_EPOCH.astype(np.int64)), int(rt.END_EPOCH.astype(np.int64)) - 1
).map(lambda ns: np.datetime64(ns, "ns"))


def vectors(size: int = 3) -> st.SearchStrategy[Any]:
    return st.one_of(
        st.lists(odd_floats, min_size=size, max_size=size),
        st.lists(st.floats(-1e8, 1e8), min_size=0, max_size=5),
        any_scalar,
    )


@st.composite
def orbital_states(draw: st.DrawFn) -> tuple[list[float], list[float]]:
    """Mostly plausible LEO states (so that propagation gets exercised), sometimes odd."""
    radius = draw(st.floats(6.65e6, 7.6e6))  # perigee above the 120-km floor
    speed_factor = draw(st.floats(0.95, 1.08))
    lat = draw(st.floats(-1.5, 1.5))
    lon = draw(st.floats(0, 2 * math.pi))
    r = radius * np.array(
        [math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)]
    )
    # A direction perpendicular to r, rotated by a random angle about r.
    a = np.cross(r, [0.0, 0.0, 1.0]) if abs(math.sin(lat)) < 0.99 else np.cross(r, [1.0, 0, 0])
    a /= np.linalg.norm(a)
    b = np.cross(r / radius, a)
    angle = draw(st.floats(0, 2 * math.pi))
    v = speed_factor * math.sqrt(MU / radius) * (math.cos(angle) * a + math.sin(angle) * b)
    return r.tolist(), v.tolist()


paper = rp.scenarios.paper_state()
craft = rp.scenarios.paper_spacecraft()


# -- time --------------------------------------------------------------------------------


@PROFILE
@given(epoch_inputs)
def test_any_epoch_input(value):
    out = contract(lambda: rt.to_datetime64(value, "epoch"))
    if out is not None:
        assert rt.FIRST_EPOCH <= out < rt.END_EPOCH
        # What we give back we take back.
        assert rt.to_datetime64(str(out)) == out
        assert rt.to_datetime64(out) == out


@PROFILE
@given(st.lists(epoch_inputs, max_size=4))
def test_any_epoch_array(values):
    out = contract(lambda: rt.to_datetime64_array(np.array(values, dtype=object), "times"))
    if out is not None:
        assert out.dtype == np.dtype("M8[ns]") and not np.isnat(out).any()


@PROFILE
@given(in_range_epochs, in_range_epochs, in_range_epochs)
def test_elapsed_seconds_add_up_and_invert(a, b, c):
    ab, bc, ac = rt.seconds_between(a, b), rt.seconds_between(b, c), rt.seconds_between(a, c)
    assert math.isfinite(ab) and abs(ab + bc - ac) <= 1e-5 * max(1.0, abs(ac)) * 1e-9 + 1e-5
    # Back from elapsed seconds to the epoch, within the float resolution of the offset.
    back = contract(lambda: rt.add_seconds(a, ab))
    if back is not None:
        tolerance = max(1e-9, abs(ab) * 2e-16) * 1e9 + 1
        assert abs(int((back - b) / np.timedelta64(1, "ns"))) <= tolerance
    ut1 = rt.ut1_seconds(b)
    assert math.isfinite(ut1)
    assert math.isfinite(rt.seconds_since_j2000(b))


@PROFILE
@given(in_range_epochs, st.lists(odd_floats, max_size=4))
def test_offsets_to_epochs(epoch, seconds):
    out = contract(lambda: rt.offsets_to_epochs(epoch, seconds))
    if out is not None:
        assert out.shape == (len(seconds),) and not np.isnat(out).any()
        assert ((out >= rt.FIRST_EPOCH) & (out < rt.END_EPOCH)).all()


@PROFILE
@given(
    st.one_of(odd_floats, st.floats(2.3e6, 2.6e6)),
    odd_floats,
    st.sampled_from(["utc", "tt", "tai", "tdb", ""]),
)
def test_julian_dates(jd, jd2, scale):
    out = contract(lambda: rt.from_jd(jd, jd2, scale=scale))
    if out is not None:
        assert rt.FIRST_EPOCH <= out < rt.END_EPOCH


# -- plain data --------------------------------------------------------------------------


@PROFILE
@given(epoch_inputs, vectors(), vectors())
def test_orbit_state_from_anything(epoch, position, velocity):
    state = contract(lambda: rp.OrbitState(epoch, position, velocity))
    if state is not None:
        assert finite(state.position, state.velocity)


@PROFILE
@given(plausible_epochs, orbital_states(), st.sampled_from([1.0, 1.0, 1e-3, 1e3]))
def test_orbit_state_accepts_orbits_and_refuses_units(epoch, rv, scale):
    # Orbits pass; the same in km (or mm) are refused with a message.
    r, v = (np.array(x) * scale for x in rv)
    state = contract(lambda: rp.OrbitState(epoch, r, v))
    if scale == 1.0:
        assert state is not None and finite(state.state)
    else:
        assert state is None


@PROFILE
@given(any_scalar, any_scalar)
def test_spacecraft(cd, area_to_mass):
    out = contract(lambda: rp.Spacecraft(cd, area_to_mass))
    if out is not None:
        assert out.drag_parameter > 0 and math.isfinite(out.drag_parameter)


@PROFILE
@given(any_scalar, any_scalar, any_scalar, any_scalar)
def test_exponential_parameters(rho0, h0, scale_height, rel_sigma):
    model = contract(lambda: rp.density.Exponential(rho0, h0, scale_height, rel_sigma))
    if model is not None:
        out = contract(lambda: model.mean_std("2002-09-07", 10.0, 20.0, 400e3))
        if out is not None:
            mean, std = out
            # A finite model gives finite densities at 400 km (or overflows to inf/0,
            # which is what the formula says; never NaN).
            assert not np.isnan(mean) and not np.isnan(std)


@PROFILE
@given(
    st.one_of(epoch_inputs, st.lists(plausible_epochs, min_size=1, max_size=3)),
    st.one_of(st.floats(-90, 90), odd_floats, st.lists(st.floats(-100, 100), max_size=3)),
    st.one_of(st.floats(-360, 720), odd_floats),
    st.one_of(st.floats(-1e5, 2e6), odd_floats, st.lists(st.floats(0, 1e6), max_size=3)),
)
def test_density_inputs(times, lat, lon, alt):
    model = rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=0.2)
    out = contract(lambda: model.mean_std(times, lat, lon, alt))
    if out is not None:
        mean, std = out
        assert not np.isnan(mean).any() and (np.asarray(mean) >= 0).all()
        assert not np.isnan(std).any() and (np.asarray(std) >= 0).all()


# -- frames ------------------------------------------------------------------------------


@PROFILE
@given(epoch_inputs, st.one_of(vectors(), st.lists(vectors(), max_size=3)))
def test_frames(epoch, positions):
    for fn in (rp.frames.inertial_to_fixed, rp.frames.fixed_to_inertial):
        out = contract(lambda fn=fn: fn(epoch, positions))
        if out is not None:
            assert finite(out)
    out = contract(lambda: rp.frames.geodetic(positions))
    if out is not None:
        assert finite(out)
    out = contract(lambda: rp.frames.gmst(epoch))
    if out is not None:
        assert 0 <= out < 2 * math.pi


@PROFILE
@given(odd_floats, odd_floats, odd_floats)
def test_geodetic_to_fixed(lat, lon, alt):
    out = contract(lambda: rp.frames.geodetic_to_fixed(lat, lon, alt))
    if out is not None:
        assert finite(out)
        back = contract(lambda: rp.frames.geodetic(out))
        if back is not None and abs(alt) < 1e7 and abs(lat) < 89.0:
            assert back[0] == pytest.approx(lat, abs=1e-6)
            assert back[2] == pytest.approx(alt, abs=1e-2)


@PROFILE
@given(vectors(), vectors())
def test_rtn(position, velocity):
    out = contract(lambda: rp.frames.rtn_basis(position, velocity))
    if out is not None:
        assert finite(out)


# -- propagation -------------------------------------------------------------------------

#: (process class, parameters): built inside the tests, whose contract covers the errors.
kappa_specs = st.one_of(
    st.tuples(st.just(rp.kappa.White), st.tuples(st.one_of(st.floats(1.0, 600.0), odd_floats))),
    st.tuples(
        st.just(rp.kappa.Interpolated), st.tuples(st.one_of(st.floats(60.0, 3600.0), odd_floats))
    ),
    st.tuples(
        st.just(rp.kappa.GaussMarkov), st.tuples(st.one_of(st.floats(60.0, 3600.0), odd_floats))
    ),
    st.tuples(st.just(rp.kappa.Constant), st.just(())),
    st.tuples(
        st.just(rp.kappa.PiecewiseConstant),
        st.tuples(
            st.one_of(st.floats(60.0, 3600.0), odd_floats),
            st.one_of(st.floats(-0.99, 0.99), odd_floats),
        ),
    ),
    st.tuples(st.sampled_from([rp.kappa.White, rp.kappa.GaussMarkov]), st.tuples(any_scalar)),
)


@PROFILE
@given(kappa_specs)
def test_kappa_processes(spec):
    cls, args = spec
    process = contract(lambda: cls(*args))
    if process is not None:
        d = process.correlation_time()
        assert d > 0 and not math.isnan(d)


plausible_durations = st.floats(1.0, 3600.0)
durations = st.one_of(
    *[plausible_durations] * 6,
    st.sampled_from([0.0, -60.0, math.nan, math.inf, 1e-12]),
)
steps = st.one_of(
    st.none(),
    st.none(),
    st.floats(5.0, 600.0),
    st.sampled_from([1e-9, 1e-3, 0.0, -10.0, 1e9, math.nan]),
)


def check_trajectory(tr: Any) -> None:
    assert finite(tr.times, tr.positions, tr.velocities)
    assert tr.positions.shape == (len(tr.times), 3)


@PROFILE
@given(
    orbital_states(),
    plausible_durations,
    st.sampled_from(["dop853", "rk8", "rk4"]),
    st.one_of(st.none(), st.floats(5.0, 300.0)),
    st.one_of(st.none(), st.floats(60.0, 4000.0)),
    st.floats(0.0, 0.5),
)
def test_propagate_exponential(rv, duration, method, step, output_step, rel_sigma):
    state = rp.OrbitState("2002-09-07T01:00Z", *rv)
    model = rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=rel_sigma)
    tr = contract(
        lambda: rp.propagate(
            state,
            craft,
            model,
            duration,
            output_step=output_step,
            dynamics=rp.Dynamics(integrator=method, step=step),
        )
    )
    if tr is not None:
        check_trajectory(tr)


@PROFILE
@given(
    durations,
    st.sampled_from(["dop853", "rk8", "rk4", "euler", "", None]),
    steps,
    st.one_of(st.none(), st.floats(1.0, 4000.0), st.sampled_from([0.0, -5.0, 1e-6, math.nan])),
    st.one_of(st.none(), odd_floats),
    st.one_of(st.just(120e3), odd_floats),
)
def test_propagate_odd_arguments(duration, method, step, output_step, rtol, floor):
    model = rp.density.Exponential(3.725e-12, 400e3, 58.515e3)
    tr = contract(
        lambda: rp.propagate(
            paper,
            craft,
            model,
            duration,
            output_step=output_step,
            dynamics=rp.Dynamics(floor_altitude=floor, integrator=method, step=step, rtol=rtol),
        )
    )
    if tr is not None:
        check_trajectory(tr)


def check_monte_carlo(result: Any) -> None:
    alive = result.times[None, :] < result.decay_times[:, None]
    assert finite(result.positions[alive], result.velocities[alive])
    assert finite(result.mean_orbit.positions)


@PROFILE
@given(
    orbital_states(),
    st.floats(60.0, 1800.0),
    st.integers(2, 8),
    st.sampled_from(
        [
            rp.kappa.GaussMarkov(),
            rp.kappa.GaussMarkov(300.0),
            rp.kappa.White(10.0),
            rp.kappa.White(60.0),
            rp.kappa.Interpolated(600.0),
            rp.kappa.Constant(),
            rp.kappa.PiecewiseConstant(600.0, 1 / 3),
        ]
    ),
    st.one_of(st.none(), st.sampled_from([30.0, 60.0, 180.0])),
    st.one_of(st.none(), st.sampled_from([60.0, 180.0, 600.0])),
    st.sampled_from(["additive", "lognormal"]),
    st.sampled_from(["rk8", "rk4"]),
)
def test_monte_carlo_exponential(rv, duration, n, kappa, step, output_step, perturbation, method):
    state = rp.OrbitState("2002-09-07T01:00Z", *rv)
    model = rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=0.2)
    result = contract(
        lambda: rp.monte_carlo(
            state,
            craft,
            model,
            duration,
            n=n,
            kappa=kappa,
            dynamics=rp.Dynamics(integrator=method, step=step),
            output_step=output_step,
            perturbation=perturbation,
            progress=False,
            threads=2,
        )
    )
    if result is not None:
        check_monte_carlo(result)


@PROFILE
@given(
    st.one_of(st.floats(60.0, 1800.0), st.sampled_from([0.0, -1.0, math.nan])),
    st.one_of(st.integers(2, 8), st.sampled_from([-1, 0, 1, 2**40]), any_scalar),
    kappa_specs,
    st.one_of(st.none(), st.floats(30.0, 600.0), st.sampled_from([1e-6, 0.0, 1e9])),
    st.one_of(st.none(), st.sampled_from([60.0, 180.0, 600.0, 0.0, 1e-3])),
    st.sampled_from(["additive", "lognormal", "multiplicative"]),
    st.one_of(st.none(), st.integers(-2, 4)),
    st.one_of(st.none(), vectors(36), st.just(np.eye(6)), st.just(np.full((6, 6), np.nan))),
)
def test_monte_carlo_odd_arguments(
    duration, n, spec, step, output_step, perturbation, threads, covariance
):
    kappa = contract(lambda: spec[0](*spec[1]))
    assume(kappa is not None)
    model = rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=0.2)
    if isinstance(covariance, list) and len(covariance) == 36:
        covariance = np.reshape(covariance, (6, 6))
    result = contract(
        lambda: rp.monte_carlo(
            paper,
            craft,
            model,
            duration,
            n=n,
            kappa=kappa,
            dynamics=rp.Dynamics(step=step),
            output_step=output_step,
            perturbation=perturbation,
            progress=False,
            threads=threads,
            initial_covariance=covariance,
        )
    )
    if result is not None:
        check_monte_carlo(result)
