"""The user cache directory, shared by the space-weather download and the sampled
density fields, and the entries stored in it.

An entry is a ``.npz`` file of named arrays plus a sha256 checksum of their contents. It
is written under a unique temporary name (process id, thread id and random bytes) in the
same directory and renamed into place, so readers never see half a file and concurrent
writers never collide. Misuse never loses a computed value:

* a corrupt entry (truncated, not an npz, wrong checksum) gives a :class:`CacheWarning`
  and is treated as missing, so the caller recomputes and overwrites it;
* an unreadable or unwritable cache (read-only, replaced by a file, disk full) gives a
  :class:`CacheWarning` and the caller keeps the value in memory; a directory deleted
  meanwhile is made again;
* the directory is kept under a size cap, ``$RHOPROP_CACHE_MAX_BYTES`` (default
  2 GB = 2e9 bytes; 0 disables writing), by deleting the least recently used entries
  (a hit refreshes an entry's modification time). An entry larger than the cap is not
  written.
"""

from __future__ import annotations

import hashlib
import os
import re
import secrets
import threading
import warnings
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ._validate import json_text
from .errors import CacheWarning

#: Environment variable of the size cap of each cache directory, bytes.
MAX_BYTES_ENV = "RHOPROP_CACHE_MAX_BYTES"
#: Environment variable of the in-memory density-tile budget, bytes (read by
#: :mod:`rhoprop.density.atlas`).
FIELD_MEMORY_ENV = "RHOPROP_FIELD_MEMORY"
#: Default size cap, bytes (2 GB).
DEFAULT_MAX_BYTES = 2_000_000_000
#: Name of the checksum array inside an entry.
CHECKSUM = "checksum"

_LOCKS: dict[str, threading.Lock] = {}
_LOCKS_GUARD = threading.Lock()


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


def bytes_from_env(name: str, default: int) -> int:
    """A number of bytes from the environment variable ``name`` (a number >= 0, e.g.
    ``5e8``), or ``default`` when it is unset or empty. ValueError naming the variable if
    it is not a number >= 0."""
    text = os.environ.get(name, "").strip()
    if not text:
        return default
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value >= 0 or value == float("inf"):
        raise ValueError(f"{name} must be a number of bytes >= 0, got {text!r}")
    return int(value)


def max_bytes() -> int:
    """The size cap of a cache directory, bytes: ``$RHOPROP_CACHE_MAX_BYTES`` (a number
    >= 0, e.g. ``5e8``) or :data:`DEFAULT_MAX_BYTES`. ValueError naming the variable if it
    is not a number >= 0."""
    return bytes_from_env(MAX_BYTES_ENV, DEFAULT_MAX_BYTES)


def check_environment() -> None:
    """ValueError naming the variable if ``$RHOPROP_CACHE_MAX_BYTES`` or
    ``$RHOPROP_FIELD_MEMORY`` is set to anything but a number of bytes >= 0: the command
    line checks them before a run, not when the run first needs them."""
    max_bytes()
    bytes_from_env(FIELD_MEMORY_ENV, 0)


def checksum(arrays: Mapping[str, np.ndarray]) -> str:
    """sha256 (hex) of named arrays: names, dtypes, shapes and bytes, in name order."""
    digest = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        digest.update(a.data.cast("B"))  # no copy of the (large) field arrays
    return digest.hexdigest()


def entry_lock(path: Path) -> threading.Lock:
    """A lock per entry path, so that threads of one process needing the same entry
    compute it once (the others then read it)."""
    key = str(path)
    with _LOCKS_GUARD:
        lock = _LOCKS.get(key)
        if lock is None:
            lock = _LOCKS[key] = threading.Lock()
        return lock


def _warn(message: str) -> None:
    warnings.warn(message, CacheWarning, stacklevel=3)


def load_entry(path: Path) -> dict[str, np.ndarray] | None:
    """The arrays of the entry at ``path`` (checksum verified and removed), or None if
    there is none. A corrupt or unreadable entry gives a :class:`CacheWarning` and None,
    so the caller recomputes the value and overwrites the entry."""
    try:
        # Our own handle: numpy leaves it open when the zip is truncated.
        with open(path, "rb") as handle, np.load(handle, allow_pickle=False) as saved:
            arrays = {name: saved[name] for name in saved.files}
    except (FileNotFoundError, NotADirectoryError):
        return None
    except (OSError, ValueError, EOFError, KeyError, TypeError, zipfile.BadZipFile) as err:
        # (TypeError: a plain .npy, not an archive.)
        _warn(f"cache entry {path} is unreadable ({err}); recomputing it")
        return None
    stored = arrays.pop(CHECKSUM, None)
    if stored is None or str(stored) != checksum(arrays):
        _warn(f"cache entry {path} is corrupt (checksum mismatch); recomputing it")
        return None
    for name, values in arrays.items():  # rhoprop stores only finite numbers
        if values.dtype.kind in "fc" and not np.isfinite(values).all():
            _warn(f"cache entry {path} holds non-finite values in {name!r}; recomputing it")
            return None
    try:
        os.utime(path)  # a hit makes the entry the most recently used
    except OSError:
        pass
    return arrays


def store_entry(path: Path, arrays: Mapping[str, Any]) -> bool:
    """Writes ``arrays`` with their checksum to ``path`` atomically and evicts the least
    recently used entries of its directory beyond :func:`max_bytes`. Returns whether the
    entry was written; an OSError (unwritable or vanished directory, full disk) gives a
    :class:`CacheWarning` instead of an exception."""
    data: dict[str, Any] = {name: np.asarray(a) for name, a in arrays.items()}
    data[CHECKSUM] = np.array(checksum(data))
    cap = max_bytes()
    size = sum(a.nbytes for a in data.values())
    if size > cap:
        return False  # documented: an entry larger than the cap is not written
    temporary: Path | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        temporary = path.with_name(
            f".{path.name}.{os.getpid()}.{threading.get_ident()}.{secrets.token_hex(8)}.tmp"
        )
        with open(temporary, "xb") as out:
            np.savez(out, **data)
        os.replace(temporary, path)
        temporary = None
        _evict(path.parent, cap, keep=path)
    except OSError as err:
        _warn(f"could not write cache entry {path} ({err}); the value is kept in memory only")
        return False
    finally:
        if temporary is not None:
            try:
                temporary.unlink(missing_ok=True)
            except OSError:
                pass
    return True


def _evict(directory: Path, cap: int, keep: Path) -> None:
    """Deletes the least recently used ``*.npz`` entries of ``directory`` until their
    total size is at most ``cap`` (never ``keep``, the entry just written)."""
    entries = []
    for path in directory.glob("*.npz"):
        try:
            stat = path.stat()
        except OSError:
            continue  # removed meanwhile by another process
        entries.append((stat.st_mtime_ns, stat.st_size, path))
    total = sum(size for _, size, _ in entries)
    for _, size, path in sorted(entries, key=lambda e: e[0]):
        if total <= cap:
            break
        if path == keep:
            continue
        try:
            path.unlink(missing_ok=True)
        except OSError:
            continue
        total -= size


def cache_info(override: str | os.PathLike[str] | None = None) -> dict[str, Any]:
    """What the cache holds: its directory, the size cap (bytes), and per subfolder
    (``tiles`` for the density atlas's day tiles, ``fields`` for fields sampled by
    :meth:`~rhoprop.density.SampledModel.field`, downloads such as the space-weather
    record and JB2008 indices) the number of files and their bytes, and under ``tiles``
    the atlas's tiles by model: its description, days, files and bytes."""
    root = cache_dir(override)
    parts: dict[str, dict[str, int]] = {}
    if root.is_dir():
        for path in sorted(root.rglob("*")):
            if path.is_file() and not path.is_symlink():
                rel = path.relative_to(root)
                key = rel.parts[0] if len(rel.parts) > 1 else "."
                part = parts.setdefault(key, {"files": 0, "bytes": 0})
                part["files"] += 1
                part["bytes"] += path.stat().st_size
    return {
        "directory": str(root),
        "max_bytes_per_folder": max_bytes(),
        "parts": parts,
        "total_bytes": sum(p["bytes"] for p in parts.values()),
        "tiles": tiles_on_disk(root / "tiles"),
    }


def tiles_on_disk(root: Path) -> list[dict[str, Any]]:
    """The tiles under ``root`` (a cache's ``tiles`` folder, written by
    :mod:`rhoprop.density.atlas`) by model: the model's description, its days and their
    bytes."""
    out: list[dict[str, Any]] = []
    if not root.is_dir():
        return out
    for folder in sorted(p for p in root.iterdir() if p.is_dir()):
        files = sorted(folder.glob("*.npz"))
        if not files:
            continue
        try:
            label = json_text((folder / "model.json").read_text(), folder.name).get(
                "repr", folder.name
            )
        except (OSError, ValueError, AttributeError):
            label = folder.name
        days = sorted({f.name[:10] for f in files})
        out.append(
            {
                "folder": folder.name,
                "model": label,
                "days": days,
                "files": len(files),
                "bytes": sum(f.stat().st_size for f in files),
            }
        )
    return out


#: The files rhoprop writes into its cache, by relative path (the layout is the cache's
#: manifest: ``cache clear`` deletes these and nothing else). Entries, then downloads.
_ENTRIES = re.compile(
    r"^(fields/[0-9a-f]{32}\.npz|tiles/[^/]+/(\d{4}-\d{2}-\d{2}_[0-9a-f]{24}\.npz|model\.json))$"
)
_DOWNLOADS = re.compile(r"^(SW-All\.(csv|txt)|jb2008/(SOLFSMY|DTCFILE)\.TXT)$")
#: Temporaries of the writers above (store_entry, the atlas's model.json, downloads).
_TEMPORARIES = re.compile(
    r"^(fields/|tiles/[^/]+/)?\.[^/]+\.tmp$|^(jb2008/)?\.(SW-All|SOLFSMY\.TXT|DTCFILE\.TXT)-[^/]*\.part$"
)


def owned_files(
    override: str | os.PathLike[str] | None = None, *, everything: bool = False
) -> tuple[list[Path], list[Path]]:
    """The files under the cache directory as (rhoprop's: the sampled fields and atlas
    tiles, with ``everything`` also the downloads and temporaries of interrupted writes;
    the rest). Symbolic links are never followed."""
    root = cache_dir(override)
    ours: list[Path] = []
    rest: list[Path] = []
    for here, dirs, files in os.walk(root):
        dirs.sort()
        for name in sorted(files):
            path = Path(here) / name
            rel = path.relative_to(root).as_posix()
            mine = _ENTRIES.match(rel) or (
                everything and (_DOWNLOADS.match(rel) or _TEMPORARIES.match(rel))
            )
            (ours if mine and not path.is_symlink() else rest).append(path)
    return ours, rest


def clear_cache(
    override: str | os.PathLike[str] | None = None, *, everything: bool = False
) -> tuple[int, int]:
    """Deletes the sampled density fields and atlas tiles (``fields/*.npz``,
    ``tiles/*/*.npz`` and the tiles' ``model.json``), or with ``everything`` also the
    downloaded space-weather record and JB2008 indices (which ``rhoprop data refresh``
    fetches again) and temporaries of interrupted writes. Only files of the names rhoprop
    writes there are deleted (a file of the user's in the cache directory stays); folders
    left empty are removed. Returns (files, bytes) deleted."""
    root = cache_dir(override)
    ours, _ = owned_files(override, everything=everything)
    files = n_bytes = 0
    for path in ours:
        try:
            size = path.lstat().st_size
            path.unlink()
        except FileNotFoundError:
            continue  # removed meanwhile by another process
        files, n_bytes = files + 1, n_bytes + size
    for parent in sorted({p.parent for p in ours}, key=lambda d: -len(d.parts)):
        while parent != root and parent.is_relative_to(root):
            try:
                parent.rmdir()  # only if empty
            except OSError:
                break
            parent = parent.parent
    return files, n_bytes
