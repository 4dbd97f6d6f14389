"""The committed type stub covers every export of the extension, and nothing more."""

from __future__ import annotations

import ast
from pathlib import Path

import rhoprop
from rhoprop import _core


def test_stub_names_match_extension():
    stub = Path(rhoprop.__file__).with_name("_core.pyi")
    tree = ast.parse(stub.read_text())
    declared = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            declared.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            declared.add(node.target.id)
    exported = {name for name in dir(_core) if not name.startswith("_")}
    assert exported == {name for name in declared if not name.startswith("_")}
    assert sorted(exported) == sorted(_core.__all__)
    assert (stub.parent / "py.typed").exists()
