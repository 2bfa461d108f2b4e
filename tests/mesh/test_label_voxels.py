"""Several meshes into one label image (issue 25 item 6): the block of the
grid each mesh fills is the whole grid's, bit for bit; the labels, the
overlap counts and the rule are checked against every mesh voxelised alone
on the same grid; bodies against trimesh's split and a scene's nodes."""

import json
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from isoflow import IsoflowError, voxelize_meshes
from isoflow.mesh import label_voxels
from isoflow.mesh.bodies import mesh_bodies
from isoflow.mesh.census import edge_table
from isoflow.mesh.load import load_mesh, weld
from isoflow.mesh.voxelize import voxelize

MESHES = Path(__file__).resolve().parents[2] / "meshes"
DATA = Path(__file__).resolve().parent / "data"


def alone(mesh, r, fill="winding"):
    """A mesh voxelised alone on the grid of the label image ``r``."""
    v, f = (mesh.vertices, mesh.faces) if hasattr(mesh, "faces") else load_mesh(mesh)
    return voxelize(v, f, pitch=r.pitch, grid=(r.origin, r.labels.shape), fill=fill, details=True).volume


def sphere(radius, centre, subdivisions=3):
    s = trimesh.creation.icosphere(subdivisions, radius)
    s.apply_translation(centre)
    return s


@pytest.mark.parametrize("name", ["rabbit.obj", "cube_no_bottom.obj", "torus.obj"])
def test_a_block_of_the_grid_is_the_whole_grids_bit_for_bit(name):
    v, f = load_mesh(MESHES / name)
    for fill in ("winding", "shell"):
        full = voxelize(v, f, resolution=40, fill=fill, details=True)
        sh = full.volume.shape
        lo, hi = (3, 5, 0), (sh[0] - 2, sh[1] - 1, sh[2])
        block = voxelize(v, f, pitch=full.pitch, grid=(full.origin, sh), window=(lo, hi), fill=fill, details=True)
        assert np.array_equal(block.volume, full.volume[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]), fill
        assert np.allclose(block.origin, full.origin + full.pitch * np.array(lo))
    with pytest.raises(IsoflowError, match="window must be"):
        voxelize(v, f, pitch=full.pitch, grid=(full.origin, sh), window=((0, 0, 0), (sh[0] + 1, 1, 1)))


@pytest.mark.parametrize("fill", ["winding", "shell", "flood"])
def test_one_mesh_is_its_own_voxelisation(fill):
    # an open mesh too: the block around its box loses nothing, and flood's
    # outside is the same (a margin free of the shell)
    for name in ("rabbit.obj", "cube_no_bottom.obj"):
        v, f = load_mesh(MESHES / name)
        r = voxelize_meshes([MESHES / name], resolution=32, fill=fill)
        want = voxelize(v, f, resolution=32, fill=fill, details=True)
        assert r.labels.shape == want.volume.shape and np.allclose(r.origin, want.origin) and r.pitch == want.pitch
        assert np.array_equal(r.labels == 1, want.volume) and r.voxels == (want.voxels,)
        assert r.overlaps == () and r.overlap_voxels == 0 and r.note is None


def test_two_overlapping_meshes_later_wins_and_the_counts_are_the_shared_voxels():
    a, b = sphere(1.0, (0, 0, 0)), sphere(0.8, (1.1, 0.3, -0.2))
    r = voxelize_meshes([a, b], resolution=48)
    A, B = alone(a, r), alone(b, r)
    shared = int((A & B).sum())
    assert shared > 100
    assert np.array_equal(r.labels == 2, B) and np.array_equal(r.labels == 1, A & ~B)
    assert not r.labels[~(A | B)].any()
    assert r.voxels == (int((A & ~B).sum()), int(B.sum()))
    assert r.overlap_voxels == shared and r.overlaps == ((1, 2, shared),)
    assert f"{shared} voxels lie inside two or more meshes (labels 1 and 2: {shared})" in r.note
    assert r.labels.dtype == np.uint8 and r.names == ("mesh 1", "mesh 2")
    # the grid is the union's: the rule of one mesh on both boxes
    both = trimesh.util.concatenate([a, b])
    grid = voxelize(both.vertices, both.faces, resolution=48, details=True)
    assert r.labels.shape == grid.volume.shape and np.allclose(r.origin, grid.origin)
    with pytest.raises(IsoflowError, match=rf"meshes overlap: {shared} voxels .*labels 1 and 2: {shared}\)"):
        voxelize_meshes([a, b], resolution=48, overlap="error")


def test_three_meshes_count_each_shared_voxel_once_and_each_pair_what_it_took():
    meshes = [sphere(1.0, (0, 0, 0)), sphere(0.9, (0.9, 0, 0)), sphere(0.8, (0.4, 0.7, 0.1))]
    r = voxelize_meshes(meshes, pitch=0.06)
    masks = [alone(m, r) for m in meshes]
    inside = sum(m.astype(int) for m in masks)
    assert (inside == 3).any()  # a voxel in all three
    assert r.overlap_voxels == int((inside >= 2).sum())
    # label before mesh j is placed: the last earlier mesh holding the voxel
    want = {}
    for j in (2, 3):
        before = np.zeros(r.labels.shape, int)
        for i in range(1, j):
            before[masks[i - 1]] = i
        for i in range(1, j):
            n = int((masks[j - 1] & (before == i)).sum())
            if n:
                want[(i, j)] = n
    assert {(i, j): n for i, j, n in r.overlaps} == want and len(want) == 3
    assert r.voxels == tuple(int((r.labels == i).sum()) for i in (1, 2, 3))


def test_split_gives_one_label_per_connected_body_as_trimesh_splits(tmp_path):
    parts = [sphere(0.5, (x, 0.3 * x, 0), 2) for x in (0, 1.5, 3)] + [trimesh.creation.box((0.8, 0.8, 0.8))]
    parts[-1].apply_translation((1.5, 2, 0))
    path = tmp_path / "parts.stl"
    trimesh.util.concatenate(parts).export(path)
    bodies = trimesh.load(path).split(only_watertight=False)
    r = voxelize_meshes([path], resolution=40, split=True)
    assert len(r.names) == len(bodies) == 4 and r.names[0] == f"{path}:1"
    assert sorted(r.voxels) == sorted(int(alone(b, r).sum()) for b in bodies)
    assert set(np.unique(r.labels)) == {0, 1, 2, 3, 4} and r.overlaps == ()


def test_split_keeps_a_cavity_with_its_body():
    outer, inner = sphere(1.0, (0, 0, 0)), sphere(0.6, (0, 0, 0))
    inner.invert()  # the cavity's wall, oriented inwards
    box = trimesh.creation.box((0.5, 0.5, 0.5))
    box.apply_translation((2, 0, 0))
    hollow = trimesh.util.concatenate([outer, inner, box])
    assert len(hollow.split(only_watertight=False)) == 3
    r = voxelize_meshes([(hollow.vertices, hollow.faces)], resolution=40, split=True)
    assert r.names == ("mesh 1:1", "mesh 1:2") and r.overlaps == ()
    shell = trimesh.util.concatenate([outer, inner])
    assert np.array_equal(r.labels == 1, alone(shell, r)) and np.array_equal(r.labels == 2, alone(box, r))
    centre = np.floor((np.zeros(3) - r.origin) / r.pitch).astype(int)
    assert r.labels[tuple(centre)] == 0  # the cavity is empty


def test_split_names_a_hollow_body_alone_as_its_file(tmp_path):
    # a mesh of one body keeps the name FILE (docs/labels.md); a hollow one,
    # two shells of one body: the file's name, not FILE:1
    outer, inner = trimesh.creation.box((2, 2, 2)), trimesh.creation.box((1, 1, 1))
    inner.invert()
    path = tmp_path / "hollow.obj"
    trimesh.util.concatenate([outer, inner]).export(path)
    assert len(trimesh.load(path, force="mesh").split(only_watertight=False)) == 2
    r = voxelize_meshes([path], pitch=0.125, split=True)
    assert r.names == (str(path),) and r.voxels == (16**3 - 8**3,)  # the cavity empty
    assert voxelize_meshes([path], pitch=0.125).names == r.names


def test_split_names_an_archives_bodies_by_its_files_in_their_natural_order(tmp_path):
    # trimesh's scene of an archive names its members' nodes at random
    # (geometry_0f7d...): the labels' names and order changed from run to run
    import zipfile

    parts = {}
    for n in (10, 2, 1):
        box = trimesh.creation.box((1, 1, 0.5 + 0.1 * n))
        box.apply_translation((2.0 * n, 0, 0))
        parts[f"part{n}.stl"] = box
    path = tmp_path / "parts.zip"
    with zipfile.ZipFile(path, "w") as archive:
        for name, box in parts.items():
            box.export(tmp_path / name)  # the member, outside the archive too (STL's float32 corners)
            archive.write(tmp_path / name, name)
    r = voxelize_meshes([path], pitch=0.1, split=True)
    order = ["part1.stl", "part2.stl", "part10.stl"]
    assert r.names == tuple(f"{path}:{name}" for name in order)
    for k, name in enumerate(order, 1):
        assert np.array_equal(r.labels == k, alone(tmp_path / name, r))
    assert voxelize_meshes([path], pitch=0.1, split=True).names == r.names


def welded(*meshes):
    """Meshes concatenated and welded, as a file of them is read."""
    m = trimesh.util.concatenate(meshes)
    return weld(np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces))


def unit_box(x, y, z, mirrored=False):
    box = trimesh.creation.box()
    if mirrored:  # upside down: its bottom triangulated as an unmirrored box's top
        box.apply_transform(np.diag([1.0, 1.0, -1.0, 1.0]))
    return box.apply_translation((x, y, z))


def split(v, f):
    """The bodies of a welded mesh as closed-or-not trimesh meshes, and the
    number of components joined across every shared edge (the rule before
    bodies were told apart around non-manifold edges)."""
    bodies = [trimesh.Trimesh(b.vertices, b.faces, process=False) for b in mesh_bodies([(v, f)], split=True)]
    return bodies, len(np.unique(edge_table(f, len(v))[5]))


def test_split_parts_boxes_that_touch_along_an_edge():
    bodies, joined = split(*welded(unit_box(0, 0, 0), unit_box(1, 1, 0)))
    assert joined == 1  # the weld shares their edge: 4 faces on it
    assert len(bodies) == 2
    for b in bodies:
        assert len(b.faces) == 12 and b.is_watertight and b.volume == pytest.approx(1.0)


@pytest.mark.parametrize("mirrored", [False, True], ids=["other-diagonal", "same-triangles"])
def test_split_parts_stacked_boxes_that_write_their_shared_face_twice(mirrored):
    """The square between the boxes is written by each (opposite
    orientations): triangulated across the other diagonal, or as the same
    two triangles (exactly coincident faces)."""
    v, f = welded(unit_box(0, 0, 0), unit_box(0, 0, 1, mirrored))
    bodies, joined = split(v, f)
    assert joined == 1 and len(f) == 24
    assert len(bodies) == 2
    for b in bodies:
        assert len(b.faces) == 12 and b.is_watertight and b.volume == pytest.approx(1.0)
    assert sorted(round(float(b.centroid[2]), 9) for b in bodies) == [0.0, 1.0]
    stack, _ = split(*welded(*(unit_box(0, 0, z, mirrored and z % 2) for z in range(3))))
    assert len(stack) == 3 and all(b.is_watertight and b.volume == pytest.approx(1.0) for b in stack)


def test_split_parts_a_checkerboard_of_cubes_touching_at_edges_and_corners():
    cells = [(x, y, z) for x in range(3) for y in range(3) for z in range(3) if (x + y + z) % 2 == 0]
    cubes = [unit_box(*c) for c in cells]
    bodies, joined = split(*welded(*cubes))
    assert len(cubes) == 14 and joined == 1
    assert len(bodies) == 14
    assert all(len(b.faces) == 12 and b.is_watertight and b.volume == pytest.approx(1.0) for b in bodies)
    assert sorted(tuple(np.round(b.centroid, 9) + 0.0) for b in bodies) == cells  # one body per cube


def test_split_keeps_a_cavity_with_its_body_beside_a_box_on_its_edge():
    outer, inner = trimesh.creation.box((3, 3, 3)), trimesh.creation.box((1, 1, 1))
    inner.invert()  # the cavity's wall, oriented inwards
    hollow, _ = split(*welded(outer, inner))
    assert len(hollow) == 1 and hollow[0].volume == pytest.approx(26.0)
    neighbour = trimesh.creation.box((3, 3, 3)).apply_translation((3, 3, 0))  # shares an edge with outer
    bodies, joined = split(*welded(outer, inner, neighbour))
    assert joined == 2  # outer and neighbour joined across the edge, the cavity's wall alone
    assert [len(b.faces) for b in bodies] == [24, 12]
    assert [b.volume for b in bodies] == pytest.approx([26.0, 27.0])
    # an inward tetrahedron on the diagonal of the cube's top: joined to the cube around that edge
    cube = trimesh.creation.box()
    tv = np.array([[-0.5, -0.5, 0.5], [0.5, 0.5, 0.5], [0.2, -0.2, 0.0], [-0.2, 0.2, 0.0]])
    tet = trimesh.Trimesh(tv, [[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]], process=False)  # inwards
    assert tet.volume < 0 and [1, 7] in cube.edges.tolist()  # tv[0], tv[1]: the cube's vertices 1 and 7
    bodies, _ = split(*welded(cube, tet))
    assert len(bodies) == 1 and bodies[0].volume == pytest.approx(1 + tet.volume)


def test_split_of_open_meshes_and_fins_is_as_before():
    """Where the faces around an edge do not bound wedges of solid, or the
    pieces would be open, faces are joined across every shared edge."""
    box = trimesh.creation.box()
    lidless = trimesh.Trimesh(box.vertices, np.delete(box.faces, [4, 6], axis=0), process=False)  # no top
    v = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [-1, -1, 0]], dtype=float)
    three_fins = (v, np.array([[0, 1, 2], [1, 0, 3], [0, 1, 6]]))
    four_fins = (v, np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 0, 5]]))  # an X of open sheets, alternating
    fin = np.array([[0.5, 0.5, -0.5], [0.5, 0.5, 0.5], [1.5, 1.5, 0.0]])
    finned = (np.vstack([box.vertices, fin]), np.vstack([box.faces, [[8, 9, 10], [9, 8, 10]]]))  # double-sided
    doubled = (box.vertices, np.vstack([box.faces, box.faces[:1, ::-1]]))  # a face written both ways
    beside = welded(unit_box(0, 0, 0), lidless.copy().apply_translation((1, 1, 0)))  # open box on a closed one's edge
    for mesh in (welded(lidless), three_fins, four_fins, weld(*finned), doubled, beside):
        bodies, joined = split(*mesh)
        assert len(bodies) == joined == 1
        assert len(bodies[0].faces) == len(mesh[1])
    # solids written double-sided (each box also inverted): a body each, not a box and its inverse
    chair = load_mesh(DATA / "chair_double_sided.obj")
    bodies, joined = split(*chair)
    assert len(bodies) == joined == 7  # five boxes, two sheets
    assert sorted(len(b.faces) for b in bodies) == [4, 4, 24, 24, 24, 24, 24]


def glb_node_names(path) -> list:
    """The names of a GLB file's nodes in the order of its JSON chunk (the
    glTF 2.0 layout: a 12-byte header, the chunk's length and type, the
    JSON), read without trimesh, whose scene graph holds another order."""
    data = Path(path).read_bytes()
    length, kind = struct.unpack_from("<I4s", data, 12)
    assert data[:4] == b"glTF" and kind == b"JSON"
    return [node["name"] for node in json.loads(data[20:20 + length])["nodes"]]


def test_a_scene_splits_by_node_in_world_coordinates(tmp_path):
    scene = trimesh.Scene()
    cube = trimesh.creation.box((1, 1, 1))
    for name, x in (("wheel10", 2.0), ("body", 0.0), ("wheel2", -2.0)):
        mesh = cube if name != "body" else sphere(0.6, (0, 0, 0))
        scene.add_geometry(mesh, node_name=name, geom_name="cube" if mesh is cube else "ball",
                           transform=trimesh.transformations.translation_matrix([x, 0.25 * x, 0]))
    path = tmp_path / "car.glb"
    scene.export(path)
    r = voxelize_meshes([path], resolution=40, split=True)
    nodes = glb_node_names(path)  # the file's order, as its JSON chunk lists the nodes
    assert nodes == ["wheel10", "body", "wheel2"] and r.names == tuple(f"{path}:{n}" for n in nodes)
    placed = {n: g.copy().apply_transform(scene.graph[n][0]) for n, g in
              (("body", sphere(0.6, (0, 0, 0))), ("wheel2", cube), ("wheel10", cube))}
    for i, node in enumerate(nodes, 1):
        assert np.array_equal(r.labels == i, alone(placed[node], r)), node
    whole = voxelize_meshes([path], resolution=40)  # without split: one label
    assert whole.names == (str(path),) and whole.voxels == (sum(r.voxels),)


def test_labels_beyond_255_take_16_bits():
    tets = [trimesh.creation.box((0.5, 0.5, 0.5)).apply_translation((x, y, 0)) for x in range(16) for y in range(17)]
    r = voxelize_meshes([trimesh.util.concatenate(tets)], pitch=0.25, split=True)
    assert len(r.names) == 272 and r.labels.dtype == np.uint16 and int(r.labels.max()) == 272
    assert r.voxels == (8,) * 272


def test_empty_labels_are_said():
    big, tiny = sphere(1.0, (0, 0, 0)), sphere(0.001, (3, 0, 0), 1)
    r = voxelize_meshes([big, tiny, sphere(0.5, (0, 0, 0))], resolution=40)
    assert r.voxels[1] == 0 and "label 2 (mesh 2) got no voxel" in r.note
    covered = voxelize_meshes([sphere(0.5, (0, 0, 0)), big], resolution=40)
    assert covered.voxels[0] == 0 and "label 1 (mesh 1) got no voxel" in covered.note


def test_too_big_is_refused_before_any_mesh_is_voxelised(monkeypatch):
    def boom(*a, **k):
        raise AssertionError("voxelised")

    monkeypatch.setattr(label_voxels, "voxelize", boom)
    a, b = sphere(1.0, (0, 0, 0)), sphere(1.0, (5, 0, 0))
    voxels = 200 * 58 * 58
    budget = int(voxels * 1.125) + 50**3
    # the label array and a bit per voxel fit, not with one sphere's block (about 61^3 bytes) as well
    with pytest.raises(IsoflowError, match=r"needs a 200x58x58 grid .*; at most resolution=\d+ fits$") as e:
        voxelize_meshes([a, b], resolution=200, max_bytes=budget)
    # the command line names its options, not the parameters
    said = e.value.command_line
    assert "--resolution 200 needs" in said and "at most --resolution" in said and "max_bytes" not in said
    # the grid named is let in by the same budget, and is the finest: the next one is not
    monkeypatch.undo()
    fit = e.value.fit
    assert 100 < fit < 200
    assert voxelize_meshes([a, b], resolution=fit, max_bytes=budget).labels.shape[0] == fit
    with pytest.raises(IsoflowError, match=f"resolution={fit + 1} needs"):
        voxelize_meshes([a, b], resolution=fit + 1, max_bytes=budget)


@pytest.mark.parametrize("split", [False, True])
def test_a_pitch_whose_grid_is_past_float64_is_refused_as_for_one_mesh(split):
    """``--pitch 1e-300`` over two unit boxes asks for a grid of about
    1e300 voxels a side: one mesh alone is refused in one line
    (GridTooLarge), but several meshes (or one with ``split``) raised
    Python's OverflowError from the count of the bytes of a block. They are
    refused as one mesh is, with the same finest pitch that fits."""
    a, b = trimesh.creation.box((1, 1, 1)), trimesh.creation.box((1, 1, 1))
    b.apply_translation((3, 0, 0))
    budget = 10**8
    with pytest.raises(IsoflowError, match=r"^voxelize: pitch=1e-300 needs a .*grid") as one:
        voxelize(trimesh.util.concatenate([a, b]).vertices, trimesh.util.concatenate([a, b]).faces, pitch=1e-300,
                 max_bytes=budget)
    meshes = [trimesh.util.concatenate([a, b])] if split else [a, b]
    with pytest.raises(IsoflowError, match=r"^voxelize_meshes: pitch=1e-300 needs a .*grid") as several:
        voxelize_meshes(meshes, pitch=1e-300, split=split, max_bytes=budget)
    assert "\n" not in str(several.value)
    assert several.value.fit > 0 and one.value.fit > 0


def test_bad_input_is_one_line_naming_it(tmp_path):
    with pytest.raises(IsoflowError, match="overlap must be one of later, error"):
        voxelize_meshes([sphere(1, (0, 0, 0))], overlap="first")
    with pytest.raises(IsoflowError, match="no meshes given"):
        voxelize_meshes([])
    with pytest.raises(IsoflowError, match="nothing.stl: no such file or directory"):
        voxelize_meshes([tmp_path / "nothing.stl"])
    with pytest.raises(IsoflowError, match="mesh 2: faces must have shape"):
        voxelize_meshes([sphere(1, (0, 0, 0)), (np.zeros((3, 3)), np.zeros((1, 2), int))])
    assert len(mesh_bodies([DATA / "panel.obj"])) == 1


def smallest_budget(call, hi: int) -> int:
    """The smallest ``max_bytes`` that ``call(max_bytes)`` accepts (bisection; refusals come before any work)."""
    lo = 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        try:
            call(mid)
        except IsoflowError:
            lo = mid
        else:
            hi = mid
    return hi


def test_overlapping_meshes_stay_within_the_budget_they_were_accepted_in():
    # meshes overlapping over most of their blocks: every shared voxel is
    # marked in the overlap bits, by tracemalloc's count (numpy reports its
    # allocations to it) within the smallest budget the grid was let in
    import tracemalloc

    a = trimesh.creation.box((1, 1, 1))
    b = a.copy().apply_translation((0.2, 0, 0))
    budget = smallest_budget(lambda m: voxelize_meshes([a, b], resolution=120, max_bytes=m), 1 << 30)
    voxelize_meshes([a, b], resolution=24)  # numba's compiled code, loaded once, is no temporary
    tracemalloc.start()
    try:
        r = voxelize_meshes([a, b], resolution=120, max_bytes=budget)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert r.overlap_voxels > 0.6 * r.labels.size
    assert peak <= budget, (peak, budget)


def test_a_small_box_on_a_grid_shared_with_a_larger_mesh_is_not_called_thin():
    # a cube 4 voxels across, its sides on the planes between voxels, beside a
    # larger box: its shell on the shared grid took in the voxels past each
    # side that only touch it (208 against its 64 voxels), so it was told the
    # winding rule "leaves 64 voxels in" a surface that "bounds little volume",
    # and offered --fill flood (216 voxels); voxelised alone, it had no note
    pitch = 0.25
    big = trimesh.creation.box(extents=(4, 4, 4))
    # the cubes' lowest corners on voxel corners of the shared grid (its origin is the big box's, -2)
    small = {n: trimesh.creation.box(extents=(n * pitch,) * 3, transform=trimesh.transformations.translation_matrix(
        np.array((4, 4 * k, 0)) + n * pitch / 2)) for k, n in enumerate((2, 3, 4, 6))}
    r = voxelize_meshes([big, *small.values()], pitch=pitch)
    for label, (n, box) in enumerate(small.items(), 2):
        centres = r.origin + pitch * (np.argwhere(np.ones(r.labels.shape, bool)) + 0.5)
        assert r.voxels[label - 1] == int(box.contains(centres).sum()) == n**3  # trimesh's count: the whole cube
        assert r.notes[label - 1] is None, (n, r.notes[label - 1])
        one = voxelize(box.vertices, box.faces, pitch=pitch, details=True)  # on a grid of its own
        assert one.voxels == n**3 and one.note is None
    # a closed plate thinner than a voxel still gets the note on the shared grid
    plate = trimesh.creation.box(extents=(3, 3, 0.05), transform=trimesh.transformations.translation_matrix((0, -4, 0)))
    thin = voxelize_meshes([big, plate], pitch=pitch)
    assert thin.voxels[1] == 0 and "the winding rule leaves no voxel in" in thin.notes[1]


def test_the_split_bodies_of_one_file_that_overlap_are_said_to_be_bodies(tmp_path):
    # two interpenetrating balls written as one file: with --split each is a
    # body of the file, and the note and the refusal called them "meshes"
    a, b = sphere(1.0, (0, 0, 0)), sphere(0.8, (1.1, 0.3, -0.2))
    trimesh.util.concatenate([a, b]).export(tmp_path / "two.stl")
    r = voxelize_meshes([tmp_path / "two.stl"], resolution=48, split=True)
    centres = r.origin + r.pitch * (np.argwhere(np.ones(r.labels.shape, bool)) + 0.5)
    # trimesh's count of the voxels in both, asked only of the centres in both
    # circumscribed balls: an icosphere is the hull of points on its sphere,
    # so no centre outside the ball is inside it, and trimesh's ray test is
    # slow on the whole grid
    near = (np.linalg.norm(centres, axis=1) <= 1.0 + 1e-9) & (np.linalg.norm(centres - (1.1, 0.3, -0.2), axis=1) <= 0.8 + 1e-9)
    shared = int((a.contains(centres[near]) & b.contains(centres[near])).sum())
    assert r.overlap_voxels == shared > 100
    assert f"{shared} voxels lie inside two or more bodies (labels 1 and 2: {shared})" in r.note
    assert "the later body's label wins" in r.note and "mesh" not in r.note
    with pytest.raises(IsoflowError, match=rf"the bodies overlap: {shared} voxels lie inside two or more bodies"):
        voxelize_meshes([tmp_path / "two.stl"], resolution=48, split=True, overlap="error")
    # meshes given as meshes keep their word
    assert "inside two or more meshes" in voxelize_meshes([a, b], resolution=48).note


def centre_count(mesh: trimesh.Trimesh, origin, pitch: float, shape) -> int:
    """trimesh's count of the voxel centres of the grid inside ``mesh``."""
    return int(mesh.contains(origin + pitch * (np.argwhere(np.ones(shape, bool)) + 0.5)).sum())


@pytest.mark.parametrize("n", [2, 3, 4])
@pytest.mark.parametrize("off", [0.5, 0.3])
def test_a_closed_cube_off_the_planes_is_judged_by_its_own_volume(n, off):
    # a closed cube n voxels across, off of a voxel off the planes between
    # voxels, on a grid shared with a larger box: its shell is about as large
    # as the cube however it lies (56 against 27 for n = 3), yet its voxels
    # are its volume (n**3 voxel volumes), and the fills would add the shell
    pitch = 0.25
    big = trimesh.creation.box(extents=(4, 4, 4))  # the shared grid's planes at -2 + k * pitch
    cube = trimesh.creation.box(extents=(n * pitch,) * 3,
                                transform=trimesh.transformations.translation_matrix([3 + (off + n / 2) * pitch] * 3))
    r = voxelize_meshes([big, cube], pitch=pitch)
    assert r.voxels[1] == centre_count(cube, r.origin, pitch, r.labels.shape) == n**3
    assert r.notes[1] is None, r.notes[1]
    # alone, on the shared grid (a grid where it is small) and on its own
    alone = voxelize(cube.vertices, cube.faces, pitch=pitch, grid=(r.origin, r.labels.shape), details=True)
    assert alone.voxels == n**3 and alone.note is None, alone.note
    own = voxelize(cube.vertices, cube.faces, pitch=pitch, details=True)
    assert own.voxels == centre_count(cube, own.origin, pitch, own.volume.shape) == n**3 and own.note is None


@pytest.mark.parametrize("lift", [0.35, 0.1])
def test_a_closed_plate_thinner_than_a_voxel_keeps_the_note(lift):
    # 0.3 of a voxel thick, its lower side lift voxels above a plane: across
    # the centres of a layer (twelve by twelve voxels, over three times its
    # volume) or between two layers (none)
    pitch = 0.25
    big = trimesh.creation.box(extents=(4, 4, 4))
    plate = trimesh.creation.box(extents=(3, 3, 0.3 * pitch), transform=trimesh.transformations.translation_matrix(
        (3 + 0.3 * pitch + 1.5, 0.3 * pitch, (lift + 0.15) * pitch)))
    r = voxelize_meshes([big, plate], pitch=pitch)
    assert r.voxels[1] == centre_count(plate, r.origin, pitch, r.labels.shape) == (144 if lift == 0.35 else 0)
    assert r.voxels[1] > 2 * plate.volume / pitch**3 or r.voxels[1] == 0
    assert r.notes[1] is not None and "the winding rule leaves" in r.notes[1]
    # a layer over twice the volume: a finer grid follows the plate, the fills would give the layer again;
    # no voxel: the fills give the plate's voxels
    assert ("a finer grid follows them" in r.notes[1]) == (lift == 0.35) != ("--fill flood" in r.notes[1])
    alone = voxelize(plate.vertices, plate.faces, pitch=pitch, grid=(r.origin, r.labels.shape), details=True)
    assert alone.voxels == r.voxels[1] and alone.note == r.notes[1]


def test_the_shell_command_says_no_thin_note_for_a_small_cube_beside_a_big_box(tmp_path):
    # isoflow voxelize big.stl small.stl --pitch P: the cube 3 voxels across,
    # half a voxel off the planes, has its 27 voxels and no note; a plate 0.3
    # of a voxel thick across a layer of centres keeps it
    pitch = 0.25
    big = trimesh.creation.box(extents=(4, 4, 4))
    cube = trimesh.creation.box(extents=(3 * pitch,) * 3, transform=trimesh.transformations.translation_matrix(
        [3 + 2 * pitch] * 3))
    plate = trimesh.creation.box(extents=(3, 3, 0.3 * pitch), transform=trimesh.transformations.translation_matrix(
        (0, -4, 0.5 * pitch)))
    names = []
    for name, mesh in (("big", big), ("small", cube), ("plate", plate)):
        mesh.export(tmp_path / f"{name}.stl")
        names.append(str(tmp_path / f"{name}.stl"))
    p = subprocess.run([sys.executable, "-m", "isoflow", "voxelize", *names[:2], "--pitch", str(pitch), "-o",
                        str(tmp_path / "out.npz")], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "winding rule leaves" not in p.stderr and "small.stl" not in p.stderr, p.stderr
    labels = np.load(tmp_path / "out.npz")["volume"]
    assert int((labels == 2).sum()) == 27
    p = subprocess.run([sys.executable, "-m", "isoflow", "voxelize", names[0], names[2], "--pitch", str(pitch), "-o",
                        str(tmp_path / "plate.npz")], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert "plate.stl" in p.stderr and "the winding rule leaves" in p.stderr, p.stderr
