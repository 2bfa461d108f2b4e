"""Binary STL for every surface whose float32 positions stay distinct.

STL holds float32 positions and no shared vertices; a reader welds equal
positions. The files are read back as users read them: trimesh (then equal
positions welded) and pymeshlab (``meshing_remove_duplicate_vertices``),
and compared with isoflow's counts of the boundary mesh: closed surfaces,
Euler number, genus, and the volume within what float32's move explains.
"""

import contextlib
import io
from pathlib import Path

import numpy as np
import pymeshlab
import pytest
import trimesh

from isoflow import DigitalObject, boundary_mesh, write_volume
from isoflow.cli import main
from isoflow.mesh.export import float32_effect
from isoflow.mesh.load import is_mesh_path

MESHES = Path(__file__).resolve().parents[2] / "meshes"


def run(*argv) -> tuple[int, str, str]:
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = main([str(a) for a in argv])
    return rc, o.getvalue(), e.getvalue()


def welded_trimesh(path):
    tm = trimesh.load(path, force="mesh", process=False)
    points, at = np.unique(np.asarray(tm.vertices), axis=0, return_inverse=True)
    return trimesh.Trimesh(points, at.reshape(-1)[tm.faces], process=False)


def pymeshlab_measures(path) -> dict:
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    ms.meshing_remove_duplicate_vertices()
    t = ms.get_topological_measures()
    t["volume"] = ms.get_geometric_measures()["mesh_volume"]
    return t


def ball(n: int = 9) -> np.ndarray:
    """A digital ball with a tunnel: well-composed (no edge or vertex
    contact), so its STL welds back to the same closed surface of genus 1."""
    x, y, z = np.mgrid[:n, :n, :n] - (n - 1) / 2
    vol = x**2 + y**2 + z**2 <= (n / 2 - 0.5) ** 2
    vol[(n - 1) // 2, (n - 1) // 2, :] = False
    return vol


PLACEMENTS = [  # (pitch, origin): non-binary pitches, far from the origin, units of 1e-6 and 1e6
    (1 / 3, (0.0, 0.0, 0.0)), (0.1, (1.0e5, -2.0e5, 3.0e4)), (0.7e-6, (12.3e-6, 0.0, -4.1e-6)),
    (3.3e-6, (2.5e-3, 0.0, 0.0)), (1e6 / 3, (0.0, 0.0, 0.0)), (0.37e6, (4.1e9, 0.0, 0.0)),
]


@pytest.mark.parametrize("pitch, origin", PLACEMENTS)
def test_stl_is_written_and_reads_back_in_any_units(tmp_path, pitch, origin):
    vol = ball()
    obj = DigitalObject(vol, pitch=pitch, origin=origin)
    write_volume(obj, tmp_path / "v.npz")
    rc, out, err = run("surface", tmp_path / "v.npz", "-o", tmp_path / "s.stl")
    assert rc == 0, err
    mesh = boundary_mesh(vol, 6)
    xyz = obj.world(mesh.vertices)
    effect = float32_effect(xyz, obj.spacing)
    assert effect["merged"] == 0
    volume = vol.sum() * pitch**3
    tm = welded_trimesh(tmp_path / "s.stl")
    assert tm.is_watertight and tm.is_winding_consistent
    assert tm.euler_number == mesh.euler_characteristic == 0 and tm.body_count == 1  # genus 1
    slack = 2 * effect["moved"] * tm.area + 1e-6 * volume
    assert abs(tm.volume - volume) <= slack
    pm = pymeshlab_measures(tmp_path / "s.stl")
    assert pm["is_mesh_two_manifold"] and pm["genus"] == 1 and pm["boundary_edges"] == 0
    assert pm["vertices_number"] == len(np.unique(xyz, axis=0))
    assert abs(pm["volume"] - volume) <= slack + 1e-4 * volume  # MeshLab sums in single precision
    # the note says how far float32 moved the corners, where that is more than a thousandth of a voxel
    noted = [line for line in err.splitlines() if "float32 positions" in line]
    assert bool(noted) == (effect["moved_voxels"] > 1e-3)
    rc, _, quiet = run("surface", tmp_path / "v.npz", "-o", tmp_path / "s.stl", "--force", "--quiet")
    assert rc == 0 and quiet.splitlines() == noted  # a warning: the file's surface is not the one asked for


def test_far_from_the_origin_the_note_gives_the_move(tmp_path):
    """Map coordinates (4e6) with 1 m voxels: float32 positions are 0.25 m
    apart there, so the corners (at .3 and .8 m) move by 0.05 m, which the
    note says."""
    obj = DigitalObject(ball(), pitch=1.0, origin=(5.0e5 + 0.1, 4.0e6 + 0.3, 0.0))
    write_volume(obj, tmp_path / "utm.npz")
    rc, out, err = run("surface", tmp_path / "utm.npz", "-o", tmp_path / "utm.stl")
    assert rc == 0, err
    line, = [x for x in err.splitlines() if "float32 positions" in x]
    corners = obj.world(boundary_mesh(ball(), 6).vertices)
    moved = np.abs(corners.astype(np.float32).astype(np.float64) - corners).max()
    assert round(moved, 6) == 0.05 and f"up to {moved:.3g} ({moved:.2g} voxels)" in line and ".ply" in line


def test_stl_is_refused_only_where_float32_merges_corners(tmp_path, capsys):
    """0.1 m voxels at 4e6 m: float32 positions are 0.25 apart there, so
    corners 0.1 apart become one: refused, with the numbers, nothing written."""
    obj = DigitalObject(ball(5), pitch=0.1, origin=(5.0e5, 4.0e6, 0.0))
    write_volume(obj, tmp_path / "utm.npz")
    rc, out, err = run("surface", tmp_path / "utm.npz", "-o", tmp_path / "utm.stl")
    assert rc == 2 and out == ""
    line, = err.strip().splitlines()
    effect = float32_effect(obj.world(boundary_mesh(ball(5), 6).vertices), obj.spacing)
    assert effect["merged"] > 0 and effect["step"] == 0.25
    assert f"would merge {effect['merged']} of this surface's {effect['positions']} distinct corner" in line
    assert "voxel size 0.1" in line and "0.25 apart" in line and ".ply" in line
    assert not (tmp_path / "utm.stl").exists()


@pytest.mark.parametrize("scale, offset", [(1.0, 0.0), (1e-6, 0.0), (1e6, 0.0), (1.0, 3.7e4)])
def test_every_sample_mesh_whose_ply_is_written_gets_its_stl(tmp_path, scale, offset):
    """The repository's sample meshes, as given and in units of 1e-6 and
    1e6 and far from the origin, at 32 across (a pitch that is no binary
    fraction): every surface written as PLY is written as STL too."""
    written = {".ply": 0, ".stl": 0}
    for path in sorted(MESHES.iterdir()):
        if not is_mesh_path(path):
            continue
        mesh = trimesh.load(path, force="mesh", process=False)
        mesh.vertices = np.asarray(mesh.vertices) * scale + offset
        src = tmp_path / f"{path.stem}.ply"
        mesh.export(src)
        status = {}
        for suffix in (".ply", ".stl"):
            rc, _, err = run("surface", src, "--resolution", 32, "-o", tmp_path / f"out_{path.stem}{suffix}")
            written[suffix] += rc == 0
            status[suffix] = rc
            if suffix == ".stl" and status[".ply"] == 0:
                assert rc == 0, (path.name, err)
    assert written[".stl"] == written[".ply"] == 15


@pytest.mark.parametrize("batch", [3, 8192])
def test_stl_in_batches_is_trimeshs_file(tmp_path, monkeypatch, batch):
    """The STL writer makes its records a batch of triangles at a time:
    the bytes of trimesh's exporter of the whole mesh, a degenerate
    triangle's zero normal included, at 6 and 26."""
    from isoflow.mesh import export

    monkeypatch.setattr(export, "STL_BATCH_TRIANGLES", batch)
    rng = np.random.default_rng(5)
    v = rng.random((9, 8, 7)) < 0.4
    obj = DigitalObject(v, pitch=(0.5, 0.25, 0.75), origin=(10.0, 0.5, -1.0))
    for conn in (6, 26):
        mesh = boundary_mesh(v, conn)
        xyz, tris = obj.world(mesh.vertices), mesh.triangles()
        tris = np.concatenate([tris[:5], [[0, 0, 1]], tris[5:]])
        export.write_stl(tmp_path / f"{conn}.stl", xyz, tris, force=True)
        want = trimesh.exchange.stl.export_stl(trimesh.Trimesh(xyz, tris, process=False))
        assert (tmp_path / f"{conn}.stl").read_bytes() == want


def test_stl_writer_holds_a_batch_of_records(tmp_path):
    """trimesh's exporter made the float64 corners, normals and records of
    every triangle at once (294 bytes per triangle by tracemalloc, which
    numpy reports its buffers to); the writer holds a batch of them."""
    import tracemalloc

    from scipy.ndimage import gaussian_filter

    from isoflow.mesh.export import write_stl

    field = gaussian_filter(np.random.default_rng(0).standard_normal((32, 32, 32)), 2) > 0
    v = np.repeat(np.repeat(np.repeat(field, 4, 0), 4, 1), 4, 2)
    mesh = boundary_mesh(v, 6)
    xyz, tris = DigitalObject(v).world(mesh.vertices), mesh.triangles()
    tracemalloc.start()
    try:
        held = tracemalloc.get_traced_memory()[0]
        write_stl(tmp_path / "p.stl", xyz, tris)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(tris) > 100_000 and (peak - held) / len(tris) < 294 / 4


def test_distinct_count_counts_what_unique_of_rows_counts(rng):
    """float32_effect counts distinct positions by column ranks
    (float32.distinct_count): the count of NumPy's unique rows, on float64
    and float32 positions with repeats and on integers, and by value where
    rows differ in the sign of a zero alone."""
    from isoflow.mesh.float32 import distinct_count

    lattice = rng.integers(-40, 40, (5000, 3))
    for rows in (lattice * 0.1 + 4e6, (lattice * 0.1 + 4e6).astype(np.float32), lattice, lattice[:, :2] * 1e-300):
        assert distinct_count(rows) == len(np.unique(rows, axis=0))
    assert distinct_count(np.array([[0.0, 1.0], [-0.0, 1.0]])) == 1 == len(np.unique(np.array([0.0, -0.0])))
    assert distinct_count(np.zeros((0, 3))) == 0
