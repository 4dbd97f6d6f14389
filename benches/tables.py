"""Markdown table cells the bench scripts print: several figures in one cell."""

from __future__ import annotations

from collections.abc import Iterable


def slashed(values: Iterable[float], spec: str) -> str:
    """``values`` formatted with ``spec`` and joined by " / " (e.g. R / T / N in one
    cell)."""
    return " / ".join(format(x, spec) for x in values)
