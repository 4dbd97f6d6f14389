"""The command line as a user runs it."""

from __future__ import annotations

import subprocess
import sys

from rhoprop.cli import main


def test_help_lists_commands(capsys):
    assert main([]) == 2
    out = capsys.readouterr().out
    assert "paper" in out and "usage: rhoprop" in out


def test_paper_quick_prints_methods_that_agree(capsys):
    assert main(["paper", "--quick"]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if line.strip().startswith(("rk8", "rk4"))]
    assert len(rows) == 2
    # Last column: distance to the adaptive solution after 6 h, m.
    assert all(float(r[-1]) < 0.1 for r in rows), rows


def test_console_script_module_entry():
    done = subprocess.run(
        [sys.executable, "-m", "rhoprop", "--version"], capture_output=True, text=True, check=True
    )
    assert done.stdout.startswith("rhoprop ")
