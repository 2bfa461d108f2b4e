"""The memory budget: refuse, before allocating, work that would not fit.

A job that runs out of memory on Linux is usually killed without a word (or
makes the machine swap for minutes); a clear error up front is better. Every
guarded job estimates its peak from numbers it knows cheaply (grid size, the
configuration histogram) and compares it with a budget: 90 % of the memory
the kernel says is available when the job starts.
"""

from __future__ import annotations

import os

from ..errors import IsoflowError


def default_budget() -> int:
    """90 % of the memory the kernel reports as available now (MemAvailable:
    free plus reclaimable cache); half the physical memory where that cannot
    be read, 4 GiB where neither can."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024 * 9 // 10
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")) // 2
    except (ValueError, OSError, AttributeError):
        return 4 << 30


def check_fits(need: int, what: str, hint: str = "", budget: int | None = None) -> None:
    """Raise :class:`IsoflowError` when ``need`` bytes exceed the budget."""
    budget = default_budget() if budget is None else int(budget)
    if need > budget:
        raise IsoflowError(
            f"{what} needs about {gib(need)} of memory, more than the budget of {gib(budget)} "
            "(the memory available now)" + (f"; {hint}" if hint else "")
        )


def gib(n: int) -> str:
    return f"{n / 2**30:.1f} GiB"
