"""The PCA reduced-order model (HASDM-ML-DP output form): closed-form lognormal moments
against the paper's coefficient-sampling Monte Carlo, exact values at grid nodes, the
local-solar-time mapping, errors and sampling into a field."""

from __future__ import annotations

import numpy as np
import pytest

from rhoprop.density.field import FieldResolution
from rhoprop.density.pcarom import PcaRom

LN10 = np.log(10.0)
LST = np.arange(24.0)
LAT = np.linspace(-90.0, 90.0, 7)
ALT = np.arange(300e3, 501e3, 50e3)
EPOCHS = np.arange(
    np.datetime64("2002-09-07T00:00"), np.datetime64("2002-09-07T13:00"), np.timedelta64(3, "h")
).astype("datetime64[ns]")


def synthetic(rank: int = 3, *, zero_std: bool = False, **kwargs) -> PcaRom:
    """A 24 LST x 7 lat x 5 alt ROM: log10 density about -11.5 at 400 km with a 60 km scale
    height and a diurnal bulge at 15 h LST; ``rank`` orthonormal modes from QR of a seeded
    random mix of smooth functions (smooth, so a sampled field interpolates them well);
    coefficient means ~ N(0, 3^2), standard deviations in [0.5, 2]."""
    rng = np.random.default_rng(42)
    lst, lat, alt = np.meshgrid(LST, LAT, ALT, indexing="ij")
    mean = -11.5 - (alt - 400e3) / (60e3 * LN10) + 0.15 * np.cos(2 * np.pi * (lst - 15) / 24)
    smooth = np.stack(
        [
            np.cos(2 * np.pi * lst / 24),
            np.sin(2 * np.pi * lst / 24),
            np.cos(np.radians(lat)),
            np.sin(np.radians(lat)),
            (alt - 400e3) / 100e3,
            np.ones_like(lst),
        ],
        axis=-1,
    ).reshape(-1, 6)
    q, _ = np.linalg.qr(smooth @ rng.standard_normal((6, rank)))
    modes = q.reshape(*mean.shape, rank)
    cm = rng.normal(0.0, 3.0, (len(EPOCHS), rank))
    cs = np.zeros_like(cm) if zero_std else rng.uniform(0.5, 2.0, cm.shape)
    return PcaRom(LST, LAT, ALT, mean, modes, EPOCHS, cm, cs, **kwargs)


def test_modes_are_orthonormal():
    u = synthetic().modes.reshape(-1, 3)
    np.testing.assert_allclose(u.T @ u, np.eye(3), atol=1e-12)


def test_analytic_matches_coefficient_sampling():
    # Monte Carlo standard errors with N samples: mean std/sqrt(N); sample std
    # std sqrt((kurt - 1) / (4 N)) with kurt the (non-excess) kurtosis of the lognormal,
    # which is std/sqrt(2N) for a Gaussian (kurt = 3); both bounded at 4 standard errors.
    n = 20000
    t = np.array(["2002-09-07T01:30", "2002-09-07T04:10", "2002-09-07T11:59"], "datetime64[ns]")
    lat, lon, alt = np.array([-55.0, 12.0, 71.0]), np.array([-170.0, 33.0, 250.0]), 4.3e5
    analytic = synthetic()
    mean_a, std_a = analytic.mean_std(t, lat, lon, alt)
    mean_s, std_s = synthetic(method="sampling", samples=n, seed=7).mean_std(t, lat, lon, alt)
    _, s2 = analytic.log10_moments(t, lat, lon, alt)
    w = np.exp(LN10**2 * s2)
    kurt = w**4 + 2 * w**3 + 3 * w**2 - 3
    z_mean = (mean_s - mean_a) / (std_a / np.sqrt(n))
    z_std = (std_s - std_a) / (std_a * np.sqrt((kurt - 1) / (4 * n)))
    print(f"rel sigma {std_a / mean_a}; mean rel diff {mean_s / mean_a - 1}, z {z_mean}")
    print(f"std rel diff {std_s / std_a - 1}, z {z_std}")
    assert np.all(np.abs(z_mean) < 4)
    assert np.all(np.abs(z_std) < 4)
    # Seeded: the same draws on every call.
    again = synthetic(method="sampling", samples=n, seed=7).mean_std(t, lat, lon, alt)
    np.testing.assert_array_equal(again, (mean_s, std_s))


def test_zero_coefficient_std_gives_the_decoded_mean_at_a_node():
    rom = synthetic(zero_std=True)
    # EPOCHS[4] is 12:00 UTC, so lon 0 is LST 12 h: the node (LST 12, lat 30, alt 400 km).
    mean, std = rom.mean_std(EPOCHS[4], 30.0, 0.0, 400e3)
    expected = 10.0 ** (rom.mean_log10[12, 4, 2] + rom.modes[12, 4, 2] @ rom.coeff_mean[4])
    assert std == 0.0
    assert mean == pytest.approx(expected, rel=1e-13)


def test_one_mode_lognormal_moments_at_a_node():
    # Independent check by Gauss-Hermite quadrature of E[10^x], x = xbar + U alpha,
    # alpha ~ N(mu, sigma^2), with mu and sigma halfway between two epochs.
    rom = synthetic(rank=1)
    t = EPOCHS[1] + np.timedelta64(90, "m")  # 04:30 UTC, halfway between epochs 1 and 2
    lon = (8.0 - 4.5) * 15.0  # LST 8 h
    i_lst, i_lat, i_alt = 8, 1, 3
    mean, std = rom.mean_std(t, LAT[i_lat], lon, ALT[i_alt])
    mu = 0.5 * (rom.coeff_mean[1, 0] + rom.coeff_mean[2, 0])
    sigma = 0.5 * (rom.coeff_std[1, 0] + rom.coeff_std[2, 0])
    xbar, u = rom.mean_log10[i_lst, i_lat, i_alt], rom.modes[i_lst, i_lat, i_alt, 0]
    nodes, weights = np.polynomial.hermite_e.hermegauss(80)
    weights = weights / weights.sum()
    rho = 10.0 ** (xbar + u * (mu + sigma * nodes))
    q_mean = weights @ rho
    q_std = np.sqrt(weights @ (rho - q_mean) ** 2)
    assert mean == pytest.approx(q_mean, rel=1e-12)
    assert std == pytest.approx(q_std, rel=1e-10)
    # And the closed form as written in the class doc.
    m, s2 = xbar + u * mu, (u * sigma) ** 2
    assert mean == pytest.approx(np.exp(LN10 * m + LN10**2 * s2 / 2), rel=1e-13)
    assert std == pytest.approx(mean * np.sqrt(np.exp(LN10**2 * s2) - 1), rel=1e-12)


def test_local_solar_time_mapping_and_periodicity():
    rom = synthetic(zero_std=True)
    t = np.datetime64("2002-09-07T12:00")
    node = rom.mean_log10[:, 3, 1] + rom.modes[:, 3, 1] @ rom.coeff_mean[4]  # lat 0, 350 km
    # 12:00 UTC at lon 0 is LST 12; lon 90 E is LST 18; lon -90 is LST 6.
    for lon, lst in ((0.0, 12), (90.0, 18), (-90.0, 6), (165.0, 23), (180.0, 0)):
        mean, _ = rom.mean_std(t, 0.0, lon, 350e3)
        assert mean == pytest.approx(10.0 ** node[lst], rel=1e-13), lon
    # Across midnight LST (23.5 h) the interpolation wraps to the 0 h node.
    mean, _ = rom.mean_std(t, 0.0, 172.5, 350e3)
    assert mean == pytest.approx(10.0 ** (0.5 * (node[23] + node[0])), rel=1e-13)
    # Longitude is periodic.
    full = synthetic()
    times = np.array(["2002-09-07T03:17", "2002-09-07T10:42"], "datetime64[ns]")
    lon = np.array([-179.0, 37.3])
    a = full.mean_std(times, 20.0, lon, 410e3)
    for shift in (360.0, -360.0, 720.0):
        b = full.mean_std(times, 20.0, lon + shift, 410e3)
        np.testing.assert_allclose(b, a, rtol=1e-12)
    # The same LST reached from a different UTC hour gives the same mean grid value.
    a = rom.mean_std("2002-09-07T06:00", 0.0, 90.0, 350e3)[0]
    assert a == pytest.approx(
        10.0 ** (rom.mean_log10[12, 3, 1] + rom.modes[12, 3, 1] @ rom.coeff_mean[2]), rel=1e-13
    )


def test_out_of_range_and_bad_inputs():
    rom = synthetic()
    t = "2002-09-07T03:00"
    with pytest.raises(ValueError, match=r"alt = 600000 m is outside .*\[300000, 500000\] m"):
        rom.mean_std(t, 0.0, 0.0, 600e3)
    with pytest.raises(ValueError, match="alt = 250000 m is outside"):
        rom.mean_std(t, 0.0, 0.0, [400e3, 250e3])
    with pytest.raises(ValueError, match=r"time 2002-09-07T13:00.* outside .*epoch range"):
        rom.mean_std("2002-09-07T13:00", 0.0, 0.0, 400e3)
    with pytest.raises(ValueError, match="time 2002-09-06"):
        rom.mean_std("2002-09-06T23:59", 0.0, 0.0, 400e3)
    with pytest.raises(ValueError, match="lat must be finite"):
        rom.mean_std(t, np.nan, 0.0, 400e3)
    with pytest.raises(ValueError, match="alt must be finite"):
        rom.mean_std(t, 0.0, 0.0, np.nan)
    with pytest.raises(ValueError, match="NaT"):
        rom.mean_std(np.datetime64("NaT"), 0.0, 0.0, 400e3)
    # A ROM with a narrower latitude axis names its range.
    narrow = PcaRom(
        LST,
        [-60.0, 0.0, 60.0],
        ALT,
        np.zeros((24, 3, 5)) - 11,
        np.zeros((24, 3, 5, 1)),
        EPOCHS,
        np.zeros((5, 1)),
        np.zeros((5, 1)),
    )
    with pytest.raises(ValueError, match=r"lat = 70 deg is outside .*\[-60, 60\] deg"):
        narrow.mean_std(t, 70.0, 0.0, 400e3)


def test_constructor_errors():
    rom = synthetic()
    args = dict(
        lst=LST,
        lat=LAT,
        alt=ALT,
        mean_log10=rom.mean_log10,
        modes=rom.modes,
        epochs=EPOCHS,
        coeff_mean=rom.coeff_mean,
        coeff_std=rom.coeff_std,
    )

    def build(**change):
        return PcaRom(**{**args, **change})

    build()
    cases = [
        ({"mean_log10": rom.mean_log10[:, :, :4]}, r"mean_log10 must have shape"),
        ({"modes": rom.modes[..., 0]}, r"modes must have shape \(nlst, nlat, nalt, r\)"),
        ({"modes": rom.modes[:-1]}, r"modes must have shape"),
        ({"coeff_mean": rom.coeff_mean[:, :2]}, r"coeff_mean must have shape \(ne, r\)"),
        ({"coeff_std": rom.coeff_std[:-1]}, r"coeff_std must have shape"),
        ({"coeff_std": -rom.coeff_std}, r"coeff_std must be >= 0"),
        ({"lst": np.r_[LST[:5], 5.3, LST[6:]]}, r"lst must be uniform and cover the day"),
        ({"lst": np.arange(24.0) * 0.5}, r"lst must be uniform and cover the day"),
        ({"lat": LAT[::-1]}, r"lat must be strictly increasing"),
        ({"lat": LAT * 1.1}, r"lat must lie within \[-90, 90\]"),
        ({"alt": [np.nan, *ALT[1:]]}, r"alt must be finite"),
        ({"alt": ALT[:1]}, r"alt must be a 1-D axis with at least 2 nodes"),
        ({"epochs": EPOCHS[::-1]}, r"epochs must be strictly increasing"),
        ({"method": "mc"}, r"method must be one of"),
    ]
    bad_mean = rom.mean_log10.copy()
    bad_mean[1, 2, 3] = np.inf
    cases.append(({"mean_log10": bad_mean}, r"mean_log10 must be finite; got inf at index"))
    bad_cm = rom.coeff_mean.copy()
    bad_cm[2, 1] = np.nan
    cases.append(({"coeff_mean": bad_cm}, r"coeff_mean must be finite; got nan at index \(2, 1\)"))
    for change, message in cases:
        with pytest.raises(ValueError, match=message):
            build(**change)
    with pytest.raises(TypeError, match="epochs must be UTC datetime64"):
        build(epochs=np.arange(5))
    with pytest.raises(ValueError, match="samples must be >= 2"):
        build(method="sampling", samples=1)


def test_cache_key_describes_the_arrays():
    a, b = synthetic(), synthetic()
    t0, t1 = EPOCHS[0], EPOCHS[-1]
    assert a.cache_key(t0, t1) == b.cache_key(t0, t1)
    assert a.cache_key(t0, t1)["method"] == "analytic"
    assert synthetic(rank=2).cache_key(t0, t1) != a.cache_key(t0, t1)
    assert synthetic(zero_std=True).cache_key(t0, t1) != a.cache_key(t0, t1)
    sampled = synthetic(method="sampling", samples=100, seed=3).cache_key(t0, t1)
    assert sampled["samples"] == 100 and sampled["seed"] == 3
    assert synthetic(method="sampling", seed=None).cache_key(t0, t1) is None
    assert "PcaRom(24x7x5 grid, 3 modes, 5 epochs" in repr(a)


def test_field_matches_direct_evaluation():
    rom = synthetic()
    res = FieldResolution(time=1800.0, altitude=50e3, latitude=30.0, longitude=15.0)
    start, end = np.datetime64("2002-09-07T01:00", "ns"), np.datetime64("2002-09-07T05:00", "ns")
    field = rom.field(start, end, altitude_range=(350e3, 450e3), resolution=res, cache=False)
    np.testing.assert_array_equal(field.altitudes, [350e3, 400e3, 450e3])
    # The coefficient epoch 03:00 inside the window is a (repeated) node.
    assert np.count_nonzero(field.times == 7200.0) == 2
    rng = np.random.default_rng(5)
    n = 20
    t = start + (rng.uniform(0, 1, n) * (end - start).astype(np.int64)).astype("timedelta64[ns]")
    lat, lon = rng.uniform(-90, 90, n), rng.uniform(-180, 180, n)
    alt = rng.uniform(350e3, 450e3, n)
    mean, std = rom.mean_std(t, lat, lon, alt)
    grid_mean, grid_std = field.mean_std(t, lat, lon, alt)
    # The std is compared relative to the mean: where the modes nearly cancel, sigma/mean is
    # small and not linear between the 30 deg latitude nodes, so its own relative error is
    # large although sigma/mean is off by < 0.01 everywhere.
    rel_mean, rel_std = grid_mean / mean - 1, (grid_std - std) / mean
    print(
        f"field vs direct: mean max {np.abs(rel_mean).max():.3%}, "
        f"std max {np.abs(rel_std).max():.3%} of the mean"
    )
    assert np.abs(rel_mean).max() < 0.01
    assert np.abs(rel_std).max() < 0.01
    # Exact at grid nodes (a field node time and longitude on an LST node).
    node = np.datetime64("2002-09-07T02:00")
    a = rom.mean_std(node, 30.0, 45.0, 400e3)
    b = field.mean_std(node, 30.0, 45.0, 400e3)
    np.testing.assert_allclose(b, a, rtol=1e-9)


def test_coefficient_sigmas_that_are_not_a_density_uncertainty_are_refused():
    # coeff_std of 1,000 overflowed exp in the lognormal moments (a RuntimeWarning, then
    # infinite densities); the constructor now names the epoch and node.
    rom = synthetic()
    for big in (1e3, 1e200):
        with pytest.raises(
            ValueError, match=r"coeff_std gives log10 density a 1-sigma of .* at epoch"
        ):
            PcaRom(
                rom.lst,
                rom.lat,
                rom.alt,
                rom.mean_log10,
                rom.modes,
                EPOCHS,
                rom.coeff_mean,
                np.full_like(rom.coeff_std, big),
            )
    # The test ROM's own (0.5-2 per unit mode, about 0.1-0.6 in log10) are taken.
    assert synthetic().rank == 3
