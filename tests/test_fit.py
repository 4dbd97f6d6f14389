"""TLE -> numerical state and Cd*A/m by a least-squares fit to SGP4 pseudo-observations
(``rp.catalog.fit``), the TLE-accuracy initial covariance (``rp.catalog.covariance``) and
how a catalog run uses and reports them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from sgp4 import exporter
from sgp4.api import WGS72, Satrec

import rhoprop as rp
from rhoprop import catalog
from rhoprop.catalog.covariance import TleAccuracy, tle_accuracy, tle_covariance
from rhoprop.catalog.fit import DEFAULT_DRAG_PARAMETER, fit_element_set
from rhoprop.cli import main
from rhoprop.frames import rtn_basis

SAMPLE = Path(__file__).parent / "data" / "sample.tle"


def _tle(norad: int, alt_km: float, bstar: float, ecc: float = 1e-3) -> tuple[str, str]:
    sat = Satrec()
    mean_motion = np.sqrt(3.986004418e14 / (6378137.0 + alt_km * 1e3) ** 3) * 60.0
    sat.sgp4init(
        WGS72, "i", norad, 2452524.0 - 2433281.5, bstar, 0.0, 0.0, ecc, 1.0, 0.9, 2.0,
        mean_motion, 0.5,
    )  # fmt: skip
    l1, l2 = exporter.export_tle(sat)
    l1 = l1[:9] + "02900A  " + l1[17:68]
    return l1 + str(exporter.compute_checksum(l1)), l2


@pytest.fixture(scope="module")
def atmosphere():
    return rp.scenarios.benchmark_exponential(0.2)


@pytest.fixture(scope="module")
def tle_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("tle") / "fit.tle"
    lines = []
    for norad, alt, bstar in ((91001, 400.0, 3e-4), (91002, 450.0, 0.0), (91003, 420.0, -1e-4)):
        lines += [f"OBJ {norad}", *_tle(norad, alt, bstar)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_fit_converges_and_reports_residuals(tle_file, atmosphere):
    obj = catalog.load(tle_file, errors="record")[0]
    f = fit_element_set(obj, atmosphere)
    assert f.converged and f.iterations <= 8
    assert f.state.epoch == obj.state.epoch
    # The default span: the day before the epoch, every 600 s.
    assert f.residuals.shape == (len(f.times), 3) and f.times[0] == -86400 and f.times[-1] == 0
    assert len(f.times) == 145
    assert f.rms_total < 2000.0  # m: J2 numerical orbit vs SGP4 over a day
    assert np.isclose(f.rms_total, np.sqrt(np.sum(f.rms**2)))
    assert f.drag_parameter > 0 and f.drag_sigma > 0
    assert f.covariance.shape == (7, 7)
    np.testing.assert_allclose(f.covariance, f.covariance.T)
    assert np.linalg.eigvalsh(f.covariance).min() > -1e-9 * np.abs(f.covariance).max()
    # The fitted state reproduces SGP4 at the epoch to about the residual level.
    assert np.linalg.norm(f.state.position - obj.state.position) < 3 * f.rms_total + 100


def test_fit_is_independent_of_the_starting_drag(tle_file, atmosphere):
    obj = catalog.load(tle_file, errors="record")[0]
    a = fit_element_set(obj, atmosphere)
    b = fit_element_set(obj, atmosphere, drag_parameter=3 * obj.drag_parameter)
    assert abs(a.drag_parameter - b.drag_parameter) < 0.1 * a.drag_parameter


def test_nonpositive_bstar_loads_with_a_guess_fitted_or_refused(tle_file, atmosphere):
    with pytest.raises(ValueError, match="fit=True"):
        catalog.load(tle_file, nonpositive_bstar="error")
    guessed = catalog.load(tle_file)[1:]  # B* = 0 and < 0: the fit's starting guess
    assert all(o.drag_parameter == DEFAULT_DRAG_PARAMETER for o in guessed)
    assert all("0.022" in o.covariance_note for o in guessed)
    fitted = catalog.load(
        tle_file,
        fit=rp.catalog.FitSettings(atmosphere),
    )
    assert [o.norad_id for o in fitted] == [91001, 91002, 91003]
    assert all(o.fit is not None and o.drag_parameter > 0 for o in fitted)
    assert all("fit to SGP4" in o.covariance_note for o in fitted)
    with pytest.raises(ValueError, match="needs a density model"):
        catalog.load(tle_file, fit=True)
    r = catalog.propagate_catalog(
        fitted,
        atmosphere,
        "2002-09-09T00:00",
        initial=rp.catalog.Initial(covariance="object"),
        execution=rp.Execution(progress=False),
    )
    assert (r.status == "propagated").all()


def test_regimes_above_leo_split_at_a_16_hour_period():
    # Near-circular orbits above 2,000 km: MEO (GPS included) below a 16-hour period, GEO
    # above; eccentric ones keep their own regime whatever the period.
    def circular(radius_km: float, e: float = 0.0) -> rp.OrbitState:
        r = radius_km * 1e3
        v = np.sqrt(rp.constants.MU / r * (1 + e))  # at perigee
        return rp.OrbitState("2023-11-13T00:00", [r, 0.0, 0.0], [0.0, v, 0.0])

    assert tle_accuracy(circular(26_560)).regime == "MEO"  # GPS, 12 h
    assert tle_accuracy(circular(8_500)).regime == "MEO"  # 2,100 km altitude
    assert tle_accuracy(circular(42_164)).regime == "GEO"
    assert tle_accuracy(circular(35_000)).regime == "GEO"  # 18 h
    assert tle_accuracy(circular(7_000, 0.7)).regime == "eccentric"


def test_tle_covariance_has_the_regime_rms_in_rtn(tle_file):
    obj = catalog.load(tle_file, errors="record")[0]
    acc = tle_accuracy(obj.state)
    assert acc.regime == "LEO below 800 km"
    cov = tle_covariance(obj.state)
    basis = rtn_basis(obj.state.position, obj.state.velocity)
    sig = np.sqrt(np.diag(basis @ cov[:3, :3] @ basis.T))
    np.testing.assert_allclose(sig, [acc.radial, acc.along_track, acc.cross_track], rtol=1e-9)
    assert np.linalg.eigvalsh(cov).min() > -1e-9 * np.abs(cov).max()
    np.testing.assert_allclose(obj.covariance, cov)


@pytest.mark.parametrize("radial", [200.0, 400.0, 600.0, 1500.0])
def test_tle_covariance_is_a_covariance_for_any_accuracy(radial):
    # A radial error implies an along-track oscillation (2 A sin nt, Clohessy-Wiltshire)
    # with twice the radial amplitude; an along-track accuracy below it (here 1 km against
    # 600 m and 1.5 km radial) must still give a positive semi-definite matrix, with the
    # stated radial and cross-track RMS and at least the stated along-track one.
    state = rp.OrbitState("2023-08-13T00:00", [6_878e3, 0.0, 0.0], [0.0, 4_730.0, 5_965.0])
    acc = TleAccuracy(radial, 1000.0, 300.0, 1000.0 / 86400.0, "test")
    cov = tle_covariance(state, acc)
    assert np.linalg.eigvalsh(cov).min() > -1e-9 * np.abs(cov).max()
    basis = rtn_basis(state.position, state.velocity)
    sig = np.sqrt(np.diag(basis @ cov[:3, :3] @ basis.T))
    np.testing.assert_allclose(sig[[0, 2]], [radial, 300.0], rtol=1e-9)
    assert sig[1] >= 1000.0 * (1 - 1e-9)


def _drift_rate(state: rp.OrbitState, cov: np.ndarray) -> float:
    """RMS along-track drift rate (m/s) a 6x6 inertial covariance implies, by
    Clohessy-Wiltshire: the secular along-track rate is -1.5 n x_c with the radial offset
    x_c = 4 x + 2 ydot / n (x radial, ydot along-track rate, both in the rotating frame)."""
    r, v = state.position, state.velocity
    n = float(np.linalg.norm(np.cross(r, v))) / float(r @ r)
    basis = rtn_basis(r, v)
    rtn = np.zeros((6, 6))
    rtn[:3, :3] = rtn[3:, 3:] = basis
    # Inertial rates seen from the frame turning at n about N: xdot + n y, ydot - n x.
    turn = np.eye(6)
    turn[3, 1], turn[4, 0] = n, -n
    rot = turn @ rtn @ cov @ rtn.T @ turn.T
    x_c = np.array([4.0, 0.0, 0.0, 0.0, 2.0 / n, 0.0])
    return 1.5 * n * float(np.sqrt(x_c @ rot @ x_c))


def test_a_fitted_leo_state_starts_with_less_of_the_regime_drift(tle_file, atmosphere):
    # The regime's drift is SGP4's own error growth; a state fitted to a day of SGP4's
    # positions starts with at most FITTED_DRIFT_RATE in LEO (the rest of the growth is
    # the density's, which the propagation carries). Checked on the matrices by the
    # Clohessy-Wiltshire relation between the radial offset and the along-track drift.
    from rhoprop.catalog.covariance import FITTED_DRIFT_RATE, fitted_accuracy

    raw = catalog.load(tle_file, errors="record")[0]
    acc = tle_accuracy(raw.state)
    assert acc.regime == "LEO below 800 km" and acc.drift_rate > FITTED_DRIFT_RATE
    assert _drift_rate(raw.state, raw.covariance) == pytest.approx(acc.drift_rate, rel=1e-6)
    fitted = catalog.load(tle_file, fit=catalog.FitSettings(atmosphere), errors="record")[0]
    assert fitted.fit is not None
    own = fitted.covariance - fitted.fit.covariance[:6, :6]
    assert _drift_rate(fitted.state, own) == pytest.approx(FITTED_DRIFT_RATE, rel=1e-6)
    assert "drift 0.3 km/day" in fitted.covariance_note
    # Full rank: the semi-major-axis error that is left keeps the matrix positive definite.
    scale = np.sqrt(np.diag(own))
    assert np.linalg.eigvalsh(own / np.outer(scale, scale)).min() > 1e-9
    # Where drag does not set the growth (GEO) a fitted state keeps it all; a regime
    # drift already below the rate stays as it is.
    geo = TleAccuracy(2000.0, 5000.0, 2000.0, 6e3 / 86400, "GEO")
    assert fitted_accuracy(geo) == geo
    slow = TleAccuracy(150.0, 600.0, 250.0, 0.5 * FITTED_DRIFT_RATE, "LEO 800-2000 km")
    assert fitted_accuracy(slow) == slow


def test_initial_covariance_choices_and_notes(tmp_path, atmosphere):
    cat = catalog.load(SAMPLE)
    end = "2002-09-08T00:00"
    # Cd*A/m uncertainty off: it would hide the initial covariance being compared here.
    quiet = rp.Execution(progress=False)

    def run(**kw):
        initial = rp.catalog.Initial(drag_sigma=0.0, **kw)
        return catalog.propagate_catalog(
            cat, atmosphere, end, output_step=21600.0, initial=initial, execution=quiet
        )

    paper = run(covariance="paper")
    default = run()  # "object"
    tle = run(covariance="tle")
    own = run(covariance="object")
    np.testing.assert_array_equal(tle.covariance, own.covariance)
    np.testing.assert_array_equal(default.covariance, own.covariance)
    ok = paper.valid[:, -1] & tle.valid[:, -1]
    # Position variance only grows; where density adds little it grows a hundredfold.
    var_tle = np.trace(tle.covariance[ok, -1, :3, :3], axis1=1, axis2=2)
    var_paper = np.trace(paper.covariance[ok, -1, :3, :3], axis1=1, axis2=2)
    assert (var_tle > var_paper).all() and (var_tle > 100 * var_paper).any()
    assert "near-zero" in paper.covariance_note[0]
    assert "TLE accuracy" in tle.covariance_note[0] and "not included" in tle.covariance_note[0]
    matrix = np.diag([1e4, 1e4, 1e4, 1.0, 1.0, 1.0])
    user = run(covariance=matrix)
    assert "user-supplied" in user.covariance_note[0]
    with pytest.raises(ValueError, match="initial_covariance"):
        run(covariance="huge")
    paths = rp.io.write_oem(tle, tmp_path / "oem")
    assert "COMMENT initial covariance: published TLE accuracy" in paths[0].read_text()
    table = catalog.summary_table(tle)
    assert all("TLE accuracy" in t for t in table["covariance_includes"])


def test_cli_catalog_fit_and_initial_covariance(tmp_path, tle_file):
    out = tmp_path / "run"
    code = main(
        [
            "catalog",
            str(tle_file),
            "--end",
            "2002-09-08T00:00Z",
            "--out",
            str(out),
            "--model",
            "exponential",
            "--fit",
            "--output-step",
            "21600",
            "--oem",
        ]
    )
    assert code == 0
    assert "fit to SGP4" in (out / "oem" / "91002.oem").read_text()
    matrix = tmp_path / "cov.txt"
    np.savetxt(matrix, np.eye(6))
    code = main(
        [
            "catalog",
            str(SAMPLE),
            "--end",
            "2002-09-08T00:00Z",
            "--out",
            str(tmp_path / "run2"),
            "--model",
            "exponential",
            "--initial-covariance",
            str(matrix),
            "--oem",
        ]
    )
    assert code == 0
    assert "user-supplied" in next((tmp_path / "run2" / "oem").iterdir()).read_text()
    bad = main(["catalog", str(SAMPLE), "--end", "2002-09-08T00:00Z", "--out",
                str(tmp_path / "run3"), "--initial-covariance", "nonsense"])  # fmt: skip
    assert bad == 1


def test_fit_with_sgp4s_own_zonals_matches_sgp4(atmosphere):
    # SGP4 (the pseudo-observations) models J2, J3 and J4: a fit with the same zonal
    # harmonics follows it to metres, a J2-only fit to hundreds of metres, and J5/J6,
    # which SGP4 lacks, make it worse again. The reference is SGP4 itself.
    obj = catalog.load(SAMPLE)[0]
    rms = {
        d: fit_element_set(
            obj,
            atmosphere,
            dynamics=rp.Dynamics(zonal_degree=d),
        ).rms_total
        for d in (2, 4, 6)
    }
    assert rms[4] < 20.0 and rms[2] > 10 * rms[4] and rms[6] > 2 * rms[4], rms
    fitted = catalog.load(
        SAMPLE,
        fit=rp.catalog.FitSettings(atmosphere, dynamics=rp.Dynamics(zonal_degree=4)),
    )
    assert fitted[0].fit.rms_total == pytest.approx(rms[4], rel=1e-6)
    with pytest.raises(ValueError, match="zonal_degree"):
        catalog.load(
            SAMPLE, fit=rp.catalog.FitSettings(atmosphere, dynamics=rp.Dynamics(zonal_degree=7))
        )


def test_tle_covariance_near_the_apogee_of_an_eccentric_orbit_has_full_rank(test_data, tmp_path):
    # 57045 NUSANTARA TIGA (e = 0.78) as published on 2023-07-04, near apogee at its epoch:
    # the drift alone took the whole radial variance, the covariance had rank 4 and the
    # CCSP's factorisation failed ("not positive definite", smallest eigenvalue -8.7e-11).
    import gzip

    src = test_data / "catalogs" / "history" / "celestrak_active_20230704.txt.gz"
    lines = gzip.decompress(src.read_bytes()).decode().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("1 57045U"))
    one = tmp_path / "57045.tle"
    one.write_text("\n".join(lines[k - 1 : k + 2]) + "\n")
    obj = catalog.load(one)[0]
    acc = tle_accuracy(obj.state)
    assert acc.regime == "eccentric"
    cov = tle_covariance(obj.state)
    sd = np.sqrt(np.diag(cov))
    # Full rank at the scale of each component (rank 4 gave 1e-17).
    assert np.linalg.eigvalsh(cov / np.outer(sd, sd)).min() > 1e-4
    # Eccentric orbits: the regime's in-plane errors along and across the velocity
    # (tests/test_eccentric.py; R and T on a circular orbit).
    along = obj.state.velocity / np.linalg.norm(obj.state.velocity)
    normal = np.cross(obj.state.position, obj.state.velocity)
    normal /= np.linalg.norm(normal)
    basis = np.array([np.cross(along, normal), along, normal])
    sig = np.sqrt(np.diag(basis @ cov[:3, :3] @ basis.T))
    np.testing.assert_allclose(sig, [acc.radial, acc.along_track, acc.cross_track], rtol=1e-6)
    r = catalog.propagate_catalog(
        [obj],
        rp.scenarios.benchmark_exponential(0.2),
        "2023-06-30T13:00",
        execution=rp.Execution(progress=False),
    )
    assert list(r.status) == ["propagated"]


def test_a_fitted_drag_far_from_its_b_star_prior_is_not_taken_for_drag(tle_file, atmosphere):
    # A manoeuvring satellite's fit took its thrust for drag: 6.9 m^2/kg (a real Starlink,
    # B* > 0) was accepted and propagated. Beyond 10x its B* prior, or pinned at the
    # floor, a fit now counts as failed and the element set runs unfitted.
    import dataclasses

    from rhoprop.catalog.elements import _fitted

    obj = catalog.load(tle_file, errors="record")[0]
    assert obj.bstar > 0
    f = fit_element_set(obj, atmosphere)
    window = (-86400.0, 0.0)
    assert isinstance(_fitted(obj, f, window), catalog.CatalogObject)
    for value in (6.9, 1e-4, f.prior / 11):
        err = _fitted(obj, dataclasses.replace(f, drag_parameter=value), window)
        assert isinstance(err, ValueError) and "not drag" in str(err), value


def test_a_fit_with_no_more_observations_than_unknowns_is_no_linear_algebra_error(
    tle_file, atmosphere
):
    # Two positions (six numbers) for seven unknowns: the fit is exact, its residual
    # scale is 0 and once divided the information matrix into infinities (numpy's
    # "SVD did not converge" out of a whole catalog load). The scale is then 1: the
    # covariance is the observations' and the prior's.
    obj = catalog.load(tle_file, errors="record")[0]
    f = fit_element_set(obj, atmosphere, span=(-600.0, 0.0))
    assert len(f.times) == 2
    assert np.all(np.isfinite(f.covariance)) and 0 < f.drag_sigma <= f.prior_sigma * (1 + 1e-9)


def test_a_meo_fit_follows_its_along_track_debiasing_one_to_one(atmosphere):
    # TLE debiasing moves every SGP4 position of the span back along-track by the bias;
    # in a near-circular orbit that is a rotation within the orbit's plane, which the
    # dynamics follow, so the fitted state moves by the same distance and nothing else.
    sat = Satrec.twoline2rv(*_tle(91010, 20200.0, 0.0))
    raw = fit_element_set(sat, atmosphere, along_track_bias={})
    moved = fit_element_set(sat, atmosphere, along_track_bias={"MEO": 300.0})
    default = fit_element_set(sat, atmosphere)
    assert (raw.along_track_bias, moved.along_track_bias) == (0.0, 300.0)
    assert default.along_track_bias == catalog.fit.ALONG_TRACK_BIAS["MEO"] != 0.0
    shift = rtn_basis(raw.state.position, raw.state.velocity) @ (
        moved.state.position - raw.state.position
    )
    assert shift == pytest.approx([0.0, -300.0, 0.0], abs=1.0)  # m, RTN (0.2 m apart)
    # LEO element sets carry none by default, nor near-Earth (SGP4) ones of the MEO
    # regime (perigee above 2,000 km, period under 225 min): it was measured on SDP4's
    leo = fit_element_set(Satrec.twoline2rv(*_tle(91011, 420.0, 3e-4)), atmosphere)
    low_meo = fit_element_set(Satrec.twoline2rv(*_tle(91013, 3000.0, 0.0)), atmosphere)
    assert tle_accuracy(low_meo.state).regime == "MEO"
    assert leo.along_track_bias == low_meo.along_track_bias == 0.0


@pytest.mark.parametrize(
    ("table", "error", "match"),
    [
        ({"LEO": 100.0}, ValueError, "unknown regime 'LEO'; the regimes are"),
        ({"MEO": float("nan")}, ValueError, r"along_track_bias\['MEO'\] must be a finite"),
        ({"MEO": "500"}, ValueError, "finite number of metres"),
        ([("MEO", 500.0)], TypeError, "must be a mapping of regime name to metres, got list"),
    ],
)
def test_along_track_bias_is_checked_where_given(atmosphere, table, error, match):
    with pytest.raises(error, match=match):
        catalog.FitSettings(atmosphere, along_track_bias=table)
    with pytest.raises(error, match=match):
        fit_element_set(
            Satrec.twoline2rv(*_tle(91012, 20200.0, 0.0)), atmosphere, along_track_bias=table
        )


def test_fit_settings_stay_hashable_with_their_along_track_bias(atmosphere):
    mine = catalog.FitSettings(atmosphere, along_track_bias={"GEO": -100})
    assert mine.along_track_bias == {"GEO": -100.0}
    assert catalog.FitSettings(atmosphere).along_track_bias == catalog.fit.ALONG_TRACK_BIAS
    assert len({mine, catalog.FitSettings(atmosphere)}) == 2  # hashable; unequal
