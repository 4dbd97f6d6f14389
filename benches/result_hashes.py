"""Hashes of representative results (propagate, Monte Carlo, CCSP, catalog runs, screening,
an ensemble; analytic and NRLMSIS atmospheres), to show that a refactor left every bit as
it was: run it on two builds (e.g. two git worktrees, each in its own venv, each with a
fresh ``RHOPROP_CACHE``) and diff the output. Uses only spellings every build since the
density atlas accepts (deprecation warnings are silenced).

Run:  RHOPROP_CACHE=$(mktemp -d) python benches/result_hashes.py [tests/data/sample.tle]
"""

import hashlib
import sys
import warnings
from pathlib import Path

import numpy as np

import rhoprop as rp
from rhoprop import catalog

warnings.simplefilter("ignore")
SAMPLE = (
    sys.argv[1] if len(sys.argv) > 1 else str(Path(__file__).parents[1] / "tests/data/sample.tle")
)
out = {}


def h(name, *arrays):
    d = hashlib.sha256()
    for a in arrays:
        d.update(np.ascontiguousarray(np.asarray(a, dtype=float)).tobytes())
    out[name] = d.hexdigest()[:16]


state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
exp = rp.scenarios.benchmark_exponential(0.2)
coarse = rp.density.FieldResolution(time=3600.0, altitude=50e3, latitude=15.0, longitude=30.0)
msis = rp.density.Msis("2.1", resolution=coarse)
h("propagate dop853", rp.propagate(state, craft, exp, 86400.0, output_step=600.0).positions)
h(
    "propagate rk8 J4",
    rp.propagate(
        state, craft, msis, 86400.0, dynamics=rp.Dynamics(integrator="rk8", zonal_degree=4)
    ).positions,
)
mc = rp.monte_carlo(state, craft, exp, 86400.0, n=64, seed=3, progress=False, drag_sigma=0.1)
h("monte_carlo exp", mc.positions, mc.velocities)
mc = rp.monte_carlo(
    state,
    craft,
    msis,
    86400.0,
    n=64,
    seed=3,
    progress=False,
    dynamics=rp.Dynamics(integrator="abm"),
)
h("monte_carlo msis abm", mc.positions)
c = rp.ccsp(
    state,
    craft,
    msis,
    2 * 86400.0,
    drag_sigma=0.1,
    dynamics=rp.Dynamics(zonal_degree=3),
)
h("ccsp msis", c.mean, c.covariance)
cat = catalog.load(SAMPLE)
r = catalog.propagate_catalog(
    cat,
    exp,
    "2002-09-08T00:00",
    output_step=1800.0,
    execution=rp.Execution(progress=False, errors="record"),
)
h("catalog ccsp", r.mean, r.covariance)
r = catalog.propagate_catalog(
    cat,
    msis,
    "2002-09-07T12:00",
    output_step=1800.0,
    execution=rp.Execution(progress=False),
    method=rp.MonteCarlo(n=16),
)
h("catalog mc msis", r.mean, r.covariance)
objs = list(cat)
s = rp.conjunction.screen(
    objs[0],
    objs[1:],
    exp,
    start="2002-09-07T00:00",
    end="2002-09-08T00:00",
    distance=5e6,
    execution=rp.Execution(progress=False),
)
h("screen", [e.miss_distance for e in s.events], [e.tca.astype("int64") for e in s.events])
ens = rp.ensemble(
    state,
    craft,
    {"a": msis, "b": rp.density.Msis("00", resolution=coarse)},
    "a",
    duration=86400.0,
    method=rp.MonteCarlo(n=32, progress=False),
)
h("ensemble", ens.component_means, ens.component_covariances)
for k, v in out.items():
    print(f"{k:24s} {v}")
