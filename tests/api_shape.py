"""Counts of the API's shape: public parameters typed ``Any``, public functions with
more than 10 parameters, functions over
80 lines (docstring excluded) in ``catalog/`` and ``conjunction/``, regular expressions
applied to exception messages, and ``_core`` functions typed to return ``dict[str, Any]``.
``tests/test_architecture.py`` keeps them at their limits.

Run:  python tests/api_shape.py
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

PACKAGE = Path(__file__).parents[1] / "python" / "rhoprop"


def _public_module(path: Path) -> bool:
    parts = path.relative_to(PACKAGE).parts
    return not any(p.startswith("_") and p != "__init__.py" for p in parts)


def _public_parameters() -> Iterator[tuple[Path, ast.FunctionDef, list[ast.arg]]]:
    """(module, function, its parameters with ``*args``/``**kwargs``) of every public
    function of a public module."""
    for path in sorted(PACKAGE.rglob("*.py")):
        if not _public_module(path):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef) and not node.name.startswith("_"):
                a = node.args
                params = [*a.posonlyargs, *a.args, *a.kwonlyargs]
                yield path, node, params + [p for p in (a.vararg, a.kwarg) if p is not None]


def any_parameters() -> list[str]:
    """``module:line function(parameter)`` of every public function's parameter typed
    ``Any`` (``*args``/``**kwargs`` included)."""
    return [
        f"{path.relative_to(PACKAGE)}:{p.lineno} {node.name}({p.arg})"
        for path, node, params in _public_parameters()
        for p in params
        if p.annotation is not None and ast.unparse(p.annotation) == "Any"
    ]


def wide_functions(limit: int = 10) -> list[str]:
    """``module function: n`` of every public function (methods included, ``self``
    not counted) with more than ``limit`` parameters (``*args``/``**kwargs`` count one).
    ``**deprecated``, which only carries the keywords kept one release after they moved
    into a settings object (each with a DeprecationWarning), is not counted: it goes at
    the next release."""
    out = []
    for path, node, params in _public_parameters():
        n = len([p for p in params if p.arg not in ("self", "cls", "deprecated")])
        if n > limit:
            out.append(f"{path.relative_to(PACKAGE)} {node.name}: {n}")
    return out


def long_functions(limit: int = 80) -> list[str]:
    """Functions of ``catalog/`` and ``conjunction/`` longer than ``limit`` lines of code
    (from the first statement after the docstring to the end)."""
    out = []
    for folder in ("catalog", "conjunction"):
        for path in sorted((PACKAGE / folder).glob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    continue
                body = node.body
                doc = (
                    isinstance(body[0], ast.Expr)
                    and isinstance(body[0].value, ast.Constant)
                    and isinstance(body[0].value.value, str)
                )
                first = body[1] if doc and len(body) > 1 else body[0]
                n = (node.end_lineno or first.lineno) - first.lineno + 1
                if n > limit:
                    out.append(f"{folder}/{path.name} {node.name}: {n} lines")
    return out


def message_regexes() -> list[str]:
    """Places that run a regular expression over ``str(...)`` of an exception."""
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.ExceptHandler) or node.name is None:
                continue
            for inner in ast.walk(node):
                if (
                    isinstance(inner, ast.Call)
                    and isinstance(inner.func, ast.Attribute)
                    and inner.func.attr in ("search", "match", "fullmatch", "findall")
                    and any(node.name in ast.unparse(arg) for arg in inner.args)
                ):
                    out.append(f"{path.relative_to(PACKAGE)}:{inner.lineno}")
    return out


def dict_returns() -> list[str]:
    """``_core`` functions whose stub returns ``dict[str, Any]``."""
    tree = ast.parse((PACKAGE / "_core.pyi").read_text())
    return [
        node.name
        for node in tree.body
        if isinstance(node, ast.FunctionDef)
        and node.returns is not None
        and "dict[str, Any]" in ast.unparse(node.returns)
    ]


def wide_core_functions(limit: int = 9) -> list[str]:
    """``_core`` functions whose stub takes more than ``limit`` parameters: a run's
    settings cross the binding as one record (``Problem``, ``MonteCarloRun``,
    ``CcspRun``, ``FitJob``, ``Tracks``), not as positional arguments."""
    tree = ast.parse((PACKAGE / "_core.pyi").read_text())
    out = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            a = node.args
            n = len([*a.posonlyargs, *a.args, *a.kwonlyargs])
            if n > limit:
                out.append(f"{node.name}: {n}")
    return out


def core_tuple_returns() -> list[str]:
    """``_core`` functions whose stub returns a tuple of more than two values (a record
    names them)."""
    tree = ast.parse((PACKAGE / "_core.pyi").read_text())
    out = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.returns is not None:
            ret = node.returns
            if (
                isinstance(ret, ast.Subscript)
                and ast.unparse(ret.value) == "tuple"
                and isinstance(ret.slice, ast.Tuple)
                and len(ret.slice.elts) > 2
            ):
                out.append(node.name)
    return out


if __name__ == "__main__":
    for title, found in (
        ("public parameters typed Any", any_parameters()),
        ("public functions with more than 10 parameters", wide_functions()),
        ("functions over 80 lines in catalog/ and conjunction/", long_functions()),
        ("regular expressions on exception messages", message_regexes()),
        ("_core functions returning dict[str, Any]", dict_returns()),
        ("_core functions with more than 9 parameters", wide_core_functions()),
        ("_core functions returning a tuple of more than 2", core_tuple_returns()),
    ):
        print(f"{title}: {len(found)}")
        for item in found:
            print(f"  {item}")
