"""Fits to a history of element sets (``load([files], fit=True, history="fit")``: Levit &
Marshall 2011)
against fits to the newest element set alone, on real data: the CelesTrak snapshots of
2023-08-07 and 2023-08-13 predict the same objects' element sets of 2023-08-20 (the
development week 2023-08-13 of ``benches/catalog_realism.py``, same selection rules), and
the B*-derived prior against the fitted Cd*A/m."""

from __future__ import annotations

import gzip
import warnings

import numpy as np
import pytest
from sgp4.api import Satrec

import rhoprop as rp
from rhoprop import catalog
from rhoprop.catalog.fit import (
    SGP4_Q0_KM,
    SGP4_RADIUS_KM,
    SGP4_S_KM,
    drag_parameter_from_bstar,
    fit_element_sets,
)
from rhoprop.density import Msis
from rhoprop.frames import rtn_basis

EXCLUDE = ("STARLINK", "ONEWEB", "IRIDIUM", "GLOBALSTAR", "ORBCOMM", "KUIPER", "ISS ",
           "CSS ", "PROGRESS", "SOYUZ", "DRAGON", "CYGNUS", "SHENZHOU", "TIANZHOU")  # fmt: skip
OBJECTS = 48


def _snapshot(path):
    lines = [ln.rstrip() for ln in gzip.open(path, "rt") if ln.strip()]
    return {int(lines[k + 1][2:7]): lines[k : k + 3] for k in range(0, len(lines) - 2, 3)}


def _altitudes(sat):
    a = sat.a * SGP4_RADIUS_KM
    return a * (1 - sat.ecco) - SGP4_RADIUS_KM, a * (1 + sat.ecco) - SGP4_RADIUS_KM


@pytest.fixture(scope="module")
def week(test_data, tmp_path_factory):
    """(older file, start file, truth {id: Satrec}, ids) of the week 2023-08-13."""
    folder = test_data / "catalogs" / "history"
    old = _snapshot(folder / "celestrak_active_20230807.txt.gz")
    start = _snapshot(folder / "celestrak_active_20230813.txt.gz")
    truth = _snapshot(folder / "celestrak_active_20230820.txt.gz")
    ids = []
    for norad in sorted(set(old) & set(start) & set(truth)):
        if any(w in start[norad][0].upper() for w in EXCLUDE):
            continue
        s0, s1, s2 = (Satrec.twoline2rv(*snap[norad][1:]) for snap in (old, start, truth))
        lo, hi = _altitudes(s1)
        gap = s2.jdsatepoch + s2.jdsatepochF - s1.jdsatepoch - s1.jdsatepochF
        history_gap = s1.jdsatepoch + s1.jdsatepochF - s0.jdsatepoch - s0.jdsatepochF
        if lo < 200 or hi > 700 or gap < 2 or not 1 < history_gap < 10:
            continue
        if s2.no_kozai < s1.no_kozai * (1 - 1e-6) or s1.no_kozai < s0.no_kozai * (1 - 1e-6):
            continue  # an orbit raise: a manoeuvre
        ids.append(norad)
    ids = [ids[i] for i in np.linspace(0, len(ids) - 1, OBJECTS).round().astype(int)]
    tmp = tmp_path_factory.mktemp("history")
    files = []
    for name, snap in (("0807.tle", old), ("0813.tle", start)):
        files.append(tmp / name)
        files[-1].write_text("".join("\n".join(snap[i]) + "\n" for i in ids))
    return files, {i: Satrec.twoline2rv(*truth[i][1:]) for i in ids}, ids


def _along_track_errors(objects, truth, model):
    """|along-track error| (m) at each truth element set's epoch of the fitted means."""
    out = []
    for obj in objects:
        sat = truth[obj.norad_id]
        _, r, v = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
        end = rp.time.from_jd(sat.jdsatepoch, sat.jdsatepochF)
        span = (end - obj.state.epoch) / np.timedelta64(1, "ns") / 1e9
        tr = rp.propagate(
            obj.state,
            rp.Spacecraft(1.0, obj.drag_parameter),
            model,
            span,
            dynamics=rp.Dynamics(zonal_degree=4),
        )
        r, v = np.array(r) * 1e3, np.array(v) * 1e3
        out.append(abs((rtn_basis(r, v) @ (tr.positions[-1] - r))[1]))
    return np.array(out)


def test_a_history_fit_against_a_single_fit_on_a_real_week(week, monkeypatch):
    # Measured: the history fit does NOT predict better here. The older element set lies
    # 6 days back, beyond HISTORY_DAYS (1 day), so by default it is left out and the fit is
    # the single one; reached with a 10-day window (the default until 2026-12-05), each
    # set's positions weighted as one observation of the orbit: median 11.5 km
    # against 10.2 km, better for 54 % of the 48 objects (before that weighting,
    # 11.3 against 9.8 km and 50 %), which is why load's default is history="newest"
    # (docs/catalog-realism.md, "What changed: B* as the prior, weights, history fits").
    # The bands pin the measured figures (the fraction within 2 binomial sigma of 48
    # objects): a change that makes history fits better (or worse still) must update
    # the docs.
    files, truth, ids = week
    model = Msis("2.1")
    single = catalog.load(
        files[-1],
        fit=rp.catalog.FitSettings(model),
    )
    newest = catalog.load(
        files,
        fit=rp.catalog.FitSettings(model),
    )  # the default: the newest, alone
    within_a_day = catalog.load(files, fit=rp.catalog.FitSettings(model), history="fit")
    assert [o.drag_parameter for o in newest] == [o.drag_parameter for o in single]
    assert [o.drag_parameter for o in within_a_day] == [o.drag_parameter for o in single]
    assert all(len(o.fit.element_sets) == 1 for o in within_a_day)
    assert all("the newest of 2 element sets" in o.covariance_note for o in newest)
    assert [o.element_sets for o in newest] == [2] * len(ids)
    assert [o.element_sets for o in single] == [1] * len(ids)
    monkeypatch.setattr(catalog.elements, "HISTORY_DAYS", 10.0)
    history = catalog.load(files, fit=rp.catalog.FitSettings(model), history="fit")
    assert [o.norad_id for o in history] == [o.norad_id for o in single] == ids
    used = [len(o.fit.element_sets) for o in history]
    assert max(used) == 2 and np.mean(used) > 1.5  # most histories are fitted whole
    for o in history:
        assert o.fit.element_set_rms.shape == (len(o.fit.element_sets),)
        assert o.fit.element_sets[-1].startswith("0813.tle")
    e_single = _along_track_errors(single, truth, model)
    e_history = _along_track_errors(history, truth, model)
    print(
        f"median |along-track error|: single {np.median(e_single) / 1e3:.2f} km, history "
        f"{np.median(e_history) / 1e3:.2f} km; history better for "
        f"{np.mean(e_history < e_single):.0%} of objects"
    )
    assert 1.0 < np.median(e_history) / np.median(e_single) < 1.35
    assert 0.35 < np.mean(e_history < e_single) < 0.65


def test_the_bstar_prior_is_the_fitted_drag_where_the_fit_sees_it(week):
    # The prior is B* converted with the ratio of SGP4's static density to the model's:
    # where the fit sees the drag well (formal sigma < 10 %), the fitted Cd*A/m - an
    # independent estimate, from SGP4's positions through rhoprop's dynamics - is the
    # prior to a few per cent (measured: median ratio 0.98, robust log scatter 0.012 on
    # the benchmark's 149 objects of this week), while B*'s plain conversion is several
    # times too small (SGP4's density is several times NRLMSIS's at 400-600 km).
    files, _, _ = week
    model = Msis("2.1")
    fitted = [
        o
        for o in catalog.load(
            files[-1],
            fit=rp.catalog.FitSettings(model),
        )
    ]
    seen = [o for o in fitted if o.fit.drag_sigma < 0.1 * o.drag_parameter]
    assert len(seen) >= 20
    to_prior = np.log([o.drag_parameter / o.fit.prior for o in seen])
    to_plain = np.log([o.drag_parameter / drag_parameter_from_bstar(o.bstar) for o in seen])
    assert abs(np.median(to_prior)) < 0.05
    assert np.median(to_plain) > np.log(2.0)
    assert 1.4826 * np.median(np.abs(to_prior - np.median(to_prior))) < 0.05


def test_sgp4_density_constants_are_spacetrack_report_3s():
    # qoms2t = ((q0 - s) / ER)^4 = 1.88027916e-9 and s = 1.01222928 ER (Hoots & Roehrich
    # 1980, Spacetrack Report No. 3, with ER = 6378.135 km).
    er = SGP4_RADIUS_KM
    assert ((SGP4_Q0_KM - SGP4_S_KM) / er) ** 4 == pytest.approx(1.88027916e-9, rel=1e-7)
    assert 1 + SGP4_S_KM / er == pytest.approx(1.01222928, rel=1e-8)


def test_history_fit_refuses_element_sets_of_different_objects(week):
    files, _, ids = week
    cat = catalog.load(files, history="each", nonpositive_bstar="prior")
    a, b = (next(o for o in cat if o.norad_id == i) for i in ids[:2])
    with pytest.raises(ValueError, match="different objects"):
        fit_element_sets([a, b], Msis("2.1"))
    with pytest.raises(ValueError, match="history must be"):
        catalog.load(files, history="all")


def test_an_element_set_too_close_to_its_neighbour_for_an_observation_is_skipped_quietly(
    test_data,
):
    # Real sets of NORAD 32791 in the dense 2026 history: two of them closer together
    # than the 600-s spacing, so one window holds no observation. Its RMS was the mean of
    # an empty slice (a RuntimeWarning out of load), a NaN among the older sets'
    # normalised RMS that max() returns when it comes first, and NaN > 3 passes the
    # manoeuvre check.
    path = (
        test_data / "history_2026" / "celestrak_stations_weather_amateur_20260228-20260430.txt.gz"
    )
    start = np.datetime64("2026-03-09T00:00", "ns")
    sets = [
        o
        for o in catalog.load(path, history="each", errors="record").objects
        if o.norad_id == 32791 and start - np.timedelta64(1, "D") <= o.state.epoch < start
    ]
    gaps = np.diff(sorted(o.state.epoch for o in sets)) / np.timedelta64(1, "s")
    assert gaps.min() < 600.0  # the case itself
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        f = fit_element_sets(sets, Msis("2.1"))
    rms = f.element_set_rms
    assert len(f.element_sets) == len(sets) and np.isnan(rms).sum() == 1
    assert np.all(rms[np.isfinite(rms)] < 2000.0)  # m: the others fit


DENSE_HISTORY = "history_2026/celestrak_stations_weather_amateur_20260228-20260430.txt.gz"
#: Start days of the dense-history test: every ninth day of the window, not chosen.
DENSE_STARTS = ("2026-03-02", "2026-03-11", "2026-03-20", "2026-03-29", "2026-04-07", "2026-04-16")


def _julian_date(epoch):
    """The Julian date (UTC days) of a datetime64, as Satrec's jdsatepoch + jdsatepochF."""
    return float((epoch - np.datetime64("2000-01-01T12:00")) / np.timedelta64(1, "D")) + 2451545


def _dense_history(test_data):
    """Element sets per NORAD id (name, line 1, line 2, epoch JD) of the 2026 history, of
    objects whose mean motion never falls between consecutive sets (no orbit raise)."""
    lines = gzip.open(test_data / DENSE_HISTORY, "rt").read().splitlines()
    sets: dict[int, list] = {}
    for i in range(0, len(lines) - 2, 3):
        sat = Satrec.twoline2rv(lines[i + 1], lines[i + 2])
        sets.setdefault(sat.satnum, []).append(
            (lines[i], lines[i + 1], lines[i + 2], sat.jdsatepoch + sat.jdsatepochF)
        )
    clean = {}
    for norad, found in sets.items():
        found.sort(key=lambda s: s[3])
        n = [Satrec.twoline2rv(s[1], s[2]).no_kozai for s in found]
        if not any(w in found[-1][0].upper() for w in EXCLUDE) and np.all(
            np.diff(n) > -5e-4 * 2 * np.pi / 1440
        ):
            clean[norad] = found
    return clean


def _by_id(objects, ids):
    """The objects of ``objects`` with the NORAD ids ``ids``, in that order."""
    found = {o.norad_id: o for o in objects}
    return [found[i] for i in ids]


def test_a_history_fit_predicts_the_next_day_of_a_dense_history_better(test_data, tmp_path):
    # Every element set of the 2 days before each start (about 4 a day per object) as a
    # user's history file holds them; the newest fitted alone (load's default) and with the
    # others of its last day (history="fit"), forecast drivers as of the start; each
    # object's along-track error at the epoch of its element set nearest start + 1 day.
    # Measured on these six starts (every ninth day, 2026-12-06): the history fit's median
    # 0.77 of the newest set's at 1 day (per start 0.41 / 1.71 / 0.56 / 0.77 / 1.11 /
    # 0.93), better for 56 % of 636 predictions; on every third start of the window (18)
    # 0.87 at 1 day, 0.97 at 3 and 1.06 at 7, which is why load keeps "newest"
    # (docs/catalog-realism.md, "History fits on the dense history"). Bands: the ratio
    # below 1 with the starts' spread around it; the share above one half, within 2.4
    # binomial sigma (0.02 for 636) of the measured one.
    history = _dense_history(test_data)
    single_errors, history_errors = [], []
    for day in DENSE_STARTS:
        start = np.datetime64(day)
        t0 = _julian_date(start)
        given = {}
        for norad, found in history.items():
            before = [s for s in found if t0 - 2 <= s[3] < t0]
            if before:
                lo, hi = _altitudes(Satrec.twoline2rv(before[-1][1], before[-1][2]))
                if lo >= 200 and hi <= 700:
                    given[norad] = before
        path = tmp_path / f"{day}.tle"
        path.write_text("".join(f"{s[0]}\n{s[1]}\n{s[2]}\n" for v in given.values() for s in v))
        model = Msis("2.1", space_weather=rp.SpaceWeather().as_of(start))
        settings = rp.catalog.FitSettings(model)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
            newest = catalog.load(path, fit=settings)
            together = catalog.load(path, fit=settings, history="fit")
            truth = {}
            for norad in given:
                later = [s for s in history[norad] if abs(s[3] - (t0 + 1)) <= 0.5]
                if later:
                    best = min(later, key=lambda s: abs(s[3] - (t0 + 1)))
                    truth[norad] = Satrec.twoline2rv(best[1], best[2])
            assert [o.norad_id for o in newest] == [o.norad_id for o in together]
            ids = [o.norad_id for o in newest if o.norad_id in truth]
            assert len(ids) > 90
            single_errors.append(_along_track_errors(_by_id(newest, ids), truth, model))
            history_errors.append(_along_track_errors(_by_id(together, ids), truth, model))
        used = [len(o.fit.element_sets) for o in together]
        assert np.median(used) >= 2  # most newest sets are fitted with others of their day
    e_single, e_history = np.concatenate(single_errors), np.concatenate(history_errors)
    ratio = np.median(e_history) / np.median(e_single)
    better = np.mean(e_history < e_single)
    pairs = zip(single_errors, history_errors, strict=True)
    per_start = " ".join(f"{np.median(h) / np.median(s):.2f}" for s, h in pairs)
    print(f"1 day: history / newest {ratio:.3f}, better {better:.0%}, per start {per_start}")
    assert 0.6 < ratio < 0.95
    assert 0.51 < better < 0.61


def _oem_comments(path):
    """The COMMENT lines of an OEM file, joined into one text."""
    lines = path.read_text().splitlines()
    return " ".join(ln[len("COMMENT ") :] for ln in lines if ln.startswith("COMMENT "))


def test_the_command_line_fits_a_history_when_asked(test_data, tmp_path):
    # rhoprop catalog --duplicates fit: each object's newest element set fitted with the
    # others of its last day, as load(history="fit") does; the OEM says how many were used.
    from rhoprop.cli import main

    history = _dense_history(test_data)
    t0 = _julian_date(np.datetime64("2026-04-07"))
    chosen = []
    for found in history.values():
        before = [s for s in found if t0 - 1 <= s[3] < t0]
        lo, hi = _altitudes(Satrec.twoline2rv(*before[-1][1:3])) if before else (0, 0)
        if len(before) >= 2 and lo >= 300 and hi <= 700:
            chosen.append(before)
        if len(chosen) == 2:
            break
    path = tmp_path / "history.tle"
    path.write_text("".join(f"{s[0]}\n{s[1]}\n{s[2]}\n" for v in chosen for s in v))
    args = ["catalog", str(path), "--end", "2026-04-08T00:00Z"]
    args += ["--oem", "--output-step", "3600"]
    assert main([*args, "--duplicates", "fit", "--out", str(tmp_path / "fit")]) == 0
    assert main([*args, "--out", str(tmp_path / "newest")]) == 0
    for before in chosen:
        norad = Satrec.twoline2rv(*before[-1][1:3]).satnum
        fit, newest = (
            _oem_comments(tmp_path / run / "oem" / f"{norad}.oem") for run in ("fit", "newest")
        )
        assert f"over -24..+0 h of {len(before)} element sets (RMS residual" in fit
        assert "element sets (RMS" not in newest and f"newest of {len(before)}" in newest
        states = [
            (tmp_path / run / "oem" / f"{norad}.oem")
            .read_text()
            .split("COVARIANCE_START")[0][-300:]
            for run in ("fit", "newest")
        ]
        assert states[0] != states[1]  # a different fit, a different orbit
