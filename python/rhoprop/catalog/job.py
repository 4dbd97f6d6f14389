"""The ``rhoprop catalog`` job: a TLE/OMM file propagated to a common end epoch, written
as CCSDS OEM files and a Parquet summary."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..density import DensityModel, Exponential, Msis
from .elements import load
from .export import OutputFolder, command_line, oem_names, sanitise, write_oem, write_summary
from .run import STATUSES, propagate_catalog

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
    overwrite: bool = False,
    duplicates: str = "error",
    command: str | None = None,
) -> list[Path]:
    """Propagates every element set of ``file`` to ``end`` (UTC ISO) and writes one OEM
    file per object to ``out/oem``, ``out/summary.parquet`` (one row per object with its
    status) and ``out/manifest.json``; ``scheduler`` is a Dask scheduler address (needs
    the ``distributed`` extra).

    ``skip_bad``: malformed element sets are skipped and objects whose propagation fails
    get status "failed" (both reported on stderr) instead of stopping the run.
    ``overwrite``: clear ``out`` if it holds an earlier run's files (else refused).
    ``duplicates``: NORAD ids occurring twice are an error (default, checked before any
    propagation) or get suffixed OEM names (``"suffix"``). Returns the paths written."""
    cat = load(file, errors="skip" if skip_bad else "raise")
    for where, message in cat.skipped:
        print(f"skipped {sanitise(where)}: {sanitise(message, 300)}", file=sys.stderr)
    if not len(cat):
        raise ValueError(f"{file}: no element set could be read ({len(cat.skipped)} skipped)")
    oem_names(cat.objects, duplicates)  # repeated ids fail here, before any work
    atmosphere = model_by_name(model)
    folder = OutputFolder(out, command=command or command_line(), overwrite=overwrite)
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
        errors="record" if skip_bad else "raise",
    )
    wall = time.perf_counter() - t0
    directory = folder.directory
    paths = write_oem(result, directory / "oem", duplicates=duplicates)
    folder.add(paths)
    summary = write_summary(result, directory / "summary.parquet")
    folder.add([summary])
    manifest = folder.finish()
    counts = {s: int(np.count_nonzero(result.status == s)) for s in STATUSES}
    for obj, status, reason in zip(result.objects, result.status, result.reason, strict=True):
        if status != "propagated":
            print(
                f"{obj.norad_id} {sanitise(obj.name)}: {status}: {sanitise(reason, 300)}",
                file=sys.stderr,
            )
    print(
        f"{len(cat)} objects ({len(cat.skipped)} skipped), {method}, to {end}: "
        f"{wall:.1f} s ({len(cat) / wall:.1f} objects/s); "
        + ", ".join(f"{v} {k}" for k, v in counts.items())
    )
    no_file = len(cat) - len(paths)
    print(
        f"wrote {len(paths)} OEM files to {directory / 'oem'}"
        + (f" ({no_file} objects without a valid epoch have none)" if no_file else "")
        + f", {summary} and {manifest}"
    )
    return [*paths, summary, manifest]
