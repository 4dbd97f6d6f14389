"""The commands' jobs: one typed, frozen record per command of the ``rhoprop`` CLI
(``CatalogJob``, ``ReentryJob``, ``ScreenJob``, ``ConjunctionJob``, ``PaperJob``,
``ScenarioJob``), each with ``run()``, which does the command's work (reads the input,
calls the library, writes the files, prints the report). The CLI only parses its
arguments into a job. The density models the commands know by name: :mod:`.models`.

A job is a plain record, so a script or a scheduler runs a command without the CLI::

    from rhoprop.jobs import CatalogJob
    CatalogJob("active.tle", end="2023-11-16T00:00Z", out="run1").run()
"""

from .catalog import CatalogJob, ReentryJob
from .conjunction import ConjunctionJob
from .models import FAMILIES, MODEL_NAMES, model_by_name, models_by_name
from .screen import ScreenJob
from .studies import PaperJob, ScenarioJob

#: The job of each ``rhoprop`` command that runs one.
JOBS = {
    "catalog": CatalogJob,
    "reentry": ReentryJob,
    "screen": ScreenJob,
    "conjunction": ConjunctionJob,
    "paper": PaperJob,
    "run": ScenarioJob,
}

__all__ = [
    "FAMILIES",
    "JOBS",
    "MODEL_NAMES",
    "CatalogJob",
    "ConjunctionJob",
    "PaperJob",
    "ReentryJob",
    "ScenarioJob",
    "ScreenJob",
    "model_by_name",
    "models_by_name",
]
