"""Regression check of the benchmarks' ratios: reads the JSON the Python
benches wrote to ``benches/results/`` and compares each ratio (never an absolute time:
this machine kind is shared and noisy) with the last recorded figure of the same SIMD
path in ``benches/baseline.json``. A ratio more than ``--tolerance`` (default 15 %)
worse than recorded is a regression: listed, and the exit status is 1. ``--record``
writes the figures found into the baseline (commit it with the change that moved them).

Run:  python benches/monte_carlo.py; python benches/ccsp.py; python benches/fit.py; ...
      python benches/regress.py [--tolerance 0.15] [--record]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).parent
RESULTS = HERE / "results"
BASELINE = HERE / "baseline.json"

#: Ratio name -> (results file, reader, True if higher is better).
Reader = Callable[[dict], float | None]


def _peer(name: str) -> Reader:
    """The fastest peer row whose name holds ``name`` (the smallest time over rhoprop's)."""

    def read(d: dict) -> float | None:
        rows = [r for r in d.get("rows", []) if name in r["name"].lower()]
        return min(r["time_ratio_to_rhoprop"] for r in rows) if rows else None

    return read


METRICS: dict[str, tuple[str, Reader, bool]] = {
    "monte_carlo field / exponential": (
        "monte_carlo.json",
        lambda d: d.get("field_over_exponential"),
        True,
    ),
    "ccsp: monte carlo / ccsp time (exponential)": (
        "ccsp.json",
        lambda d: d.get("exponential", {}).get("ratio"),
        True,
    ),
    "fit: batched core / python reference": ("fit.json", lambda d: d.get("ratio"), True),
    "heyoka time / rhoprop time (fastest heyoka row)": (
        "compare_peers.json",
        _peer("heyoka"),
        True,
    ),
    "scipy time / rhoprop time": ("compare_peers.json", _peer("scipy"), True),
}


def current() -> dict[str, dict[str, float]]:
    """{SIMD path: {metric: value}} of the results present, each under the path its own
    results file records (the benches may have run on different paths)."""
    found: dict[str, dict[str, float]] = {}
    for metric, (file, read, _) in METRICS.items():
        f = RESULTS / file
        if not f.exists():
            continue
        data = json.loads(f.read_text())
        machine = data.get("machine", data)
        value = read(data)
        if value is not None:
            found.setdefault(machine.get("simd_path") or "unknown", {})[metric] = float(value)
    return found


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--tolerance", type=float, default=0.15)
    parser.add_argument("--record", action="store_true")
    args = parser.parse_args()
    by_path = current()
    if not by_path:
        print(f"no results in {RESULTS}: run the benches first", file=sys.stderr)
        return 2
    baseline = json.loads(BASELINE.read_text()) if BASELINE.exists() else {}
    worse = []
    for simd, found in sorted(by_path.items()):
        recorded = baseline.get(simd, {})
        print(f"SIMD path {simd}; tolerance {100 * args.tolerance:.0f} %")
        print(f"{'ratio':<50} {'now':>8} {'recorded':>9} {'change':>8}")
        for metric, value in found.items():
            old = recorded.get(metric)
            higher = METRICS[metric][2]
            if old is None:
                print(f"{metric:<50} {value:>8.3g} {'-':>9} {'new':>8}")
                continue
            change = value / old - 1
            bad = change < -args.tolerance if higher else change > args.tolerance
            worse += [metric] if bad else []
            flag = "  REGRESSION" if bad else ""
            print(f"{metric:<50} {value:>8.3g} {old:>9.3g} {100 * change:>+7.0f}%{flag}")
        if args.record:
            baseline[simd] = {**recorded, **found}
    if args.record:
        BASELINE.write_text(json.dumps(baseline, indent=1, sort_keys=True) + "\n")
        print(f"recorded in {BASELINE}")
        return 0
    return 1 if worse else 0


if __name__ == "__main__":
    sys.exit(main())
