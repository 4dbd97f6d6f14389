"""The exception tree: one tree under RhopropError (a ValueError), with
OutsideRecordError for lookups outside a data record (space weather, PCA ROM) and
DecayError for results that need an object in orbit; messages give real values."""

from __future__ import annotations

import numpy as np
import pytest
from test_gridded import exponential_grid
from test_pcarom import synthetic

import rhoprop as rp
from rhoprop import errors


def test_one_tree_under_value_error():
    for cls in (
        rp.DensityFieldError,
        rp.IntegrationError,
        rp.OutsideRecordError,
        rp.DecayError,
        rp.ScenarioError,
    ):
        assert issubclass(cls, rp.RhopropError) and issubclass(cls, ValueError), cls
    assert not issubclass(rp.OutsideRecordError, rp.DensityFieldError)
    assert rp.OutsideRecordError is errors.OutsideRecordError
    assert rp.DecayError is errors.DecayError
    assert {"OutsideRecordError", "DecayError"} <= set(rp.__all__)
    assert issubclass(errors.CacheWarning, RuntimeWarning)
    # The core's classes live in rhoprop.errors (the extension raises them).
    assert rp.DensityFieldError is errors.DensityFieldError
    assert issubclass(errors.StepUnderflowError, rp.IntegrationError)


def test_core_errors_arrive_typed_with_their_values():
    # Each core error variant is its own class, its values attributes: no message parsing.
    from rhoprop import _core

    field, _ = exponential_grid()
    state = rp.scenarios.paper_state()
    with pytest.raises(errors.DensityFieldError) as info:
        rp.propagate(state, rp.Spacecraft(2.2, 0.01), field, 400 * 86400.0)
    e = info.value
    assert e.axis.startswith("time") and e.value > e.max and e.time is not None
    with pytest.raises(errors.NonFiniteError) as info:
        _core.ExponentialAtmosphere(float("nan"), 0.0, 1.0)
    assert info.value.name == "rho0" and np.isnan(info.value.value)
    with pytest.raises(errors.InvalidValueError) as info:
        _core.ExponentialAtmosphere(1e-12, 0.0, -5.0)
    assert info.value.value == -5.0 and "> 0" in info.value.reason
    # A CCSP covariance that is not positive definite carries its time and eigenvalue; in a
    # catalog, at t = 0 it is the user's initial covariance: an error, not a shortened run.
    from test_catalog import END, SAMPLE

    with pytest.raises(errors.CovarianceError, match="object 9000") as info:
        rp.catalog.propagate_catalog(
            rp.catalog.load(SAMPLE),
            rp.scenarios.benchmark_exponential(0.2),
            END,
            initial=rp.catalog.Initial(covariance=-np.eye(6)),
            execution=rp.Execution(progress=False),
        )
    assert info.value.time == 0.0 and info.value.min_eigenvalue < 0


@pytest.fixture(scope="module")
def sw():
    return rp.SpaceWeather()


def test_space_weather_lookups_outside_the_record(sw):
    _, last = sw.span
    with pytest.raises(rp.OutsideRecordError, match=r"1957-10-01T12:00:00 .* outside"):
        sw.drivers("1957-10-01T12:00")
    with pytest.raises(rp.OutsideRecordError, match=r"2039-01-01.*monthly predicted"):
        sw.drivers("2039-01-01T00:00")
    with pytest.raises(rp.OutsideRecordError, match="outside"):
        sw.drivers(last + np.timedelta64(1, "ns"))
    with pytest.raises(rp.OutsideRecordError, match="date 1950-01-01 is not in the"):
        sw.daily("1950-01-01")
    with pytest.raises(rp.OutsideRecordError, match="no kp values between 1900-01-01"):
        sw.mean_geomagnetic("1900-01-01", "1900-12-31")
    # Old code catching ValueError still works.
    with pytest.raises(ValueError):
        sw.drivers("1957-10-01T12:00")
    # NaT is bad input, not a lookup outside the record.
    with pytest.raises(ValueError, match="NaT") as err:
        sw.drivers(np.array(["2002-09-07", "NaT"], "datetime64[ns]"))
    assert not isinstance(err.value, rp.OutsideRecordError)


def test_space_weather_missing_values(tmp_path, sw):
    # A csv record whose F10.7 is blank on one day: asking for it is outside the record.
    from test_spaceweather import CSV_TEXT

    lines = CSV_TEXT.splitlines()
    header = lines[0].split(",")
    col = header.index("F10.7_OBS")
    rows = [line.split(",") for line in lines[1:]]
    target = next(i for i, r in enumerate(rows) if r[0] == "2002-09-06")
    rows[target][col] = ""
    path = tmp_path / "blank.csv"
    path.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    record = rp.SpaceWeather(path)
    with pytest.raises(rp.OutsideRecordError, match=r"missing F10\.7 or ap values .*2002-09-07"):
        record.drivers("2002-09-07T12:00")


def test_pcarom_lookups_outside_the_record():
    rom = synthetic()
    t = "2002-09-07T03:00"
    with pytest.raises(rp.OutsideRecordError, match=r"alt = 600000 m is outside .*\[300000"):
        rom.mean_std(t, 0.0, 0.0, 600e3)
    with pytest.raises(rp.OutsideRecordError, match=r"time 2002-09-07T13:00.* epoch range"):
        rom.mean_std("2002-09-07T13:00", 0.0, 0.0, 400e3)
    with pytest.raises(rp.OutsideRecordError, match=r"time 2002-09-06T23:59"):
        rom.log10_moments("2002-09-06T23:59", 0.0, 0.0, 400e3)
    # Bad input stays a plain ValueError.
    with pytest.raises(ValueError, match="lat must be finite") as err:
        rom.mean_std(t, np.nan, 0.0, 400e3)
    assert not isinstance(err.value, rp.OutsideRecordError)


def test_pcarom_and_density_inputs_accept_every_epoch_form():
    rom = synthetic()
    a = rom.mean_std(np.datetime64("2002-09-07T01:00"), 10.0, 20.0, 400e3)
    b = rom.mean_std("2002-09-07T03:00+02:00", 10.0, 20.0, 400e3)
    np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match=r"times is an empty string"):
        rom.mean_std("", 10.0, 20.0, 400e3)
    with pytest.raises(TypeError, match="times must be UTC datetime64"):
        rom.mean_std(12.0, 10.0, 20.0, 400e3)


def test_gridded_outside_its_grid_is_a_density_field_error():
    grid, _ = exponential_grid()
    with pytest.raises(rp.DensityFieldError, match="the grid covers"):
        grid.field("2002-09-06T00:00", "2002-09-07T06:00")
    # The native grid is returned for any epoch form inside it.
    assert grid.field("2002-09-07T02:00+02:00", "2002-09-07T06:00Z") is grid.native_field
