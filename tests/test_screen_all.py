"""All-on-all screening (rp.conjunction.screen_all): the events equal an all-pairs 1-s
brute-force search on a real catalog subset; the Pc per model and for the mixture
against direct pc_2d calls on independently propagated CCSP moments; memory chunks,
thread count and bad input."""

from __future__ import annotations

import dataclasses
import gzip
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import catalog
from rhoprop.conjunction import pc_2d, screen_all
from rhoprop.conjunction.all_on_all import ALL_ON_ALL_STAGES, radial_pair_count
from rhoprop.conjunction.event_pc import RADII, object_radius
from rhoprop.conjunction.kernel import as_object
from rhoprop.constants import MU
from rhoprop.jobs.models import model_by_name
from rhoprop.time import add_seconds, seconds_between

MODEL = rp.density.Exponential.benchmark()


@pytest.fixture(scope="module")
def snapshot(test_data: Path, tmp_path_factory: pytest.TempPathFactory) -> catalog.Catalog:
    src = test_data / "catalogs" / "celestrak_active_20231113.txt.gz"
    path = tmp_path_factory.mktemp("screen_all") / "active.tle"
    path.write_text(gzip.open(src, "rt").read())
    return catalog.load(path, errors="record", nonpositive_bstar="error")  # B* > 0 only


def _perigee_apogee(state: rp.OrbitState) -> tuple[float, float]:
    r, v = state.position, state.velocity
    rn = np.linalg.norm(r)
    a = 1.0 / (2.0 / rn - v @ v / MU)
    e = np.linalg.norm(np.cross(v, np.cross(r, v)) / MU - r / rn)
    return a * (1 - e) - 6378e3, a * (1 + e) - 6378e3


@pytest.fixture(scope="module")
def shell(snapshot: catalog.Catalog) -> tuple[list[catalog.CatalogObject], np.datetime64]:
    """300 objects of the real snapshot crowded in one shell (perigee and apogee 480 to
    620 km) with epochs within a day of the start (so both searches start from the same
    short propagation), every k-th by NORAD id; the start is the latest epoch."""
    start = max(o.state.epoch for o in snapshot)
    crowd = sorted(
        (
            o
            for o in snapshot
            if seconds_between(o.state.epoch, start) < 86400.0
            and all(480e3 < h < 620e3 for h in _perigee_apogee(o.state))
        ),
        key=lambda o: o.norad_id,
    )
    step = max(1, len(crowd) // 300)
    return crowd[::step][:300], start


def _brute_force(objs, start, end, distance):
    """All pairs on a 1-s grid, no filter: each object by DOP853 at rtol 1e-12 from its
    epoch to ``start``, then with 1-s outputs; every sign change of r_rel . v_rel from -
    to + with a distance within ``distance`` + 10 km, TCA from a cubic through
    r_rel . v_rel at the 4 samples around it, the miss from quintics through the relative
    position at the 6 samples around it (exact to ~1 us and ~1 mm)."""
    span = seconds_between(start, end)
    pos, vel = [], []
    for o in objs:
        craft = rp.Spacecraft(1.0, o.drag_parameter)
        lead = seconds_between(o.state.epoch, start)
        s0 = rp.propagate(
            o.state,
            craft,
            MODEL,
            lead,
            dynamics=rp.Dynamics(zonal_degree=4, rtol=1e-12),
        ).state_at(-1)
        tr = rp.propagate(
            s0,
            craft,
            MODEL,
            span,
            output_step=1.0,
            dynamics=rp.Dynamics(zonal_degree=4, rtol=1e-12),
        )
        assert tr.decayed_at is None
        pos.append(tr.positions)
        vel.append(tr.velocities)
    pos, vel = np.array(pos), np.array(vel)
    found = []
    for i in range(len(objs) - 1):
        r = pos[i + 1 :] - pos[i]
        f = np.einsum("jtc,jtc->jt", r, vel[i + 1 :] - vel[i])
        d = np.linalg.norm(r, axis=2)
        jj, kk = np.nonzero((f[:, :-1] < 0) & (f[:, 1:] >= 0))
        for j, k in zip(jj, kk, strict=True):
            if k < 3 or k >= len(f[j]) - 4 or min(d[j, k], d[j, k + 1]) > distance + 10e3:
                continue
            x = np.arange(-1.0, 3.0)
            roots = np.roots(np.polyfit(x, f[j, k - 1 : k + 3], 3))
            x0 = min(z.real for z in roots if abs(z.imag) < 1e-9 and 0 <= z.real <= 1)
            xs = np.arange(-2.0, 4.0)
            rel = [np.polyval(np.polyfit(xs, r[j, k - 2 : k + 4, c], 5), x0) for c in range(3)]
            tca = add_seconds(start, float(k) + x0)
            found.append((i, i + 1 + int(j), tca, float(np.linalg.norm(rel))))
    return found


def test_screen_all_equals_an_all_pairs_brute_force_search(shell):
    objs, start = shell
    assert len(objs) == 300
    end = add_seconds(start, 3 * 3600.0)
    distance = 20e3
    res = screen_all(
        objs,
        MODEL,
        start=start,
        end=end,
        distance=distance,
        pc=False,
        execution=rp.Execution(progress=False),
    )
    brute = [b for b in _brute_force(objs, start, end, distance) if b[3] <= distance]
    assert len(brute) >= 20  # the subset holds real approaches
    # The filters do their work: far fewer pair-intervals reach the bounds than exist.
    intervals = res.counts["pairs"] * 180
    assert res.counts["spatial"] < intervals / 20
    assert res.counts["interpolated"] < res.counts["coarse_grid"] < res.counts["spatial"]
    index = {(o.norad_id): n for n, o in enumerate(objs)}

    # TCA within 1 ms and the miss within 1 m; for slow pairs TCA is ill-conditioned (a
    # 1 cm difference of the propagations moves it by 1 cm / v_rel).
    def close(e, tca):
        tol = max(1e-3, 0.01 / e.relative_speed)
        return abs((e.tca - tca) / np.timedelta64(1, "ns")) * 1e-9 < tol

    for i, j, tca, miss in brute:
        match = [e for e in res.events if (index[e.id1], index[e.id2]) == (i, j) and close(e, tca)]
        assert len(match) == 1, (objs[i].name, objs[j].name, tca, miss)
        assert abs(match[0].miss_distance - miss) < 1.0
    assert len(res.events) == len(brute)
    assert sum(e.relative_speed > 1000.0 for e in res.events) >= 10
    assert all(e.miss_distance <= distance for e in res.events)
    # Each event's stretch within the distance: around TCA, and for a fast encounter
    # (relative motion a straight line over seconds) the analytic 2 sqrt(D^2 - d^2) / v
    # to 0.1 % (the interpolant of 60-s samples and the bisection to 1 ms).
    fast = 0
    for e in res.events:
        assert e.within is not None and e.within[0] <= e.tca <= e.within[1]
        if e.relative_speed > 1000.0 and e.within_seconds < 60.0:
            expect = 2 * np.sqrt(distance**2 - e.miss_distance**2) / e.relative_speed
            assert e.within_seconds == pytest.approx(expect, rel=1e-3, abs=2e-3)
            fast += 1
    assert fast >= 10


def test_memory_chunks_and_threads_do_not_change_the_events(shell):
    objs, start = shell
    objs = objs[:120]
    end = add_seconds(start, 6 * 3600.0)
    kwargs = dict(start=start, end=end, distance=30e3, pc=False)
    one = screen_all(objs, MODEL, execution=rp.Execution(threads=1, progress=False), **kwargs)
    # 120 objects x 48 B x 50 samples: chunks of 50 samples (7 chunks over 6 h).
    small = rp.Execution(threads=2, max_memory=120 * 48 * 50, progress=False)
    cut = screen_all(objs, MODEL, execution=small, **kwargs)
    assert one.chunks == 1 and cut.chunks == 8
    assert len(one.events) == len(cut.events) >= 5
    for a, b in zip(one.events, cut.events, strict=True):
        assert (a.id1, a.id2) == (b.id1, b.id2)
        assert abs(seconds_between(a.tca, b.tca)) < 1e-3
        assert abs(a.miss_distance - b.miss_distance) < 0.1
    counts = [one.counts[k] for k in ALL_ON_ALL_STAGES]
    assert counts[0] == counts[1] == 120 and one.counts["pairs"] == 120 * 119 // 2


def test_pc_per_model_and_mixture_follow_from_the_ccsp_moments(shell):
    # Two models of different mean density; the mixture is the weighted mean of the
    # per-model Pc; each per-model Pc equals pc_2d on moments rebuilt here from
    # propagate_catalog (same CCSP), within the interpolation to TCA.
    objs, start = shell
    objs = objs[:150]
    end = add_seconds(start, 6 * 3600.0)
    models = {
        "low 1.0x": MODEL,
        "High-1.6x": rp.density.Exponential(1.6 * MODEL.rho0, MODEL.h0, MODEL.scale_height),
    }
    res = screen_all(
        objs,
        models,
        start=start,
        end=end,
        distance=30e3,
        pc=rp.conjunction.PcSettings(weights={"low 1.0x": 3.0, "High-1.6x": 1.0}),
        execution=rp.Execution(progress=False),
    )
    assert res.models == ["low 1.0x", "High-1.6x"] and np.allclose(res.weights, [0.75, 0.25])
    # The event table as columns and as a DataFrame: model columns named for Parquet.
    table = res.table()
    np.testing.assert_array_equal(table["pc_low_1_0x"], res.pc_models[:, 0])
    np.testing.assert_array_equal(table["pc_high_1_6x"], res.pc_models[:, 1])
    pytest.importorskip("pandas")
    frame = res.to_pandas()
    assert list(frame.columns) == list(table) and len(frame) == len(res.events)
    np.testing.assert_array_equal(frame["pc"].to_numpy(), res.pc)
    assert (frame["tca"].to_numpy() == table["tca"]).all()
    assert len(res.events) >= 3
    assert np.isfinite(res.pc_models).all()
    assert np.allclose(res.pc, res.pc_models @ res.weights, rtol=1e-12, atol=0)
    assert list(res.pc) == sorted(res.pc, reverse=True)
    e = res.events[0]
    hbr = object_radius(e.name1) + object_radius(e.name2)
    assert res.hard_body_radius[0] == hbr
    # The reference model's Gaussian is centred on the screened states: rebuild it from a
    # catalog run whose last output is TCA itself.
    by_id = {o.norad_id: o for o in objs}
    cat = rp.catalog.propagate_catalog(
        [by_id[e.id1], by_id[e.id2]],
        MODEL,
        e.tca,
        output_step=60.0,
        execution=rp.Execution(progress=False),
    )
    assert cat.epochs[-1] == e.tca
    c1 = cat.covariance[0, -1, :3, :3]
    c2 = cat.covariance[1, -1, :3, :3]
    direct = pc_2d(e.state1[:3], e.state1[3:], c1, e.state2[:3], e.state2[3:], c2, hbr).pc
    # The screen's CCSP updates hourly and at TCA, this one every 60 s: the Pc (1.5e-16,
    # far in the tail, where it moves most with the covariance) agrees to 1e-7 here.
    # Interpolated to TCA from outputs 300 s apart (until 2026-12-05) it was 1 % off.
    assert res.pc_models[0, 0] == pytest.approx(direct, rel=1e-4)


def test_model_columns_are_plain_names():
    from rhoprop.conjunction.all_on_all import model_column

    assert model_column("NRLMSIS 2.1") == "pc_nrlmsis_2_1"
    assert model_column("JB2008") == "pc_jb2008"
    assert model_column(" -- ") == "pc_model"


def test_radii_table_and_hard_body_radius(shell):
    objs, start = shell
    objs = objs[:80]
    end = add_seconds(start, 6 * 3600.0)
    kw = dict(start=start, end=end, distance=30e3, execution=rp.Execution(progress=False))
    res = screen_all(objs, MODEL, pc=rp.conjunction.PcSettings(hard_body_radius=20.0), **kw)
    assert len(res.events) >= 1 and (res.hard_body_radius == 20.0).all()
    e = res.events[0]
    table = screen_all(
        objs, MODEL, pc=rp.conjunction.PcSettings(radii={e.id1: 7.0, e.id2: 3.0}), **kw
    )
    same = [n for n, x in enumerate(table.events) if (x.id1, x.id2, x.tca) == (e.id1, e.id2, e.tca)]
    assert table.hard_body_radius[same[0]] == 10.0
    assert object_radius("FENGYUN 1C DEB") == RADII["debris"]
    assert object_radius("CZ-4C R/B") == RADII["rocket body"]
    assert object_radius("STARLINK-1007") == RADII["payload"]


def test_radial_pair_count_matches_a_direct_count(shell):
    objs, _ = shell
    few = [as_object(o, "o", i) for i, o in enumerate(objs[:60])]
    got = radial_pair_count(few, 5e3, 4)
    from rhoprop.conjunction.all_on_all import J2, R_EARTH, RADIAL_MARGIN, ZONAL_PAD, radial_ranges

    perigee, apogee, _a, p = radial_ranges(few)
    pad = ZONAL_PAD[6] * J2 * R_EARTH**2 / p + RADIAL_MARGIN
    lo, hi = perigee - pad, apogee + pad
    direct = sum(
        1
        for i in range(60)
        for j in range(i + 1, 60)
        if lo[j] <= hi[i] + 5e3 and lo[i] <= hi[j] + 5e3
    )
    assert got == direct


def test_bad_input_is_refused_naming_what(shell):
    objs, start = shell
    end = add_seconds(start, 3600.0)
    with pytest.raises(ValueError, match="distance"):
        screen_all(
            objs[:5],
            MODEL,
            start=start,
            end=end,
            distance=-1.0,
            execution=rp.Execution(progress=False),
        )
    with pytest.raises(ValueError, match="end"):
        screen_all(
            objs[:5],
            MODEL,
            start=end,
            end=start,
            distance=1e3,
            execution=rp.Execution(progress=False),
        )
    with pytest.raises(ValueError, match="at least two"):
        screen_all(
            objs[:1],
            MODEL,
            start=start,
            end=end,
            distance=1e3,
            execution=rp.Execution(progress=False),
        )
    with pytest.raises(ValueError, match="grid_step"):
        screen_all(
            objs[:5],
            MODEL,
            start=start,
            end=end,
            distance=1e3,
            search=rp.conjunction.Search(grid_step=900.0),
        )
    with pytest.raises(ValueError, match="reference"):
        screen_all(objs[:5], {"m": MODEL}, reference="x", start=start, end=end, distance=1e3)
    with pytest.raises(ValueError, match="weights"):
        screen_all(
            objs[:5],
            {"m": MODEL},
            pc=rp.conjunction.PcSettings(weights={"y": 1.0}),
            start=start,
            end=end,
            distance=1e3,
        )
    with pytest.raises(TypeError, match="objects"):
        screen_all([1, 2], MODEL, start=start, end=end, distance=1e3)
    with pytest.raises(ValueError, match="hard_body_radius"):
        screen_all(
            objs[:5],
            MODEL,
            start=start,
            end=end,
            distance=1e3,
            pc=rp.conjunction.PcSettings(hard_body_radius=-1),
        )
    with pytest.raises(ValueError, match="radii"):
        screen_all(
            objs[:5],
            MODEL,
            start=start,
            end=end,
            distance=1e3,
            pc=rp.conjunction.PcSettings(radii={5: 0.0}),
        )


def test_screen_all_messages_name_its_own_parameter_and_the_repeats(shell):
    # They named "secondaries" (a parameter of screen) and, for two identical states,
    # said only "needs at least two objects within max_span; 0 of 1 lie further".
    objs, start = shell
    end = add_seconds(start, 3600.0)
    kw = {"start": start, "end": end, "distance": 1e3, "execution": rp.Execution(progress=False)}
    with pytest.raises(TypeError, match=r"^objects must be a rhoprop\.catalog\.Catalog"):
        screen_all(None, MODEL, **kw)
    with pytest.raises(TypeError, match=r"^objects must be a Catalog or a list"):
        screen_all(objs[0], MODEL, **kw)
    with pytest.raises(ValueError, match=r"two different objects.*1 repeat another's epoch"):
        screen_all([objs[0], objs[0]], MODEL, **kw)
    with pytest.raises(ValueError, match=r"two different objects.*got 0"):
        screen_all([objs[0], objs[0]], MODEL, **kw, search=rp.conjunction.Search(max_span=1.0))


def test_element_sets_older_than_max_span_are_set_aside_and_named(shell):
    # Merged snapshots hold element sets months old; their propagation to the window
    # would hold months of density tiles. Beyond max_span (60 days) they are listed in
    # skipped, and the others' events are those of the run without them.
    import dataclasses

    objs, start = shell
    objs = objs[:60]
    end = add_seconds(start, 3600.0)
    old = objs[0]
    stale_state = rp.OrbitState(
        add_seconds(old.state.epoch, -61 * 86400.0), old.state.position, old.state.velocity
    )
    stale = dataclasses.replace(old, state=stale_state, name="OLD ONE")
    quiet = rp.Execution(progress=False)
    kw = {"start": start, "end": end, "distance": 30e3, "pc": False, "execution": quiet}
    res = screen_all([*objs[1:], stale], MODEL, **kw)
    assert [n for n, _ in res.skipped] == ["OLD ONE"]
    assert "days before the start, beyond max_span (60 days" in res.skipped[0][1]
    alone = screen_all(objs[1:], MODEL, **kw)
    assert [(e.name1, e.name2, e.tca) for e in res.events] == [
        (e.name1, e.name2, e.tca) for e in alone.events
    ]
    with pytest.raises(ValueError, match="max_span"):
        screen_all(objs[:5], MODEL, **kw, search=rp.conjunction.Search(max_span=-1.0))
    from rhoprop.cli import main

    sample = Path(__file__).parent / "data" / "sample.tle"
    with pytest.raises(SystemExit) as stop:
        main(["screen", str(sample), "--end", "2002-09-08", "--max-span", "-1"])
    assert stop.value.code == 2


SYNTHETIC = """
import numpy as np, rhoprop as rp
epoch = np.datetime64("2023-11-14T00:00:00", "ns")
rng = np.random.default_rng(1)
def circ(alt, inc, raan, u):
    r = 6378137.0 + alt; vc = np.sqrt(3.986004418e14 / r)
    inc, raan, u = np.radians([inc, raan, u])
    p = r * np.array([np.cos(u), np.sin(u) * np.cos(inc), np.sin(u) * np.sin(inc)])
    v = vc * np.array([-np.sin(u), np.cos(u) * np.cos(inc), np.cos(u) * np.sin(inc)])
    c, s = np.cos(raan), np.sin(raan)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    return rp.OrbitState(epoch, rot @ p, rot @ v)
craft = rp.Spacecraft(2.2, 0.005)
def objects(n):
    return [(circ(rng.uniform(395e3, 405e3), rng.uniform(40, 100), rng.uniform(0, 360),
                  rng.uniform(0, 360)), craft, f"obj {i}") for i in range(n)]
"""


def test_progress_reports_every_stage():
    namespace: dict[str, object] = {}
    exec(SYNTHETIC, namespace)
    objs = namespace["objects"](150)  # type: ignore[operator]
    epoch = np.datetime64("2023-11-14T00:00:00", "ns")
    seen: dict[str, tuple[int, int]] = {}
    res = screen_all(
        objs,
        MODEL,
        start=epoch,
        end=epoch + np.timedelta64(6, "h"),
        distance=20e3,
        execution=rp.Execution(
            progress=lambda stage, done, total: seen.__setitem__(stage, (done, total))
        ),
    )
    assert len(res.events) >= 1
    assert seen["propagation"] == (150, 150)
    assert seen["sieve"][1] == 360 and seen["Pc (CCSP per model)"][0] >= 2
    assert seen["Pc (per event)"] == (len(res.events), len(res.events))


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_screen_all_stops_on_ctrl_c():
    # ~30 s of screening (6,000 objects x 3 days); SIGINT after it started ends it with
    # KeyboardInterrupt within seconds.
    code = textwrap.dedent(SYNTHETIC) + textwrap.dedent(
        """
        from rhoprop.conjunction import screen_all
        objs = objects(6000)
        print("started", flush=True)
        screen_all(objs, rp.density.Exponential.benchmark(), start=epoch,
                   end=epoch + np.timedelta64(3, "D"), distance=5e3, progress=False)
        print("finished", flush=True)
        """
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "started"
    time.sleep(2.0)
    sent = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert "finished" not in out
    assert "KeyboardInterrupt" in err
    assert time.perf_counter() - sent < 10.0


def test_dask_screen_equals_local(shell):
    # Every stage on a 2-worker LocalCluster (propagation in blocks of objects, the sieve
    # in ranges of grid intervals, the refinement in slices of candidates, the Pc stage's
    # CCSP), over several time chunks (a small max_memory): the local run's events, states,
    # stretches, counts and Pc, bit for bit.
    distributed = pytest.importorskip("distributed")
    objs, start = shell
    objs = objs[:80]
    kw = dict(
        start=start,
        end=add_seconds(start, 6 * 3600.0),
        distance=30e3,
    )
    small = rp.Execution(progress=False, max_memory=1e5)  # 26 samples a chunk for 80 objects
    local = screen_all(objs, MODEL, execution=small, **kw)
    assert len(local.events) >= 1 and local.chunks >= 3
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        on_dask = dataclasses.replace(small, client=client)
        remote = screen_all(objs, MODEL, execution=on_dask, **kw)
    assert [(e.id1, e.id2, e.tca, e.within, e.edge) for e in remote.events] == [
        (e.id1, e.id2, e.tca, e.within, e.edge) for e in local.events
    ]
    for a, b in zip(remote.events, local.events, strict=True):
        np.testing.assert_array_equal(a.state1, b.state1)
        np.testing.assert_array_equal(a.state2, b.state2)
    assert remote.counts == local.counts and remote.chunks == local.chunks
    np.testing.assert_array_equal(remote.pc_models, local.pc_models)


def _twin(obj: catalog.CatalogObject, start: np.datetime64) -> tuple:
    """An object meeting ``obj`` 30 m apart at start + 1.5 h at 2 degrees (265 m/s):
    ``obj``'s state then, raised 30 m and its velocity turned 2 degrees about the radial,
    taken back 30 min (velocity reversed, drag-free: the zonal field is time-reversible)
    to an epoch of start + 1 h."""
    craft = rp.Spacecraft(1.0, obj.drag_parameter)
    lead = seconds_between(obj.state.epoch, start) + 5400.0
    at = rp.propagate(
        obj.state,
        craft,
        MODEL,
        lead,
        dynamics=rp.Dynamics(zonal_degree=4),
    )
    r, v = at.positions[-1], at.velocities[-1]
    u = r / np.linalg.norm(r)
    c, s = np.cos(np.radians(2.0)), np.sin(np.radians(2.0))
    v2 = v * c + np.cross(u, v) * s + u * (u @ v) * (1 - c)
    flipped = rp.OrbitState(add_seconds(start, 5400.0), r + 30.0 * u, -v2, at.frame)
    back = rp.propagate(
        flipped,
        rp.Spacecraft(1.0, 1e-12),
        MODEL,
        1800.0,
        dynamics=rp.Dynamics(zonal_degree=4),
    )
    epoch = add_seconds(start, 3600.0)
    state = rp.OrbitState(epoch, back.positions[-1], -back.velocities[-1], back.frame)
    return (state, craft, "TWIN")


def test_member_monte_carlo_pc_of_the_most_probable_events(shell):
    objs, start = shell
    models = {
        "low": MODEL,
        "high": rp.density.Exponential(1.6 * MODEL.rho0, MODEL.h0, MODEL.scale_height),
    }
    res = screen_all(
        [*objs[:30], _twin(objs[0], start)],
        models,
        start=start,
        end=add_seconds(start, 3 * 3600.0),
        distance=30e3,
        pc=rp.conjunction.PcSettings(hard_body_radius=50.0, monte_carlo_events=2, members=400),
        execution=rp.Execution(progress=False),
    )
    top = res.events[0]
    assert {top.name1, top.name2} == {objs[0].name, "TWIN"}
    assert top.miss_distance < 100.0
    assert abs(seconds_between(top.tca, add_seconds(start, 5400.0))) < 1.0
    # The two most probable events get a Monte Carlo Pc, unless one lies before an
    # object's epoch (the twin's is start + 1 h): then NaN, as documented.
    assert np.isfinite(res.pc_monte_carlo[0]) and np.isnan(res.pc_monte_carlo[2:]).all()
    mixed = res.pc_monte_carlo_models[:2] @ res.weights
    assert np.allclose(res.pc_monte_carlo[:2], mixed, equal_nan=True)
    # Members and Gaussians describe the same spread: for the twin they agree within the
    # Monte Carlo's noise (160,000 member pairs, ~450 hits from 400 + 400 members: the
    # U-statistic's relative sigma is ~10 %; measured 2.78e-3 against 2.84e-3).
    assert res.pc[0] > 1e-3
    assert res.pc[0] / 1.4 < res.pc_monte_carlo[0] < 1.4 * res.pc[0]
    with pytest.raises(TypeError, match="monte_carlo_events"):
        screen_all(
            objs[:5],
            MODEL,
            start=start,
            end=add_seconds(start, 3600.0),
            distance=1e3,
            pc=rp.conjunction.PcSettings(monte_carlo_events=1.5),
        )


def test_rhoprop_screen_writes_the_event_table_and_cdms(shell, test_data, tmp_path, capsys):
    pytest.importorskip("ccsds_ndm")
    import pyarrow.parquet as pq

    from rhoprop.cli import main
    from rhoprop.conjunction import read_cdm

    objs, start = shell
    objs = objs[:120]
    tle = tmp_path / "crowd.tle"
    # As published: with Chandra (CXO), whose orbit reaches 21.8 Earth radii.
    raw = gzip.open(test_data / "catalogs" / "celestrak_active_20231113.txt.gz", "rt").read()
    lines = raw.splitlines()
    at = next(n for n, line in enumerate(lines) if line.strip() == "CXO")
    cxo = "\n".join(lines[at : at + 3]) + "\n"
    tle.write_text(cxo + "".join(f"{o.name}\n{o.elements[0]}\n{o.elements[1]}\n" for o in objs))
    end = add_seconds(start, 6 * 3600.0)
    out = tmp_path / "out"
    args = ["screen", str(tle), "--start", str(start), "--end", str(end), "--distance", "30000"]
    every = ["--cdm-min-pc", "0"]
    assert main([*args, "--model", "exponential", "--out", str(out), *every]) == 0
    captured = capsys.readouterr()
    printed = captured.out
    assert "skipped" in captured.err and "Earth radii" in captured.err  # listed, not fatal
    table = pq.read_table(out / "events.parquet").to_pydict()
    cdms = sorted((out / "cdm").glob("*.cdm"))
    assert len(table["tca"]) == len(cdms) >= 3
    assert f"{len(cdms)} events within 30000 m" in printed
    # By default a CDM only for the events with mixture Pc >= 1e-7 (the table has all);
    # --no-cdm none; a threshold that is no probability is refused before any work.
    assert main([*args, "--model", "exponential", "--out", str(tmp_path / "d")]) == 0
    assert "(events with Pc >= 1e-07)" in capsys.readouterr().out
    likely = [n for n, p in enumerate(table["pc"]) if p >= 1e-7]
    written = sorted(p.name for p in (tmp_path / "d" / "cdm").glob("*.cdm"))
    assert written == [cdms[n].name for n in likely] and len(likely) < len(cdms)
    assert main([*args, "--model", "exponential", "--out", str(tmp_path / "n"), "--no-cdm"]) == 0
    assert not (tmp_path / "n" / "cdm").exists()
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main([*args, "--out", str(tmp_path / "x"), "--cdm-min-pc", "2"])
    assert "must be a probability" in capsys.readouterr().err and not (tmp_path / "x").exists()
    first = read_cdm(cdms[0])
    assert first.miss_distance == pytest.approx(table["miss_distance"][0], abs=1e-3)
    assert first.collision_probability == pytest.approx(table["pc"][0], rel=1e-9)
    assert table["pc"] == sorted(table["pc"], reverse=True)
    assert str(first.object1.designator) == str(table["id1"][0])
    # --strict stops at Chandra, naming it (exit 1, the message on stderr).
    assert main([*args, "--model", "exponential", "--out", str(tmp_path / "o2"), "--strict"]) == 1
    assert "Earth radii" in capsys.readouterr().err
    # The same run from Python gives the same events.
    res = screen_all(
        objs,
        model_by_name("exponential"),
        start=start,
        end=end,
        distance=30e3,
        execution=rp.Execution(progress=False),
    )
    assert len(res.events) == len(cdms)
    # A CDM's states are the screened TEME states rotated to EME2000 (REF_FRAME true):
    # read back with the maintained reader, they equal astropy's TEME -> GCRS to 1 m.
    from astropy import units as u
    from astropy.coordinates import GCRS, TEME, CartesianRepresentation
    from astropy.time import Time

    from rhoprop.conjunction.cdm import cdm_text
    from rhoprop.jobs.screen import _message

    ev = res.events[0]
    path = tmp_path / "one.cdm"
    path.write_text(cdm_text(_message(res, 0, np.datetime64("2026-12-05"))))
    back = read_cdm(path)
    t = Time(ev.tca, scale="utc")
    for obj, teme in ((back.object1, ev.state1), (back.object2, ev.state2)):
        ref = TEME(CartesianRepresentation(teme[:3] * u.m), obstime=t).transform_to(GCRS(obstime=t))
        assert obj.ref_frame == "EME2000"
        assert np.linalg.norm(obj.position - ref.cartesian.xyz.to(u.m).value) < 1.0
        assert np.linalg.norm(obj.position - teme[:3]) > 20e3  # the rotation is no relabel


def test_default_start_is_not_moved_by_one_element_set_dated_ahead(shell):
    # The 2023-07-04 snapshot holds one element set of 2023-07-07: the newest epoch would
    # start the window three days late. The default is the 99 % quantile of the epochs.
    import dataclasses

    from rhoprop.jobs.screen import default_start

    objs, _ = shell
    newest = max(o.state.epoch for o in objs)
    odd = objs[0]
    ahead = rp.OrbitState(add_seconds(newest, 3 * 86400.0), odd.state.position, odd.state.velocity)
    cat = catalog.Catalog([*objs, dataclasses.replace(odd, state=ahead)])
    assert default_start(cat) <= newest
    epochs = np.sort([o.state.epoch for o in cat])
    assert default_start(cat) == epochs[int(0.99 * (len(epochs) - 1))]


def test_a_stop_on_the_step_grid_does_not_underflow(test_data, tmp_path):
    # INMARSAT 3-F5's epoch lies 858.740832 s before the start: the adaptive run from its
    # epoch to the start took a last step whose t + (t_end - t) rounded to one ulp short
    # of the start, then a 1.1e-13 s step: StepUnderflowError aborted the whole screen.
    lines = (
        gzip.decompress((test_data / "catalogs" / "celestrak_active_20231113.txt.gz").read_bytes())
        .decode()
        .splitlines()
    )
    names = {"INMARSAT 3-F5", "INMARSAT 4-F1"}
    text = "".join(
        "\n".join(lines[i : i + 3]) + "\n"
        for i in range(len(lines) - 2)
        if lines[i].strip() in names and lines[i + 1].startswith("1 ")
    )
    path = tmp_path / "geo.tle"
    path.write_text(text)
    objs = catalog.load(path)
    assert len(objs) == 2
    gap = seconds_between(objs.objects[0].state.epoch, np.datetime64("2023-11-13T12:00"))
    assert gap == pytest.approx(858.740832, abs=1e-6)
    result = screen_all(
        objs,
        rp.density.Msis(),
        start="2023-11-13T12:00",
        end="2023-11-14T12:00",
        distance=5e3,
    )
    assert result.counts["screened"] == 2 and not result.skipped


def _circular(start: np.datetime64, radius: float, along: float) -> rp.OrbitState:
    """A circular orbit of ``radius`` m in a fixed plane, ``along`` m ahead (> 0) of the
    reference point at ``start``."""
    x, u = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.6, 0.8])
    phi = along / radius
    v = np.sqrt(MU / radius)
    pos = radius * (np.cos(phi) * x + np.sin(phi) * u)
    return rp.OrbitState(start, pos, v * (-np.sin(phi) * x + np.cos(phi) * u))


def test_minima_at_the_window_ends_are_events():
    # Two objects on circular orbits 1 m apart in radius and 100 m apart along-track: the
    # lower one drifts 1.7 mm/s forward, so the distance grows all window when it starts
    # ahead (closest approach: the window's start) and falls all window when it starts
    # behind (closest approach after the window's end). Neither had an event (no sign
    # change of r . v inside the window); both are now events flagged with their edge,
    # without a short-encounter Pc.
    start = np.datetime64("2024-03-01T00:00")
    end = start + np.timedelta64(6, "h")
    craft = rp.Spacecraft(2.2, 0.01)
    r = 6778e3
    a = _circular(start, r, 0.0)
    for along, edge in ((100.0, "start"), (-100.0, "end")):
        b = _circular(start, r - 1.0, along)
        res = screen_all(
            [(a, craft, "a"), (b, craft, "b")], MODEL, start=start, end=end, distance=5e3
        )
        assert [e.edge for e in res.events] == [edge], res.events
        event = res.events[0]
        assert event.tca == (start if edge == "start" else end)
        gap = np.linalg.norm(event.relative_position)
        if edge == "start":
            assert gap == pytest.approx(np.hypot(1.0, 100.0), abs=0.01)
        else:  # 6 h at 1.5 n (1 m) = 1.7 mm/s closes about 37 m
            assert 55.0 < gap < 70.0
        table = res.table()
        assert table["edge"][0] == edge and np.isnan(table["pc"][0])
        assert "window's " + edge in table["pc_note"][0]
        # Within 5 km for the whole window: the stretch is the window.
        assert event.within == (start, end)
        assert table["within_start"][0] == start and table["within_end"][0] == end


def test_a_slow_pass_is_one_event_with_its_stretch_within_the_distance():
    # Two circular orbits 500 m apart in radius: the lower one gains about 0.85 m/s
    # along-track and passes the upper from 9 km behind to 9 km ahead in 6 h, within
    # 5 km for about 3 h. The stretch against the distance of two rp.propagate runs
    # sampled every 10 s, crossings interpolated linearly: within 5 s (0.85 m/s: a few
    # metres of difference between the two propagations' samples).
    start = np.datetime64("2024-03-01T00:00")
    end = start + np.timedelta64(6, "h")
    craft = rp.Spacecraft(2.2, 0.01)
    r = 6778e3
    a, b = _circular(start, r, 0.0), _circular(start, r - 500.0, -9e3)
    res = screen_all([(a, craft, "a"), (b, craft, "b")], MODEL, start=start, end=end, distance=5e3)
    assert len(res.events) >= 1 and all(e.edge is None for e in res.events)
    spans = {e.within for e in res.events}
    assert len(spans) == 1  # every minimum of the stretch carries the whole stretch
    first, last = spans.pop()
    ta = rp.propagate(a, craft, MODEL, 6 * 3600.0, output_step=10.0)
    tb = rp.propagate(b, craft, MODEL, 6 * 3600.0, output_step=10.0)
    d = np.linalg.norm(tb.positions - ta.positions, axis=1) - 5e3
    t = (ta.epochs - start) / np.timedelta64(1, "s")
    k = np.flatnonzero(np.diff(np.sign(d)) != 0)
    assert len(k) == 2  # in once, out once
    cross = [t[i] - d[i] * (t[i + 1] - t[i]) / (d[i + 1] - d[i]) for i in k]
    got = [(w - start) / np.timedelta64(1, "s") for w in (first, last)]
    assert got == pytest.approx(cross, abs=5.0)
    assert 2 * 3600 < got[1] - got[0] < 4 * 3600


def _plane_orbit(
    epoch: np.datetime64, radius: float, node: np.ndarray, normal: np.ndarray, u: float
):
    """A circular orbit of ``radius`` m in the plane of ``normal`` at argument of latitude
    ``u`` rad from the unit ``node``."""
    w = np.cross(normal, node)
    v = np.sqrt(MU / radius)
    return rp.OrbitState(
        epoch,
        radius * (np.cos(u) * node + np.sin(u) * w),
        v * (-np.sin(u) * node + np.cos(u) * w),
    )


def test_events_days_from_the_epochs_say_when_the_gaussian_no_longer_holds():
    # Two 300 km orbits of one inclination, nodes 30 deg apart, both at the planes'
    # crossing at their epoch (one 20 m higher): they meet there once per revolution for
    # weeks. A day after the epochs the arcs are straight at the scale of the spread; nine
    # days after, the arc's sag is the radial spread and each event says its 2-D Pc is
    # approximate (docs/mc-vs-ccsp.md, "Every run knows").
    epoch = np.datetime64("2024-03-01T00:00")
    inc = np.radians(51.6)
    states = []
    for raan, dr in ((0.0, 0.0), (np.radians(30.0), 20.0)):
        node = np.array([np.cos(raan), np.sin(raan), 0.0])
        normal = np.array([np.sin(raan) * np.sin(inc), -np.cos(raan) * np.sin(inc), np.cos(inc)])
        states.append((node, normal, dr))
    cross = np.cross(states[0][1], states[1][1])
    cross /= np.linalg.norm(cross)
    objs = []
    for name, (node, normal, dr) in zip("AB", states, strict=True):
        u = np.arctan2(cross @ np.cross(normal, node), cross @ node)
        r = rp.constants.R_EARTH + 300e3 + dr
        objs.append((_plane_orbit(epoch, r, node, normal, u), rp.Spacecraft(2.2, 0.01), name))
    model = rp.density.Exponential.benchmark(rel_sigma=0.2)
    notes = {}
    for days in (1, 9):
        start = epoch + np.timedelta64(days * 86400, "s")
        res = screen_all(
            objs,
            model,
            start=start,
            end=start + np.timedelta64(2, "h"),
            distance=50e3,
            execution=rp.Execution(progress=False),
        )
        assert len(res.events) >= 1 and np.isfinite(res.pc).all()
        notes[days] = res.pc_notes
    assert not any("curves" in n for n in notes[1]), notes[1]
    assert all("A's spread curves" in n and "B's spread curves" in n for n in notes[9])


def test_an_object_whose_epoch_is_after_all_its_events_gets_its_epoch_covariance():
    # The Pc stage runs each object to its own TCAs after its epoch; one needed only
    # before its epoch (a start before it) is not run and takes its covariance at epoch,
    # while its partner runs (this raised KeyError when the Pc went to each own TCA).
    a = rp.scenarios.paper_state()
    craft = rp.scenarios.paper_spacecraft()
    r, v = np.array(a.position), np.array(a.velocity)
    b0 = rp.OrbitState(a.epoch, r * (1 + 500.0 / np.linalg.norm(r)), v)
    later = rp.propagate(b0, craft, MODEL, 86400.0, output_step=86400.0)
    b = rp.OrbitState(add_seconds(a.epoch, 86400.0), later.positions[-1], later.velocities[-1])
    res = screen_all(
        [(a, craft), (b, craft)],
        MODEL,
        start=a.epoch,
        end=add_seconds(a.epoch, 6 * 3600.0),
        distance=5e3,
        execution=rp.Execution(progress=False),
    )
    assert len(res.events) == 1
    assert "an object's epoch is after TCA: its covariance at epoch" in res.pc_notes[0]
    assert np.isfinite(res.pc_models).all() and np.isfinite(res.covariance2[0]).all()
