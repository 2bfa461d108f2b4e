"""Every surface file isoflow writes opens as the surface it describes.

Written through the command line, read back by trimesh (``process=False``:
the file's own vertices) and pymeshlab, as a user would: closed, 2-manifold,
consistently oriented, Euler number ``2 chi + 2 p`` (docs/mathematics.md, "The
boundary mesh"; chi from scikit-image, independent of isoflow), exact voxel volume.
"""

import contextlib
import io
from pathlib import Path

import numpy as np
import pymeshlab
import pytest
import trimesh
from conftest import random_volume, torus
from skimage.measure import euler_number

from isoflow import boundary_mesh
from isoflow.cli import main

# the formats written by default, and ASCII PLY, by suffix and extra option
FORMATS = [(".ply", ()), (".ply", ("--ascii",)), (".obj", ()), (".glb", ()), (".stl", ())]
SKIMAGE_CONN = {6: 1, 26: 3}

RING = [(0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 1, 2), (1, 0, 0), (1, 0, 1), (1, 0, 2), (1, 1, 2)]


def surface(tmp_path, volume, conn, suffix, options=(), name="s"):
    """Run ``isoflow surface`` on a volume; returns (exit code, file, stdout, stderr)."""
    src = tmp_path / f"{name}.npy"
    np.save(src, volume)
    out = tmp_path / f"{name}{'_ascii' if options else ''}{suffix}"
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = main(["surface", str(src), "-o", str(out), "--connectivity", str(conn), "--force", *options])
    return rc, out, o.getvalue(), e.getvalue()


def read_trimesh(path: Path):
    # STL stores no shared vertices: read it with trimesh's usual merge
    return trimesh.load(path, force="mesh", process=path.suffix == ".stl")


def read_pymeshlab(path: Path) -> dict:
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    if path.suffix == ".stl":
        ms.meshing_remove_duplicate_vertices()  # MeshLab's usual weld of an STL
    t = ms.get_topological_measures()
    t["volume"] = ms.get_geometric_measures().get("mesh_volume")
    t["euler"] = t["vertices_number"] - t["edges_number"] + t["faces_number"]
    return t


def assert_reads_as(path: Path, volume, conn, euler):
    tm = read_trimesh(path)
    assert tm.is_watertight and tm.is_winding_consistent, path
    assert tm.euler_number == euler, (path, tm.euler_number, euler)
    assert tm.volume == pytest.approx(volume.sum(), rel=1e-9)
    pm = read_pymeshlab(path)
    assert pm["is_mesh_two_manifold"] and pm["boundary_edges"] == 0, (path, pm)
    assert pm["non_two_manifold_edges"] == pm["non_two_manifold_vertices"] == 0
    assert pm["euler"] == euler, (path, pm["euler"], euler)
    assert pm["volume"] == pytest.approx(volume.sum(), rel=1e-9)


@pytest.mark.parametrize("conn", [6, 26])
def test_random_volumes_every_format_opens_in_trimesh_and_pymeshlab(tmp_path, rng, conn):
    seen = {"doubled edges": 0, "pinched": 0, "split vertices": 0, "stl welded": 0, "stl watertight": 0}
    for i in range(150):
        v = random_volume(rng, 5)
        if not v.any():
            continue
        m = boundary_mesh(v, conn)
        euler = 2 * euler_number(np.pad(v, 1), SKIMAGE_CONN[conn]) + 2 * m.pinched
        seen["doubled edges"] += m.midpoints > 0
        seen["pinched"] += m.pinched > 0
        seen["split vertices"] += int((m.sheet > 0).any())
        for suffix, options in (FORMATS[i % 5], FORMATS[(i + 2) % 5]):  # two formats per volume
            rc, path, _, err = surface(tmp_path, v, conn, suffix, options)
            assert rc == 0, err
            if suffix != ".stl":
                assert_reads_as(path, v, conn, euler)
                continue
            # STL: readers weld by position; exact where nothing is split,
            # else one note on stderr with the count, and the volume still exact
            split = (m.sheet > 0).any() or m.midpoints
            if split:
                seen["stl welded"] += 1
                line, = err.strip().splitlines()
                assert "STL keeps no shared vertices" in line and "PLY, OBJ or GLB" in line
                assert read_trimesh(path).volume == pytest.approx(v.sum())
            else:
                seen["stl watertight"] += 1
                assert err == ""
                assert_reads_as(path, v, conn, euler)
    assert all(seen.values()), seen  # every hard case occurred


@pytest.mark.parametrize("suffix,options", FORMATS)
def test_ring_of_eight_voxels(tmp_path, suffix, options):
    """The issue's ring: genus 1 at 6-connectivity, with four pentagons
    (trimesh read its OBJ as not watertight with Euler 2, and could not read
    its binary PLY at all)."""
    v = np.zeros((2, 2, 3), bool)
    v[tuple(np.array(RING).T)] = True
    m = boundary_mesh(v, 6)
    assert np.count_nonzero((m.polygons() >= 0).sum(axis=1) == 5) == 4
    assert m.euler_characteristic == 0 and [c["genus"] for c in m.components()] == [1]
    rc, path, _, err = surface(tmp_path, v, 6, suffix, options)
    assert rc == 0, err
    if suffix == ".stl":  # the ring's doubled edges are welded by every STL reader
        assert "STL keeps no shared vertices" in err
        return
    assert_reads_as(path, v, 6, 0)
    assert read_pymeshlab(path)["genus"] == 1


@pytest.mark.parametrize("suffix,options", FORMATS[:4])
def test_two_voxels_sharing_an_edge_at_26(tmp_path, suffix, options):
    v = np.zeros((2, 2, 1), bool)
    v[0, 0, 0] = v[1, 1, 0] = True
    rc, path, _, err = surface(tmp_path, v, 26, suffix, options)
    assert rc == 0, err
    assert_reads_as(path, v, 26, 2)  # one sphere through the shared edge
    assert len(read_trimesh(path).split(only_watertight=False)) == 1


def test_well_composed_stl_opens_watertight_after_the_weld(tmp_path):
    v = torus(6, 2.5)
    assert boundary_mesh(v).midpoints == 0 and not (boundary_mesh(v).sheet > 0).any()
    rc, path, _, err = surface(tmp_path, v, 6, ".stl")
    assert rc == 0 and err == ""
    assert_reads_as(path, v, 6, 0)
    assert read_pymeshlab(path)["genus"] == 1


def test_file_contents_per_format(tmp_path):
    """What docs/formats.md says each format holds: binary PLY quads (triangles when an
    edge is doubled), OBJ polygons starting at a midpoint, GLB triangles with
    vertex colours and the curvature columns."""
    edge = np.zeros((2, 2, 1), bool)
    edge[0, 0, 0] = edge[1, 1, 0] = True
    cube = np.ones((2, 2, 2), bool)
    _, ply, out, _ = surface(tmp_path, cube, 6, ".ply", name="cube")
    assert "faces: quads" in ply.read_bytes()[:2000].decode("ascii", "replace")
    assert "(quads)" in out
    _, ply, out, _ = surface(tmp_path, edge, 26, ".ply", name="edge")
    assert "faces: triangles" in ply.read_bytes()[:2000].decode("ascii", "replace")
    _, obj, _, _ = surface(tmp_path, edge, 26, ".obj", name="edge")
    rows = [line.split()[1:] for line in obj.read_text().splitlines() if line.startswith("f ")]
    verts = [line.split()[1:] for line in obj.read_text().splitlines() if line.startswith("v ")]
    pentagons = [r for r in rows if len(r) == 5]
    assert len(pentagons) == 4
    for r in pentagons:  # the first corner is the midpoint: not a lattice point
        x = np.array(verts[int(r[0]) - 1], float)
        assert (np.abs(x - np.round(x)) > 0.25).any()
    _, glb, _, _ = surface(tmp_path, cube, 6, ".glb", name="cube")
    tm = read_trimesh(glb)
    assert len(tm.faces) == 2 * 24 and len(tm.vertices) == 26
    assert tm.visual.kind == "vertex" and len(np.unique(tm.visual.vertex_colors, axis=0)) > 1
    assert {"_config", "_gamma", "_a"} <= set(tm.vertex_attributes)
    assert tm.vertex_attributes["_a"].sum() == 8  # a^T n = 8 chi on the cube


def test_ascii_only_for_ply(tmp_path):
    rc, path, _, err = surface(tmp_path, np.ones((1, 1, 1), bool), 6, ".obj", ("--ascii",))
    assert rc == 2 and "--ascii applies to .ply" in err and not path.exists()


def test_readback_disagreement_exits_1_naming_the_file(tmp_path, monkeypatch):
    """A writer that loses a face: the read-back check catches it."""
    from isoflow.mesh import export

    real = export.surface_faces

    def lossy(mesh, suffix, **kw):
        kind, faces = real(mesh, suffix, **kw)
        return kind, faces[1:]

    monkeypatch.setattr(export, "surface_faces", lossy)
    rc, path, _, err = surface(tmp_path, np.ones((2, 2, 2), bool), 6, ".ply")
    assert rc == 1
    line, = err.strip().splitlines()
    assert str(path) in line and "trimesh reads" in line and "watertight False" in line


def test_readback_beyond_the_memory_budget_is_skipped_and_said(tmp_path, monkeypatch):
    """The file is written; the read-back (an OBJ's asks 380 bytes a line
    of the file) is skipped with one note when it would not fit."""
    from isoflow.mesh import readback
    from isoflow.scale import memory

    v = np.ones((3, 3, 3), bool)
    # meshing needs about 17 kB (16 B a lattice point, 300 a face), the read-back 43 kB (113 lines);
    # the read-back's fixed part (its imports: up to 221 MiB) left out of a budget this small
    monkeypatch.setattr(readback, "readback_fixed", lambda: 0)
    monkeypatch.setattr(memory, "default_budget", lambda: 30_000)
    rc, path, out, err = surface(tmp_path, v, 6, ".obj")
    assert rc == 0 and path.exists() and "trimesh reads" not in out
    line, = err.strip().splitlines()
    assert "not read back" in line and "budget" in line and str(path) in line
    # a PLY's read-back (150 bytes a triangle: 16 kB) fits the same budget
    rc, path, out, err = surface(tmp_path, v, 6, ".ply")
    assert rc == 0 and "trimesh reads" in out and err == ""
    monkeypatch.undo()
    rc, path, out, err = surface(tmp_path, v, 6, ".ply", ("--no-check",))
    assert rc == 0 and err == "" and "trimesh reads" not in out


PLACEMENTS = [  # (pitch, origin): tiny and huge units, map coordinates, far from the origin in thin voxels
    (1e-120, (0.0, 0.0, 0.0)), (1e40, (0.0, 0.0, 0.0)), (0.1, (500000.0, 4000000.0, 0.0)),
    (0.001, (1e6, 0.0, 0.0)), (1.0, (0.0, 0.0, 0.0)),
]


@pytest.mark.parametrize("conn", [6, 26])
@pytest.mark.parametrize("pitch, origin", PLACEMENTS)
def test_positions_stay_on_the_voxel_grid_in_any_units(tmp_path, capsys, rng, pitch, origin, conn):
    """float32 (PLY's and GLB's positions until now, OBJ's 9 digits) put
    vertices of tiny units at 0, of huge units at inf, and of map
    coordinates off the grid (and the read-back's volume, summed far from
    the origin, refused right files). Every file now holds the world
    positions to a millionth of a voxel, as trimesh and pymeshlab read
    them; the usual units keep float32 PLYs."""
    from isoflow import DigitalObject, write_volume

    vol = rng.random((4, 5, 3)) < 0.5  # edge and vertex contacts
    obj = DigitalObject(vol, pitch=pitch, origin=origin)
    write_volume(obj, tmp_path / "v.npz")
    want = obj.world(boundary_mesh(vol, conn).vertices)
    key = {tuple(p) for p in np.round((want - obj.world(np.zeros((1, 3)))) / pitch, 6).tolist()}
    for out in ("s.ply", "a.ply", "s.obj", "s.glb"):
        extra = ["--ascii"] if out == "a.ply" else []
        assert main(["surface", str(tmp_path / "v.npz"), "-o", str(tmp_path / out), "--connectivity", str(conn),
                     "--force", *extra]) == 0, capsys.readouterr()
        got = np.asarray(trimesh.load(tmp_path / out, force="mesh", process=False).vertices, np.float64)
        assert np.isfinite(got).all()
        on_grid = np.round((got - obj.world(np.zeros((1, 3)))) / pitch, 6)
        assert np.abs(on_grid - np.round(on_grid * 2) / 2).max() < 1e-6, out
        assert {tuple(p) for p in on_grid.tolist()} == key, out
        if out != "s.glb":
            ms = pymeshlab.MeshSet()
            ms.load_new_mesh(str(tmp_path / out))
            mine = np.round((ms.current_mesh().vertex_matrix() - obj.world(np.zeros((1, 3)))) / pitch, 6)
            assert {tuple(p) for p in mine.tolist()} == key, out
    header = (tmp_path / "s.ply").read_bytes().split(b"end_header")[0]
    assert (b"property float x" in header) == (pitch == 1.0)  # doubles only where float32 would not hold them
    err = capsys.readouterr().err
    assert "Warning" not in err and "warning" not in err, err


def test_stl_that_cannot_hold_the_positions_is_refused(tmp_path, capsys):
    from isoflow import DigitalObject, write_volume

    # 0.1 m voxels at 4e6 m, where float32 positions are 0.25 apart: of the
    # corners at 0.1, 0.2, 0.3, 0.4 m two become one
    vol = np.zeros((3, 5, 3), bool)
    vol[1, 1:4, 1] = True
    write_volume(DigitalObject(vol, pitch=0.1, origin=(500000.0, 4000000.0, 0.0)), tmp_path / "utm.npz")
    assert main(["surface", str(tmp_path / "utm.npz"), "-o", str(tmp_path / "utm.stl")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "float32" in err[0] and "would merge" in err[0] and ".ply" in err[0]
    assert not (tmp_path / "utm.stl").exists()


def _titles(monkeypatch):
    """The titles of every picture a command saves (then saved as usual)."""
    from isoflow.flow import pictures
    from isoflow.mesh import render

    seen = []
    real = render.save_figure

    def save(fig, path):
        seen.append(" ".join([fig._suptitle.get_text() if fig._suptitle else ""] + [a.get_title() for a in fig.axes]))
        return real(fig, path)

    monkeypatch.setattr(render, "save_figure", save)
    monkeypatch.setattr(pictures, "save_figure", save)
    return seen


def test_pictures_name_the_green_they_draw(tmp_path, monkeypatch):
    # not well-composed vertices are drawn green (and faces there greenish),
    # but the key said only "blue concave, white flat, red convex": the
    # thin rings of a guarded flow were half green with no word on it
    seen = _titles(monkeypatch)
    contact = np.zeros((4, 4, 4), bool)
    contact[1, 1, 1] = contact[2, 2, 2] = True  # two voxels sharing one corner only: not well-composed there
    box = np.zeros((4, 4, 4), bool)
    box[1:3, 1:3, 1:3] = True
    np.save(tmp_path / "contact.npy", contact)
    np.save(tmp_path / "box.npy", box)
    for name in ("contact", "box"):
        assert main(["surface", str(tmp_path / f"{name}.npy"), "--connectivity", "26", "-o", str(tmp_path / f"{name}.ply"),
                     "--png", str(tmp_path / f"{name}.png")]) == 0
        assert main(["flow", str(tmp_path / f"{name}.npy"), "--connectivity", "26", "--steps", "1",
                     "--out", str(tmp_path / f"run_{name}")]) == 0
    surface_contact, flow_contact, surface_box, flow_box = [s for s in seen if "concave" in s]
    for title in (surface_contact, flow_contact):
        assert "blue concave, white flat, red convex, green not well-composed" in title
    for title in (surface_box, flow_box):
        assert "green" not in title and "blue concave, white flat, red convex" in title
    from isoflow.mesh.export import gamma_colours

    mesh = boundary_mesh(contact, 26)
    corner = np.all(mesh.vertices == 2, axis=1)  # the shared corner, once per sheet
    assert corner.sum() == 2 and (mesh.vertex_class[corner] == -1).all()
    r, g, b = gamma_colours(mesh.gamma, mesh.vertex_class)[corner][0].astype(int)
    assert g > r and g > b


def test_one_pinched_vertex_is_counted_in_the_singular(tmp_path):
    """Two voxels meeting at a corner, 26-connected: one object (scikit-image
    chi 1) whose mesh splits the corner, V - E + F = 4 = 2 chi + 2 p, so
    p = 1, said as "1 pinched vertex" (in memory and from a zarr store),
    with what the mesh did there: MeshLab shows two shells where the
    connectivity asked for one object."""
    v = np.zeros((3, 3, 3), bool)
    v[0, 0, 0] = v[1, 1, 1] = True
    chi = euler_number(v, SKIMAGE_CONN[26])
    rc, path, out, _ = surface(tmp_path, v, 26, ".ply")
    pinched = (read_pymeshlab(path)["euler"] - 2 * chi) // 2
    assert rc == 0 and pinched == 1
    assert out.splitlines()[0].endswith(", 1 pinched vertex (split in the mesh, joined by the connectivity)")
    zarr = pytest.importorskip("zarr")
    store = zarr.open_array(str(tmp_path / "v.zarr"), mode="w", shape=v.shape, chunks=(2, 2, 2), dtype="u1")
    store[:] = v
    o = io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(io.StringIO()):
        rc = main(["surface", str(tmp_path / "v.zarr"), "-o", str(tmp_path / "z.ply"), "--connectivity", "26"])
    assert rc == 0 and (", 1 pinched vertex (split in the mesh, joined by the connectivity; written block by block"
                        in o.getvalue())


@pytest.mark.parametrize("binary", [False, True])
def test_write_rows_writes_what_savetxt_writes(rng, monkeypatch, binary):
    """The OBJ and ASCII PLY tables are formatted a block of rows at a time
    (export.write_rows): byte for byte what NumPy's savetxt writes, on
    floats of every size and sign (nan, inf, 1e300, -0.0) at the digits
    the writers use, and on indices, across block boundaries."""
    import io

    from isoflow.mesh import export

    monkeypatch.setattr(export, "ROWS_AT_ONCE", 7)
    floats = rng.standard_normal((50, 3)) * 10.0 ** rng.integers(-300, 300, (50, 3))
    floats[:4] = [[np.nan, np.inf, -np.inf], [-0.0, 0.0, 1.0], [1e-320, 2.5, -3.25], [123456789.123, 1, 2]]
    ints = rng.integers(0, 2**31, (23, 4))
    for rows, line in ((floats, "v %.17g %.17g %.17g\n"), (floats, "%.9g %.6g %.3g\n"), (ints, "f %d %d %d %d\n"),
                       (ints[:0], "f %d %d %d %d\n")):
        ours, theirs = (io.BytesIO(), io.BytesIO()) if binary else (io.StringIO(), io.StringIO())
        export.write_rows(ours, rows, line, binary=binary)
        np.savetxt(theirs, rows, fmt=line[:-1])
        assert ours.getvalue() == theirs.getvalue(), line
