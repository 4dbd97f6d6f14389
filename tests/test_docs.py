"""The documentation site's code examples run as written (the site: mkdocs.yml, docs/).

Every ```python block of each page listed in PAGES runs, the blocks of one page in order in
one namespace (as a reader runs them top to bottom), in a temporary working directory that
holds ``catalog.tle`` (the synthetic sample catalog) for the pages that read a TLE file.
A block preceded by the comment ``<!-- docs-test: skip REASON -->`` (blank lines between are
fine) is skipped with that reason: blocks that need real data, a network or objects the
reader brings. Every page under docs/ is either in PAGES or in ELSEWHERE (with where its
examples run), so a new page cannot escape. README.md: tests/test_readme.py.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
DOCS = ROOT / "docs"
SAMPLE = Path(__file__).parent / "data" / "sample.tle"

#: Pages whose python blocks run here, with a check of what they print.
PAGES: dict[str, tuple[str, ...]] = {
    "getting-started.md": ("2002-09-08T01:00:00", "(500, 25)", "CCSP / Monte Carlo: 0.9"),
    "own-model.md": ("FromFunction(name='my_model')", "4.810e-12 +- 7.2e-13", "True True"),
    "mc-vs-ccsp.md": ("PiecewiseConstant / CCSP: 0.9", "long-time theory: 1.52"),
    "ensembles.md": ("'NRLMSISE-00': 2.19", "1 mode(s)"),
    "catalogs.md": ("propagated", "local == dask: True"),
    "plots.md": (),
    "conjunction.md": (),
    "density-sensor.md": (),
    "reentry.md": (),
}
#: Pages whose examples run elsewhere, or that have none.
ELSEWHERE = {
    "analysis.md": "tests/test_results_xarray.py::test_docs_analysis_examples_run",
    "index.md": "no python blocks",
    "paper-study.md": "no python blocks",
    "performance.md": "no python blocks",
    "density-models.md": "no python blocks",
    "density-calibration.md": "no python blocks",
    "architecture.md": "no python blocks",
    "conventions.md": "no python blocks",
    "catalog-realism.md": "no python blocks",
    "prediction-accuracy.md": "no python blocks",
    "reentry-notes.md": "no python blocks",
}

_BLOCK = re.compile(
    r"(?:<!--\s*docs-test:\s*skip\s+(?P<reason>.*?)\s*-->\s*\n(?:[ \t]*\n)*)?"
    r"^```python\n(?P<code>.*?)^```",
    flags=re.S | re.M,
)


def blocks(page: str) -> list[tuple[str, str | None]]:
    """(code, skip reason or None) of every python block of ``page``, in order."""
    text = (DOCS / page).read_text()
    return [(m["code"], m["reason"]) for m in _BLOCK.finditer(text)]


def test_every_page_is_accounted_for():
    pages = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md")}
    pages = {p for p in pages if not p.startswith("api/")}  # mkdocstrings pages, no code
    assert pages == set(PAGES) | set(ELSEWHERE), "list each docs page in PAGES or ELSEWHERE"
    for page, why in ELSEWHERE.items():
        if why == "no python blocks":
            assert not blocks(page), f"{page} has python blocks: add it to PAGES"


def test_skip_markers_parse():
    reasons = [reason for _, reason in blocks("conjunction.md") if reason]
    assert reasons and all("active.tle" in r for r in reasons)


@pytest.mark.parametrize("page", sorted(PAGES))
def test_page_examples_run(page, tmp_path, monkeypatch, capsys):
    found = blocks(page)
    assert found, f"{page} has no python blocks"
    runnable = [code for code, reason in found if reason is None]
    if not runnable:
        pytest.skip("; ".join(f"{page}: {reason}" for _, reason in found))
    shutil.copy(SAMPLE, tmp_path / "catalog.tle")
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {}
    for code in runnable:
        exec(compile(code, f"docs/{page}", "exec"), namespace)
    out = capsys.readouterr().out
    for expected in PAGES[page]:
        assert expected in out, f"docs/{page} no longer prints {expected!r}:\n{out}"


def _api_rewrite():
    import importlib.util

    spec = importlib.util.spec_from_file_location("sphinx_roles", DOCS / "_ext" / "sphinx_roles.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_api_reference_escapes_stars_and_splits_multi_name_entries():
    """The API reference once showed ``Cd*A/m ... B*`` as italics and
    TleAccuracy's ``radial, along_track, cross_track`` as one broken row."""
    ext = _api_rewrite()
    assert ext.escape_stars("Cd*A/m from B*, x**2, ``a*b``, `c*d`, *density*") == (
        r"Cd\*A/m from B\*, x\*\*2, ``a*b``, `c*d`, *density*"
    )
    text = "RMS.\n\nAttributes:\n    a, b: errors, m.\n        at epoch.\n    c: rate.\n"
    assert ext.split_multi_names(text) == (
        "RMS.\n\nAttributes:\n    a: errors, m.\n        at epoch.\n"
        "    b: errors, m.\n        at epoch.\n    c: rate.\n"
    )


def test_no_api_docstring_renders_unintended_italics():
    """Every public docstring, rewritten as the site's griffe extension does and rendered
    by Python-Markdown (mkdocs' renderer): an <em> only where the source wrote *word*."""
    import inspect

    import markdown

    import rhoprop as rp

    ext = _api_rewrite()
    seen: set[int] = set()
    docs: list[tuple[str, str]] = []

    def visit(name: str, obj: object, depth: int) -> None:
        if id(obj) in seen or depth > 4:
            return
        seen.add(id(obj))
        if isinstance(obj, (property, staticmethod, classmethod)):
            obj = obj.fget if isinstance(obj, property) else obj.__func__
        home = obj.__name__ if inspect.ismodule(obj) else getattr(obj, "__module__", None)
        if not str(home).startswith("rhoprop"):
            return
        doc = inspect.getdoc(obj)
        if doc:
            docs.append((name, doc))
        if inspect.ismodule(obj):
            for key in getattr(obj, "__all__", [k for k in dir(obj) if not k.startswith("_")]):
                visit(f"{name}.{key}", getattr(obj, key, None), depth + 1)
        elif inspect.isclass(obj):
            for key, value in vars(obj).items():
                if not key.startswith("_"):
                    visit(f"{name}.{key}", value, depth + 1)

    visit("rhoprop", rp, 0)
    assert len(docs) > 250
    # Emphasis as a writer means it: *word(s)* with the stars outside words.
    intended = re.compile(r"(?<![\w*])\*(\w[^*\n]*?\w|\w)\*(?![\w*])")
    bad = []
    for name, doc in docs:
        html = markdown.markdown(ext.rewrite(doc))
        meant = set(intended.findall(doc))
        bad += [(name, em) for em in re.findall(r"<em>(.*?)</em>", html) if em not in meant]
    assert not bad, bad[:5]
