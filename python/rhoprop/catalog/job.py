"""The ``rhoprop catalog`` job: a TLE/OMM file propagated to a common end epoch, written
as CCSDS OEM files and a Parquet summary."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..density import DensityModel, Exponential, Msis
from .elements import load
from .export import write_oem, write_summary
from .run import propagate_catalog

#: Density models by the names the command line accepts.
MODEL_NAMES = ("2.1", "2.0", "00", "exponential")


def model_by_name(name: str) -> DensityModel:
    """An NRLMSIS version ("2.1", "2.0", "00") or the benchmark exponential atmosphere with
    20 % relative sigma ("exponential")."""
    if name == "exponential":
        return Exponential.benchmark(0.2)
    if name not in MODEL_NAMES:
        raise ValueError(f"unknown model {name!r}; expected one of {', '.join(MODEL_NAMES)}")
    return Msis(name)


def run_catalog_file(
    file: str | Path,
    end: str,
    out: str | Path,
    *,
    method: str = "ccsp",
    members: int = 100,
    model: str = "2.1",
    output_step: float = 3600.0,
    scheduler: str | None = None,
    skip_bad: bool = False,
) -> list[Path]:
    """Propagates every element set of ``file`` to ``end`` (UTC ISO) and writes one OEM
    file per object to ``out/oem`` and ``out/summary.parquet``; ``scheduler`` is a Dask
    scheduler address (needs the ``distributed`` extra). Returns the paths written."""
    cat = load(file, errors="skip" if skip_bad else "raise")
    for where, message in cat.skipped:
        print(f"skipped {where}: {message}", file=sys.stderr)
    atmosphere = model_by_name(model)
    client = None
    if scheduler:
        from distributed import Client

        client = Client(scheduler)
    t0 = time.perf_counter()
    result = propagate_catalog(
        cat,
        atmosphere,
        end,
        method=method,
        n=members,
        client=client,
        output_step=output_step,
    )
    wall = time.perf_counter() - t0
    directory = Path(out)
    paths = write_oem(result, directory / "oem")
    summary = write_summary(result, directory / "summary.parquet")
    decayed = int(np.count_nonzero(~np.isnat(result.decay_epoch)))
    print(
        f"{len(cat)} objects ({len(cat.skipped)} skipped), {method}, to {end}: "
        f"{wall:.1f} s ({len(cat) / wall:.1f} objects/s); {decayed} decay within the window"
    )
    print(f"wrote {len(paths)} OEM files to {directory / 'oem'} and {summary}")
    return [*paths, summary]
