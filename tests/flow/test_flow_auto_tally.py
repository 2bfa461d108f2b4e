"""``run_flow(method="auto")`` over many small flows, and over one long
flow of a small volume, in one process: the ski-rental rule of
:mod:`isoflow.scale.compiled`, weighed in voxel-steps
(:func:`isoflow.flow.engines.weigh_flow`). Each loop runs in a fresh
process, as a user's script would, so that nothing else has loaded the
compiled flow step there (its kernels are :mod:`isoflow.scale.flowbits`,
imported only by the bit rows' engine)."""

import json
from pathlib import Path

import numpy as np
import pytest

from isoflow.digital.lattice import DigitalObject
from isoflow.flow import engines
from isoflow.flow.run import run_flow
from isoflow.scale import compiled

needs_numba = pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")

#: argv[1] flows of :func:`small_volume` under "auto" in a fresh process;
#: after each, its result and whether the flow step's kernels are loaded
LOOP = """
import json, sys
sys.path.insert(0, sys.argv[2])
from test_flow_auto_tally import small_volume
from isoflow.flow.run import run_flow

rows = []
for i in range(int(sys.argv[1])):
    r = run_flow(small_volume(i), connectivity=(6, 26)[i % 2], keep_states=False)
    rows.append([r.to_dict(), "isoflow.scale.flowbits" in sys.modules])
print(json.dumps(rows))
"""

#: one plain flow of :func:`disk` under "auto" in a fresh process: its
#: result and, after each step, whether the flow step's kernels are loaded
LONG = """
import json, sys
sys.path.insert(0, sys.argv[1])
from test_flow_auto_tally import disk
from isoflow.flow.run import run_flow

loaded = []
tell = lambda step, state: loaded.append("isoflow.scale.flowbits" in sys.modules)
r = run_flow(disk(), connectivity=4, keep_states=False, progress=tell)
print(json.dumps([r.to_dict(), loaded]))
"""


def _run(script: str, *args) -> list:
    """What ``script`` prints as JSON, run in a fresh process with ``args``
    and this file's folder (for its inputs)."""
    from fresh_process import run_json  # (here: the script imports this file, beside none of tests/)

    return run_json(script, *args, folder=Path(__file__).parent)


def small_volume(seed: int) -> np.ndarray:
    """A small 3D volume: a ball or a smoothed random field (several
    components and tunnels), 20 to 34 across."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(20, 35))
    if seed % 2:
        from scipy.ndimage import gaussian_filter

        return gaussian_filter(rng.random((n,) * 3), 1.5) > 0.5
    x = np.indices((n,) * 3) - (n - 1) / 2
    return (x**2).sum(0) <= (0.45 * n) ** 2


def disk() -> np.ndarray:
    """A 300^2 disk, whose plain flow takes about 270 steps."""
    x = np.indices((300, 300)) - 149.5
    return (x**2).sum(0) <= 135**2


def numpy_work(result) -> list[int]:
    """The work of each step of a run on the arrays, in voxel-steps: the
    array of the state each step starts from (``keep_states``), and the
    fixed cost of a step (:func:`isoflow.flow.engines.step_work`)."""
    return [engines.step_work(s.volume.size) for s in result.states[:-1]]


@needs_numba
def test_a_loop_of_small_flows_under_auto_takes_the_compiled_step_once_their_work_passes_the_threshold():
    # each flow equals the same flow on the arrays, wherever the loop moves
    # to bit rows; the first flow loads no compiled step (its whole work,
    # even counted as PAYBACK_STEPS steps of its input, is below the
    # threshold), and every flow after the one at which the arrays' work
    # (taken from the runs on the arrays) reaches FLOW_WORK has loaded it.
    # The threshold is passed at the 8th flow: 14 leave six flows of either
    # connectivity after it
    count = 14
    rows = _run(LOOP, count)
    # the states (for the arrays' work) are kept until the work passes the
    # threshold: where it is passed needs no flow after it
    reference, done = [], 0
    for i in range(count):
        reference.append(run_flow(small_volume(i), connectivity=(6, 26)[i % 2], method="numpy",
                                  keep_states=done < engines.FLOW_WORK))
        done += sum(numpy_work(reference[-1])) if done < engines.FLOW_WORK else 0
    work = np.cumsum([sum(numpy_work(r)) if r.states else 0 for r in reference])
    first = small_volume(0)
    assert engines.step_work(first.size) * engines.PAYBACK_STEPS < engines.FLOW_WORK
    passed = int(np.searchsorted(work, engines.FLOW_WORK))
    assert 2 < passed < count - 5  # (small flows, and enough of them)
    for i, ((got, loaded), want) in enumerate(zip(rows, reference)):
        assert got == json.loads(json.dumps(want.to_dict())), i
        if i == 0:
            assert not loaded
        if i >= passed:
            assert loaded, (i, passed)


@needs_numba
def test_one_long_flow_of_a_small_image_moves_to_the_compiled_step_once_its_own_work_passes_the_threshold():
    # a 300^2 disk (90,000 voxels) flows ~270 steps: too small to start
    # compiled, and its own steps' work passes FLOW_WORK within the run, which
    # is the one on the arrays, step for step
    rows, loaded = _run(LONG)
    want = run_flow(disk(), connectivity=4, method="numpy")
    assert rows == json.loads(json.dumps(want.to_dict()))
    work = np.cumsum(numpy_work(want))
    passed = int(np.searchsorted(work, engines.FLOW_WORK))
    assert engines.step_work(disk().size) * engines.PAYBACK_STEPS < engines.FLOW_WORK < work[-1]
    assert not loaded[0] and all(loaded[passed:]), passed


def test_the_flow_tally_counts_numpy_steps_and_stays_past_the_threshold_once_compiled():
    # the rule's arithmetic (the conftest starts every test on a fresh
    # tally): a question leaves the tally as it is; each NumPy step adds its
    # work; the step that reaches the threshold is compiled and keeps the
    # tally past it, so that the next flows start compiled at any size
    tally = engines.FLOW_TALLY
    one = engines.step_work(1000)
    assert not engines.weigh_flow(1000, 1) and compiled.tallied(tally) == 0
    assert not engines.weigh_flow(1000, 1, record=True) and compiled.tallied(tally) == one
    compiled.add_to_tally(tally, engines.FLOW_WORK - 2 * one)
    assert engines.weigh_flow(1000, 1, record=True) and compiled.tallied(tally) >= engines.FLOW_WORK
    assert engines.weigh_flow(1, 1)
    assert compiled.tallied(False) == compiled.tallied(True) == 0  # the other thresholds keep their own


@needs_numba
def test_a_compiled_flow_pays_numbas_start_for_the_auto_flows_after_it():
    # a run with method="compiled" loads the compiled step: a small "auto"
    # flow after it takes the compiled step from its first (before, it
    # started on the arrays until its own work reached the threshold); both
    # give what the arrays give
    small = DigitalObject(small_volume(3))
    assert not engines.weigh_flow(small.volume.size)
    run_flow(small, connectivity=6, method="compiled", steps=2)
    assert engines.weigh_flow(small.volume.size)
    engine = engines.flow_engine("auto", small, 6)
    assert not isinstance(engine.start(small), DigitalObject)  # bit rows from the start
    assert run_flow(small, connectivity=6).to_dict() == run_flow(small, connectivity=6, method="numpy").to_dict()
