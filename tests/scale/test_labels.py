"""isoflow.scale.labels: cc3d's labels for 2D and 3D, scipy's elsewhere,
and the same partition as scipy.ndimage.label in every case."""

import subprocess
import sys

import numpy as np
import pytest
from scipy.ndimage import generate_binary_structure
from scipy.ndimage import label as scipy_label

from isoflow.scale.labels import label, rank, structure

#: every adjacency of each dimension, with scipy's rank for it
ADJACENCIES = [(2, 4, 1), (2, 8, 2), (3, 6, 1), (3, 18, 2), (3, 26, 3), (4, 8, 1), (4, 80, 4)]


@pytest.mark.parametrize("ndim,conn,scipy_rank", ADJACENCIES)
def test_structure_is_scipys(ndim, conn, scipy_rank):
    assert rank(ndim, conn) == scipy_rank
    assert (structure(ndim, conn) == generate_binary_structure(ndim, scipy_rank)).all()


def _same_partition(a, b, mask):
    """The labels a and b split mask's voxels the same way (0 elsewhere)."""
    assert ((a > 0) == mask).all() and ((b > 0) == mask).all()
    pairs = np.unique(np.stack([a[mask].astype(np.int64), b[mask].astype(np.int64)]), axis=1)
    # one b label per a label and one a label per b label
    assert len(np.unique(pairs[0])) == len(np.unique(pairs[1])) == pairs.shape[1]


def _volumes(ndim, rng):
    """Random volumes with face, edge and vertex contacts (sparse noise
    gives many diagonal-only neighbours), thin ones (one voxel thick, where
    scipy labels), and the empty and full ones."""
    sides = {2: [(9, 11), (1, 17), (2, 2), (2, 15), (15, 2)],
             3: [(7, 8, 9), (1, 9, 9), (9, 1, 2), (1, 1, 7), (2, 2, 2), (2, 9, 2), (2, 2, 13), (13, 2, 2)],
             4: [(5, 4, 6, 3)]}[ndim]
    for shape in sides:
        for p in (0.0, 0.2, 0.35, 0.5, 0.8, 1.0):
            for _ in range(3):
                yield rng.random(shape) < p


@pytest.mark.parametrize("ndim,conn,scipy_rank", ADJACENCIES)
def test_labels_split_the_voxels_as_scipy_does(ndim, conn, scipy_rank):
    rng = np.random.default_rng(ndim * 100 + conn)
    for vol in _volumes(ndim, rng):
        mine, n = label(vol, conn)
        theirs, m = scipy_label(vol, generate_binary_structure(ndim, scipy_rank))
        assert n == m == len(np.unique(mine[vol]))
        assert mine.dtype == np.int32
        _same_partition(mine, theirs, vol)
        small, k = label(vol, conn, smallest=True)
        assert k == n
        _same_partition(small, theirs, vol)
        # bytes other than 1 (a .view(bool) of integers) and a read-only
        # array (cc3d wants a writable buffer) split the same way
        odd = np.where(vol, rng.choice(np.array([1, 2, 64, 255], np.uint8), vol.shape), 0).astype(np.uint8)
        frozen = odd.view(bool)
        frozen.setflags(write=False)
        again, k = label(frozen, conn)
        assert k == n
        _same_partition(again, theirs, vol)


def test_a_small_info_command_never_imports_scipy_ndimage(tmp_path):
    """scipy.ndimage's import (0.3-0.4 s) was half of what `isoflow info`
    waited for on a small volume; 2D and 3D volumes are labelled by cc3d."""
    vol = np.zeros((20, 21, 22), bool)
    vol[3:15, 3:15, 3:15] = True
    vol[6:12, 6:12, :] = False  # a tube: a torus
    vol[17, 17, 17] = vol[18, 18, 18] = True  # touching at a vertex only
    np.save(tmp_path / "v.npy", vol)
    code = ("import sys, json; from isoflow.cli import main; main(['info', sys.argv[1], '--json']); "
            "print(json.dumps(sorted(m for m in sys.modules if m.startswith('scipy.ndimage'))))")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "v.npy")], capture_output=True, text=True,
                         check=True).stdout.strip().splitlines()
    import json

    report = json.loads("\n".join(out[:-1]))
    assert json.loads(out[-1]) == []
    # scipy's count of the same components (6: the tube and two voxels)
    assert report["betti"][0] == scipy_label(vol)[1] == 3


@pytest.mark.parametrize("compiled", [False, True])
def test_every_memory_layout_gives_the_same_report(compiled):
    """A Fortran-ordered, a strided and a reversed view of a volume give the
    C-ordered volume's report, surfaces included (cc3d keeps a Fortran
    mask's order in its labels, which the sheets' flat indexing must not
    mistake for C order), on the small path and on the compiled one."""
    from skimage.measure import euler_number

    from isoflow.digital.analysis import analyze

    method = "compiled" if compiled else "numpy"
    rng = np.random.default_rng(5)
    vol = rng.random((14, 15, 16)) < 0.4  # face, edge and vertex contacts
    wide = np.zeros((14, 15, 32), bool)
    wide[:, :, ::2] = vol
    views = {"fortran": np.asfortranarray(vol), "strided": wide[:, :, ::2], "reversed": vol[::-1, :, ::-1].copy()[::-1, :, ::-1]}
    for conn, sk in ((6, 1), (26, 3)):
        want = analyze(vol, conn)
        assert want["euler_characteristic"] == euler_number(vol, sk)
        for name, view in views.items():
            got = analyze(view, conn, method=method)
            assert got == want, (name, conn)
