"""Solar radiation pressure (``Spacecraft(cr=...)``) against an independent integration:
scipy's DOP853 of two-body + J2 + a cannonball pushed by the Sun's light (the Sun from
astropy, its shadow computed here from the two discs' geometry), in TEME axes, the axes
rhoprop integrates a TEME state in. Compared: the displacement radiation pressure causes
(with minus without), which takes out what the two integrations share."""

from __future__ import annotations

import numpy as np
import pytest

import rhoprop as rp
from rhoprop.constants import J2, MU, R_EARTH

scipy_integrate = pytest.importorskip("scipy.integrate")
coordinates = pytest.importorskip("astropy.coordinates")
astropy_time = pytest.importorskip("astropy.time")
units = pytest.importorskip("astropy.units")

P_SUN = 4.56e-6  # N/m^2 at 1 AU (Montenbruck & Gill eq. 3.69)
AU = 1.495978707e11
R_SUN = 6.96e8


def _sun_teme(epoch: np.datetime64, span: float) -> tuple[np.ndarray, np.ndarray]:
    """Hourly geocentric Sun positions (m) in TEME from astropy, over ``span`` s."""
    t = np.arange(0.0, span + 3600.0, 3600.0)
    when = astropy_time.Time(str(epoch), scale="utc") + t * units.s
    sun = coordinates.get_body("sun", when)
    teme = sun.transform_to(coordinates.TEME(obstime=when))
    return t, np.asarray(teme.cartesian.xyz.to_value(units.m)).T


def _lit(r: np.ndarray, sun: np.ndarray) -> float:
    """Share of the Sun's disc seen from ``r``: 1 - the overlap of the Earth's and the
    Sun's apparent discs over the Sun's (circular segments, not a lookup)."""
    to_sun = sun - r
    ds, dr = np.linalg.norm(to_sun), np.linalg.norm(r)
    a, b = np.arcsin(R_SUN / ds), np.arcsin(R_EARTH / dr)
    c = np.arccos(np.clip(np.dot(-r, to_sun) / (dr * ds), -1.0, 1.0))
    if c >= a + b:
        return 1.0
    if c <= b - a:
        return 0.0
    # Segments of the two circles cut by their common chord.
    alpha = np.arccos(np.clip((a * a + c * c - b * b) / (2 * a * c), -1, 1))
    beta = np.arccos(np.clip((b * b + c * c - a * a) / (2 * b * c), -1, 1))
    overlap = a * a * (alpha - np.sin(2 * alpha) / 2) + b * b * (beta - np.sin(2 * beta) / 2)
    return 1.0 - overlap / (np.pi * a * a)


def _reference(state: np.ndarray, epoch, span: float, cr_am: float, shadow: bool = True):
    """Positions (m) every 600 s: two-body + J2 about TEME's z + radiation pressure."""
    hours, suns = _sun_teme(epoch, span)

    def sun_at(t: float) -> np.ndarray:
        return np.array([np.interp(t, hours, suns[:, k]) for k in range(3)])

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        r = y[:3]
        rn = np.linalg.norm(r)
        z2 = (r[2] / rn) ** 2
        k = 1.5 * J2 * MU * R_EARTH**2 / rn**5
        acc = -MU * r / rn**3 + k * r * np.array([5 * z2 - 1, 5 * z2 - 1, 5 * z2 - 3])
        if cr_am:
            s = sun_at(t)
            away = r - s
            d = np.linalg.norm(away)
            nu = _lit(r, s) if shadow else 1.0
            acc = acc + nu * P_SUN * cr_am * (AU / d) ** 2 * away / d
        return np.concatenate([y[3:], acc])

    t = np.arange(0.0, span + 1.0, 600.0)
    out = scipy_integrate.solve_ivp(
        rhs, (0.0, span), state, method="DOP853", t_eval=t, rtol=1e-12, atol=1e-6, max_step=60.0
    )
    assert out.success
    return out.y[:3].T


def _rhoprop(state: np.ndarray, epoch, span: float, area_to_mass: float, cr: float | None):
    start = rp.OrbitState(epoch, state[:3], state[3:], frame="TEME")
    run = rp.propagate(
        start,
        rp.Spacecraft(1.0, area_to_mass, cr=cr),
        rp.scenarios.benchmark_exponential(0.0),  # no drag above 1,000 km
        span,
        dynamics=rp.Dynamics(field_degree=0, third_bodies=False, integrator="dop853"),
        output_step=600.0,
    )
    return run.positions


@pytest.mark.parametrize(
    ("name", "state", "epoch", "days", "area_to_mass", "cr"),
    [
        # A geostationary satellite in June (no eclipses): the eccentricity drift.
        (
            "GEO",
            [42_164e3, 0.0, 0.0, 0.0, 3_074.66, 0.0],
            "2024-06-17T00:00",
            3.0,
            0.02,
            1.5,
        ),
        # High area-to-mass debris at 1,500 km through the Earth's shadow every orbit.
        (
            "eclipsing",
            [7_878e3, 0.0, 0.0, 0.0, 4_912.0, 5_162.0],
            "2024-03-20T00:00",
            1.0,
            1.0,
            1.2,
        ),
    ],
)
def test_radiation_pressure_displaces_as_an_independent_integration(
    name, state, epoch, days, area_to_mass, cr
):
    state = np.array(state)
    epoch = np.datetime64(epoch, "ns")
    span = days * 86400.0
    moved = _rhoprop(state, epoch, span, area_to_mass, cr) - _rhoprop(
        state, epoch, span, area_to_mass, None
    )
    cr_am = cr * area_to_mass
    want = _reference(state, epoch, span, cr_am) - _reference(state, epoch, span, 0.0)
    size = np.linalg.norm(want, axis=1).max()
    # Measured: GEO displaced 1.2 km, rhoprop within 0.3 m of the reference; eclipsing
    # 2.3 km, within 1.6 m (147 m before DOP853 retook steps across the shadow's edges).
    # The tolerance, 0.5 % of the displacement, holds the two Sun ephemerides' arcminute
    # (3e-4 rad) and their shadow edges seconds apart.
    assert size > {"GEO": 1000.0, "eclipsing": 2000.0}[name]
    miss = np.linalg.norm(moved - want, axis=1).max()
    assert miss < 5e-3 * size, f"{name}: {miss:.1f} m off a displacement of {size:.0f} m"
    if name == "eclipsing":
        # The shadow is in: without it the reference is displaced differently by far more.
        lit = _reference(state, epoch, span, cr_am, shadow=False) - _reference(
            state, epoch, span, 0.0
        )
        assert np.linalg.norm(lit - want, axis=1).max() > 20 * miss


def test_without_cr_runs_are_unchanged_and_bad_cr_is_refused():
    sc = rp.Spacecraft(2.2, 0.01)
    assert sc.cr is None and sc.radiation_parameter == 0.0
    assert rp.Spacecraft(2.2, 0.01, cr=1.3).radiation_parameter == pytest.approx(0.013)
    for bad, error, text in [
        (-0.1, ValueError, "cr = -0.1 is out of range"),
        (5.5, ValueError, "must be 0 to 5"),
        (float("nan"), ValueError, "cr must be finite"),
        ("1.3", TypeError, "cr must be a real number"),
    ]:
        with pytest.raises(error, match=text):
            rp.Spacecraft(2.2, 0.01, cr=bad)
    # cr = 0 is no push at all: the same numbers as without cr, to the bit.
    state = np.array([42_164e3, 0.0, 0.0, 0.0, 3_074.66, 0.0])
    epoch = np.datetime64("2024-06-17T00:00", "ns")
    np.testing.assert_array_equal(
        _rhoprop(state, epoch, 86400.0, 0.02, 0.0), _rhoprop(state, epoch, 86400.0, 0.02, None)
    )
