"""Catalogs: TLE/OMM parsing against sgp4 itself, malformed input, decay, OEM round trip
through an independent reader, Parquet summary, Dask equals local, the CLI."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from sgp4 import exporter
from sgp4.api import Satrec

import rhoprop as rp
from rhoprop import catalog, io
from rhoprop.catalog.run import propagate_to_own_epochs
from rhoprop.cli import main

SAMPLE = Path(__file__).parent / "data" / "sample.tle"
END = "2002-09-07T06:00:00"


def tle_pairs():
    lines = SAMPLE.read_text().splitlines()
    return [(lines[i], lines[i + 1], lines[i + 2]) for i in range(0, len(lines), 3)]


def test_tle_states_equal_sgp4_at_epoch():
    cat = catalog.load(SAMPLE)
    assert len(cat) == 6 and not cat.skipped
    for obj, (name, l1, l2) in zip(cat, tle_pairs(), strict=True):
        sat = Satrec.twoline2rv(l1, l2)
        _, r, v = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
        np.testing.assert_array_equal(obj.state.position, np.array(r) * 1e3)
        np.testing.assert_array_equal(obj.state.velocity, np.array(v) * 1e3)
        assert obj.name == name and obj.norad_id == sat.satnum
        # Cd A/m = 2 B* / rho0, rho0 = 0.15696615 kg m^-2 ER^-1 (12.7416 B*).
        assert obj.drag_parameter == pytest.approx(2 * sat.bstar / 0.15696615, rel=1e-12)


def omm_records():
    return [exporter.export_omm(Satrec.twoline2rv(l1, l2), name) for name, l1, l2 in tle_pairs()]


def write_xml(records, path):
    meta = (
        "OBJECT_NAME",
        "OBJECT_ID",
        "CENTER_NAME",
        "REF_FRAME",
        "TIME_SYSTEM",
        "MEAN_ELEMENT_THEORY",
    )
    mean = (
        "EPOCH",
        "MEAN_MOTION",
        "ECCENTRICITY",
        "INCLINATION",
        "RA_OF_ASC_NODE",
        "ARG_OF_PERICENTER",
        "MEAN_ANOMALY",
    )
    segs = []
    for r in records:

        def tags(keys, r=r):
            return "".join(f"<{k}>{r[k]}</{k}>" for k in keys if k in r)

        rest = [k for k in r if k not in meta and k not in mean]
        segs.append(
            f"<segment><metadata>{tags(meta)}</metadata><data><meanElements>"
            f"{tags(mean)}</meanElements><tleParameters>{tags(rest)}</tleParameters>"
            "</data></segment>"
        )
    path.write_text(f"<ndm><omm><body>{''.join(segs)}</body></omm></ndm>")


@pytest.mark.parametrize("kind", ["json", "csv", "xml"])
def test_omm_formats_match_the_tles(tmp_path, kind):
    records = omm_records()
    path = tmp_path / f"cat.{kind}"
    if kind == "json":
        path.write_text(json.dumps(records))
    elif kind == "csv":
        with path.open("w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(records[0]))
            w.writeheader()
            w.writerows(records)
    else:
        write_xml(records, path)
    omm = catalog.load(path)
    tle = catalog.load(SAMPLE)
    for a, b in zip(omm, tle, strict=True):
        # OMM text carries the same elements as the TLE, with more digits: within metres.
        assert np.linalg.norm(a.state.position - b.state.position) < 10.0
        assert a.norad_id == b.norad_id and a.name == b.name


@pytest.mark.parametrize("form", ["whole seconds", "Z"])
def test_omm_epochs_in_every_ccsds_form_rebuild_the_element_set(tmp_path, form):
    # CCSDS epochs may end in Z or carry no fraction; sgp4's OMM reader takes neither.
    # The loaded object's Satrec (what catalog and reentry runs rebuild) must come from
    # the same epoch as the TLE's, to the microsecond.
    records = omm_records()
    for r in records:
        whole = str(np.datetime64(r["EPOCH"], "s"))
        r["EPOCH"] = whole if form == "whole seconds" else r["EPOCH"] + "Z"
    path = tmp_path / "cat.json"
    path.write_text(json.dumps(records))
    for obj, (_, l1, l2) in zip(catalog.load(path), tle_pairs(), strict=True):
        tle = Satrec.twoline2rv(l1, l2)
        sat = obj.satrec()
        days = (sat.jdsatepoch - tle.jdsatepoch) + (sat.jdsatepochF - tle.jdsatepochF)
        limit = 1.0 if form == "whole seconds" else 1e-6  # s: the fraction cut, or none
        assert abs(days * 86400.0) < limit


def test_malformed_input_is_named_or_skipped(tmp_path):
    lines = SAMPLE.read_text().splitlines()
    bad = lines.copy()
    bad[4] = bad[4][:-1] + str((int(bad[4][-1]) + 1) % 10)  # line 5: checksum broken
    path = tmp_path / "bad.tle"
    path.write_text("\n".join(bad))
    with pytest.raises(ValueError, match="line 5 fails its checksum"):
        catalog.load(path)
    cat = catalog.load(path, errors="record")
    assert len(cat) == 5 and len(cat.skipped) == 1 and "lines 5-6" in cat.skipped[0][0]
    records = omm_records()
    del records[2]["MEAN_MOTION"]
    jpath = tmp_path / "bad.json"
    jpath.write_text(json.dumps(records))
    with pytest.raises(ValueError, match=r"JSON record 2: missing field 'MEAN_MOTION'"):
        catalog.load(jpath)
    neg = lines.copy()
    neg[1] = neg[1][:53] + "-10000-3" + neg[1][61:68]
    neg[1] += str(exporter.compute_checksum(neg[1]))
    npath = tmp_path / "neg.tle"
    npath.write_text("\n".join(neg))
    with pytest.raises(ValueError, match=r"B\* = -0.0001 is not positive"):
        catalog.load(npath, nonpositive_bstar="error")
    cat = catalog.load(npath, drag_parameters={90001: 0.005})
    assert cat[0].drag_parameter == 0.005
    with pytest.raises(ValueError, match="errors must be"):
        catalog.load(SAMPLE, errors="ignore")


@pytest.fixture(scope="module")
def local_result():
    return catalog.propagate_catalog(
        catalog.load(SAMPLE),
        rp.scenarios.benchmark_exponential(0.2),
        END,
        output_step=1800.0,
        execution=rp.Execution(progress=False),
    )


def test_common_epochs_and_decay(local_result):
    r = local_result
    assert r.epochs[-1] == np.datetime64(END, "ns")
    assert r.epochs[0] >= max(o.state.epoch for o in r.objects)
    assert r.mean.shape == (6, len(r.epochs), 6) and r.valid.all() and np.isnat(r.decay_epoch).all()
    assert list(r.status) == ["propagated"] * 6 and list(r.reason) == [""] * 6
    # A very dense atmosphere brings the low objects down inside the window: status
    # "decayed" with the epoch; outputs after it are invalid and NaN (they used to hold
    # the last valid state).
    dense = rp.density.Exponential(3e-9, 400e3, 58.515e3, rel_sigma=0.2)
    d = catalog.propagate_catalog(
        catalog.load(SAMPLE),
        dense,
        "2002-09-09T00:00",
        execution=rp.Execution(progress=False),
    )
    assert (~np.isnat(d.decay_epoch)).any()
    k = int(np.flatnonzero(~np.isnat(d.decay_epoch))[0])
    assert not d.valid[k, -1] and np.isfinite(d.mean[d.valid]).all()
    assert np.isnan(d.mean[~d.valid]).all() and np.isnan(d.covariance[~d.valid]).all()
    assert d.status[k] == "decayed"
    assert str(d.decay_epoch[k].astype("datetime64[ms]")) in d.reason[k]
    np.testing.assert_array_equal(d.status == "decayed", ~np.isnat(d.decay_epoch))


def test_each_object_to_its_own_epochs_is_the_catalog_run_at_those_epochs(local_result):
    # A screen's Pc needs each object at its own TCAs only. Run to its own epochs, an
    # object's CCSP is the catalog run's wherever the epochs (so the updates) agree: the
    # whole grid, or a prefix of it (a CCSP is the same up to where it stops); a shorter
    # row ends in NaN, not valid.
    r = local_result
    objs = catalog.load(SAMPLE).objects
    own = [r.epochs if i % 2 else r.epochs[:3] for i in range(len(objs))]
    mine = propagate_to_own_epochs(objs, rp.scenarios.benchmark_exponential(0.2), own)
    assert list(mine.status) == ["propagated"] * len(objs)
    for i, epochs in enumerate(own):
        k = len(epochs)
        np.testing.assert_array_equal(mine.mean[i, :k], r.mean[i, :k])
        np.testing.assert_array_equal(mine.covariance[i, :k], r.covariance[i, :k])
        assert mine.valid[i, :k].all() and not mine.valid[i, k:].any()
        assert np.isnan(mine.mean[i, k:]).all()
    # A sigma scale (screen_all's mixture spread) is the model with its sigma scaled:
    # 0.5 x an exponential's 20 % is its 10 %, bit for bit.
    own_short = [r.epochs[:3]] * len(objs)
    half = propagate_to_own_epochs(
        objs, rp.scenarios.benchmark_exponential(0.2), own_short, sigma_scale=0.5
    )
    tenth = propagate_to_own_epochs(objs, rp.scenarios.benchmark_exponential(0.1), own_short)
    np.testing.assert_array_equal(half.covariance, tenth.covariance)
    early = [objs[0].state.epoch - np.timedelta64(1, "s")]
    with pytest.raises(ValueError, match="is before its own"):
        propagate_to_own_epochs(objs[:1], rp.scenarios.benchmark_exponential(0.2), [early])
    with pytest.raises(ValueError, match="one array per object"):
        propagate_to_own_epochs(objs, rp.scenarios.benchmark_exponential(0.2), own[:1])


def test_element_sets_older_than_max_span_end_stale_and_leave_the_rest_unchanged(
    local_result, tmp_path, capsys
):
    # A run holds the density tiles of every day it flies through: the 2023 snapshots
    # merged (181 objects last seen months before the end) took 16 GB before max_span.
    # Objects 90001-90003 lie 18, 15.6 and 13.2 h before END; with max_span 14 h the
    # first two end "stale", unrun, and the others' results are the full run's, bit for bit.
    r = catalog.propagate_catalog(
        catalog.load(SAMPLE),
        rp.scenarios.benchmark_exponential(0.2),
        END,
        output_step=1800.0,
        execution=rp.Execution(progress=False),
        max_span=14 * 3600.0,
    )
    assert list(r.status) == ["stale"] * 2 + ["propagated"] * 4
    assert "0.8 days before the end, beyond max_span" in r.reason[0]
    assert not r.valid[:2].any() and np.isnan(r.mean[:2]).all()
    np.testing.assert_array_equal(r.mean[2:], local_result.mean[2:])
    np.testing.assert_array_equal(r.covariance[2:], local_result.covariance[2:])
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="max_span"):
            catalog.propagate_catalog(
                catalog.load(SAMPLE), rp.scenarios.benchmark_exponential(0.2), END, max_span=bad
            )
    # The CLI says so per object and in its counts.
    out = tmp_path / "run"
    args = ["catalog", str(SAMPLE), "--end", END, "--model", "exponential", "--out", str(out)]
    assert main([*args, "--max-span", str(14 / 24)]) == 0
    captured = capsys.readouterr()
    assert "2 stale" in captured.out and captured.err.count(": stale: epoch") == 2
    with pytest.raises(SystemExit) as stop:  # refused by argparse, naming the option
        main([*args, "--max-span", "-1", "--overwrite"])
    assert stop.value.code == 2
    assert "argument --max-span: must be a number >= 0" in capsys.readouterr().err


def test_a_ccsp_that_loses_definiteness_is_shortened_and_says_so(monkeypatch):
    # At 1e-8 kg/m^3 the Cartesian filter's covariance of object 90004 stops being
    # positive definite before its mean orbit decays (its straight-line sigma points leave
    # the orbit): outputs end there, status "shortened" with the epoch. The default filter
    # (equinoctial elements) keeps it positive definite to the end.
    import functools

    from rhoprop.catalog import objects

    dense = rp.density.Exponential(1e-8, 400e3, 58.515e3, rel_sigma=0.2)

    def run():
        # The paper's near-zero initial covariance, so that the density alone breaks it.
        return catalog.propagate_catalog(
            catalog.load(SAMPLE),
            dense,
            "2002-09-09T00:00",
            initial=rp.catalog.Initial(covariance="paper"),
            execution=rp.Execution(progress=False),
        )

    default = run()
    k = [o.norad_id for o in default.objects].index(90004)
    # Valid to the end (at 2,500x the usual density its arc curves: "non_gaussian" says so).
    assert default.status[k] in ("propagated", "non_gaussian") and default.valid[k].all()
    for cov in default.covariance[k]:
        assert np.linalg.eigvalsh(cov).min() > 0
    monkeypatch.setattr(objects, "ccsp", functools.partial(objects.ccsp, coordinates="cartesian"))
    monkeypatch.setattr(
        objects, "ccsp_many", functools.partial(objects.ccsp_many, coordinates="cartesian")
    )
    d = run()
    assert d.status[k] == "shortened" and np.isnat(d.decay_epoch[k])
    assert "lost positive definiteness at 2002-09-0" in d.reason[k]
    n_valid = d.valid[k].sum()
    assert 0 < n_valid < len(d.epochs) and d.valid[k, :n_valid].all()
    for cov in d.covariance[k, :n_valid]:
        assert np.linalg.eigvalsh(cov).min() > 0
    assert set(d.status) <= {"propagated", "non_gaussian", "decayed", "shortened"}


def narrow_field():
    """A sampled field covering 250-480 km only: the upper objects leave it."""

    def fn(t, lat, lon, alt):
        mean = 3.725e-12 * np.exp(-(alt - 400e3) / 58.515e3)
        return mean, 0.2 * mean

    model = rp.density.FromFunction(fn, name="exp")
    return model.field("2002-09-06T12:00", END, altitude_range=(250e3, 480e3))


def test_errors_are_raised_chained_or_recorded_never_swallowed(tmp_path):
    cat = catalog.load(SAMPLE)
    field = narrow_field()
    # Default: the first failing object raises its own error type, named and chained.
    with pytest.raises(rp.DensityFieldError, match=r"object 9000\d \(SYNTH-\d") as info:
        catalog.propagate_catalog(
            cat,
            field,
            END,
            output_step=1800.0,
            execution=rp.Execution(progress=False),
        )
    assert isinstance(info.value.__cause__, rp.DensityFieldError)
    # errors="record": every object is kept, with its status and reason.
    r = catalog.propagate_catalog(
        cat,
        field,
        END,
        output_step=1800.0,
        execution=rp.Execution(progress=False, errors="record"),
    )
    failed = r.status == "failed"
    assert failed.any() and (r.status[~failed] == "propagated").all()
    assert all(
        x.startswith("DensityFieldError: density field does not cover") for x in r.reason[failed]
    )
    assert not r.valid[failed].any() and np.isnan(r.mean[failed]).all()
    assert r.valid[~failed].all()
    # The summary keeps every object with its status; OEM files only where there is data.
    import pyarrow.parquet as pq

    table = pq.read_table(io.write_summary(r, tmp_path / "s.parquet")).to_pydict()
    assert table["status"] == list(r.status) and len(table["reason"]) == 6
    assert len(io.write_oem(r, tmp_path / "oem")) == int((~failed).sum())
    ephemeris = pq.read_table(io.write_ephemeris(r, tmp_path / "e.parquet")).to_pydict()
    assert set(ephemeris["object"]) == set(np.flatnonzero(~failed).tolist())
    with pytest.raises(ValueError, match="errors must be 'raise' or 'record'"):
        catalog.propagate_catalog(
            cat,
            field,
            END,
            execution=rp.Execution(errors="ignore"),
        )


def test_monte_carlo_catalog_goes_through_the_public_wrapper():
    cat = catalog.load(SAMPLE)
    model = rp.scenarios.benchmark_exponential(0.2)
    r = catalog.propagate_catalog(
        cat,
        model,
        END,
        method=rp.MonteCarlo(n=16, seed=3),
        output_step=1800.0,
        execution=rp.Execution(progress=False),
    )
    obj = cat[2]
    mc = rp.monte_carlo(
        obj.state,
        rp.Spacecraft(1.0, obj.drag_parameter),
        model,
        output_times=rp.time.to_seconds(r.epochs, obj.state.epoch),
        n=16,
        seed=5,
        progress=False,
        drag_sigma=0.15,  # drag_sigma="auto": 0.15 for an object without a fit
        initial_covariance=obj.covariance,  # the catalog default, "object"
        dynamics=rp.Dynamics(zonal_degree=4),  # the catalog default
    )
    np.testing.assert_array_equal(r.covariance[2], mc.moments().covariance)
    np.testing.assert_array_equal(r.drag_sigma, 0.15)
    assert (r.status == "propagated").all()


def test_oem_round_trip_with_an_independent_reader(tmp_path, local_result):
    from oem import OrbitEphemerisMessage

    paths = io.write_oem(local_result, tmp_path)
    assert len(paths) == 6
    oem = OrbitEphemerisMessage.open(str(paths[1]))
    segment = oem.segments[0]
    states = np.array([s.vector for s in segment.states])  # km, km/s
    np.testing.assert_allclose(states * 1e3, local_result.mean[1], rtol=1e-8)
    cov = np.array([c.matrix for c in segment.covariances])  # km^2 ...
    np.testing.assert_allclose(cov * 1e6, local_result.covariance[1], rtol=1e-8, atol=1e-12)


def test_ephemeris_table_round_trip_with_pandas_and_agrees_with_the_oem_files(
    tmp_path, local_result, monkeypatch
):
    # The catalog's default output: one Parquet table of every object's mean and
    # covariance, read back by pandas (no rhoprop) and compared with the result and with
    # the GCRF OEM files (the same rotation, by an independent reader).
    import json

    import pandas as pd
    import pyarrow.parquet as pq
    from oem import OrbitEphemerisMessage

    r = local_result
    path = io.write_ephemeris(r, tmp_path / "ephemeris.parquet")
    df = pd.read_parquet(path)
    assert len(df) == int(r.valid.sum()) and " " not in "".join(df.columns)
    assert str(df["epoch"].dtype) == "datetime64[ns, UTC]"
    for k in (0, 3):
        rows = df[df["object"] == k]
        assert (rows["norad_id"] == r.objects[k].norad_id).all()
        np.testing.assert_array_equal(
            rows["epoch"].dt.tz_localize(None).to_numpy(), r.epochs[r.valid[k]]
        )
        np.testing.assert_array_equal(rows[list(io.ephemeris.STATE)], r.mean[k, r.valid[k]])
        full = np.zeros((len(rows), 6, 6))
        for name in io.ephemeris.COVARIANCE_COLUMNS:
            i, j = (io.ephemeris.STATE.index(c) for c in name.split("_")[1:])
            full[:, i, j] = full[:, j, i] = rows[name].to_numpy()
        np.testing.assert_array_equal(full, r.covariance[k, r.valid[k]])
    meta = json.loads(pq.read_schema(path).metadata[b"rhoprop"])
    assert meta["frame"] == "TEME" and meta["time_scale"] == "UTC"
    assert [o["norad_id"] for o in meta["objects"]] == [o.norad_id for o in r.objects]
    gcrf = pd.read_parquet(io.write_ephemeris(r, tmp_path / "g.parquet", frame="GCRF"))
    (oem_path,) = io.write_oem(r, tmp_path / "oem", ref_frame="GCRF")[1:2]
    states = [s.vector for s in OrbitEphemerisMessage.open(str(oem_path)).segments[0].states]
    got = gcrf[gcrf["object"] == 1][list(io.ephemeris.STATE)].to_numpy()
    np.testing.assert_allclose(got, np.array(states) * 1e3, rtol=1e-8, atol=1e-6)
    # Written in row groups of a few objects at a time: the same table.
    monkeypatch.setattr(io.ephemeris, "ROW_GROUP_OBJECTS", 2)
    grouped = pd.read_parquet(io.write_ephemeris(r, tmp_path / "grouped.parquet"))
    pd.testing.assert_frame_equal(grouped, df)
    assert pq.ParquetFile(tmp_path / "grouped.parquet").num_row_groups == 3
    with pytest.raises(ValueError, match="frame must be one of"):
        io.write_ephemeris(r, tmp_path / "x.parquet", frame="ITRF")
    with pytest.raises(TypeError, match="takes a CatalogResult"):
        io.write_ephemeris([1, 2], tmp_path / "x.parquet")


def test_parquet_summary(tmp_path, local_result):
    import pyarrow.parquet as pq

    table = pq.read_table(io.write_summary(local_result, tmp_path / "s.parquet"))
    assert table.num_rows == 6
    assert {"norad_id", "along_track_std_m", "decay_epoch"} <= set(table.column_names)
    assert (np.asarray(table["along_track_std_m"]) > 0).all()


def test_dask_cluster_equals_local(local_result):
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote = catalog.propagate_catalog(
            catalog.load(SAMPLE),
            rp.scenarios.benchmark_exponential(0.2),
            END,
            output_step=1800.0,
            execution=rp.Execution(client=client, chunk_size=2, progress=False),
        )
        objs = catalog.load(SAMPLE).objects
        own = [local_result.epochs[: 2 + i] for i in range(len(objs))]
        model = rp.scenarios.benchmark_exponential(0.2)
        there = propagate_to_own_epochs(objs, model, own, client=client)
    np.testing.assert_array_equal(remote.mean, local_result.mean)
    np.testing.assert_array_equal(remote.covariance, local_result.covariance)
    np.testing.assert_array_equal(remote.status, local_result.status)
    here = propagate_to_own_epochs(objs, model, own)
    np.testing.assert_array_equal(there.covariance, here.covariance)
    np.testing.assert_array_equal(there.valid, here.valid)


def test_dask_raises_the_workers_own_exception():
    # Not a bare RuntimeError: the task's DensityFieldError, the object named, chained.
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
        pytest.raises(rp.DensityFieldError, match=r"object 9000\d") as info,
    ):
        catalog.propagate_catalog(
            catalog.load(SAMPLE),
            narrow_field(),
            END,
            output_step=1800.0,
            execution=rp.Execution(client=client, chunk_size=2, progress=False),
        )
    assert info.value.__cause__ is not None


def test_cli_catalog(tmp_path, capsys):
    code = main(
        ["catalog", str(SAMPLE), "--end", END, "--out", str(tmp_path), "--model", "exponential"]
    )
    assert code == 0
    assert not (tmp_path / "oem").exists()  # OEM files on request (--oem)
    assert (tmp_path / "summary.parquet").exists()
    assert "objects/s" in capsys.readouterr().out
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["complete"] and manifest["rhoprop_version"] == rp.__version__
    assert manifest["command"].startswith("rhoprop catalog ")
    assert sorted(manifest["files"]) == ["ephemeris.parquet", "summary.parquet"]
    each = tmp_path.parent / f"{tmp_path.name}_each"
    base = ["catalog", str(SAMPLE), "--end", END, "--model", "exponential"]
    assert main([*base, "--out", str(each), "--oem"]) == 0
    assert sorted(json.loads((each / "manifest.json").read_text())["files"]) == sorted(
        [
            "ephemeris.parquet",
            "summary.parquet",
            *(f"oem/{o.norad_id}.oem" for o in catalog.load(SAMPLE)),
        ]
    )
    # The same folder again: refused (it holds that run's files), unless --overwrite.
    args = ["catalog", str(SAMPLE), "--end", END, "--out", str(tmp_path), "--model", "exponential"]
    assert main(args) == 1
    assert "holds the files of an earlier run" in capsys.readouterr().err
    assert main([*args, "--overwrite"]) == 0


def test_cli_catalog_duplicate_ids(tmp_path, capsys):
    # The same element set twice: one object each by default (a history of one epoch),
    # an error before any work, or suffixed OEM names.
    text = SAMPLE.read_text()
    twice = tmp_path / "twice.tle"
    twice.write_text(text + text)
    out = tmp_path / "out"
    args = ["catalog", str(twice), "--end", END, "--out", str(out), "--model", "exponential"]
    assert main([*args, "--out", str(tmp_path / "combined"), "--oem"]) == 0
    assert len(list((tmp_path / "combined" / "oem").glob("*.oem"))) == 6
    assert main([*args, "--duplicates", "error"]) == 1
    assert "occur more than once" in capsys.readouterr().err and not out.exists()
    assert main([*args, "--duplicates", "suffix", "--oem"]) == 0
    names = sorted(p.name for p in (out / "oem").glob("*.oem"))
    assert len(names) == 12 and "90001_2.oem" in names


def test_dask_survives_a_worker_dying_mid_run(local_result):
    # One of the two worker processes is killed while tasks are running: Dask reschedules
    # its chunks and nothing is lost or duplicated (same numbers as the local run).
    import contextlib
    import os
    import threading
    import time

    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        out = {}

        def run():
            out["r"] = catalog.propagate_catalog(
                catalog.load(SAMPLE),
                rp.scenarios.benchmark_exponential(0.2),
                END,
                output_step=1800.0,
                execution=rp.Execution(client=client, chunk_size=1, progress=False),
            )

        worker = threading.Thread(target=run)
        worker.start()
        deadline = time.time() + 30
        while not any(client.processing().values()):
            assert time.time() < deadline, "no task started"
            time.sleep(0.01)
        victim = next(iter(client.scheduler_info()["workers"]))
        killed_while_running = worker.is_alive()
        with contextlib.suppress(Exception):  # the worker dies before it can answer
            client.run(os._exit, 1, workers=[victim])
        worker.join(120)
    assert killed_while_running
    np.testing.assert_array_equal(out["r"].mean, local_result.mean)
    np.testing.assert_array_equal(out["r"].covariance, local_result.covariance)


def test_load_reads_gzip_compressed_catalogs(test_data, tmp_path):
    import gzip

    src = test_data / "catalogs" / "celestrak_active_20231113.txt.gz"
    plain = tmp_path / "active.txt"
    plain.write_bytes(gzip.decompress(src.read_bytes()))
    a = rp.catalog.load(src, errors="record")
    b = rp.catalog.load(plain, errors="record")
    assert len(a) == len(b) > 1000 and len(a.skipped) == len(b.skipped)
    assert [o.norad_id for o in a] == [o.norad_id for o in b]
    damaged = tmp_path / "damaged.txt.gz"
    damaged.write_bytes(src.read_bytes()[:500])
    with pytest.raises(ValueError, match="damaged gzip"):
        rp.catalog.load(damaged)


def test_a_published_catalog_loads_as_it_comes_far_orbits_set_aside(test_data, tmp_path, capsys):
    # Published catalogs hold orbits beyond the 10 Earth radii rhoprop propagates (TESS,
    # MMS, Chandra): valid element sets, not bad input. By default they are set aside and
    # listed, whatever `errors`; an object whose newest element set is set aside is not
    # predicted from an older one that happened to lie nearer (MMS 1 in the 2023
    # snapshots: 9.1 Earth radii at its 11-13 epoch, 25.5 at its 11-18 one).
    import gzip

    def sets(snapshot: str, names: set[str]) -> str:
        lines = gzip.open(test_data / "catalogs" / snapshot, "rt").read().splitlines()
        return "".join(
            "\n".join(lines[i : i + 3]) + "\n"
            for i in range(len(lines) - 2)
            if lines[i].strip() in names and lines[i + 1].startswith("1 ")
        )

    path = tmp_path / "two_snapshots.tle"
    path.write_text(
        sets("celestrak_active_20231113.txt.gz", {"MMS 1", "ISS (ZARYA)"})
        + sets("history/celestrak_active_20231118.txt.gz", {"MMS 1", "TESS"})
    )
    with pytest.warns(RuntimeWarning, match="2 objects beyond 10 Earth radii set aside"):
        cat = catalog.load(path)
    assert [o.name for o in cat] == ["ISS (ZARYA)"]
    reasons = " | ".join(message for _, message in cat.skipped)
    assert len(cat.skipped) == 3, reasons
    assert "TESS (NORAD 43435) is 19.7 Earth radii" in reasons
    assert "MMS 1 (NORAD 40482) is 25.5 Earth radii" in reasons
    assert "MMS 1 (NORAD 40482): its newest element set (2023-11-18" in reasons
    with pytest.raises(ValueError, match=r"lines \d+-\d+: MMS 1 .* beyond the 10"):
        catalog.load(path, far_orbits="error")
    with pytest.warns(RuntimeWarning):
        each = catalog.load(path, history="each")
    assert sorted(o.name for o in each) == ["ISS (ZARYA)", "MMS 1"]  # MMS 1 of 11-13
    with pytest.raises(ValueError, match="far_orbits must be"):
        catalog.load(path, far_orbits="ignore")
    # The CLI runs such a file with its defaults and lists what it set aside.
    out = tmp_path / "run"
    end = "2023-11-20T00:00Z"
    assert (
        main(["catalog", str(path), "--end", end, "--model", "exponential", "--out", str(out)]) == 0
    )
    err = capsys.readouterr().err
    assert err.count("skipped") == 3 and "TESS" in err and "RuntimeWarning" not in err


def test_an_initial_covariance_callable_is_called_once_per_object():
    calls = []

    def per_object(obj):
        calls.append(obj.norad_id)
        return np.diag([100.0**2] * 3 + [0.1**2] * 3)

    cat = catalog.load(SAMPLE)
    catalog.propagate_catalog(
        cat,
        rp.scenarios.benchmark_exponential(0.2),
        END,
        output_step=1800.0,
        initial=rp.catalog.Initial(covariance=per_object),
        execution=rp.Execution(progress=False),
    )
    assert sorted(calls) == sorted(o.norad_id for o in cat)


def test_high_orbits_take_longer_steps_at_no_cost_in_accuracy(test_data):
    # catalog_step: LEO keeps the RK8 default, GEO and GPS take 1/64 of their (perigee)
    # period. Over 7 days the longer step moves them by less than a centimetre against
    # RK8 at 180 s (measured 0.6 mm at 1,800 s for GEO, docs/performance.md).
    from rhoprop.catalog.objects import catalog_step

    cat = rp.catalog.load(
        test_data / "catalogs" / "celestrak_active_20231113.txt.gz", errors="record"
    )
    by_name = {o.name: o for o in cat}
    leo = next(o for o in cat if o.name.startswith("STARLINK"))
    assert catalog_step(leo.state) == 180.0
    craft = rp.Spacecraft(1.0, 0.01)
    atmosphere = rp.scenarios.benchmark_exponential(0.0)
    for name, low, high in (
        ("INTELSAT 901 (IS-901)", 1300, 1400),
        ("NAVSTAR 81 (USA 319)", 600, 700),
    ):
        state = by_name[name].state
        h = catalog_step(state)
        assert low < h < high
        runs = [
            rp.propagate(
                state,
                craft,
                atmosphere,
                7 * 86400.0,
                dynamics=rp.Dynamics(integrator="rk8", step=s),
            )
            for s in (h, 180.0)
        ]
        assert np.linalg.norm(runs[0].positions[-1] - runs[1].positions[-1]) < 0.01


def test_start_before_the_newest_epoch_leaves_only_that_objects_earlier_outputs_empty():
    # SYNTH-6's epoch (2002-09-07T00:00) is the newest: by default the outputs begin
    # there. From 2002-09-06T12:00 (SYNTH-1's epoch) each object is valid from its own
    # epoch on, SYNTH-6 with the same states there as without a start.
    cat = catalog.load(SAMPLE)
    model = rp.scenarios.benchmark_exponential(0.2)
    plain = catalog.propagate_catalog(
        cat,
        model,
        END,
        output_step=3600.0,
        execution=rp.Execution(progress=False),
    )
    early = catalog.propagate_catalog(
        cat,
        model,
        END,
        output_step=3600.0,
        execution=rp.Execution(progress=False),
        start="2002-09-06T12:00",
    )
    assert plain.epochs[0] == np.datetime64("2002-09-07T00:00")
    assert early.epochs[0] == np.datetime64("2002-09-06T12:00")
    k = [o.norad_id for o in cat].index(90006)
    lead = len(early.epochs) - len(plain.epochs)
    assert lead == 12
    assert not early.valid[k, :lead].any() and early.valid[k, lead:].all()
    for i, obj in enumerate(cat):
        np.testing.assert_array_equal(early.valid[i], early.epochs >= obj.state.epoch)
    assert (early.status == "propagated").all()
    np.testing.assert_array_equal(early.mean[k, lead:], plain.mean[k])
    with pytest.raises(ValueError, match="start"):
        catalog.propagate_catalog(
            cat,
            model,
            END,
            start=END,
            execution=rp.Execution(progress=False),
        )


def test_cli_catalog_starts_where_99_percent_of_the_epochs_are(tmp_path, capsys):
    out = tmp_path / "run"
    assert (
        main(["catalog", str(SAMPLE), "--end", END, "--out", str(out), "--model", "exponential"])
        == 0
    )
    printed = capsys.readouterr().out
    # Six epochs 2.4 h apart: the 99 % quantile is the fifth (2002-09-06T21:36).
    assert "2002-09-06T22:00:00Z to 2002-09-07T06:00:00Z" in printed, printed


def test_an_indefinite_ccsp_covariance_is_near_decay_only_with_a_low_perigee():
    # An HEO of 372 x 31,841 km was reported "near decay" when its CCSP covariance lost
    # definiteness; the reason now follows the perigee.
    from rhoprop.catalog.objects import _why_indefinite
    from rhoprop.constants import MU, R_EARTH

    def orbit(perigee_km: float, apogee_km: float) -> rp.OrbitState:
        rp_, ra = R_EARTH + perigee_km * 1e3, R_EARTH + apogee_km * 1e3
        v = np.sqrt(MU * (2 / rp_ - 2 / (rp_ + ra)))
        return rp.OrbitState("2023-11-13T00:00", [rp_, 0.0, 0.0], [0.0, v, 0.0])

    assert _why_indefinite(orbit(180, 300)) == "near decay"
    assert "outgrew one Gaussian" in _why_indefinite(orbit(372, 31_841))
