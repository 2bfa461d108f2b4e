"""The lookup tables of section 4 against the paper's equations."""

import numpy as np
import pytest
from skimage.measure import euler_number

from isoflow.digital import configurations as C
from isoflow.digital import indices as I
from isoflow.digital import symmetry as S

# The paper's values per class, indexed by class = gamma + 4 (eq. 4.6):
# octant counts n(alpha) (eqs. 4.4-4.5), a (eq. 4.10), k (eq. 4.11) and the
# code whose f (eq. 4.8) the class carries.
PAPER_OCTANTS = {0: 4, 1: 5, 2: 6, 3: 7, 4: 4, 5: 1, 6: 2, 7: 3, 8: 4}
PAPER_A = (-2, -1, 0, 1, 0, 1, 0, -1, -2)
PAPER_K = (4, 1, 0, 1, 0, 1, 0, 1, 4)
PAPER_CODE = {
    0: "---", 1: "+--", 2: "-00", 3: "---", 4: "00∅", 5: "+++", 6: "+00", 7: "++-", 8: "+--",
}


def paper_f(code: str) -> int:
    s = [{"+": 1, "-": -1, "0": 0, "∅": 0}[c] for c in code]
    return sum(s) * sum(abs(v) for v in s)


def test_126_well_composed_boundary_configurations_in_nine_classes():
    cls = I.class_lut()
    boundary_wc = I.well_composed(3) & (cls != I.OFF_SURFACE)
    assert boundary_wc.sum() == 126
    assert (cls == I.NOT_WELL_COMPOSED).sum() == 128
    canon = S.configuration_orbits(3)
    assert len(set(canon[boundary_wc])) == 9
    # classes are unions of orbits and every class is exactly one orbit
    for k in range(9):
        assert len(set(canon[cls == k])) == 1


@pytest.mark.parametrize("conn", [6, 26])
def test_class_values_match_paper_table(conn):
    cls, gamma, a, f = I.class_lut(), I.gamma_lut(), I.a_lut(conn), I.f_lut()
    popcount = np.array([bin(c).count("1") for c in range(256)])
    for k in range(9):
        members = cls == k
        assert set(gamma[members]) == {k - 4}
        assert set(popcount[members]) == {PAPER_OCTANTS[k]}
        assert set(a[members]) == {PAPER_A[k]}
        assert set(a[members] ** 2) == {PAPER_K[k]}
        assert set(f[members]) == {paper_f(PAPER_CODE[k])}


def test_per_axis_codes_are_the_paper_codes_up_to_permutation():
    """Eq. 4.3: seven classes get the paper's code (in some axis order) from
    the per-axis rule; the two with a = -2 carry the paper's labels."""
    cls = I.class_lut()
    for k in range(9):
        for c in np.flatnonzero(cls == k):
            text = I.code_string(int(c))
            if k in (0, 8):
                assert text == I.CLASS_LABELS[k]
            else:
                assert sorted(text[1:-1].split(",")) == sorted(PAPER_CODE[k])


def test_f_takes_the_values_listed_after_definition_9():
    vals = set(I.f_lut()[I.class_lut() >= 0].tolist())
    assert vals == {0, 1, -1, 3, -3, 9, -9}


def test_tables_are_invariant_under_the_48_symmetries():
    sym = S.hyperoctahedral_group(3).configuration_permutations
    assert sym.shape == (48, 256)
    for lut in (I.class_lut(), I.gamma_lut(), I.a_lut(6), I.a_lut(26), I.f_lut(), I.well_composed(3)):
        assert (lut[sym] == lut[None, :]).all()


def test_symmetry_of_a_volume_permutes_its_configurations(rng):
    v = rng.random((4, 5, 6)) < 0.5
    hist = np.bincount(C.configurations(v).ravel(), minlength=256)
    sym = S.hyperoctahedral_group(3).configuration_permutations
    for g in range(48):
        moved = np.bincount(C.configurations(S.apply_symmetry(v, g)).ravel(), minlength=256)
        expected = np.zeros(256, np.int64)
        np.add.at(expected, sym[g], hist)
        assert (moved == expected).all()


def test_normal_points_to_the_background():
    """Definition 14: the normal of a well-composed boundary vertex has the
    signs of the summed outward normals of its boundary faces."""
    from isoflow.digital.surface import slot_octants

    normals = I.normal_lut()
    for c in np.flatnonzero(I.class_lut() >= 0):
        total = np.zeros(3)
        for slot in range(12):
            lo, hi = slot_octants(slot)
            inside_lo, inside_hi = (c >> lo) & 1, (c >> hi) & 1
            if inside_lo != inside_hi:
                total[slot // 4] += 1 if inside_lo else -1
        assert (np.sign(total) == normals[c]).all(), c
        assert set(np.abs(normals[c])) <= {0, 1}


def test_a_is_two_minus_abs_gamma_off_the_flat_class():
    """The vertex angle and the angle defect agree: a = 2 - |gamma| (eqs. 4.6,
    4.10), gamma in eighths, for every non-flat class."""
    cls, gamma, a = I.class_lut(), I.gamma_lut(), I.a_lut()
    curved = (cls >= 0) & (cls != 4)
    assert (a[curved] == 2 - np.abs(gamma[curved])).all()


# ---------------------------------------------------------------- plane


def test_planar_classes():
    pcls = I.planar_class_lut()
    assert (pcls == 0).sum() == 4  # one pixel of four: convex
    assert (pcls == 1).sum() == 4  # two adjacent: flat
    assert (pcls == 2).sum() == 4  # three: concave
    assert (pcls == I.NOT_WELL_COMPOSED).sum() == 2  # the two diagonals


def test_planar_index_eq_4_2_values():
    square = np.ones((3, 3), bool)  # the points of a 2x2 block of squares
    r4 = I.planar_index(square)
    assert r4[0, 0] == 1 and r4[2, 2] == 1  # corners: r = 1/4, convex
    assert r4[0, 1] == 0  # edge midpoint: flat
    assert r4[1, 1] == 0  # interior point
    ell = np.ones((3, 3), bool)
    ell[2, 2] = False
    ell4 = I.planar_index(ell)
    assert ell4[1, 1] == -1  # the re-entrant corner: r = -1/4, concave


def test_planar_index_on_lines_one_point_wide():
    """The values the docstring gives for thin sets, whose sum is 4 chi by
    scikit-image (connectivity 1: vertices, 4-adjacent edges, squares):
    a line's ends turn by a half turn each, a junction of 3 or 4 lines by
    -2 or -4, an isolated point by a whole turn."""
    from skimage.measure import euler_number

    plus = np.zeros((5, 5), bool)
    plus[2, :] = plus[:, 2] = True
    tee = plus.copy()
    tee[2, :2] = False
    dot = np.zeros((3, 3), bool)
    dot[1, 1] = True
    for points, middle, ends, turn in ((plus, (2, 2), 4, -4), (tee, (2, 2), 3, -2), (dot, (1, 1), 0, 4)):
        r4 = I.planar_index(points)
        assert r4[middle] == turn
        assert np.count_nonzero(r4 == 2) == ends and set(np.unique(r4[points])) <= {turn, 0, 2}
        assert r4.sum() == 4 * euler_number(points, 1) == 4


@pytest.mark.parametrize("table", [I.gamma_lut, I.class_lut, I.code_lut, I.normal_lut, I.f_lut])
def test_the_public_tables_cannot_be_written_into(table):
    # they are cached: a caller's class_lut()[:] = 0 made every later analyze of a box with a cavity
    # report n = (64, 0, ..., 0) instead of the paper's 8 convex and 8 concave corners, 24 + 24 edges
    with pytest.raises(ValueError, match="read-only"):
        table()[0] = 7
    box = np.ones((3, 3, 3), bool)
    box[1, 1, 1] = False
    from isoflow import analyze

    assert analyze(box).n == [0, 0, 0, 8, 24, 8, 24, 0, 0]


def test_planar_index_refuses_what_is_no_2d_set_of_points():
    # a 3x3x3 cube gave a 3x3x5 array, a row of points NumPy's IndexError, and 0.5 or NaN counted as
    # points (a 3x3 square of them: 4 convex corners, sum 4 chi = 4) where every other mask refuses them
    from isoflow.errors import IsoflowError

    with pytest.raises(IsoflowError, match="points: planar_index takes a 2D array, got a 3D array"):
        I.planar_index(np.ones((3, 3, 3), bool))
    with pytest.raises(IsoflowError, match="points: planar_index takes a 2D array, got a 1D array"):
        I.planar_index(np.ones(3, bool))
    for value in (0.5, np.nan):
        with pytest.raises(IsoflowError, match=f"points: not a binary image .* e.g. {value}"):
            I.planar_index(np.full((3, 3), value))


def test_planar_index_of_a_label_image_offers_its_own_remedy():
    """A label image given to planar_index was told to use
    isoflow.label_table, which has no planar index. The remedy it now
    offers, one label's points, runs and sums to 4 chi (scikit-image's
    Euler number at 4-connectivity)."""
    import re

    from isoflow.errors import IsoflowError

    image = np.zeros((7, 8), np.uint8)
    image[1:6, 1:4] = 1
    image[1:6, 5:8] = 2
    image[3, 6] = 0  # a hole in label 2: chi 0
    with pytest.raises(IsoflowError) as info:
        I.planar_index(image)
    message = str(info.value)
    assert "label_table" not in message
    remedy = re.search(r"planar_index\(image == (\d+)\)", message)
    assert remedy is not None, message
    label = int(remedy[1])
    assert int(I.planar_index(image == label).sum()) == 4 * euler_number(image == label, connectivity=1)
    assert euler_number(image == 2, connectivity=1) == 0


@pytest.mark.parametrize("points", [[1, 2, 3], np.arange(8).reshape(2, 2, 2), [[[0.5]]], 7])
def test_planar_index_says_the_shape_before_the_values(points):
    """``planar_index([1, 2, 3])`` said "not a binary volume (2 voxels ...)":
    a list that is not 2D is refused for its dimension, which no values
    mend, whatever it holds."""
    from isoflow.errors import IsoflowError

    with pytest.raises(IsoflowError) as info:
        I.planar_index(points)
    message = str(info.value)
    assert f"takes a 2D array, got a {np.ndim(points)}D array of shape {np.shape(points)}" in message
    assert "binary" not in message
    square = I.planar_index(np.ones((3, 3), np.float32))  # 0/1 of any type is a set of points
    assert square.shape == (3, 3) and int(square.sum()) == 4


def test_planar_index_sums_to_four_chi(rng):
    for _ in range(200):
        pts = rng.random(rng.integers(1, 12, 2)) < rng.uniform(0.2, 0.9)
        assert I.planar_index(pts).sum() == 4 * euler_number(pts, connectivity=1)


def test_euler_lut_defaults_to_the_face_connectivity_of_its_dimension():
    # each dimension's own default connectivity (2n), not the 3D one
    import isoflow

    for n, face in ((1, 2), (2, 4), (3, 6), (4, 8)):
        assert np.array_equal(isoflow.euler_lut(n), isoflow.euler_lut(n, face))
    ring = np.ones((3, 3), bool)
    ring[1, 1] = False  # a ring of 8 pixels: chi 0 under 4-connectivity, as scikit-image counts
    chi = int(isoflow.configuration_histogram(ring) @ isoflow.euler_lut(2)) // 4
    assert chi == euler_number(np.pad(ring, 1), connectivity=1) == 0
    assert np.array_equal(isoflow.a_lut(None), isoflow.a_lut(6))
