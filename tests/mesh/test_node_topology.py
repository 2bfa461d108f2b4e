"""The topology of many disjoint triangle meshes in one pass
(isoflow.mesh.node_topology), node by node against trimesh's own figures of
each mesh; and the nodes of a glTF scene as the read-back places them
(isoflow.mesh.readback.scene_nodes) against trimesh's scene graph."""

import numpy as np
import pytest
import trimesh

from isoflow.digital.surface import boundary_mesh
from isoflow.mesh.node_topology import node_topology, node_volumes
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
    faces = np.concatenate([f + at for (_, f), at in zip(parts, vfirst)])
    found = node_topology(faces, vfirst, ffirst)
    # far from the origin and in small units, as a world-placed node
    units = np.full(len(parts), 0.25)
    volumes = node_volumes(np.concatenate([v for v, _ in parts]) * 0.25 + 1e5, faces, vfirst, ffirst, units)
    assert found["closed"][:12].all() and not found["closed"][12:16].any() and found["closed"][16]
    for t, (vertices, triangles) in enumerate(parts):
        tm = trimesh.Trimesh(vertices, triangles, process=False)
        assert found["closed"][t] == (tm.is_watertight and tm.is_winding_consistent), t
        used = np.count_nonzero(tm.referenced_vertices)
        assert found["vertices"][t] == used
        assert found["bodies"][t] == tm.body_count - (len(vertices) - used), t
        assert found["edges"][t] == len(tm.edges_unique), t
        assert found["euler"][t] == tm.euler_number, t
        if found["closed"][t]:
            assert volumes[t] == pytest.approx(tm.volume, rel=1e-12), t  # trimesh's, in voxel units


def test_a_triangle_naming_another_nodes_vertex_is_not_closed():
    tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    faces = np.concatenate([tet, tet + 4])
    faces[5, 0] = 2  # the second node's triangle on the first node's vertex
    found = node_topology(faces, np.array([0, 4, 8]), np.array([0, 4, 8]))
    assert found["closed"].tolist() == [True, False] and found["bodies"].tolist() == [1, -1]
    assert found["edges"].tolist() == [6, -1]
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    volumes = node_volumes(np.concatenate([corners, corners]), faces, [0, 4, 8], [0, 4, 8])
    assert volumes[0] == pytest.approx(1 / 6) and np.isnan(volumes[1])


def test_a_triangle_naming_a_vertex_far_below_its_node_writes_nothing_outside_the_scratch():
    """A corner before the node's first vertex, met as the second end of an
    edge, is refused before it indexes the scratch: the pass as Python runs
    it (whose indexing raises where the compiled pass would write outside
    the array) gives the node as not closed, as trimesh's check would."""
    from isoflow.mesh.node_topology import _node

    tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    faces = np.concatenate([tet, tet + 4, tet + 8])
    faces[8, 1] = 0  # the third node's triangle on the first node's vertex 0, eight below its own
    scratch = (np.empty(5, np.int64), np.empty(12, np.int64), np.full(8, -1, np.int64), np.empty(4, np.int64),
               np.empty(4, np.bool_))
    start, keys, mark, parent, used = scratch
    assert _node.py_func(faces, 8, 4, 8, 12, start, keys, mark, parent, used) == (False, -1, -1, -1)
    assert node_topology(faces, np.array([0, 4, 8, 12]), np.array([0, 4, 8, 12]))["bodies"].tolist() == [1, 1, -1]


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


def test_shared_positions_counts_the_positions_trimesh_welds(rng):
    """The positions that carry two mesh vertices or more (what a reader of
    an STL welds): trimesh's merge of the mesh's own vertices removes one
    vertex for each extra copy, on boundary meshes of random objects with
    edge and vertex contacts at 6 and 26, away from the origin too."""
    from types import SimpleNamespace

    from isoflow.mesh.export import shared_positions

    seen = 0
    for t in range(16):
        vol = rng.random((6, 5, 7)) < 0.45
        mesh = boundary_mesh(vol, 6 if t % 2 else 26)
        vertices = np.asarray(mesh.vertices, float) - (3.0 if t % 3 else 0.0)
        keys = np.round(2 * vertices).astype(np.int64)
        _, counts = np.unique(keys, axis=0, return_counts=True)
        want = int(np.count_nonzero(counts > 1))
        assert shared_positions(SimpleNamespace(vertices=vertices)) == want, t
        merged = trimesh.Trimesh(vertices, np.zeros((0, 3), np.int64), process=False)
        merged.merge_vertices(merge_tex=True, merge_norm=True)
        assert len(vertices) - len(merged.vertices) == (counts - 1).sum()
        seen += want
    assert seen > 0
    assert shared_positions(SimpleNamespace(vertices=np.zeros((0, 3)))) == 0
