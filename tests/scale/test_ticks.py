"""Ticks: the progress of calls on threads, each counting in a slot of its
own; more calls than slots share them (a machine of hundreds of threads,
ISOFLOW_THREADS=512), never writing past them."""

from __future__ import annotations

import numpy as np

from isoflow.scale import ticks


def test_more_calls_than_counters_share_them_and_say_no_more_than_was_done():
    said = []
    counted = ticks.Ticks(lambda done, total: said.append(done), {"work": 100})
    calls = ticks.MOST_CALLS + 7
    counted.stage("work", calls)
    views = [counted.slot(call) for call in range(calls)]
    assert all(v.shape == (1,) and v.base is counted.slots for v in views)  # views of the counters, none past them
    for call in range(calls):
        counted.add(call, 1)  # on this thread: said at once
    assert said[-1] <= 100 and said == sorted(said)
    assert int(counted.slots[:: ticks.SPACING].sum()) == calls  # every unit counted, shared or not
    counted.finish()
    assert said[-1] == 100


def test_a_compiled_loops_view_is_its_own_call_counter():
    counted = ticks.Ticks(None, {})
    counted.stage("any", 4)
    counted.slot(1)[0] = 3  # as _label_loop writes done[0]
    counted.add(2, 1)
    assert counted.slots[ticks.SPACING] == 3 and counted.slots[2 * ticks.SPACING] == 1
    assert np.count_nonzero(counted.slots) == 2
