"""The code as pyproject.toml's ruff and mypy sections configure them.

ruff (pyflakes, pycodestyle, isort, bugbear, NumPy's deprecations, pyupgrade)
over the whole repository, mypy over the modules of the public API: both are
part of the test extra, so a fresh ``pip install -e .[test]`` runs them.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def run(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", *argv], cwd=ROOT, capture_output=True, text=True, timeout=600)


@pytest.mark.skipif(importlib.util.find_spec("ruff") is None, reason="ruff is in the test extra")
def test_ruff_finds_nothing():
    r = run("ruff", "check", "--output-format", "concise", ".")
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]


@pytest.mark.skipif(importlib.util.find_spec("mypy") is None, reason="mypy is in the test extra")
def test_mypy_finds_nothing_in_the_public_modules():
    r = run("mypy")
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    assert "Success" in r.stdout
