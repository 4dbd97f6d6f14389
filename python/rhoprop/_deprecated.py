"""Keywords kept one release after they moved into a settings record: folded into the
record with a DeprecationWarning that says where they go now."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import fields, replace
from typing import Any, TypeVar

R = TypeVar("R")


def fold_keywords(
    function: str,
    argument: str,
    record: R | None,
    default: R,
    given: Mapping[str, object],
    spelled: str,
    stacklevel: int = 3,
    renamed: Mapping[str, str] | None = None,
) -> R:
    """``record`` (None: ``default``, the function's own) with the deprecated keywords
    ``given`` of ``function`` folded in, with a DeprecationWarning pointing to
    ``argument=spelled(...)``. A keyword the record does not have is a TypeError, as
    Python's own; so is a keyword given together with ``argument=`` (one place for a
    setting). ``renamed`` maps a keyword to its field where the names differ
    (``initial_covariance`` -> ``covariance``)."""
    renamed = renamed or {}
    names = {f.name for f in fields(default)}  # type: ignore[arg-type]
    wrong = sorted({renamed.get(k, k) for k in given} - names)
    if wrong:
        raise TypeError(f"{function}() got an unexpected keyword argument {wrong[0]!r}")
    if not given:
        return default if record is None else record
    keys = ", ".join(f"{k}=" for k in given)
    if record is not None:
        raise TypeError(f"{function}() got {argument}= and {keys}; give the settings in one place")
    warnings.warn(
        f"{function}({keys}) is deprecated; give "
        f"{argument}={spelled}({', '.join(f'{renamed.get(k, k)}=...' for k in given)})",
        DeprecationWarning,
        stacklevel=stacklevel,
    )
    changes: dict[str, Any] = {renamed.get(k, k): v for k, v in given.items()}
    return replace(default, **changes)  # type: ignore[type-var]
