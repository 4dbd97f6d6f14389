"""How a run over many objects executes: :class:`Execution`. One record that a catalog,
reentry or screening run takes whole (``execution=``) and a job hands from one run to
the next. Nothing in it changes a number of an object that runs: results are the same
bit for bit whatever the threads, the Dask client or the chunking (fixed seeds per
object and member)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from . import _validate
from ._deprecated import fold_keywords
from .options import Errors
from .parallel import worker_count

__all__ = ["Execution", "execution_argument"]


@dataclass(frozen=True)
class Execution:
    """How a run over many objects executes, checked when made.

    Attributes:
        threads: worker threads (None: ``$RHOPROP_THREADS``, else every core; at most 4
            per core). Results do not depend on it.
        client: a ``dask.distributed.Client`` to run on (None: this process); checked by
            the function that runs on it, which names itself. Results equal the local
            run's.
        chunk_size: objects per task sent to ``client`` (>= 1).
        progress: True shows progress bars on a terminal for runs over a second; False
            none; or a callable, called with what each function documents (the objects
            done; for ``screen_all`` the stage, done and total).
        errors: ``"raise"`` (default): the first object that fails raises its error,
            named; ``"record"``: it is recorded in the result (a status, ``skipped``) and
            the run goes on.
        max_memory: bytes one step of the run may hold (None: each function's default;
            ``screen_all`` cuts its window into time chunks whose tracks fit it).

    Example:
        >>> import rhoprop as rp
        >>> rp.Execution(threads=2, progress=False).errors
        'raise'
    """

    threads: int | None = None
    client: object = None
    chunk_size: int = 50
    progress: bool | Callable[..., object] = True
    errors: Errors = "raise"
    max_memory: float | None = None

    def __post_init__(self) -> None:
        if self.threads is not None:
            if isinstance(self.threads, bool) or not isinstance(self.threads, (int, np.integer)):
                raise ValueError(f"threads must be a positive integer, got {self.threads!r}")
            object.__setattr__(self, "threads", worker_count(int(self.threads)))
        if (
            isinstance(self.chunk_size, bool)
            or not isinstance(self.chunk_size, int)
            or self.chunk_size < 1
        ):
            raise ValueError(f"chunk_size must be a positive integer, got {self.chunk_size!r}")
        if not isinstance(self.progress, bool) and not callable(self.progress):
            raise TypeError(
                f"progress must be True, False or a callable, got {type(self.progress).__name__}"
            )
        object.__setattr__(self, "errors", _validate.errors_argument("Execution", self.errors))
        if self.max_memory is not None:
            object.__setattr__(
                self, "max_memory", _validate.positive("max_memory", self.max_memory)
            )

    def require_defaults(self, function: str, names: tuple[str, ...]) -> None:
        """ValueError if ``function``, which does not use ``names`` (attributes), is given
        one of them away from its default: a setting a function cannot use is refused,
        never ignored."""
        default = Execution()
        changed = [n for n in names if getattr(self, n) != getattr(default, n)]
        if changed:
            raise ValueError(
                f"{function}() does not use execution.{' or execution.'.join(changed)}; "
                "leave it at the default"
            )


def execution_argument(
    function: str,
    execution: Execution | None,
    given: Mapping[str, object],
    stacklevel: int = 4,
) -> Execution:
    """The :class:`Execution` of a call to ``function``: ``execution`` (None: the
    defaults) with the call's deprecated loose keywords ``given`` (``threads=``,
    ``progress=``, ...) folded in with a DeprecationWarning (:func:`fold_keywords`)."""
    if execution is not None and not isinstance(execution, Execution):
        raise TypeError(f"execution must be a rhoprop.Execution, got {type(execution).__name__}")
    out = fold_keywords(
        function, "execution", execution, Execution(), given, "rp.Execution", stacklevel
    )
    _validate.client(function, out.client)
    return out
