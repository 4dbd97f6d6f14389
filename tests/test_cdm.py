"""CCSDS conjunction data messages (rp.conjunction.cdm) and the Pc with density-model
uncertainty added (rp.conjunction.with_density).

References: NASA CARA's 2-D Pc test cases (../shared/data/conjunction, written here as
KVN CDMs by a plain template, not by our writer), analytic equinoctial elements, and
forward propagation of the shooting solution.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.conjunction import cdm
from rhoprop.conjunction.with_density import cartesian, density_pc, equinoctial, state_before

pytest.importorskip("ccsds_ndm")

_COV_ORDER = [
    "CR_R",
    "CT_R",
    "CT_T",
    "CN_R",
    "CN_T",
    "CN_N",
    "CRDOT_R",
    "CRDOT_T",
    "CRDOT_N",
    "CRDOT_RDOT",
    "CTDOT_R",
    "CTDOT_T",
    "CTDOT_N",
    "CTDOT_RDOT",
    "CTDOT_TDOT",
    "CNDOT_R",
    "CNDOT_T",
    "CNDOT_N",
    "CNDOT_RDOT",
    "CNDOT_TDOT",
    "CNDOT_NDOT",
]


def _kvn(case: dict, hbr_comment: bool = True, frame: str = "EME2000") -> str:
    """A KVN CDM of a CARA case, by template (units as the standard writes them)."""
    lines = [
        "CCSDS_CDM_VERS = 1.0",
        "CREATION_DATE = 2025-01-01T00:00:00.000",
        "ORIGINATOR = TEST",
        "MESSAGE_ID = CARA_CASE",
    ]
    if hbr_comment:
        lines.append(f"COMMENT HBR = {case['hbr_m']}")
    lines += [
        "TCA = 2025-01-02T00:00:00.000",
        "MISS_DISTANCE = 1.0 [m]",
        "RELATIVE_SPEED = 1.0 [m/s]",
        "COLLISION_PROBABILITY = 0.1",
        "COLLISION_PROBABILITY_METHOD = FOSTER-1992",
    ]
    for k in (1, 2):
        cov = np.asarray(case[f"cov{k}"])
        lines += [
            f"OBJECT = OBJECT{k}",
            f"OBJECT_DESIGNATOR = {10000 + k}",
            "CATALOG_NAME = SATCAT",
            f"OBJECT_NAME = OBJ{k}",
            "INTERNATIONAL_DESIGNATOR = 2000-001A",
            "EPHEMERIS_NAME = NONE",
            "COVARIANCE_METHOD = CALCULATED",
            "MANEUVERABLE = NO",
            f"REF_FRAME = {frame}",
        ]
        for name, x in zip(("X", "Y", "Z"), case[f"r{k}"], strict=True):
            lines.append(f"{name} = {x / 1e3!r} [km]")
        for name, x in zip(("X_DOT", "Y_DOT", "Z_DOT"), case[f"v{k}"], strict=True):
            lines.append(f"{name} = {x / 1e3!r} [km/s]")
        idx = [(i, j) for i in range(6) for j in range(i + 1)]
        for name, (i, j) in zip(_COV_ORDER, idx, strict=True):
            unit = ["m**2", "m**2/s", "m**2/s**2"][(i >= 3) + (j >= 3)]
            lines.append(f"{name} = {float(cov[i, j])!r} [{unit}]")
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def cara_rtn_cases(test_data):
    cases = json.loads((test_data / "conjunction" / "cara_2d_pc_cases.json").read_text())
    return [c for c in cases["cases"] if c["cov1_frame"].startswith("RTN")]


def test_cara_cases_read_from_kvn_give_the_cara_pc(cara_rtn_cases):
    assert len(cara_rtn_cases) >= 6
    for case in cara_rtn_cases:
        msg = cdm.read_cdm(_kvn(case))
        np.testing.assert_allclose(msg.object1.position, case["r1"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(msg.object2.velocity, case["v2"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(msg.object2.covariance, case["cov2"], rtol=1e-15)
        assert msg.hard_body_radius == case["hbr_m"]
        pc = float(getattr(msg.pc(), "pc", msg.pc()))
        tol = case["tolerance"]
        if tol["type"] == "rel":
            assert pc == pytest.approx(case["expected_pc"], rel=tol["value"]), case["name"]
        else:
            assert abs(pc - case["expected_pc"]) <= tol["value"], case["name"]


@pytest.mark.parametrize("fmt", ["kvn", "xml"])
def test_written_messages_read_back_the_same(cara_rtn_cases, tmp_path, fmt):
    msg = cdm.read_cdm(_kvn(cara_rtn_cases[0]))
    msg = dataclasses.replace(
        msg,
        object1=dataclasses.replace(msg.object1, drag_parameter=0.012),
    )
    path = cdm.write_cdm(msg, tmp_path / f"event.{fmt}")
    back = cdm.read_cdm(path)
    assert back.tca == msg.tca and back.creation_date == msg.creation_date
    assert back.hard_body_radius == msg.hard_body_radius
    assert back.object1.drag_parameter == pytest.approx(0.012)
    assert back.object2.drag_parameter is None
    for a, b in ((back.object1, msg.object1), (back.object2, msg.object2)):
        np.testing.assert_allclose(a.position, b.position, rtol=1e-15, atol=1e-6)
        np.testing.assert_allclose(a.velocity, b.velocity, rtol=1e-15, atol=1e-9)
        np.testing.assert_allclose(a.covariance, b.covariance, rtol=1e-15)
    assert back.lead_time == pytest.approx(86400.0)


def test_relative_state_is_object2_in_object1_rtn(cara_rtn_cases):
    msg = cdm.read_cdm(_kvn(cara_rtn_cases[0]))
    rel = cdm.relative_rtn(msg)
    dr = msg.object2.position - msg.object1.position
    assert np.linalg.norm(rel[:3]) == pytest.approx(np.linalg.norm(dr), rel=1e-12)
    radial = msg.object1.position / np.linalg.norm(msg.object1.position)
    assert rel[0] == pytest.approx(dr @ radial, rel=1e-12)


def test_bad_messages_are_refused_clearly(cara_rtn_cases, tmp_path):
    case = cara_rtn_cases[0]
    with pytest.raises(ValueError, match="REF_FRAME 'ITRF'"):
        cdm.read_cdm(_kvn(case, frame="ITRF"))
    no_hbr = cdm.read_cdm(_kvn(case, hbr_comment=False))
    assert no_hbr.hard_body_radius is None
    with pytest.raises(ValueError, match="hard_body_radius"):
        no_hbr.pc()
    assert float(getattr(no_hbr.pc(15.0), "pc", 0.0)) > 0
    with pytest.raises(ValueError, match="does not exist"):
        cdm.read_cdm(tmp_path / "missing.cdm")
    with pytest.raises(ValueError, match=r"not a CDM|cannot parse"):
        cdm.read_cdm("CCSDS_OPM_VERS = 2.0\nCREATION_DATE = 2020-01-01T00:00:00\n")
    with pytest.raises(ValueError, match="format"):
        cdm.cdm_text(no_hbr, "json")


def test_equinoctial_elements_match_their_definition():
    # Circular, inclined 51.6 deg, node 40 deg, at argument of latitude 30 deg.
    a, inc, node, u = 6.8e6, np.radians(51.6), np.radians(40.0), np.radians(30.0)
    speed = np.sqrt(rp.constants.MU / a)
    p_hat = np.array([np.cos(node), np.sin(node), 0.0])
    q_hat = np.array(
        [-np.sin(node) * np.cos(inc), np.cos(node) * np.cos(inc), np.sin(inc)],
    )
    x = np.concatenate(
        [
            a * (np.cos(u) * p_hat + np.sin(u) * q_hat),
            speed * (-np.sin(u) * p_hat + np.cos(u) * q_hat),
        ]
    )
    e = equinoctial(x)
    expected = [
        a,
        0.0,
        0.0,
        np.tan(inc / 2) * np.sin(node),
        np.tan(inc / 2) * np.cos(node),
        node + u,
    ]
    np.testing.assert_allclose(e, expected, rtol=1e-12, atol=1e-12)
    rng = np.random.default_rng(7)
    for _ in range(20):
        r = rng.normal(size=3)
        r *= rng.uniform(6.6e6, 4.2e7) / np.linalg.norm(r)
        v = np.cross(rng.normal(size=3), r)
        v *= (
            np.sqrt(rp.constants.MU / np.linalg.norm(r)) * rng.uniform(0.8, 1.2) / np.linalg.norm(v)
        )
        y = np.concatenate([r, v])
        np.testing.assert_allclose(cartesian(equinoctial(y)), y, rtol=0, atol=1e-6)


def _leo_message(miss: float = 50.0, hbr: float = 20.0) -> cdm.ConjunctionMessage:
    """Two 400-km objects crossing at 90 degrees, ``miss`` m apart cross-track."""
    tca = np.datetime64("2024-05-12T12:00:00", "ns")
    r = 6778e3
    speed = np.sqrt(rp.constants.MU / r)
    p1, v1 = np.array([r, 0.0, 0.0]), np.array([0.0, speed, 0.0])
    p2, v2 = np.array([r, 0.0, miss]), np.array([0.0, 0.0, speed])
    cov = np.diag([30.0**2, 200.0**2, 30.0**2, 0.2**2, 0.03**2, 0.03**2])
    return cdm.ConjunctionMessage(
        tca=tca,
        object1=cdm.CdmObject("A", "1", p1, v1, cov, drag_parameter=0.01),
        object2=cdm.CdmObject("B", "2", p2, v2, cov, drag_parameter=0.02),
        creation_date=tca - np.timedelta64(1, "D"),
        miss_distance=miss,
        relative_speed=float(np.linalg.norm(v2 - v1)),
        hard_body_radius=hbr,
    )


def test_shooting_finds_the_state_that_reaches_tca():
    msg = _leo_message()
    model = rp.density.Exponential.benchmark()
    target = rp.OrbitState(msg.tca, msg.object1.position, msg.object1.velocity)
    craft = rp.Spacecraft(2.2, 0.01 / 2.2)
    for lead in (3600.0, 2 * 86400.0):
        start = state_before(target, craft, model, lead)
        assert start.epoch == msg.tca - np.timedelta64(int(lead), "s")
        end = rp.propagate(
            start,
            craft,
            model,
            lead,
            dynamics=rp.Dynamics(integrator="dop853", rtol=1e-12),
        )
        # The shooting used RK8 at 180 s; DOP853 at 1e-12 is the independent check.
        assert np.linalg.norm(end.positions[-1] - target.position) < 0.5


def test_density_pc_without_density_uncertainty_is_the_message_pc():
    msg = _leo_message()
    model = rp.density.Exponential.benchmark(rel_sigma=0.0)
    out = density_pc(
        msg,
        {"exp": model},
        "exp",
        method=rp.Ccsp(),
    )
    assert out.pc_message == pytest.approx(float(getattr(msg.pc(), "pc", msg.pc())), rel=1e-12)
    # Only the CCSP's near-zero initial covariance (1 mm, 1 um/s) grows over the day.
    assert out.pc == pytest.approx(out.pc_message, rel=1e-4)
    assert np.abs(out.offsets1).max() < 1.0


def test_density_pc_mixes_models_with_shared_atmosphere():
    msg = _leo_message(miss=30.0)
    models = {
        "low": rp.density.Exponential.benchmark(rel_sigma=0.1),
        "high": rp.density.Exponential(1.5 * 3.725e-12, 400e3, 58.515e3, rel_sigma=0.3),
    }
    out = density_pc(
        msg,
        models,
        "low",
        method=rp.Ccsp(),
        debias=rp.Debias(cds={"high": 2.2}),
    )
    assert out.names == ["low", "high"]
    assert out.pc == pytest.approx(out.weights @ out.pc_models, rel=1e-12)
    # More drag in "high" (Cd not debiased here): the orbit sinks and speeds up, so the
    # objects arrive ahead of the message's states along-track.
    t1 = msg.object1.velocity / np.linalg.norm(msg.object1.velocity)
    assert out.offsets1[1] @ t1 > 100.0
    assert abs(out.offsets1[0] @ t1) < 0.05 * abs(out.offsets1[1] @ t1)
    # Density spread adds to the message's along-track variance.
    var_msg = t1 @ msg.object1.covariance[:3, :3] @ t1  # RTN T axis = velocity here
    assert t1 @ out.covariances1[1] @ t1 > var_msg
    # Each model's Pc is the Gaussian Pc of its own offsets and covariances.
    again = rp.conjunction.pc_2d(
        msg.object1.position + out.offsets1[1],
        msg.object1.velocity,
        out.covariances1[1],
        msg.object2.position + out.offsets2[1],
        msg.object2.velocity,
        out.covariances2[1],
        20.0,
    )
    assert float(getattr(again, "pc", again)) == pytest.approx(out.pc_models[1], rel=1e-12)
    # Each model's maximum Pc and dilution flag are its own Gaussian's.
    top = again.maximum()
    assert out.pc_max_models[1] == top.pc_max and out.dilution_models[1] == top.dilution
    assert (out.pc_max_models >= out.pc_models).all() and out.pc_max_message >= out.pc_message
    assert "| Pc max | dilution |" in out.table()
    assert "mixture" in out.table()


def test_density_pc_refuses_what_it_cannot_do():
    msg = _leo_message()
    model = rp.density.Exponential.benchmark(rel_sigma=0.1)
    no_beta = dataclasses.replace(
        msg, object2=dataclasses.replace(msg.object2, drag_parameter=None)
    )
    with pytest.raises(ValueError, match="CD_AREA_OVER_MASS"):
        density_pc(no_beta, {"m": model}, "m")
    with pytest.raises(ValueError, match="lead_time"):
        density_pc(msg, {"m": model}, "m", lead_time=10.0)


def test_rhoprop_conjunction_reads_the_example_cdm(tmp_path, capsys):
    from pathlib import Path

    from rhoprop.cli import main

    example = Path(__file__).parents[1] / "examples" / "conjunction.cdm"
    out = tmp_path / "pc.json"
    assert main(["conjunction", str(example), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "mixture (density-model uncertainty)" in printed
    figures = json.loads(out.read_text())
    msg = cdm.read_cdm(example)
    # The message's own Pc is recomputed as written; the mixture is the weighted mean.
    assert figures["pc_message"] == pytest.approx(msg.collision_probability, rel=1e-9)
    pcs, weights = figures["pc_models"], figures["weights"]
    mixed = sum(weights[name] * pc for name, pc in pcs.items())
    assert figures["pc_mixture"] == pytest.approx(mixed, rel=1e-12)
    # Each model's maximum Pc is at least its Pc; the table says where it is diluted.
    assert all(figures["pc_max_models"][name] >= pc for name, pc in pcs.items())
    assert "| Pc max | dilution |" in printed
    assert figures["lead_time_s"] == 2 * 86400.0 and figures["hard_body_radius_m"] == 15.0


def test_a_name_cannot_forge_a_line(cara_rtn_cases, tmp_path):
    # A name carrying a newline and a KVN keyword stays one sanitised value: the
    # written message has exactly one COLLISION_PROBABILITY line, or none.
    msg = cdm.read_cdm(_kvn(cara_rtn_cases[0]))
    evil = "EVIL\nCOLLISION_PROBABILITY = 0.99"
    msg = dataclasses.replace(
        msg, object1=dataclasses.replace(msg.object1, name=evil), message_id="ID\nX = 1"
    )
    text = cdm.write_cdm(msg, tmp_path / "event.kvn").read_text()
    lines = [ln.strip() for ln in text.splitlines()]
    assert not any(ln.startswith("COLLISION_PROBABILITY = 0.99") for ln in lines)
    assert not any(ln.startswith("X = 1") for ln in lines)
    assert cdm.read_cdm(tmp_path / "event.kvn").object1.name == "EVIL_COLLISION_PROBABILITY = 0.99"
