"""Close-approach screening: closest_approach and screen against
independent references: orbits built to meet at a known time and place, a brute-force
fine-grid search with a tight DOP853, a brute-force all-pairs screen of a real catalog
snapshot, the radial prefilter's pads against propagated radii, bad input and Ctrl-C."""

from __future__ import annotations

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
from rhoprop import _core, catalog
from rhoprop.conjunction import CloseApproach, closest_approach, screen
from rhoprop.conjunction.screening import STAGES
from rhoprop.constants import J2, MU, R_EARTH
from rhoprop.time import add_seconds, seconds_between, ut1_seconds

MODEL = rp.density.Exponential.benchmark()
CRAFT = rp.Spacecraft(2.2, 0.005)
#: The constructed encounter: both objects are at (nearly) the same place at T.
T = np.datetime64("2023-11-14T06:00:30.000000000", "ns")
MISS = 300.0


def _back(position, velocity, dt, at=T, craft=CRAFT):
    """The state ``dt`` s before ``at`` of the orbit through (position, velocity) then:
    the core's fixed-step RK8 backwards at a 10 s step (the only backward integrator)."""
    problem = _core.Problem(
        epoch=ut1_seconds(at),
        state=np.concatenate([position, velocity]),
        drag=craft.drag_parameter,
        floor_altitude=0.0,
        zonal_degree=2,
    )
    s = _core.propagate(
        MODEL.atmosphere(None, 0.0), problem, np.array([0.0, -dt]), "rk8", 10.0
    ).states
    # TEME: the core integrated in the axes given, the frame screens run in.
    return rp.OrbitState(add_seconds(at, -dt), s[-1, :3], s[-1, 3:], "TEME")


def encounter(miss=MISS, lead1=6 * 3600.0, lead2=5 * 3600.0 + 17.3, inc2=97.0, at=T):
    """Two orbits (ISS-like 51.6 deg and, by default, sun-synchronous-like 97 deg
    inclination, 400 km) that cross at ``at`` with a radial offset ``miss`` (perpendicular
    to the relative velocity, so ``at`` is the time of closest approach to first order);
    their states ``lead1`` / ``lead2`` s before it."""
    r = np.array([6778e3, 0.0, 0.0])
    vc = np.sqrt(MU / 6778e3)
    i1, i2 = np.radians(51.6), np.radians(inc2)
    v1 = vc * np.array([0.0, np.cos(i1), np.sin(i1)])
    v2 = vc * np.array([0.0, np.cos(i2), np.sin(i2)])
    r2 = r + miss * r / np.linalg.norm(r)
    return _back(r, v1, lead1, at), _back(r2, v2, lead2, at)


def brute_force_tca(s1, s2, guess, half=120.0):
    """Independent reference: both orbits by DOP853 at rtol 1e-12 from their own epochs
    with 1 s outputs up to ``guess`` + ``half``, the distance minimum on that grid, then
    both again from the grid state before it at 1 ms outputs over 2 s and the minimum
    there (the parabola through the three samples around it for the time)."""
    end = add_seconds(guess, half)

    def grid(state, start, span, step):
        tr = rp.propagate(
            state,
            CRAFT,
            MODEL,
            span,
            output_step=step,
            dynamics=rp.Dynamics(rtol=1e-12),
        )
        return tr

    t0 = add_seconds(guess, -half)
    a0 = rp.propagate(
        s1,
        CRAFT,
        MODEL,
        seconds_between(s1.epoch, t0),
        dynamics=rp.Dynamics(rtol=1e-12),
    ).state_at(-1)
    b0 = rp.propagate(
        s2,
        CRAFT,
        MODEL,
        seconds_between(s2.epoch, t0),
        dynamics=rp.Dynamics(rtol=1e-12),
    ).state_at(-1)
    span = seconds_between(t0, end)
    ta, tb = grid(a0, t0, span, 1.0), grid(b0, t0, span, 1.0)
    d = np.linalg.norm(tb.positions - ta.positions, axis=1)
    k = int(np.argmin(d))
    fa, fb = grid(ta.state_at(k - 1), None, 2.0, 1e-3), grid(tb.state_at(k - 1), None, 2.0, 1e-3)
    d = np.linalg.norm(fb.positions - fa.positions, axis=1)
    j = int(np.argmin(d))
    y0, y1, y2 = d[j - 1] ** 2, d[j] ** 2, d[j + 1] ** 2
    shift = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) * 1e-3
    tca = add_seconds(fa.epochs[j], shift)
    return tca, float(d[j])


def test_closest_approach_matches_known_encounter_and_brute_force():
    s1, s2 = encounter()
    # Different epochs (17.3 s apart) and output grids: aligned on absolute times.
    tr1 = rp.propagate(s1, CRAFT, MODEL, 12 * 3600.0, output_step=60.0)
    tr2 = rp.propagate(s2, CRAFT, MODEL, 12 * 3600.0, output_step=45.0)
    events = closest_approach(tr1, tr2, model=MODEL, spacecraft=CRAFT, names=("iss", "sso"))
    assert all(isinstance(e, CloseApproach) for e in events)
    assert [e.tca for e in events] == sorted(e.tca for e in events)
    best = min(events, key=lambda e: e.miss_distance)
    ref_tca, ref_miss = brute_force_tca(s1, s2, T)
    dt = abs((best.tca - ref_tca) / np.timedelta64(1, "ns")) * 1e-9
    assert dt < 1e-3, dt
    assert abs(best.miss_distance - ref_miss) < 1.0
    # The construction itself: the orbits meet at T, MISS apart (to the mm level of the
    # backward RK8 and the second-order offset of TCA from T).
    assert abs((best.tca - T) / np.timedelta64(1, "ns")) * 1e-9 < 1e-3
    assert best.miss_distance == pytest.approx(MISS, abs=0.05)
    assert best.relative_speed == pytest.approx(
        2 * np.sqrt(MU / 6778e3) * np.sin(np.radians(97.0 - 51.6) / 2), rel=1e-3
    )
    assert (best.name1, best.name2) == ("iss", "sso")
    np.testing.assert_allclose(best.relative_position, best.state2[:3] - best.state1[:3])
    # At TCA the relative velocity is perpendicular to the relative position.
    cos = best.relative_position @ best.relative_velocity
    cos /= best.miss_distance * best.relative_speed
    assert abs(cos) < 1e-6
    # Every other local minimum is a real one: the distance grows on both sides.
    for e in events:
        assert e.relative_position @ e.relative_velocity == pytest.approx(
            0.0, abs=1e-3 * e.miss_distance * e.relative_speed
        )


def test_closest_approach_interpolation_only_for_fine_outputs():
    s1, s2 = encounter(lead1=600.0, lead2=600.0)
    tr1 = rp.propagate(
        s1,
        CRAFT,
        MODEL,
        1200.0,
        output_step=5.0,
        dynamics=rp.Dynamics(rtol=1e-12),
    )
    tr2 = rp.propagate(
        s2,
        CRAFT,
        MODEL,
        1200.0,
        output_step=5.0,
        dynamics=rp.Dynamics(rtol=1e-12),
    )
    (event,) = closest_approach(tr1, tr2, max_distance=1e3)
    ref_tca, ref_miss = brute_force_tca(s1, s2, T, half=30.0)
    assert abs((event.tca - ref_tca) / np.timedelta64(1, "ns")) * 1e-9 < 1e-3
    assert abs(event.miss_distance - ref_miss) < 1.0
    coarse = rp.propagate(s1, CRAFT, MODEL, 1200.0, output_step=60.0)
    with pytest.raises(ValueError, match="too coarse"):
        closest_approach(coarse, tr2)


def test_closest_approach_bad_input():
    s1, s2 = encounter()
    tr1 = rp.propagate(s1, CRAFT, MODEL, 3600.0, output_step=60.0)
    with pytest.raises(TypeError, match="Trajectory"):
        closest_approach(tr1, s2)
    with pytest.raises(TypeError, match="spacecraft"):
        closest_approach(tr1, tr1, model=MODEL)
    with pytest.raises(TypeError, match="model"):
        closest_approach(tr1, tr1, model="msis", spacecraft=CRAFT)
    later = rp.OrbitState(add_seconds(s1.epoch, 7200.0), s1.position, s1.velocity, "TEME")
    tr3 = rp.propagate(later, CRAFT, MODEL, 3600.0, output_step=60.0)
    with pytest.raises(ValueError, match="share no time span"):
        closest_approach(tr1, tr3, model=MODEL, spacecraft=CRAFT)
    with pytest.raises(ValueError, match="fine_step"):
        closest_approach(tr1, tr1, model=MODEL, spacecraft=CRAFT, fine_step=0.0)


def test_screen_finds_an_encounter_between_grid_samples():
    # T sits mid-way between the 60-s samples from `start`: at the samples the objects are
    # ~200 km apart, so only the sampling margin keeps the pair.
    s1, s2 = encounter()
    start = add_seconds(T, -3 * 3600.0)
    decoys = [
        (rp.OrbitState(s1.epoch, s1.position, -s1.velocity, "TEME"), CRAFT, "retrograde"),
        (
            rp.OrbitState(s1.epoch, 1.3 * s1.position, s1.velocity / np.sqrt(1.3), "TEME"),
            CRAFT,
            "high",
        ),
    ]
    res = screen(
        (s1, CRAFT, "primary"),
        [(s2, CRAFT, "secondary"), *decoys],
        MODEL,
        start=start,
        end=add_seconds(T, 3 * 3600.0),
        distance=1e3,
        execution=rp.Execution(progress=False),
    )
    assert list(res.counts) == list(STAGES)
    assert res.counts["secondaries"] == 3 and res.counts["radial"] == 2
    assert res.counts["events"] == 1
    (event,) = res.events
    ref_tca, ref_miss = brute_force_tca(s1, s2, T)
    assert abs((event.tca - ref_tca) / np.timedelta64(1, "ns")) * 1e-9 < 1e-3
    assert abs(event.miss_distance - ref_miss) < 1.0
    assert (event.name1, event.name2) == ("primary", "secondary")
    assert set(res.timings) >= {"radial", "propagation", "coarse_grid", "refinement"}
    # The events as a table and a DataFrame (as the all-on-all screen gives them).
    frame = res.to_pandas()
    assert list(frame["name2"]) == ["secondary"] and frame["tca"][0] == event.tca
    assert frame["miss_distance"][0] == event.miss_distance and frame["edge"][0] == ""
    assert frame["id1"][0] == -1 and np.isnat(res.table()["within_start"][0])


@pytest.mark.parametrize(
    ("inc2", "phase", "grid_step"),
    [(97.0, 0.5, 60.0), (170.0, 0.5, 60.0), (128.4, 0.37, 240.0), (53.0, 0.81, 120.0)],
)
def test_screen_sampling_margin_keeps_fast_encounters(inc2, phase, grid_step):
    # Encounters at a fraction `phase` of a grid interval, relative speeds 0.19 to
    # 13.2 km/s (nearly head-on at 170 deg): at the nearest sample the objects are 4 to
    # 846 km apart, 3 to 2,800 times the distance, yet the bound (relative speed x half the
    # spacing) keeps them, and the refined TCA and miss are the built ones.
    start = np.datetime64("2023-11-14T03:00:00", "ns")
    at = add_seconds(start, (30 + phase) * grid_step)
    s1, s2 = encounter(lead1=3 * 3600.0, lead2=2 * 3600.0 + 41.0, inc2=inc2, at=at)
    res = screen(
        (s1, CRAFT),
        [(s2, CRAFT)],
        MODEL,
        start=start,
        end=add_seconds(start, 6 * 3600.0),
        distance=400.0,
        search=rp.conjunction.Search(grid_step=grid_step),
        execution=rp.Execution(progress=False),
    )
    (event,) = res.events
    assert abs((event.tca - at) / np.timedelta64(1, "ns")) * 1e-9 < 1e-3
    assert event.miss_distance == pytest.approx(MISS, abs=0.05)


def _spherical_exponential(times, lat, lon, alt):
    """The benchmark exponential atmosphere as a function of geodetic inputs (it uses the
    spherical altitude |r| - Re), for a sampled model."""
    lla = np.stack([np.ravel(lat), np.ravel(lon), np.ravel(alt)], axis=1)
    h = np.linalg.norm(_core.geodetic_to_fixed(lla), axis=1).reshape(np.shape(alt)) - R_EARTH
    mean = 3.725e-12 * np.exp(-(h - 400e3) / 58.515e3)
    return mean, 0.1 * mean


def test_screen_with_a_sampled_model_and_an_eccentric_secondary():
    # A sampled model (fields per altitude tier: the 400 km objects at full resolution, a
    # 400 x 9,130 km orbit in a coarser one) gives the event the analytic atmosphere gives
    # (measured: 14 us and 1.4 cm apart).
    s1, s2 = encounter()
    start = add_seconds(T, -3 * 3600.0)
    end = add_seconds(T, 3 * 3600.0)
    eccentric = rp.OrbitState(s1.epoch, s1.position, 1.18 * s1.velocity, "TEME")
    secs = [(s2, CRAFT, "secondary"), (eccentric, CRAFT, "eccentric")]
    kw = {"start": start, "end": end, "distance": 1e3, "execution": rp.Execution(progress=False)}
    sampled = rp.density.FromFunction(_spherical_exponential)
    res = screen((s1, CRAFT), secs, sampled, **kw)
    ref = screen((s1, CRAFT), secs, MODEL, **kw)
    assert res.counts["propagated"] == 2 and not res.skipped
    (event,), (expected,) = res.events, ref.events
    assert abs((event.tca - expected.tca) / np.timedelta64(1, "ns")) * 1e-9 < 1e-3
    assert event.miss_distance == pytest.approx(expected.miss_distance, abs=0.5)
    assert res.timings["field"] > 0
    # closest_approach re-propagates through the sampled model too (epochs 17.3 s apart).
    tr1 = rp.propagate(s1, CRAFT, MODEL, 7 * 3600.0, output_step=60.0)
    tr2 = rp.propagate(s2, CRAFT, MODEL, 6 * 3600.0, output_step=60.0)
    (close,) = closest_approach(tr1, tr2, model=sampled, spacecraft=CRAFT, max_distance=1e3)
    assert abs((close.tca - expected.tca) / np.timedelta64(1, "ns")) * 1e-9 < 1e-3
    assert close.miss_distance == pytest.approx(expected.miss_distance, abs=0.5)


def _circular(alt, inc_deg, raan_deg, u_deg, epoch):
    r = R_EARTH + alt
    vc = np.sqrt(MU / r)
    inc, raan, u = np.radians([inc_deg, raan_deg, u_deg])
    pos = r * np.array([np.cos(u), np.sin(u) * np.cos(inc), np.sin(u) * np.sin(inc)])
    vel = vc * np.array([-np.sin(u), np.cos(u) * np.cos(inc), np.cos(u) * np.sin(inc)])
    rot = np.array(
        [[np.cos(raan), -np.sin(raan), 0.0], [np.sin(raan), np.cos(raan), 0.0], [0, 0, 1.0]]
    )
    return rp.OrbitState(epoch, rot @ pos, rot @ vel)


def test_screen_bad_input_and_decay():
    epoch = np.datetime64("2023-11-14T00:00:00", "ns")
    prim = (_circular(400e3, 51.6, 0.0, 0.0, epoch), CRAFT)
    sec = [(_circular(410e3, 97.0, 30.0, 10.0, epoch), CRAFT)]
    end = add_seconds(epoch, 3600.0)
    kw = {"start": epoch, "end": end, "distance": 5e3, "execution": rp.Execution(progress=False)}
    with pytest.raises(ValueError, match="after start"):
        screen(prim, sec, MODEL, **{**kw, "end": epoch})
    with pytest.raises(ValueError, match="distance"):
        screen(prim, sec, MODEL, **{**kw, "distance": 0.0})
    with pytest.raises(ValueError, match="grid_step"):
        screen(prim, sec, MODEL, **kw, search=rp.conjunction.Search(grid_step=600.0))
    with pytest.raises(ValueError, match="empty"):
        screen(prim, [], MODEL, **kw)
    with pytest.raises(ValueError, match="only the primary"):
        screen(prim, [prim], MODEL, **kw)
    with pytest.raises(TypeError, match="secondaries"):
        screen(prim, 42, MODEL, **kw)
    with pytest.raises(TypeError, match="single object"):
        screen(prim, sec[0], MODEL, **kw)
    with pytest.raises(TypeError, match="OrbitState"):
        screen(prim, [(sec[0][0], 2.2)], MODEL, **kw)
    with pytest.raises(TypeError, match="model"):
        screen(prim, sec, None, **kw)
    with pytest.raises(ValueError, match="errors"):
        screen(prim, sec, MODEL, **{**kw, "execution": rp.Execution(errors="ignore")})
    # A secondary that comes down before the window starts is skipped, with its decay
    # epoch; one that comes down inside it is screened up to then.
    # (Both start at the primary's altitude, so that the radial prefilter keeps them.)
    early = (
        _circular(400e3, 51.6, 0.0, 5.0, add_seconds(epoch, -2 * 86400.0)),
        rp.Spacecraft(2.2, 20.0),
        "old",
    )
    heavy = rp.Spacecraft(2.2, 300.0)
    inside = (_circular(400e3, 51.6, 0.0, 5.0, epoch), heavy, "sinking")
    res = screen(prim, [*sec, early, inside], MODEL, **kw)
    assert [name for name, _ in res.skipped] == ["old"]
    assert "decayed at" in res.skipped[0][1]
    assert [name for name, _ in res.notes] == ["sinking"]
    assert res.counts["propagated"] == res.counts["radial"] - 1
    # A primary that decays before the end is refused.
    sinking_primary = (inside[0], heavy)
    with pytest.raises(rp.DecayError, match="primary"):
        screen(sinking_primary, sec, MODEL, **kw)


def test_screen_secondary_decaying_after_an_approach():
    # A secondary with 8,000x the drag passes the primary 10 min into the window (1.5 km)
    # and comes down 75 min later: its approaches are refined, its decay noted, nothing
    # after it.
    s1, s2 = encounter(lead2=600.0)
    heavy = rp.Spacecraft(2.2, 40.0)
    start = add_seconds(T, -600.0)
    res = screen(
        (s1, CRAFT),
        [(s2, heavy, "sinking")],
        MODEL,
        start=start,
        end=add_seconds(T, 3 * 3600.0),
        distance=200e3,
        execution=rp.Execution(progress=False),
    )
    assert [name for name, _ in res.notes] == ["sinking"]
    decayed = np.datetime64(res.notes[0][1].split()[2], "ns")
    assert res.events and all(e.tca < decayed for e in res.events)
    first = res.events[0]
    assert abs((first.tca - T) / np.timedelta64(1, "s")) < 60
    cos = first.relative_position @ first.relative_velocity
    assert abs(cos) < 1e-6 * first.miss_distance * first.relative_speed


def test_screen_progress_and_interrupt_in_process():
    epoch = np.datetime64("2023-11-14T00:00:00", "ns")
    prim = (_circular(400e3, 51.6, 0.0, 0.0, epoch), CRAFT)
    secs = [(_circular(400e3 + 5e3 * k, 60.0, 7.0 * k, 3.0 * k, epoch), CRAFT) for k in range(6)]
    seen: list[int] = []
    screen(
        prim,
        secs,
        MODEL,
        start=epoch,
        end=add_seconds(epoch, 3600.0),
        distance=5e3,
        execution=rp.Execution(threads=1, progress=seen.append),
    )
    assert seen == list(range(1, 7))

    def stop(done: int) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        screen(
            prim,
            secs,
            MODEL,
            start=epoch,
            end=add_seconds(epoch, 3600.0),
            distance=5e3,
            execution=rp.Execution(progress=stop),
        )


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_screen_stops_on_ctrl_c():
    # ~20 s of screening (20,000 secondaries x 3 days); SIGINT after it started must end
    # it with KeyboardInterrupt (measured: the process exits 0.3 s after the signal).
    code = textwrap.dedent(
        """
        import numpy as np, rhoprop as rp
        from rhoprop.conjunction import screen
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
        secs = [(circ(rng.uniform(395e3, 405e3), rng.uniform(40, 100), rng.uniform(0, 360),
                      rng.uniform(0, 360)), craft) for _ in range(20000)]
        print("started", flush=True)
        screen((circ(400e3, 51.6, 0, 0), craft), secs, rp.density.Exponential.benchmark(),
               start=epoch, end=epoch + np.timedelta64(3, "D"), distance=5e3, progress=False)
        print("finished", flush=True)
        """
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "started"
    time.sleep(2.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    # Stopped, not finished (the screen would print "finished" some 15 s later).
    assert "finished" not in out
    assert "KeyboardInterrupt" in err


# ---------------------------------------------------------------------------------------
# Real catalog snapshot


@pytest.fixture(scope="module")
def snapshot(test_data: Path, tmp_path_factory: pytest.TempPathFactory) -> catalog.Catalog:
    src = test_data / "catalogs" / "celestrak_active_20231113.txt.gz"
    path = tmp_path_factory.mktemp("screening") / "active.tle"
    path.write_text(gzip.open(src, "rt").read())
    return catalog.load(path, errors="record", nonpositive_bstar="error")  # B* > 0 only


def _osculating(state: rp.OrbitState) -> tuple[float, float, float]:
    r, v = state.position, state.velocity
    rn = np.linalg.norm(r)
    a = 1.0 / (2.0 / rn - v @ v / MU)
    h = np.cross(r, v)
    e = np.linalg.norm(np.cross(v, h) / MU - r / rn)
    return a * (1 - e), a * (1 + e), float(h @ h / MU)


def test_radial_pads_cover_propagated_radii(snapshot):
    # The zonal pad (4 J2 Re^2/p, J2 only) covers the radii the objects really reach over
    # 3 days without drag, for a seeded sample of the real catalog.
    rng = np.random.default_rng(7)
    for i in rng.choice(len(snapshot), 60, replace=False):
        obj = snapshot[int(i)]
        perigee, apogee, p = _osculating(obj.state)
        tr = rp.propagate(obj.state, rp.Spacecraft(1.0, 1e-9), MODEL, 3 * 86400.0, output_step=20.0)
        radii = np.linalg.norm(tr.positions, axis=1)
        pad = 4.0 * J2 * R_EARTH**2 / p
        assert perigee - pad < radii.min() and radii.max() < apogee + pad, obj.name


def _brute_force_screen(prim, objs, start, end, distance):
    """Every (primary, secondary) pair on a 1-s grid with no prefilter: each object by
    DOP853 at rtol 1e-12 from its epoch to `start`, then 1-s outputs; local minima of the
    distance within `distance` + 10 km; TCA from the root of a cubic fitted to
    r_rel . v_rel at the 4 samples around it, miss distance from quintics fitted to the
    relative position at the 6 samples around it (exact to ~1 us and ~1 mm)."""
    span = seconds_between(start, end)

    def track(obj):
        craft = rp.Spacecraft(1.0, obj.drag_parameter)
        lead = seconds_between(obj.state.epoch, start)
        s0 = rp.propagate(
            obj.state,
            craft,
            MODEL,
            lead,
            dynamics=rp.Dynamics(rtol=1e-12),
        ).state_at(-1)
        return rp.propagate(
            s0,
            craft,
            MODEL,
            span,
            output_step=1.0,
            dynamics=rp.Dynamics(rtol=1e-12),
        )

    p = track(prim)
    found = []
    for obj in objs:
        tr = track(obj)
        n = min(len(tr.times), len(p.times))
        r = tr.positions[:n] - p.positions[:n]
        f = np.einsum("ij,ij->i", r, tr.velocities[:n] - p.velocities[:n])
        d = np.linalg.norm(r, axis=1)
        k = np.flatnonzero((f[:-1] < 0) & (f[1:] >= 0))
        for j in k[(k >= 3) & (k < n - 4)]:
            if min(d[j], d[j + 1]) > distance + 10e3:
                continue
            x = np.arange(-1.0, 3.0)
            roots = np.roots(np.polyfit(x, f[j - 1 : j + 3], 3))
            x0 = min(z.real for z in roots if abs(z.imag) < 1e-9 and 0 <= z.real <= 1)
            xs = np.arange(-2.0, 4.0)
            rel = [np.polyval(np.polyfit(xs, r[j - 2 : j + 4, c], 5), x0) for c in range(3)]
            found.append((obj.norad_id, add_seconds(p.epochs[j], x0), float(np.linalg.norm(rel))))
    return found


def test_screen_real_snapshot_equals_brute_force_all_pairs(snapshot):
    # Subset: the 120 objects with epochs in the last day whose osculating ranges come
    # nearest the primary's, plus 80 seeded random others; 6 hours; 30 km.
    prim = next(o for o in snapshot if o.norad_id == 25544)  # ISS (ZARYA)
    start = max(o.state.epoch for o in snapshot)
    end = add_seconds(start, 6 * 3600.0)
    recent = [
        o
        for o in snapshot
        if o.norad_id != 25544 and seconds_between(o.state.epoch, start) < 86400.0
    ]
    lo, hi, _ = _osculating(prim.state)
    gap = [max(_osculating(o.state)[0] - hi, lo - _osculating(o.state)[1], 0.0) for o in recent]
    order = np.argsort(gap, kind="stable")
    rng = np.random.default_rng(3)
    rest = rng.choice(order[120:], 80, replace=False)
    objs = [recent[int(i)] for i in (*order[:120], *rest)]
    distance = 30e3
    res = screen(
        prim,
        objs,
        MODEL,
        start=start,
        end=end,
        distance=distance,
        execution=rp.Execution(progress=False),
    )
    brute = _brute_force_screen(prim, objs, start, end, distance)
    assert res.counts["radial"] < len(objs)  # the prefilters do drop objects
    within = [b for b in brute if b[2] <= distance]
    assert len(within) >= 5  # the subset holds real approaches

    # Same events: every brute-force approach within the distance found (TCA within 1 ms,
    # miss within 1 m) and nothing else. For slow approaches (docked vehicles drifting
    # apart at 2 m/s) TCA is ill-conditioned: a 1 cm difference of the propagations
    # (rtol 1e-10 in the screen, 1e-12 here) moves it by 1 cm / v_rel, so there the
    # tolerance is 5 cm of relative motion.
    def close(e, tca):
        tol = max(1e-3, 0.05 / e.relative_speed)
        return abs((e.tca - tca) / np.timedelta64(1, "ns")) * 1e-9 < tol

    for norad, tca, miss in within:
        match = [e for e in res.events if e.id2 == norad and close(e, tca)]
        assert len(match) == 1, (norad, tca, miss)
        assert abs(match[0].miss_distance - miss) < 1.0
    fast = 0
    for e in res.events:
        near = [b for b in brute if b[0] == e.id2 and close(e, b[1])]
        assert len(near) == 1 and abs(near[0][2] - e.miss_distance) < 1.0
        fast += e.relative_speed > 100.0
    assert fast >= 2  # approaches checked at the 1 ms level
    assert res.counts["events"] == len({e.id2 for e in res.events})


def test_screen_real_snapshot_counts_are_consistent(snapshot):
    prim = next(o for o in snapshot if o.norad_id == 25544)
    start = max(o.state.epoch for o in snapshot)
    # A Catalog, the primary itself among its objects.
    subset = catalog.Catalog([*[o for o in snapshot if o.norad_id != 25544][:1500], prim])
    res = screen(
        prim,
        subset,
        MODEL,
        start=start,
        end=add_seconds(start, 3 * 3600.0),
        distance=10e3,
        execution=rp.Execution(progress=False),
    )
    assert res.skipped == [(prim.name, "the primary itself")]
    counts = [res.counts[s] for s in STAGES]
    assert counts[0] == 1500 and counts == sorted(counts, reverse=True)
    assert all(e.miss_distance <= 10e3 for e in res.events)
    assert [e.tca for e in res.events] == sorted(e.tca for e in res.events)
