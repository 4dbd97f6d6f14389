"""rhoprop vs peers on the same ensemble problem, side by side in one run.

Problem: the paper's orbit, two-body + J2 + drag in the co-rotating exponential atmosphere
rho = 3.725e-12 exp(-(h - 400 km) / 58.515 km), Cd 3.0912, A/m 0.0015 m^2/kg, 3 days,
1000 members whose drag parameter is scaled by (1 + 0.2 z_i), z_i ~ N(0, 1), seed 1.
Each contender runs at its cheapest setting that keeps the z = 0 member within 1 m of a
tight reference (scipy DOP853, rtol 1e-13). rhoprop draws its z_i from its own seeded
member streams (``kappa.Constant`` with a 20 % relative sigma is exactly this scaling);
the peers use numpy's default_rng(1).

Contenders: rhoprop (Monte Carlo engine, all cores); heyoka (``pip install heyoka``):
scalar integrators in its ensemble API and its SIMD batch integrator at 4 and 8 lanes
(and its recommended width; the fastest counts), all cores, JIT
compile time reported separately; scipy solve_ivp DOP853 looping over members (timed on a
subset and scaled); a vectorised numpy RK4 over all members.

Run:  python benches/compare_peers.py [--repeat 3] [--members 1000]
Prints a table and writes benches/results/compare_peers.json.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

import rhoprop as rp
from machine import describe, info

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
from reference import J2, MU, OMEGA, RE, exponential_rhs, reference_orbit

RHO0, H0, SCALE = 3.725e-12, 400e3, 58.515e3
DAYS = 3.0
T_END = DAYS * 86400.0


def median_wall(fn, repeat: int) -> tuple[float, object]:
    walls, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        walls.append(time.perf_counter() - t0)
    return float(np.median(walls)), out


def run_rhoprop(state, craft, n: int, repeat: int, ref: np.ndarray, method: str = "rk8") -> dict:
    model = rp.density.Exponential(RHO0, H0, SCALE, rel_sigma=0.2)
    # Cheapest steps meeting 1 m (benches/accuracy.py): RK8 at 240 s ends 0.88 m off,
    # Adams-Bashforth-Moulton at 80 s 0.34 m (90 s: 1.15 m).
    step = {"rk8": 240.0, "abm": 80.0}[method]
    det = rp.propagate(
        state,
        craft,
        model,
        T_END,
        dynamics=rp.Dynamics(integrator=method, step=step),
    )
    err = float(np.linalg.norm(det.positions[-1] - ref))

    def go():
        return rp.monte_carlo(
            state,
            craft,
            model,
            T_END,
            n=n,
            kappa=rp.kappa.Constant(),
            seed=1,
            output_step=None,
            progress=False,
            dynamics=rp.Dynamics(integrator=method, step=step),
        )

    wall, _ = median_wall(go, repeat)
    return {
        "name": f"rhoprop ({method.upper()} {step:g} s, {rp._core.simd_path()}, all cores)",
        "wall_s": wall,
        "z0_error_m": err,
        "setting": f"{method} step {step:g} s",
    }


def heyoka_system():
    import heyoka as hy

    x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    r2 = x * x + y * y + z * z
    r = hy.sqrt(r2)
    zz = 5.0 * z * z / r2
    k = -1.5 * J2 * MU * RE * RE / (r2 * r2 * r)
    grav = -MU / (r2 * r)
    rho = RHO0 * hy.exp(-(r - RE - H0) / SCALE)
    wx, wy = vx + OMEGA * y, vy - OMEGA * x
    vrel = hy.sqrt(wx * wx + wy * wy + vz * vz)
    drag = -0.5 * rho * hy.par[0] * vrel
    return [
        (x, vx),
        (y, vy),
        (z, vz),
        (vx, grav * x + k * x * (1.0 - zz) + drag * wx),
        (vy, grav * y + k * y * (1.0 - zz) + drag * wy),
        (vz, grav * z + k * z * (3.0 - zz) + drag * vz),
    ]


def run_heyoka(state, b0: float, drags: np.ndarray, repeat: int, ref: np.ndarray) -> list[dict]:
    import heyoka as hy

    sys_ = heyoka_system()
    y0 = state.state
    # Loosest tolerance meeting 1 m for the z = 0 member (scalar integrator).
    tol = None
    for cand in (1e-7, 3e-8, 1e-8, 3e-9, 1e-9, 3e-10, 1e-10):
        ta = hy.taylor_adaptive(sys_, y0.copy(), tol=cand, pars=[b0])
        ta.propagate_until(T_END)
        if np.linalg.norm(ta.state[:3] - ref) < 1.0:
            tol, err = cand, float(np.linalg.norm(ta.state[:3] - ref))
            break
    if tol is None:
        raise RuntimeError("no heyoka tolerance met 1 m")
    rows = []
    t0 = time.perf_counter()
    ta = hy.taylor_adaptive(sys_, y0.copy(), tol=tol, pars=[b0])
    jit_scalar = time.perf_counter() - t0

    def scalar():
        def gen(ta_copy, i):
            ta_copy.time = 0.0
            ta_copy.state[:] = y0
            ta_copy.pars[0] = drags[i]
            return ta_copy

        return hy.ensemble_propagate_until(ta, T_END, len(drags), gen)

    wall, _ = median_wall(scalar, repeat)
    rows.append(
        {
            "name": "heyoka ensemble, scalar integrators",
            "wall_s": wall,
            "jit_s": jit_scalar,
            "z0_error_m": err,
            "setting": f"tol {tol:g}",
        }
    )
    # Every batch width worth trying: heyoka's recommended one (4 doubles with AVX2,
    # 8 with AVX-512) and both 4 and 8, so that its fastest width is the one compared.
    for batch in sorted({hy.recommended_simd_size(), 4, 8}):
        rows.append(_heyoka_batch(hy, sys_, y0, b0, drags, tol, err, batch, repeat))
    return rows


def _heyoka_batch(hy, sys_, y0, b0, drags, tol, err, batch: int, repeat: int) -> dict:
    """heyoka's ensemble of SIMD batch integrators of ``batch`` lanes over ``drags``."""
    n_iter = int(np.ceil(len(drags) / batch))
    padded = np.resize(drags, n_iter * batch)
    t0 = time.perf_counter()
    tb = hy.taylor_adaptive_batch(
        sys_, np.repeat(y0[:, None], batch, axis=1), tol=tol, pars=np.full((1, batch), b0)
    )
    jit_batch = time.perf_counter() - t0

    def batched():
        def gen(ta_copy, i):
            ta_copy.set_time(0.0)
            ta_copy.state[:] = y0[:, None]
            ta_copy.pars[0, :] = padded[i * batch : (i + 1) * batch]
            return ta_copy

        return hy.ensemble_propagate_until(tb, T_END, n_iter, gen)

    wall, _ = median_wall(batched, repeat)
    recommended = " (recommended)" if batch == hy.recommended_simd_size() else ""
    return {
        "name": f"heyoka ensemble, SIMD batch of {batch}{recommended}",
        "wall_s": wall,
        "jit_s": jit_batch,
        "z0_error_m": err,
        "setting": f"tol {tol:g}",
    }


def run_scipy(state, drags: np.ndarray, ref: np.ndarray, subset: int) -> dict:
    from scipy.integrate import solve_ivp

    # Loosest rtol meeting 1 m for the z = 0 member.
    rtol = None
    for cand in (1e-9, 3e-10, 1e-10, 3e-11, 1e-11):
        sol = solve_ivp(
            exponential_rhs(RHO0, H0, SCALE, B_REF),
            (0, T_END),
            state.state,
            method="DOP853",
            rtol=cand,
            atol=1e-6,
        )
        if np.linalg.norm(sol.y[:3, -1] - ref) < 1.0:
            rtol, err = cand, float(np.linalg.norm(sol.y[:3, -1] - ref))
            break
    t0 = time.perf_counter()
    for b in drags[:subset]:
        solve_ivp(
            exponential_rhs(RHO0, H0, SCALE, b),
            (0, T_END),
            state.state,
            method="DOP853",
            rtol=rtol,
            atol=1e-6,
        )
    per = (time.perf_counter() - t0) / subset
    return {
        "name": f"scipy solve_ivp DOP853 loop (timed on {subset}, scaled)",
        "wall_s": per * len(drags),
        "z0_error_m": err,
        "setting": f"rtol {rtol:g}",
    }


def run_numpy_rk4(state, drags: np.ndarray, ref: np.ndarray) -> dict:
    h = 6.0  # RK4 at 6 s: ~0.25 m (5 s: 0.12 m, 10 s: 3.1 m; benches/accuracy.py)

    def f(y, b):
        r = y[:, :3]
        v = y[:, 3:]
        rn = np.sqrt(np.einsum("ij,ij->i", r, r))[:, None]
        z2 = (r[:, 2:3] / rn) ** 2
        a = -MU * r / rn**3
        k = -1.5 * J2 * MU * RE**2 / rn**5
        a += k * r * np.hstack([1 - 5 * z2, 1 - 5 * z2, 3 - 5 * z2])
        rho = RHO0 * np.exp(-(rn - RE - H0) / SCALE)
        w = v + OMEGA * np.hstack([r[:, 1:2], -r[:, 0:1], np.zeros_like(rn)])
        a -= 0.5 * rho * b[:, None] * np.linalg.norm(w, axis=1)[:, None] * w
        return np.hstack([v, a])

    y = np.repeat(state.state[None], len(drags), axis=0)
    t0 = time.perf_counter()
    for _ in range(int(T_END / h)):
        k1 = f(y, drags)
        k2 = f(y + 0.5 * h * k1, drags)
        k3 = f(y + 0.5 * h * k2, drags)
        k4 = f(y + h * k3, drags)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    wall = time.perf_counter() - t0
    zero = int(np.argmin(np.abs(drags - B_REF)))
    err = float(np.linalg.norm(y[zero, :3] - ref)) if drags[zero] == B_REF else float("nan")
    return {
        "name": "numpy RK4 vectorised over members",
        "wall_s": wall,
        "z0_error_m": err,
        "setting": "rk4 step 6 s",
    }


B_REF = 3.0912 * 0.0015


def main() -> None:
    print(describe())
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--members", type=int, default=1000)
    parser.add_argument("--scipy-subset", type=int, default=10)
    parser.add_argument("--skip", nargs="*", default=[], help="contenders to skip")
    args = parser.parse_args()
    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    ref = reference_orbit(state.state, np.array([0.0, T_END]), RHO0, H0, SCALE, B_REF)[-1, :3]
    z = np.random.default_rng(1).standard_normal(args.members)
    z[0] = 0.0  # the accuracy member
    drags = B_REF * (1 + 0.2 * z)
    rows = [
        run_rhoprop(state, craft, args.members, args.repeat, ref, "abm"),
        run_rhoprop(state, craft, args.members, args.repeat, ref, "rk8"),
    ]
    if "heyoka" not in args.skip:
        rows += run_heyoka(state, B_REF, drags, args.repeat, ref)
    if "scipy" not in args.skip:
        rows.append(run_scipy(state, drags, ref, args.scipy_subset))
    if "numpy" not in args.skip:
        rows.append(run_numpy_rk4(state, drags, ref))
    base = rows[0]["wall_s"]
    member_days = args.members * DAYS
    print(
        f"{os.cpu_count()} cores; {args.members} members x {DAYS:g} days; median of {args.repeat}"
    )
    print(
        f"{'contender':<52} {'setting':<16} {'z=0 err [m]':>11} {'wall [s]':>9} "
        f"{'member-days/s':>14} {'x rhoprop':>10} {'JIT [s]':>8}"
    )
    for r in rows:
        r["member_days_per_s"] = member_days / r["wall_s"]
        r["time_ratio_to_rhoprop"] = r["wall_s"] / base
        jit = f"{r['jit_s']:.2f}" if "jit_s" in r else ""
        print(
            f"{r['name']:<52} {r['setting']:<16} {r['z0_error_m']:>11.3f} {r['wall_s']:>9.3f} "
            f"{r['member_days_per_s']:>14,.0f} {r['time_ratio_to_rhoprop']:>10.2f} {jit:>8}"
        )
    out = Path(__file__).parent / "results" / "compare_peers.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(
        json.dumps({**info(), "members": args.members, "days": DAYS, "rows": rows}, indent=2)
    )


if __name__ == "__main__":
    main()
