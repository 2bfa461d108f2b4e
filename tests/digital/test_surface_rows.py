"""The boundary mesh from the bit rows (``method="compiled"``) equals the
NumPy mesh (the oracle, ``method="numpy"``): the same vertices with every
attribute, the same faces with the same corners, sheets, midpoints and
normals, up to the order of vertices and faces."""

import numpy as np
import pytest
import trimesh
from conftest import ball, random_volume, torus

from isoflow import DigitalObject, boundary_mesh, euler_characteristic
from isoflow.digital.surface import mesh_method
from isoflow.mesh import export
from isoflow.mesh.readback import check_surface_file
from isoflow.scale.compiled import least_voxels, using

ATTRIBUTES = ("config", "sheet", "vertex_class", "gamma", "a", "f", "code", "normal")


def canonical(mesh) -> tuple[list, set]:
    """The mesh without its numbering: a sorted list of vertex keys and a
    set of faces. A lattice vertex is its position, sheet and attributes; a
    midpoint its position, attributes and the two faces that share it; a
    face its normal, lowest corner and the keys of its corners and edge
    midpoints in order, starting at the lowest corner."""
    pos = np.round(2 * mesh.vertices).astype(np.int64)
    attrs = [np.asarray(getattr(mesh, name)).reshape(len(pos), -1) if len(pos) else None for name in ATTRIBUTES]
    lowest = pos[mesh.faces].min(axis=1)
    face_id = [(tuple(n), tuple(low)) for n, low in zip(mesh.face_normals.tolist(), lowest.tolist())]
    users: dict[int, list] = {}
    for f, row in enumerate(mesh.edge_midpoint.tolist()):
        for m in row:
            if m >= 0:
                users.setdefault(m, []).append(face_id[f])
    assert all(len(u) == 2 for u in users.values()), "a midpoint is on two faces, one pair"
    keys = []
    for v in range(len(pos)):
        own = tuple(tuple(a[v].tolist()) for a in attrs)
        keys.append((tuple(pos[v].tolist()), own, tuple(sorted(users[v])) if v in users else ()))
    faces = set()
    for f, (corners, mids) in enumerate(zip(mesh.faces.tolist(), mesh.edge_midpoint.tolist())):
        seq = [(keys[c], keys[m] if m >= 0 else None) for c, m in zip(corners, mids)]
        start = min(range(4), key=lambda t: keys[corners[t]][0])
        faces.add((face_id[f], tuple(seq[start:] + seq[:start])))
    assert len(faces) == len(mesh.faces)
    return sorted(keys), faces


def assert_same_mesh(volume, connectivity, threads=None):
    with using(threads):
        ours = boundary_mesh(volume, connectivity, method="compiled")
    ref = boundary_mesh(volume, connectivity, method="numpy")
    assert ours.pinched == ref.pinched and ours.connectivity == ref.connectivity
    assert ours.faces.dtype == ref.faces.dtype == ours.edge_midpoint.dtype
    assert len(ours.vertices) == len(ref.vertices) and len(ours.faces) == len(ref.faces)
    assert canonical(ours) == canonical(ref)
    return ours


def contact_volume(rng, side: int) -> np.ndarray:
    """Random voxels with planted edge and vertex contacts (two voxels, or
    two background cells, meeting at an edge or a point only)."""
    v = rng.random((side, side + 1, side + 2)) < rng.uniform(0.2, 0.8)
    for _ in range(3):
        x, y, z = rng.integers(0, side - 1, 3)
        cube = np.zeros((2, 2, 2), bool)
        if rng.random() < 0.5:
            cube[0, 0, 0] = cube[1, 1, 1] = True  # a vertex contact
        else:
            cube[0, 0, :] = cube[1, 1, :] = True  # an edge contact
        v[x:x + 2, y:y + 2, z:z + 2] = cube ^ (rng.random() < 0.5)  # of the object or of the background
    return v


@pytest.mark.parametrize("conn", [6, 26])
def test_random_volumes_with_contacts(rng, conn):
    seen_pinch = seen_midpoint = 0
    for _ in range(120):
        v = random_volume(rng, 7)
        m = assert_same_mesh(v, conn)
        seen_pinch += m.pinched > 0
        seen_midpoint += m.midpoints > 0
    for side in (3, 6, 11):
        for _ in range(6):
            m = assert_same_mesh(contact_volume(rng, side), conn)
            seen_pinch += m.pinched > 0
            seen_midpoint += m.midpoints > 0
    assert seen_pinch and seen_midpoint  # the hard cases did occur


@pytest.mark.parametrize("conn", [6, 26])
@pytest.mark.parametrize("threads", [2, 3, 5])
def test_slabs_on_threads_meet_at_their_seams(rng, conn, threads):
    # slabs of a few vertex planes each, seams through contacts and pinches
    v = contact_volume(rng, 13)
    with using(threads):
        m = assert_same_mesh(v, conn)
    assert m.midpoints and m.pinched


@pytest.mark.parametrize("conn", [6, 26])
def test_special_volumes(conn):
    cases = {
        "empty": np.zeros((4, 5, 6), bool),
        "full": np.ones((4, 5, 6), bool),
        "one voxel": np.ones((1, 1, 1), bool),
        "one voxel inside": np.pad(np.ones((1, 1, 1), bool), ((1, 2), (0, 3), (2, 0))),
        "row": np.ones((1, 1, 130), bool),  # three words in the row
        "sheet": np.ones((9, 1, 9), bool),
        "thin diagonal": np.eye(9, dtype=bool)[:, :, None] | np.eye(9, dtype=bool)[:, None, :],
        "ball": ball(5),
        "torus at the border": torus(6, 2)[2:, :-3, 1:],
        "word edges": np.pad(np.ones((2, 3, 64), bool), ((0, 0), (0, 0), (63, 1))),
    }
    for name, v in cases.items():
        m = assert_same_mesh(v, conn)
        if v.any():
            assert m.euler_characteristic == 2 * euler_characteristic(v, conn) + 2 * m.pinched, name
        else:
            assert len(m.vertices) == len(m.faces) == 0


def test_memory_orders_and_dtypes(rng):
    v = contact_volume(rng, 9)
    # a bool array whose bytes are 7, not 1 (a .view(bool)) is the object
    # too; a uint8 7 is a value other than 0 and 1, refused as analyze does
    sevens = (v.astype(np.uint8) * 7).view(bool)
    for variant in (np.asfortranarray(v), v[::-1, :, ::2], np.swapaxes(v, 0, 2), v.astype(np.uint8), sevens,
                    v.astype(np.float32)):
        assert canonical(assert_same_mesh(variant, 26)) == canonical(boundary_mesh(np.asarray(variant) != 0, 26))
    assert_same_mesh(np.asfortranarray(v), 6, threads=2)


@pytest.mark.parametrize("conn", [6, 26])
def test_written_file_reads_back(tmp_path, rng, conn):
    import pymeshlab

    v = contact_volume(rng, 8)
    obj = DigitalObject(v, offset=(1, 2, 3), pitch=0.5, origin=(10.0, 0.0, -1.0))
    m = boundary_mesh(v, conn, method="compiled")
    assert m.midpoints and m.pinched
    for suffix in (".ply", ".obj"):
        path = tmp_path / f"s{conn}{suffix}"
        export.write_mesh_file(path, m, obj)
        check = check_surface_file(path, m, obj, components=m.components())
        assert check["agree"], check["problem"]
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(path))
        topo = ms.get_topological_measures()
        assert topo["boundary_edges"] == 0 and topo["is_mesh_two_manifold"]
        assert topo["genus"] == sum(c["genus"] for c in m.components())
    ply = trimesh.load(tmp_path / f"s{conn}.ply", process=False).metadata["_ply_raw"]["vertex"]["data"]
    assert ply["a"].astype(int).sum() == 8 * euler_characteristic(v, conn)
    assert sorted(ply["config"].ravel()) == sorted(boundary_mesh(v, conn, method="numpy").config)


def test_method_choice():
    small, large = np.zeros((4, 4, 4), bool), np.zeros(least_voxels(surfaces=True), bool).reshape(-1, 100, 100)
    assert mesh_method(small) == "numpy" and mesh_method(large) == "compiled"
    assert mesh_method(large, "numpy") == "numpy" and mesh_method(small, "compiled") == "compiled"
    with pytest.raises(ValueError, match="method"):
        boundary_mesh(small, method="fast")
