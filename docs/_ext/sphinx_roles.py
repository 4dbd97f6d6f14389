"""Griffe extension for the API reference: the package's docstrings are Google style in
plain text with Sphinx cross-reference roles (``:class:`~rhoprop.density.Msis```), which
Markdown would misread. Loaded by mkdocs.yml (mkdocstrings' python handler); each docstring
is rewritten as the object is loaded:

* every Sphinx role becomes inline code of the name it shows (the last dotted part with
  ``~``, the full name without);
* a bare ``*`` outside code (``Cd*A/m``, ``B*``, ``x**2``) is escaped, so that Markdown
  does not turn the text between two of them into italics; a ``*word*`` pair written as
  emphasis stays emphasis;
* an entry of an Args/Attributes section that documents several names at once
  (``radial, along_track, cross_track: RMS errors, m.``) becomes one entry per name with
  the shared description, instead of one row named by the whole list.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:class|func|meth|attr|mod|data|exc|obj|const):`(~?)([^`]+)`")
#: Code spans (any number of backticks, matched by the same number) and *emphasis* pairs.
_KEEP = re.compile(r"(`+)[^`]*?\1|(?<![\w*\\])\*(?=[^\s*])[^*\n]*?(?<=[^\s*\\])\*(?![\w*])")
_SECTION = re.compile(r"^(\s*)(Args|Arguments|Parameters|Attributes|Other Parameters):\s*$")
_MULTI = re.compile(r"^(\s+)(\*{0,2}\w+(?:\s*,\s*\*{0,2}\w+)+)\s*:(.*)$")


def _code(match: re.Match[str]) -> str:
    tilde, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if tilde else target}`"


def strip_roles(text: str) -> str:
    """``text`` with every Sphinx role replaced by inline code."""
    return _ROLE.sub(_code, text)


def escape_stars(text: str) -> str:
    """``text`` with every ``*`` outside code spans and ``*emphasis*`` pairs escaped."""
    out, last = [], 0
    for match in _KEEP.finditer(text):
        out.append(re.sub(r"(?<!\\)\*", r"\\*", text[last : match.start()]))
        out.append(match.group(0))
        last = match.end()
    out.append(re.sub(r"(?<!\\)\*", r"\\*", text[last:]))
    return "".join(out)


def split_multi_names(text: str) -> str:
    """``text`` with each multi-name entry of an Args/Attributes section repeated once per
    name (its continuation lines with it)."""
    lines = text.splitlines()
    out: list[str] = []
    section_indent: int | None = None
    i = 0
    while i < len(lines):
        line = lines[i]
        header = _SECTION.match(line)
        if header:
            section_indent = len(header.group(1))
            out.append(line)
            i += 1
            continue
        indent = len(line) - len(line.lstrip())
        if line.strip() and section_indent is not None and indent <= section_indent:
            section_indent = None  # a line back at the header's indent ends the section
        entry = _MULTI.match(line) if section_indent is not None else None
        if not entry:
            out.append(line)
            i += 1
            continue
        lead, names, first = entry.groups()
        body = [first]
        i += 1
        while i < len(lines) and (
            not lines[i].strip() or len(lines[i]) - len(lines[i].lstrip()) > len(lead)
        ):
            if not lines[i].strip() and (
                i + 1 >= len(lines) or len(lines[i + 1]) - len(lines[i + 1].lstrip()) <= len(lead)
            ):
                break  # a blank line before the next entry or the section's end
            body.append(lines[i])
            i += 1
        for name in (n.strip() for n in names.split(",")):
            out.append(f"{lead}{name}:{body[0]}")
            out.extend(body[1:])
    return "\n".join(out) + ("\n" if text.endswith("\n") else "")


def rewrite(text: str) -> str:
    """The docstring ``text`` as the API reference shows it (see the module docstring)."""
    return escape_stars(strip_roles(split_multi_names(text)))


class SphinxRoles(griffe.Extension):
    """Rewrites every docstring as the object is loaded (see the module docstring)."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = rewrite(obj.docstring.value)
