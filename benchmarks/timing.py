"""Timing a whole command as a user waits for it, shared by the benchmarks."""

from __future__ import annotations

import os
import resource
import subprocess
import time


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
