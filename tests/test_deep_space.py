"""Deep-space orbits (period >= 225 min): the Sun's and the Moon's pull and the tesseral
field in the dynamics, and their fit by default, judged against the next published element sets of
real GEO and GPS objects (CelesTrak 2023-11-13 -> 2023-11-19)."""

from __future__ import annotations

import gzip
import warnings

import numpy as np
import pytest
from sgp4.api import Satrec

import rhoprop as rp
from rhoprop import catalog
from rhoprop.catalog.objects import fit_choice


def _snapshot(path) -> dict[int, tuple[str, str, str]]:
    lines = gzip.decompress(path.read_bytes()).decode().splitlines()
    out = {}
    for i in range(len(lines) - 2):
        if lines[i + 1].startswith("1 ") and lines[i + 2].startswith("2 "):
            out[int(lines[i + 1][2:7])] = (lines[i], lines[i + 1], lines[i + 2])
    return out


def _pairs(test_data, revs: tuple[float, float], count: int):
    first = _snapshot(test_data / "catalogs" / "celestrak_active_20231113.txt.gz")
    second = _snapshot(test_data / "catalogs" / "celestrak_active_20231119.txt.gz")
    picked = []
    for norad, sets in first.items():
        if norad not in second:
            continue
        sat = Satrec.twoline2rv(sets[1], sets[2])
        later = Satrec.twoline2rv(*second[norad][1:])
        rev = sat.no_kozai * 1440 / (2 * np.pi)
        gap = later.jdsatepoch + later.jdsatepochF - sat.jdsatepoch - sat.jdsatepochF
        if revs[0] < rev < revs[1] and sat.ecco < 0.02 and gap >= 3:
            picked.append((sets, later))
        if len(picked) == count:
            break
    return picked


@pytest.mark.parametrize(
    ("revs", "limit_km"),
    # Measured on 40 objects each: GEO 12.0 km since 2026-12-06, when GEO fits stopped
    # holding SDP4's radius and took three days either side (8.6 km before: closer to
    # these later element sets, which are SDP4's too, and 5x worse against precise
    # orbits, the test below; 13.4 with the single "above LEO" TLE accuracy weighting
    # the fit, 13.2 with C22/S22 alone, 15.3 with it 1.55x too strong, 20.6 km before
    # the deep-space forces), GPS 1.23 km (1.75 fitted over one day either side; 1.9;
    # 2.2; 2.3; 5.0 km before); SGP4 itself 8.1 and 1.0 km. On these 20: 12.8 (8.5
    # before) and 1.47 km. Debiased along-track since 2026-12-07: 11.95 and 1.02 km on
    # the 40 (these SDP4 truths share the lag the debiasing removes).
    [((0.99, 1.01), 15.0), ((1.9, 2.1), 3.5)],
    ids=["GEO", "GPS"],
)
def test_fitted_deep_space_orbits_reach_their_next_element_sets(
    test_data, tmp_path, revs, limit_km
):
    pairs = _pairs(test_data, revs, 20)
    assert len(pairs) == 20
    path = tmp_path / "deep.tle"
    path.write_text("".join("\n".join(sets) + "\n" for sets, _ in pairs))
    objs = list(catalog.load(path))
    assert all(fit_choice(o, "auto") for o in objs)  # deep space: fitted by default
    fitted = catalog.fit_objects(
        objs,
        rp.density.Msis("2.1"),
        dynamics=rp.Dynamics(zonal_degree=4),
    )
    errors = []
    for obj, (_, later) in zip(fitted, pairs, strict=True):
        assert not isinstance(obj, Exception), obj
        _, r, _ = later.sgp4(later.jdsatepoch, later.jdsatepochF)
        when = rp.time.from_jd(later.jdsatepoch, later.jdsatepochF, scale="utc")
        span = float((when - obj.state.epoch) / np.timedelta64(1, "s"))
        run = rp.propagate(
            obj.state,
            rp.Spacecraft(1.0, obj.drag_parameter),
            rp.scenarios.benchmark_exponential(0.0),
            span,
            dynamics=rp.Dynamics(zonal_degree=4, integrator="rk8", step=600.0),
        )
        errors.append(np.linalg.norm(run.positions[-1] - np.array(r) * 1e3) / 1e3)
    assert np.median(errors) < limit_km, np.median(errors)


@pytest.mark.parametrize("revs", [(0.99, 1.01), (1.9, 2.1)], ids=["GEO", "GPS"])
def test_deep_space_covariance_covers_the_next_element_sets(test_data, tmp_path, revs):
    # propagate_catalog with its defaults (fit, the regime's TLE covariance, CCSP) to each
    # later element set's epoch; the truth's own TLE covariance added. The regimes were
    # chosen on the four development weeks (docs/catalog-realism.md, "Deep-space
    # covariance"); before, one "above LEO" regime held 55 % of these GEO errors inside
    # 2 sigma (too narrow) and 100 % of the GPS ones inside 1 sigma (too wide). With 20
    # objects a fraction is good to about 10 points: at least 75 % inside 2 sigma (goal
    # 85 %), at most 95 % inside 1 sigma (68 % for a Gaussian; manoeuvres add tails).
    from rhoprop.catalog.covariance import tle_covariance
    from rhoprop.frames import rtn_basis

    pairs = _pairs(test_data, revs, 20)
    path = tmp_path / "deep.tle"
    path.write_text("".join("\n".join(sets) + "\n" for sets, _ in pairs))
    z = []
    for obj, (_, later) in zip(catalog.load(path), pairs, strict=True):
        when = rp.time.from_jd(later.jdsatepoch, later.jdsatepochF, scale="utc")
        _, r, v = later.sgp4(later.jdsatepoch, later.jdsatepochF)
        truth = rp.OrbitState(when, np.array(r) * 1e3, np.array(v) * 1e3)
        res = catalog.propagate_catalog(
            [obj],
            rp.density.Msis("2.1"),
            when,
            execution=rp.Execution(progress=False),
        )
        assert list(res.status) == ["propagated"]
        mean = res.mean[0, -1]
        cov = res.covariance[0, -1, :3, :3] + tle_covariance(truth)[:3, :3]
        along = rtn_basis(mean[:3], mean[3:])[1]
        sigma = float(np.sqrt(along @ cov @ along))
        z.append(abs(float(along @ (truth.position - mean[:3]))) / sigma)
    z = np.array(z)
    assert np.mean(z < 2) >= 0.75 and np.mean(z < 1) <= 0.95, (np.mean(z < 1), np.mean(z < 2))


GNSS_START = np.datetime64("2024-06-17T00:00", "ns")
BEIDOU_GEO = ("C01", "C02", "C03", "C04", "C05", "C59", "C60", "C62")


def _beidou_runs(test_data, tmp_path, kind: str, hours: list[int], bias=None):
    """The BeiDou satellites of ``kind`` ("GEO": the geostationary ones, "MEO"), each
    from its newest element set before 2024-06-17 (as benches/precise_gnss.py), fitted
    (``along_track_bias=bias``, None: the library's) and run with the library's defaults
    to GPS ``hours`` after it, against GFZ's precise orbits (GPS time, Earth-fixed; to
    GCRS with astropy): per satellite, rhoprop's and SDP4's RTN errors (hours, 3), m."""
    coordinates = pytest.importorskip("astropy.coordinates")
    astropy_time = pytest.importorskip("astropy.time")
    units = pytest.importorskip("astropy.units")
    from astropy.utils import iers

    iers.conf.auto_download = False
    gnss = test_data / "precise_orbits/gnss"
    ends = [GNSS_START + np.timedelta64(h, "h") - np.timedelta64(18, "s") for h in hours]
    lines = (gnss / "beidou_tles_trackthatsatellite_20240617.txt").read_text().splitlines()
    newest: dict[str, tuple[float, str]] = {}
    for name, l1, l2 in zip(lines[0::3], lines[1::3], lines[2::3], strict=True):
        prn = name[name.find("(C") + 1 : name.find("(C") + 4] if "(C" in name else ""
        meo = prn and prn not in BEIDOU_GEO and "IGSO" not in name and prn != "C38"
        sat = Satrec.twoline2rv(l1, l2)
        epoch = rp.time.from_jd(sat.jdsatepoch, sat.jdsatepochF, scale="utc")
        if (
            (prn in BEIDOU_GEO if kind == "GEO" else meo)
            and epoch < GNSS_START
            and (prn not in newest or newest[prn][0] < sat.jdsatepoch + sat.jdsatepochF)
        ):
            newest[prn] = (sat.jdsatepoch + sat.jdsatepochF, f"{name}\n{l1}\n{l2}\n")
    days = [rp.io.read_sp3(gnss / f"GBM0MGXRAP_2024{d}0000_01D_05M_ORB_SP3.gz") for d in (169, 170)]
    epochs = np.concatenate([d.epochs for d in days])  # read_sp3 gives UTC epochs
    positions = {
        p: np.concatenate([d.positions[p] for d in days])
        for p in newest
        if all(p in d.positions for d in days)
    }
    at = [int(np.flatnonzero(epochs == end)[0]) for end in ends]
    prns = [p for p in sorted(positions) if np.isfinite(positions[p][at]).all()]
    path = tmp_path / f"{kind}.tle"
    path.write_text("".join(newest[p][1] for p in prns))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rp.errors.PredictedDriversWarning)
        model = rp.density.Msis("2.1", space_weather=rp.SpaceWeather().as_of(GNSS_START))
        cat = catalog.load(path, fit=catalog.FitSettings(model, along_track_bias=bias))
        res = catalog.propagate_catalog(
            cat, model, ends[-1], output_step=3600.0, execution=rp.Execution(progress=False)
        )
    out = {}
    for i, prn in enumerate(prns):
        ours, sdp4 = [], []
        for end, k in zip(ends, at, strict=True):
            t = astropy_time.Time(str(end), scale="utc")
            itrs = coordinates.ITRS(
                coordinates.CartesianRepresentation(positions[prn][k] * units.m), obstime=t
            )
            true = np.asarray(
                itrs.transform_to(coordinates.GCRS(obstime=t)).cartesian.xyz.to_value(units.m)
            )
            # the run's axes are the TEME of the object's epoch
            j = int(np.argmin(np.abs(res.epochs - end)))
            assert res.epochs[j] == end
            mine = rp.frames.teme_to_gcrf(cat[i].state.epoch, res.mean[i, j])
            sat = Satrec.twoline2rv(*newest[prn][1].splitlines()[1:])
            whole = float(np.floor(t.jd))
            _, r, v = sat.sgp4(whole, t.jd - whole)
            theirs = rp.frames.teme_to_gcrf(end, np.concatenate([r, v]) * 1e3)
            basis = rp.frames.rtn_basis(true, theirs[3:])
            ours.append(basis @ (mine[:3] - true))
            sdp4.append(basis @ (theirs[:3] - true))
        out[prn] = (np.array(ours), np.array(sdp4))
    return out


def test_geostationary_fits_follow_their_period_against_precise_orbits(test_data, tmp_path):
    # Fitted to SDP4's radius (the fit's weights before 2026-12-06) they ran ahead by
    # about 1.3 km a day: 2.72 km after 47 h against SDP4's 2.18; weighting the radius
    # as the along-track position, over three days either side, 0.51 km (7 satellites;
    # 0.59 km debiased). The median at 47 h must stay under half SDP4's.
    runs = _beidou_runs(test_data, tmp_path, "GEO", [47])
    assert len(runs) >= 6, sorted(runs)
    ours = [np.linalg.norm(o[-1]) for o, _ in runs.values()]
    sdp4 = [np.linalg.norm(t[-1]) for _, t in runs.values()]
    assert np.median(ours) < 0.5 * np.median(sdp4), (np.median(ours), np.median(sdp4))


def test_meo_element_sets_are_debiased_along_track_against_precise_orbits(test_data, tmp_path):
    # SDP4 lags BeiDou's precise MEO orbits by about 0.6 km along-track, and fits to it
    # by about 0.5 km (rp.catalog.fit.ALONG_TRACK_BIAS; benches/precise_gnss.py). With
    # the library's debiasing the fitted predictions' median along-track error at 6, 24
    # and 47 h is within 250 m of zero (-0.18 km measured, -0.67 km without; the
    # satellites scatter by 0.5 km, so the median of 27 is known to about 0.12 km) and
    # their median position error at most 0.8 of the undebiased fits' (0.44 against
    # 0.69 km measured).
    hours = [6, 24, 47]
    debiased = _beidou_runs(test_data, tmp_path, "MEO", hours)
    raw = _beidou_runs(test_data, tmp_path, "MEO", hours, bias={})
    assert len(debiased) >= 25, sorted(debiased)
    along = np.median([o[:, 1] for o, _ in debiased.values()])
    along_raw = np.median([o[:, 1] for o, _ in raw.values()])
    assert abs(along) < 250.0 and along_raw < -400.0, (along, along_raw)
    error = np.median([np.linalg.norm(o, axis=1) for o, _ in debiased.values()])
    error_raw = np.median([np.linalg.norm(o, axis=1) for o, _ in raw.values()])
    assert error < 0.8 * error_raw, (error, error_raw)
