"""Results for analysis: ``to_xarray()`` on every result type (labelled
dims, UTC datetime64 epochs, units and frame in attributes), netCDF round trips through
h5netcdf, ``CatalogResult.to_pandas()``, and xarray kept an optional import."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import catalog, io

xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")
pytest.importorskip("h5py")

SAMPLE = Path(__file__).parent / "data" / "sample.tle"
AIR = rp.density.Exponential(3.725e-12, 400e3, 58.515e3, rel_sigma=0.2)
#: At 1e-9 kg/m^3 (400 km) with a held 50 % bias some members come down within 1.8 days
#: (tests/test_decay.py).
DENSE = rp.density.Exponential(1e-9, 400e3, 58.515e3, rel_sigma=0.5)


@pytest.fixture(scope="module")
def setup():
    return rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()


def round_trip(ds, tmp_path, name):
    """``ds`` written to netCDF-4 (h5netcdf) and read back, with the file's path."""
    path = tmp_path / f"{name}.nc"
    ds.to_netcdf(path, engine="h5netcdf")
    back = xr.load_dataset(path, engine="h5netcdf")
    xr.testing.assert_identical(ds, back)
    return back


def check_common(ds, result_type):
    assert ds.attrs["rhoprop_version"] == rp.__version__
    assert ds.attrs["result_type"] == result_type
    assert ds.epoch.dtype == np.dtype("datetime64[ns]")
    assert ds.elapsed.attrs["units"] == "s"
    for name, var in ds.data_vars.items():
        if var.dtype.kind == "f":
            assert "units" in var.attrs, name  # "1" for dimensionless


def test_trajectory(setup, tmp_path):
    state, craft = setup
    traj = rp.propagate(state, craft, AIR, 7200.0, output_step=600.0)
    ds = traj.to_xarray()
    check_common(ds, "Trajectory")
    assert dict(ds.sizes) == {"epoch": 13, "component": 3}
    assert list(ds.component.values) == ["x", "y", "z"]
    np.testing.assert_array_equal(ds.epoch.values, traj.epochs)
    assert ds.epoch.values[0] == np.datetime64("2002-09-07T01:00:00", "ns")
    assert ds.epoch.values[-1] == np.datetime64("2002-09-07T03:00:00", "ns")
    np.testing.assert_array_equal(ds.elapsed.values, traj.times)
    np.testing.assert_array_equal(ds.position.values, traj.positions)
    np.testing.assert_array_equal(ds.velocity.sel(component="z").values, traj.velocities[:, 2])
    assert ds.position.attrs["units"] == "m" and ds.velocity.attrs["units"] == "m/s"
    assert ds.attrs["frame"] == "GCRF" and ds.attrs["initial_epoch"].startswith("2002-09-07T01")
    assert np.isnan(ds.attrs["decayed_at_s"]) and ds.attrs["evaluations"] == traj.evaluations
    back = round_trip(ds, tmp_path, "trajectory")
    # Selection by UTC time works on the file's contents.
    at = back.position.sel(epoch="2002-09-07T02:00").values
    np.testing.assert_array_equal(at, traj.positions[6])


def test_monte_carlo_with_decayed_members(setup, tmp_path):
    state, craft = setup
    mc = rp.monte_carlo(
        state,
        craft,
        DENSE,
        1.8 * 86400.0,
        n=60,
        kappa=rp.kappa.Constant(),
        output_step=3600.0,
        record_density=True,
        progress=False,
        seed=3,
    )
    assert mc.decayed.any() and not mc.decayed.all()
    ds = mc.to_xarray()
    check_common(ds, "MonteCarloResult")
    assert dict(ds.sizes) == {
        "member": 60,
        "epoch": len(mc.times),
        "component": 3,
        "rtn": 3,
        "rtn2": 3,
        "state": 6,
        "state2": 6,
    }
    assert list(ds.rtn.values) == ["R", "T", "N"]
    assert list(ds.state.values) == ["x", "y", "z", "vx", "vy", "vz"]
    np.testing.assert_array_equal(ds.position.values, mc.positions)
    np.testing.assert_array_equal(ds.rtn_error.sel(rtn="T").values, mc.along_track)
    np.testing.assert_array_equal(ds.density.values, mc.densities)
    np.testing.assert_array_equal(ds.alive.values, mc.alive)
    np.testing.assert_array_equal(ds.decay_time.values, mc.decay_times)
    np.testing.assert_array_equal(ds.survivors.values, mc.survivors)
    assert ds.density.attrs["units"] == "kg/m^3"
    assert ds.attrs["kappa"] == "constant" and ds.attrs["seed"] == 3 and ds.attrs["members"] == 60
    # The RTN statistics over the members still flying, against plain numpy.
    along = mc.along_track
    np.testing.assert_allclose(
        ds.rtn_std.sel(rtn="T").values[1:], np.nanstd(along, axis=0, ddof=1)[1:], rtol=1e-9
    )
    np.testing.assert_allclose(
        ds.rtn_mean.sel(rtn="T").values, np.nanmean(along, axis=0), rtol=1e-9, atol=1e-9
    )
    # Moments: the state covariance of the survivors (np.cov over the finite members).
    last = mc.alive[:, -1]
    states = np.concatenate([mc.positions[last, -1], mc.velocities[last, -1]], axis=1)
    np.testing.assert_allclose(ds.covariance.values[-1], np.cov(states.T), rtol=1e-9)
    np.testing.assert_allclose(ds.along_track_std.values, mc.moments().along_track_std, rtol=1e-12)
    # The xarray way of the same statistic gives the same number.
    np.testing.assert_allclose(
        ds.rtn_error.sel(rtn="T").isel(epoch=-1).std("member", ddof=1).item(),
        np.nanstd(along[:, -1], ddof=1),
        rtol=1e-12,
    )
    back = round_trip(ds, tmp_path, "monte_carlo")
    assert np.isnan(back.position.values[~mc.alive]).all()
    assert back.alive.dtype == bool
    # Statistics only.
    small = mc.to_xarray(members=False)
    assert "position" not in small and "decay_time" in small and "rtn_std" in small
    # Members drawn with their own Cd*A/m: the factors travel per member.
    factors = np.linspace(0.8, 1.2, 60)
    ds = dataclasses.replace(mc, drag_sigma=0.1, drag_factors=factors).to_xarray()
    assert ds.attrs["drag_sigma"] == 0.1
    np.testing.assert_array_equal(ds.drag_factor.values, factors)


def test_ccsp(setup, tmp_path):
    state, craft = setup
    cc = rp.ccsp(state, craft, AIR, 6 * 3600.0, update_interval=3600.0)
    ds = cc.to_xarray()
    check_common(ds, "CcspResult")
    np.testing.assert_array_equal(ds.epoch.values, cc.epochs)
    np.testing.assert_array_equal(ds["mean"].values, cc.mean)
    np.testing.assert_array_equal(ds.covariance.values, cc.covariance)
    np.testing.assert_array_equal(ds.cross_covariance.values, cc.cross_covariance)
    np.testing.assert_array_equal(ds.rtn_covariance.values, cc.rtn_covariance)
    np.testing.assert_array_equal(ds.along_track_std.values, cc.along_track_std)
    # The RTN covariance is the inertial one rotated into the mean's RTN frame.
    basis = rp.frames.rtn_basis(cc.mean[-1, :3], cc.mean[-1, 3:]).reshape(3, 3)
    rotated = basis @ ds.covariance.values[-1, :3, :3] @ basis.T
    np.testing.assert_allclose(ds.rtn_covariance.values[-1], rotated, rtol=1e-9, atol=1e-12)
    cov = ds.covariance.sel(state="vy", state2="y").values
    np.testing.assert_array_equal(cov, cc.covariance[:, 4, 1])
    assert ds.covariance.attrs["units"].startswith("m^2")
    round_trip(ds, tmp_path, "ccsp")
    # Cd*A/m carried as a second consider parameter: its setting and cross-covariance.
    drag = np.arange(len(cc.times) * 6.0).reshape(-1, 6)
    ds = dataclasses.replace(cc, drag_sigma=0.1, drag_cross_covariance=drag).to_xarray()
    assert ds.attrs["drag_sigma"] == 0.1
    np.testing.assert_array_equal(ds.drag_cross_covariance.sel(state="vx").values, drag[:, 3])


def test_ensemble(setup, tmp_path):
    state, craft = setup
    models = {
        "ref": AIR,
        "denser": rp.density.Exponential(1.2 * 3.725e-12, 400e3, 58.515e3, rel_sigma=0.2),
    }
    ens = rp.ensemble(
        state,
        craft,
        models,
        "ref",
        duration=6 * 3600.0,
        method=rp.MonteCarlo(n=100, progress=False),
        weights=[3, 1],
    )
    ds = ens.to_xarray()
    check_common(ds, "EnsembleResult")
    assert list(ds.model.values) == ["ref", "denser"]
    assert ds.attrs["reference"] == "ref" and ds.attrs["method"] == "monte_carlo"
    np.testing.assert_array_equal(ds.cd.values, [ens.cd["ref"], ens.cd["denser"]])
    np.testing.assert_allclose(ds.weight.values, [0.75, 0.25])
    np.testing.assert_array_equal(
        ds.component_mean.sel(model="denser").values, ens.component_means[:, 1]
    )
    np.testing.assert_array_equal(
        ds.component_covariance.sel(model="ref").values, ens.component_covariances[:, 0]
    )
    # The mixture's along-track moments, against the GaussianMixture of the same output.
    for i in (1, len(ens.times) // 2, -1):
        mix = ens.along_track_mixture(i)
        assert ds.mixture_along_track_mean.values[i] == pytest.approx(mix.mean()[0], rel=1e-9)
        assert ds.mixture_along_track_std.values[i] == pytest.approx(
            np.sqrt(mix.covariance()[0, 0]), rel=1e-9
        )
    np.testing.assert_array_equal(ds.epoch.values, ens.results["ref"].epochs)
    assert ds.attrs["kappa"] == "two_scale" and ds.attrs["members"] == 100
    round_trip(ds, tmp_path, "ensemble")
    # A CCSP ensemble: the same layout, method "ccsp", no kappa settings.
    cc = rp.ensemble(
        state,
        craft,
        models,
        "ref",
        method=rp.Ccsp(),
        duration=6 * 3600.0,
        debias=rp.Debias(cds={"denser": 3.0}),
    )
    ds = cc.to_xarray()
    assert ds.attrs["method"] == "ccsp" and "kappa" not in ds.attrs
    mix = cc.along_track_mixture()
    assert ds.mixture_along_track_std.values[-1] == pytest.approx(
        np.sqrt(mix.covariance()[0, 0]), rel=1e-9
    )
    round_trip(ds, tmp_path, "ensemble_ccsp")


@pytest.fixture(scope="module")
def catalog_result():
    dense = rp.density.Exponential(3e-9, 400e3, 58.515e3, rel_sigma=0.2)
    return catalog.propagate_catalog(
        catalog.load(SAMPLE),
        dense,
        "2002-09-09T00:00",
        output_step=3 * 3600.0,
        execution=rp.Execution(progress=False),
    )


def test_catalog(catalog_result, tmp_path):
    r = catalog_result
    assert (~np.isnat(r.decay_epoch)).any()  # some objects decay: NaN and NaT travel too
    ds = r.to_xarray()
    check_common(ds, "CatalogResult")
    assert "TEME" in ds.attrs["frame"] and ds.attrs["method"] == "ccsp"
    assert dict(ds.sizes)["object"] == len(r.objects)
    np.testing.assert_array_equal(ds.norad_id.values, [o.norad_id for o in r.objects])
    np.testing.assert_array_equal(ds.epoch.values, r.epochs)
    np.testing.assert_array_equal(ds["mean"].values, r.mean)
    np.testing.assert_array_equal(ds.valid.values, r.valid)
    np.testing.assert_array_equal(ds.decay_epoch.values, r.decay_epoch)
    assert list(ds.status.values) == list(r.status)
    # Along-track sigma at each object's last valid output equals the summary's.
    table = io.summary_table(r)
    for k in range(len(r.objects)):
        valid = np.flatnonzero(r.valid[k])
        if len(valid):
            at = ds.along_track_std.isel(object=k, epoch=int(valid[-1])).item()
            assert at == pytest.approx(table["along_track_std_m"][k], rel=1e-12)
    back = round_trip(ds, tmp_path, "catalog")
    assert back.decay_epoch.dtype == np.dtype("datetime64[ns]")


def test_catalog_to_pandas(catalog_result, tmp_path):
    pd = pytest.importorskip("pandas")
    r = catalog_result
    frame = r.to_pandas()
    assert isinstance(frame, pd.DataFrame) and len(frame) == len(r.objects)
    table = io.summary_table(r)
    assert list(frame.columns) == list(table)
    np.testing.assert_array_equal(frame["norad_id"].to_numpy(), table["norad_id"])
    np.testing.assert_array_equal(frame["along_track_std_m"].to_numpy(), table["along_track_std_m"])
    assert frame["decay_epoch"].dtype.kind == "M"
    # The same rows as the Parquet summary.
    pq = pytest.importorskip("pyarrow.parquet")
    parquet = pq.read_table(io.write_summary(r, tmp_path / "s.parquet")).to_pandas()
    np.testing.assert_array_equal(parquet["status"].to_numpy(), frame["status"].to_numpy())
    np.testing.assert_array_equal(
        parquet["along_track_std_m"].to_numpy(), frame["along_track_std_m"].to_numpy()
    )


def test_without_xarray_a_one_line_import_error(setup, monkeypatch):
    state, craft = setup
    traj = rp.propagate(state, craft, AIR, 600.0)
    monkeypatch.setitem(sys.modules, "xarray", None)
    with pytest.raises(ImportError, match=r"pip install xarray") as info:
        traj.to_xarray()
    assert "\n" not in str(info.value) and "Trajectory.to_xarray()" in str(info.value)
    assert info.value.__cause__ is None and info.value.__suppress_context__
    monkeypatch.setitem(sys.modules, "pandas", None)
    r = catalog.CatalogResult.__new__(catalog.CatalogResult)
    with pytest.raises(ImportError, match=r"to_pandas\(\) needs the optional package pandas"):
        r.to_pandas()


def test_importing_rhoprop_does_not_import_xarray():
    code = (
        "import sys, rhoprop as rp; rp.propagate; rp.catalog; "
        "print([m for m in ('xarray', 'pandas') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_docs_analysis_examples_run(tmp_path, monkeypatch, capsys):
    pytest.importorskip("astropy.time")
    import re
    import shutil

    text = (Path(__file__).parents[1] / "docs" / "analysis.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) == 3
    shutil.copy(SAMPLE, tmp_path / "catalog.tle")
    monkeypatch.chdir(tmp_path)
    for block in blocks:
        exec(compile(block, "docs/analysis.md", "exec"), {})
    out = capsys.readouterr().out
    assert "two_scale 16700.0" in out and "2002-09-07T01:00:00.000000000" in out
    assert (tmp_path / "monte_carlo.nc").is_file()
