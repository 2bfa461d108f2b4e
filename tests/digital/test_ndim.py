"""Tests of isoflow.ndim: nD configurations, Euler tables, classes, codes.

Every table of the module is derived from the geometry of the window; these
tests check it against things computed by a different route: scikit-image's
Euler number (2D/3D), Betti numbers from scipy.ndimage.label and from global
GF(2) homology, products, symmetries applied to whole images, and Burnside's
lemma with signed permutation matrices for the 4D class counts.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage.measure import euler_number

from isoflow.digital import configurations as C
from isoflow.digital import homology as hom
from isoflow.digital import indices as I
from isoflow.digital import ndim as nd
from isoflow.digital import symmetry as S
from isoflow.digital.topology import euler_characteristic
from isoflow.errors import IsoflowError

#: the object's two adjacencies: faces (2n) and everything (3^n - 1)
ADJ = ("face", "full")


def conn(n: int, adjacency: str) -> int:
    """The connectivity isoflow takes for the adjacency in n dimensions."""
    return 2 * n if adjacency == "face" else 3**n - 1


def euler(x: np.ndarray, adjacency: str) -> int:
    return euler_characteristic(x, conn(x.ndim, adjacency))


def euler_table(n: int, adjacency: str) -> np.ndarray:
    return I.euler_lut(n, conn(n, adjacency))


def structure(n: int, adjacency: str) -> np.ndarray:
    """scipy structuring element of the object's adjacency."""
    return ndi.generate_binary_structure(n, 1 if adjacency == "face" else n)


def other(adjacency: str) -> str:
    return "full" if adjacency == "face" else "face"


def random_image(rng, n, lo=1, hi=6):
    shape = tuple(int(s) for s in rng.integers(lo, hi + 1, size=n))
    return rng.random(shape) < rng.uniform(0.05, 0.95)


def config_image(c: int, n: int) -> np.ndarray:
    """The 2^n window of configuration c as a 2x..x2 image."""
    x = np.zeros((2,) * n, dtype=bool)
    for b, d in enumerate(C.octants(n)):
        if c >> b & 1:
            x[tuple(d)] = True
    return x


# --------------------------------------------------------------------------
# 1. the group


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_group_order_and_permutations(n):
    g = S.hyperoctahedral_group(n)
    assert len(g) == 2**n * math.factorial(n)
    nb = 2**n
    assert np.array_equal(np.sort(g.bit_permutations, axis=1), np.tile(np.arange(nb), (len(g), 1)))
    assert np.array_equal(g.bit_permutations[0], np.arange(nb))  # identity first
    # face adjacency of the window cells (one differing bit) is preserved
    for a in range(nb):
        for i in range(n):
            b = a ^ (1 << i)
            diff = g.bit_permutations[:, a] ^ g.bit_permutations[:, b]
            assert np.all((diff & (diff - 1)) == 0) and np.all(diff != 0)
    # the induced action on configurations is a permutation for every element
    cp = g.configuration_permutations
    assert cp.shape == (len(g), 1 << nb)
    srt = np.sort(cp, axis=1)
    assert np.array_equal(srt, np.broadcast_to(np.arange(1 << nb), srt.shape))


def test_group_closed_under_composition():
    g = S.hyperoctahedral_group(3)
    rows = {tuple(r) for r in g.bit_permutations}
    for p in g.bit_permutations:
        for q in g.bit_permutations:
            assert tuple(q[p]) in rows


def test_symmetries_act_on_images_like_on_configurations():
    """configurations(apply_symmetry(X, g)) == permuted configurations of X, all 384."""
    rng = np.random.default_rng(11)
    x = rng.random((4, 3, 5, 2)) < 0.5
    g = S.hyperoctahedral_group(4)
    conf = C.configurations(x)
    chi = {a: euler(x, a) for a in ADJ}
    for k in range(len(g)):
        y = S.apply_symmetry(x, k)
        h_image = np.bincount(C.configurations(y).ravel(), minlength=1 << 16)
        h_perm = np.bincount(g.configuration_permutations[k][conf].ravel(), minlength=1 << 16)
        assert np.array_equal(h_image, h_perm)
        for a in ADJ:
            assert euler(y, a) == chi[a]


# --------------------------------------------------------------------------
# 2. the Euler tables


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_euler_lut_basic_values_and_invariance(n):
    full = (1 << (1 << n)) - 1
    c = np.arange(full + 1)
    g = S.hyperoctahedral_group(n)
    for a in ADJ:
        lut = euler_table(n, a)
        assert lut.dtype == np.int64
        assert lut[0] == 0 and lut[full] == 0  # off the surface: no curvature
        for b in range(1 << n):
            assert lut[1 << b] == 1  # one cell: each of its 2^n corners carries 1
        for k in range(len(g)):  # a share of chi cannot depend on the pose
            assert np.array_equal(lut[g.configuration_permutations[k]], lut)
    # local duality: lut_max[c] = (-1)^(n+1) lut_min[complement of c]
    assert np.array_equal(euler_table(n, "full"), (-1) ** (n + 1) * euler_table(n, "face")[full ^ c])


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_shares_agree_where_boundary_is_a_manifold(n):
    m = nd.manifold_configurations(n)
    assert np.array_equal(euler_table(n, "face")[m], euler_table(n, "full")[m])


def test_lut_3d_classes_match_design_table():
    """a (eq. 4.10) of the nine 3D classes, by octant count (docs/mathematics.md)."""
    lut = euler_table(3, "face")
    got = sorted((bin(int(r)).count("1"), int(lut[r])) for r in nd.boundary_classes(3))
    assert got == [(1, 1), (2, 0), (3, -1), (4, -2), (4, -2), (4, 0), (5, -1), (6, 0), (7, 1)]


# --------------------------------------------------------------------------
# 3. configurations and chi


def test_configurations_shape_dtype_and_bits():
    x = np.zeros((2, 3), dtype=bool)
    x[1, 2] = True
    c = C.configurations(x)
    assert c.shape == (3, 4) and c.dtype == np.uint8
    # vertex w sees cell w - 1 + d in bit d0 + 2 d1: cell (1,2) is d=(1,1) of
    # vertex (1,2), d=(0,1) of (2,2), d=(1,0) of (1,3), d=(0,0) of (2,3)
    assert c[1, 2] == 8 and c[2, 2] == 4 and c[1, 3] == 2 and c[2, 3] == 1
    assert c.sum() == 15
    block = C.configurations(np.ones((2, 2, 2, 2), dtype=bool))
    assert block.dtype == np.uint16 and block[1, 1, 1, 1] == 0xFFFF
    one = C.configurations(np.ones((1, 1, 1, 1), dtype=bool))
    assert one[1, 1, 1, 1] == 1 and one[0, 0, 0, 0] == 1 << 15  # cell d=0, d=(1,1,1,1)
    assert sorted(one.ravel()) == [1 << b for b in range(16)]


def test_chi_matches_skimage_2d_3d():
    rng = np.random.default_rng(0)
    for _ in range(300):
        n = int(rng.choice([2, 3]))
        x = random_image(rng, n, 1, 7)
        assert euler(x, "face") == euler_number(x, connectivity=1)
        assert euler(x, "full") == euler_number(x, connectivity=n)


def test_chi_1d_counts_runs():
    rng = np.random.default_rng(1)
    for _ in range(50):
        x = rng.random(int(rng.integers(1, 20))) < 0.5
        runs = int(np.count_nonzero(np.diff(np.concatenate([[0], x.astype(int)])) == 1))
        for a in ADJ:
            assert euler(x, a) == runs


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_gauss_bonnet_sum_is_2n_chi(n):
    rng = np.random.default_rng(2 + n)
    for _ in range(10):
        x = random_image(rng, n, 1, 4 if n == 4 else 6)
        for a in ADJ:
            chi = euler(x, a)
            assert nd.vertex_curvature(x, conn(x.ndim, a)).sum() == 2**n * chi == nd.gauss_bonnet_sum(x, conn(x.ndim, a))


def test_chi_4d_known_shapes():
    disc = np.ones((3, 3), dtype=bool)
    annulus = disc.copy()
    annulus[1, 1] = False
    for a in ADJ:
        assert euler(hom.product_image(annulus, disc), a) == 0
        assert euler(hom.product_image(annulus, annulus), a) == 0
        assert euler(hom.ball(3.2, 4), a) == 1
        assert euler(hom.box_minus_box(5, 1, 4), a) == 0  # 1 - b3
        assert euler(hom.box_minus_box(6, 2, 4), a) == 0
        assert euler(hom.box_minus_box(5, 3, 4), a) == 0


def test_chi_multiplicative_on_products():
    rng = np.random.default_rng(4)
    for _ in range(25):
        a2, b2 = random_image(rng, 2, 1, 5), random_image(rng, 2, 1, 5)
        a1, b3 = random_image(rng, 1, 1, 5), random_image(rng, 3, 1, 4)
        for adj in ADJ:
            chi = lambda x, adj=adj: euler(x, adj)
            assert chi(hom.product_image(a2, b2)) == chi(a2) * chi(b2)
            assert chi(hom.product_image(a1, b3)) == chi(a1) * chi(b3)


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_complement_duality_in_padded_box(n):
    """chi_max(B minus X) = 1 + (-1)^(n+1) chi_min(X), and min/max swapped.

    B is the box of the padded array (X has one background layer on every
    side); this is Alexander duality, derived in docs/ndim.md from
    lut_max[c] = (-1)^(n+1) lut_min[~c].
    """
    rng = np.random.default_rng(40 + n)
    for _ in range(15):
        x = random_image(rng, n, 1, 4 if n == 4 else 6)
        comp = ~np.pad(x, 1)
        sign = (-1) ** (n + 1)
        for a in ADJ:
            assert euler(comp, other(a)) == 1 + sign * euler(x, a)
    if n == 3:  # the 3D statement: chi_6(X) = chi_26(B minus X) - 1
        x = hom.box_minus_box(5, 1, 3)
        assert euler(x, "face") == euler(~np.pad(x, 1), "full") - 1


def _b0(x, adjacency):
    return ndi.label(x, structure(x.ndim, adjacency))[1]


def _b_top(x, adjacency):
    """b_(n-1): background components (complementary adjacency) off the border."""
    lab, k = ndi.label(~np.pad(x, 1), structure(x.ndim, other(adjacency)))
    border = set()
    for ax in range(x.ndim):
        border |= set(np.unique(np.take(lab, 0, axis=ax))) | set(np.unique(np.take(lab, -1, axis=ax)))
    return k - len(border - {0})


def test_chi_4d_random_against_betti_numbers():
    """chi = b0 - b1 + b2 - b3 with b0, b3 from scipy and b0..b3 from homology."""
    rng = np.random.default_rng(5)
    for _ in range(12):
        x = random_image(rng, 4, 1, 3)
        for a in ADJ:
            b = hom.gf2_betti_numbers(x, conn(x.ndim, a))
            assert b[4] == 0
            assert b[0] == _b0(x, a)
            assert b[3] == _b_top(x, a)
            assert euler(x, a) == b[0] - b[1] + b[2] - b[3]


def test_betti_numbers_2d_3d_against_scipy():
    rng = np.random.default_rng(6)
    for _ in range(30):
        n = int(rng.choice([2, 3]))
        x = random_image(rng, n, 1, 5)
        for a in ADJ:
            b = hom.gf2_betti_numbers(x, conn(x.ndim, a))
            assert b[0] == _b0(x, a) and b[n - 1] == _b_top(x, a) and b[n] == 0
            assert sum((-1) ** i * v for i, v in enumerate(b)) == euler(x, a)


# --------------------------------------------------------------------------
# 4. classes


def test_class_counts_2d_3d():
    c2, c3 = nd.class_counts(2), nd.class_counts(3)
    assert c2["orbits"] == 6 and c2["well_composed_classes"] == 3
    assert c2["well_composed_configurations"] == 12
    assert c3["orbits"] == 22
    assert c3["well_composed_classes"] == 9  # the paper's nine classes
    assert c3["well_composed_configurations"] == 126
    for c in (c2, c3):  # in 2D and 3D the three notions coincide
        assert c["well_composed_classes"] == c["digitally_well_composed_classes"] == c["manifold_classes"]
    assert nd.class_counts(1)["orbits"] == 3


def _signed_permutation_matrices(n):
    """All n x n matrices with one +-1 per row and column, found by search."""
    mats = []
    for rows in itertools.product(range(2 * n), repeat=n):
        cols = [r % n for r in rows]
        if len(set(cols)) < n:
            continue
        m = np.zeros((n, n), dtype=int)
        for i, r in enumerate(rows):
            m[i, r % n] = 1 if r < n else -1
        mats.append(m)
    return mats


def _independent_well_composed_4d():
    """Face-connectedness of object and background by scipy.ndimage.label."""
    s = ndi.generate_binary_structure(4, 1)
    ok = np.zeros(1 << 16, dtype=bool)
    for c in range(1, (1 << 16) - 1):
        x = config_image(c, 4)
        ok[c] = ndi.label(x, s)[1] == 1 and ndi.label(~x, s)[1] == 1
    return ok


def test_4d_class_counts_by_burnside_and_matrices():
    n = 4
    mats = _signed_permutation_matrices(n)
    assert len(mats) == 384
    cells = 2 * C.octants(n).astype(int) - 1  # centred cell coordinates, +-1
    lookup = {tuple(v): b for b, v in enumerate(cells)}
    bitperms = np.array([[lookup[tuple(m @ v)] for v in cells] for m in mats])
    # Burnside: orbits = mean number of configurations fixed (constant on cycles)
    wc = _independent_well_composed_4d()
    assert np.array_equal(wc, I.well_composed(4))
    fixed_all = fixed_wc = 0
    for perm in bitperms:
        seen, cycles = set(), []
        for b in range(16):
            if b not in seen:
                cyc, j = 0, b
                while j not in seen:
                    seen.add(j)
                    cyc |= 1 << j
                    j = perm[j]
                cycles.append(cyc)
        k = len(cycles)
        subsets = (np.arange(1 << k)[:, None] >> np.arange(k)) & 1
        fixed = subsets @ np.array(cycles)
        fixed_all += 1 << k
        fixed_wc += int(wc[fixed].sum())
    counts = nd.class_counts(4)
    assert fixed_all % 384 == 0 and fixed_wc % 384 == 0
    assert counts["orbits"] == fixed_all // 384 == 402
    assert counts["well_composed_classes"] == fixed_wc // 384 == 107
    assert counts["well_composed_configurations"] == 20112
    # canonical forms by the matrix route agree with the module's orbits
    conf = np.arange(1 << 16)
    canon = np.full(conf.shape, 1 << 16)
    for perm in bitperms:
        img = np.zeros_like(conf)
        for b in range(16):
            img |= ((conf >> b) & 1) << perm[b]
        canon = np.minimum(canon, img)
    assert np.array_equal(canon, S.configuration_orbits(4))


def test_4d_manifold_and_digitally_well_composed_classes():
    counts = nd.class_counts(4)
    assert counts["digitally_well_composed_classes"] == 46
    assert counts["manifold_classes"] == 45
    assert counts["manifold_configurations"] == 5528
    dwc, man = nd.digitally_well_composed(4), nd.manifold_configurations(4)
    canon = S.configuration_orbits(4)
    assert np.all(I.well_composed(4)[dwc]) and np.all(dwc[man])
    # the one digitally well-composed class that is not a manifold point: two
    # linked 8-cycles of the 4-cube graph; the boundary is a cone on a torus
    (hopf,) = np.unique(canon[dwc & ~man])
    assert bin(int(hopf)).count("1") == 8
    links = nd.link_betti_numbers(int(hopf), 4)
    assert links["boundary"] == (0, 2, 1, 0)  # reduced Betti numbers of a torus
    assert links["object"] == links["background"] == (0, 1, 0, 0)  # solid tori
    assert euler_table(4, "face")[hopf] == -8 and euler_table(4, "full")[hopf] == 8
    # on every manifold class the two object/background link pieces are balls
    for r in np.unique(canon[man]):
        links = nd.link_betti_numbers(int(r), 4)
        assert links["object"] == links["background"] == (0, 0, 0, 0)


# --------------------------------------------------------------------------
# 5. curvature codes


def _codes_by_count(n, rule):
    out = {}
    for r in nd.boundary_classes(n):
        out.setdefault(bin(int(r)).count("1"), []).append(
            "".join(sorted(nd.format_codes(nd.curvature_code(r, n, rule))[1:-1].split(",")))
        )
    return {k: sorted(v) for k, v in out.items()}


def test_codes_3d_reproduce_paper_for_seven_classes():
    lut = euler_table(3, "face")
    got = {}
    for r in nd.boundary_classes(3):
        codes = nd.curvature_code(r, 3, "paper")
        key = (bin(int(r)).count("1"), int(lut[r]))
        got.setdefault(key, []).append(
            ("".join(sorted(nd.format_codes(codes)[1:-1].split(","))), float(nd.index_48(codes)))
        )
    # sorted code characters: '+' < '-' < '0' < '∅'
    assert got[(1, 1)] == [("+++", 9.0)]  # (+,+,+) convex corner
    assert got[(2, 0)] == [("+00", 1.0)]  # (+,0,0) convex edge
    assert got[(3, -1)] == [("++-", 3.0)]  # (+,+,-)
    assert got[(4, 0)] == [("00∅", 0.0)]  # (0,0,∅) flat
    assert got[(5, -1)] == [("+--", -3.0)]  # (+,-,-)
    assert got[(6, 0)] == [("-00", -1.0)]  # (-,0,0) concave edge
    assert got[(7, 1)] == [("---", -9.0)]  # (-,-,-) concave corner
    # the two a = -2 classes: the per-axis rule gives (-,-,-) and (-,0,-);
    # the paper labels them (+,-,-)+ and (-,-,-)- (docs/mathematics.md)
    assert sorted(got[(4, -2)]) == [("---", -9.0), ("--0", -4.0)]


def test_codes_2d_planar():
    lut = euler_table(2, "face")
    for c in range(16):
        codes = nd.curvature_code(c, 2)
        k = bin(c).count("1")
        if c in (0, 15):
            assert np.all(codes == I.NONE)
        elif not I.well_composed(2)[c]:
            assert np.all(codes == I.UNDEFINED)
        elif k == 1:
            assert list(codes) == [1, 1]
        elif k == 3:
            assert list(codes) == [-1, -1]
        else:
            assert sorted(codes) == [I.FLAT, I.NONE]
        if I.well_composed(2)[c]:  # eq. 6.1 in 2D is twice the Euler share
            assert nd.curvature_index(c, 2) == 2 * lut[c]


@pytest.mark.parametrize("n", [2, 3, 4])
def test_codes_equivariant_and_symmetric_rule_antisymmetric(n):
    g = S.hyperoctahedral_group(n)
    full = (1 << (1 << n)) - 1
    conf = np.arange(full + 1)
    for rule in nd.CODE_RULES:
        table = nd.curvature_code(conf, n, rule)
        for k in range(len(g)):  # output axis j of the image is input axis p_j
            assert np.array_equal(table[g.configuration_permutations[k]], table[:, g.axis_permutations[k]])
    sym = nd.curvature_code(conf, n, "symmetric")
    flipped = np.where(np.abs(sym) <= 1, -sym, sym)
    assert np.array_equal(sym[full ^ conf], flipped)  # convex <-> concave
    m = nd.manifold_configurations(n)
    assert not np.any(sym[m] == I.UNDEFINED)
    assert np.all(sym[~m & (conf != 0) & (conf != full)] == I.UNDEFINED)
    f = nd.curvature_index(conf, n, "6.1", "symmetric")
    assert np.array_equal(f[full ^ conf][m], -f[m])


def test_codes_4d_box_corners():
    # a 4D box: corner (1 cell), edge (2), 2-face (4), 3-face (8)
    assert list(nd.curvature_code(1, 4)) == [1, 1, 1, 1]
    assert sorted(nd.curvature_code(3, 4)) == [0, 0, 0, 1]
    assert list(nd.curvature_code(15, 4)) == [0, 0, 0, 0]
    assert list(nd.curvature_code(255, 4)) == [0, 0, 0, I.NONE]
    assert nd.curvature_index(1, 4, "6.1") == 4 and nd.curvature_index(1, 4, "4.8") == 16
    assert nd.curvature_index(0xFFFF ^ 1, 4, "6.1") == -4
    assert np.isnan(nd.curvature_index(1 | 1 << 15, 4))  # two antipodal cells


# --------------------------------------------------------------------------
# 6. eqs. 6.2 and 6.3: the counterexamples of docs/ndim.md


def _cross_shell(k: int) -> np.ndarray:
    """The 2k cells face-adjacent to an empty centre cell in a k-flat of 4D
    (k = 3: an octahedral shell, a 2-sphere; k = 4: a 3-sphere)."""
    x = np.zeros((3,) * k + (1,) * (4 - k), dtype=bool)
    for i in range(k):
        for s in (0, 2):
            idx = [1] * k + [0] * (4 - k)
            idx[i] = s
            x[tuple(idx)] = True
    return x


def test_eq62_counterexamples():
    # max: six cells around an empty one in a 3-flat: a 2-sphere, chi = 2
    x = _cross_shell(3)
    assert hom.gf2_betti_numbers(x, conn(x.ndim, "full")) == (1, 0, 1, 0, 0)
    assert nd.gauss_bonnet_sum(x, conn(x.ndim, "full")) == 32  # = 2^4 chi, > 2^4 (1 - g) for every g >= 0
    # min: a 2x2x2x2 block minus two antipodal cells, 14 cells, chi = 2
    y = np.ones((2, 2, 2, 2), dtype=bool)
    y[0, 0, 0, 0] = y[1, 1, 1, 1] = False
    assert hom.gf2_betti_numbers(y, conn(y.ndim, "face")) == (1, 0, 1, 0, 0)
    assert nd.gauss_bonnet_sum(y, conn(y.ndim, "face")) == 32
    # max: eight cells around an empty one: a 3-sphere, b3 = 1, chi = 0
    z = _cross_shell(4)
    assert hom.gf2_betti_numbers(z, conn(z.ndim, "full")) == (1, 0, 0, 1, 0)
    assert nd.gauss_bonnet_sum(z, conn(z.ndim, "full")) == 0


def test_eq63_counterexamples_and_products():
    # the L-tromino: connected, no holes, E = 24 is not a multiple of 16
    x = np.zeros((2, 2, 1, 1), dtype=bool)
    x[0, 0], x[1, 0], x[0, 1] = True, True, True
    for a in ADJ:
        assert hom.gf2_betti_numbers(x, conn(x.ndim, a)) == (1, 0, 0, 0, 0)
        assert nd.surface_energy(x, conn(x.ndim, a)) == 24
    # two cells sharing a 2-face: one piece under 'max', E = 40
    y = np.zeros((2, 2, 1, 1), dtype=bool)
    y[0, 0], y[1, 1] = True, True
    assert hom.gf2_betti_numbers(y, conn(y.ndim, "full"))[0] == 1 and nd.surface_energy(y, conn(y.ndim, "full")) == 40
    # E is multiplicative on products, so tight products meet 2^n sum(b_i)
    ring = np.ones((3, 3), dtype=bool)
    ring[1, 1] = False
    torus = hom.product_image(ring, ring)
    e = nd.surface_energy(torus, conn(4, "face"))
    assert e == nd.surface_energy(ring, conn(2, "face")) ** 2 == 64 == 16 * sum(hom.gf2_betti_numbers(torus, conn(4, "face")))


def test_energy_at_least_2n_sum_of_betti_numbers_empirically():
    """E >= 2^n (b0 + ... + b_(n-1)): observed, not proved (docs/ndim.md)."""
    rng = np.random.default_rng(9)
    for _ in range(20):
        n = int(rng.choice([2, 3, 4]))
        x = random_image(rng, n, 2, 3 if n == 4 else 5)
        for a in ADJ:
            assert nd.surface_energy(x, conn(x.ndim, a)) >= 2**n * sum(hom.gf2_betti_numbers(x, conn(x.ndim, a)))


# --------------------------------------------------------------------------
# errors


def test_bad_input_raises():
    with pytest.raises(IsoflowError):
        C.configurations(np.full((2, 2), 2))  # not binary
    with pytest.raises(IsoflowError):
        C.configurations(np.zeros((1,) * 5, dtype=bool))
    with pytest.raises(IsoflowError):
        C.configurations(np.array(True))
    with pytest.raises(IsoflowError):
        euler_characteristic(np.zeros((2, 2), dtype=bool), 26)
    with pytest.raises(IsoflowError):
        I.euler_lut(5, 10)
    with pytest.raises(IsoflowError):
        S.hyperoctahedral_group(0)
    with pytest.raises(IsoflowError):
        nd.curvature_code(16, 2)
    with pytest.raises(IsoflowError):
        nd.curvature_code(1, 1)
    with pytest.raises(IsoflowError):
        nd.curvature_index(1, 3, equation="5.1")
    with pytest.raises(IsoflowError):
        S.apply_symmetry(np.zeros((2, 2), dtype=bool), 8)
    with pytest.raises(IsoflowError):
        hom.gf2_betti_numbers(np.ones((6, 6, 6, 6), dtype=bool), max_faces=1000)


def test_symmetry_indices_and_codes_that_are_none_are_refused():
    """apply_symmetry, index_61, index_48 and link_betti_numbers refuse what
    is no element, no code or not one configuration with IsoflowError, and
    compute what is (the group by NumPy's flips and transposes,
    Definition 9 by hand)."""
    # an index that is no integer: 2.5 was cut to 2 by the range check, then
    # NumPy's IndexError; True would be element 1
    for g in (2.5, True, "3"):  # (2.0 is element 2)
        with pytest.raises(IsoflowError, match=f"symmetry index must be an integer 0..7, got {g!r}"):
            S.apply_symmetry(np.zeros((2, 2), dtype=bool), g)
    # codes that are no codes: 5 and 0.5 counted as flat (index 0), a string
    # ended in NumPy's UFuncTypeError; an array of configurations in a
    # TypeError of its own
    for codes in ([5, 1], [0.5, 1], [True, False], "ab"):
        for index in (nd.index_61, nd.index_48):
            with pytest.raises(IsoflowError, match="codes must be"):
                index(np.asarray(codes))
    with pytest.raises(IsoflowError, match="takes one configuration, got an array of shape"):
        nd.link_betti_numbers(np.array([1, 2]), 2)
    # Definition 9 by hand: s(+) = 1, s(-) = -1, s(0) = s(∅) = 0
    codes = np.array([[1, 1], [1, -1], [0, 2], [-1, -2]])
    s = [[1, 1], [1, -1], [0, 0]]
    np.testing.assert_array_equal(nd.index_61(codes)[:3], [sum(v) * np.prod(np.abs(v)) for v in s])
    np.testing.assert_array_equal(nd.index_48(codes)[:3], [sum(v) * sum(np.abs(v)) for v in s])
    assert np.isnan(nd.index_61(codes)[3]) and np.isnan(nd.index_48(codes)[3])  # UNDEFINED
    # the elements it takes: (p, f) as np.transpose(np.flip(X, f), p), all eight of the square
    image = np.arange(6).reshape(2, 3)
    seen = {str(S.apply_symmetry(image, np.int64(g)).tolist()) for g in range(8)}
    expected = {str(np.transpose(np.flip(image, f), p).tolist()) for p in ((0, 1), (1, 0)) for f in ((), (0,), (1,), (0, 1))}
    assert seen == expected and len(seen) == 8
