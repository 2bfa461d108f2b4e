"""The paper's own figures, read against isoflow.

A. Imiya, *Curvature and Flow in Digital Space*, Actes des rencontres du
CIRM 3(1) (2013), pp. 183-194. The OCR in the project's seed keeps the
equation, theorem and figure numbers but no page breaks, so each test cites
those. The expected values are the paper's, or counts known from the cube
and from scikit-image, never isoflow's own output.
"""

import inspect
from fractions import Fraction

import numpy as np
import pytest
from skimage.measure import euler_number

import isoflow
from isoflow import analyze, boundary_mesh, read_object, run_flow
from isoflow.digital import indices as I

#: scikit-image's connectivity for isoflow's object connectivity
SKIMAGE = {6: 1, 26: 3}


def test_docstrings_cite_the_equations_of_their_quantities():
    """gamma is the vertex angle of eq. 4.6 (eq. 4.5 gives octant counts),
    f the vertex index of eq. 4.8 (not eq. 4.6), and a solid torus, with one
    tunnel, is Theorem 11's case (Theorem 10 is the object without tunnels,
    ``a^T n = 8``)."""
    assert "eq. 4.6" in inspect.getdoc(isoflow.QuadMesh.gamma)
    assert "eq. 4.8" in inspect.getdoc(isoflow.QuadMesh.f)
    torus = inspect.getdoc(isoflow.analyze).split("A solid torus", 1)[1].split(">>>", 1)[0]
    assert "Theorem 11" in torus and "Theorem 10" not in torus


def test_each_class_holds_the_configurations_the_cube_gives_it():
    """Section 4.2, eqs. 4.4-4.6: the nine classes as sets of octants of the
    2x2x2 window, counted on the cube: a corner (8 vertices), an edge (12
    edges), an L of three (a vertex and two of its three neighbours:
    8 x 3), a face (6), a vertex with its three neighbours (8), a path of
    three edges along the three axes (8 x 3 x 2 x 1 / 2 = 24), and the
    complements of the first three. 126 in all; of the other 130, the
    empty and full windows are off the surface."""
    by_class = dict(zip(I.CLASS_LABELS, (24, 24, 12, 8, 6, 8, 12, 24, 8)))
    cls = I.class_lut()
    assert {label: int(np.count_nonzero(cls == k)) for k, label in enumerate(I.CLASS_LABELS)} == by_class
    assert sum(by_class.values()) == 126
    assert np.count_nonzero(cls == I.OFF_SURFACE) == 2
    assert np.count_nonzero(cls == I.NOT_WELL_COMPOSED) == 256 - 126 - 2


def test_the_nine_classes_and_their_a_do_not_depend_on_the_connectivity():
    """Section 4.2 counts nine configurations "on the boundary of a
    6-connected object"; a well-composed vertex reads the same under 6 and
    26, so each class has one a (eq. 4.10) at both, and on an object whose
    vertices are all well-composed (Example 19) both sums are 8 times
    scikit-image's Euler number at either connectivity."""
    cls, six, twenty_six = I.class_lut(), I.a_lut(6), I.a_lut(26)
    for k in range(9):
        members = np.flatnonzero(cls == k)
        assert len(set(six[members].tolist()) | set(twenty_six[members].tolist())) == 1
    volume = read_object(isoflow.data.example19()).volume
    assert analyze(volume, 6).a_dot_n == analyze(volume, 26).a_dot_n == 8 * euler_number(volume, 1) == 8 * euler_number(volume, 3)


def test_property_6_every_surface_point_lies_on_two_or_three_digital_planes():
    """Property 6 (from Theorem 5): the per-axis codes of eq. 4.3 are
    defined (not ∅) on two planes at a flat point and on three elsewhere."""
    cls, code = I.class_lut(), I.code_lut()
    for c in np.flatnonzero(cls >= 0):
        planes = int(np.count_nonzero(code[c] != I.NONE))
        assert planes == (2 if cls[c] == 4 else 3), I.code_string(int(c))


def eq_4_2(points: np.ndarray, m: int, n: int) -> Fraction:
    """Eq. 4.2 as printed: ``r = 1 - 1/2 sum f_k + 1/4 sum f_k f_k+1 f_k+2``
    over ``k`` in N = {1, 3, 5, 7}, ``k + 8 = k``, with x1 = (m+1, n),
    x3 = (m, n+1), x5 = (m-1, n), x7 = (m, n-1) (eq. 4.1) and the even
    indices the diagonals between them."""
    ring = [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)]  # x1 .. x8
    padded = np.pad(points, 1)

    def f(k: int) -> int:
        dm, dn = ring[(k - 1) % 8]
        return int(padded[m + 1 + dm, n + 1 + dn])

    sides = sum(f(k) for k in (1, 3, 5, 7))
    squares = sum(f(k) * f(k + 1) * f(k + 2) for k in (1, 3, 5, 7))
    return 1 - Fraction(sides, 2) + Fraction(squares, 4)


def test_planar_index_is_eq_4_2_as_printed():
    """Eq. 4.2 evaluated literally at every point of random point sets, and
    the signs of Figure 2.1 (d): convex (A) positive, flat (B) zero, concave
    (C) negative."""
    rng = np.random.default_rng(42)
    for _ in range(60):
        points = rng.random(rng.integers(2, 9, 2)) < rng.uniform(0.3, 0.9)
        got = I.planar_index(points)
        for m, n in np.argwhere(points):
            assert got[m, n] == 4 * eq_4_2(points, m, n)
    ell = np.ones((3, 3), bool)
    ell[2, 2] = False  # a square of points with one corner cut: A at (0, 0), B at (0, 1), C at (1, 1)
    assert [eq_4_2(ell, *p) for p in ((0, 0), (0, 1), (1, 1))] == [Fraction(1, 4), 0, Fraction(-1, 4)]


@pytest.mark.parametrize("shape", [(1, 1, 1), (2, 3, 4), (5, 1, 2), (3, 3, 3)])
def test_theorem_10_and_the_energy_of_a_cuboid(shape):
    """Theorem 10 (eq. 4.12): an object without tunnels has ``a^T n = 8``;
    the proof of Theorem 24: "E = 8 for a cuboid", its eight corners
    (+,+,+) with k = 1 (eq. 4.11) and nothing else curved."""
    box = np.ones(shape, bool)
    report = analyze(box)
    assert euler_number(box, 1) == 1
    assert report.a_dot_n == 8 and report.energy == 8
    assert report.n[I.CLASS_LABELS.index("(+,+,+)")] == 8


@pytest.mark.parametrize("connectivity", [6, 26])
@pytest.mark.parametrize("g", [1, 2, 3])
def test_theorems_11_and_24_on_a_plate_with_g_holes(g, connectivity):
    """Theorem 11 (eq. 4.13): ``a^T n = 8 (1 - g)`` for an object with g
    tunnels (scikit-image: chi = 1 - g); Theorem 24 (eq. 5.23):
    ``E = k^T n >= 8 (1 + g)``."""
    plate = np.ones((2 * g + 1, 3, 2), bool)
    plate[1::2, 1] = False  # g square holes through a plate two voxels thick
    report = analyze(plate, connectivity)
    assert euler_number(plate, SKIMAGE[connectivity]) == 1 - g
    assert report.a_dot_n == 8 * (1 - g)
    assert report.energy >= 8 * (1 + g)


def test_theorem_10_as_printed_fails_for_an_object_with_a_cavity():
    """A hollow 4x4x4 box has no tunnel, yet ``a^T n = 16``, not the 8 of
    eq. 4.12: scikit-image counts chi = 2 (docs/mathematics.md, "Where
    isoflow departs from the paper"). Theorem 11 holds when its g_i are the
    genera of the closed boundary surfaces, the cavity's among them."""
    hollow = np.ones((4, 4, 4), bool)
    hollow[1:3, 1:3, 1:3] = False
    report = analyze(hollow)
    assert euler_number(hollow, 1) == 2
    assert report.a_dot_n == 16 == 8 * sum(1 - g for g in report.genus)


#: eq. 5.20 as printed: each dual point and the points of eq. 5.19 that go to it
EQ_5_20 = {
    (0.5, 0.5, 0.5): [(0, 0, 0)],
    (0.5, 1.5, 0.5): [(0, 2, 1), (0, 2, 0), (1, 2, 1), (1, 2, 0)],
    (1.5, 1.5, 0.5): [(1, 1, 0)],
    (1.5, 0.5, 0.5): [(1, 0, 0), (2, 0, 0), (2, 1, 0), (2, 1, 1), (2, 0, 1)],
    (0.5, 0.5, 1.5): [(0, 0, 2), (0, 1, 2), (1, 0, 2), (1, 1, 2)],
    (0.5, 1.5, 1.5): [(0, 1, 1)],
    (1.5, 1.5, 1.5): [(1, 1, 1)],
    (1.5, 0.5, 1.5): [(1, 0, 1)],
}


def test_eq_5_20_leaves_out_two_points_that_the_symmetry_of_example_19_places():
    """Eq. 5.20 maps 18 of the 20 points of eq. 5.19: (0, 0, 1) and
    (0, 1, 0) are missing. The object is its own image under every
    permutation of the axes and eq. 5.20 commutes with them wherever both
    sides are printed, so (1, 0, 0) -> (3/2, 1/2, 1/2) places the two:
    (0, 1, 0) -> (1/2, 3/2, 1/2) and (0, 0, 1) -> (1/2, 1/2, 3/2)
    (docs/mathematics.md, "Misprints in the paper")."""
    from itertools import permutations

    image = {p: target for target, sources in EQ_5_20.items() for p in sources}
    paper = {tuple(p) for p in np.loadtxt(isoflow.data.example19(), int)}
    assert len(paper) == 20 and set(image) < paper
    assert paper - set(image) == {(0, 0, 1), (0, 1, 0)}
    assert {tuple(p[i] for i in s) for p in paper for s in permutations(range(3))} == paper
    for s in permutations(range(3)):
        for p, target in image.items():
            moved = tuple(p[i] for i in s)
            if moved in image:
                assert image[moved] == tuple(target[i] for i in s)


def test_example_19_lands_on_the_cube_of_eq_5_21():
    """Example 19: the points of eq. 5.19 go to the 8 dual points of
    eq. 5.20, each at most half a unit away along every axis; they are the
    cube P of eq. 5.21, the corners of the surface of isoflow's first step,
    and P converges to the point (1, 1, 1) (Figure 5.3), the energy never
    rising on the way (Theorem 25)."""
    obj = read_object(isoflow.data.example19())
    for target, sources in EQ_5_20.items():
        assert all(np.abs(np.subtract(target, s)).max() == 0.5 for s in sources)
    run = run_flow(obj)
    first = run.states[1]
    corners = first.world(boundary_mesh(first.volume).vertices)
    assert {tuple(v) for v in corners.tolist()} == set(EQ_5_20)
    assert run.limit["center"] == [1.0, 1.0, 1.0]
    # Theorem 25 on this run: E = 13 corners + 3 of (+,+,-) + 4 for (+,-,-)+ = 20, then a cube's 8 (proof of
    # Theorem 24), then nothing
    assert [s["energy"] for s in run.steps] == [20, 8, 0]


def test_the_docs_cite_the_paper_as_published():
    """The paper's first page: Actes des rencontres du CIRM, Vol. 3, no. 1
    (2013), pp. 183-194; the citing sections gave only the title and year."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    for page in ("README.md", "docs/index.md", "docs/mathematics.md"):
        text = " ".join((root / page).read_text(encoding="utf-8").split())
        assert "Curvature and Flow in Digital Space" in text and "CIRM 3(1) (2013), pp. 183-194" in text, page


def cell_counts(config: int) -> tuple[int, ...]:
    """Octants in the object, and the vertex's 6 half-edges and 12
    quarter-faces (of the lattice cells around it) that have some or all of
    their 4 or 2 octants in it, and whether the 8 octants are all in."""
    inside = {o for o in range(8) if config >> o & 1}
    octant = [((o & 1), (o >> 1) & 1, (o >> 2) & 1) for o in range(8)]
    edges = [{o for o in range(8) if octant[o][i] == s} for i in range(3) for s in (0, 1)]
    faces = [{o for o in range(8) if octant[o][i] == si and octant[o][j] == sj}
             for i in range(3) for j in range(i + 1, 3) for si in (0, 1) for sj in (0, 1)]
    some = [sum(bool(cell & inside) for cell in cells) for cells in (edges, faces)]
    every = [sum(cell <= inside for cell in cells) for cells in (edges, faces)]
    return len(inside), *some, *every, int(len(inside) == 8)


def test_a_at_6_and_26_is_eight_times_the_vertex_share_of_chi():
    """Eq. 4.10's a, on all 256 configurations, from the cells around the
    vertex: under 26 the object is the union of its closed cubes, each cell
    shared by the 8, 4 or 2 vertices of its cube, edge or face,
    ``a = 8 (1 - E/2 + F/4 - C/8)``; under 6 it is the union of the open
    cubes and the faces, edges and vertex all of whose cubes are in it, an
    open 3-manifold whose compactly supported Euler number is -chi,
    ``a = C - 2 F + 4 E - 8 V``. Both give the paper's values on the nine
    classes (eq. 4.10), and they differ on 96 of the 128 configurations
    that are not well-composed."""
    six, twenty_six = I.a_lut(6), I.a_lut(26)
    for c in range(256):
        cubes, edges_some, faces_some, edges_all, faces_all, full = cell_counts(c)
        assert twenty_six[c] == 8 * (cubes > 0) - 4 * edges_some + 2 * faces_some - cubes, c
        assert six[c] == cubes - 2 * faces_all + 4 * edges_all - 8 * full, c
    nwc = I.class_lut() == I.NOT_WELL_COMPOSED
    assert np.array_equal(six[~nwc], twenty_six[~nwc])
    assert np.count_nonzero(six[nwc] != twenty_six[nwc]) == 96
