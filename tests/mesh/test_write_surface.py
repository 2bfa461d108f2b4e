"""``isoflow.write_surface``: the Python call that writes the file ``isoflow
surface`` writes, read back by trimesh and pymeshlab and held to the
counts of ``analyze`` (docs/formats.md, "Surface files")."""

from __future__ import annotations

import contextlib
import io
import warnings

import numpy as np
import pymeshlab
import pytest
import trimesh

import isoflow
from isoflow import IsoflowError, IsoflowWarning
from isoflow.cli import main

RING = [(0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 1, 2), (1, 0, 0), (1, 0, 1), (1, 0, 2), (1, 1, 2)]
PITCH, ORIGIN = 0.5, (1.0, -2.0, 3.25)

# (suffix, ascii, triangulate): every file the command writes
FILES = [(".ply", False, False), (".ply", True, False), (".obj", False, False), (".stl", False, False),
         (".glb", False, False), (".ply", False, True), (".obj", False, True)]


def object_with_contacts() -> isoflow.DigitalObject:
    """The ring of eight voxels (doubled edges at 6: pentagons) and two
    voxels meeting at a vertex (a split vertex at 6), placed off the
    origin with voxels of 0.5."""
    v = np.zeros((6, 4, 5), bool)
    v[tuple((np.array(RING) + 1).T)] = True
    v[4, 1, 1] = v[5, 2, 2] = True
    return isoflow.DigitalObject(v, pitch=PITCH, origin=ORIGIN)


def command(tmp_path, obj, out, *options) -> None:
    src = isoflow.write_volume(obj, tmp_path / "in.npz", force=True)
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = main(["surface", str(src), "-o", str(out), "--connectivity", "6", *options])
    assert rc == 0, e.getvalue()


def without_comments(data: bytes) -> bytes:
    """A file's bytes less its first comment line (which names the input or
    the call); everything else is the same file."""
    lines = data.split(b"\n")
    first = next(i for i, line in enumerate(lines) if line.startswith((b"comment ", b"# ")))
    return b"\n".join(lines[:first] + lines[first + 1:])


def pymeshlab_euler(path) -> int:
    """V - E + F of the file as pymeshlab reads it, once it is seen to be a
    closed two-manifold."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    t = ms.get_topological_measures()
    assert t["boundary_edges"] == 0 and t["is_mesh_two_manifold"]
    return t["vertices_number"] - t["edges_number"] + t["faces_number"]


@pytest.mark.parametrize("suffix,ascii,triangulate", FILES)
def test_the_file_is_the_one_the_command_writes(tmp_path, suffix, ascii, triangulate):
    obj = object_with_contacts()
    report = isoflow.analyze(obj, 6)
    mesh = isoflow.boundary_mesh(obj.volume, 6)
    assert mesh.midpoints and (mesh.sheet > 0).any()  # doubled edges and split copies at contacts
    by_command = tmp_path / f"command{suffix}"
    command(tmp_path, obj, by_command, *(["--ascii"] if ascii else []), *(["--triangulate"] if triangulate else []))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IsoflowWarning)  # the STL's weld, said in test_stl_says_what_readers_do
        path = isoflow.write_surface(obj, tmp_path / f"call{suffix}", ascii=ascii, triangulate=triangulate)
    assert path == tmp_path / f"call{suffix}"
    if suffix == ".glb":  # the comment is in the JSON chunk, whose length it changes
        a, b = (trimesh.load(p, force="mesh", process=False) for p in (by_command, path))
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
        assert all(np.array_equal(a.vertex_attributes[k], b.vertex_attributes[k]) for k in ("_gamma", "_a", "_config"))
    elif suffix == ".stl":  # the 80-byte header says who wrote it, as a PLY's comment does
        assert path.read_bytes()[80:] == by_command.read_bytes()[80:]
        assert path.read_bytes()[:80].rstrip() == b"isoflow write_surface, 6-connectivity"
    else:
        assert without_comments(path.read_bytes()) == without_comments(by_command.read_bytes())
    if suffix == ".stl":  # readers weld the split copies: only the volume is the object's
        assert trimesh.load(path).volume == pytest.approx(obj.voxels * PITCH**3)
        return
    # read back by both readers: closed, the Euler number of analyze's surfaces, in world units
    euler = sum(s["euler_characteristic"] for s in report["surfaces"])
    tm = trimesh.load(path, force="mesh", process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    assert tm.euler_number == euler == 4  # the ring's torus (0) and the two cubes' spheres (2 + 2)
    assert tm.volume == pytest.approx(obj.voxels * PITCH**3)
    assert tm.bounds[0].tolist() == [ORIGIN[0] + PITCH, ORIGIN[1] + PITCH, ORIGIN[2] + PITCH]
    assert pymeshlab_euler(path) == euler
    if suffix == ".ply":
        a = tm.metadata["_ply_raw"]["vertex"]["data"]["a"]
        assert int(a.sum()) == 8 * report["euler_characteristic"] == 16  # chi: torus 0, cubes 1 + 1
    if ascii:  # quads, and pentagons through the midpoints: a face per boundary square
        faces = tm.metadata["_ply_raw"]["face"]["data"]["vertex_indices"]
        assert len(faces) == sum(s["faces"] for s in report["surfaces"]) == 32 + 12


def test_a_bare_array_and_a_mesh_given_write_the_same_file(tmp_path):
    v = object_with_contacts().volume
    first = isoflow.write_surface(v, tmp_path / "a.ply", 26)
    mesh = isoflow.boundary_mesh(v, 26)
    second = isoflow.write_surface(v, tmp_path / "b.ply", mesh=mesh)
    assert first.read_bytes() == second.read_bytes()
    tm = trimesh.load(first, process=False)
    assert tm.bounds[0].tolist() == [1.0, 1.0, 1.0]  # a bare array: voxels of 1 at the origin
    assert tm.euler_number == sum(s["euler_characteristic"] for s in isoflow.analyze(v, 26)["surfaces"])


def test_an_existing_file_is_refused_without_force(tmp_path):
    obj = isoflow.DigitalObject(np.ones((2, 2, 2), bool))
    out = tmp_path / "s.obj"
    out.write_text("taken")
    with pytest.raises(IsoflowError, match=r"s\.obj: exists; pass force=True to overwrite$"):
        isoflow.write_surface(obj, out)
    assert out.read_text() == "taken"
    isoflow.write_surface(obj, out, force=True)
    assert len(trimesh.load(out, process=False).vertices) == 26


@pytest.mark.parametrize("call,words", [
    (lambda p: isoflow.write_surface(np.ones((2, 2, 2), bool), p / "s.obj", ascii=True),
     "s.obj: ascii=True applies to .ply output only"),
    (lambda p: isoflow.write_surface(np.ones((2, 2, 2), bool), p / "s.txt"), "s.txt: surface must end in .ply"),
    (lambda p: isoflow.write_surface(np.ones((2, 2), bool), p / "s.ply"),
     "write_surface needs a 3D object, got 2D"),
    (lambda p: isoflow.write_surface(np.zeros((2, 2, 2), bool), p / "s.ply"), "s.ply: the object is empty"),
    (lambda p: isoflow.write_surface(np.ones((2, 2, 2), bool), p / "s.ply", 8), "connectivity"),
    (lambda p: isoflow.write_surface(np.ones((2, 2, 2), bool), p / "s.ply", 26,
                                     mesh=isoflow.boundary_mesh(np.ones((2, 2, 2), bool), 6)),
     "s.ply: the mesh is 6-connected, connectivity=26 was asked"),
    (lambda p: isoflow.write_surface(np.ones((1, 1, 1), bool), p / "s.ply",
                                     mesh=isoflow.boundary_mesh(np.ones((2, 2, 2), bool))),
     "s.ply: the mesh reaches [2.0, 2.0, 2.0], outside the object's array of shape [1, 1, 1]"),
    (lambda p: isoflow.write_surface(np.ones((1, 1, 1), bool), p / "s.ply", mesh=np.zeros((3, 3))),  # type: ignore[arg-type]
     "s.ply: mesh= takes the QuadMesh of boundary_mesh(obj.volume), got ndarray"),
    (lambda p: isoflow.write_surface(np.ones((2, 2, 2), bool), p / "s.ply", check="no"),  # type: ignore[arg-type]
     "s.ply: check must be True or False, got 'no'"),
])
def test_bad_input_is_one_line_and_nothing_is_written(tmp_path, call, words):
    with pytest.raises(IsoflowError) as e:
        call(tmp_path)
    assert words in str(e.value) and "\n" not in str(e.value)
    assert not any(tmp_path.iterdir())


def test_stl_says_what_readers_do(tmp_path):
    # split copies at contacts: welded by every STL reader, said as a warning
    with pytest.warns(IsoflowWarning, match=r"s\.stl: STL keeps no shared vertices, so readers weld the split "
                      r"copies at \d+ edge/vertex contacts"):
        isoflow.write_surface(object_with_contacts(), tmp_path / "s.stl")
    # float32 moves corners 1e5 + 0.3 away by about 0.004: said with the numbers
    far = isoflow.DigitalObject(np.ones((2, 2, 2), bool), origin=(1e5 + 0.3, 0.0, 0.0))
    with pytest.warns(IsoflowWarning, match=r"far\.stl: STL stores float32 positions, which move the corners by up "
                      r"to 0\.00\d+"):
        isoflow.write_surface(far, tmp_path / "far.stl")
    x = trimesh.load(tmp_path / "far.stl").vertices[:, 0]
    assert np.abs(np.unique(x) - (1e5 + 0.3 + np.arange(3))).max() < 0.004
    # float32 would merge corners: refused, nothing written
    merged = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=0.1, origin=(4e6, 0.0, 0.0))
    with pytest.raises(IsoflowError, match=r"merged\.stl: binary STL holds float32 positions, which would merge"):
        isoflow.write_surface(merged, tmp_path / "merged.stl")
    assert not (tmp_path / "merged.stl").exists()


@pytest.mark.parametrize("connectivity", [6, 26])
@pytest.mark.parametrize("suffix", [".ply", ".obj"])
def test_random_volumes_with_contacts_read_back_closed_by_both_readers(tmp_path, rng, connectivity, suffix):
    """Random volumes (edge and vertex contacts among them, checked) written
    by write_surface and read as written by trimesh and pymeshlab: closed
    two-manifolds whose V - E + F is analyze's sum over its closed surfaces
    (2 chi + 2 pinched) and whose volume is the voxels'; the a column sums
    to 8 chi (Theorems 10-11)."""
    from conftest import random_volume

    contacts = 0
    for i in range(12):
        v = np.pad(random_volume(rng), 1)
        if not v.any():
            continue
        diagonal = [v[1:, 1:] & v[:-1, :-1] & ~v[1:, :-1] & ~v[:-1, 1:],  # two voxels meeting at an edge only
                    v[1:, 1:, 1:] & v[:-1, :-1, :-1]]  # or at a vertex (among other cases)
        contacts += int(any(d.any() for d in diagonal))
        obj = isoflow.DigitalObject(v, pitch=PITCH, origin=ORIGIN)
        report = isoflow.analyze(obj, connectivity)
        euler = sum(s["euler_characteristic"] for s in report["surfaces"])
        assert euler == 2 * report["euler_characteristic"] + 2 * report["pinched_vertices"]
        path = isoflow.write_surface(obj, tmp_path / f"r{i}{suffix}", connectivity)
        tm = trimesh.load(path, force="mesh", process=False)
        assert tm.is_watertight and tm.is_winding_consistent and tm.euler_number == euler
        assert tm.volume == pytest.approx(obj.voxels * PITCH**3)
        assert pymeshlab_euler(path) == euler
        if suffix == ".ply":
            assert int(tm.metadata["_ply_raw"]["vertex"]["data"]["a"].sum()) == 8 * report["euler_characteristic"]
    assert contacts >= 3


@pytest.mark.parametrize("connectivity", [6, 26])
def test_a_mesh_of_another_object_in_the_same_box_is_refused(tmp_path, rng, connectivity):
    """mesh= of another random object of the array's shape, which reaches
    the same corners of the box: refused in one line, nothing written (only
    its bounds and connectivity were checked, and the other object's
    surface was written as this one's)."""
    from conftest import random_volume

    for i in range(8):
        a = random_volume(rng)
        b = rng.random(a.shape) < 0.5
        a[0, 0, 0] = a[-1, -1, -1] = b[0, 0, 0] = b[-1, -1, -1] = True  # the same bounding box
        if np.array_equal(a, b):
            continue
        with pytest.raises(IsoflowError) as e:
            isoflow.write_surface(a, tmp_path / f"s{i}.ply", connectivity, mesh=isoflow.boundary_mesh(b, connectivity))
        assert str(e.value).startswith(f"{tmp_path / f's{i}.ply'}: the mesh") and "\n" not in str(e.value)
        assert str(e.value).endswith("pass the mesh of this object")
        assert not any(tmp_path.iterdir())


def test_a_mesh_of_the_same_counts_but_another_object_is_refused(tmp_path):
    """Two voxels on one diagonal of a 3 x 2 x 1 box, or on the other: the
    same box, and meshes of the same faces, vertices and V - E + F as
    trimesh reads them, yet not the same surface; the corner whose
    configuration differs is named."""
    a, b = np.zeros((3, 2, 1), bool), np.zeros((3, 2, 1), bool)
    a[0, 0, 0] = a[2, 1, 0] = True
    b[0, 1, 0] = b[2, 0, 0] = True
    isoflow.write_surface(a, tmp_path / "a.ply")
    isoflow.write_surface(b, tmp_path / "b.ply")
    ta, tb = (trimesh.load(tmp_path / n, process=False) for n in ("a.ply", "b.ply"))
    assert (len(ta.vertices), len(ta.faces), ta.euler_number) == (len(tb.vertices), len(tb.faces), tb.euler_number)
    assert ta.bounds.tolist() == tb.bounds.tolist() and not np.array_equal(ta.vertices, tb.vertices)
    with pytest.raises(IsoflowError, match=r"s\.ply: the mesh's corner \[\d, \d, \d\] \(array-corner units\) has "
                       r"configuration \d+, the object's there is \d+ \(\d+ corners differ\): pass the mesh of this "
                       r"object$"):
        isoflow.write_surface(a, tmp_path / "s.ply", mesh=isoflow.boundary_mesh(b))
    assert not (tmp_path / "s.ply").exists()


@pytest.mark.parametrize("suffix,ascii,triangulate", FILES)
def test_the_read_back_check_writes_the_same_file(tmp_path, rng, suffix, ascii, triangulate):
    """check=True (the default, as ``isoflow surface``) and check=False
    write the same bytes, and the read-back passes on random volumes and
    on the object with doubled edges and contacts."""
    from conftest import random_volume

    objects = [object_with_contacts()] + [np.pad(random_volume(rng), 1) for _ in range(4)]
    (tmp_path / "c").mkdir()
    (tmp_path / "u").mkdir()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IsoflowWarning)  # the STL's weld, said in test_stl_says_what_readers_do
        for i, obj in enumerate(o for o in objects if np.any(o)):
            # one name in two folders: a GLB's node is named after the file
            checked = isoflow.write_surface(obj, tmp_path / "c" / f"{i}{suffix}", ascii=ascii, triangulate=triangulate)
            unchecked = isoflow.write_surface(obj, tmp_path / "u" / f"{i}{suffix}", ascii=ascii,
                                              triangulate=triangulate, check=False)
            assert checked.read_bytes() == unchecked.read_bytes()
    assert not [p.name for d in ("c", "u") for p in (tmp_path / d).iterdir() if p.name.startswith(".")]  # no temporary


def test_a_file_that_reads_back_otherwise_is_refused_and_nothing_replaced(tmp_path, monkeypatch):
    """A writer that loses a face (as a defect of it would): trimesh reads
    the file open, the check names the file and what differs, and the
    previous file stays as it was; check=False writes the open file."""
    import dataclasses

    from isoflow.mesh import export

    whole = export.write_mesh_file

    def losing_a_face(path, mesh, obj, **kw):
        cut = {k: getattr(mesh, k)[:-1] for k in ("faces", "edge_midpoint", "face_normals")}
        return whole(path, dataclasses.replace(mesh, **cut), obj, **kw)

    monkeypatch.setattr(export, "write_mesh_file", losing_a_face)
    out = tmp_path / "s.ply"
    out.write_text("previous")
    with pytest.raises(IsoflowError, match=r"s\.ply: trimesh reads watertight False \(isoflow: True\).*; nothing was "
                       r"replaced$") as e:
        isoflow.write_surface(np.ones((2, 2, 2), bool), out, force=True)
    assert "\n" not in str(e.value) and out.read_text() == "previous" and sorted(tmp_path.iterdir()) == [out]
    isoflow.write_surface(np.ones((2, 2, 2), bool), out, force=True, check=False)
    assert not trimesh.load(out, process=False).is_watertight


def test_an_obj_of_mixed_polygons_reads_back_without_trimeshs_line_parser(tmp_path, rng, monkeypatch):
    """An OBJ of quads and pentagons (doubled edges at 6) is one that
    trimesh parses line by line in Python; the read-back reads its arrays
    on the file's bytes, the vertices and triangles trimesh.load gives,
    and agrees with isoflow's counts without trimesh.load."""
    from conftest import random_volume

    from isoflow.digital.surface import boundary_mesh
    from isoflow.mesh.readback import check_surface_file, obj_as_trimesh_reads

    objects = [object_with_contacts()] + [isoflow.DigitalObject(np.pad(random_volume(rng), 1)) for _ in range(4)]
    written = []
    for i, obj in enumerate(objects):
        mesh = boundary_mesh(obj.volume, 6)
        path = isoflow.write_surface(obj, tmp_path / f"{i}.obj", mesh=mesh, check=False)
        sizes = {len(line.split()) - 1 for line in path.read_text().splitlines() if line.startswith("f ")}
        tm = trimesh.load(path, force="mesh", process=False)
        vertices, triangles = obj_as_trimesh_reads(path)
        np.testing.assert_array_equal(vertices, tm.vertices)
        np.testing.assert_array_equal(triangles, tm.faces)
        written.append((path, mesh, obj, len(sizes) > 1))
    assert written[0][3]  # the ring's pentagons among its quads

    def unread(*args, **kwargs):
        raise AssertionError("trimesh.load called")

    monkeypatch.setattr(trimesh, "load", unread)
    for path, mesh, obj, _ in written:
        check = check_surface_file(path, mesh, obj)
        assert check["agree"], check["problem"]


@pytest.mark.parametrize("corrupt", [
    lambda lines, f: lines.__setitem__(f[3], f"f 1 2 {10 ** 6}"),
    lambda lines, f: lines.__setitem__(f[3], " ".join(lines[f[3]].split()[:3])),
    lambda lines, f: lines.__delitem__(slice(f[len(f) // 2], None)),
    lambda lines, f: lines.__setitem__(f[0], lines[f[0]].replace("f ", "f 0 ", 1)),
    lambda lines, f: lines.__setitem__(f[0] - 1, "v 9 9 9"),
], ids=["index-past-the-vertices", "a-face-of-two-corners", "cut-short", "index-0", "a-vertex-moved"])
def test_an_obj_that_reads_otherwise_is_refused(tmp_path, corrupt):
    """An OBJ of quads and pentagons altered after writing reads back as
    not isoflow's surface: trimesh fails on it or reads it open, of
    another Euler number or volume."""
    from isoflow.digital.surface import boundary_mesh
    from isoflow.mesh.readback import check_surface_file

    obj = object_with_contacts()
    mesh = boundary_mesh(obj.volume, 6)
    path = isoflow.write_surface(obj, tmp_path / "s.obj", mesh=mesh, check=False)
    lines = path.read_text().split("\n")
    corrupt(lines, [i for i, line in enumerate(lines) if line.startswith("f ")])
    path.write_text("\n".join(lines))
    try:
        tm = trimesh.load(path, force="mesh", process=False)
        differs = (not tm.is_watertight or tm.euler_number != mesh.euler_characteristic
                   or not np.isclose(tm.volume, obj.voxels * PITCH ** 3))
    except Exception:
        differs = True
    assert differs  # trimesh's own reading of the altered file
    check = check_surface_file(path, mesh, obj)
    assert check["agree"] is False and check["problem"].startswith(f"{path}: trimesh"), check


@pytest.mark.parametrize("suffix", [".ply", ".obj"])
def test_a_header_names_only_the_columns_its_file_holds(tmp_path, capsys, suffix):
    # the OBJ's comments named the PLY's per-vertex columns, which it does not hold
    isoflow.write_volume(object_with_contacts(), tmp_path / "in.npz")
    out = tmp_path / f"s{suffix}"
    assert main(["surface", str(tmp_path / "in.npz"), "-o", str(out), "-q"]) == 0
    comments = [line for line in out.read_text(errors="replace").splitlines() if line.startswith(("#", "comment"))]
    named = any("gamma" in line for line in comments)
    raw = trimesh.load(out, process=False).metadata.get("_ply_raw")  # an OBJ has no columns beside x y z
    held = raw is not None and "gamma" in raw["vertex"]["data"].dtype.names
    assert named == held == (suffix == ".ply"), comments


def test_an_obj_of_an_input_named_with_a_line_break_is_lines_of_obj_keywords(tmp_path, capsys):
    # the name's line break ended the comment: its rest was a line of no OBJ keyword
    isoflow.write_volume(object_with_contacts(), tmp_path / "in\nput.npz")
    out = tmp_path / "s.obj"
    assert main(["surface", str(tmp_path / "in\nput.npz"), "-o", str(out), "-q"]) == 0
    lines = out.read_text().splitlines()
    assert all(line.split()[0] in ("#", "v", "f") for line in lines), [x for x in lines if x[:1] not in "#vf"]
    assert any(line.startswith("# isoflow surface of in put.npz, 6-connectivity") for line in lines)
