"""The command line run in this test's own process, as ``subprocess.run``
of ``python -m isoflow ARGS`` would give it back (exit status, stdout,
stderr): for a test whose subject is what the command says or writes, not
the shell that starts it. A process of its own costs the interpreter's,
NumPy's and numba's start-up each time; the tests that are about a fresh
process (what it imports, its peak memory, a signal, the console entry
point) keep one."""

from __future__ import annotations

import contextlib
import io
import os
import subprocess

from isoflow.cli import main


def isoflow_here(*args, cwd=None) -> subprocess.CompletedProcess:
    """``isoflow ARGS`` run by :func:`isoflow.cli.main` in this process
    (in ``cwd`` where given), its output captured."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.chdir(cwd or os.getcwd()), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([*map(str, args)])
        except SystemExit as exc:  # argparse's own refusals
            code = exc.code if isinstance(exc.code, int) else 2
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())
