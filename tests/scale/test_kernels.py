"""The compiled kernels give the same numbers as the numpy / scipy paths."""

import numpy as np
import pytest
from conftest import random_volume
from scipy.ndimage import generate_binary_structure, label
from skimage.measure import euler_number

from isoflow import DigitalObject, analyze
from isoflow.digital.configurations import configurations
from isoflow.scale import compiled, kernels

pytestmark = pytest.mark.skipif(not kernels.HAVE_NUMBA, reason="numba not installed")

#: adjacency -> scipy's neighbourhood rank (6 and 4 faces, 18 edges, 26 and 8 all)
RANK = {4: 1, 6: 1, 18: 2, 8: 2, 26: 3}


def scipy_count(v, conn):
    return label(v, generate_binary_structure(v.ndim, RANK[conn]))[1]


def scipy_enclosed(v, conn):
    lab, n = label(~v, generate_binary_structure(v.ndim, RANK[conn]))
    border = set()
    for ax in range(v.ndim):
        border |= set(np.take(lab, 0, ax).ravel()) | set(np.take(lab, -1, ax).ravel())
    return n - len(border - {0})


@pytest.mark.parametrize("threads", [1, 2, 3, 7])
def test_histogram_kernel(rng, threads):
    with compiled.using(threads):
        for _ in range(60):
            v = random_volume(rng, 9)
            want = np.bincount(configurations(v).ravel(), minlength=256)
            assert (kernels.histogram3d(v) == want).all()


@pytest.mark.parametrize("threads", [1, 2, 3, 7])
def test_component_kernels(rng, threads):
    # more slabs than layers too: (1, 1, 7) on 7 threads; the seams between
    # slabs are joined after the slabs
    shapes = [(1, 1, 7), (7, 1, 1), (1, 7, 1)]  # thin shapes broke cc3d's 26-labelling
    with compiled.using(threads):
        for t in range(120):
            v = rng.random(shapes[t % 3]) < 0.5 if t < 30 else random_volume(rng, 8, ndim=2 + t % 2)
            for conn in ((6, 18, 26) if v.ndim == 3 else (4, 8)):
                assert kernels.count_components(v, conn) == scipy_count(v, conn)
                assert kernels.count_enclosed(v, conn) == scipy_enclosed(v, conn)


def test_thread_count_from_the_environment_and_the_option(monkeypatch):
    from isoflow.errors import IsoflowError

    monkeypatch.setenv("ISOFLOW_THREADS", "3")
    assert compiled.thread_count() == 3
    with compiled.using(5):
        assert compiled.thread_count() == 5
    assert compiled.thread_count() == 3
    monkeypatch.delenv("ISOFLOW_THREADS")
    assert compiled.thread_count() == compiled.available_cpus() >= 1
    for bad in ("0", "-2", "two", "1.5"):
        monkeypatch.setenv("ISOFLOW_THREADS", bad)
        with pytest.raises(IsoflowError, match="ISOFLOW_THREADS"):
            compiled.thread_count()
    assert compiled.slabs(3, 7) == [(0, 1), (1, 2), (2, 3)]
    assert compiled.slabs(10, 3) == [(0, 3), (3, 6), (6, 10)]


def test_small_passes_take_fewer_threads_unless_asked(monkeypatch):
    # a thread per VOXELS_PER_THREAD voxels at most, unless asked by the
    # option or the environment (the tests of seams ask for theirs)
    monkeypatch.delenv("ISOFLOW_THREADS", raising=False)
    monkeypatch.setattr(compiled, "available_cpus", lambda: 16)
    per = compiled.VOXELS_PER_THREAD
    assert [compiled.thread_count(v) for v in (0, 64**3, per - 1, per, 2 * per, 5 * per + 7, 10**12)] == \
        [1, 1, 1, 1, 2, 5, 16]
    assert compiled.thread_count() == 16
    with compiled.using(3):
        assert compiled.thread_count(10) == 3
    monkeypatch.setenv("ISOFLOW_THREADS", "7")
    assert compiled.thread_count(10) == 7


def test_run_ahead_yields_in_order_with_the_next_calls_on_threads():
    """The results come in the order of the calls, while the calls after
    the one asked for run at once: two that each wait for the other (a
    barrier of two) finish only on two threads."""
    import threading

    meet = threading.Barrier(2, timeout=20)

    def both(k):
        meet.wait()
        return k * k

    assert list(compiled.run_ahead([(both, k) for k in range(6)], threads=2)) == [0, 1, 4, 9, 16, 25]
    assert list(compiled.run_ahead([(pow, 2, k) for k in range(5)], threads=1)) == [1, 2, 4, 8, 16]
    assert list(compiled.run_ahead([], threads=4)) == []


def test_run_ahead_stopped_early_starts_no_more_calls():
    """A caller that stops after the first result (a closed pipe) leaves
    the calls beyond the threads' look-ahead unstarted, and each started
    one finished (none left running after the generator is closed)."""
    import threading
    import time

    started, done = [], []
    lock = threading.Lock()

    def slow(k):
        with lock:
            started.append(k)
        time.sleep(0.02)
        with lock:
            done.append(k)
        return k

    results = compiled.run_ahead([(slow, k) for k in range(40)], threads=2)
    assert next(results) == 0
    results.close()
    assert len(started) <= 3  # the one yielded and the two ahead of it
    assert sorted(done) == sorted(started)


def test_analyze_gives_the_same_report_with_the_kernels(rng):
    v = rng.random((30, 31, 29)) < 0.45
    slow = analyze(DigitalObject(v), 26, surfaces=False)
    fast = analyze(DigitalObject(v), 26, surfaces=False, method="compiled")
    assert fast == slow
    assert fast["euler_characteristic"] == euler_number(v, 3)


def test_mesh_components_equal_scipy_graph_components(rng):
    # random noise: many surfaces, pinches and doubled edges (midpoint slots)
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from isoflow.digital.surface import boundary_mesh
    from isoflow.scale.kernels import label_polygons

    for conn in (6, 26):
        mesh = boundary_mesh(rng.random((14, 12, 13)) < 0.5, conn)
        poly = mesh.polygons()
        nv = len(mesh.vertices)
        rows = np.repeat(np.arange(len(poly)), poly.shape[1])
        cols = poly.ravel()
        keep = cols >= 0
        # bipartite face-vertex graph: independent of the kernel's union order
        graph = coo_matrix((np.ones(keep.sum()), (rows[keep] + nv, cols[keep])),
                           shape=(nv + len(poly),) * 2)
        n, ref = connected_components(graph, directed=False)
        label, count = label_polygons(poly, nv)
        assert count == n and mesh.midpoints > 0
        # same partition: the pairs (label, ref) are a bijection
        pairs = np.unique(np.stack([label, ref[:nv]], 1), axis=0)
        assert len(pairs) == n == len(np.unique(label)) == len(np.unique(ref[:nv]))


def test_bool_arrays_with_bytes_other_than_one_are_read_as_true(rng):
    # np.ndarray.view(bool) keeps the raw bytes (here 2); the kernels read
    # bytes, and once wrote past their arrays on such input
    from conftest import compiled_side

    u = (rng.random((compiled_side(),) * 3) < 0.3).astype(np.uint8) * 2
    v = u.view(bool)
    assert v.size >= compiled.least_voxels(surfaces=True)
    for conn, sk in ((6, 1), (26, 3)):
        r = analyze(DigitalObject(v), conn, surfaces=False)
        assert r["euler_characteristic"] == euler_number(u > 0, connectivity=sk)
        assert r["betti"][0] == scipy_count(u > 0, conn)
    # a bare array reaches the compiled pass with its bytes as they are
    # (analyze makes them 0/1 only for the NumPy passes): the same report,
    # surfaces included, as the 0/1 volume's, on both paths
    for part in (np.s_[:], np.s_[:30, :30, :30]):
        for conn, sk in ((6, 1), (26, 3)):
            r = analyze(v[part], conn)
            assert r == analyze(u[part] > 0, conn)
            assert r["euler_characteristic"] == euler_number(u[part] > 0, connectivity=sk)
    # the kernels themselves test bytes for nonzero
    assert (kernels.histogram3d(v) == kernels.histogram3d(u > 0)).all()
    assert kernels.count_components(v, 6) == scipy_count(u > 0, 6)
