"""The boundary quad mesh: closed, outward, right volume, right Euler number,
checked by trimesh, pymeshlab and manifold3d."""

import numpy as np
import pytest
import trimesh
from conftest import ball, random_volume, torus

from isoflow import DigitalObject, boundary_mesh, euler_characteristic
from isoflow.mesh.export import mesh_vertex_table, write_obj, write_ply


def as_trimesh(mesh):
    return trimesh.Trimesh(mesh.vertices, mesh.triangles(), process=False)


@pytest.mark.parametrize("conn", [6, 26])
def test_random_volumes_give_closed_manifolds(rng, conn):
    seen_pinch = seen_double = 0
    for _ in range(250):
        v = random_volume(rng, 6)
        if not v.any():
            continue
        m = boundary_mesh(v, conn)
        tm = as_trimesh(m)
        chi = euler_characteristic(v, conn)
        assert tm.is_watertight and tm.is_winding_consistent
        assert tm.volume == pytest.approx(v.sum())
        assert (tm.area_faces > 0).all()
        # docs/mathematics.md: V - E + F = 2 chi + 2 p with the pinches split
        assert tm.euler_number == m.euler_characteristic == 2 * chi + 2 * m.pinched
        assert m.a.sum() == 8 * chi
        seen_pinch += m.pinched > 0
        seen_double += m.midpoints > 0
    assert seen_pinch and seen_double  # the hard cases did occur


def test_faces_point_outward():
    v = ball(5)
    m = boundary_mesh(v)
    # the centroid of every face lies outside the object along its normal
    centre = m.vertices[m.faces].mean(axis=1)
    outside = np.floor(centre + 0.5 * m.face_normals).astype(int)
    inside = np.floor(centre - 0.5 * m.face_normals).astype(int)
    assert not v[tuple(outside.T)].any() if (outside >= 0).all() and (outside < v.shape[0]).all() else True
    assert v[tuple(inside.T)].all()
    tm = as_trimesh(m)
    assert np.allclose(tm.face_normals[0::2], m.face_normals)


def test_surface_components_and_genus():
    ring = torus(6, 2)
    comps = boundary_mesh(ring).components()
    assert [c["genus"] for c in comps] == [1]
    two = np.concatenate([ring, ring], axis=0)
    assert [c["genus"] for c in boundary_mesh(two).components()] == [1, 1]
    solid = ball(6)
    hollow = solid & ~ball(3, size=solid.shape[0])
    assert [c["genus"] for c in boundary_mesh(hollow).components()] == [0, 0]


def test_edge_contact_follows_connectivity():
    v = np.zeros((2, 2, 1), bool)
    v[0, 0, 0] = v[1, 1, 0] = True
    apart = boundary_mesh(v, 6)
    joined = boundary_mesh(v, 26)
    assert len(apart.components()) == 2 and len(apart.vertices) == 16
    # 26: two cubes glued along an edge form one sphere (chi 2) whose sheet
    # passes the shared edge twice: 14 lattice vertices plus one midpoint on
    # each copy of the edge
    assert len(joined.components()) == 1
    assert (joined.sheet >= 0).sum() == 14 and joined.midpoints == 2
    assert joined.euler_characteristic == 2 == 2 * euler_characteristic(v, 26)


def test_vertex_contact_is_split_and_counted():
    v = np.zeros((2, 2, 2), bool)
    v[0, 0, 0] = v[1, 1, 1] = True
    assert boundary_mesh(v, 6).pinched == 0
    m = boundary_mesh(v, 26)
    assert m.pinched == 1 and len(m.components()) == 2
    assert m.euler_characteristic == 2 * euler_characteristic(v, 26) + 2


def test_matches_manifold3d_and_pymeshlab():
    import manifold3d
    import pymeshlab

    v = torus(7, 3) | ball(4, size=torus(7, 3).shape[0])
    m = boundary_mesh(v)
    mf = manifold3d.Manifold(
        manifold3d.Mesh(vert_properties=m.vertices.astype(np.float32), tri_verts=m.triangles().astype(np.uint32))
    )
    assert mf.volume() == pytest.approx(v.sum())
    assert mf.genus() == 1 - m.euler_characteristic // 2
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(m.vertices, m.triangles()))
    topo = ms.get_topological_measures()
    assert topo["boundary_edges"] == 0
    assert topo["is_mesh_two_manifold"]
    assert topo["genus"] == sum(c["genus"] for c in m.components())


@pytest.mark.parametrize("ascii", [False, True])
def test_ply_export_loads_with_quads_and_attributes(tmp_path, ascii):
    import pymeshlab

    rng = np.random.default_rng(7)
    v = rng.random((5, 5, 5)) < 0.5  # with non-well-composed places
    obj = DigitalObject(v, offset=(1, 2, 3), pitch=0.5, origin=(10.0, 0.0, -1.0))
    m = boundary_mesh(v)
    path = write_ply(tmp_path / "s.ply", mesh_vertex_table(m, obj), m.polygons(), ascii=ascii)
    header = path.read_bytes().split(b"end_header")[0].decode()
    for name in ("config", "gamma", "a", "f", "red", "green", "blue"):
        assert f" {name}\n" in header
    tm = trimesh.load(path, process=False)
    assert tm.is_watertight
    assert tm.volume == pytest.approx(v.sum() * 0.5**3)
    assert np.allclose(tm.bounds[0], obj.world(np.argwhere(v).min(axis=0)))
    ply = tm.metadata["_ply_raw"]["vertex"]["data"]
    assert (ply["config"].ravel() == m.config).all()
    assert ply["a"].astype(int).ravel().sum() == 8 * euler_characteristic(v)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    assert ms.current_mesh().vertex_number() == len(m.vertices)
    assert ms.get_topological_measures()["boundary_edges"] == 0


def test_obj_export_loads(tmp_path):
    v = torus(6, 2)
    m = boundary_mesh(v)
    path = write_obj(tmp_path / "t.obj", m.vertices, m.polygons())
    tm = trimesh.load(path, process=False)
    assert tm.is_watertight and tm.euler_number == 0
    assert tm.volume == pytest.approx(v.sum())
    assert sum(1 for line in path.read_text().splitlines() if line.startswith("f ")) == len(m.faces)
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    topo = ms.get_topological_measures()
    assert ms.current_mesh().vertex_number() == len(m.vertices)
    assert topo["boundary_edges"] == 0 and topo["genus"] == 1


def test_refuses_to_overwrite(tmp_path):
    from isoflow.errors import IsoflowError

    m = boundary_mesh(ball(2))
    p = tmp_path / "x.obj"
    write_obj(p, m.vertices, m.faces)
    with pytest.raises(IsoflowError, match="exists"):
        write_obj(p, m.vertices, m.faces)
    write_obj(p, m.vertices, m.faces, force=True)
