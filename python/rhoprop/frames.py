"""Frames and time: GMST (IAU-82), inertial <-> Earth-fixed, geodetic WGS-84, the RTN
frame of a reference orbit, equinoctial elements, and named frames: TEME (SGP4's),
GCRF (EME2000 and ICRF name its axes here) and ITRF, converted by :func:`convert`.
Inputs may be one vector (3,) or many (n, 3)."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from . import _core, _validate
from .time import (
    J2000_UTC,
    EpochLike,
    EpochsLike,
    to_datetime64_array,
    to_seconds,
    ut1_seconds,
)


def _rows(name: str, value: Any, width: int = 3) -> tuple[np.ndarray, bool]:
    """``value`` as finite rows (n, width) and whether it was one row (width,)."""
    try:
        a = _validate.real_array(name, value)
    except (TypeError, ValueError) as err:
        raise TypeError(
            f"{name} must be numbers of shape ({width},) or (n, {width}): {err}"
        ) from None
    single = a.ndim == 1
    a2 = np.atleast_2d(a)
    if a2.ndim != 2 or a2.shape[1] != width:
        raise ValueError(f"{name} must have shape ({width},) or (n, {width}), got {a.shape}")
    if not np.isfinite(a2).all():
        raise ValueError(f"{name} must be finite")
    return np.ascontiguousarray(a2), single


def _ut1(epochs: EpochsLike, n: int) -> np.ndarray:
    """The core's Earth-rotation time (UT1 = UTC seconds since 2000-01-01T12:00, see
    :func:`rhoprop.time.ut1_seconds`) of one epoch (repeated n times) or of n epochs."""
    values = to_datetime64_array(epochs, "epochs")
    if values.ndim == 0:
        return np.full(n, ut1_seconds(values[()]))
    if values.ndim != 1 or len(values) != n:
        raise ValueError(f"got {values.size} epochs for {n} positions")
    out: np.ndarray = ut1_seconds(values)
    return out


def gmst(epochs: EpochsLike) -> np.ndarray | float:
    """Greenwich mean sidereal time (IAU-82), rad in [0, 2 pi), at UTC epochs (UT1 = UTC):
    one epoch gives a float, several an array."""
    values = to_datetime64_array(epochs, "epochs")
    if values.ndim == 0:
        return float(_core.gmst(_ut1(values, 1))[0])
    return _core.gmst(_ut1(values.ravel(), values.size)).reshape(values.shape)


def inertial_to_fixed(epochs: EpochsLike, positions: npt.ArrayLike) -> np.ndarray:
    """Inertial positions (3,) or (n, 3), m -> Earth-fixed, rotated about z by GMST at
    ``epochs`` (one epoch or n)."""
    p, single = _rows("positions", positions)
    out = _finite("Earth-fixed positions", _core.inertial_to_fixed(_ut1(epochs, len(p)), p))
    return out[0] if single else out


def fixed_to_inertial(epochs: EpochsLike, positions_fixed: npt.ArrayLike) -> np.ndarray:
    """Earth-fixed positions (3,) or (n, 3), m -> inertial, rotated about z by -GMST at
    ``epochs`` (one epoch or n); the inverse of :func:`inertial_to_fixed`."""
    p, single = _rows("positions_fixed", positions_fixed)
    theta = _core.gmst(_ut1(epochs, len(p)))
    c, s = np.cos(theta), np.sin(theta)
    with np.errstate(over="ignore", invalid="ignore"):  # reported by _finite
        out = np.stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1], p[:, 2]], axis=1)
    out = _finite("inertial positions", out)
    return out[0] if single else out


#: Radii (m) between which geodetic coordinates are computed: Heikkinen's closed form is
#: singular within e^2 a = 42.7 km of the centre and its squares overflow far out.
GEODETIC_RADII = (50e3, 1e15)


def geodetic(positions_fixed: npt.ArrayLike) -> np.ndarray:
    """Earth-fixed positions (3,) or (n, 3), m -> geodetic WGS-84 [lat deg, lon deg,
    alt m], closed form (Heikkinen), sub-millimetre. Positions within 50 km of the centre
    or beyond 1e15 m are a ValueError (no closed-form answer there)."""
    p, single = _rows("positions_fixed", positions_fixed)
    with np.errstate(over="ignore"):  # an infinite radius is refused below
        radius = np.linalg.norm(p, axis=1)
    low, high = GEODETIC_RADII
    bad = np.flatnonzero((radius < low) | (radius > high))
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"positions_fixed[{i}] is {radius[i]:.4g} m from the Earth's centre: geodetic "
            f"coordinates are computed between {low:g} and {high:g} m"
        )
    out = _finite("geodetic coordinates", _core.geodetic(p))
    return out[0] if single else out


def _finite(what: str, out: np.ndarray) -> np.ndarray:
    """``out`` if finite, else a ValueError naming the first bad row (inputs so large
    that the arithmetic overflows)."""
    bad = ~np.isfinite(out)
    if bad.any():
        row = int(np.argwhere(bad)[0][0]) if out.ndim > 1 else 0
        raise ValueError(f"{what} overflow at row {row}: the inputs are too large")
    return out


def geodetic_to_fixed(lat: npt.ArrayLike, lon: npt.ArrayLike, alt: npt.ArrayLike) -> np.ndarray:
    """Geodetic WGS-84 latitude, longitude (deg) and altitude (m) -> Earth-fixed (…, 3), m."""
    la, lo, al = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (lat, lon, alt)))
    lla = np.stack([la.ravel(), lo.ravel(), al.ravel()], axis=1)
    if not np.isfinite(lla).all():
        raise ValueError("lat, lon and alt must be finite")
    if (np.abs(lla[:, 0]) > 90.0).any():
        raise ValueError(f"lat must lie in [-90, 90] deg, got {lla[np.abs(lla[:, 0]) > 90, 0][0]}")
    out = _finite("Earth-fixed positions", _core.geodetic_to_fixed(lla))
    return out.reshape((*la.shape, 3))


def rtn_basis(position: npt.ArrayLike, velocity: npt.ArrayLike) -> np.ndarray:
    """RTN basis (3, 3) or (n, 3, 3) of the orbit through ``position`` (m) and
    ``velocity`` (m/s): rows R = r/|r|, T = N x R, N = (r x v)/|r x v|."""
    p, single = _rows("position", position)
    v, _ = _rows("velocity", velocity)
    if len(p) != len(v):
        raise ValueError(f"position has {len(p)} rows but velocity has {len(v)}")
    out = _core.rtn_basis(p, v)
    return out[0] if single else out


def to_rtn(
    positions: npt.ArrayLike, ref_positions: npt.ArrayLike, ref_velocities: npt.ArrayLike
) -> np.ndarray:
    """Position differences ``positions - ref_positions`` (…, 3), m, expressed in the RTN
    frame of the reference orbit (radial, along-track, cross-track). ``positions`` may
    carry leading member axes: shape (..., n, 3) against references (n, 3)."""
    basis = rtn_basis(ref_positions, ref_velocities)
    delta = np.asarray(positions, dtype=float) - np.asarray(ref_positions, dtype=float)
    return np.asarray(np.einsum("...ij,...j->...i", basis, delta))


def to_equinoctial(
    states: npt.ArrayLike,
    reference: npt.ArrayLike | None = None,
    semi_major: Literal["osculating", "energy"] = "osculating",
) -> np.ndarray:
    """Inertial states (6,) or (n, 6), m and m/s, as equinoctial elements (a m, h, k, p,
    q, lambda rad): k + i h = e exp(i (omega + Omega)),
    q + i p = tan(i / 2) exp(i Omega), lambda = M + omega + Omega (docs/conventions.md,
    "CCSP coordinates").

    ``semi_major``: ``"osculating"`` (default, the two-body a of the state) or
    ``"energy"``, -mu / (2 E) with E the energy in the J2 field (constant along a J2
    orbit, where the osculating a swings by about 13 km at 400 km): the a of a
    :func:`rhoprop.ccsp` run's ``element_mean``.

    ``reference`` (a state (6,); default the first state) fixes the axes (turned 180 deg
    about x when its orbit is retrograde, so the elements stay regular) and lambda is
    returned within pi of the reference's, so a spread of states across lambda = +-pi
    stays one spread. With the initial state of a :func:`rhoprop.ccsp` run as reference,
    Monte Carlo members compare directly with its ``element_mean`` and
    ``element_covariance`` (with ``semi_major="energy"``). Raises ValueError for a state
    not on an elliptic orbit or an unknown ``semi_major``."""
    s, single = _rows("states", states, 6)
    ref = s[0] if reference is None else _rows("reference", reference, 6)[0][0]
    out = _core.equinoctial_elements(s, np.ascontiguousarray(ref), semi_major)
    return out[0] if single else out


def from_equinoctial(
    elements: npt.ArrayLike,
    reference: npt.ArrayLike,
    semi_major: Literal["osculating", "energy"] = "osculating",
) -> np.ndarray:
    """Equinoctial elements (6,) or (n, 6) (as :func:`to_equinoctial`, with the same
    ``semi_major``) back to inertial states, m and m/s, in the axes of ``reference`` (a
    state (6,))."""
    e, single = _rows("elements", elements, 6)
    ref = _rows("reference", reference, 6)[0][0]
    out = _core.equinoctial_to_cartesian(e, np.ascontiguousarray(ref), semi_major)
    return out[0] if single else out


def teme_to_gcrf_matrix(epoch: EpochLike) -> np.ndarray:
    """The rotation (3, 3) taking vectors in TEME of the UTC ``epoch`` (SGP4's frame: the
    true equator of date, x along the mean equinox of date measured on it) to GCRF, by
    the route astropy and Vallado et al. (2006, "Revisiting Spacetrack Report #3", AIAA
    2006-6753) take: TEME -> pseudo-Earth-fixed by GMST (IAU-82), then back to the
    celestial intermediate frame by the Earth rotation angle and to GCRF by ERFA's IAU
    2006/2000A ``c2i06a`` (frame bias included). Polar motion cancels on that route and
    UT1 = UTC changes it by under a millimetre. Equal to astropy's TEME -> GCRS to 1 mm in
    LEO (``tests/test_frames.py``); the IAU 1976/1980 matrices it replaced on 2026-12-05
    were 0.6-1.5 m from it."""
    out: np.ndarray = _teme_to_gcrf_matrices(to_datetime64_array(epoch, "epoch").reshape(1))[0]
    return out


def teme_to_gcrf(epoch: EpochLike, states: npt.ArrayLike) -> np.ndarray:
    """States [x, y, z, vx, vy, vz] (6,) or (n, 6), m and m/s, in TEME of the UTC
    ``epoch`` -> GCRF (:func:`teme_to_gcrf_matrix`; the frame's own rotation, 1e-11 rad/s
    from precession and nutation, is left out of the velocities: under 0.1 mm/s)."""
    return convert(epoch, states, "TEME", "GCRF")


def gcrf_to_teme(epoch: EpochLike, states: npt.ArrayLike) -> np.ndarray:
    """The inverse of :func:`teme_to_gcrf`: GCRF states (6,) or (n, 6) -> TEME of the UTC
    ``epoch``."""
    return convert(epoch, states, "GCRF", "TEME")


#: Inertial frames a state may be given in: GCRF, EME2000 and ICRF (one set of axes here:
#: the 23-mas frame bias between the J2000 mean equator and GCRF is not told apart, under
#: 1 m in LEO and 5 m at GEO) and TEME, SGP4's true equator and mean equinox of date.
INERTIAL_FRAMES = ("GCRF", "EME2000", "ICRF", "TEME")
#: Every frame :func:`convert` takes: the inertial ones and the Earth-fixed ITRF.
FRAMES = (*INERTIAL_FRAMES, "ITRF")
#: Names read as another frame's.
_ALIASES = {"J2000": "EME2000", "ITRS": "ITRF", "GCRS": "GCRF"}
#: The frames that share GCRF's axes.
_GCRF_AXES = ("GCRF", "EME2000", "ICRF")


def frame_name(name: str, value: object, allowed: tuple[str, ...] = FRAMES) -> str:
    """``value`` as one of ``allowed`` (case-insensitive; J2000 reads as EME2000, GCRS as
    GCRF, ITRS as ITRF), else a TypeError or ValueError naming argument ``name``."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a frame name {allowed}, got {type(value).__name__}")
    frame = _ALIASES.get(value.strip().upper(), value.strip().upper())
    if frame not in allowed:
        hint = (
            "; an Earth-fixed state is converted first: rp.frames.convert(epoch, state, "
            "'ITRF', 'GCRF')"
            if frame == "ITRF"
            else ""
        )
        raise ValueError(f"{name} must be one of {allowed}, got {value!r}{hint}")
    return frame


def same_axes(a: str, b: str) -> bool:
    """Whether frames ``a`` and ``b`` (names as :func:`frame_name` returns) share axes."""
    return a == b or (a in _GCRF_AXES and b in _GCRF_AXES)


def _teme_to_gcrf_matrices(epochs: np.ndarray) -> np.ndarray:
    """:func:`teme_to_gcrf_matrix` of each epoch (n,) -> (n, 3, 3)."""
    import erfa  # type: ignore[import-untyped]

    tt = to_seconds(epochs, J2000_UTC) / 86400.0
    ut1 = ut1_seconds(epochs) / 86400.0  # UT1 = UTC, days since 2000-01-01T12:00
    j2000 = np.full(tt.shape, 2451545.0)
    gmst_minus_era = erfa.gmst82(j2000, ut1) - erfa.era00(j2000, ut1)
    to_cirs = erfa.rz(gmst_minus_era, np.eye(3))
    return np.asarray(np.swapaxes(erfa.c2i06a(j2000, tt), -1, -2) @ to_cirs)


def _rotate(matrices: np.ndarray, states: np.ndarray) -> np.ndarray:
    """States (n, 6) rotated by matrices (n, 3, 3), position and velocity alike."""
    pos = np.einsum("nij,nj->ni", matrices, states[:, :3])
    vel = np.einsum("nij,nj->ni", matrices, states[:, 3:])
    return np.concatenate([pos, vel], axis=1)


def _with_astropy(epochs: np.ndarray, states: np.ndarray, source: str, target: str) -> np.ndarray:
    """TEME or GCRF <-> ITRF through astropy (IAU 2006/2000A, UT1 - UTC and polar motion
    from the IERS tables astropy ships, never downloaded: rhoprop runs offline)."""
    try:
        from astropy import units as u  # type: ignore[import-untyped]
        from astropy.coordinates import (  # type: ignore[import-untyped]
            GCRS,
            ITRS,
            TEME,
            CartesianDifferential,
            CartesianRepresentation,
        )
        from astropy.time import Time  # type: ignore[import-untyped]
        from astropy.utils import iers  # type: ignore[import-untyped]
    except ImportError:  # pragma: no cover - astropy is a test dependency
        raise ImportError(
            "conversions to and from ITRF use astropy, which is not installed (pip install astropy)"
        ) from None
    classes = {"TEME": TEME, "GCRF": GCRS, "ITRF": ITRS}
    with iers.conf.set_temp("auto_download", False):
        t = Time(epochs.astype("datetime64[ns]"), scale="utc")
        rep = CartesianRepresentation(
            states[:, :3].T * u.m, differentials=CartesianDifferential(states[:, 3:].T * u.m / u.s)
        )
        out = classes[source](rep, obstime=t).transform_to(classes[target](obstime=t)).cartesian
    pos = out.xyz.to(u.m).value.T
    vel = out.differentials["s"].d_xyz.to(u.m / u.s).value.T
    return np.ascontiguousarray(np.concatenate([pos, vel], axis=1))


def convert(
    epochs: EpochsLike, states: npt.ArrayLike, from_frame: str, to_frame: str
) -> np.ndarray:
    """States [x, y, z, vx, vy, vz] (6,) or (n, 6), m and m/s, at UTC ``epochs`` (one, or
    one per state) from frame ``from_frame`` to ``to_frame`` (names of :data:`FRAMES`).

    TEME <-> GCRF by :func:`teme_to_gcrf_matrix` of each epoch (ERFA; astropy's route, to
    1 mm in LEO). Anything <-> ITRF through astropy (UT1 - UTC and polar
    motion from its bundled IERS tables, never downloaded; its velocities carry the
    Earth's rotation). GCRF, EME2000 and ICRF are one set of axes here (:data:`INERTIAL_FRAMES`).
    Tested against astropy and a round trip in ``tests/test_frames.py``."""
    source = frame_name("from_frame", from_frame)
    target = frame_name("to_frame", to_frame)
    x, single = _rows("states", states, 6)
    values = to_datetime64_array(epochs, "epochs")
    if values.ndim == 0:
        values = np.full(len(x), values[()])
    elif values.ndim != 1 or len(values) != len(x):
        raise ValueError(f"got {values.size} epochs for {len(x)} states")
    source = "GCRF" if source in _GCRF_AXES else source
    target = "GCRF" if target in _GCRF_AXES else target
    if source == target:
        out = x.copy()
    elif "ITRF" in (source, target):
        out = _with_astropy(values, x, source, target)
    else:
        m = _teme_to_gcrf_matrices(values)
        out = _rotate(m if source == "TEME" else np.swapaxes(m, -1, -2), x)
    return out[0] if single else out
