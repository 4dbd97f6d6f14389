"""The user cache directory, shared by the space-weather download and the sampled
density fields."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir(override: str | os.PathLike[str] | None = None) -> Path:
    """The cache directory: ``override`` if given, else ``$RHOPROP_CACHE``, else
    ``$XDG_CACHE_HOME/rhoprop``, else ``~/.cache/rhoprop`` (not created here)."""
    if override is not None:
        return Path(override).expanduser()
    if os.environ.get("RHOPROP_CACHE"):
        return Path(os.environ["RHOPROP_CACHE"]).expanduser()
    if os.environ.get("XDG_CACHE_HOME"):
        return Path(os.environ["XDG_CACHE_HOME"]).expanduser() / "rhoprop"
    return Path.home() / ".cache" / "rhoprop"
