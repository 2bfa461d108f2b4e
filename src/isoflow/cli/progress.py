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
def progress_bar(args: argparse.Namespace, label: str, unit: str = "it",
                 estimate: bool = False) -> Iterator[Progress | None]:
    """A tqdm bar on stderr fed by a core ``progress(done, total)`` callback.

    Yields the callback, or None (no bar, and tqdm not imported) when
    ``--quiet`` is given or stderr is not a terminal, so that logs and pipes
    get no carriage returns. The bar appears at the first report (not while
    a mesh is still being read) and is cleared when the work ends, so the
    terminal keeps only the results. A ``total`` of None gives a counter
    (the flow, whose length is not known in advance). With ``estimate``
    (work whose shares are alike, as the voxeliser's pieces), a pipe gets
    :func:`time_note` instead of nothing.
    """
    if args.quiet or not sys.stderr.isatty():
        yield time_note(args, label) if estimate and not args.quiet else None
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


#: a piped run says how long it will take once it has worked this long (seconds) ...
NOTE_AFTER = 2.0
#: ... if the whole will take at least this long
NOTE_LONG = 30.0


def time_note(args: argparse.Namespace, label: str) -> Progress:
    """A ``progress(done, total)`` callback for a pipe or a log: once the
    work has run :data:`NOTE_AFTER` seconds, if what is done so far says
    that the whole will take :data:`NOTE_LONG` seconds or more, one note
    line with the estimate (and nothing more, so logs stay short)."""
    import time

    start = time.monotonic()
    said: list[bool] = []

    def show(done: int, total: int | None) -> None:
        if said or not total or done <= 0:
            return
        elapsed = time.monotonic() - start
        if elapsed < NOTE_AFTER:
            return
        said.append(True)
        whole = elapsed * total / done
        if whole >= NOTE_LONG:
            print(f"isoflow {args.command}: note: {label} will take about {duration(whole)} in all "
                  f"({100 * done / total:.0f} % done in {duration(elapsed)})", file=sys.stderr, flush=True)

    return show


def duration(seconds: float) -> str:
    """``45 s``, ``3 min 20 s``, ``2 h 5 min``: as a person says it."""
    s = int(round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60} s"
    return f"{s // 3600} h {s % 3600 // 60} min"
