"""The output folder of a run and safe file writes: :class:`OutputFolder` (every file
written to a temporary name and renamed, a ``manifest.json`` of what the run produced, and
no mixing with another run's files), atomic writes, the command line recorded in
manifests, and :func:`sanitise` for text copied from inputs into outputs (only printable
ASCII survives, anything else becomes ``_``)."""

from __future__ import annotations

import contextlib
import datetime as _dt
import json
import os
import shutil
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .._version import __version__

#: The manifest every run writes into its output folder.
MANIFEST = "manifest.json"


def sanitise(text: object, limit: int = 100) -> str:
    """``text`` as one line of printable ASCII (other characters become ``_``), stripped
    and cut to ``limit`` characters: safe to copy into a KVN header or a Markdown
    table."""
    clean = "".join(c if " " <= c <= "~" else "_" for c in str(text)).strip()
    return clean[:limit]


def _iso(t: np.datetime64) -> str:
    return str(t.astype("datetime64[us]"))


def _temporary(path: Path) -> Path:
    """A temporary name beside ``path`` with the same suffix (writers such as matplotlib
    pick the format from it), unique per process and thread."""
    return path.with_name(f".{path.stem}.tmp{os.getpid()}-{id(path):x}{path.suffix}")


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yields a temporary path to write ``path`` to; renamed onto ``path`` when the block
    ends without error, removed otherwise: a reader never sees a half-written file."""
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary(final)
    try:
        yield tmp
        os.replace(tmp, final)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Writes ``text`` to ``path`` through a temporary file and a rename."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


class OutputFolder:
    """The output folder of one run (``rhoprop paper``, ``run``, ``catalog``).

    On creation it claims ``directory``: a missing or empty folder is used; a folder
    holding a previous run's files (it has a ``manifest.json``) is refused, or with
    ``overwrite=True`` emptied first; a non-empty folder without a manifest is always
    refused (rhoprop deletes only what a run of its own wrote). A manifest marked
    incomplete is written at once, so an interrupted run's folder is recognised too (a
    folder holding only the manifest of a run that wrote nothing is reused as empty).
    Files go through :meth:`path` (a temporary name, renamed when done) and are listed
    in the manifest by :meth:`finish`, with the rhoprop version and the command.
    """

    def __init__(self, directory: str | Path, *, command: str, overwrite: bool = False) -> None:
        self.directory = Path(directory)
        self.command = command
        self.files: list[Path] = []
        self.started = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        if self.directory.exists() and not self.directory.is_dir():
            raise NotADirectoryError(f"output folder {self.directory} is a file")
        entries = sorted(self.directory.iterdir()) if self.directory.exists() else []
        if entries == [self.directory / MANIFEST] and not _produced(entries[0]):
            entries = []  # a run that stopped before it wrote anything: reuse quietly
        if entries:
            names = ", ".join(p.name for p in entries[:5]) + (", ..." if len(entries) > 5 else "")
            if not (self.directory / MANIFEST).is_file():
                raise FileExistsError(
                    f"output folder {self.directory} is not empty ({names}) and holds no "
                    f"{MANIFEST} of an earlier rhoprop run; choose an empty or new folder"
                )
            if not overwrite:
                raise FileExistsError(
                    f"output folder {self.directory} holds the files of an earlier run "
                    f"({names}); choose another folder or overwrite it (--overwrite on the "
                    "command line, overwrite=True in Python)"
                )
            for entry in entries:
                if entry.is_dir() and not entry.is_symlink():
                    shutil.rmtree(entry)
                else:
                    entry.unlink()
        self.directory.mkdir(parents=True, exist_ok=True)
        self._write_manifest(complete=False)

    def _write_manifest(self, complete: bool) -> None:
        manifest = {
            "rhoprop_version": __version__,
            "command": self.command,
            "started": self.started,
            "complete": complete,
            "files": [p.relative_to(self.directory).as_posix() for p in self.files],
        }
        if complete:
            manifest["finished"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        write_text_atomic(self.directory / MANIFEST, json.dumps(manifest, indent=2) + "\n")

    @contextlib.contextmanager
    def path(self, name: str | Path) -> Iterator[Path]:
        """A temporary path for the file ``name`` (relative to the folder), renamed to it
        when the block ends without error and then listed in the manifest."""
        final = self.directory / name
        with atomic_path(final) as tmp:
            yield tmp
        self.files.append(final)

    def write_text(self, name: str | Path, text: str) -> Path:
        """Writes a text file of the run."""
        with self.path(name) as tmp:
            tmp.write_text(text)
        return self.directory / name

    def add(self, paths: list[Path]) -> None:
        """Lists files a writer already put (atomically) into the folder."""
        self.files.extend(Path(p) for p in paths)

    def finish(self) -> Path:
        """Writes the complete manifest; returns its path."""
        self._write_manifest(complete=True)
        return self.directory / MANIFEST


def _produced(manifest: Path) -> bool:
    """Whether a manifest says its run completed or wrote files (unreadable: assume so)."""
    try:
        data = json.loads(manifest.read_text())
        return bool(data.get("complete")) or bool(data.get("files"))
    except (OSError, ValueError, AttributeError):
        return True


def command_line() -> str:
    """The command that runs now, as the manifest records it."""
    return " ".join(["rhoprop", *sys.argv[1:]]) if sys.argv else "rhoprop"
