"""The read-back of a GLB (isoflow.mesh.readback.trimesh_figures) reads
the nodes trimesh's glTF reader gives, placed by their transforms and
joined, without trimesh.load's scene dump (two copies of the mesh, each
deriving face colours from the vertex colours). What it finds must be
what trimesh.load(path, force="mesh", process=False) gives: trimesh's own
is_watertight, euler_number, body count and volume, on isoflow's files
(26-connected with midpoints, far from the origin under a node
transform) and on scenes trimesh writes (several nodes, transforms,
colours)."""

import numpy as np
import pytest
import trimesh

from isoflow import DigitalObject, boundary_mesh, write_surface
from isoflow.mesh import readback


def as_trimesh_loads(path):
    loaded = trimesh.load(path, force="mesh", process=False)
    bodies = int(loaded.body_count) - int(np.count_nonzero(~loaded.referenced_vertices))
    return {"watertight": bool(loaded.is_watertight), "euler_number": int(loaded.euler_number), "bodies": bodies,
            "volume": float(loaded.volume)}


def assert_reads_as_trimesh(path):
    ours, theirs = readback.trimesh_figures(path), as_trimesh_loads(path)
    assert ours["watertight"] == theirs["watertight"]
    assert ours["euler_number"] == theirs["euler_number"]
    if theirs["watertight"] and theirs["euler_number"] % 2 == 0:
        assert ours["genus"] == theirs["bodies"] - theirs["euler_number"] // 2
    assert ours["volume"] == pytest.approx(theirs["volume"], rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("origin", [(0.0, 0.0, 0.0), (4e6 + 0.1, 0.0, -3e5)])
@pytest.mark.parametrize("conn", [6, 26])
def test_isoflows_glb_reads_as_trimesh_load_reads_it(tmp_path, rng, conn, origin):
    volume = rng.random((9, 8, 7)) < 0.45  # edge and vertex contacts: midpoints at 26, pinches at 6
    obj = DigitalObject(volume, pitch=(0.5, 1.0, 2.0), origin=origin)
    path = tmp_path / "s.glb"
    write_surface(obj, path, connectivity=conn)
    assert_reads_as_trimesh(path)
    mesh = boundary_mesh(volume, conn)
    assert readback.trimesh_figures(path)["euler_number"] == mesh.euler_characteristic


def test_a_scene_of_several_nodes_with_transforms_and_colours(tmp_path):
    scene = trimesh.Scene()
    box = trimesh.creation.box()
    box.visual.vertex_colors = np.tile([200, 30, 30, 255], (len(box.vertices), 1))
    torus = trimesh.creation.torus(2.0, 0.5)
    scene.add_geometry(box, node_name="a", transform=trimesh.transformations.translation_matrix([5.0, 0.0, 0.0]))
    scene.add_geometry(torus, node_name="b", transform=trimesh.transformations.rotation_matrix(0.3, [0, 0, 1]))
    scene.add_geometry(box, node_name="c", geom_name="box_again")
    path = tmp_path / "scene.glb"
    scene.export(path)
    assert_reads_as_trimesh(path)
    figures = readback.trimesh_figures(path)
    assert figures["euler_number"] == 2 + 0 + 2 and figures["genus"] == 1  # two boxes and a torus
