"""Griffe extension for the API reference: the package's docstrings are Google style with
Sphinx cross-reference roles (``:class:`~rhoprop.density.Msis```), which Markdown would show
verbatim. Each role becomes inline code of the name it shows: the last dotted part with
``~``, the full name without. Loaded by mkdocs.yml (mkdocstrings' python handler)."""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:class|func|meth|attr|mod|data|exc|obj|const):`(~?)([^`]+)`")


def _code(match: re.Match[str]) -> str:
    tilde, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if tilde else target}`"


def strip_roles(text: str) -> str:
    """``text`` with every Sphinx role replaced by inline code."""
    return _ROLE.sub(_code, text)


class SphinxRoles(griffe.Extension):
    """Rewrites Sphinx roles in every docstring as the object is loaded."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = strip_roles(obj.docstring.value)
