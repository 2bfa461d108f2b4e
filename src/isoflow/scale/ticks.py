"""Progress of passes on threads, and where they stop.

Each call of a pass counts its own work where it does it, in a slot of
its own (a compiled loop writes it as it goes); the thread that waits for
the calls (:func:`isoflow.scale.compiled.run`) says their sum every tenth
of a second, so that a progress bar is fed from one thread only. Where a
call counts work it also looks at :data:`isoflow.scale.cancel.STOP` and
ends there (:class:`~isoflow.scale.cancel.Stopped`) once a signal set it:
a long pass stops within one of its steps, not at its end.

A pass of several stages (a label table: its pieces, the vertex pass, the
graph of pieces, the walks) gives each stage a share of one total, so
that one bar goes once from 0 to 100 %.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping

import numpy as np

from .cancel import STOP, Stopped

#: int64 slots between two calls' counters: each on a cache line of its own
SPACING = 8

#: calls of one stage with a counter of their own (a thread each); calls
#: beyond share them (``call % MOST_CALLS``), since a compiled loop writes
#: its count with no bounds check; a shared counter says less than the
#: work done, never more
MOST_CALLS = 256


#: voxels of a step of a pass between two counts (and looks at a stop): a
#: step is then a small share of what a bar shows, and a stop comes soon
STEP_VOXELS = 1 << 20


def layer_step(layer: int) -> int:
    """The layers of ``layer`` voxels each in a step (one at least).

    Examples
    --------
    >>> layer_step(512 * 512), layer_step(4096 * 4096)
    (4, 1)
    """
    return max(1, STEP_VOXELS // max(int(layer), 1))


class Ticks:
    """``progress(done, total)`` of work in stages, counted on threads and
    said on the thread that makes the ticks (which waits for the others).

    Parameters
    ----------
    progress : callable or None
        Told ``(done, total)`` as the work goes, ``done`` rising, ``total``
        the sum of ``shares``; None: only the stops are looked at.
    shares : mapping of str to int
        Each stage's share of the total, in the order of the stages.

    Examples
    --------
    >>> said = []
    >>> ticks = Ticks(lambda done, total: said.append((done, total)), {"read": 20, "sum": 80})
    >>> ticks.stage("read", 4)
    >>> ticks.add(0, 2); ticks.add(1, 2)
    >>> ticks.stage("sum", 10)
    >>> ticks.reached(0, 5)  # a count set, as a compiled loop sets it
    >>> ticks.finish()
    >>> said
    [(0, 100), (10, 100), (20, 100), (60, 100), (100, 100)]

    Work that counts itself, followed as the rest of a bar

    >>> said.clear(); ticks = Ticks(lambda done, total: said.append(done), {"read": 20, "sum": 80})
    >>> ticks.stage("read", 1); ticks.add(0, 1)
    >>> for done in range(5): ticks.follow(done, 4)
    >>> said
    [0, 20, 40, 60, 80, 100]
    """

    def __init__(self, progress: Callable[[int, int], object] | None, shares: Mapping[str, int]) -> None:
        self.progress, self.shares = progress, dict(shares)
        self.total = sum(self.shares.values())
        self.slots = np.zeros(SPACING * MOST_CALLS, np.int64)
        self.base, self.share, self.size, self.told = 0, 0, 1, -1
        self.owner = threading.get_ident()  # the thread that says the progress

    def stage(self, name: str, size: int) -> None:
        """Begin stage ``name`` of ``size`` units of work, the one before
        it done."""
        self.base += self.share
        self.share, self.size = self.shares.get(name, 0), max(int(size), 1)
        self.slots[:] = 0
        self.say()

    def rest(self, size: int) -> None:
        """Begin a stage of ``size`` units that takes all the shares left
        (the work done another way from here on)."""
        self.base += self.share
        self.share, self.size = self.total - self.base, max(int(size), 1)
        self.slots[:] = 0
        self.say()

    def follow(self, done: int, total: int) -> None:
        """Say ``done`` of ``total`` units of work that counts itself (a
        pass with a ``progress(done, total)`` of its own) as the rest of
        the bar: a callback for such a pass."""
        if self.share != self.total - self.base or self.size != max(int(total), 1):
            self.rest(total)
        self.slots[0] = done
        self.say()

    def slot(self, call: int) -> np.ndarray:
        """Call ``call``'s counter of this stage, one int64 (a compiled
        loop writes its count there)."""
        at = SPACING * (call % MOST_CALLS)
        return self.slots[at:at + 1]

    def add(self, call: int, units: int) -> None:
        """Count ``units`` more done by call ``call``, said at once where
        the call runs on the thread that made these ticks (which then has
        no wait in which to say it); :class:`~isoflow.scale.cancel.Stopped`
        where a stop was asked."""
        self.slots[SPACING * (call % MOST_CALLS)] += units
        self._said_here()

    def reached(self, call: int, done: int) -> None:
        """Call ``call`` has done ``done`` units of this stage in all (a
        count set, as a compiled loop sets it, not added), said as
        :meth:`add` says it; :class:`~isoflow.scale.cancel.Stopped` where
        a stop was asked."""
        self.slot(call)[0] = done
        self._said_here()

    def _said_here(self) -> None:
        if threading.get_ident() == self.owner:
            self.say()
        if STOP[0]:
            raise Stopped

    def say(self) -> None:
        """Tell ``progress`` the work done, where more than it was told."""
        if self.progress is None:
            return
        done = self.base + self.share * min(int(self.slots[::SPACING].sum()), self.size) // self.size
        if done > self.told:
            self.told = done
            self.progress(done, self.total)

    def finish(self) -> None:
        """All the work done."""
        self.base, self.share, self.size = self.total, 0, 1
        self.say()


def silent(ticks: Ticks | None) -> Ticks:
    """``ticks``, or where None, ticks that tell no one (the stops are
    looked at all the same).

    Examples
    --------
    >>> quiet = silent(None)
    >>> quiet.stage("any", 2); quiet.add(0, 1); quiet.progress is None
    True
    >>> silent(quiet) is quiet
    True
    """
    return Ticks(None, {}) if ticks is None else ticks
