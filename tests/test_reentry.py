"""Reentry windows (``rp.catalog.reentry``, ``rhoprop reentry``): Monte Carlo over density
and ballistic-coefficient uncertainty, decay epochs as quantiles with NaT beyond the
horizon."""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import catalog
from rhoprop.catalog import CatalogObject
from rhoprop.cli import main
from rhoprop.time import add_seconds

SAMPLE = Path(__file__).parent / "data" / "sample.tle"


def _low(norad: int, alt: float) -> CatalogObject:
    r = 6378137.0 + alt
    v = np.sqrt(3.986004418e14 / r)
    state = rp.OrbitState("2002-09-06T12:00", [r, 0, 0], [0, v * 0.6, v * 0.8])
    return CatalogObject(f"LOW {norad}", norad, state, 0.02, 1e-3, "test")


@pytest.fixture(scope="module")
def atmosphere():
    return rp.scenarios.benchmark_exponential(0.2)


def test_windows_are_ordered_and_count_every_member(atmosphere):
    objs = [_low(1, 200e3), _low(2, 220e3)]
    r = catalog.reentry(
        objs, atmosphere, method=rp.MonteCarlo(n=20), duration=dt.timedelta(days=10), groups=4
    )
    assert r.members == 20 and r.groups == 4
    assert (r.decayed_fraction == 1).all()
    assert (r.epoch_q025 <= r.epoch_median).all() and (r.epoch_median <= r.epoch_q975).all()
    assert (r.epoch_q975 > r.epoch_q025).all()
    assert r.epoch_median[0] < r.epoch_median[1]  # the lower object comes down first
    rows = r.rows()
    assert rows[0]["norad_id"] == 1 and rows[0]["epoch_median"].endswith("Z")
    # Windows of any probability from the members' decay times: the 95 % one is the
    # q025/q975 pair; an 80 % window lies inside it; each end is a member's own decay
    # (inverted CDF), counted against the sorted times by hand.
    assert r.decay_times.shape == (2, 20) and np.isfinite(r.decay_times).all()
    lo95, hi95 = r.window(0.95)
    np.testing.assert_array_equal(lo95, r.epoch_q025)
    np.testing.assert_array_equal(hi95, r.epoch_q975)
    lo80, hi80 = r.window(0.8)
    assert (lo95 <= lo80).all() and (lo80 < hi80).all() and (hi80 <= hi95).all()
    for k in range(2):
        t = np.sort(r.decay_times[k])
        start, end = ((e[k] - objs[k].state.epoch) / np.timedelta64(1, "s") for e in (lo80, hi80))
        # 20 members: the 10 % quantile is the 2nd smallest, the 90 % the 18th.
        assert start == pytest.approx(t[1], abs=1e-6) and end == pytest.approx(t[17], abs=1e-6)
    for bad in (0.0, 1.0, float("nan")):
        with pytest.raises(ValueError, match="level"):
            r.window(bad)
    # The same windows as a table (datetime64 columns, the rows' other values) and a
    # DataFrame of one row per object.
    table = r.table()
    np.testing.assert_array_equal(table["epoch_q10"], lo80)
    np.testing.assert_array_equal(table["epoch_median"], r.epoch_median)
    assert set(table) == set(rows[0]) and all(len(c) == 2 for c in table.values())
    frame = r.to_pandas()
    assert list(frame.columns) == list(table) and list(frame["norad_id"]) == [1, 2]
    assert frame["decayed_fraction"].tolist() == [row["decayed_fraction"] for row in rows]


def test_drag_uncertainty_widens_the_window(atmosphere):
    obj = [_low(1, 200e3)]
    narrow = catalog.reentry(
        obj, atmosphere, method=rp.MonteCarlo(n=20), duration=10 * 86400.0, groups=1
    )
    wide = catalog.reentry(
        obj, atmosphere, method=rp.MonteCarlo(n=20), duration=10 * 86400.0, drag_sigma=0.4
    )
    span = lambda r: r.epoch_q975[0] - r.epoch_q025[0]  # noqa: E731
    assert span(wide) > span(narrow)


def test_nat_beyond_the_horizon(atmosphere):
    r = catalog.reentry(
        [_low(1, 200e3)], atmosphere, method=rp.MonteCarlo(n=10), duration=3600.0, groups=2
    )
    assert r.decayed_fraction[0] == 0
    assert np.isnat(r.epoch_median[0]) and np.isnat(r.epoch_q025[0]) and np.isnat(r.epoch_q975[0])
    assert np.isinf(r.decay_times).all() and np.isnat(r.window(0.5)[0][0])
    with pytest.raises(ValueError, match="duration"):
        catalog.reentry([_low(1, 200e3)], atmosphere, duration=-1.0)
    with pytest.raises(TypeError, match="duration"):
        catalog.reentry([_low(1, 200e3)], atmosphere, duration="soon")


def test_progress_counts_the_objects_done_and_false_turns_it_off(atmosphere):
    # rp.MonteCarlo(progress=False) was refused; a run showed no progress at all.
    objs = [_low(1, 200e3), _low(2, 210e3), _low(3, 220e3)]
    calls: list[int] = []
    method = rp.MonteCarlo(n=4, progress=calls.append)
    catalog.reentry(objs, atmosphere, method=method, duration=3600.0, groups=2)
    assert calls == [1, 2, 3]
    quiet = rp.MonteCarlo(n=4, progress=False)
    r = catalog.reentry(objs, atmosphere, method=quiet, duration=3600.0, groups=2)
    assert r.members == 4


def test_cli_reentry_prints_and_writes(tmp_path, capsys):
    out = tmp_path / "re"
    code = main(
        ["reentry", str(SAMPLE), "--horizon", "2", "--members", "10", "--model",
         "exponential", "--out", str(out)]
    )  # fmt: skip
    assert code == 0
    text = (out / "reentry.csv").read_text().splitlines()
    assert text[0].startswith(
        "norad_id,name,epoch_q025,epoch_q10,epoch_median,epoch_q90,epoch_q975"
    )
    assert len(text) == 1 + len(catalog.load(SAMPLE))
    printed = capsys.readouterr().out
    assert "members each" in printed and "fitted (" in printed  # fitted by default
    assert (out / "manifest.json").is_file()
    assert ",True," in text[1]  # the fitted column


def test_reentry_fits_element_sets_by_default(atmosphere):
    """Windows from B* missed most real decays; fitted ones held them
    (benches/reentry.py). The default fits every object that carries an element set and
    says so; an object without one keeps its values, with the reason."""
    objs = catalog.load(SAMPLE).objects[:2]
    fitted = catalog.reentry(
        [*objs, _low(9, 200e3)], atmosphere, method=rp.MonteCarlo(n=10), duration=86400.0
    )
    assert list(fitted.fitted) == [True, True, False]
    assert np.isfinite(fitted.fit_rms[:2]).all() and np.isnan(fitted.fit_rms[2])
    assert fitted.fit_note[:2] == ["", ""] and "no element set" in fitted.fit_note[2]
    # The windows use the fitted Cd*A/m (not B*'s).
    assert fitted.drag_parameter[0] == fitted.objects[0].fit.drag_parameter
    plain = catalog.reentry(
        objs, atmosphere, method=rp.MonteCarlo(n=10), duration=86400.0, fit=False
    )
    assert not plain.fitted.any() and plain.drag_parameter[0] == objs[0].drag_parameter
    # An object fitted before (load(fit=True)) is used as it is.
    again = catalog.reentry(
        fitted.objects[:1], atmosphere, method=rp.MonteCarlo(n=10), duration=86400.0
    )
    assert again.objects[0] is fitted.objects[0]
    with pytest.raises(TypeError, match="fit must be True or False"):
        catalog.reentry(objs, atmosphere, fit="yes")


def test_horizon_is_the_deprecated_name_of_duration(atmosphere):
    with pytest.warns(DeprecationWarning, match="duration="):
        old = catalog.reentry(
            [_low(1, 200e3)], atmosphere, method=rp.MonteCarlo(n=10), horizon=3600.0, groups=2
        )
    new = catalog.reentry(
        [_low(1, 200e3)], atmosphere, method=rp.MonteCarlo(n=10), duration=3600.0, groups=2
    )
    assert old.horizon == new.horizon == 3600.0


def test_a_diverged_fit_is_no_fit(test_data):
    """COSMOS 1408 DEB 49643, 1.3 days before its decay: the Gauss-Newton over +-1 day
    diverged to Cd*A/m = 11.7 m^2/kg with a 10,765 km RMS residual and was used, so the
    window said 'not down within 12 days'. Such a fit now counts as failed."""
    lines = (test_data / "reentry" / "reentry_tles_2022_2023.txt").read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("1 49643"))
    (obj,) = _load_text("\n".join(lines[k - 1 : k + 2]))
    (fit,) = catalog.fit_objects([obj], rp.density.Msis("2.1"))
    assert isinstance(fit, Exception)
    assert fit.__class__ is ValueError


def test_catalog_and_reentry_runs_of_one_element_set_agree(test_data):
    """COSMOS 1408 DEB 50520 and 50589, 1.1-1.5 days before reentry, whose fits fail:
    propagate_catalog flew them with B* scaled to the model and decayed 13-15 h before
    the reentry run's 95 % window (plain B*). One rule for both now (plain below a 250 km
    perigee): the catalog's decay epoch lies inside the window."""
    lines = (test_data / "reentry" / "reentry_tles_2022_2023.txt").read_text().splitlines()
    picked = []
    for norad in ("50520", "50589"):
        k = next(i for i, line in enumerate(lines) if line.startswith(f"1 {norad}"))
        picked += lines[k - 1 : k + 2]
    objs = _load_text("\n".join(picked))
    model = rp.density.Msis("2.1")
    windows = catalog.reentry(objs, model, method=rp.MonteCarlo(n=100), duration=6 * 86400.0)
    assert not windows.fitted.any()  # both fits fail (diverge), as measured
    for k, obj in enumerate(windows.objects):
        end = add_seconds(obj.state.epoch, 6 * 86400.0)
        run = catalog.propagate_catalog(
            [obj], model, end, execution=rp.Execution(progress=False), max_span=None
        )
        decay = run.decay_epoch[0]
        assert windows.epoch_q025[k] <= decay <= windows.epoch_q975[k], obj.name


def _load_text(text: str) -> list[CatalogObject]:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "one.tle"
        path.write_text(text + "\n")
        return catalog.load(path).objects


def test_several_element_sets_of_one_object_are_one_history(atmosphere):
    """A file holding an object's history once gave one independent window
    per element set, and nothing said the object appeared more than once."""
    import dataclasses

    obj = catalog.load(SAMPLE).objects[0]
    later_state = rp.OrbitState(
        rp.time.add_seconds(obj.state.epoch, 3600.0), obj.state.position, obj.state.velocity
    )
    later = dataclasses.replace(obj, state=later_state)
    other = catalog.load(SAMPLE).objects[1]
    one = catalog.reentry(
        [obj, later, other], atmosphere, method=rp.MonteCarlo(n=10), duration=86400.0, fit=False
    )
    assert [o.norad_id for o in one.objects] == [obj.norad_id, other.norad_id]
    assert one.objects[0] is later and list(one.element_sets) == [2, 1]
    each = catalog.reentry(
        [obj, later, other],
        atmosphere,
        method=rp.MonteCarlo(n=10),
        duration=86400.0,
        fit=False,
        history="each",
    )
    assert len(each.objects) == 3 and list(each.element_sets) == [2, 2, 1]
    with pytest.raises(ValueError, match="history must be 'auto', 'newest', 'fit' or 'each'"):
        catalog.reentry([obj], atmosphere, history="all")


def test_the_object_whose_time_nodes_aborted_runs(test_data):
    """NORAD 50038 (COSMOS 1408 DEB) once raised 'time node 4 =
    8045.416800000001 is invalid: time nodes must not decrease (previous
    8045.416800000002)' from the band field's float offsets. The atlas builds its tile
    nodes from integer nanoseconds; the run completes and brings every member down."""
    lines = (test_data / "reentry" / "reentry_tles_2022_2023.txt").read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("1 50038"))
    objs = _load_text("\n".join(lines[k - 1 : k + 2]))
    r = catalog.reentry(
        objs, rp.density.Msis("2.1"), method=rp.MonteCarlo(n=10), duration=6 * 86400.0, groups=2
    )
    assert r.decayed_fraction[0] == 1.0 and not np.isnat(r.epoch_q975[0])


def test_the_density_error_is_held_over_each_members_run(atmosphere):
    """The default kappa is the model's density error held over the whole
    run (DEFAULT_KAPPA, Constant), not the paper's 18-minute Gauss-Markov that averages
    away over a multi-day decay. A member with density mean + k sigma = (1 + 0.2 k) mean
    (the benchmark atmosphere's 20 %) is exactly a member with Cd*A/m x (1 + 0.2 k), so
    without Cd*A/m uncertainty (groups=1) the 2.5 % / 97.5 % decay epochs are the
    deterministic decays (a 0 % sigma atmosphere) with Cd*A/m x (1 +- 1.96 x 0.2).
    Tolerance 5 %: 4000 members put the sample's k quantiles within 0.04 (1 sigma) of
    +-1.96, 1.4 % in decay time; measured 2.1 % and 0.0 %."""
    import dataclasses

    obj = _low(1, 200e3)
    span = 20 * 86400.0
    assert catalog.reentry_windows.DEFAULT_KAPPA == rp.kappa.Constant()
    wide = catalog.reentry(
        [obj],
        atmosphere,
        method=rp.MonteCarlo(n=4000, seed=1),
        duration=span,
        groups=1,
    )
    still = rp.scenarios.benchmark_exponential(0.0)

    def decay(factor: float) -> np.datetime64:
        scaled = dataclasses.replace(obj, drag_parameter=obj.drag_parameter * factor)
        return catalog.reentry(
            [scaled], still, method=rp.MonteCarlo(n=2), duration=span, groups=1
        ).epoch_median[0]

    def days(t: np.datetime64) -> float:
        return float((t - obj.state.epoch) / np.timedelta64(1, "s")) / 86400.0

    assert days(wide.epoch_q025[0]) == pytest.approx(days(decay(1 + 1.96 * 0.2)), rel=0.05)
    assert days(wide.epoch_q975[0]) == pytest.approx(days(decay(1 - 1.96 * 0.2)), rel=0.05)
    assert days(wide.epoch_median[0]) == pytest.approx(days(decay(1.0)), rel=0.05)
    # The paper's 18-minute process averages the same 20 % away over the 4-day decay.
    brief = catalog.reentry(
        [obj],
        atmosphere,
        method=rp.MonteCarlo(n=400, kappa=rp.kappa.GaussMarkov(), seed=1),
        duration=span,
        groups=1,
    )
    assert days(brief.epoch_q975[0]) < 1.1 * days(decay(1.0))


def test_history_fit_takes_the_earlier_element_sets(test_data):
    """With history="fit" the fit of the newest element set also takes the
    object's earlier ones (fit_objects' history). Two element sets under a day apart of a low
    object of CelesTrak's 2023-11-18 and 11-19 snapshots are reconciled (both used); a fit
    needs fit=True."""
    snaps = test_data / "catalogs"
    older = catalog.load(snaps / "history" / "celestrak_active_20231118.txt.gz", errors="record")
    older = older.objects
    newer = catalog.load(snaps / "celestrak_active_20231119.txt.gz", errors="record").objects
    by_id = {o.norad_id: o for o in older}
    model = rp.density.Msis("2.1")

    def gap(o: CatalogObject) -> float:
        return float((o.state.epoch - by_id[o.norad_id].state.epoch) / np.timedelta64(1, "D"))

    pair = next(
        (by_id[o.norad_id], o)
        for o in newer
        if o.norad_id in by_id
        and 0.5 < gap(o) < catalog.HISTORY_DAYS
        and np.linalg.norm(o.state.position) < 6378137.0 + 330e3
        and o.bstar > 1e-4
    )
    r = catalog.reentry(
        list(pair), model, method=rp.MonteCarlo(n=10), duration=86400.0, groups=2, history="fit"
    )
    assert len(r.objects) == 1 and r.element_sets[0] == 2 and r.fitted[0]
    assert len(r.objects[0].fit.element_sets) == 2
    alone = catalog.reentry(
        list(pair), model, method=rp.MonteCarlo(n=10), duration=86400.0, groups=2, history="newest"
    )
    assert len(alone.objects[0].fit.element_sets) == 1
    # The default ("auto") fits the history when it fits at all.
    default = catalog.reentry(
        list(pair), model, method=rp.MonteCarlo(n=10), duration=86400.0, groups=2
    )
    assert len(default.objects[0].fit.element_sets) == 2
    np.testing.assert_array_equal(default.decay_times, r.decay_times)
    with pytest.raises(ValueError, match="needs fit=True"):
        catalog.reentry(list(pair), model, fit=False, history="fit")


def _earliest_within_a_week(
    test_data: Path,
) -> tuple[list[CatalogObject], dict[int, np.datetime64]]:
    """Per real reentry of the reference set, its earliest element set 1-7 days before the
    SATCAT decay day (benches/reentry.py's choice), and the decay days."""
    import csv

    folder = test_data / "reentry"
    with open(folder / "satcat_decay_2022_2023.csv") as f:
        rows = list(csv.DictReader(f))
    days = {int(r["NORAD_CAT_ID"]): np.datetime64(r["DECAY_DATE"], "ns") for r in rows}
    best: dict[int, CatalogObject] = {}
    for obj in catalog.load(folder / "reentry_tles_2022_2023.txt", history="each").objects:
        lead = (days[obj.norad_id] - obj.state.epoch) / np.timedelta64(1, "D")
        if 1 <= lead <= 7 and (
            obj.norad_id not in best or obj.state.epoch < best[obj.norad_id].state.epoch
        ):
            best[obj.norad_id] = obj
    return [best[k] for k in sorted(best)], days


def test_default_windows_hold_real_decays(test_data):
    """The reentry windows' goal on the real reentries (SATCAT decay days, an independent record):
    the default 95 % windows hold the decay day for >= 70 % of the 49 objects, no wider
    than 80 % of the remaining life (median). The benchmark's own setting, 200 members
    (benches/reentry.py --settings fitted, 2026-12-04): 35 of 49 held (71 %; 35 needed),
    median width 60 %; with the 18-minute Gauss-Markov of before: 55 %, 37 %. With 60
    members (before 2026-12-04) the windows moved by an object with any change of the
    fits (73 % / 69 % with the LEO radial TLE accuracy at 200 / 300 m)."""
    objs, days = _earliest_within_a_week(test_data)
    assert len(objs) == 49
    r = catalog.reentry(
        objs, rp.density.Msis("2.1"), method=rp.MonteCarlo(n=200), duration=12 * 86400.0
    )
    day = np.array([days[o.norad_id] for o in r.objects])
    top = np.where(np.isnat(r.epoch_q975), np.datetime64("2100-01-01", "ns"), r.epoch_q975)
    held = (r.epoch_q025 < day + np.timedelta64(1, "D")) & (top >= day)
    remaining = day + np.timedelta64(12, "h") - np.array([o.state.epoch for o in r.objects])
    width = (r.epoch_q975 - r.epoch_q025) / remaining
    assert held.mean() >= 0.70, f"{held.mean():.0%} of windows hold the decay day"
    assert np.nanmedian(width.astype(float)) <= 0.80, f"median width {np.nanmedian(width):.0%}"


def test_an_element_set_below_the_floor_is_named():
    # One element set already at 75 km stopped a whole reentry run with "initial geodetic
    # altitude ... below the decay floor", naming no object.
    import math

    from rhoprop.catalog import CatalogObject

    r = rp.constants.R_EARTH + 75e3
    v = math.sqrt(rp.constants.MU / r)
    state = rp.OrbitState("2024-03-01T00:00", [r, 0.0, 0.0], [0.0, 0.6 * v, 0.8 * v])
    low = CatalogObject("DOWN 99077", 99077, state, 0.02, 1e-3, "test")
    with pytest.raises(ValueError, match=r"object 99077 \(DOWN 99077, test\).*floor"):
        rp.catalog.reentry(
            [low],
            rp.density.Exponential.benchmark(),
            duration=86400.0,
            method=rp.MonteCarlo(n=10),
        )
