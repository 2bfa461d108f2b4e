"""Fixtures for the documentation and the examples (a pytest plugin that
tests/conftest.py loads).

The site is built once per test session as ``python -m sphinx -W
--keep-going -b html docs OUT``; its gallery runs every script of
``examples/`` and writes each one's files into ``OUT/examples/NAME``
(``ISOFLOW_EXAMPLES_OUT``, read by ``docs/_gallery.py``). The examples'
tests read those files and what the gallery shows each script printing,
so that every example runs once per test session, not twice. Without
Sphinx and its extensions the examples run on their own instead, as a
user runs them.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
EXAMPLES = ROOT / "examples"

#: the import names of the `docs` extra's packages
DOCS_TOOLS = ("sphinx", "numpydoc", "pydata_sphinx_theme", "sphinx_gallery", "myst_parser", "sphinxarg")


def missing_docs_tools() -> list[str]:
    return [name for name in DOCS_TOOLS if importlib.util.find_spec(name) is None]


def example_names() -> list[str]:
    return sorted(p.stem for p in EXAMPLES.glob("[a-z]*.py"))


@dataclass
class Site:
    """A finished build: its exit status and log, the HTML, and where the
    gallery's examples wrote their files."""

    returncode: int
    log: str
    html: Path
    examples: Path

    def warnings(self) -> list[str]:
        return [line for line in self.log.splitlines() if "WARNING" in line or "ERROR" in line]


def printed_in_gallery(name: str) -> str:
    """What the gallery shows an example printing: the literal block after
    ``sphx-glr-script-out`` in the page sphinx-gallery wrote."""
    page = (DOCS / "auto_examples" / f"{name}.rst").read_text()
    start = page.index(".. rst-class:: sphx-glr-script-out")
    lines = page[start:].splitlines()[1:]
    block = lines[next(i for i, line in enumerate(lines) if "code-block::" in line) + 1:]
    out = []
    for line in block:
        if line.strip() and not line.startswith("    "):
            break
        out.append(line[4:])
    return "\n".join(out).strip("\n") + "\n"


@pytest.fixture(scope="session")
def site(tmp_path_factory) -> Site:
    missing = missing_docs_tools()
    if missing:
        pytest.skip(f"building the docs needs {', '.join(missing)}: pip install -e '.[docs]'")
    out = tmp_path_factory.mktemp("site")
    env = dict(os.environ, ISOFLOW_EXAMPLES_OUT=str(out / "examples"), MPLBACKEND="Agg")
    env.pop("ISOFLOW_DOCS_NO_GALLERY", None)
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", "-d", str(out / "doctrees"),
         str(DOCS), str(out / "html")],
        capture_output=True, text=True, env=env, cwd=ROOT)
    return Site(proc.returncode, proc.stdout + proc.stderr, out / "html", out / "examples")


def run_alone(name: str, out: Path) -> str:
    """Run examples/NAME.py OUT from another directory, as a user would; its stdout."""
    proc = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py"), str(out)],
                          capture_output=True, text=True, cwd=out.parent, env=dict(os.environ, MPLBACKEND="Agg"))
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


@pytest.fixture(scope="session")
def example_run(request, tmp_path_factory):
    """``example_run(NAME) -> (directory, printed)``: an example's files and
    its output, from the gallery's run when the docs can be built."""
    if not missing_docs_tools():
        built = request.getfixturevalue("site")

        def from_gallery(name: str) -> tuple[Path, str]:
            where = built.examples / name
            assert where.is_dir(), f"the gallery did not run {name}.py:\n" + "\n".join(built.warnings()[-20:])
            return where, printed_in_gallery(name)

        return from_gallery
    alone = tmp_path_factory.mktemp("examples")
    done: dict[str, tuple[Path, str]] = {}

    def on_its_own(name: str) -> tuple[Path, str]:
        if name not in done:
            done[name] = (alone / name, run_alone(name, alone / name))
        return done[name]

    return on_its_own


def script_output_pictures(site: Site, name: str) -> list[str]:
    """The pictures the gallery page of an example shows."""
    page = (site.html / "auto_examples" / f"{name}.html").read_text()
    return re.findall(r'<img[^>]+src="([^"]*sphx_glr_' + re.escape(name) + r'_\d+\.png)"', page)
