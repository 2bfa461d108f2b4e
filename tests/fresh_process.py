"""Scripts run in a fresh process, as a user's script runs: what
``method="auto"`` does over many inputs depends on what the process has
loaded and tallied, which a test's own process shares with every test."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path


def run_json(script: str, *args, folder: Path) -> list:
    """What ``script`` prints as JSON, run in a fresh process with ``args``
    and then ``folder`` (a test's own, for its inputs) as its arguments."""
    run = subprocess.run([sys.executable, "-c", script, *map(str, args), str(folder)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)
