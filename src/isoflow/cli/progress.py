"""Progress bars on stderr for long work, fed by the core's callbacks."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from collections.abc import Callable, Iterator

from ..errors import counted, terminal_text

#: the bar once the total is known: the share done and the time left (the
#: core's units, chunks of columns or layers of blocks, mean nothing to a user)
BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]"

#: a counter whose count is said in words (``noun``): the count, and the time taken
COUNT_FORMAT = "{desc} [{elapsed}]"

Progress = Callable[[int, "int | None"], None]


#: the bar's width where the terminal reports no size
NARROWEST = 80


def terminal_size() -> tuple[int, int]:
    """The columns and rows of the terminal on stderr, each 0 where it
    reports none.

    Examples
    --------
    >>> columns, rows = terminal_size()
    >>> columns >= 0 and rows >= 0
    True
    """
    try:
        size = os.get_terminal_size(sys.stderr.fileno())
    except (OSError, ValueError, AttributeError):  # not a terminal, or a stand-in without a descriptor
        return 0, 0
    return size.columns, size.lines


def bar_width() -> dict:
    """tqdm's keywords for the bar's size on the terminal on stderr.

    tqdm sizes a bar from the terminal as it goes (``dynamic_ncols``) and
    draws none where the terminal reports 0 columns (a pty never sized:
    ``script``, some containers' ttys) or 0 rows (``stty rows 0``, some CI
    terminals), as it reads the bar's row as lying below the screen. Such
    a terminal gets a bar of a fixed size: as wide as its columns, else
    :data:`NARROWEST`.

    Examples
    --------
    >>> sorted(bar_width())  # whatever the terminal, tqdm is told enough to draw the bar
    ['dynamic_ncols', 'ncols', 'nrows']
    """
    columns, rows = terminal_size()
    if columns and rows:
        return {"ncols": None, "nrows": None, "dynamic_ncols": True}
    return {"ncols": max(columns - 1, 1) if columns else NARROWEST, "nrows": 24, "dynamic_ncols": False}


@contextlib.contextmanager
def progress_bar(args: argparse.Namespace, label: str, unit: str = "it",
                 estimate: bool = False, hint: str | None = None,
                 noun: str | None = None) -> Iterator[Progress | None]:
    """A tqdm bar on stderr fed by a core ``progress(done, total)`` callback.

    Yields the callback, or None (no bar, and tqdm not imported) when
    ``--quiet`` is given or stderr is not a terminal, so that logs and pipes
    get no carriage returns. The bar appears at the first report (not while
    a mesh is still being read) and is cleared when the work ends, so the
    terminal keeps only the results; work that ends (not work stopped by
    an error or an interrupt) has its last count drawn before the
    clearing. A ``total`` of None gives a counter (the flow, whose length
    is not known in advance). With ``estimate``
    (work whose shares are alike, as the voxeliser's pieces), a pipe gets
    a :class:`TimeNote` instead of nothing, with ``hint`` (what would take
    less) after its estimate where the core says its rule sums solid angles.
    With ``noun``, a counter says the count in words (``flow: 1 step``,
    ``flow: 12 steps``, :func:`~isoflow.errors.counted`) and the time
    taken, not tqdm's ``1 steps`` and a rate.
    """
    if args.quiet or not sys.stderr.isatty():
        yield TimeNote(args, label, hint) if estimate and not args.quiet else None
        return
    from tqdm import tqdm

    bars: list = []
    width = bar_width()

    def show(done: int, total: int | None) -> None:
        words = total is None and noun is not None
        desc = f"{label}: {counted(done, noun)}" if words else label
        if not bars:
            form = BAR_FORMAT if total is not None else COUNT_FORMAT if words else None
            bars.append(tqdm(desc=desc, total=total, initial=done, unit=unit, file=sys.stderr, leave=False, **width,
                             bar_format=form))
        if total != bars[0].total:  # genus: the stepping adds a resolution
            bars[0].total = total
        if words:
            bars[0].set_description_str(desc, refresh=False)
        bars[0].update(done - bars[0].n)

    finished = False
    try:
        yield show
        finished = True
    finally:
        for bar in bars:
            if finished and bar.n != bar.last_print_n:
                # tqdm draws at most every tenth of a second: the last count of
                # work that ended between two draws is drawn before the clearing,
                # so that the bar is not seen to stop short of its end
                bar.refresh()
            bar.close()


@contextlib.contextmanager
def writing_line(args: argparse.Namespace, path: object) -> Iterator[None]:
    """On a terminal, one line saying that ``path`` is being written, for as
    long as it is, then cleared (as the bars are): compressing a large
    volume can take as long as voxelising it, and the bar, cleared at its
    end, would leave the terminal silent meanwhile. Nothing with
    ``--quiet`` or on a pipe, whose log gets the result line.

    Examples
    --------
    >>> import argparse
    >>> with writing_line(argparse.Namespace(quiet=True, command="voxelize"), "out.nii.gz"):
    ...     pass
    """
    import warnings

    if args.quiet or not sys.stderr.isatty():
        yield
        return
    line = f"{args.command}: writing {path}"
    sys.stderr.write(line)
    sys.stderr.flush()
    shown, up = warnings.showwarning, True

    def clear() -> None:
        nonlocal up
        if up:
            sys.stderr.write("\r" + " " * len(line) + "\r")
            sys.stderr.flush()
            up = False

    def show(*warning, **where) -> None:  # a warning of the write gets a line of its own
        clear()
        shown(*warning, **where)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = shown
        clear()


#: a piped run says how long it will take once it has worked this long (seconds) ...
NOTE_AFTER = 2.0
#: ... if the whole will take at least this long
NOTE_LONG = 30.0


@contextlib.contextmanager
def reading_back(path: str | os.PathLike, check: bool = True) -> Iterator[None]:
    """The read-back check of a file already written, and what runs between
    its rename and the check: interrupted, the command's last line says the
    file is there and only its check was cut short (``isoflow: interrupted:
    PATH is written, not read back``), not a bare "interrupted" that leaves
    the user guessing; ``check=False`` (``--no-check``) leaves out the hint
    to pass it.

    Examples
    --------
    >>> try:
    ...     with reading_back("s.ply", check=False):
    ...         raise KeyboardInterrupt
    ... except KeyboardInterrupt as exc:
    ...     print(exc)
    s.ply is written, not read back
    """
    try:
        yield
    except KeyboardInterrupt:
        hint = " (--no-check skips the read-back)" if check else ""
        raise KeyboardInterrupt(f"{path} is written, not read back{hint}") from None


class TimeNote:
    """A ``progress(done, total)`` callback for a pipe or a log: once the
    work has run :data:`NOTE_AFTER` seconds past its first finished share,
    if the pace since then says that the whole will take :data:`NOTE_LONG`
    seconds or more, one note line with the estimate (and nothing more, so
    logs stay short), ending with ``hint`` where given and the core has
    told (:meth:`rule`) that its winding rule sums solid angles.

    The pace is taken from the first report with work done on, not from
    the start: before it lie the reading of the mesh and numba's loading or
    compiling of the passes, which cost the same however large the work,
    and divided by a first share of a few hundred they made a job of
    minutes read as one of hours. It is taken over at least as long as the
    first share took since the first report (of any share, none done
    included), and read as a share ends: the threads begin their pieces
    together and end them in bursts, so two pieces ending a second apart
    after 70 s each made a job of five hours read as one of 18 minutes,
    and read just before the next burst, as one of ten hours.

    Examples
    --------
    >>> import argparse
    >>> note = TimeNote(argparse.Namespace(command="voxelize"), "voxelize", hint="--fill shell is quicker")
    >>> note.rule(False); note.solid_angles
    False
    >>> note.rule(True); note.rule(False); note.solid_angles
    True
    """

    def __init__(self, args: argparse.Namespace, label: str, hint: str | None = None):
        self.command, self.label, self.hint = args.command, label, hint
        #: whether any mesh's winding rule sums solid angles, as the core
        #: tells it: only then do the fills of ``hint`` take less
        self.solid_angles = False
        self.start = time.monotonic()
        self.begun: float | None = None
        self.first: tuple[float, int] | None = None
        self.seen = 0
        self.said = False

    def rule(self, solid_angles: bool) -> None:
        """What the core tells of a mesh before filling it
        (:class:`~isoflow.mesh.voxelize.RuleProgress`): whether its
        winding rule sums solid angles. Of several meshes, one that does
        is enough for the hint."""
        self.solid_angles = self.solid_angles or solid_angles

    def phase(self) -> None:
        """A new kind of work begins under the same count (the files of
        ``surface --labels`` after every label's mesh): its first share
        bears that work's own set-up (a writer's imports, its compiled
        passes' loading), seconds that a pace taken over it would charge
        to every share after it, so the pace is taken afresh from the end
        of that share.

        Examples
        --------
        >>> import argparse
        >>> note = TimeNote(argparse.Namespace(command="surface"), "label surfaces")
        >>> note(40, 80); note.first is not None
        True
        >>> note.phase(); note.first is None
        True
        """
        self.begun = self.first = None

    def __call__(self, done: int, total: int | None) -> None:
        if self.said or not total:
            return
        now = time.monotonic()
        if self.begun is None:
            self.begun = now
        ended, self.seen = done > self.seen, done  # a share ended just now
        if done <= 0:
            return
        if self.first is None:
            self.first = (now, done)
            return
        t0, d0 = self.first
        if not ended or done <= d0 or now - t0 < max(NOTE_AFTER, t0 - self.begun):
            return
        self.said = True
        elapsed = now - self.start
        whole = elapsed + (now - t0) / (done - d0) * (total - done)
        if whole >= NOTE_LONG:
            hint = self.hint if self.solid_angles else None
            print(terminal_text(f"isoflow {self.command}: note: {self.label} will take about {duration(whole)} in all "
                                f"({100 * done / total:.0f} % done in {duration(elapsed)})" + (f"; {hint}" if hint else "")),
                  file=sys.stderr, flush=True)


def duration(seconds: float) -> str:
    """``45 s``, ``3 min 20 s``, ``2 h 5 min``: as a person says it."""
    s = int(round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60} s"
    return f"{s // 3600} h {s % 3600 // 60} min"
