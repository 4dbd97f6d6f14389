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
    return rp.scenarios.paper_state()


@pytest.fixture
def paper_craft() -> rp.Spacecraft:
    return rp.scenarios.paper_spacecraft()


@pytest.fixture
def benchmark_atmosphere() -> rp.density.Exponential:
    return rp.scenarios.benchmark_exponential()
