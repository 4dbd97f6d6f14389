"""How many workers run at once: the ``--threads`` option of the command line and
``$RHOPROP_THREADS``. The core's thread pool reads ``$RAYON_NUM_THREADS`` at each call
(it is made again when that changes, and in a forked child); the Python pools that run
objects side by side (catalogs, fits, screening) read :func:`worker_count`. Results never
depend on the count (fixed seeds per member)."""

from __future__ import annotations

import concurrent.futures as cf
import os
import threading
from collections.abc import Callable, Sequence
from typing import TypeVar

T = TypeVar("T")
R = TypeVar("R")

#: Environment variable of the default worker count.
THREADS_ENV = "RHOPROP_THREADS"
#: Most worker threads per CPU core a run may ask for (more only thrash and, by the
#: thousand, exhaust the process's threads).
MAX_THREADS_PER_CPU = 4


def max_threads() -> int:
    """The most worker threads a run may use: 4 per CPU core."""
    return MAX_THREADS_PER_CPU * (os.cpu_count() or 1)


def worker_count(threads: int | None = None) -> int:
    """``threads`` if given, else ``$RHOPROP_THREADS``, else the CPU count; ValueError
    naming the source unless a whole number from 1 to :func:`max_threads`."""
    source = "threads"
    value: object = threads
    if threads is None:
        text = os.environ.get(THREADS_ENV, "").strip()
        if not text:
            return os.cpu_count() or 1
        source, value = f"${THREADS_ENV}", text
    try:
        count = int(str(value))
    except ValueError:
        count = 0
    if isinstance(value, bool) or count < 1 or str(count) != str(value).strip():
        raise ValueError(f"{source} must be a whole number >= 1, got {value!r}")
    if count > max_threads():
        raise ValueError(
            f"{source} = {count} is more than {max_threads()} ({MAX_THREADS_PER_CPU} per CPU "
            "core of this machine)"
        )
    return count


def core_threads() -> int | None:
    """Threads of a core call given none: ``$RHOPROP_THREADS`` when set (checked as
    :func:`worker_count` checks it: a bad value was ignored here), else None (the core's
    pool, ``$RAYON_NUM_THREADS`` or every CPU)."""
    if not os.environ.get(THREADS_ENV, "").strip():
        return None
    return worker_count()


def set_threads(threads: int) -> None:
    """Makes ``threads`` the default of this process: the Python pools (through
    ``$RHOPROP_THREADS``) and the core's pool (``$RAYON_NUM_THREADS``, read at the next
    core call)."""
    count = worker_count(threads)
    os.environ[THREADS_ENV] = str(count)
    os.environ["RAYON_NUM_THREADS"] = str(count)


def map_in_threads(
    fn: Callable[[T], R],
    items: Sequence[T],
    workers: int,
    stop: threading.Event,
    on_result: Callable[[int, R], object] | None = None,
) -> list[R]:
    """``fn`` over ``items`` on ``workers`` threads (the core releases the GIL), results
    in input order; ``on_result(i, result)`` is called in order as each comes in (e.g. a
    progress bar). An error or Ctrl-C sets ``stop`` (for ``fn`` to end early), cancels the
    items not started and is raised."""
    pool = cf.ThreadPoolExecutor(max_workers=workers)
    results: list[R] = []
    try:
        futures = [pool.submit(fn, item) for item in items]
        for i, fut in enumerate(futures):
            results.append(fut.result())
            if on_result is not None:
                on_result(i, results[-1])
    except BaseException:
        stop.set()
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()
    return results
