"""Progress bars on stderr for long work, fed by the core's callbacks."""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Callable, Iterator

#: the bar once the total is known: the share done and the time left (the
#: core's units, chunks of columns or layers of blocks, mean nothing to a user)
BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]"

Progress = Callable[[int, "int | None"], None]


@contextlib.contextmanager
def progress_bar(args: argparse.Namespace, label: str, unit: str = "it") -> Iterator[Progress | None]:
    """A tqdm bar on stderr fed by a core ``progress(done, total)`` callback.

    Yields the callback, or None (no bar, and tqdm not imported) when
    ``--quiet`` is given or stderr is not a terminal, so that logs and pipes
    get no carriage returns. The bar appears at the first report (not while
    a mesh is still being read) and is cleared when the work ends, so the
    terminal keeps only the results. A ``total`` of None gives a counter
    (the flow, whose length is not known in advance).
    """
    if args.quiet or not sys.stderr.isatty():
        yield None
        return
    from tqdm import tqdm

    bars: list = []

    def show(done: int, total: int | None) -> None:
        if not bars:
            bars.append(tqdm(desc=label, total=total, initial=done, unit=unit, file=sys.stderr, leave=False,
                             dynamic_ncols=True, bar_format=None if total is None else BAR_FORMAT))
        if total != bars[0].total:  # genus: the stepping adds a resolution
            bars[0].total = total
        bars[0].update(done - bars[0].n)

    try:
        yield show
    finally:
        for bar in bars:
            bar.close()
