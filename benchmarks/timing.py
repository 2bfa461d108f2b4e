"""Timing a whole command as a user waits for it, and writing a
benchmark's results, shared by the benchmarks."""

from __future__ import annotations

import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path


def timed_command(argv: list[str], pythonpath: str | None = None) -> tuple[float, float]:
    """Wall and CPU seconds (the child's, all its threads) of one command,
    run with ``PYTHONPATH=pythonpath`` when given; its output is dropped."""
    env = dict(os.environ)
    if pythonpath is not None:
        env["PYTHONPATH"] = pythonpath
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    subprocess.run(argv, env=env, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)


def write_results(path: str, script: str, argv: list[str] | None, results: list[dict]) -> None:
    """``results`` as JSON at ``path`` under ``meta``: the command that made
    them (``python benchmarks/SCRIPT ARGS``), the machine, Python and the
    load average while it ran."""
    meta = {"command": f"python benchmarks/{script} " + " ".join(argv if argv is not None else sys.argv[1:]),
            "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs",
            "python": platform.python_version(), "load_average": [round(x, 2) for x in os.getloadavg()]}
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps({"meta": meta, "results": results}, indent=1) + "\n")
