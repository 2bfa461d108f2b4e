"""Several meshes into one label image (issue 25 item 6): the block of the
grid each mesh fills is the whole grid's, bit for bit; the labels, the
overlap counts and the rule are checked against every mesh voxelised alone
on the same grid; bodies against trimesh's split and a scene's nodes."""

from pathlib import Path

import numpy as np
import pytest
import trimesh

from isoflow import IsoflowError, voxelize_meshes
from isoflow.mesh import label_voxels
from isoflow.mesh.bodies import mesh_bodies
from isoflow.mesh.load import load_mesh
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
    assert r.names == (f"{path}:body", f"{path}:wheel2", f"{path}:wheel10")  # natural order of the names
    placed = {n: g.copy().apply_transform(scene.graph[n][0]) for n, g in
              (("body", sphere(0.6, (0, 0, 0))), ("wheel2", cube), ("wheel10", cube))}
    for i, node in enumerate(("body", "wheel2", "wheel10"), 1):
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
    # the label array and a bit per voxel fit, not with one sphere's block (about 61^3 bytes) as well
    with pytest.raises(IsoflowError, match="needs a 200x58x58 grid .*coarser resolution= or pitch=") as e:
        voxelize_meshes([a, b], resolution=200, max_bytes=int(voxels * 1.125) + 50**3)
    # the command line names its options, not the parameters
    said = e.value.command_line
    assert "--resolution 200 needs" in said and "coarser --resolution or --pitch" in said and "max_bytes" not in said


def test_bad_input_is_one_line_naming_it(tmp_path):
    with pytest.raises(IsoflowError, match="overlap must be one of later, error"):
        voxelize_meshes([sphere(1, (0, 0, 0))], overlap="first")
    with pytest.raises(IsoflowError, match="no meshes given"):
        voxelize_meshes([])
    with pytest.raises(IsoflowError, match="nothing.stl: file not found"):
        voxelize_meshes([tmp_path / "nothing.stl"])
    with pytest.raises(IsoflowError, match="mesh 2: faces must have shape"):
        voxelize_meshes([sphere(1, (0, 0, 0)), (np.zeros((3, 3)), np.zeros((1, 2), int))])
    assert len(mesh_bodies([DATA / "panel.obj"])) == 1
