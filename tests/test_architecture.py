"""The house (docs/architecture.md): folders are layers, each importing only
the layers below it; no import cycle between modules; no module takes
another module's private (``_name``) function.

Read from the source with ``ast``, every import counted, those inside
functions too (isoflow imports heavy libraries lazily, but a lazy import of
an upper layer is still an upward dependency).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "isoflow"

#: folder -> the folders its modules may import (errors.py is everyone's)
MAY_IMPORT = {
    "scale": {"scale"},
    "digital": {"scale", "digital"},
    "mesh": {"scale", "digital", "mesh"},
    "flow": {"scale", "digital", "mesh", "flow"},
}


def module_name(path: Path) -> str:
    parts = path.relative_to(SRC).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in PACKAGE.rglob("*.py")}


def imports(name: str, path: Path, known: set[str]) -> list[tuple[str, str | None, int]]:
    """(imported module, imported name or None, line) for every isoflow import."""
    is_package = path.name == "__init__.py"
    base = name.split(".") if is_package else name.split(".")[:-1]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(a.name, None, node.lineno) for a in node.names if a.name.split(".")[0] == "isoflow"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = base[: len(base) - node.level + 1]
                target = ".".join(anchor + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "isoflow":
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                if sub in known:  # `from . import guard`: a module, not a name
                    found.append((sub, None, node.lineno))
                else:
                    found.append((target, alias.name, node.lineno))
    return found


def graph() -> dict[str, set[str]]:
    mods = modules()
    known = set(mods)
    return {name: {m for m, _, _ in imports(name, path, known) if m in known and m != name}
            for name, path in mods.items()}


def layer(name: str) -> str | None:
    parts = name.split(".")
    return parts[1] if len(parts) > 2 else None  # isoflow.<folder>.<module>


def test_every_module_is_read():
    mods = modules()
    assert {"isoflow.cli", "isoflow.errors", "isoflow.digital.topology", "isoflow.flow.guard"} <= set(mods)
    # the reader sees relative imports: the flow's guard uses the flow's motion
    assert "isoflow.flow.motion" in graph()["isoflow.flow.guard"]


def test_no_private_name_crosses_a_module():
    mods = modules()
    known = set(mods)
    bad = [
        f"{name} line {line}: {target}.{what}"
        for name, path in mods.items()
        for target, what, line in imports(name, path, known)
        if what and what.startswith("_") and not what.startswith("__") and target != name
    ]
    assert not bad, "private names imported from another module:\n" + "\n".join(bad)


def test_no_import_cycle():
    g = graph()
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in g[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in g:
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


@pytest.mark.parametrize("folder", sorted(MAY_IMPORT))
def test_each_folder_imports_only_the_layers_below(folder):
    g = graph()
    bad = []
    for name, targets in g.items():
        if layer(name) != folder:
            continue
        for t in targets:
            if t != "isoflow.errors" and layer(t) not in MAY_IMPORT[folder]:
                bad.append(f"{name} -> {t}")
    assert not bad, f"{folder}/ may import only {sorted(MAY_IMPORT[folder])}:\n" + "\n".join(bad)


def on_top(name: str) -> bool:
    """The package's front door and the command line (a package whose
    modules import each other)."""
    return name in ("isoflow", "isoflow.__main__") or name == "isoflow.cli" or name.startswith("isoflow.cli.")


def test_nothing_imports_the_top():
    """cli and the package's front door are imported by nothing inside."""
    g = graph()
    upward = [f"{n} -> {t}" for n, ts in g.items() if not on_top(n) for t in ts if on_top(t)]
    assert not upward, upward
    assert "isoflow.cli.main" in g and "isoflow.cli.info" in g["isoflow.cli.main"]
