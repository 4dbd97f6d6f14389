"""The settings records of the many-object runs (rp.Execution, rp.catalog.Initial,
rp.conjunction.Search, rp.conjunction.PcSettings): each is checked when it is made, a
run given one equals the run given the old loose keywords bit for bit (those still work
for one release, with a warning), a keyword given with its record is a TypeError, and a
setting a function cannot use is refused, never ignored."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from test_screening import CRAFT, MODEL, T, _circular, encounter

import rhoprop as rp
from rhoprop import catalog
from rhoprop.conjunction import PcSettings, Search, screen, screen_all
from rhoprop.time import add_seconds

SAMPLE = Path(__file__).parent / "data" / "sample.tle"
END = "2002-09-07T06:00:00"
AIR = rp.scenarios.benchmark_exponential(0.2)
QUIET = rp.Execution(progress=False)


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda: rp.Execution(threads=0), ValueError, "threads must be"),
        (lambda: rp.Execution(threads=2.5), ValueError, "threads must be"),
        (lambda: rp.Execution(chunk_size=0), ValueError, "chunk_size must be"),
        (lambda: rp.Execution(progress="yes"), TypeError, "progress must be"),
        (lambda: rp.Execution(errors="ignore"), ValueError, "errors must be"),
        (lambda: rp.Execution(max_memory=-1.0), ValueError, "max_memory must be > 0"),
        (lambda: catalog.Initial(covariance="huge"), ValueError, "initial_covariance"),
        (lambda: catalog.Initial(drag_sigma="fit"), ValueError, "drag_sigma must be 'auto'"),
        (lambda: catalog.Initial(drag_sigma=[0.1]), TypeError, "drag_sigma must be 'auto'"),
        (lambda: catalog.Initial(fit="yes"), ValueError, "fit must be"),
        (lambda: catalog.Initial(fit=1), ValueError, "fit must be"),
        (lambda: Search(grid_step=0.0), ValueError, "grid_step must be > 0"),
        (lambda: Search(fine_step=-1.0), ValueError, "fine_step must be > 0"),
        (lambda: Search(max_span=0.0), ValueError, "max_span must be > 0"),
        (lambda: PcSettings(hard_body_radius=-1.0), ValueError, "hard_body_radius"),
        (lambda: PcSettings(radii={5: 0.0}), ValueError, r"radii\[5\]"),
        (lambda: PcSettings(radii=[1.0]), TypeError, "radii must be a mapping"),
        (lambda: PcSettings(weights=[1.0]), TypeError, "weights must be a mapping"),
        (lambda: PcSettings(members=1), ValueError, "members"),
        (lambda: PcSettings(seed=-1), ValueError, "seed"),
    ],
)
def test_records_are_checked_when_made(make, error, match):
    with pytest.raises(error, match=match):
        make()


def test_a_catalog_run_takes_its_records_whole_and_the_old_keywords_warn():
    cat = catalog.load(SAMPLE)
    new = catalog.propagate_catalog(
        cat,
        AIR,
        END,
        output_step=1800.0,
        initial=catalog.Initial(covariance="tle", drag_sigma=0.1, fit=False),
        execution=rp.Execution(progress=False, errors="record", chunk_size=2),
    )
    with pytest.warns(DeprecationWarning) as seen:
        old = catalog.propagate_catalog(
            cat,
            AIR,
            END,
            output_step=1800.0,
            initial_covariance="tle",
            drag_sigma=0.1,
            fit=False,
            progress=False,
            errors="record",
            chunk_size=2,
        )
    said = " ".join(str(w.message) for w in seen)
    assert "initial=rp.catalog.Initial(covariance=..., drag_sigma=..., fit=...)" in said
    assert "execution=rp.Execution(chunk_size=..., progress=..., errors=...)" in said
    np.testing.assert_array_equal(old.covariance, new.covariance)
    assert (new.status == "propagated").all() and (new.drag_sigma == 0.1).all()
    assert all("TLE accuracy" in n for n in new.covariance_note)
    with pytest.raises(TypeError, match="got execution= and progress="):
        catalog.propagate_catalog(cat, AIR, END, execution=QUIET, progress=False)
    # A Monte Carlo's threads and memory are the method's: the catalog refuses its own.
    with pytest.raises(ValueError, match=r"does not use execution\.threads"):
        catalog.propagate_catalog(cat, AIR, END, execution=rp.Execution(threads=1))


def test_a_screen_takes_its_records_whole_and_the_old_keywords_warn():
    s1, s2 = encounter()
    window = {"start": add_seconds(T, -3 * 3600.0), "end": add_seconds(T, 3 * 3600.0)}
    args = ((s1, CRAFT, "a"), [(s2, CRAFT, "b")], MODEL)
    new = screen(
        *args,
        distance=1e3,
        search=Search(grid_step=30.0, fine_step=0.5),
        execution=rp.Execution(threads=1, progress=False),
        **window,
    )
    with pytest.warns(DeprecationWarning) as seen:
        old = screen(
            *args, distance=1e3, grid_step=30.0, fine_step=0.5, threads=1, progress=False, **window
        )
    said = " ".join(str(w.message) for w in seen)
    assert "search=rp.conjunction.Search(grid_step=..., fine_step=...)" in said
    assert "execution=rp.Execution(threads=..., progress=...)" in said
    assert len(new.events) == 1 and new.grid_step == 30.0
    assert [(e.tca, e.miss_distance) for e in old.events] == [
        (e.tca, e.miss_distance) for e in new.events
    ]
    with pytest.raises(ValueError, match=r"does not use execution\.chunk_size"):
        screen(*args, distance=1e3, execution=rp.Execution(chunk_size=5), **window)


def test_a_screen_sets_aside_secondaries_beyond_max_span():
    # A secondary whose element set is 61 days older than the window is not propagated
    # across those days (as in screen_all): it is listed in skipped with the reason.
    epoch = np.datetime64("2023-11-14T00:00:00", "ns")
    prim = (_circular(400e3, 51.6, 0.0, 0.0, epoch), CRAFT, "primary")
    near = (_circular(410e3, 97.0, 30.0, 10.0, epoch), CRAFT, "near")
    old = (_circular(410e3, 97.0, 30.0, 10.0, add_seconds(epoch, -61 * 86400.0)), CRAFT, "old")
    window = {"start": epoch, "end": add_seconds(epoch, 3600.0), "distance": 5e3}
    res = screen(prim, [near, old], MODEL, execution=QUIET, **window)
    assert [n for n, _ in res.skipped] == ["old"]
    assert "beyond max_span (60 days" in res.skipped[0][1]
    assert res.counts["secondaries"] == 2 and res.counts["radial"] <= 1
    with pytest.raises(ValueError, match=r"the primary old: .*beyond max_span"):
        screen(old, [near], MODEL, execution=QUIET, **window)


def test_screen_all_takes_its_records_whole_and_the_old_keywords_warn():
    s1, s2 = encounter()
    objs = [(s1, CRAFT, "a"), (s2, CRAFT, "b")]
    window = {"start": add_seconds(T, -3 * 3600.0), "end": add_seconds(T, 3 * 3600.0)}
    new = screen_all(
        objs,
        MODEL,
        distance=1e3,
        pc=PcSettings(hard_body_radius=15.0, seed=3),
        search=Search(grid_step=30.0),
        execution=rp.Execution(progress=False, max_memory=1e6),
        **window,
    )
    with pytest.warns(DeprecationWarning) as seen:
        old = screen_all(
            objs,
            MODEL,
            distance=1e3,
            hard_body_radius=15.0,
            seed=3,
            grid_step=30.0,
            progress=False,
            max_memory=1e6,
            **window,
        )
    said = " ".join(str(w.message) for w in seen)
    assert "pc=rp.conjunction.PcSettings(hard_body_radius=..., seed=...)" in said
    assert "search=rp.conjunction.Search(grid_step=...)" in said
    assert "execution=rp.Execution(max_memory=..., progress=...)" in said
    assert len(new.events) == 1 and (new.hard_body_radius == 15.0).all()
    np.testing.assert_array_equal(old.pc, new.pc)
    assert np.isfinite(new.pc).all()
    with pytest.raises(TypeError, match="got pc= and seed="):
        screen_all(objs, MODEL, distance=1e3, pc=PcSettings(), seed=1, **window)
    with pytest.raises(TypeError, match="pc must be True, False or a PcSettings"):
        screen_all(objs, MODEL, distance=1e3, pc="yes", **window)
    with pytest.raises(ValueError, match=r"does not use execution\.chunk_size"):
        screen_all(objs, MODEL, distance=1e3, execution=rp.Execution(chunk_size=5), **window)


def test_every_record_is_frozen():
    for record in (rp.Execution(), catalog.Initial(), Search(), PcSettings()):
        field = dataclasses.fields(record)[0].name
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(record, field, None)


def test_load_takes_its_fit_settings_whole_and_the_old_keywords_warn():
    fitted = catalog.load(SAMPLE, fit=catalog.FitSettings(AIR, threads=1))
    with pytest.warns(DeprecationWarning, match=r"load\(model=, threads=\) is deprecated"):
        old = catalog.load(SAMPLE, fit=True, model=AIR, threads=1)
    assert all(o.fit is not None for o in fitted)
    assert [o.drag_parameter for o in old] == [o.drag_parameter for o in fitted]
    assert fitted[0].fit.rms_total < 100.0  # a real fit to SGP4 (J2..J4: metres)
    with pytest.raises(TypeError, match="got fit=FitSettings"):
        catalog.load(SAMPLE, fit=catalog.FitSettings(AIR), model=AIR)
    with pytest.raises(TypeError, match="fit must be True, False or a FitSettings"):
        catalog.load(SAMPLE, fit="yes")
    with pytest.raises(ValueError, match=r"dynamics\.integrator would be ignored"):
        catalog.FitSettings(AIR, dynamics=rp.Dynamics(integrator="rk4"))
    with pytest.raises(ValueError, match="field_degree"):
        catalog.FitSettings(AIR, dynamics=rp.Dynamics(field_degree=8))
    with pytest.raises(TypeError, match="model"):
        catalog.FitSettings(None)


def test_ensemble_takes_its_debias_whole_and_the_old_keywords_warn():
    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    models = {"ref": AIR, "dense": rp.density.Exponential(5e-12, 400e3, 58.515e3, 0.2)}
    run = {"method": rp.Ccsp(), "duration": 7200.0}
    new = rp.ensemble(state, craft, models, "ref", debias=rp.Debias(cds={"dense": 2.5}), **run)
    with pytest.warns(DeprecationWarning, match=r"debias=rp\.Debias\(cds=\.\.\.\)"):
        old = rp.ensemble(state, craft, models, "ref", cds={"dense": 2.5}, **run)
    np.testing.assert_array_equal(old.component_covariances, new.component_covariances)
    assert new.results["dense"].mean is not None
    longer = rp.ensemble(state, craft, models, "ref", debias=rp.Debias(window=4 * 3600.0), **run)
    assert not np.array_equal(longer.component_means, new.component_means)  # Cd debiased
    with pytest.raises(ValueError, match=r"cds\['dense'\] must be > 0"):
        rp.Debias(cds={"dense": 0.0})
    with pytest.raises(TypeError, match="got debias= and cds="):
        rp.ensemble(state, craft, models, "ref", debias=rp.Debias(), cds={"dense": 2.5}, **run)
