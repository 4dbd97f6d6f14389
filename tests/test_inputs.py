"""Input sanity of the plain data types: a state that is not an Earth
orbit in SI units is refused when it is made, with what was expected, instead of failing
later ("adaptive integrator: step size underflow")."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.constants import MU, R_EARTH, R_POLE

EPOCH = "2002-09-07T01:00:00Z"


def circular(radius: float) -> float:
    return float(np.sqrt(MU / radius))


@pytest.mark.parametrize(
    ("position", "velocity"),
    [
        (rp.scenarios.PAPER_POSITION, rp.scenarios.PAPER_VELOCITY),
        ([7e6, 0, 0], [0, 7.5e3, 0]),
        ([0, 0, R_POLE + 100.0], [circular(R_POLE), 0, 0]),  # just above the pole
        ([42_164e3, 0, 0], [0, 3074.7, 0]),  # geostationary
        ([6_778e3, 0, 0], [0, 1.4 * circular(6_778e3), 0]),  # perigee of e = 0.96
        ([9.9 * R_EARTH, 0, 0], [0, 0.31 * circular(9.9 * R_EARTH), 0]),  # apogee, far out
    ],
)
def test_orbits_pass(position, velocity):
    state = rp.OrbitState(EPOCH, position, velocity)
    np.testing.assert_array_equal(state.position, position)


@pytest.mark.parametrize(
    ("position", "velocity", "message"),
    [
        # The paper's state in km and km/s, then each in turn.
        ([3782.9007, -5441.6007, -1420.0751], [-0.6067, 1.5393, -7.4884], "position looks like km"),
        (
            [6800.0, 0, 0],
            [0, 7.6e3, 0],
            r"position looks like km: \|r\| = 6800; rhoprop takes metres",
        ),
        (rp.scenarios.PAPER_POSITION, [-0.6067, 1.5393, -7.4884], "velocity looks like km/s"),
        ([7e6, 0, 0], [0, 7.5, 0], r"velocity looks like km/s: \|v\| = 7.5; rhoprop takes m/s"),
        # Inside the WGS-84 ellipsoid: at the equator 6370 km is 8 km underground, while at
        # the pole the same radius is 13 km up (accepted above).
        ([6_370e3, 0, 0], [0, 7.9e3, 0], "below the Earth's surface"),
        ([1e6, 0, 0], [0, 7e3, 0], "below the Earth's surface"),
        ([0, 0, 0], [0, 7e3, 0], "below the Earth's surface"),
        ([1e8, 0, 0], [0, 2e3, 0], "15.7 Earth radii .* within 10 Earth radii"),
        ([3.8e11, 0, 0], [0, 1e3, 0], "Earth radii"),  # lunar distance in mm
        ([7e6, 0, 0], [0, 0, 0], r"speed \|v\| = 0 m/s is not orbital"),
        ([7e6, 0, 0], [0, 2e3, 0], r"expected 0.3 to 1.5 times the circular speed"),
        ([7e6, 0, 0], [0, 12e3, 0], "not orbital"),
        ([7e6, 0, 0], [0, 7.5e6, 0], "not orbital"),  # mm/s
    ],
)
def test_non_orbits_raise_saying_what_was_expected(position, velocity, message):
    with pytest.raises(ValueError, match=message):
        rp.OrbitState(EPOCH, position, velocity)


def test_km_state_fails_at_construction_not_in_the_integrator():
    # The motivating example: a state in km used to fail in propagate with "adaptive
    # integrator: step size underflow (h = 1.2e-37 s)".
    with pytest.raises(ValueError, match="looks like km"):
        rp.OrbitState(
            EPOCH, np.array(rp.scenarios.PAPER_POSITION) / 1e3, rp.scenarios.PAPER_VELOCITY
        )


def test_bounds_are_the_documented_ones():
    from rhoprop.propagation import state

    assert state.MAX_RADII == 10.0 and state.SPEED_RANGE == (0.3, 1.5)
    r = 7e6
    for factor, ok in ((0.299, False), (0.301, True), (1.499, True), (1.501, False)):
        v = [0, factor * circular(r), 0]
        if ok:
            rp.OrbitState(EPOCH, [r, 0, 0], v)
        else:
            with pytest.raises(ValueError, match="not orbital"):
                rp.OrbitState(EPOCH, [r, 0, 0], v)
    rp.OrbitState(EPOCH, [R_EARTH + 1.0, 0, 0], [0, circular(R_EARTH), 0])
    with pytest.raises(ValueError, match="below the Earth's surface"):
        rp.OrbitState(EPOCH, [R_EARTH - 1.0, 0, 0], [0, circular(R_EARTH), 0])


def test_spacecraft_is_unchanged():
    craft = rp.Spacecraft(2.2, 0.01)
    assert craft.drag_parameter == pytest.approx(0.022)
    with pytest.raises(ValueError, match="cd must be > 0"):
        rp.Spacecraft(0.0, 0.01)
    with pytest.raises(TypeError, match="area_to_mass must be a real number"):
        rp.Spacecraft(2.2, "big")  # type: ignore[arg-type]


def test_durations():
    from rhoprop import _validate

    assert _validate.seconds("duration", dt.timedelta(hours=1)) == 3600.0
    assert _validate.seconds("duration", np.timedelta64(90, "m")) == 5400.0
    assert _validate.seconds("duration", np.timedelta64(1500, "ms")) == 1.5
    # Coarse units in whole seconds: no int64 overflow through nanoseconds.
    assert _validate.seconds("duration", np.timedelta64(10**6, "D")) == 8.64e10
    with pytest.raises(ValueError, match="duration is NaT"):
        _validate.seconds("duration", np.timedelta64("NaT"))
    with pytest.raises(ValueError, match="years or months is ambiguous"):
        _validate.seconds("duration", np.timedelta64(1, "Y"))


def test_frames_refuse_what_has_no_answer():
    # Found by tests/test_properties.py: these gave NaN (or a silent wrong answer).
    with pytest.raises(ValueError, match=r"positions_fixed\[0\] is 1.414 m from the Earth's"):
        rp.frames.geodetic([0.0, 1.0, 1.0])  # Heikkinen is singular near the centre
    with pytest.raises(ValueError, match="between 50000 and 1e\\+15 m"):
        rp.frames.geodetic([1e300, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"lat must lie in \[-90, 90\] deg, got 1000"):
        rp.frames.geodetic_to_fixed(1000.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="overflow"):
        rp.frames.fixed_to_inertial("2002-09-07", [1.5e308, 1.5e308, 0.0])
    # Still fine in between.
    lla = rp.frames.geodetic([R_EARTH + 400e3, 0.0, 0.0])
    np.testing.assert_allclose(lla, [0.0, 0.0, 400e3], atol=1e-6)


def test_models_and_craft_refuse_overflow():
    with pytest.raises(ValueError, match="overflows at spherical altitude"):
        rp.density.Exponential(1.0, 400e3, 1.0).mean_std("2002-09-07", 0.0, 0.0, 399e3)
    with pytest.raises(ValueError, match="out of the float range"):
        rp.Spacecraft(1e200, 1e200)
    with pytest.raises(ValueError, match="out of the float range"):
        rp.Spacecraft(1e-300, 1e-300)
