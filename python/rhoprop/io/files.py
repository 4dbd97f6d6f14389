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
import re
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .._validate import json_text
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
    holding a previous run's files (it has rhoprop's ``manifest.json``) is refused, or with
    ``overwrite=True`` cleared of that run's files first. rhoprop deletes only files a
    manifest of its own lists: the files of the manifest plus those in its journal
    (``.rhoprop-journal``, where each file is listed before it is written, so that an
    interrupted run's files are known too) and the temporaries of those files. A folder
    holding anything else (a file of the user's, another tool's ``manifest.json``, a name
    reaching outside the folder) is refused and nothing is deleted. A manifest marked
    incomplete is written at once (a folder holding only the manifest of a run that wrote
    nothing is reused as empty). Files go through :meth:`path` (a temporary name, renamed
    when done) or are announced by :meth:`expect` before a writer puts them there, and
    are listed in the manifest by :meth:`finish`, with the rhoprop version and the command.
    """

    def __init__(self, directory: str | Path, *, command: str, overwrite: bool = False) -> None:
        self.directory = Path(directory)
        self.command = command
        self.files: list[Path] = []
        self._listed: set[str] = set()
        self.started = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
        if self.directory.exists() and not self.directory.is_dir():
            raise NotADirectoryError(f"output folder {self.directory} is a file")
        if self.directory.exists():
            self._claim(overwrite)
        self.directory.mkdir(parents=True, exist_ok=True)
        self._write_manifest(complete=False)

    def _claim(self, overwrite: bool) -> None:
        """Empties the existing folder of an earlier run's files (see the class
        docstring), or raises FileExistsError deleting nothing."""
        entries = sorted(self.directory.iterdir())
        manifest = self.directory / MANIFEST
        if not entries:
            return
        names = ", ".join(p.name for p in entries[:5]) + (", ..." if len(entries) > 5 else "")
        listed = _listed_files(self.directory)
        if listed is None:
            raise FileExistsError(
                f"output folder {self.directory} is not empty ({names}) and holds no "
                f"{MANIFEST} of an earlier rhoprop run; choose an empty or new folder"
            )
        ours, foreign = _split(self.directory, listed)
        if foreign:
            shown = ", ".join(foreign[:5]) + (", ..." if len(foreign) > 5 else "")
            raise FileExistsError(
                f"output folder {self.directory} holds files that no rhoprop manifest of "
                f"it lists ({shown}); rhoprop deletes only its own files: move them away "
                "or choose another folder"
            )
        produced = [
            p for p in ours if p.parent != self.directory or p.name not in (MANIFEST, JOURNAL)
        ]
        if not overwrite and (produced or _produced(manifest)):
            # (A folder holding only the manifest of a run that wrote nothing is reused.)
            raise FileExistsError(
                f"output folder {self.directory} holds the files of an earlier run "
                f"({names}); choose another folder or overwrite it (--overwrite on the "
                "command line, overwrite=True in Python)"
            )
        for path in ours:
            path.unlink(missing_ok=True)
        for parent in sorted({p.parent for p in ours}, key=lambda d: -len(d.parts)):
            while parent != self.directory and parent.is_relative_to(self.directory):
                try:
                    parent.rmdir()  # only if empty
                except OSError:
                    break
                parent = parent.parent

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

    def expect(self, paths: list[Path]) -> None:
        """Lists in the journal files that a writer is about to put into the folder (so
        that an interrupted run's files are still known as the run's)."""
        new = []
        for p in paths:
            rel = Path(p).relative_to(self.directory).as_posix()
            if rel not in self._listed:
                self._listed.add(rel)
                new.append(rel)
        if new:
            with open(self.directory / JOURNAL, "a") as journal:
                journal.write("".join(f"{rel}\n" for rel in new))

    @contextlib.contextmanager
    def path(self, name: str | Path) -> Iterator[Path]:
        """A temporary path for the file ``name`` (relative to the folder), renamed to it
        when the block ends without error and then listed in the manifest."""
        final = self.directory / name
        self.expect([final])
        with atomic_path(final) as tmp:
            yield tmp
        self.files.append(final)

    def write_text(self, name: str | Path, text: str) -> Path:
        """Writes a text file of the run."""
        with self.path(name) as tmp:
            tmp.write_text(text)
        return self.directory / name

    def add(self, paths: list[Path]) -> None:
        """Lists files a writer already put (atomically) into the folder (announce them
        with :meth:`expect` before writing)."""
        self.expect([Path(p) for p in paths])
        self.files.extend(Path(p) for p in paths)

    def finish(self) -> Path:
        """Writes the complete manifest and removes the journal; returns its path."""
        self._write_manifest(complete=True)
        (self.directory / JOURNAL).unlink(missing_ok=True)
        return self.directory / MANIFEST


#: The journal of files a running run has announced (see :class:`OutputFolder`).
JOURNAL = ".rhoprop-journal"
#: Temporary names of :func:`atomic_path` (and the OEM writer's ``.kvn`` beside them).
_TEMPORARY = re.compile(r"^\.(?P<stem>.+)\.tmp\d+-[0-9a-f]+(?P<suffix>\.[^.]*)?(\.kvn)?$")


def _listed_files(directory: Path) -> set[str] | None:
    """The relative names that rhoprop's manifest (and journal) in ``directory`` list,
    or None if the folder has no manifest of rhoprop's (missing, unreadable, or not
    rhoprop's shape: an object with ``rhoprop_version`` and a list of names)."""
    try:
        data = json_text((directory / MANIFEST).read_text(), str(directory / MANIFEST))
    except (OSError, ValueError):  # unreadable, not JSON, nested too deep: not rhoprop's
        return None
    if not (
        isinstance(data, dict)
        and isinstance(data.get("rhoprop_version"), str)
        and isinstance(data.get("files"), list)
        and all(isinstance(name, str) for name in data["files"])
    ):
        return None
    names = set(data["files"]) | {MANIFEST, JOURNAL}
    try:
        # A damaged line (a byte that is not UTF-8) names no file of ours: whatever it
        # meant stays foreign, and the overwrite refuses instead of deleting it.
        journal = (directory / JOURNAL).read_text(encoding="utf-8", errors="surrogateescape")
        names |= set(journal.splitlines())
    except OSError:
        pass
    return names


def _split(directory: Path, listed: set[str]) -> tuple[list[Path], list[str]]:
    """Every file under ``directory`` (symbolic links not followed) as (the run's: listed,
    or a temporary of a listed file; foreign: anything else, by relative name)."""
    ours: list[Path] = []
    foreign: list[str] = []
    for root, dirs, files in os.walk(directory):
        dirs.sort()
        here = Path(root)
        for name in [*sorted(files), *(d for d in dirs if (here / d).is_symlink())]:
            path = here / name
            rel = path.relative_to(directory).as_posix()
            temporary = _TEMPORARY.match(name)
            if temporary:
                final = here / (temporary["stem"] + (temporary["suffix"] or ""))
                rel_final = final.relative_to(directory).as_posix()
            if rel in listed or (temporary and rel_final in listed):
                ours.append(path)
            else:
                foreign.append(rel)
    return ours, foreign


def _produced(manifest: Path) -> bool:
    """Whether a manifest says its run completed or wrote files (unreadable: assume so)."""
    try:
        data = json_text(manifest.read_text(), str(manifest))
        return bool(data.get("complete")) or bool(data.get("files"))
    except (OSError, ValueError, AttributeError):
        return True


def command_line() -> str:
    """The command that runs now, as the manifest records it."""
    return " ".join(["rhoprop", *sys.argv[1:]]) if sys.argv else "rhoprop"
