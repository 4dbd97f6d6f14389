"""What a benchmark ran on: CPU model, cores and the SIMD path the core dispatched to.
Every bench script prints :func:`describe` first and stores :func:`info` in its JSON."""

from __future__ import annotations

import os
import platform
from pathlib import Path

from rhoprop import _core


def cpu_model() -> str:
    """The CPU model name (Linux /proc/cpuinfo, else the platform's processor string)."""
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def info() -> dict[str, object]:
    """CPU model, core count and the core's SIMD path, for the JSON results."""
    return {"cpu": cpu_model(), "cores": os.cpu_count(), "simd_path": _core.simd_path()}


def describe() -> str:
    """One line: 'CPU: <model>, <n> cores; SIMD path: <path>'."""
    i = info()
    return f"CPU: {i['cpu']}, {i['cores']} cores; SIMD path: {i['simd_path']}"


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far, MB."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def element_sets(text: str):
    """(name, line 1, line 2) of every 3-line element set of a TLE file's text, and its
    ``sgp4`` Satrec."""
    from sgp4.api import Satrec

    lines = [ln.rstrip() for ln in text.splitlines() if ln.strip()]
    for k in range(0, len(lines) - 2, 3):
        name, l1, l2 = lines[k : k + 3]
        if l1.startswith("1 ") and l2.startswith("2 "):
            yield name, l1, l2, Satrec.twoline2rv(l1, l2)


def perigee_altitude(sat) -> float:
    """Mean perigee altitude of an element set, m (Kozai mean motion, spherical Earth)."""
    a = (3.986004418e14 / (sat.no_kozai / 60.0) ** 2) ** (1 / 3)
    return a * (1 - sat.ecco) - 6378137.0
