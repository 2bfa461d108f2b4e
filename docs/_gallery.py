"""The gallery's helpers (sphinx-gallery names them in conf.py as strings).

Every example takes an output directory on its command line; in the
gallery it writes into ``$ISOFLOW_EXAMPLES_OUT/NAME`` (the test suite reads
the files there, so that each example runs once per test run), else into
``docs/_build/examples/NAME``, with ``--force`` so that a rebuild replaces
them.
"""

from __future__ import annotations

import os
from pathlib import Path


def examples_out() -> Path:
    default = Path(__file__).resolve().parent / "_build" / "examples"
    return Path(os.environ.get("ISOFLOW_EXAMPLES_OUT") or default)


def reset_argv(gallery_conf, script_vars) -> list[str]:
    """``OUT --force`` for the example being run."""
    name = Path(script_vars["src_file"]).stem
    return [str(examples_out() / name), "--force"]
