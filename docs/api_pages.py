"""The API page, written from ``isoflow.__all__`` before Sphinx reads it.

One autosummary table per part of the package (the subpackage that defines
each name), each name on a page of its own generated from its docstring,
then the sample data of :mod:`isoflow.data`. Nothing outside ``__all__``
is documented as API.
"""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path
from types import ModuleType

#: subpackage -> section title, in the page's order
PARTS = {
    "digital": "Digital geometry: configurations, curvature indices, topology",
    "mesh": "Meshes, volumes and files",
    "flow": "The digital curvature flow",
    "errors": "Errors and warnings",
}


def part(package: ModuleType, name: str) -> str:
    """The subpackage that defines ``name`` (``digital`` for tables and
    constants, whose objects do not say where they come from)."""
    obj = getattr(package, name)
    module = getattr(obj, "__module__", None) if (inspect.isclass(obj) or callable(obj)) else None
    if module is None:
        return "digital"
    sub = module.split(".")[1] if module.count(".") else "errors"
    return sub if sub in PARTS else "digital"


def page(package: ModuleType) -> str:
    groups: dict[str, list[str]] = {p: [] for p in PARTS}
    for name in sorted(package.__all__, key=str.lower):
        if inspect.ismodule(getattr(package, name)):
            continue  # a public subpackage (isoflow.data) has its own section
        groups[part(package, name)].append(name)
    lines = [
        ".. This file is written by docs/api_pages.py from isoflow.__all__; do not edit it.",
        "",
        "Python API",
        "==========",
        "",
        "Everything ``import isoflow`` offers (``isoflow.__all__``), each with its",
        "docstring: parameters, what it returns, the paper's equations and an",
        "example that the test suite runs. Names are loaded on first use, so",
        "``import isoflow`` is quick. The sample meshes are in :mod:`isoflow.data`.",
        "",
        ".. currentmodule:: isoflow",
        "",
    ]
    for key, title in PARTS.items():
        if not groups[key]:
            continue
        lines += [title, "-" * len(title), "", ".. autosummary::", "   :toctree: generated", "", ""]
        lines[-1:] = [f"   {name}" for name in groups[key]] + [""]
    lines += [
        "Sample data",
        "-----------",
        "",
        ".. automodule:: isoflow.data",
        "   :no-members:",
        "",
        ".. currentmodule:: isoflow.data",
        "",
        ".. autosummary::",
        "   :toctree: generated",
        "",
        *(f"   {name}" for name in sorted(importlib.import_module(f"{package.__name__}.data").__all__)),
        "",
    ]
    return "\n".join(lines)


def write(path: Path, package: ModuleType) -> None:
    """Write the page only when it changes (Sphinx rebuilds what changed)."""
    text = page(package)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
