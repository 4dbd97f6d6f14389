"""Shared fixtures: the paper's orbit and the analytic benchmark atmosphere."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

import rhoprop as rp

sys.path.insert(0, str(Path(__file__).parent))


@pytest.fixture(autouse=True, scope="session")
def _isolated_cache(tmp_path_factory):
    """Sampled fields and downloads go to a temporary cache, never the user's."""
    mp = pytest.MonkeyPatch()
    mp.setenv("RHOPROP_CACHE", str(tmp_path_factory.mktemp("rhoprop-cache")))
    yield
    mp.undo()


@pytest.fixture
def paper_state() -> rp.OrbitState:
    """The paper's state labelled TEME: the axes the dynamics are written in (the zonal
    field's pole is z there), so that independent references that put J2 about z
    compare with it directly. ``rp.scenarios.paper_state()`` itself is GCRF."""
    s = rp.scenarios.paper_state()
    return rp.OrbitState(s.epoch, s.position, s.velocity, "TEME")


@pytest.fixture
def paper_craft() -> rp.Spacecraft:
    return rp.scenarios.paper_spacecraft()


@pytest.fixture
def benchmark_atmosphere() -> rp.density.Exponential:
    return rp.scenarios.benchmark_exponential()


@pytest.fixture(scope="session")
def test_data() -> Path:
    """The third-party reference data (``../shared/data`` in CI): never copied into the
    repository, read from ``$RHOPROP_TEST_DATA``. Skips with a reason where it is unset (a
    user's clone); fails under CI, which must provide it."""
    import os

    root = os.environ.get("RHOPROP_TEST_DATA")
    if not root:
        if os.environ.get("CI"):
            pytest.fail("RHOPROP_TEST_DATA is unset under CI; .ci/run must point it at the data")
        pytest.skip("RHOPROP_TEST_DATA is unset: reference data not available in this clone")
    path = Path(root)
    if not path.is_dir():
        pytest.fail(f"RHOPROP_TEST_DATA={root} is not a directory")
    return path
