"""Frames and time: GMST (IAU-82), inertial <-> Earth-fixed, geodetic WGS-84, the RTN
frame of a reference orbit, equinoctial elements, and TEME <-> GCRF (SGP4's frame and the
inertial frame other tools expect). Inputs may be one vector (3,) or many (n, 3)."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from . import _core, _validate
from .time import EpochLike, EpochsLike, seconds_since_j2000, to_datetime64_array, ut1_seconds


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
    true equator of date, x along the mean equinox of date measured on it) to GCRF, as
    Vallado et al. (2006, "Revisiting Spacetrack Report #3", AIAA 2006-6753) give it:
    about the true pole by minus the equation of the equinoxes (1994), then the inverse
    of the IAU 1976 precession and 1980 nutation (ERFA's ``eqeq94`` and ``pnm80``). The
    23-mas frame bias between the J2000 mean equator and GCRF is not applied (under 1 m
    in LEO, 5 m at GEO): the result serves as EME2000 and as GCRF alike. Checked against
    astropy's TEME -> GCRS in ``tests/test_frames.py``."""
    import erfa  # type: ignore[import-untyped]

    days = seconds_since_j2000(epoch) / 86400.0
    tt1, tt2 = 2451545.0, days
    to_true_of_date = erfa.rz(-erfa.eqeq94(tt1, tt2), np.eye(3))
    out: np.ndarray = erfa.pnm80(tt1, tt2).T @ to_true_of_date
    return out


def teme_to_gcrf(epoch: EpochLike, states: npt.ArrayLike) -> np.ndarray:
    """States [x, y, z, vx, vy, vz] (6,) or (n, 6), m and m/s, in TEME of the UTC
    ``epoch`` -> GCRF (:func:`teme_to_gcrf_matrix`; the frame's own rotation, 1e-11 rad/s
    from precession and nutation, is left out of the velocities: under 0.1 mm/s)."""
    x, single = _rows("states", states, 6)
    m = teme_to_gcrf_matrix(epoch)
    out = np.concatenate([x[:, :3] @ m.T, x[:, 3:] @ m.T], axis=1)
    return out[0] if single else out


def gcrf_to_teme(epoch: EpochLike, states: npt.ArrayLike) -> np.ndarray:
    """The inverse of :func:`teme_to_gcrf`: GCRF states (6,) or (n, 6) -> TEME of the UTC
    ``epoch``."""
    x, single = _rows("states", states, 6)
    m = teme_to_gcrf_matrix(epoch)
    out = np.concatenate([x[:, :3] @ m, x[:, 3:] @ m], axis=1)
    return out[0] if single else out
