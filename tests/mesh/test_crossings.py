"""The exact crossing test against independent exact references.

References: libigl's CGAL ``remesh_self_intersections`` (exact predicates)
for faces with no or one common corner; for faces on a common edge its
Python build constructs the supporting plane in floating point and misses
coplanar overlaps whose plane is not representable, so there the reference
is rational arithmetic (``fractions.Fraction``) in these tests; and a
separating-axis test in rationals for faces with no common corner.
"""

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import trimesh

from isoflow.mesh.crossings import crossing_pairs
from isoflow.mesh.genus import mesh_topology, self_intersections
from isoflow.mesh.load import load_mesh
from isoflow.mesh.predicates import ExactPoints

cgal = pytest.importorskip("igl.copyleft.cgal")
MESHES = Path(__file__).resolve().parents[2] / "meshes"


def cgal_pairs(v, f) -> set:
    pairs = cgal.remesh_self_intersections(np.asarray(v, np.float64), np.asarray(f, np.int64), detect_only=True,
                                           cutoff=10**9)[2]
    return {tuple(sorted(p)) for p in pairs.tolist()}


def mine(v, f) -> set:
    """The crossing pairs, found alike by the NumPy and the compiled pass."""
    numpy, compiled = ({tuple(p) for p in crossing_pairs(v, f, method=m).tolist()} for m in ("numpy", "compiled"))
    assert numpy == compiled
    return numpy


def q(p):
    return [Fraction(float(x)) for x in p]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def edge_pair_crosses(v, fa, fb) -> bool:
    """Rational reference for faces on a common edge: coplanar, and the two
    other corners on one side of the edge (normals of one direction)."""
    (u, w), a, b = sorted(set(fa) & set(fb)), (set(fa) - set(fb)).pop(), (set(fb) - set(fa)).pop()
    U, W, A, B = (q(v[i]) for i in (u, w, a, b))
    na, nb = cross(sub(W, U), sub(A, U)), cross(sub(W, U), sub(B, U))
    return dot(cross(na, nb), cross(na, nb)) == 0 and dot(na, nb) > 0


def separated(ta, tb) -> bool:
    """Rational separating-axis test of two closed triangles."""
    ta, tb = [q(p) for p in ta], [q(p) for p in tb]
    ea = [sub(ta[(i + 1) % 3], ta[i]) for i in range(3)]
    eb = [sub(tb[(i + 1) % 3], tb[i]) for i in range(3)]
    na, nb = cross(ea[0], ea[1]), cross(eb[0], eb[1])
    axes = [na, nb] + [cross(x, y) for x in ea for y in eb] + [cross(na, x) for x in ea] + [cross(nb, y) for y in eb]
    for axis in axes:
        if not any(axis):
            continue
        pa, pb = [dot(axis, p) for p in ta], [dot(axis, p) for p in tb]
        if max(pa) < min(pb) or max(pb) < min(pa):
            return True
    return False


def integer_plane(rng, count: int) -> np.ndarray:
    """``count`` integer points on one plane with a small integer normal
    off the axes: coplanar exactly, in float64 too."""
    n = rng.integers(1, 4, 3) * rng.choice([-1, 1], 3)
    u = np.cross(n, [1, 0, 0] if n[0] == 0 or abs(n[1]) + abs(n[2]) else [0, 1, 0])
    w = np.cross(n, u)
    ij = rng.integers(-6, 7, (count, 2))
    return (rng.integers(-50, 50, 3) + ij[:, :1] * u + ij[:, 1:] * w).astype(np.float64)


def near_touching_pair(rng, kind: int):
    """Two triangles on a common edge (0), corner (1) or apart (2, 3),
    placed within 1e-17..1e-3 of touching, or exactly on one plane."""
    if kind in (0, 3) and rng.random() < 0.4:
        v = integer_plane(rng, 4 if kind == 0 else 6)
        f = np.array([[0, 1, 2], [1, 0, 3]] if kind == 0 else [[0, 1, 2], [3, 4, 5]])
        return np.ldexp(v, int(rng.integers(-30, 30))), f
    p = rng.uniform(-1, 1, (3, 3))
    n = np.cross(p[1] - p[0], p[2] - p[0])
    n /= np.linalg.norm(n)
    eps = 10.0 ** rng.uniform(-17, -3) * rng.choice([-1, 1]) if rng.random() < 0.7 else 0.0

    def in_plane(s=1.0):
        return p[0] + rng.uniform(-s, s) * (p[1] - p[0]) + rng.uniform(-s, s) * (p[2] - p[0])

    if kind == 0:
        v = np.vstack([p, in_plane() + eps * n])
        f = np.array([[0, 1, 2], [1, 0, 3]])
    elif kind == 1:
        v = np.vstack([p, in_plane() + eps * n, in_plane() + eps * rng.uniform(-1, 1) * n])
        f = np.array([[0, 1, 2], [0, 3, 4]])
    elif kind == 2:  # a corner near the other face (or its edge)
        c = p.mean(axis=0) if rng.random() < 0.5 else p[0] + rng.uniform(0, 1) * (p[1] - p[0])
        v = np.vstack([p, c + eps * n, c + n + rng.normal(size=3), c + n + rng.normal(size=3)])
        f = np.array([[0, 1, 2], [3, 4, 5]])
    else:  # nearly coplanar
        v = np.vstack([p] + [in_plane(1.5) + eps * rng.uniform(-1, 1) * n for _ in range(3)])
        f = np.array([[0, 1, 2], [3, 4, 5]])
    v = v * 10.0 ** rng.integers(-3, 4) + rng.uniform(-100, 100, 3)
    if rng.random() < 0.3:
        v = np.round(v, 1)  # short decimals: exact coplanarities off the axes
    return v, f


@pytest.mark.parametrize("kind", [0, 1, 2, 3])
def test_near_touching_pairs_match_exact_references(kind):
    rng = np.random.default_rng(kind)
    answers = set()
    for _ in range(150):
        v, f = near_touching_pair(rng, kind)
        if any(not any(cross(sub(q(v[t[1]]), q(v[t[0]])), sub(q(v[t[2]]), q(v[t[0]])))) for t in f):
            continue  # collinear corners: no face to test
        got = (0, 1) in mine(v, f)
        points, at = np.unique(v, axis=0, return_inverse=True)
        fp = at.reshape(-1)[f]  # corners are common by position
        if len(set(fp[0]) & set(fp[1])) == 2:
            want = edge_pair_crosses(points, fp[0], fp[1])
        else:
            want = (0, 1) in cgal_pairs(v, f)
        if not set(fp[0]) & set(fp[1]):
            assert want == (not separated(v[f[0]], v[f[1]]))
        assert got == want, (v.tolist(), f.tolist())
        answers.add(got)
    assert answers == {True, False}  # both answers occur


def test_sample_meshes_match_exact_references():
    """Every sample mesh: CGAL's pairs, plus the coplanar overlaps on common
    edges that the rational reference finds (not_convex.obj has 12)."""
    counts = {}
    for path in sorted(MESHES.iterdir()):
        if path.suffix.lower() not in (".obj", ".ply", ".stl", ".off"):
            continue
        v, f = load_mesh(path)
        want = cgal_pairs(v, f)
        got = mine(v, f)
        for i, j in got - want:
            assert len(set(f[i]) & set(f[j])) == 2 and edge_pair_crosses(v, f[i], f[j]), (path.name, i, j)
        for i, j in want - got:  # CGAL's touching pairs at T-junctions that zero-area faces close
            assert along_sliver_edge(v, f, f[i], f[j]) or along_sliver_edge(v, f, f[j], f[i]), (path.name, i, j)
        counts[path.name] = len(got), len(want - got)
    assert counts["rabbit.obj"] == (195, 0) and counts["torus.obj"] == (0, 0) and counts["not_convex.obj"] == (156, 0)
    assert counts["wallhole.obj"] == (34, 16)


def along_sliver_edge(v, f, F, G) -> bool:
    """Rational reference for the sliver rule: an edge of G lies within an
    edge of F, both edges of faces whose corners are collinear, and G's
    third corner is off F's plane or on the other side of that edge."""
    def collinear(t):
        a, b, c = (q(v[i]) for i in t)
        return cross(sub(b, a), sub(c, a)) == [0, 0, 0]

    sliver_edges = {frozenset((t[e], t[(e + 1) % 3])) for t in f if collinear(t) for e in range(3)}
    for e in range(3):
        p, r, c = F[e], F[(e + 1) % 3], F[(e + 2) % 3]
        for g in range(3):
            a, b, k = G[g], G[(g + 1) % 3], G[(g + 2) % 3]
            if {a, b} == {p, r} or {frozenset((p, r)), frozenset((a, b))} - sliver_edges:
                continue
            P, R, C, K = q(v[p]), q(v[r]), q(v[c]), q(v[k])
            within = all(cross(sub(R, P), sub(q(v[m]), P)) == [0, 0, 0]
                         and 0 <= dot(sub(q(v[m]), P), sub(R, P)) <= dot(sub(R, P), sub(R, P)) for m in (a, b))
            normal = cross(sub(R, P), sub(C, P))
            if within and (dot(normal, sub(K, P)) != 0 or dot(cross(sub(R, P), sub(K, P)), normal) < 0):
                return True
    return False


def torus_pair(gap: float, offset=(0.0, 0.0, 0.0)):
    """Two tori side by side whose tubes are ``gap`` apart (negative: they
    overlap), as one mesh."""
    a = trimesh.creation.torus(1.0, 0.25, major_sections=32, minor_sections=12)
    b = a.copy()
    b.apply_translation([2.5 + gap, 0.0, 0.0])
    v = np.vstack([a.vertices, b.vertices]) + np.asarray(offset)
    return v, np.vstack([a.faces, b.faces + len(a.vertices)])


@pytest.mark.parametrize("gap", [1e-12, 0.0, -1e-3])
def test_two_tori_nearly_touching(gap):
    v, f = torus_pair(gap)
    got, want = mine(v, f), cgal_pairs(v, f)
    assert got == want
    assert bool(got) == (gap < 0)  # the outermost points of the tubes are no vertices: no contact at 0


@pytest.mark.parametrize("k", [-900, -20, 20, 900])
def test_units_do_not_create_or_remove_crossings(k):
    """Scaling by a power of two is exact: the crossings stay the same, in
    units of 1e-271 to 1e271, far beyond where the float filter decides."""
    v, f = load_mesh(MESHES / "rabbit.obj")
    assert mine(np.ldexp(v, k), f) == mine(v, f)
    v, f = torus_pair(1e-9, offset=(1e6, -3e5, 7.25))
    assert mine(np.ldexp(v, k), f) == set() == cgal_pairs(v, f)


def test_slivers_and_a_flat_fan():
    """A fan of 200 slivers around one corner in a plane (a CAD cap): they
    meet only at their common edges and corner; folding one sliver back
    onto its neighbour makes a coplanar overlap."""
    t = np.linspace(0, 1e-3, 201)
    rim = np.column_stack([np.cos(t), np.sin(t), np.zeros_like(t)]) * 50 + [3.3, -7.1, 0.1]
    v = np.vstack([[3.3, -7.1, 0.1], rim])
    f = np.array([[0, i + 1, i + 2] for i in range(200)])
    assert mine(v, f) == set()
    folded = np.vstack([f, [[0, 3, 2]]])  # the second sliver again, the other way: a duplicate, not tested
    assert mine(v, folded) == set()
    over = np.vstack([f, [[0, 1, 3]]])  # covers slivers 0 and 1
    got = mine(v, over)
    assert got == {(0, 200), (1, 200)} and all(edge_pair_crosses(v, over[i], over[j]) for i, j in got)


def test_self_intersections_split_by_component():
    v, f = load_mesh(MESHES / "rabbit.obj")
    _, comp = mesh_topology(v, f, return_components=True)
    r = self_intersections(v, f, comp)
    faces = np.unique(np.array(sorted(cgal_pairs(v, f))))
    assert r == {"self_intersecting_faces": 0, "faces_touching_own_component": 0,
                 "faces_crossing_other_components": len(faces), "zero_area_faces": 0, "pairs_along_slivers": 0}


def test_a_voxel_surface_has_no_crossing(rng):
    """isoflow's own boundary surfaces (triangulated, corners welded by
    position) are embedded: every face pair on them is coplanar or meets
    along what they share (int64 decides in the compiled pass)."""
    from isoflow import boundary_mesh

    vol = np.zeros((12, 12, 12), bool)
    vol[2:10, 2:10, 2:10] = rng.random((8, 8, 8)) < 0.6
    m = boundary_mesh(vol, 26)
    tri = m.triangles()
    assert mine(np.asarray(m.vertices, float) * 0.37 + 1e3, tri) == set() == cgal_pairs(np.asarray(m.vertices, float), tri)


def test_orientation_signs_are_exact():
    """Points that float64 arithmetic misjudges: d off the plane by one unit
    in the last place of a coordinate near 1e16."""
    big = 2.0**53
    p = ExactPoints([[big, 0, 0], [0, big, 0], [0, 0, big], [big / 3, big / 3, big / 3 + 2]])
    s = p.orient3d(np.array([0]), np.array([1]), np.array([2]), np.array([3]))
    a, b, c, d = (q(x) for x in ([big, 0, 0], [0, big, 0], [0, 0, big], [big / 3, big / 3, big / 3 + 2]))
    det = dot(sub(a, d), cross(sub(b, d), sub(c, d)))
    assert s[0] == (det > 0) - (det < 0) != 0


def t_junction_box(splits=(0.5,)):
    """A closed box (trimesh's) whose face on one side of an edge is split
    at points of that edge, its neighbour across the edge left whole, and
    zero-area faces (slivers) closing the T-junction as CAD exports do: a
    closed manifold of genus 0. Returns vertices, faces, the whole face's
    index and the split faces' indices."""
    box = trimesh.creation.box()
    v, f = box.vertices.copy(), box.faces.tolist()
    split, whole = (int(x) for x in box.face_adjacency[0])
    a, b, k = f[split]
    while {a, b} != set(box.face_adjacency_edges[0].tolist()):
        a, b, k = b, k, a
    ends = [a] + [len(v) + i for i in range(len(splits))] + [b]
    v = np.vstack([v, [v[a] + t * (v[b] - v[a]) for t in splits]])  # on the edge exactly: halves and quarters
    f[split:split + 1] = [[p, q, k] for p, q in zip(ends[:-1], ends[1:])]
    # sliver i: from the point before split point i to b, then to it: every edge has two faces, one each way
    f += [[ends[i], b, ends[i + 1]] for i in range(len(splits))]
    whole += len(splits) if whole > split else 0
    return v, np.array(f), whole, list(range(split, split + len(splits) + 1))


@pytest.mark.parametrize("splits", [(0.5,), (0.25, 0.5), (0.25, 0.5, 0.75)])
def test_zero_area_faces_closing_a_t_junction_are_no_crossing(splits):
    """CGAL sees the whole face meet the split ones at the split points
    (one common corner or none, touching); the slivers make the edge one,
    so isoflow reports no crossing, and the mesh is the closed genus-0
    surface manifold3d sees."""
    import manifold3d as m3

    v, f, whole, parts = t_junction_box(splits)
    _, comp = mesh_topology(v, f, return_components=True)
    report = mesh_topology(v, f)
    assert report["watertight"] and report["genus"] == 0
    mf = m3.Manifold(m3.Mesh(vert_properties=v.astype(np.float32), tri_verts=f.astype(np.uint32)))
    assert mf.status() == m3.Error.NoError and mf.genus() == 0
    cgal = cgal_pairs(v, f)
    assert cgal and all(whole in p and (set(p) - {whole}) <= set(parts) for p in cgal)
    assert mine(v, f) == set()
    r = self_intersections(v, f, comp)
    assert r["self_intersecting_faces"] == 0 and r["zero_area_faces"] == len(splits)
    assert r["pairs_along_slivers"] == len(cgal)


def test_a_split_face_folded_onto_the_whole_one_still_crosses():
    """A split face turned into the whole face's plane, on its side of the
    edge, overlaps it: the slivers explain the common edge, not the
    overlap."""
    v, f, whole, parts = t_junction_box((0.5,))
    k = f[parts[0], 2]  # the split faces' corner off the edge
    v = v.copy()
    v[k] = v[f[whole]].mean(axis=0)  # the whole face's centre: in its plane exactly (a box face)
    assert (min(whole, parts[0]), max(whole, parts[0])) in mine(v, f)


def test_genus_of_a_t_junction_box_agrees_and_names_the_sliver(tmp_path, capsys):
    import json

    from isoflow.cli import main

    v, f, _, _ = t_junction_box((0.5,))
    trimesh.Trimesh(v, f, process=False).export(tmp_path / "t.obj")
    assert main(["genus", str(tmp_path / "t.obj"), "--resolution", "16", "32", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["self_intersecting_faces"] == 0 and report["agree"] and report["solid_genus"] == 0
    assert "1 zero-area face (corners in a line)" in report["verdict"]
    assert "2 face pairs meet along it where it closes a split edge" in report["verdict"]


def test_a_union_not_built_is_not_said_to_be_manifold3ds_failure():
    """``wallhole.obj`` crosses itself, so genus builds no solid for it;
    the note on its faces that touch said the union was one "which
    manifold3d could not build (not computed)", though manifold3d takes
    the mesh (no error, as trimesh welds it) and was never asked."""
    import manifold3d as m3

    from isoflow.mesh.genus import verify_genus

    loaded = trimesh.load(MESHES / "wallhole.obj", force="mesh")
    welded = trimesh.Trimesh(loaded.vertices, loaded.faces, process=True)  # equal positions merged
    made = m3.Manifold(m3.Mesh(np.asarray(welded.vertices, np.float32), np.asarray(welded.faces, np.uint32)))
    assert made.status() == m3.Error.NoError
    verdict = verify_genus(MESHES / "wallhole.obj", resolutions=[16], step=False)
    assert verdict.kind == "self_intersecting" and "error" not in verdict.manifold3d
    assert "manifold3d could not build" not in verdict.verdict
    assert "which is not built for a mesh that is open, inconsistently oriented or crosses itself" in verdict.verdict
