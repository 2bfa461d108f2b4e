"""The API page, written from ``isoflow.__all__`` before Sphinx reads it.

One autosummary table per part of the package (the subpackage that defines
each name), each name on a page of its own generated from its docstring,
then the sample data of :mod:`isoflow.data`. Nothing outside ``__all__``
is documented as API.
"""

from __future__ import annotations

import importlib
import inspect
import sys
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from sphinx.application import Sphinx

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


def public_target(package: ModuleType, target: str) -> str | None:
    """``isoflow.NAME...`` where ``target`` names a public object by the
    module that defines it (``isoflow.digital.topology.euler_characteristic``,
    ``isoflow.digital.lattice.DigitalObject.world``), else None: the API
    documents it under ``isoflow`` alone, so the internal path has no page."""
    parts = target.split(".")
    if parts[0] != package.__name__:
        return None
    for cut in range(len(parts) - 1, 1, -1):
        module = sys.modules.get(".".join(parts[:cut]))
        if module is None:
            continue
        name = parts[cut]
        public = name in package.__all__ and getattr(module, name, None) is getattr(package, name)
        return ".".join([package.__name__, *parts[cut:]]) if public else None
    return None


def constant_doc(package: ModuleType, name: str) -> list[str] | None:
    """The ``#:`` comment above a public constant where its module defines it
    (``name``: ``isoflow.CLASS_LABELS``), else None. Autodoc looks for it in
    ``isoflow/__init__.py``, which only loads the name, and falls back on
    the docstring of the value's type: a tuple's, "Built-in immutable
    sequence"."""
    from sphinx.errors import PycodeError
    from sphinx.pycode import ModuleAnalyzer

    short = name.rpartition(".")[2]
    if short not in package.__all__:
        return None
    value = getattr(package, short)
    for modname, module in sorted(sys.modules.items()):
        if not modname.startswith(package.__name__ + ".") or vars(module).get(short) is not value:
            continue
        try:
            lines = ModuleAnalyzer.for_module(modname).find_attr_docs().get(("", short))
        except PycodeError:
            continue
        if lines:
            return list(lines)
    return None


def connect(app: Sphinx, package: ModuleType) -> None:
    """Resolve references by internal paths to the public pages and give
    constants their comments (conf.py's ``setup``)."""

    def resolve(app, env, node, contnode):  # Sphinx's missing-reference event
        target = public_target(package, node.get("reftarget", "")) if node.get("refdomain") == "py" else None
        if target is None:
            return None
        return env.get_domain("py").resolve_xref(env, node["refdoc"], app.builder, node["reftype"], target, node, contnode)

    def document(app, what, name, obj, options, lines):  # autodoc-process-docstring
        found = constant_doc(package, name) if what == "data" else None
        if found is not None:
            lines[:] = found

    app.connect("missing-reference", resolve)
    app.connect("autodoc-process-docstring", document, priority=400)  # before numpydoc's (500) reads the lines
