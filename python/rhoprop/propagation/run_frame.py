"""The axes runs integrate in, and the way into and out of them.

The dynamics are written in true-of-date axes: the zonal field about the pole of date,
the Earth's rotation by GMST about it, the Sun and Moon precessed to the date. A run
integrates in those axes at its initial epoch (TEME's; over weeks they drift from the
axes of date by milliarcseconds). A TEME state enters as it is; a GCRF (EME2000, ICRF)
state is rotated into them and every output back out, by the one rotation of the
initial epoch (:func:`rhoprop.frames.teme_to_gcrf_matrix`), so a result is in its
initial state's frame. Without it a GCRF state's zonal field would act about a pole
0.36 deg off in 2026: kilometres of cross-track error a day in LEO.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from .. import frames
from .state import OrbitState


def into_run(
    state: OrbitState, covariance: npt.ArrayLike | None = None
) -> tuple[OrbitState, np.ndarray | None, np.ndarray | None]:
    """``state`` (and a 6x6 ``covariance`` of it, SI) in the run's axes, and the rotation
    (3, 3) that takes the run's outputs back to ``state.frame`` (None: they are in it).
    A covariance that is not a 6x6 of numbers is passed on as it is, for the run's own
    check to name."""
    if state.frame == "TEME":
        return state, covariance, None  # type: ignore[return-value]
    rot = frames.teme_to_gcrf_matrix(state.epoch)
    inside = OrbitState(state.epoch, rot.T @ state.position, rot.T @ state.velocity, "TEME")
    try:
        cov = None if covariance is None else np.asarray(covariance, dtype=float)
    except (TypeError, ValueError):
        return inside, covariance, rot  # type: ignore[return-value]  # the run says why
    if cov is not None and cov.shape == (6, 6):
        cov = covariances(rot.T, cov)
    return inside, cov, rot


def vectors(rot: np.ndarray | None, values: np.ndarray) -> np.ndarray:
    """Vectors (..., 3) or states (..., 6) (position and velocity alike) rotated by
    ``rot`` (None: unchanged)."""
    if rot is None:
        return values
    a = np.asarray(values, dtype=float)
    if a.shape[-1] == 3:
        return np.asarray(a @ rot.T)
    out = np.empty_like(a)
    out[..., :3] = a[..., :3] @ rot.T
    out[..., 3:] = a[..., 3:] @ rot.T
    return out


def covariances(rot: np.ndarray | None, values: np.ndarray) -> np.ndarray:
    """6x6 state covariances (..., 6, 6) rotated by ``rot`` (None: unchanged)."""
    if rot is None:
        return values
    big = np.zeros((6, 6))
    big[:3, :3] = big[3:, 3:] = rot
    out: np.ndarray = big @ np.asarray(values, dtype=float) @ big.T
    return out


#: Rows rotated at a time in place (a Monte Carlo's member arrays are the run's memory).
IN_PLACE_ROWS = 1 << 16


def vectors_in_place(rot: np.ndarray | None, values: np.ndarray) -> np.ndarray:
    """Vectors (..., 3) rotated by ``rot`` in place, a block of rows at a time, so that a
    Monte Carlo's (members, outputs, 3) arrays are not copied whole; returns ``values``."""
    if rot is None:
        return values
    if not (values.flags.c_contiguous and values.flags.writeable):
        return vectors(rot, values)
    flat = values.reshape(-1, 3)  # a view: the array is contiguous
    for lo in range(0, len(flat), IN_PLACE_ROWS):
        block = flat[lo : lo + IN_PLACE_ROWS]
        block[...] = block @ rot.T
    return values
