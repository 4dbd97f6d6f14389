"""Forecast space weather: the record's predictions as drivers past the observed days
(``SpaceWeather.with_forecast``), driver uncertainty growing with lead time, the
PredictedDriversWarning, offline errors that name the refresh command, and
``rhoprop data refresh``."""

from __future__ import annotations

import urllib.error
import warnings

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.cli import main
from rhoprop.density import Msis
from rhoprop.errors import OutsideRecordError, PredictedDriversWarning
from rhoprop.jobs import models as job
from rhoprop.spaceweather import forecast_sigma


@pytest.fixture(scope="module")
def records():
    sw = rp.SpaceWeather()
    return sw, sw.with_forecast()


def after_observed(sw, days):
    """An epoch `days` after the record's last observed day (noon), ISO string: the
    bundled record's observed end moves with each spaceweather release."""
    last = sw.date[sw.section == 0][-1].astype("datetime64[h]")
    return str(last + np.timedelta64(24 * days + 12, "h"))


def test_observed_epochs_are_unchanged_and_silent(records):
    sw, fc = records
    t = ["2023-11-13T05:00", "2002-09-07T12:00"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a, b = sw.drivers(t), fc.drivers(t)
    np.testing.assert_array_equal(a.f107, b.f107)
    np.testing.assert_array_equal(a.f107a, b.f107a)
    np.testing.assert_array_equal(a.ap, b.ap)
    assert a.lead_time is None and (b.lead_time == 0).all()
    assert (b.f107_forecast_sigma == 0).all() and (b.ap_forecast_sigma == 0).all()
    m0, m1 = Msis(space_weather=sw), Msis(space_weather=fc)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert m0.mean_std(t[0], 10, 20, 400e3) == m1.mean_std(t[0], 10, 20, 400e3)


def test_predicted_epochs_work_with_a_warning_and_growing_sigma(records):
    sw, fc = records
    late = after_observed(sw, 240)
    with pytest.raises(OutsideRecordError, match="rhoprop data refresh"):
        sw.drivers(late)
    with pytest.warns(PredictedDriversWarning, match="epochs after the last observed day"):
        d = fc.drivers([late, after_observed(sw, 700)])
    assert np.isfinite(d.f107).all() and np.isfinite(d.ap).all()
    assert (d.lead_time > 200).all() and d.lead_time[1] > d.lead_time[0]
    assert d.f107_forecast_sigma[1] >= d.f107_forecast_sigma[0] > 0.02
    f, a = forecast_sigma([0, 1, 3, 27, 1000])
    assert f[0] == 0 and a[0] == 0 and (np.diff(f) >= 0).all() and (np.diff(a) >= 0).all()
    assert fc.span[1] > np.datetime64("2030-01-01")


def test_a_state_after_the_observed_days_propagates_three_days_with_the_warning(records):
    sw, fc = records
    v = np.sqrt(3.986004418e14 / 6778137.0)
    state = rp.OrbitState(after_observed(sw, 240), [6778137.0, 0, 0], [0, 0.6 * v, 0.8 * v])
    craft = rp.Spacecraft(2.2, 0.01)
    with pytest.warns(PredictedDriversWarning):
        traj = rp.propagate(state, craft, Msis(space_weather=fc), 3 * 86400.0, output_step=3600.0)
    assert traj.times[-1] == 3 * 86400.0 and traj.decayed_at is None


def test_lead_time_sigma_raises_the_density_sigma(records):
    sw, fc = records
    at = after_observed(sw, 240)
    with pytest.warns(PredictedDriversWarning):
        d = fc.drivers(at)
    # The same drivers as an observed record would give them: no lead-time sigma.
    plain = rp.spaceweather.Drivers(d.epochs, d.f107, d.f107a, d.ap)
    model = Msis(space_weather=fc)

    def sigma(drivers):
        def call(f107, f107a, ap):
            return model._calc(d.epochs, np.array([0.0]), np.array([0.0]), np.array([400e3]),
                               f107, f107a, ap)  # fmt: skip

        return model._driver_variance(call, drivers)[1]

    assert sigma(d)[0] > 2 * sigma(plain)[0]


def test_forecast_record_pickles_and_says_so(records):
    import pickle

    _, fc = records
    copy = pickle.loads(pickle.dumps(fc))
    assert "forecast from" in repr(copy) and copy.span == fc.span


def test_data_refresh_command(monkeypatch, capsys):
    calls = []
    monkeypatch.setattr(
        rp.SpaceWeather,
        "refresh",
        classmethod(lambda cls, **kw: calls.append("sw") or rp.SpaceWeather()),
    )
    from rhoprop.density import Jb2008Indices

    monkeypatch.setattr(
        Jb2008Indices, "refresh", classmethod(lambda cls, **kw: calls.append("jb") or "files")
    )
    assert main(["data", "refresh"]) == 0
    out = capsys.readouterr().out
    assert calls == ["sw", "jb"] and "space weather:" in out and "JB2008 indices" in out

    def offline(cls, **kw):
        raise urllib.error.URLError("no network")

    monkeypatch.setattr(rp.SpaceWeather, "refresh", classmethod(offline))
    assert main(["data", "refresh"]) == 1
    err = capsys.readouterr().err
    assert "no network" in err and "SW-All.csv" in err


def test_catalog_models_use_the_forecast_record():
    model = job.model_by_name("2.1")
    assert "forecast from" in repr(model.space_weather)
