"""``rhoprop paper`` and ``rhoprop run``: the paper's study and a TOML scenario, as typed
jobs (the studies themselves live in :mod:`rhoprop.studies`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .catalog import atlas_line

__all__ = ["PaperJob", "ScenarioJob"]


@dataclass(frozen=True)
class PaperJob:
    """The paper's study (:func:`rhoprop.studies.report.run_paper`) into ``out``:
    ``quick`` (1 day, 100 members), ``members`` per Monte Carlo (None: 1000, 100 with
    ``quick``), ``seed``, ``overwrite`` an earlier run's folder, the ``command`` recorded
    in the manifest. Its run also prints the density atlas's memory line."""

    out: str | Path
    quick: bool = False
    members: int | None = None
    seed: int = 0
    overwrite: bool = False
    command: str | None = None

    def run(self) -> list[Path]:
        """Runs the study. Returns the paths written."""
        from ..studies.report import run_paper

        paths = run_paper(
            self.out,
            quick=self.quick,
            members=self.members,
            seed=self.seed,
            overwrite=self.overwrite,
            command=self.command,
        )
        print(atlas_line())
        return paths


@dataclass(frozen=True)
class ScenarioJob:
    """A TOML scenario file (:func:`rhoprop.studies.scenario_file.run_scenario_file`):
    its ensemble, figure, summaries and OEM files in ``out`` (None: the file's
    ``output.directory``); ``seed`` overrides the file's Monte Carlo seed."""

    path: str | Path
    out: str | Path | None = None
    seed: int | None = None
    overwrite: bool = False
    command: str | None = None

    def run(self) -> int:
        """Runs the scenario. Returns the exit status (0)."""
        from ..studies.scenario_file import run_scenario_file

        return run_scenario_file(
            self.path,
            out=self.out,
            overwrite=self.overwrite,
            command=self.command,
            seed=self.seed,
        )
