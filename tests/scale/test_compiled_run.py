"""compiled.run, which runs a pass's slabs on threads: each call on a
thread of its own at once, its threads kept between the calling thread's
calls (starting them cost more than a small volume's pass: the random
volumes of tests/digital/test_closed_surfaces.py spent two thirds of their
time starting threads), and an error raised only once every call is done."""

from __future__ import annotations

import signal
import threading
import time

import pytest

from isoflow.scale import compiled


def _here(barrier: threading.Barrier | None = None) -> threading.Thread:
    if barrier is not None:
        barrier.wait()  # every call of the run waits for the others: each must have a thread at once
    return threading.current_thread()


def test_the_threads_are_kept_between_a_threads_calls():
    # each run's calls wait for each other, so that each holds a thread of its
    # own (a call that returned at once could leave its thread to the next);
    # the threads alive before the second run are held here, so no new
    # thread can take one's id (an earlier test may have left more threads
    # in this thread's pool than three: the second run may take any of them)
    first = compiled.run([(_here, threading.Barrier(3, timeout=30))] * 3)
    alive = threading.enumerate()
    second = compiled.run([(_here, threading.Barrier(3, timeout=30))] * 3)
    assert threading.current_thread() not in first  # several calls run on threads of their own
    assert len({id(t) for t in first}) == len({id(t) for t in second}) == 3
    assert {id(t) for t in second} <= {id(t) for t in alive}  # none started anew
    more = compiled.run([(_here,)] * 5)  # more calls than the threads kept: still one thread each at once
    assert threading.current_thread() not in more


@pytest.mark.parametrize("calls", [2, 3, 7])
def test_each_call_has_a_thread_of_its_own_at_once(calls):
    barrier = threading.Barrier(calls, timeout=30)
    threads = compiled.run([(_here, barrier)] * calls)
    assert len({id(t) for t in threads}) == calls and not barrier.broken


def test_calling_threads_at_once_each_have_their_calls_threads():
    # two threads (as a dask worker's) run passes at the same time: neither waits for the other's calls
    barriers = [threading.Barrier(3, timeout=30) for _ in range(2)]
    got: dict[int, list] = {}

    def caller(k):
        got[k] = compiled.run([(_here, barriers[k])] * 3)

    callers = [threading.Thread(target=caller, args=(k,)) for k in range(2)]
    for t in callers:
        t.start()
    for t in callers:
        t.join(60)
    assert sorted(got) == [0, 1] and not any(b.broken for b in barriers)
    assert not {id(t) for t in got[0]} & {id(t) for t in got[1]}


def test_an_error_is_raised_once_every_call_is_done():
    done = []

    def slow():
        time.sleep(0.3)
        done.append(True)

    def fails():
        raise ValueError("a pass failed")

    with pytest.raises(ValueError, match="a pass failed"):
        compiled.run([(fails,), (slow,)])
    assert done == [True]  # nothing of the run left running behind the error


@pytest.mark.skipif(not hasattr(signal, "setitimer"), reason="an interval timer's signal")
def test_an_interrupted_wait_stops_the_calls_and_returns_once_they_have():
    """Ctrl-C lands in the waiting thread of calls that count their work
    (and look at cancel.STOP there, as the label table's passes do): they
    are asked to stop, and the interrupt goes on only once they have
    returned, with STOP as it was; calls let run on would hold the
    process at its exit."""
    from isoflow.scale import cancel
    from isoflow.scale.ticks import Ticks

    ended: list[float] = []

    def until_stopped() -> None:
        deadline = time.monotonic() + 20
        while not cancel.STOP[0] and time.monotonic() < deadline:
            time.sleep(0.005)
        ended.append(time.monotonic())

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    before = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.3)
        start = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            compiled.run([(until_stopped,)] * 2, Ticks(None, {}))
        raised = time.monotonic()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, before)
    assert len(ended) == 2 and max(ended) <= raised  # both returned before the interrupt went on
    assert raised - start < 10  # stopped, not run to their end
    assert cancel.STOP[0] == 0  # not left set for the next work
