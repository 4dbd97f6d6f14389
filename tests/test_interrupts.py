"""Ctrl-C stops every long call: a subprocess starts a run that would
take seconds to minutes, gets a real SIGINT about a second later, and must exit with
KeyboardInterrupt within 2 s of it, without finishing the run. The bounds are generous on
purpose: the binding polls for Ctrl-C every 50 ms and the catalog finishes at most its
running objects (~10 ms each here)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")

SETUP = """
import rhoprop as rp
state = rp.scenarios.paper_state()
craft = rp.Spacecraft(2.2, 1e-6)  # so little drag that nothing decays
model = rp.scenarios.benchmark_exponential(0.2)
"""

RUNS = {
    # ~3 s: the adaptive DOP853 at rtol 1e-12 through a sampled field for 3.5 years, just
    # under the core's 10^6 adaptive steps (the field is sampled before "started").
    "propagate_dop853": (
        "import numpy as np\n"
        "def fn(t, lat, lon, alt):\n"
        "    m = 3.725e-12 * np.exp(-(alt - 400e3) / 58.515e3)\n"
        "    return m, 0.2 * m\n"
        "res = rp.density.FieldResolution(time=30 * 86400.0)\n"
        "band = rp.density.altitude_band(state.position, state.velocity)\n"
        "end = rp.time.add_seconds(state.epoch, 1.1e8, round_up=True)\n"
        "field = rp.density.FromFunction(fn).field(state.epoch, end, altitude_range=band,"
        " resolution=res)\n"
        "print('started', flush=True)\n"
        "rp.propagate(state, craft, field, 1.1e8, dynamics=rp.Dynamics(rtol=1e-12))"
    ),
    # ~8 s: 10^7 RK8 steps of 10 s.
    "propagate_rk8": (
        "rp.propagate(state, craft, model, 9.99e7, "
        "dynamics=rp.Dynamics(integrator='rk8', step=10.0))"
    ),
    # ~80 s: 200,000 members x 3 days.
    "monte_carlo": (
        "rp.monte_carlo(state, craft, model, 3 * 86400.0, n=200_000, output_step=None, "
        "progress=False)"
    ),
    # ~40 s: 55 years of 180-s RK8 steps (under the 10^7-step limit), daily updates; certain
    # density, so that the sigma points stay together and nothing comes down.
    "ccsp": (
        "certain = rp.scenarios.benchmark_exponential(0.0)\n"
        "print('started', flush=True)\n"
        "rp.ccsp(state, craft, certain, 55 * 365.25 * 86400.0, update_interval=86400.0)"
    ),
    # ~50 s: 6,000 objects on threads.
    "propagate_catalog": (
        "from pathlib import Path\n"
        "from rhoprop import catalog\n"
        f"cat = catalog.load(Path({os.path.dirname(__file__)!r}) / 'data' / 'sample.tle')\n"
        "print('started', flush=True)\n"
        "catalog.propagate_catalog(list(cat) * 1000, model, '2002-09-10T00:00', "
        "execution=rp.Execution(progress=False))"
    ),
    # Minutes: reentry windows of 5,000 members per object on threads (once
    # 17-21 s to stop, as every running object finished its members first).
    "reentry": (
        "from pathlib import Path\n"
        "from rhoprop import catalog\n"
        f"cat = catalog.load(Path({os.path.dirname(__file__)!r}) / 'data' / 'sample.tle')\n"
        "print('started', flush=True)\n"
        "catalog.reentry(list(cat) * 10, model, method=rp.MonteCarlo(n=5000), "
        "duration=30 * 86400.0, history='each')"
    ),
    # ~80 s: two models of 100,000 members each.
    "ensemble": (
        "rp.ensemble(state, craft, {'a': model, 'b': model}, 'a', duration=3 * 86400.0, "
        "debias=rp.Debias(cds={'b': 2.2}), "
        "method=rp.MonteCarlo(n=100_000, output_step=None, progress=False))"
    ),
}


@pytest.mark.parametrize("name", list(RUNS))
def test_ctrl_c_stops_the_run(name):
    call = RUNS[name]
    start = "" if "print('started'" in call else "print('started', flush=True)\n"
    script = textwrap.dedent(SETUP) + start + call + "\nprint('finished', flush=True)\n"
    child = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout is not None
        line = child.stdout.readline()  # after imports and set-up
        assert line.strip() == "started", child.stderr.read() if child.stderr else ""
        time.sleep(1.0)
        assert child.poll() is None, "the run ended before it was interrupted"
        os.kill(child.pid, signal.SIGINT)
        sent = time.perf_counter()
        out, err = child.communicate(timeout=30)
        waited = time.perf_counter() - sent
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert "finished" not in out
    assert "KeyboardInterrupt" in err, err[-2000:]
    assert waited < 2.0, f"{name} took {waited:.2f} s to stop after SIGINT"
