"""Worker processes forked after a core run: `multiprocessing`'s default
on Linux forks, and a child inherits rayon's global pool without its threads, so it waited
for ever. The core's pool is now made again in each process (rust/python/src/pool.rs)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="fork is POSIX")

SCRIPT = textwrap.dedent(
    """
    import multiprocessing as mp
    import rhoprop as rp

    state, craft = rp.scenarios.paper_state(), rp.scenarios.paper_spacecraft()
    model = rp.scenarios.benchmark_exponential(0.2)

    def job(seed):
        mc = rp.monte_carlo(state, craft, model, 3600.0, n=64, seed=seed, progress=False)
        cc = rp.ccsp(state, craft, model, 3600.0)
        return mc.positions[:, -1].tobytes(), cc.mean[-1].tobytes()

    if __name__ == "__main__":
        parent = [job(s) for s in (1, 2)]  # the parent's pool runs first
        with mp.get_context("fork").Pool(2) as pool:
            children = pool.map(job, [1, 2])
        assert children == parent, "a forked child's numbers differ from the parent's"
        print("ok")
    """
)


def test_core_runs_in_processes_forked_after_a_run(tmp_path):
    script = tmp_path / "fork_after_run.py"
    script.write_text(SCRIPT)
    # A few seconds when it works; the old binding never returned.
    done = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "ok"
