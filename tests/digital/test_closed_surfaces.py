"""The closed surfaces counted without the mesh equal the mesh's own
components (``boundary_mesh(...).components()``), on random volumes full of
edge and vertex contacts and on shapes of known genus, along both paths
(numpy/scipy for small volumes, the compiled sweep for large ones) and on
any number of threads."""

import numpy as np
import pytest
from conftest import ball, torus

from isoflow import analyze, boundary_mesh, euler_characteristic
from isoflow.digital.closed_surfaces import closed_surfaces, sweep_tables
from isoflow.digital.topology import betti_numbers
from isoflow.scale import compiled


def mesh_answer(v, conn):
    m = boundary_mesh(v, conn)
    comps = sorted((c["euler_characteristic"], c["genus"], c["faces"]) for c in m.components())
    return comps, m.pinched, m.midpoints // 2


def counted(r):
    surfaces = sorted((s["euler_characteristic"], s["genus"], s["faces"]) for s in r["surfaces"])
    return surfaces, r["pinched_vertices"], r["doubled_edges"]


@pytest.mark.parametrize("conn", [6, 26])
def test_random_volumes_small_path(rng, conn):
    seen = np.zeros(3, int)
    for _ in range(700):
        shape = rng.integers(1, 8, 3)
        v = rng.random(shape) < rng.uniform(0.1, 0.9)
        want = mesh_answer(v, conn)
        assert counted(closed_surfaces(v, conn)) == want
        seen += [want[1] > 0, want[2] > 0, len(want[0]) > 1]
    # vertex contacts split against the connectivity, doubled edges (from
    # edge contacts) and several surfaces all occurred, many times
    assert (seen > 50).all(), seen


@pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")
@pytest.mark.parametrize("conn", [6, 26])
def test_random_volumes_compiled_path_on_1_2_3_7_threads(rng, conn):
    seen = np.zeros(3, int)
    for t in range(700):
        shape = rng.integers(1, 10, 3)
        v = rng.random(shape) < rng.uniform(0.1, 0.9)
        seen += _check_compiled(v, conn, (1, 2, 3, 7)[t % 4])
    assert (seen > 50).all(), seen


def _check_compiled(v, conn, threads):
    """The compiled pass on ``threads`` threads against the mesh's
    components, scipy's Betti numbers and the configuration histogram;
    returns which of cavities, tunnels, several surfaces the volume has."""
    want = mesh_answer(v, conn)
    with compiled.using(threads):
        r = closed_surfaces(v, conn, method="compiled")
    assert counted(r) == want
    # the same pass gives the Betti counts: components, enclosed background
    b = betti_numbers(v, conn)
    assert list(r["betti_counts"]) == [b[0], b[2]]
    assert (r["hist"] == np.bincount(_configs(v), minlength=256)).all()
    return np.array([want[1] > 0, want[2] > 0, len(want[0]) > 1])


def _configs(v):
    from isoflow.digital.configurations import configurations

    return configurations(v).ravel()


def shapes():
    solid = ball(9)
    n = solid.shape[0]
    hollow = solid & ~ball(5, size=n)  # two spheres: outer and cavity
    ring = torus(8, 3)
    two = np.zeros((40, 24, 24), bool)
    two[:22, :22, :22] = torus(7, 3, size=22)
    two[20:, 2:22, 2:22] = torus(7, 3, size=20, axis=0)  # linked-ish, touching
    nested = ball(14) & ~ball(11, size=32)
    nested |= ball(6, size=32)  # a ball inside a shell: three spheres
    return {"ball": (solid, [0]), "hollow": (hollow, [0, 0]), "torus": (ring, [1]),
            "nested": (nested, [0, 0, 0]), "two tori": (two, None)}


@pytest.mark.parametrize("method", ["numpy", "compiled"])
@pytest.mark.parametrize("conn", [6, 26])
def test_known_shapes(method, conn):
    if method == "compiled" and not compiled.have_numba():
        pytest.skip("numba not installed")
    for name, (v, genus) in shapes().items():
        r = closed_surfaces(v, conn, method=method)
        assert counted(r) == mesh_answer(v, conn), name
        if genus is not None:
            assert sorted(s["genus"] for s in r["surfaces"]) == genus, name
        chi = euler_characteristic(v, conn)
        # docs/mathematics.md: the surfaces' chi add up to 2 chi + 2 p
        assert sum(s["euler_characteristic"] for s in r["surfaces"]) == 2 * chi + 2 * r["pinched_vertices"]


@pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")
@pytest.mark.parametrize("conn", [6, 26])
def test_random_volumes_with_rows_of_several_words(rng, conn):
    # the sweep reads rows 64 voxels to a word: rows that end inside a word,
    # on its last bit, one past it, and runs across words, on 1, 2, 3 and 7
    # threads, with edge and vertex contacts
    seen = np.zeros(3, int)
    for t, nz in enumerate([63, 64, 65, 127, 128, 129, 200] * 6):
        shape = (*rng.integers(1, 6, 2), nz)
        v = rng.random(shape) < rng.uniform(0.2, 0.8)
        # long runs too, crossing word boundaries
        v[..., 50:140] |= rng.random(shape[:2] + (1,)) < 0.3
        seen += _check_compiled(v, conn, (1, 2, 3, 7)[t % 4])
    assert (seen > 10).all(), seen


@pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")
def test_sweep_finds_the_pinches_again_when_a_slab_has_more_than_its_buffer(rng, monkeypatch):
    # many pinches in one slab and a buffer of one pair: the slab is swept
    # again for its pinches alone, and the answer is the same
    from isoflow.scale import sweep

    real = sweep.sweep
    for conn, density in ((6, 0.8), (26, 0.2)):
        v = rng.random((12, 40, 40)) < density
        want = mesh_answer(v, conn)
        b = betti_numbers(v, conn)
        monkeypatch.setattr(sweep, "sweep", lambda *args, **kw: real(*args, **kw, pair_capacity=1))
        with compiled.using(2):
            r = closed_surfaces(v, conn, method="compiled")
        monkeypatch.setattr(sweep, "sweep", real)
        assert counted(r) == want
        assert list(r["betti_counts"]) == [b[0], b[2]]
        assert want[1] > 20  # the buffers did overflow


def test_analyze_reports_the_surfaces_of_both_paths(rng):
    v = rng.random((20, 21, 19)) < 0.5
    small = analyze(v, 26)
    if compiled.have_numba():
        assert analyze(v, 26, threads=3, method="compiled") == small
    comps, pinched, doubled = mesh_answer(v, 26)
    assert sorted((s["euler_characteristic"], s["genus"], s["faces"]) for s in small["surfaces"]) == comps
    assert small["pinched_vertices"] == pinched and small["doubled_edges"] == doubled
    faces = [s["faces"] for s in small["surfaces"]]
    assert faces == sorted(faces, reverse=True)  # largest first


def test_tables_follow_the_mesh_rules():
    # every sheet of every configuration has at least three faces, the
    # octants it names are an object and a background one, and the face
    # slots add up to the configuration's boundary faces
    from isoflow.digital.surface import face_slots

    for conn in (6, 26):
        nsheet, obj, bg, quarters, spokes, pinch = sweep_tables(conn)
        for c in range(256):
            n = nsheet[c]
            assert quarters[c, :n].sum() == face_slots()[c]
            assert (quarters[c, :n] >= 3).all()
            for s in range(n):
                assert (c >> int(obj[c, s])) & 1 and not (c >> int(bg[c, s])) & 1
        assert (nsheet[[0, 255]] == 0).all()
        assert np.count_nonzero(pinch[:, 0] >= 0) == 4  # four pairs of opposite octants


def test_the_small_path_stays_within_its_memory_estimate_and_refuses_beyond_it(monkeypatch):
    # small_census checks its peak up front (bytes per voxel and per mesh
    # vertex): the estimate must bound what tracemalloc measures, on shapes
    # with little and much boundary per voxel, and a budget below it is
    # refused with one line naming the volume, before any labelling
    import tracemalloc

    from isoflow.digital import closed_surfaces as cs
    from isoflow.errors import IsoflowError
    from isoflow.scale import memory

    rng = np.random.default_rng(11)
    vols = {"ball": ball(30), "torus": torus(20, 6), "noise": rng.random((50, 45, 40)) < 0.3,
            "empty": np.zeros((40, 40, 40), bool), "full": np.ones((40, 40, 40), bool)}
    for name, v in vols.items():
        for conn in (6, 26):
            hist = np.bincount(cs.configurations(v).ravel(), minlength=256)
            estimate = cs.SMALL_BYTES_PER_VOXEL * v.size + cs.SMALL_BYTES_PER_SHEET * int(hist @ sweep_tables(conn)[0])
            tracemalloc.start()
            got = cs.small_census(v, conn)
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            assert peak <= estimate, (name, conn, peak / v.size, estimate / v.size)
            assert counted(got) == mesh_answer(v, conn)
            with monkeypatch.context() as m, pytest.raises(IsoflowError, match="x".join(map(str, v.shape))):
                m.setattr(memory, "default_budget", lambda estimate=estimate: estimate - 1)
                cs.small_census(v, conn)


def test_between_the_thresholds_the_census_is_below_its_size_and_both_methods_agree():
    # with the surfaces, a volume between 2 and 4 million voxels is below
    # the compiled census's size (numba's start would cost more than it
    # saves), the passes without the surfaces above theirs; both
    # methods give the same report, and the mesh's surfaces
    from isoflow.scale.compiled import have_numba, least_voxels, use_compiled

    if not have_numba():
        pytest.skip("numba not installed")
    v = np.zeros((141, 141, 141), bool)
    assert least_voxels() <= v.size < least_voxels(surfaces=True)
    v[:40, :40, :40] = torus(12, 5, size=40)
    v[60:90, 60:90, 60:90] = ball(14, size=30)
    v[100, 100, 100] = v[101, 101, 101] = True  # a vertex contact
    assert not use_compiled(v, surfaces=True) and use_compiled(v)  # by the size alone
    compiled_report = analyze(v, 26, method="compiled")
    for conn in (6, 26):
        report = analyze(v, conn)
        assert counted(report)[0] == mesh_answer(v, conn)[0]
        if conn == 26:
            assert report == compiled_report


def odd_bools(rng, shape, density):
    """A bool array whose set bytes are 1, 2, 4, ... 255 (as ``.view(bool)``
    of an integer array gives), and the same array with canonical bytes."""
    u = np.where(rng.random(shape) < density, rng.choice([1, 2, 4, 8, 128, 255], shape), 0).astype(np.uint8)
    return u.view(bool), u != 0


@pytest.mark.parametrize("method", ["numpy", "compiled"])
@pytest.mark.parametrize("conn", [6, 26])
def test_bool_bytes_other_than_one_and_read_only_arrays(rng, conn, method):
    """numpy reads any nonzero byte of a bool array as True; the passes read
    them so too (cc3d labelled each byte value apart, and the NumPy census
    gave odd Euler characteristics), and take read-only arrays (cc3d wants
    a writable buffer): the answers are those of the canonical array,
    which the mesh's components check."""
    for _ in range(60):
        odd, v = odd_bools(rng, rng.integers(2, 8, 3), rng.uniform(0.2, 0.8))
        assert (odd.view(np.uint8) > 1).any() or not v.any()
        want = analyze(v, conn)
        frozen = v.copy()
        frozen.setflags(write=False)
        for x in (odd, frozen):
            assert counted(closed_surfaces(x, conn, method=method)) == mesh_answer(v, conn)
            assert analyze(x, conn, method=method) == want
            assert betti_numbers(x, conn, method=method) == want["betti"]
        assert (odd.view(np.uint8) > 1).any() or not v.any()  # the input is left as it was


@pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")
@pytest.mark.parametrize("conn", [6, 26])
def test_sweep_counts_a_box_of_vertices(rng, conn):
    # a block of a larger volume is swept at the vertices it counts: their
    # histogram (the configurations, zeros outside), their doubled edges
    # with both ends counted, and the loose ends of those with one end
    # counted (the doubled spokes of the mesh's tables at those vertices)
    from isoflow.digital.closed_surfaces import MESH_ADJACENCY
    from isoflow.digital.configurations import configurations
    from isoflow.scale import bitrows, kernels, sweep

    spokes = sweep_tables(conn)[4]
    seen_loose = 0
    for _ in range(12):
        v = rng.random(tuple(rng.integers(3, 9, 2)) + (int(rng.choice([5, 64, 70])),)) < rng.uniform(0.3, 0.7)
        lo = [int(rng.integers(0, 3)), int(rng.integers(0, 3)), int(rng.integers(0, 2))]
        hi = [int(rng.integers(n - 1, n + 2)) for n in v.shape[:2]] + [v.shape[2] + int(rng.integers(0, 2))]
        bits, off, goff = bitrows.pack(v)
        adj = kernels.ADJACENCY[MESH_ADJACENCY[conn][0]] + kernels.ADJACENCY[MESH_ADJACENCY[conn][1]]
        with compiled.using(int(rng.integers(1, 4))):
            found = sweep.sweep(bits, v.shape, off, goff, adj, sweep_tables(conn), pinch_objects=conn == 26,
                                counted=np.array([lo, hi]))
        cfg = configurations(v)
        box = tuple(slice(a, b) for a, b in zip(lo, hi))
        assert (found["hist"] == np.bincount(cfg[box].ravel(), minlength=256)).all()
        inside = np.zeros(cfg.shape, bool)
        inside[box] = True
        doubled, loose = 0, set()
        for w in zip(*np.nonzero(inside)):
            for d in range(6):
                axis, step = d >> 1, 2 * (d & 1) - 1
                u = list(w)
                u[axis] += step
                if not (spokes[cfg[w]] >> d) & 1 or not 0 <= u[axis] < cfg.shape[axis]:
                    continue
                if inside[tuple(u)]:
                    doubled += step > 0 and (spokes[cfg[tuple(u)]] >> (d ^ 1)) & 1
                else:
                    loose.add((*map(int, w), d))
        assert found["doubled"] == doubled
        assert {tuple(map(int, e)) for e in found["loose"]} == loose
        seen_loose += len(loose)
    assert seen_loose > 20


@pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")
@pytest.mark.parametrize("conn", [6, 26])
def test_numpy_and_compiled_reports_are_identical_and_the_betti_numbers_scipys(rng, conn):
    # the NumPy census (the object and the background labelled once each,
    # the connectivity's components joined at the pinches) and the compiled
    # sweep give the same report, every field, on volumes full of edge and
    # vertex contacts; b0 and b2 are scipy's labellings' counts (the
    # background padded: its outside component is not enclosed)
    from scipy import ndimage

    full, faces = ndimage.generate_binary_structure(3, 3), ndimage.generate_binary_structure(3, 1)
    obj_structure, bg_structure = (faces, full) if conn == 6 else (full, faces)
    seen = np.zeros(3, int)
    for _ in range(300):
        v = rng.random(rng.integers(1, 12, 3)) < rng.uniform(0.1, 0.9)
        numpy_report = analyze(v, conn, method="numpy")
        assert numpy_report.to_dict() == analyze(v, conn, method="compiled").to_dict()
        b0 = ndimage.label(v, obj_structure)[1]
        enclosed = ndimage.label(np.pad(~v, 1, constant_values=True), bg_structure)[1] - 1
        assert (numpy_report.betti[0], numpy_report.betti[2]) == (b0, enclosed)
        seen += [numpy_report.pinched_vertices > 0, numpy_report.doubled_edges > 0, len(numpy_report.surfaces) > 1]
    assert (seen > 30).all(), seen


@pytest.mark.parametrize("conn", [6, 26])
def test_the_numpy_census_labels_twice_and_a_thin_volume_needs_no_scipy(conn):
    # the object and the background are labelled once each (the
    # connectivity's own components are the mesh's joined at the pinches),
    # and a volume one voxel thick is labelled padded, by cc3d, so that the
    # census never imports scipy.ndimage (as docs/performance.md says of
    # every volume below the compiled pass's size)
    import subprocess
    import sys

    code = (
        "import sys, numpy as np\n"
        "from isoflow.scale import labels\n"
        "from isoflow.digital import closed_surfaces as cs\n"
        "calls = []\n"
        "real = labels.label\n"
        "labels.label = lambda *a, **k: calls.append(a[0].shape) or real(*a, **k)\n"
        "v = np.random.default_rng(1).random((1, 30, 30)) < 0.5\n"
        f"cs.small_census(v, {conn})\n"
        "print(len(calls), 'scipy.ndimage' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["2", "False"]


@pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")
def test_auto_takes_the_compiled_census_once_it_is_loaded_and_numpy_in_a_fresh_process():
    # "auto" weighs numba's start against a small volume: in a fresh
    # process it counts a small one by NumPy without importing numba; once
    # a compiled pass has run here (numba holds the sweep's machine code)
    # it takes the compiled census at any size, with the same report, and
    # "numpy" still takes NumPy
    import subprocess
    import sys

    code = (
        "import sys, numpy as np\n"
        "from isoflow import analyze\n"
        "from isoflow.digital import closed_surfaces as cs\n"
        "v = np.random.default_rng(3).random((20, 21, 19)) < 0.5\n"
        "first = [cs.use_census(v), 'numba' in sys.modules]\n"
        "want = analyze(v, 26)\n"
        "numba_after_auto = 'numba' in sys.modules\n"
        "analyze(np.ones((2, 2, 2), bool), method='compiled')\n"
        "after = [cs.use_census(v), cs.use_census(v, method='numpy'), analyze(v, 26) == want]\n"
        "print(*first, numba_after_auto, *after)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False", "False", "True", "False", "True"]
