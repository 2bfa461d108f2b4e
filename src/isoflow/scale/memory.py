"""The memory budget: refuse, before allocating, work that would not fit.

A job that runs out of memory on Linux is usually killed without a word (or
makes the machine swap for minutes); a clear error up front is better. Every
guarded job estimates its peak from numbers it knows cheaply (grid size, the
configuration histogram) and compares it with a budget: 90 % of the memory
the kernel says is available when the job starts, or of the room a
container's or batch job's memory limit (its control group) leaves, where
that is less.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from numpy.typing import DTypeLike

from ..errors import DoesNotFit, IsoflowError, given_text, whole_given

#: where Linux says what memory this process may use: its own files, and
#: the control groups' (both are paths so that a test can give others)
PROC_SELF = Path("/proc/self")
MEMINFO = Path("/proc/meminfo")
CGROUPS = Path("/sys/fs/cgroup")


#: the budgets :func:`budget_held` holds, innermost last (one for the
#: whole process, its threads too: a run's writers are threads)
_HELD: list[int] = []


@contextlib.contextmanager
def budget_held(budget: int | None = None) -> Iterator[int]:
    """Within it, :func:`default_budget` answers one budget, read once on
    entry (or ``budget``): a run that checks each of its many outputs (a
    surface per label, each file read back) reads the memory available
    and its control groups' limits once, not once an output.

    Parameters
    ----------
    budget : int, optional
        The bytes to answer; default: :func:`default_budget` now.

    Yields
    ------
    int
        The budget held.

    Examples
    --------
    >>> with budget_held(10**6) as held:
    ...     held, default_budget()
    (1000000, 1000000)
    >>> default_budget() == 10**6
    False
    """
    held = default_budget() if budget is None else int(budget)
    _HELD.append(held)
    try:
        yield held
    finally:
        _HELD.pop()


def default_budget() -> int:
    """90 % of the least room Linux leaves this process now: the memory
    available (MemAvailable: free plus reclaimable cache); its control
    group's limit less what the group holds, each group up to the root
    (:func:`cgroup_room`: a container's limit, a batch job's as Slurm sets
    it, which MemAvailable, the whole machine's, does not see: work past
    it is killed without a word). Half the physical memory where
    MemAvailable cannot be read, 4 GiB where that cannot be either. (An
    address-space limit, ``ulimit -v``, is left to the allocation that
    fails: it raises MemoryError, said in one line, and the address space
    held counts reservations no job fills.)

    Returns
    -------
    int
        Bytes.

    Examples
    --------
    >>> physical = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")  # (MemAvailable moves between reads)
    >>> 0 < default_budget() <= 0.9 * physical
    True

    Within :func:`budget_held`, the budget it read on entry.
    """
    if _HELD:
        return _HELD[-1]
    available, group = meminfo_available(), cgroup_room()
    budgets = [room * 9 // 10 for room in (available, group) if room is not None]
    if available is None:
        try:
            budgets.append(int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")) // 2)
        except (ValueError, OSError, AttributeError):
            budgets.append(4 << 30)
    return max(0, min(budgets))


def meminfo_available() -> int | None:
    """The machine's MemAvailable in bytes (free plus reclaimable cache),
    None where ``/proc/meminfo`` cannot be read.

    Examples
    --------
    >>> meminfo_available() > 0
    True
    """
    try:
        with open(MEMINFO) as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def cgroup_room() -> int | None:
    """The bytes this process's memory control groups have left: at each
    group from the process's own to the root of its hierarchy, the limit
    less the usage short of the inactive file cache the kernel reclaims
    before it kills (cgroup v2: ``memory.max``, ``memory.current``; v1:
    ``memory.limit_in_bytes``, ``memory.usage_in_bytes``), the least of
    them; None where no group sets a limit (or none can be read).

    Returns
    -------
    int or None

    Examples
    --------
    >>> room = cgroup_room()  # None where no group sets a limit (a machine of one's own)
    >>> room is None or default_budget() <= room
    True
    """
    try:
        lines = (PROC_SELF / "cgroup").read_text().splitlines()
    except OSError:
        return None
    rooms = []
    for line in lines:
        parts = line.split(":", 2)
        if len(parts) != 3:
            continue
        _, controllers, group = parts
        if controllers == "":  # v2 (mounted at the root, or beside v1 as "unified")
            places = [(CGROUPS, "memory.max", "memory.current", "inactive_file"),
                      (CGROUPS / "unified", "memory.max", "memory.current", "inactive_file")]
        elif "memory" in controllers.split(","):
            places = [(CGROUPS / "memory", "memory.limit_in_bytes", "memory.usage_in_bytes", "total_inactive_file")]
        else:
            continue
        for root, limit_file, usage_file, cache_key in places:
            for folder in _groups_up(root, group):
                limit = _read_bytes(folder / limit_file)
                if limit is None or limit >= 1 << 60:  # "max", or v1's page-rounded 2^63: no limit
                    continue
                usage = _read_bytes(folder / usage_file) or 0
                rooms.append(limit - max(0, usage - _stat_value(folder / "memory.stat", cache_key)))
    return min(rooms) if rooms else None


def _groups_up(root: Path, group: str):
    """The folders of a control group and of each group above it, to the
    hierarchy's root (a container sees its own group as the root: the
    path ``/proc`` gives may then not be there under ``root``)."""
    folder = root / group.strip("/")
    while True:
        if folder.is_dir():
            yield folder
        if folder == root or root not in folder.parents:
            return
        folder = folder.parent


def _read_bytes(path: Path) -> int | None:
    try:
        text = path.read_text().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def _stat_value(path: Path, key: str) -> int:
    try:
        for line in path.read_text().splitlines():
            name, _, value = line.partition(" ")
            if name == key and value.strip().isdigit():
                return int(value)
    except OSError:
        pass
    return 0


def budget_of(max_bytes: object, where: str = "voxelize") -> int:
    """The memory budget a caller's ``max_bytes`` sets: the default
    (:func:`default_budget`) for None, else a positive whole number of bytes
    (``8e9`` too); anything else is refused naming it, where ``int()`` took
    "1000000" and 2.5 in silence and raised its own ValueError for "8GB".

    Parameters
    ----------
    max_bytes : int, float or None
        What was given.
    where : str
        The function, for the message.

    Returns
    -------
    int

    Examples
    --------
    >>> budget_of(8e9)
    8000000000
    >>> budget_of("8GB")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: voxelize: max_bytes must be a positive whole number of bytes, got '8GB'
    """
    if max_bytes is None:
        return default_budget()
    whole = whole_given(max_bytes)
    if whole is None or whole < 1:
        raise IsoflowError(f"{where}: max_bytes must be a positive whole number of bytes, got {given_text(max_bytes)}")
    return whole


def check_fits(need: int, what: str, hint: str = "", budget: int | None = None) -> None:
    """Raise :class:`DoesNotFit` when ``need`` bytes exceed the budget."""
    budget = default_budget() if budget is None else int(budget)
    if need > budget:
        raise DoesNotFit(
            f"{what} needs about {sized(need)} of memory, more than the budget of {sized(budget)} "
            "(the memory available now)" + (f"; {hint}" if hint else "")
        )


def worker_room(client) -> tuple[int, int] | None:
    """The memory limit and threads of the ``dask.distributed`` worker
    with the most memory per thread: the workers hold their own memory,
    which this machine's says nothing of.

    Parameters
    ----------
    client : distributed.Client
        The cluster's client (its scheduler's ``identity`` gives each
        worker's ``memory_limit`` and ``nthreads``).

    Returns
    -------
    tuple of int or None
        ``(memory_limit, nthreads)``; None where a worker has no limit (0:
        it holds anything) or the cluster has no worker yet.

    Examples
    --------
    >>> class Cluster:  # what a client's scheduler_info() says of its workers
    ...     def scheduler_info(self, n_workers=-1):
    ...         return {"workers": {"tcp://w1": {"memory_limit": 200_000_000, "nthreads": 2},
    ...                             "tcp://w2": {"memory_limit": 150_000_000, "nthreads": 1}}}
    >>> worker_room(Cluster())
    (150000000, 1)
    """
    rooms = [(int(w.get("memory_limit") or 0), max(int(w.get("nthreads") or 1), 1)) for w in _workers(client)]
    if not rooms or any(limit <= 0 for limit, _ in rooms):
        return None
    # the scheduler may give the largest tasks to the worker with the most memory per thread
    return max(rooms, key=lambda room: room[0] / room[1])


def _workers(client) -> list[dict]:
    """Each worker's record, as the scheduler says it now.

    A client's ``scheduler_info()`` asks the scheduler and then returns the
    client's cached copy, which the client's own refresh (every
    ``distributed.client.scheduler-info-interval``, of totals and no
    worker) may replace in between: the cluster then reads as having no
    worker, and its memory limit goes unchecked. The scheduler's answer is
    taken as it comes instead; an object with ``scheduler_info()`` alone
    is asked that.
    """
    identity = getattr(getattr(client, "scheduler", None), "identity", None)
    if identity is None:
        info = client.scheduler_info(n_workers=-1)
    else:
        try:
            info = client.sync(identity, n_workers=-1)
        except TypeError:  # a dask.distributed whose scheduler lists every worker without being asked
            info = client.sync(identity)
    return list(info["workers"].values())


def check_workers_fit(client, per_task: int, what: str, hint: str = "", held: int = 0) -> None:
    """Raise :class:`IsoflowError` when tasks of ``per_task`` bytes, as many
    at a time as a worker has threads, beside ``held`` bytes, exceed the
    memory limit of every worker of a ``dask.distributed`` cluster
    (:func:`worker_room`), saying how many at a time would fit a worker
    where one does.

    Parameters
    ----------
    client : distributed.Client
        The cluster's client (its scheduler's ``identity`` gives each
        worker's ``memory_limit`` and ``nthreads``).
    per_task : int
        The bytes one task holds.
    what : str
        What runs, for the message.
    hint : str
        What to do instead, for the message.
    held : int
        The bytes a worker may hold beside its tasks at work (the results
        that later tasks take), whatever its threads.

    Notes
    -----
    The worker with the most memory per thread decides; a worker without a
    limit (0) fits anything, and a cluster with no worker yet is not
    refused.

    Examples
    --------
    >>> class Cluster:  # what a client's scheduler_info() says of its workers
    ...     def scheduler_info(self, n_workers=-1):
    ...         return {"workers": {"tcp://w1": {"memory_limit": 200_000_000, "nthreads": 2}}}
    >>> check_workers_fit(Cluster(), 50_000_000, "summing blocks")
    >>> check_workers_fit(Cluster(), 150_000_000, "summing blocks", hint="write smaller chunks")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: summing blocks needs about 286.1 MiB on a dask.distributed worker (2 threads at a
    time), more than its memory limit of 190.7 MiB; one at a time fits it (workers of one thread each), or write
    smaller chunks
    """
    room = worker_room(client)
    if room is None:
        return
    limit, threads = room
    need = per_task * threads + held
    if need <= limit:
        return
    fit = max(limit - held, 0) // max(per_task, 1)
    if fit >= 1:  # fewer threads per worker would do
        fits = ("one at a time fits it (workers of one thread each)" if fit == 1 else
                f"{fit} at a time fit it (workers of {fit} threads each)")
        hint = f"{fits}, or {hint}" if hint else fits
    raise IsoflowError(f"{what} needs about {sized(need)} on a dask.distributed worker ({threads} "
                       f"thread{'s' if threads > 1 else ''} at a time), more than its memory limit of {sized(limit)}"
                       + (f"; {hint}" if hint else ""))


def sized(n: int) -> str:
    """A number of bytes as a person reads it: in GiB from 1 GiB on, in MiB
    or KiB below (a budget of "0.0 GiB" says nothing).

    Examples
    --------
    >>> sized(3 << 30), sized(12_000_000), sized(200_000), sized(100)
    ('3.0 GiB', '11.4 MiB', '195 KiB', '100 bytes')
    """
    if n >= 1 << 30:
        return f"{n / 2**30:.1f} GiB"
    if n >= 1 << 20:
        return f"{n / 2**20:.1f} MiB"
    return f"{n / 2**10:.0f} KiB" if n >= 1 << 10 else f"{n} bytes"


#: a map of this many bytes or more asks for the processor's large pages
#: (2 MiB, where the system lends them on request), as NumPy does for its
#: own large arrays: the system then zeroes and maps a table a large page
#: at a time instead of in thousands of small faults
HUGE_PAGES_FROM = 4 << 20


def _pages(nbytes: int):
    """A private anonymous memory map of ``nbytes`` (at least 1), in large
    pages from :data:`HUGE_PAGES_FROM` bytes on."""
    import mmap

    if hasattr(mmap, "MAP_PRIVATE"):  # POSIX: a private map (a shared one faults slower)
        pages = mmap.mmap(-1, max(nbytes, 1), flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    else:  # Windows: its anonymous maps take no flags
        pages = mmap.mmap(-1, max(nbytes, 1))
    if nbytes >= HUGE_PAGES_FROM and hasattr(mmap, "MADV_HUGEPAGE"):
        pages.madvise(mmap.MADV_HUGEPAGE)
    return pages


def mapped(shape: int | tuple[int, ...], dtype: DTypeLike, fill: object = None) -> np.ndarray:
    """An array in pages of its own (a private anonymous memory map, in
    large pages from :data:`HUGE_PAGES_FROM` bytes on), zeros or ``fill``:
    given back to the system the moment it is let go. The C
    allocator keeps arrays of up to 32 MiB in heaps that it seldom gives
    back once one of that size was freed, so a pass that makes and frees
    many of them holds far more memory than it uses; the large passes over
    label images take their tables this way."""
    kind = np.dtype(dtype)
    count = int(np.prod(shape, dtype=np.int64))
    if count * kind.itemsize < 1 << 20:  # small: the allocator's pools serve it as well
        out = np.zeros(shape, kind)
    else:
        out = np.frombuffer(_pages(count * kind.itemsize), kind, count).reshape(shape)
    if fill is not None:
        out[...] = fill
    return out


class Growable:
    """A 1D buffer of ``size`` entries of ``dtype`` in pages of its own
    (zeros, as :func:`mapped`) that changes its size without a copy where
    the system can move its pages (Linux's ``mremap``): its entries stay
    where they are and the pages beyond them are not touched until
    written. A copy would write each entry a second time into memory the
    process touches for the first time, which costs about what finding
    the entries did.

    :meth:`array` gives the buffer as an array; :meth:`resize` moves the
    pages only where no such array is held any more (else it copies).

    Parameters
    ----------
    size : int
        Entries at first.
    dtype : numpy dtype
        Their type.

    Examples
    --------
    >>> runs = Growable(1 << 20, np.int32)
    >>> a = runs.array()
    >>> a[:3] = 7
    >>> del a
    >>> runs.resize(1 << 22, used=3)
    >>> b = runs.array()
    >>> len(b), b[:4].tolist()
    (4194304, [7, 7, 7, 0])
    """

    def __init__(self, size: int, dtype: DTypeLike) -> None:
        self.dtype = np.dtype(dtype)
        self.size = int(size)
        self._pages = _pages(self.size * self.dtype.itemsize)

    def array(self) -> np.ndarray:
        """The buffer's ``size`` entries (a view of its pages)."""
        return np.frombuffer(self._pages, self.dtype, self.size)

    def resize(self, size: int, used: int) -> None:
        """``size`` entries, of which the first ``used`` are kept (the rest
        zeros)."""
        nbytes = max(int(size) * self.dtype.itemsize, 1)
        used = min(used, int(size))
        try:
            self._pages.resize(nbytes)
        except (BufferError, OSError, SystemError, ValueError):
            # an array of the buffer still held, or a system that cannot move
            # pages: new pages, the entries copied
            pages = _pages(nbytes)
            np.frombuffer(pages, self.dtype, used)[:] = np.frombuffer(self._pages, self.dtype, used)
            self._pages = pages
        else:
            if nbytes >= HUGE_PAGES_FROM and hasattr(self._pages, "madvise"):
                import mmap

                if hasattr(mmap, "MADV_HUGEPAGE"):
                    self._pages.madvise(mmap.MADV_HUGEPAGE)
        self.size = int(size)
