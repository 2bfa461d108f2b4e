"""Shared shapes for the tests: digital balls, tori and rings built from
their defining inequalities, so that their topology is known exactly."""

import io
import sys

import numpy as np
import pytest

# the documentation built once per session, and the examples' runs in its gallery
pytest_plugins = ["docs_site"]

#: test files that share a session's work, run on one worker of pytest-xdist:
#: the documentation's site, whose gallery runs the examples, built once; the
#: compiled passes that a cold cache would otherwise compile on both workers
#: at once (the winding rule's, the label table's)
SHARED_WORKER = {"test_docs.py": "site", "test_examples.py": "site",
                 "test_winding.py": "winding", "test_voxelize.py": "winding", "test_fills.py": "winding",
                 "test_winding_tree.py": "winding", "test_readers.py": "winding",
                 "test_label_table.py": "labels", "test_labels_cli.py": "labels"}


#: the test files (or groups of :data:`SHARED_WORKER`) that take longest on a
#: cold cache, begun first and in this order (seconds, cold, 2026-12-03: the
#: winding rule's group 177, the flow's plain reference 76, mostly its
#: compile, the wheel built and installed 71, the label table's group 71, out
#: of core 60, the flow on bit rows 54, the site with its gallery 47, the
#: chunked flow 43); each worker takes the next file when it is done, so no
#: long one is left to run alone at the end while the other idles.
#: pyproject.toml passes ``--no-loadscope-reorder``: pytest-xdist would
#: otherwise order the files by their number of tests
LONGEST_FIRST = ("winding", "test_plain_reference.py", "test_packaging.py", "labels", "test_outofcore.py",
                 "test_bitflow.py", "site", "test_chunked.py")


def pytest_configure(config):
    """isoflow's modules compiled to bytecode once, before the workers
    start: the tests run hundreds of commands (``python -m isoflow ...``),
    and where ``PYTHONDONTWRITEBYTECODE`` is set each would compile every
    module it imports from source again, which an installed package (pip
    compiles it at install) never does."""
    if hasattr(config, "workerinput"):  # a pytest-xdist worker: the controller did it
        return
    import compileall
    from pathlib import Path

    import isoflow

    compileall.compile_dir(Path(isoflow.__file__).parent, quiet=2)  # quiet: a read-only install stays as it is


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist's own, which reads the groups
def pytest_collection_modifyitems(config, items):
    """Each test file on one worker of pytest-xdist (``--dist loadgroup``
    in pyproject.toml): a file's tests use the same compiled passes, which
    a cold cache then compiles once rather than on both workers at once;
    the files of :data:`SHARED_WORKER` share one, and those of
    :data:`LONGEST_FIRST` come first, in its order."""
    def rank(item) -> int:
        scope = SHARED_WORKER.get(item.path.name, item.path.name)
        return LONGEST_FIRST.index(scope) if scope in LONGEST_FIRST else len(LONGEST_FIRST)

    items.sort(key=rank)  # stable: the rest keep their order
    for item in items:
        item.add_marker(pytest.mark.xdist_group(SHARED_WORKER.get(item.path.name, item.nodeid.split("::")[0])))


def ball(radius: float, size: int | None = None, centre=None) -> np.ndarray:
    size = size or int(2 * radius + 4)
    c = (size - 1) / 2 if centre is None else centre
    x = np.indices((size,) * 3) - np.reshape(c, (-1, 1, 1, 1))
    return (x**2).sum(0) <= radius**2


def torus(R: float, r: float, size: int | None = None, axis: int = 2, centre=None) -> np.ndarray:
    """Solid torus of major radius R and minor radius r, around ``axis``."""
    size = size or int(2 * (R + r) + 4)
    c = np.full(3, (size - 1) / 2) if centre is None else np.asarray(centre, float)
    x = np.indices((size,) * 3).astype(float) - c.reshape(3, 1, 1, 1)
    others = [i for i in range(3) if i != axis]
    rho = np.sqrt(x[others[0]] ** 2 + x[others[1]] ** 2)
    return (rho - R) ** 2 + x[axis] ** 2 <= r**2


def compiled_side() -> int:
    """The side of the smallest cube of voxels that takes the compiled
    passes with and without the surfaces
    (:func:`isoflow.scale.compiled.least_voxels`), for tests that run them
    as a user would, in a fresh process."""
    from isoflow.scale.compiled import least_voxels

    return int(round(least_voxels(surfaces=True) ** (1 / 3))) + 2


@pytest.fixture
def rng():
    return np.random.default_rng(20131122)


def without_compile_note(stderr: str) -> str:
    """A child process' stderr less the compile note: where numba's cache
    is cold (a fresh ``NUMBA_CACHE_DIR``, as CI has), whether a pass is
    compiled in this test's command or in an earlier test's depends on the
    order the tests run in, which the workers share out."""
    from isoflow.scale.compiled import COMPILE_NOTE

    return "\n".join(line for line in stderr.splitlines() if not line.endswith(COMPILE_NOTE))


def random_volume(rng, max_side: int = 7, ndim: int = 3) -> np.ndarray:
    shape = rng.integers(1, max_side + 1, ndim)
    return rng.random(shape) < rng.uniform(0.1, 0.9)


@pytest.fixture(autouse=True)
def _as_in_a_single_call(monkeypatch):
    """No compile note is said in a test: a command run in-process whose
    pass numba compiles for the first time, in a fresh cache, would add the
    note to the stderr a test reads (the note is tested on its own in
    test_cli.py)."""
    from isoflow.scale import compiled

    monkeypatch.setattr(compiled, "_compile_noted", True)


@pytest.fixture(autouse=True)
def _fresh_tally():
    """Each test's ``method="auto"`` weighs its volumes as a fresh process
    would: the tests share a process, and the voxels earlier tests sent
    down the NumPy passes would otherwise take later ones compiled
    (:func:`isoflow.scale.compiled.reset_tally`)."""
    from isoflow.scale import compiled

    compiled.reset_tally()


class Terminal(io.StringIO):
    """A stderr that says it is a terminal and keeps what is written."""

    def isatty(self):
        return True


def stderr_of(monkeypatch, stream, argv) -> str:
    """What the command line ``argv`` writes on ``stream`` put in place of
    stderr (a :class:`Terminal`: the progress bars), the command run in
    this process and ending with status 0."""
    from isoflow.cli import main

    monkeypatch.setattr(sys, "stderr", stream)
    assert main([str(a) for a in argv]) == 0
    monkeypatch.undo()
    return stream.getvalue()
