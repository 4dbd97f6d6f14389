"""Independent reference propagation for tests: scipy's DOP853 on a numpy right-hand side
written from the equations of docs/conventions.md, "Frames and dynamics" (no rhoprop code
involved)."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

MU = 3.986004418e14
RE = 6378137.0
J2 = 1.08262668e-3
OMEGA = 7.292115e-5


def exponential_rhs(rho0: float, h0: float, scale: float, drag: float):
    """dy/dt for two-body + J2 + drag in a co-rotating exponential atmosphere."""

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        r = y[:3]
        v = y[3:]
        rn = np.linalg.norm(r)
        z2 = (r[2] / rn) ** 2
        a = -MU * r / rn**3
        k = -1.5 * J2 * MU * RE**2 / rn**5
        a = a + k * r * np.array([1 - 5 * z2, 1 - 5 * z2, 3 - 5 * z2])
        rho = rho0 * np.exp(-(rn - RE - h0) / scale)
        vrel = v - np.cross([0.0, 0.0, OMEGA], r)
        a = a - 0.5 * rho * drag * np.linalg.norm(vrel) * vrel
        return np.concatenate([v, a])

    return rhs


def reference_orbit(
    y0: np.ndarray, times: np.ndarray, rho0: float, h0: float, scale: float, drag: float
) -> np.ndarray:
    """States (len(times), 6) from scipy DOP853 at rtol 1e-13."""
    sol = solve_ivp(
        exponential_rhs(rho0, h0, scale, drag),
        (0.0, float(times[-1])),
        np.asarray(y0, dtype=float),
        method="DOP853",
        t_eval=times,
        rtol=1e-13,
        atol=1e-7,
    )
    assert sol.success, sol.message
    return sol.y.T
