"""Stopping compiled work at once: a flag the passes poll, and pieces of
work on threads that end when it is set.

A signal reaches Python only between bytecodes of the main thread, and
numba's compiled passes (which release the GIL) cannot be interrupted. So
long work is cut into pieces that run on worker threads while the main
thread waits (a wait that signals interrupt), and the compiled passes poll
:data:`STOP` between blocks of their own work.  Whoever catches the
interrupt (the command line's signal handler, or :func:`run_pieces` in the
main thread) sets the flag; each worker then returns within one block of
work and the interrupt goes on, with nothing left running behind it.
"""

from __future__ import annotations

import itertools
import threading
from collections.abc import Callable
from concurrent.futures import FIRST_EXCEPTION, wait

import numpy as np

#: set to 1 to stop: compiled passes take it as an argument and poll it
STOP = np.zeros(1, dtype=np.int8)
#: how often the waiting thread wakes to report progress (seconds)
POLL = 0.1


class Stopped(KeyboardInterrupt):
    """Work ended early because :data:`STOP` was set (an interrupt elsewhere)."""


def request_stop() -> None:
    """Ask every running piece of work to end (a signal handler may call it)."""
    STOP[0] = 1


def clear_stop() -> None:
    """Let work run again (at the start of a command)."""
    STOP[0] = 0


def stop_requested() -> bool:
    """Whether :func:`request_stop` was called since the last :func:`clear_stop`."""
    return bool(STOP[0])


_POOL: list = []


def pool():
    """One pool of two threads for the compiled passes (which release the
    GIL), kept for the process: starting threads per piece of work cost
    more than a piece on a busy machine."""
    if not _POOL:
        from concurrent.futures import ThreadPoolExecutor

        _POOL.append(ThreadPoolExecutor(max_workers=2, thread_name_prefix="isoflow-worker"))
    return _POOL[0]


def run_pieces(work: Callable[[int], object], n: int, threads: int = 2,
               progress: Callable[[int, int], object] | None = None) -> None:
    """Run ``work(0) ... work(n - 1)`` on ``threads`` worker threads (at
    most two), each taking the next piece when it is done with one.

    Parameters
    ----------
    work : callable
        Does piece i; it should poll :data:`STOP` if one piece is long.
    n : int
        Number of pieces.
    threads : int
        1 or 2 (a single worker still runs off the main thread, so that a
        signal is taken while it works).
    progress : callable, optional
        ``progress(done, n)``, called from the waiting thread.

    Raises
    ------
    KeyboardInterrupt
        When the wait is interrupted, or :class:`Stopped` when :data:`STOP`
        was set elsewhere: in both cases after every worker has returned.

    Examples
    --------
    >>> out = []
    >>> run_pieces(out.append, 3, threads=1)
    >>> out
    [0, 1, 2]
    """
    if n <= 0:
        return
    if threading.current_thread() is not threading.main_thread():
        for i in range(n):  # no signal comes to this thread, and a pool's worker must not wait on the pool
            if STOP[0]:
                raise Stopped
            work(i)
        return
    counter = itertools.count()
    done = [0]
    crew = _Crew()

    def worker() -> None:
        if not crew.join():
            return
        try:
            while not STOP[0] and not crew.over:
                with crew.lock:
                    i = next(counter)
                if i >= n:
                    return
                work(i)
                with crew.lock:
                    done[0] += 1
        finally:
            crew.leave()

    futures: list = []
    try:
        for _ in range(max(1, min(2, threads, n))):
            futures.append(pool().submit(worker))
        while True:
            finished, running = wait(futures, timeout=POLL, return_when=FIRST_EXCEPTION)
            for f in finished:
                f.result()  # a worker's exception, at once
            if progress is not None:
                progress(done[0], n)
            if not running:
                break
    except BaseException:
        ours = not STOP[0]  # a signal handler may have set it already, for other work too
        STOP[0] = 1
        crew.wait_out()
        if ours:
            STOP[0] = 0
        raise
    if STOP[0]:
        raise Stopped


class _Crew:
    """The workers of one :func:`run_pieces` call, counted as they begin
    and end rather than by their futures: an interrupt that lands inside
    ``submit``, after the work was queued and before its future came
    back, leaves a worker no future names, and waiting on the futures
    would let it run on once :data:`STOP` is cleared."""

    def __init__(self) -> None:
        self.lock = threading.Condition()
        self.running = 0
        self.over = False  # the call has ended: a worker that begins now returns at once

    def join(self) -> bool:
        """Count a worker in; False once the call is over."""
        with self.lock:
            if self.over:
                return False
            self.running += 1
            return True

    def leave(self) -> None:
        with self.lock:
            self.running -= 1
            self.lock.notify_all()

    def wait_out(self) -> None:
        """End the call and wait until every worker that began has
        returned, whatever interrupts the wait meanwhile.

        A second interrupt comes often: ``timeout`` sends its signal to the
        command and then to the command's process group, and people press
        Ctrl-C twice. Let through, it would end the wait with workers still
        running; the command then clears :data:`STOP` and, at exit, waits for
        those workers, which go on through all their pieces (minutes to hours
        after saying ``terminated``). The workers poll :data:`STOP`, so the wait
        is one block of work."""
        while True:
            try:
                with self.lock:
                    self.over = True
                    while self.running:
                        self.lock.wait()
                return
            except KeyboardInterrupt:
                continue
