"""States between a trajectory's outputs: a Hermite polynomial through the positions and
velocities of the nearest outputs, refused where the outputs are too far apart for it.

Four outputs (degree 7) give the state; three of them (degree 5) check it: where the two
differ by more than the tolerance (1 m by default) the outputs are too coarse and the
caller is told to ask for the epoch itself or a finer output step, never given an
interpolated guess. The check is conservative: for the paper's 400 km orbit, outputs
every 60 s interpolate to 0.05 mm, every 5 minutes to 2 mm; every 10 minutes to 0.14 m
but the fits differ by 3 m, so the default tolerance refuses it (every 15 minutes: 57 m).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Default largest disagreement of the degree-7 and degree-5 fits, m.
DEFAULT_TOLERANCE = 1.0
#: A time within this of an output (s) is that output, returned as it is.
ON_OUTPUT = 1e-6


def hermite(
    times: NDArray[np.float64], pos: NDArray[np.float64], vel: NDArray[np.float64], t: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Position and velocity at ``t`` from the Hermite polynomial matching ``pos`` (k, 3)
    and ``vel`` (k, 3) at ``times`` (k,) s (Newton's divided differences on doubled nodes;
    the velocity is the polynomial's derivative)."""
    centre = float(times.mean())
    z = np.repeat(np.asarray(times, dtype=float) - centre, 2)
    n = len(z)
    q = np.zeros((n, n, pos.shape[1]))
    q[:, 0] = np.repeat(pos, 2, axis=0)
    for i in range(1, n):
        if i % 2:
            q[i, 1] = vel[i // 2]
        else:
            q[i, 1] = (q[i, 0] - q[i - 1, 0]) / (z[i] - z[i - 1])
    for j in range(2, n):
        for i in range(j, n):
            q[i, j] = (q[i, j - 1] - q[i - 1, j - 1]) / (z[i] - z[i - j])
    x = t - centre
    p = q[n - 1, n - 1].copy()
    dp = np.zeros_like(p)
    for k in range(n - 2, -1, -1):
        dp = dp * (x - z[k]) + p
        p = p * (x - z[k]) + q[k, k]
    return p, dp


def interpolate_state(
    times: NDArray[np.float64],
    positions: NDArray[np.float64],
    velocities: NDArray[np.float64],
    t: float,
    tolerance: float = DEFAULT_TOLERANCE,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The state at ``t`` (s, on the outputs' axis) between outputs at ``times`` (nt,):
    an output itself within :data:`ON_OUTPUT`, else the degree-7 Hermite fit of the four
    nearest outputs, checked against the degree-5 fit of the three nearest. ValueError
    outside the outputs, next to an output without a state (after decay), or where the
    two fits differ by more than ``tolerance`` m."""
    if not times[0] - ON_OUTPUT <= t <= times[-1] + ON_OUTPUT:
        raise ValueError(f"t = {t:g} s lies outside the outputs ({times[0]:g} to {times[-1]:g} s)")
    nearest = int(np.argmin(np.abs(times - t)))
    if abs(times[nearest] - t) <= ON_OUTPUT:
        return positions[nearest].copy(), velocities[nearest].copy()
    if len(times) < 3:
        raise ValueError("interpolating between outputs needs at least three of them")
    order = np.argsort(np.abs(times - t), kind="stable")
    four = np.sort(order[:4])
    three = np.sort(order[:3])
    if not (np.isfinite(positions[four]).all() and np.isfinite(velocities[four]).all()):
        raise ValueError(f"t = {t:g} s is next to an output without a state (after decay)")
    r, v = hermite(times[four], positions[four], velocities[four], t)
    r5, _ = hermite(times[three], positions[three], velocities[three], t)
    gap = float(np.linalg.norm(r - r5))
    if not gap <= tolerance:
        step = float(np.median(np.diff(times)))
        raise ValueError(
            f"the outputs are too far apart to interpolate at t = {t:g} s to {tolerance:g} m "
            f"(fits of degree 7 and 5 differ by {gap:.3g} m; outputs every {step:g} s): "
            "propagate to the epoch itself (the run's end, or output_times of monte_carlo "
            "and ccsp) or with a finer output_step (for LEO, 60 s interpolates to "
            "millimetres)"
        )
    return r, v
