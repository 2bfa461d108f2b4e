"""``method="auto"`` over many small volumes in one process: the ski-rental
rule of :mod:`isoflow.scale.compiled`. Each loop runs in a fresh process,
as a user's script would, so that nothing else has loaded numba there."""

from pathlib import Path

import numpy as np
import pytest

from isoflow.scale import compiled

needs_numba = pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")

#: a loop over small random volumes under "auto", in a fresh process
#: (:func:`volume`), and after each call the Euler characteristic, the
#: Betti numbers' alternating sum (the surfaces' own for closed_surfaces),
#: whether the compiled census is loaded and whether numba is imported
LOOP = """
import json, sys
sys.path.insert(0, sys.argv[3])
from test_auto_tally import volume  # (which imports no numba)
from isoflow import analyze, closed_surfaces
from isoflow.digital.closed_surfaces import census_loaded

ndim, count = int(sys.argv[1]), int(sys.argv[2])
rows = []
for i in range(count):
    v = volume(i, ndim)
    conn = (6, 26)[i % 2] if ndim == 3 else (4, 8)[i % 2]
    if ndim == 3 and i % 3 == 2:
        c = closed_surfaces(v, conn)
        chi = betti_chi = sum(s["euler_characteristic"] for s in c.surfaces) // 2 - c.pinched_vertices
    else:
        r = analyze(v, conn)
        chi, betti_chi = r["euler_characteristic"], sum((-1) ** k * b for k, b in enumerate(r["betti"]))
    rows.append([int(v.size), conn, int(chi), int(betti_chi), census_loaded(), "numba" in sys.modules])
print(json.dumps(rows))
"""


def _run(script: str, *args) -> list:
    """What ``script`` prints as JSON, run in a fresh process with ``args``
    and this file's folder (for its inputs)."""
    from fresh_process import run_json  # (here: the script imports this file, beside none of tests/)

    return run_json(script, *args, folder=Path(__file__).parent)


def volume(seed: int, ndim: int) -> np.ndarray:
    """A small random volume (random fields have many edge and vertex contacts)."""
    rng = np.random.default_rng(seed)
    shape = rng.integers(*((30, 61) if ndim == 3 else (200, 401)), ndim)
    return rng.random(shape) < rng.uniform(0.3, 0.7)


def label_image(seed: int) -> np.ndarray:
    """Five 10^3 blocks of labels 1-5 in a 40^3 image, each with holes and random contacts."""
    rng = np.random.default_rng(seed)
    image = np.zeros((40, 40, 40), np.uint8)
    for label in range(1, 6):
        x, y, z = rng.integers(0, 30, 3)
        image[x:x + 10, y:y + 10, z:z + 10] = np.where(rng.random((10, 10, 10)) < 0.7, label, 0)
    return image


def _crossing(sizes: list[int], least: int) -> int:
    """The first volume whose voxels and those before it reach ``least``."""
    return int(np.searchsorted(np.cumsum(sizes), least))


@needs_numba
def test_auto_loads_the_compiled_census_once_small_volumes_add_up_to_the_threshold():
    # analyze and closed_surfaces (with the surfaces: one threshold) on
    # small volumes, at 6 and 26: every Euler characteristic is
    # scikit-image's (connectivity 1 for 6, 3 for 26), the split mesh's
    # surfaces give 2 chi + 2 pinched vertices, and the compiled census is
    # loaded (numba imported) from the volume that takes the voxels past
    # least_voxels(surfaces=True) on, not before
    from skimage.measure import euler_number

    count = 60
    rows = _run(LOOP, 3, count)
    sizes = [row[0] for row in rows]
    at = _crossing(sizes, compiled.least_voxels(surfaces=True))
    assert 0 < at < count - 5  # (the volumes are small, and enough of them)
    for i, (size, conn, chi, betti_chi, loaded, numba) in enumerate(rows):
        v = volume(i, 3)
        assert size == v.size
        assert chi == betti_chi == euler_number(v, connectivity={6: 1, 26: 3}[conn]), (i, conn)
        assert loaded == (i >= at) and numba == (i >= at), (i, at)


@needs_numba
def test_auto_takes_the_compiled_betti_numbers_once_small_images_add_up_to_the_threshold():
    # 2D images: the compiled pass is the union-find of the Betti numbers,
    # whose threshold is least_voxels() (no surfaces); chi from b0 - b1 is
    # scikit-image's (connectivity 1 for 4, 2 for 8) before and after
    from skimage.measure import euler_number

    count = 40
    rows = _run(LOOP, 2, count)
    at = _crossing([row[0] for row in rows], compiled.least_voxels())
    assert 0 < at < count - 5
    for i, (_, conn, chi, betti_chi, _, numba) in enumerate(rows):
        assert chi == betti_chi == euler_number(volume(i, 2), connectivity={4: 1, 8: 2}[conn]), (i, conn)
        assert numba == (i >= at), (i, at)


def test_the_tally_counts_a_pass_once_and_a_question_never():
    # the rule's arithmetic, here where the conftest starts every test on a
    # fresh tally: below the threshold a question leaves it as it is; each
    # pass adds its voxels, and the one that reaches the threshold takes the
    # compiled path and keeps the tally past it
    from isoflow.scale.compiled import least_voxels, reset_tally, tallied, weigh

    least = least_voxels()
    assert tallied(False) == 0 and not weigh(least // 2) and tallied(False) == 0
    assert not weigh(least // 2, record=True) and tallied(False) == least // 2
    assert tallied(True) == 0  # the threshold with the surfaces keeps its own
    assert weigh(least - least // 2, record=True) and weigh(1) and tallied(False) >= least
    reset_tally()
    assert tallied(False) == 0 and not weigh(1)


LABEL_LOOP = """
import json, sys
sys.path.insert(0, sys.argv[2])
from test_auto_tally import label_image
from isoflow import label_table

rows = []
for i in range(int(sys.argv[1])):
    t = label_table(label_image(i), 6)
    rows.append([t["label"].tolist(), t["euler_characteristic"].tolist(), "numba" in sys.modules])
print(json.dumps(rows))
"""


@needs_numba
def test_label_tables_of_many_small_images_start_numba_once_their_numpy_work_adds_up():
    # each image alone is far below label_table's NumPy work threshold
    # (five labels: 65,000 plus their boxes, at most 5 * 12^3 voxels), a
    # hundred of them far above it (NUMBA_START_WORK = 6 million): the
    # first image never imports numba, the last one has; every label's chi
    # is scikit-image's for its mask
    from skimage.measure import euler_number

    from isoflow.digital.label_table import LABEL_WORK, NUMBA_START_WORK

    count = 100
    assert 5 * (LABEL_WORK + 12**3) < NUMBA_START_WORK < count * 5 * LABEL_WORK
    rows = _run(LABEL_LOOP, count)
    assert not rows[0][2] and rows[-1][2]
    for i, (labels, chis, _) in enumerate(rows):
        image = label_image(i)
        for label, chi in zip(labels, chis):
            assert chi == euler_number(image == label, connectivity=1), (i, label)
