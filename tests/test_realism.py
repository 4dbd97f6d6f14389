"""A small real-data check of catalog realism (the full measurement is
``benches/catalog_realism.py``): four LEO objects of the CelesTrak snapshot of 2023-11-13,
fitted (``load(fit=True)``) and propagated with the CCSP through NRLMSIS 2.1 to the epochs
of their element sets of 2023-11-19; the fitted mean is compared with SGP4."""

from __future__ import annotations

import gzip

import numpy as np
import pytest
from sgp4.api import Satrec

import rhoprop as rp
from rhoprop import catalog
from rhoprop.density import Msis
from rhoprop.frames import rtn_basis

# Non-manoeuvring objects below 700 km (HJ-2A, STRIX-1, TIANHUI 5B, DUCHIFAT-1).
IDS = (46478, 53815, 58201, 40021)


def _tles(path, ids):
    lines = [ln.rstrip() for ln in gzip.open(path, "rt") if ln.strip()]
    out = {}
    for k in range(0, len(lines) - 2, 3):
        norad = int(lines[k + 1][2:7])
        if norad in ids:
            out[norad] = lines[k : k + 3]
    return out


@pytest.fixture(scope="module")
def snapshots(test_data):
    folder = test_data / "catalogs"
    first = _tles(folder / "celestrak_active_20231113.txt.gz", IDS)
    second = _tles(folder / "celestrak_active_20231119.txt.gz", IDS)
    assert set(first) == set(second) == set(IDS)
    return first, second


def test_fitted_mean_beats_sgp4_and_covariance_is_stated(tmp_path, snapshots):
    first, second = snapshots
    path = tmp_path / "four.tle"
    path.write_text("".join("\n".join(first[i]) + "\n" for i in IDS))
    field = Msis("2.1").field("2023-11-11", "2023-11-20", altitude_range=(300e3, 750e3))
    cat = catalog.load(
        path,
        fit=rp.catalog.FitSettings(field),
    )
    assert all(o.fit is not None and o.fit.converged for o in cat)
    assert all(o.fit.rms_total < 1500 for o in cat)  # m, over two days
    ours, theirs = [], []
    for obj in cat:
        s1 = Satrec.twoline2rv(*first[obj.norad_id][1:])
        s2 = Satrec.twoline2rv(*second[obj.norad_id][1:])
        end = rp.time.from_jd(s2.jdsatepoch, s2.jdsatepochF)
        _, r2, v2 = s2.sgp4(s2.jdsatepoch, s2.jdsatepochF)
        _, r1, _ = s1.sgp4(s2.jdsatepoch, s2.jdsatepochF)
        truth, vel = np.array(r2) * 1e3, np.array(v2) * 1e3
        res = catalog.propagate_catalog(
            [obj],
            field,
            end,
            output_step=1e9,
            initial=rp.catalog.Initial(covariance="object"),
            execution=rp.Execution(progress=False),
        )
        assert res.valid[0, -1] and "TLE accuracy" in res.covariance_note[0]
        along = rtn_basis(truth, vel)[1]
        ours.append(abs(along @ (res.mean[0, -1, :3] - truth)))
        theirs.append(abs(along @ (np.array(r1) * 1e3 - truth)))
    assert np.median(ours) < np.median(theirs)
    assert max(ours) < 50e3
