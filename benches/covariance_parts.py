"""What sets the width of the predicted covariance: ``history_days.py`` dumps recombined.

Give the ``--dump`` files of runs of ``history_days.py`` over the same starts that differ
only in ``--initial-covariance`` (the predicted means are the same). For each, and for
the near-zero ("paper") run with the truth's TLE accuracy replaced by an independent error
of the start and the truth (``--independent``, R,T,N m: by default about what
consecutive element sets measure of each other, ``element_set_pairs.py``), per horizon:
along-track errors inside 1 / 2 / 3 sigma, the median |error| / sigma (0.67 for a
calibrated Gaussian) and the share of start days whose 2-sigma share is in 85-98 %.

Run:  python benches/covariance_parts.py object.npz nodrift.npz --paper paper.npz
"""

from __future__ import annotations

import argparse

import numpy as np


def along_track(error: np.ndarray, cov: np.ndarray, start: np.ndarray) -> str:
    """The coverage figures of one configuration at one horizon, as a table cell."""
    ratio = np.abs(error[:, 1]) / np.sqrt(cov[:, 1, 1])
    inside = [100 * np.mean(ratio <= k) for k in (1, 2, 3)]
    days = [np.mean(ratio[start == d] <= 2) for d in np.unique(start)]
    in_band = 100 * np.mean([0.85 <= f <= 0.98 for f in days])
    return (
        " / ".join(f"{x:.0f}" for x in inside)
        + f", {np.median(ratio):.2f}, days in band {in_band:.0f} %"
    )


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("dumps", nargs="+", help="history_days.py --dump files")
    parser.add_argument("--paper", default=None, help="the --initial-covariance paper dump")
    parser.add_argument("--independent", default="11,115,9", help="R,T,N m (default 11,115,9)")
    args = parser.parse_args()
    runs = {path: dict(np.load(path)) for path in args.dumps}
    if args.paper:
        paper = dict(np.load(args.paper))
        runs[f"{args.paper}, truth's TLE accuracy"] = paper
        independent = np.diag([float(x) for x in args.independent.split(",")]) ** 2
        # Start and truth each with the independent error only.
        runs[f"{args.paper}, independent {args.independent} m"] = {
            **paper,
            "truth": np.broadcast_to(2 * independent, paper["truth"].shape),
        }
    horizons = sorted(set(np.concatenate([r["horizon"] for r in runs.values()])))
    print(
        "| run | "
        + " | ".join(f"{h:g} d: inside 1/2/3 sigma %, median |e|/sigma" for h in horizons)
        + " |"
    )
    print("| --- |" + " --- |" * len(horizons))
    for name, r in runs.items():
        cells = []
        for h in horizons:
            m = r["horizon"] == h
            cells.append(along_track(r["error"][m], r["cov"][m] + r["truth"][m], r["start"][m]))
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
