"""The Python snippets of README.md and docs/*.md call the public API as it
is: every ``isoflow.NAME(...)`` (or a name imported from isoflow) exists and
takes the keywords the snippet gives. The snippets need files they do not
make, so they are read, not run."""

from __future__ import annotations

import ast
import inspect
import re
from pathlib import Path

import pytest

import isoflow

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def snippets(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), re.S)


def calls(code: str) -> list[tuple[str, list[str], int]]:
    """(public name, keywords, line) of every call of a public function."""
    tree = ast.parse(code)
    imported = {a.asname or a.name: a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
                and node.module == "isoflow" for a in node.names}
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) and f.value.id == "isoflow":
            name = f.attr
        elif isinstance(f, ast.Name) and f.id in imported:
            name = imported[f.id]
        else:
            continue
        found.append((name, [k.arg for k in node.keywords if k.arg], node.lineno))
    return found


@pytest.mark.parametrize("page", [p for p in PAGES if snippets(p)], ids=lambda p: p.name)
def test_snippets_call_the_api_as_it_is(page):
    wrong = []
    for code in snippets(page):
        for name, keywords, line in calls(code):
            if name not in isoflow.__all__:
                wrong.append(f"line {line}: isoflow.{name} is not public")
                continue
            obj = getattr(isoflow, name)
            if not callable(obj) or isinstance(obj, type):
                continue
            params = inspect.signature(obj).parameters
            if any(p.kind is p.VAR_KEYWORD for p in params.values()):
                continue
            wrong += [f"line {line}: {name}() takes no {k}=" for k in keywords if k not in params]
    assert not wrong, wrong
