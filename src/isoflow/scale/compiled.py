"""When the compiled passes run, and on how many threads.

The passes of :mod:`isoflow.scale.kernels` and :mod:`isoflow.scale.sweep`
are compiled with numba. They are used for host volumes from
:data:`MIN_VOXELS` on; below that, numpy and cc3d answer sooner than numba
can start (importing numba and loading its cached machine code is paid
once per process), so one small volume never imports numba at all.
The choice is a function of the input and of the voxels already counted
in the process (:func:`use_compiled`, below), never of a clock; a
caller that knows better says so with ``method="compiled"``, as
scikit-image's functions take ``method=``. Both passes give the same
answers.

Many small volumes in one process are weighed together, by the
ski-rental rule: ``"auto"`` keeps a tally of the voxels it has sent down
the NumPy passes in the process (one per threshold, :func:`least_voxels`
with and without the surfaces), and takes the compiled pass once that
tally and the volume at hand reach the threshold, which is the size at
which one volume's compiled pass, numba's start included, costs what its
NumPy pass does. NumPy's share is then at most what numba's start costs,
so any sequence of volumes costs at most about twice the better of
always NumPy and always compiled; a single small volume still never
imports numba. From then on the tally stays past the threshold, and the
3D census of ``analyze`` and ``closed_surfaces`` takes the compiled pass
at any size once numba holds its machine code in the process (a compiled
pass ran there, so numba's start is paid:
:func:`isoflow.digital.closed_surfaces.use_census`).

The passes release the GIL, so plain Python threads run them in parallel
(no OpenMP pool, no parallel compile). Each pass splits the volume into as
many slabs along its first axis as there are threads and joins what crosses
the seams afterwards. The threads are started once per calling thread and
kept for its next passes (:func:`run`).

The number of threads is, in order of precedence: the ``threads`` given to
:func:`using` (``isoflow info --threads N``, ``analyze(..., threads=N)``),
the environment variable ``ISOFLOW_THREADS``, the CPUs this process may run
on (``os.sched_getaffinity``, which honours ``taskset`` and container CPU
sets; ``os.cpu_count()`` where that is missing). Unless asked, a pass over
a small volume takes fewer threads: one per :data:`VOXELS_PER_THREAD`, as
starting and joining a thread costs about what sweeping a few hundred
thousand voxels does.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import threading
from collections.abc import Iterator
from functools import cache
from typing import TYPE_CHECKING, Literal

from ..errors import IsoflowError, choice_of, given_text, whole_given

if TYPE_CHECKING:
    import numpy as np

    from .ticks import Ticks

#: host volumes with at least this many voxels (126^3 and up) use the compiled
#: passes (the histogram, the Betti numbers)
MIN_VOXELS = 2_000_000

#: with the surfaces, host volumes take the compiled census (histogram,
#: Betti numbers and surfaces in one sweep) from this many times
#: MIN_VOXELS on (4 million, 159^3): below it the NumPy census is the
#: faster command, numba's start being the larger part of the compiled
#: one's time (the crossover is measured by benchmarks/run.py on porous
#: fields, the most boundary per voxel of its inputs)
CENSUS_FACTOR = 2


def least_voxels(surfaces: bool = False) -> int:
    """The voxels from which a host volume takes the compiled passes, for a
    pass with or without the surfaces."""
    return MIN_VOXELS * (CENSUS_FACTOR if surfaces else 1)

#: unless asked, a pass takes at most one thread per this many voxels
VOXELS_PER_THREAD = 1_000_000

#: the environment variable that overrides the CPU count
ENV = "ISOFLOW_THREADS"

_asked: contextvars.ContextVar[int | None] = contextvars.ContextVar("isoflow_threads", default=None)

#: what a process says, once, when numba starts compiling one of isoflow's
#: passes instead of loading it from its cache: the first run after
#: installing (or on a new CPU, or after an upgrade) waits seconds per pass,
#: with nothing else to show
COMPILE_NOTE = ("numba is compiling isoflow's passes for this CPU, once after installing (seconds to about "
                "two minutes the first time each kind of work runs; later runs load them from its cache)")

#: called with :data:`COMPILE_NOTE` in its place when set (the command line
#: prints it on stderr); else the note is logged to the ``isoflow`` logger
on_first_compile = None
_compile_noted = False

#: called once numba is imported (by :mod:`isoflow.scale.jit`), when set:
#: the command line freezes what the import made (``gc.freeze``), objects
#: that live until the process ends, so that the collector does not walk
#: them again each time it collects the oldest generation; a library's
#: caller keeps the collector as it set it
on_numba_import = None


def note_compile() -> None:
    """Say :data:`COMPILE_NOTE` once per process (called by
    :mod:`isoflow.scale.jit` when numba starts compiling a pass of
    isoflow's, which it does only where its cache has none)."""
    global _compile_noted
    if _compile_noted:
        return
    _compile_noted = True
    if on_first_compile is not None:
        on_first_compile(COMPILE_NOTE)
    else:
        import logging

        logging.getLogger("isoflow").info(COMPILE_NOTE)


def read_only_view(array: np.ndarray) -> np.ndarray:
    """A read-only view of ``array`` (no copy), for a compiled pass that
    only reads it.

    numba types a read-only array apart from a writeable one, so a pass
    handed both (a volume from ``np.load(mmap_mode="r")`` or a view of
    bytes, and one the program made) is compiled twice, each compile a
    wait on its first call; handed this view always, it is compiled once.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.arange(3)
    >>> view = read_only_view(a)
    >>> view.flags.writeable, a.flags.writeable, view.base is a
    (False, True, True)
    """
    view = array.view()
    view.flags.writeable = False
    return view


@cache
def have_numba() -> bool:
    """numba is installed (found without importing it: that is the slow part)."""
    from importlib.util import find_spec

    return find_spec("numba") is not None


#: how a pass is computed: chosen by the input's size (``"auto"``), the
#: NumPy passes, or the compiled ones
Method = Literal["auto", "numpy", "compiled"]
METHODS = ("auto", "numpy", "compiled")


def check_method(method: object) -> Method:
    """``method`` as the plain string of :data:`METHODS` it names, else
    one IsoflowError naming them (an array too, whose comparison with
    them NumPy would refuse with its own ValueError).

    Examples
    --------
    >>> import numpy as np
    >>> check_method(np.str_("numpy"))
    'numpy'
    """
    chosen = choice_of(method, METHODS)
    if chosen is None:
        raise IsoflowError(f"method must be one of {', '.join(METHODS)}, got {given_text(method)}")
    return chosen  # type: ignore[return-value]


#: the voxels that ``"auto"`` has weighed below the threshold in this
#: process, per threshold (True: with the surfaces): those it sent down
#: the NumPy passes, and then the volume that took it past the threshold
_tally: dict[object, int] = {}


def tallied(kind: object) -> int:
    """The work that ``"auto"`` has sent down the NumPy passes of ``kind``
    in this process (:func:`use_compiled`; ``kind``: True or False for the
    thresholds with and without the surfaces, or a caller's own name for
    a pass that weighs its work otherwise).

    Examples
    --------
    >>> tallied("a kind nothing counts")
    0
    """
    return _tally.get(kind, 0)


def add_to_tally(kind: object, work: int) -> None:
    """Count ``work`` that ``"auto"`` sends down the NumPy passes of
    ``kind`` (see :func:`tallied`).

    Examples
    --------
    >>> add_to_tally("an example's kind", 5); tallied("an example's kind")
    5
    """
    _tally[kind] = _tally.get(kind, 0) + int(work)


def reset_tally() -> None:
    """Forget what ``"auto"`` has tallied in this process, so that the
    next volume is weighed as in a fresh process (for tests, which share
    one process; the compiled passes numba has loaded stay loaded).

    Examples
    --------
    >>> add_to_tally(False, 10); reset_tally(); tallied(False)
    0
    """
    _tally.clear()


def use_compiled(volume: object, surfaces: bool = False, method: Method = "auto", record: bool = False) -> bool:
    """Whether a pass over ``volume`` takes the compiled path.

    ``"auto"``: a host NumPy volume of 2 or 3 dimensions, where numba is
    installed, whose voxels and those ``"auto"`` has already sent down the
    NumPy passes of this threshold in the process (:func:`tallied`)
    together reach :func:`least_voxels` (see the module). ``"numpy"``:
    never. ``"compiled"``: always, or one line saying why it cannot (no
    numba, a device array, a 4D volume).

    ``record``: the pass runs now, and ``"auto"`` counts a volume below
    the threshold in the tally, once per pass (a question alone leaves it
    as it is).

    Examples
    --------
    >>> import numpy as np
    >>> use_compiled(np.zeros((8, 8, 8), bool), method="numpy"), use_compiled(np.zeros((0, 8, 8), bool))
    (False, False)
    """
    import numpy as np

    method = check_method(method)
    if method == "numpy":
        return False
    host = isinstance(volume, np.ndarray) and volume.ndim in (2, 3)
    if method == "compiled":
        if not host:
            raise IsoflowError("method='compiled' takes 2D and 3D NumPy volumes (use 'numpy' or 'auto')")
        if not have_numba():
            raise IsoflowError("method='compiled' needs numba: pip install numba")
        return True
    return host and have_numba() and weigh(int(volume.size), surfaces, record)  # type: ignore[attr-defined]


def weigh(voxels: int, surfaces: bool = False, record: bool = False) -> bool:
    """``"auto"``'s choice for a pass over ``voxels`` host voxels (numba
    installed): the compiled pass where they and the voxels of this
    threshold that ``"auto"`` has already sent down the NumPy passes in
    the process (:func:`tallied`) reach :func:`least_voxels`; ``record``
    as for :func:`use_compiled`.

    Examples
    --------
    >>> weigh(least_voxels()), weigh(0)
    (True, False)
    """
    least = least_voxels(surfaces)
    compiled = voxels > 0 and tallied(surfaces) + voxels >= least  # (nothing to sweep in an empty one)
    if record and voxels < least:
        # the volume that takes the tally past the threshold is counted
        # too, so that it stays past it for the next volumes
        add_to_tally(surfaces, voxels)
    return compiled


def check_threads(n, where: str = "threads") -> int:
    """A thread count: a positive integer, or a clear error."""
    try:
        value = int(n)
    except (TypeError, ValueError, OverflowError):  # OverflowError: an infinite float
        value = 0
    if value < 1 or str(n).strip() != str(value):
        raise IsoflowError(f"{where} must be a positive integer, got {given_text(n)}")
    return value


def thread_argument(value: object, name: str = "threads") -> int:
    """A thread count given to a Python function: a whole number >= 1, as
    the other integer arguments take one (:func:`~isoflow.errors.whole_given`:
    ``int``, a NumPy integer, a whole float or a 0D array of one); anything
    else refused naming ``name``.

    :func:`check_threads` reads a count from text (the command line, the
    environment), and so took ``"8"``, ``Fraction(8)`` and ``Decimal("8")``
    (their text is ``8``).

    Parameters
    ----------
    value : object
        The count given: an ``int``, a NumPy integer, a whole float or a 0D
        array of one.
    name : str, default "threads"
        The argument, as the refusal names it.

    Returns
    -------
    int
        The count, a Python int.

    Raises
    ------
    IsoflowError
        Where ``value`` is no such integer, or is below 1.

    Examples
    --------
    >>> import numpy as np
    >>> from fractions import Fraction
    >>> thread_argument(8), thread_argument(np.array(8)), thread_argument(np.int32(2), "workers"), thread_argument(4.0)
    (8, 8, 2, 4)
    >>> thread_argument(Fraction(8))
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: threads must be a positive integer, got Fraction(8, 1)
    """

    whole = whole_given(value)
    if whole is None or whole < 1:
        raise IsoflowError(f"{name} must be a positive integer, got {given_text(value)}")
    return whole


def check_env_threads() -> None:
    """Refuse an :data:`ENV` that is not a thread count before any work:
    read only where a compiled pass runs, it passed unseen on a small input
    and failed the same command on a large one.

    Examples
    --------
    >>> import os
    >>> os.environ[ENV] = "abc"
    >>> check_env_threads()
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: the environment variable ISOFLOW_THREADS must be a positive integer, got 'abc'
    >>> del os.environ[ENV]; check_env_threads()
    """
    env = os.environ.get(ENV, "").strip()
    if env:
        check_threads(env, f"the environment variable {ENV}")


def available_cpus() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not on Linux
        return max(1, os.cpu_count() or 1)


def asked_threads() -> int | None:
    """The threads asked for now: :func:`using`'s count (``--threads N``),
    else the environment variable :data:`ENV`'s; None where neither is
    set, and each pass takes its own default (every CPU for the compiled
    passes, :func:`thread_count`).

    Returns
    -------
    int or None
        The count asked for, or None.

    Examples
    --------
    >>> with using(3):
    ...     asked_threads()
    3
    """
    asked = _asked.get()
    if asked is not None:
        return asked
    env = os.environ.get(ENV, "").strip()
    return check_threads(env, f"the environment variable {ENV}") if env else None


def thread_count(voxels: int | None = None) -> int:
    """The number of threads the compiled passes use now (see the module
    docs): for a pass over ``voxels`` voxels, when given, no more than one
    per :data:`VOXELS_PER_THREAD` unless asked."""
    asked = asked_threads()
    if asked is not None:
        return asked
    if voxels is not None:
        return max(1, min(available_cpus(), voxels // VOXELS_PER_THREAD))
    return available_cpus()


@contextlib.contextmanager
def using(threads: int | np.integer | None):
    """Run the enclosed passes on ``threads`` threads (None: the default)."""
    if threads is None:
        yield
        return
    token = _asked.set(thread_argument(threads))
    try:
        yield
    finally:
        _asked.reset(token)


def slabs(n: int, parts: int) -> list[tuple[int, int]]:
    """``[a, b)`` ranges splitting ``range(n)`` into at most ``parts`` nearly
    equal, non-empty pieces, in order."""
    parts = max(1, min(parts, n))
    cuts = [n * t // parts for t in range(parts + 1)]
    return [(a, b) for a, b in zip(cuts, cuts[1:]) if b > a]


#: each calling thread's pool of pass threads, kept between its calls of :func:`run`
_pools = threading.local()


def _pool(size: int):
    """The calling thread's pool of at least ``size`` threads, started
    once and kept: a pass over a small volume takes less time than
    starting its threads, and a volume swept slab by slab runs many
    passes. Each calling thread has its own pool, which it waits on
    until its calls are done, so each call still has a thread of its own
    whatever other threads run; a forked child starts its own pool (the
    parent's threads are not in it)."""
    from concurrent.futures import ThreadPoolExecutor

    held = getattr(_pools, "held", None)
    if held is None or held[0] != os.getpid() or held[1] < size:
        if held is not None and held[0] == os.getpid():
            held[2].shutdown(wait=False)  # its threads end once idle
        held = (os.getpid(), size, ThreadPoolExecutor(max_workers=size, thread_name_prefix="isoflow-pass"))
        _pools.held = held
    return held[2]


def run(calls: list, ticks: Ticks | None = None) -> list:
    """Run ``(fn, *args)`` calls, each on its own thread when there are
    several; results in order, once every call is done. The calls are
    compiled passes that release the GIL; one call runs on the calling
    thread, several on threads the calling thread keeps for its next
    calls, while it waits. With ``ticks``, calls that count their work
    there and look at :data:`~isoflow.scale.cancel.STOP` at each count
    (the label table's passes), it says their progress and, where the
    wait is interrupted (Ctrl-C), asks them to stop and returns once they
    have (within a step of their work); other calls are left to end as
    they do, the interrupt raised at once.

    Parameters
    ----------
    calls : list of tuple
        ``(fn, *args)`` for each call.
    ticks : Ticks, optional
        The calls' progress (:class:`~isoflow.scale.ticks.Ticks`), said
        every tenth of a second while they run; the calls stop when asked.

    Returns
    -------
    list
        ``fn(*args)`` of each call, in order; the first call's error (in
        order) is raised once all are done.

    Examples
    --------
    >>> run([(pow, 2, k) for k in range(4)])
    [1, 2, 4, 8]
    """
    if len(calls) <= 1:
        return [fn(*args) for fn, *args in calls]
    from concurrent.futures import wait

    from .cancel import POLL, STOP

    pool = _pool(len(calls))
    futures = [pool.submit(fn, *args) for fn, *args in calls]
    if ticks is None:
        wait(futures)  # no call left running when one fails, as a pool of its own would wait
        return [f.result() for f in futures]
    try:
        while wait(futures, timeout=POLL)[1]:
            ticks.say()
    except BaseException:
        ours = not STOP[0]  # a signal handler may have set it already, for other work too
        STOP[0] = 1
        _wait_out(futures)
        if ours:
            STOP[0] = 0
        raise
    return [f.result() for f in futures]


def _wait_out(futures: list) -> None:
    """Wait until every call has returned, whatever interrupts the wait
    (people press Ctrl-C twice; ``timeout`` signals the command and then
    its group): a call let run on would hold the process at its exit."""
    from concurrent.futures import wait

    while True:
        try:
            wait(futures)
            return
        except KeyboardInterrupt:
            continue


def run_ahead(calls: list, threads: int | None = None) -> Iterator:
    """The results of ``(fn, *args)`` calls, in order, each yielded as soon
    as it is done, while the next ``threads`` calls run on threads of
    their own (default :func:`thread_count`): what the caller does with
    one result (writes it out) overlaps the work on the next, and at most
    ``threads + 1`` results are held at once. A caller that stops early
    (an error, a closed pipe) cancels the calls not yet started and waits
    for those running. One thread, or one call: each runs on the calling
    thread when its result is asked for.

    Examples
    --------
    >>> list(run_ahead([(pow, 2, k) for k in range(5)], threads=2))
    [1, 2, 4, 8, 16]
    """
    threads = thread_count() if threads is None else threads
    if threads <= 1 or len(calls) <= 1:
        for fn, *args in calls:
            yield fn(*args)
        return
    from collections import deque
    from concurrent.futures import ThreadPoolExecutor

    pool = ThreadPoolExecutor(max_workers=min(threads, len(calls)))
    pending: deque = deque()
    try:
        for fn, *args in calls:
            pending.append(pool.submit(fn, *args))
            if len(pending) > threads:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
