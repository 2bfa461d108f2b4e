"""The topology of many disjoint triangle meshes in one pass
(isoflow.mesh.node_topology), node by node against trimesh's own figures of
each mesh; and the nodes of a glTF scene as the read-back places them
(isoflow.mesh.readback.scene_nodes) against trimesh's scene graph."""

import numpy as np
import pytest
import trimesh

from isoflow.digital.surface import boundary_mesh
from isoflow.mesh.node_topology import node_topology
from isoflow.mesh.readback import scene_nodes


def meshes(rng, count):
    """Boundary meshes of random objects (edge and vertex contacts, at 6
    and 26, some of several bodies), as (vertices, triangles), and the same
    damaged: a triangle lost, a triangle turned over, a triangle twice, a
    triangle with a vertex repeated, a vertex no triangle uses."""
    out = []
    for t in range(count):
        vol = rng.random((5, 4, 6)) < 0.4
        vol[1, 1, 1] = vol[2, 2, 2] = True  # a vertex contact at 26, two bodies at 6
        vol[1, 2, 2] = vol[2, 1, 1] = vol[1, 1, 2] = vol[2, 2, 1] = vol[1, 2, 1] = vol[2, 1, 2] = False
        mesh = boundary_mesh(vol, 6 if t % 2 else 26)
        out.append((np.asarray(mesh.vertices, float), mesh.triangles().astype(np.int64)))
    vertices, triangles = out[0]
    out.append((vertices, triangles[1:]))
    out.append((vertices, np.concatenate([triangles[:1, ::-1], triangles[1:]])))
    out.append((vertices, np.concatenate([triangles, triangles[:1]])))
    out.append((vertices, np.concatenate([triangles[:-1], [[triangles[-1, 0], triangles[-1, 0], triangles[-1, 1]]]])))
    out.append((np.concatenate([vertices, [[9.0, 9.0, 9.0]]]), triangles))
    return out


def test_every_node_as_trimesh_measures_it_alone(rng):
    parts = meshes(rng, 12)
    vfirst = np.concatenate([[0], np.cumsum([len(v) for v, _ in parts])])
    ffirst = np.concatenate([[0], np.cumsum([len(f) for _, f in parts])])
    found = node_topology(np.concatenate([f + at for (_, f), at in zip(parts, vfirst)]), vfirst, ffirst)
    assert found["closed"][:12].all() and not found["closed"][12:16].any() and found["closed"][16]
    for t, (vertices, triangles) in enumerate(parts):
        tm = trimesh.Trimesh(vertices, triangles, process=False)
        assert found["closed"][t] == (tm.is_watertight and tm.is_winding_consistent), t
        used = np.count_nonzero(tm.referenced_vertices)
        assert found["vertices"][t] == used
        assert found["bodies"][t] == tm.body_count - (len(vertices) - used), t
        if found["closed"][t]:
            assert found["euler"][t] == tm.euler_number, t


def test_a_triangle_naming_another_nodes_vertex_is_not_closed():
    tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    faces = np.concatenate([tet, tet + 4])
    faces[5, 0] = 2  # the second node's triangle on the first node's vertex
    found = node_topology(faces, np.array([0, 4, 8]), np.array([0, 4, 8]))
    assert found["closed"].tolist() == [True, False] and found["bodies"].tolist() == [1, -1]


@pytest.mark.parametrize("nested", [False, True])
def test_scene_nodes_placed_as_trimesh_places_them(tmp_path, nested):
    scene = trimesh.Scene()
    box, ball = trimesh.creation.box(), trimesh.creation.icosphere(1)
    move = trimesh.transformations.translation_matrix([5.0, -2.0, 0.5])
    turn = trimesh.transformations.rotation_matrix(0.7, [0, 0, 1], [1.0, 2.0, 3.0])
    scene.add_geometry(box, node_name="box", geom_name="box", transform=move)
    scene.add_geometry(ball, node_name="ball", geom_name="ball", transform=turn, parent_node_name="box" if nested else None)
    path = tmp_path / "s.glb"
    scene.export(path)
    read = trimesh.load(path, force="scene", process=False)
    nodes = scene_nodes(path)
    assert sorted(nodes) == sorted(read.graph.nodes_geometry)
    for name, (vertices, triangles) in nodes.items():
        transform, geometry = read.graph[name]
        tm = read.geometry[geometry]
        np.testing.assert_array_equal(triangles, tm.faces)
        np.testing.assert_allclose(vertices, trimesh.transform_points(tm.vertices, transform), atol=1e-9)
    if nested:  # the ball under the box: both transforms apply
        np.testing.assert_allclose(nodes["ball"][0].mean(axis=0), (move @ turn)[:3, 3], atol=1e-6)
