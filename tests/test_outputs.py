"""Nothing lost or silently mixed in outputs: output folders with a
manifest that refuse (or, asked to, clear) an earlier run's files, files written to a
temporary name and renamed, text from inputs sanitised, scenario output folders inside
the scenario's folder, and ``rp.io.write_oem`` for single results."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from sgp4 import exporter
from sgp4.api import Satrec

import rhoprop as rp
from rhoprop import catalog, io
from rhoprop.cli import main
from rhoprop.io import MANIFEST, OutputFolder, atomic_path, sanitise
from rhoprop.studies.scenario_file import ScenarioError, load_scenario

SAMPLE = Path(__file__).parent / "data" / "sample.tle"
END = "2002-09-07T06:00:00"


def test_output_folder_claims_lists_and_refuses(tmp_path):
    out = tmp_path / "run"
    folder = OutputFolder(out, command="rhoprop test")
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["complete"] is False and manifest["files"] == []
    folder.write_text("a.txt", "A")
    with folder.path("sub/b.bin") as tmp:
        assert tmp.parent == out / "sub" and tmp.name != "b.bin"
        tmp.write_bytes(b"B")
        assert not (out / "sub" / "b.bin").exists()  # only the rename makes it appear
    folder.finish()
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["complete"] and manifest["files"] == ["a.txt", "sub/b.bin"]
    assert manifest["rhoprop_version"] == rp.__version__ and manifest["command"] == "rhoprop test"
    assert sorted(p.name for p in out.rglob("*")) == ["a.txt", "b.bin", MANIFEST, "sub"]
    # Another run into the same folder: refused, or cleared with overwrite=True.
    with pytest.raises(FileExistsError, match="holds the files of an earlier run"):
        OutputFolder(out, command="again")
    OutputFolder(out, command="again", overwrite=True)
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST]
    # That run stopped before writing anything (e.g. bad input): the folder is reusable.
    OutputFolder(out, command="third")
    # A folder of files rhoprop did not write is never cleared.
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    with pytest.raises(FileExistsError, match=r"holds no manifest\.json"):
        OutputFolder(mine, command="x", overwrite=True)
    assert (mine / "thesis.tex").read_text() == "precious"


def _tree(folder: Path) -> dict[str, bytes]:
    return {
        p.relative_to(folder).as_posix(): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and not p.is_symlink()
    }


def test_overwrite_never_deletes_a_file_the_run_did_not_write(tmp_path):
    """--overwrite once deleted a user file added to an earlier run's folder
    and an index.html beside another tool's manifest.json. Now such a folder is refused
    and nothing is deleted."""
    out = tmp_path / "run"
    folder = OutputFolder(out, command="rhoprop test")
    folder.write_text("oem/1.oem", "A")
    folder.finish()
    (out / "notes.txt").write_text("mine")
    (out / "oem" / "plot.py").write_text("mine too")
    before = _tree(out)
    lists = r"no rhoprop manifest of it lists \(notes\.txt, oem/plot"
    with pytest.raises(FileExistsError, match=lists):
        OutputFolder(out, command="again", overwrite=True)
    assert _tree(out) == before
    # Another tool's manifest.json: not rhoprop's, nothing deleted.
    other = tmp_path / "site"
    other.mkdir()
    (other / MANIFEST).write_text(json.dumps({"name": "my app", "files": ["index.html"]}))
    (other / "index.html").write_text("<html>")
    with pytest.raises(FileExistsError, match=r"holds no manifest\.json of an earlier rhoprop"):
        OutputFolder(other, command="x", overwrite=True)
    assert (other / "index.html").exists()


def test_overwrite_deletes_an_interrupted_runs_files_and_nothing_outside(tmp_path):
    out = tmp_path / "run"
    folder = OutputFolder(out, command="rhoprop test")
    folder.expect([out / "oem" / "1.oem", out / "oem" / "2.oem"])
    (out / "oem").mkdir()
    (out / "oem" / "1.oem").write_text("written before the stop")
    (out / "oem" / ".2.tmp123-7f00.oem").write_text("half written")
    # (the run stops here: no finish, the manifest lists no files, the journal does)
    with pytest.raises(FileExistsError, match="earlier run"):
        OutputFolder(out, command="again")
    OutputFolder(out, command="again", overwrite=True)
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST]
    # A forged manifest naming files outside the folder or through a link: never followed.
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "keep.txt").write_text("keep")
    (out / "linked").symlink_to(outside, target_is_directory=True)
    forged = {"rhoprop_version": "0", "files": ["../outside/keep.txt", "linked/keep.txt"]}
    (out / MANIFEST).write_text(json.dumps(forged))
    with pytest.raises(FileExistsError, match="no rhoprop manifest of it lists \\(linked\\)"):
        OutputFolder(out, command="x", overwrite=True)
    assert (outside / "keep.txt").read_text() == "keep"


def test_a_failed_write_leaves_no_file(tmp_path):
    target = tmp_path / "x.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("writer died")
    assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["x.txt"]


def test_sanitise():
    assert sanitise("EVIL\nMETA_STOP\r\nX\x00Y\tZ é") == "EVIL_META_STOP__X_Y_Z _"
    assert sanitise("  fine name  ") == "fine name" and len(sanitise("a" * 500)) == 100


def test_object_names_cannot_inject_lines_into_an_oem(tmp_path):
    from oem import OrbitEphemerisMessage

    l1, l2 = SAMPLE.read_text().splitlines()[1:3]
    record = exporter.export_omm(Satrec.twoline2rv(l1, l2), "SAT")
    record["OBJECT_NAME"] = "EVIL\nMETA_STOP\nREF_FRAME = ITRF"
    path = tmp_path / "evil.json"
    path.write_text(json.dumps([record]))
    cat = catalog.load(path)
    r = catalog.propagate_catalog(
        cat,
        rp.scenarios.benchmark_exponential(0.2),
        END,
        output_step=1800.0,
        execution=rp.Execution(progress=False),
    )
    (oem_path,) = io.write_oem(r, tmp_path / "oem")
    text = oem_path.read_text()
    assert "OBJECT_NAME = EVIL_META_STOP_REF_FRAME = ITRF\n" in text
    assert text.count("META_STOP") == 2 and text.count("\nREF_FRAME = TEME") == 1
    oem = OrbitEphemerisMessage.open(str(oem_path))
    assert len(list(oem.segments[0].states)) == len(r.epochs)


def test_a_catalog_oem_in_gcrf_is_rotated_from_teme(tmp_path):
    # REF_FRAME = GCRF named the TEME states as GCRF (about 40 km off in LEO). Now the
    # states and covariances are rotated by the element set's epoch's TEME -> GCRF.
    from oem import OrbitEphemerisMessage

    cat = catalog.load(SAMPLE)
    r = catalog.propagate_catalog(
        cat[:2],
        rp.scenarios.benchmark_exponential(0.2),
        END,
        output_step=1800.0,
        execution=rp.Execution(progress=False),
    )
    teme = io.write_oem(r, tmp_path / "teme")
    gcrf = io.write_oem(r, tmp_path / "gcrf", ref_frame="GCRF")
    for k, (a, b) in enumerate(zip(teme, gcrf, strict=True)):
        assert "REF_FRAME = GCRF" in b.read_text() and "rotated from TEME" in b.read_text()
        sa = list(OrbitEphemerisMessage.open(str(a)).segments[0].states)
        sb = list(OrbitEphemerisMessage.open(str(b)).segments[0].states)
        m = rp.frames.teme_to_gcrf_matrix(r.objects[k].state.epoch)
        for x, y in zip(sa, sb, strict=True):
            np.testing.assert_allclose(
                np.asarray(y.position), m @ np.asarray(x.position), atol=1e-6
            )
            np.testing.assert_allclose(
                np.asarray(y.velocity), m @ np.asarray(x.velocity), atol=1e-9
            )
        # The same physical states as astropy's TEME -> GCRS of the TEME of the element
        # set's epoch (the axes the run integrated in; TEME of each output's date would
        # differ by the nutation of the hours between, ~1 m here), to 1 m.
        epoch = r.objects[k].state.epoch
        for x, y in zip(sa, sb, strict=True):
            ref = _astropy_gcrs(epoch, 1e3 * np.asarray(x.position))
            assert np.linalg.norm(1e3 * np.asarray(y.position) - ref) < 1.0
        cov_a = next(iter(OrbitEphemerisMessage.open(str(a)).segments[0].covariances)).matrix
        cov_b = next(iter(OrbitEphemerisMessage.open(str(b)).segments[0].covariances)).matrix
        # A rotation keeps the trace of the position block.
        assert np.trace(cov_b[:3, :3]) == pytest.approx(np.trace(cov_a[:3, :3]), rel=1e-9)


def _astropy_gcrs(epoch, teme, inverse=False):
    """astropy's TEME -> GCRS (or back) of a position (3,), m: the independent reference."""
    from astropy import units as u
    from astropy.coordinates import GCRS, TEME, CartesianRepresentation
    from astropy.time import Time
    from astropy.utils import iers

    with iers.conf.set_temp("auto_download", False):
        t = epoch if isinstance(epoch, Time) else Time(np.datetime64(epoch, "ns"), scale="utc")
        source, target = (GCRS, TEME) if inverse else (TEME, GCRS)
        out = source(CartesianRepresentation(np.asarray(teme) * u.m), obstime=t).transform_to(
            target(obstime=t)
        )
    return out.cartesian.xyz.to(u.m).value


def test_a_single_result_oem_is_in_its_frame_or_converted(tmp_path):
    # A result is in its initial state's frame and its OEM says so; ref_frame="TEME"
    # rotates it, to astropy's GCRS -> TEME within 1 m (read back with the oem library).
    from oem import OrbitEphemerisMessage

    state = rp.OrbitState("2026-03-15T06:30Z", [6778e3, 1200e3, -300e3], [-1200.0, 7000.0, 1500.0])
    craft = rp.Spacecraft(2.2, 0.01)
    tr = rp.propagate(
        state, craft, rp.scenarios.benchmark_exponential(0.2), 7200.0, output_step=1800.0
    )
    assert tr.frame == "GCRF" and tr.state_at(0).frame == "GCRF"
    np.testing.assert_allclose(tr.positions[0], state.position, atol=1e-6)  # rotated twice
    (own,) = io.write_oem(tr, tmp_path / "own")
    (teme,) = io.write_oem(tr, tmp_path / "teme", ref_frame="TEME")
    assert "REF_FRAME = GCRF" in own.read_text() and "REF_FRAME = TEME" in teme.read_text()
    back = list(OrbitEphemerisMessage.open(str(teme)).segments[0].states)
    assert len(back) == len(tr.times)
    for k, x in enumerate(back):  # TEME of the initial epoch, the run's axes
        ref = _astropy_gcrs(tr.epoch, tr.positions[k], inverse=True)
        assert np.linalg.norm(1e3 * np.asarray(x.position) - ref) < 1.0
    # Relabelling between GCRF, EME2000 and ICRF moves nothing.
    (eme,) = io.write_oem(tr, tmp_path / "eme", ref_frame="EME2000")
    first = next(iter(OrbitEphemerisMessage.open(str(eme)).segments[0].states))
    np.testing.assert_allclose(1e3 * np.asarray(first.position), state.position, atol=1e-3)


def test_non_utf8_bytes_are_skipped_or_named(tmp_path):
    # A stray byte in one name: "raise" names the line; "skip" still loads everything.
    path = tmp_path / "latin1.tle"
    path.write_bytes(SAMPLE.read_bytes().replace(b"SYNTH-2", b"SYNTH-\xe9"))
    with pytest.raises(ValueError, match=r"latin1.tle line 4: byte 0xe9 is not UTF-8"):
        catalog.load(path)
    cat = catalog.load(path, errors="record")
    assert len(cat) == 6 and cat[1].name == "SYNTH-\ufffd"


@pytest.fixture(scope="module")
def single():
    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    model = rp.scenarios.benchmark_exponential(0.2)
    return {
        "ccsp": rp.ccsp(state, craft, model, 7200.0),
        "mc": rp.monte_carlo(state, craft, model, 7200.0, n=20, progress=False),
        "trajectory": rp.propagate(state, craft, model, 7200.0, output_step=3600.0),
    }


@pytest.mark.parametrize("kind", ["ccsp", "mc", "trajectory"])
def test_write_oem_takes_a_single_result(tmp_path, single, kind):
    from oem import OrbitEphemerisMessage

    result = single[kind]
    (path,) = io.write_oem(result, tmp_path, object_name="PAPER\nSAT", object_id="2002-001A")
    assert path.name == "2002-001A.oem"
    text = path.read_text()
    assert "OBJECT_NAME = PAPER_SAT\n" in text and "REF_FRAME = GCRF" in text  # its own
    segment = OrbitEphemerisMessage.open(str(path)).segments[0]
    m = result.moments()
    states = np.array([s.vector for s in segment.states]) * 1e3
    np.testing.assert_allclose(states, m.mean, rtol=1e-8)
    if kind == "trajectory":
        assert "COVARIANCE_START" not in text
    else:
        cov = np.array([c.matrix for c in segment.covariances]) * 1e6
        np.testing.assert_allclose(cov, m.covariance, rtol=1e-8, atol=1e-12)


def test_write_oem_rtn_covariance_and_xml(tmp_path, single):
    from oem import OrbitEphemerisMessage

    result = single["ccsp"]
    m = result.moments()
    (path,) = io.write_oem(result, tmp_path / "rtn", ref_frame="GCRF", covariance_frame="rtn")
    text = path.read_text()
    assert "REF_FRAME = GCRF" in text and "COV_REF_FRAME = RTN" in text
    covs = list(OrbitEphemerisMessage.open(str(path)).segments[0].covariances)
    assert {c.frame for c in covs} == {"RTN"}
    # Independent rotation: the position block against the result's own RTN covariance.
    got = np.array([c.matrix for c in covs]) * 1e6
    np.testing.assert_allclose(got[:, :3, :3], m.rtn_covariance, rtol=1e-8, atol=1e-9)
    # The velocity block rotates with the same basis (rows R, T, N of each mean state).
    basis = rp.frames.rtn_basis(m.mean[:, :3], m.mean[:, 3:])
    expect = np.einsum("nij,njk,nlk->nil", basis, m.covariance[:, 3:, 3:], basis)
    np.testing.assert_allclose(got[:, 3:, 3:], expect, rtol=1e-8, atol=1e-15)
    # XML through the library reads back the same states and inertial covariances.
    (xml,) = io.write_oem(result, tmp_path / "xml", file_format="xml")
    assert xml.suffix == ".xml" and xml.read_text().lstrip().startswith("<?xml")
    segment = OrbitEphemerisMessage.open(str(xml)).segments[0]
    states = np.array([s.vector for s in segment.states]) * 1e3
    np.testing.assert_allclose(states, m.mean, rtol=1e-8)
    cov = np.array([c.matrix for c in segment.covariances]) * 1e6
    np.testing.assert_allclose(cov, m.covariance, rtol=1e-8, atol=1e-12)


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"ref_frame": "ITRF"}, "ref_frame must be one of"),
        ({"covariance_frame": "ric"}, "covariance_frame must be one of"),
        ({"file_format": "json"}, "file_format must be"),
        ({"file_format": "xml", "covariance_frame": "rtn"}, "XML writer drops COV_REF_FRAME"),
    ],
)
def test_write_oem_refuses_what_it_cannot_write(tmp_path, single, options, match):
    with pytest.raises(ValueError, match=match):
        io.write_oem(single["ccsp"], tmp_path, **options)
    assert not list(tmp_path.iterdir())


def test_write_oem_says_what_it_takes(tmp_path):
    with pytest.raises(TypeError, match=r"write_oem takes a CatalogResult .* not a list"):
        io.write_oem([1, 2], tmp_path)


def test_scenario_output_stays_in_the_scenario_folder(tmp_path):
    from test_ensemble import GOOD

    folder = tmp_path / "study"
    folder.mkdir()
    path = folder / "s.toml"
    path.write_text(GOOD + '\n[output]\ndirectory = "results"\n')
    # Relative to the scenario file, not to the working directory.
    assert load_scenario(path)["directory"] == (folder / "results").resolve()
    for bad in ("../../..", "../elsewhere", "."):
        path.write_text(GOOD + f'\n[output]\ndirectory = "{bad}"\n')
        with pytest.raises(ScenarioError, match=r"output\.directory"):
            load_scenario(path)
    absolute = tmp_path / "abs"
    path.write_text(GOOD + f"\n[output]\ndirectory = {json.dumps(str(absolute))}\n")
    assert load_scenario(path)["directory"] == absolute


def test_rhoprop_run_writes_a_manifest_and_refuses_to_mix(tmp_path, capsys):
    from test_ensemble import GOOD

    path = tmp_path / "s.toml"
    path.write_text(GOOD.replace('name = "tiny"', 'name = "tiny\\nstudy"'))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out)]) == 0
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["complete"]
    assert sorted(manifest["files"]) == [
        "ensemble.nc",
        "ensemble.png",
        "oem/a.oem",
        "oem/b.oem",
        "summary.json",
        "summary.md",
    ]
    assert (out / "summary.md").read_text().startswith("# tiny_study\n")
    assert main(["run", str(path), "--out", str(out)]) == 1
    assert "--overwrite" in capsys.readouterr().err
    assert main(["run", str(path), "--out", str(out), "--overwrite"]) == 0


def test_scenario_models_whose_names_clean_to_one_id_write_separate_oem_files():
    # "X/Y" and "X_Y" (also "é"/"ü", long names differing at the end) once wrote the
    # same oem/X_Y.oem; one silently replaced the other.
    from rhoprop.studies.scenario_file import oem_ids

    long_a, long_b = "M" * 120 + "a", "M" * 120 + "b"
    names = ["X/Y", "X_Y", "NRLMSIS 2.1", "NRLMSIS_2.1", "é", "ü", long_a, long_b, "JB2008"]
    ids = oem_ids(names)
    assert len(set(ids.values())) == len(names)
    assert ids["JB2008"] == "JB2008"  # a name that collides with none keeps its plain id
    assert ids["X/Y"].startswith("X_Y_") and ids["X_Y"].startswith("X_Y_")
    assert all(c.isascii() and c.isprintable() and c not in " /" for c in "".join(ids.values()))
    assert oem_ids(list(reversed(names))) == ids  # the same ids whatever the order


def test_state_at_an_epoch_interpolates_between_outputs_or_says_they_are_too_coarse():
    # Against the state the integrator gives at that epoch itself (a run ending there):
    # 60-s outputs agree to 1 mm, 5-minute outputs to 1 cm; 15-minute outputs are refused
    # at the default 1 m (the degree-7 fit is 57 m off there).
    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    model = rp.scenarios.benchmark_exponential(0.2)
    t_odd = 4 * 3600 + 1234.567
    truth = rp.propagate(state, craft, model, t_odd).state_at(-1)
    for step, tol_m in ((60.0, 1e-3), (300.0, 1e-2)):
        tr = rp.propagate(state, craft, model, 6 * 3600.0, output_step=step)
        got = tr.state_at(truth.epoch)
        assert got.epoch == truth.epoch
        assert np.linalg.norm(got.position - truth.position) < tol_m
        assert np.linalg.norm(got.velocity - truth.velocity) < tol_m / 100
        # An output's own epoch gives its state exactly.
        assert np.array_equal(tr.state_at(tr.epochs[7]).position, tr.positions[7])
    coarse = rp.propagate(state, craft, model, 6 * 3600.0, output_step=900.0)
    with pytest.raises(ValueError, match=r"too far apart to interpolate .* to 1 m"):
        coarse.state_at(truth.epoch)
    with pytest.raises(ValueError, match="outside the outputs"):
        coarse.state_at("2002-09-08T12:00")
    with pytest.raises(TypeError, match="a bool"):
        coarse.state_at(True)
    assert coarse.state_at(-1).epoch == coarse.epochs[-1]


def test_an_oem_recommends_hermite_only_where_its_states_interpolate(tmp_path):
    # INTERPOLATION metadata (CCSDS 502.0-B-3): written where a degree-7 Hermite fit holds
    # the states to 1 m (60-s outputs), left out where it cannot (hourly LEO states); the
    # maintained reader takes the file and interpolates it to within a metre of the state
    # the integrator gives at that epoch.
    from oem import OrbitEphemerisMessage

    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    model = rp.scenarios.benchmark_exponential(0.2)
    dense = rp.propagate(state, craft, model, 3 * 3600.0, output_step=60.0)
    (path,) = io.write_oem(dense, tmp_path / "dense", object_id="DENSE")
    text = path.read_text()
    assert "INTERPOLATION = HERMITE\nINTERPOLATION_DEGREE = 7" in text
    message = OrbitEphemerisMessage.open(str(path))
    (segment,) = message.segments
    assert segment.metadata["INTERPOLATION"] == "HERMITE"
    from astropy.time import Time

    t_odd = 2 * 3600 + 1234.567
    truth = rp.propagate(state, craft, model, t_odd).state_at(-1)
    read = message(Time(str(truth.epoch), scale="utc"))
    assert np.linalg.norm(np.asarray(read.position) * 1e3 - truth.position) < 1.0
    hourly = rp.propagate(state, craft, model, 6 * 3600.0)
    (path,) = io.write_oem(hourly, tmp_path / "hourly", object_id="HOURLY")
    assert "INTERPOLATION" not in path.read_text()


def test_oem_interpolation_metadata_where_states_interpolate_to_a_metre(tmp_path):
    # Degree-7 Hermite at 400 km (measured against 10-s outputs): 1-6 cm every 300 s,
    # 3-12 m every 600 s. The OEM says HERMITE 7 for the first, a COMMENT for the second;
    # state_at interpolates the first and refuses the second.
    from oem import OrbitEphemerisMessage

    s, c = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    m = rp.scenarios.benchmark_exponential(0.2)
    truth = rp.propagate(s, c, m, 7200.0, output_step=10.0)
    for step, ok in ((300.0, True), (600.0, False)):
        tr = rp.propagate(s, c, m, 7200.0, output_step=step)
        (path,) = io.write_oem(tr, tmp_path / str(int(step)))
        text = path.read_text()
        assert ("INTERPOLATION_DEGREE = 7" in text) == ok
        assert ("too far apart to interpolate" in text) == (not ok)
        OrbitEphemerisMessage.open(str(path))  # the comment is valid OEM
        at = rp.time.add_seconds(s.epoch, step / 2)
        if ok:
            got = tr.state_at(at).position
            assert np.linalg.norm(got - truth.state_at(at).position) < 0.1
        else:
            with pytest.raises(ValueError, match="degree 7 and 9"):
                tr.state_at(at)
