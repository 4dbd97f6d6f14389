"""The examples in the package's docstrings run and print what they say (doctest)."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import rhoprop

#: Modules kept only as deprecated aliases (they warn when imported).
DEPRECATED = ("rhoprop.catalog.export",)
MODULES = sorted(
    m.name
    for m in pkgutil.walk_packages(rhoprop.__path__, "rhoprop.")
    if not m.name.startswith(("rhoprop._core", "rhoprop.__main__")) and m.name not in DEPRECATED
)


def _with_examples() -> list[str]:
    finder = doctest.DocTestFinder()
    out = []
    for name in MODULES:
        module = importlib.import_module(name)
        tests = [t for t in finder.find(module, name) if t.examples]
        # Only the module's own objects (not names it imported from elsewhere).
        if any(t.name.startswith(name) for t in tests):
            out.append(name)
    return out


def test_the_examples_are_found():
    assert {"rhoprop.propagation.propagate", "rhoprop.density.msis"} <= set(_with_examples())


@pytest.mark.parametrize("name", _with_examples())
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testmod(module, optionflags=flags, verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"
