"""Concave polygons (an L, a U, an arrowhead quad: CAD exports write them
as faces of their own) are read as the polygons they are, whatever corner
they start from: the OBJ, OFF and PLY readers cut them into triangles that
stay inside them, turned as they are, and a prism with such caps voxelises,
measures and reads back as the same prism written as triangles.

The references here are known without isoflow: the caps' areas by the
shoelace formula, the prism's volume as area times height, the triangles of
the reference files written by hand."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from isoflow.cli.main import main
from isoflow.mesh import ply, readers
from isoflow.mesh.load import load_mesh
from isoflow.mesh.readers import triangulate

#: outlines counter-clockwise seen from +z, and a cut of each into triangles
#: by hand (corner numbers), checked against the shoelace area below
SHAPES = {
    # an L whose first corner does not see the far arm: the fan crosses the notch
    "L": ([(2, 0), (2, 1), (1, 1), (1, 2), (0, 2), (0, 0)],
          [(0, 1, 5), (1, 2, 5), (2, 4, 5), (2, 3, 4)]),
    # a U (two reflex corners, 4 and 5) from an outer corner
    "U": ([(0, 0), (3, 0), (3, 2), (2, 2), (2, 1), (1, 1), (1, 2), (0, 2)],
          [(1, 2, 3), (1, 3, 4), (0, 1, 4), (0, 4, 5), (0, 5, 7), (5, 6, 7)]),
    # an arrowhead quad, reflex at corner 3: a file of quads only
    "arrow": ([(0, 0), (3, 1), (0, 2), (1, 1)], [(0, 1, 3), (1, 2, 3)]),
}
#: (shape, the corner each polygon starts from): the U from its reflex
#: corner 4 (its fan crosses the notch too), the L from its reflex corner 2
#: (whose fan stays inside), the arrowhead from its reflex corner
CASES = [("L", 0), ("L", 2), ("U", 0), ("U", 4), ("arrow", 0), ("arrow", 3)]
HEIGHT = 1.0


def _shoelace(outline) -> float:
    x, y = np.asarray(outline, float).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def prism(name: str, first: int):
    """Vertices, polygons (the two caps from corner ``first``, quads
    around) and the hand-cut triangles of a prism over the shape."""
    outline, cut = SHAPES[name]
    n = len(outline)
    ring = np.array([(x, y, 0.0) for x, y in outline])
    v = np.vstack([ring, ring + [0, 0, HEIGHT]])
    order = [(first + i) % n for i in range(n)]
    bottom = [order[0]] + order[:0:-1]  # the same corner first, turned to face -z
    top = [n + i for i in order]
    sides = [[i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    triangles = [(a, c, b) for a, b, c in cut] + [(n + a, n + b, n + c) for a, b, c in cut]
    triangles += [t for a, b, c, d in sides for t in ((a, b, c), (a, c, d))]
    return v, [bottom, top, *sides], triangles


#: the formats written: ``materials.obj`` is an OBJ of two materials with
#: texture coordinates, which isoflow leaves to trimesh to read
FORMATS = [".obj", ".off", ".ply", "materials.obj"]


def write(path: Path, v, faces) -> Path:
    """``faces`` (polygons or triangles) as an OBJ, ASCII OFF or ASCII PLY
    file, by the file's suffix; an OBJ named ``*materials.obj`` with two
    materials and texture coordinates."""
    rows = [" ".join(repr(float(c)) for c in p) for p in np.asarray(v).tolist()]
    if path.name.endswith("materials.obj"):
        text = "mtllib none.mtl\n" + "".join(f"v {r}\n" for r in rows) + "vt 0 0\nvt 1 0\n"
        for n, f in enumerate(faces):
            text += "usemtl a\n" * (n == 0) + "usemtl b\n" * (n == 2)
            text += "f " + " ".join(f"{i + 1}/{1 + n % 2}" for i in f) + "\n"
    elif path.suffix == ".obj":
        text = "".join(f"v {r}\n" for r in rows) + "".join("f " + " ".join(str(i + 1) for i in f) + "\n" for f in faces)
    elif path.suffix == ".off":
        text = f"OFF\n{len(v)} {len(faces)} 0\n" + "".join(f"{r}\n" for r in rows)
        text += "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces)
    else:
        text = (f"ply\nformat ascii 1.0\nelement vertex {len(v)}\nproperty double x\nproperty double y\n"
                f"property double z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
        text += "".join(f"{r}\n" for r in rows) + "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces)
    path.write_text(text)
    return path


def run(*args):
    """The real console entry point in a subprocess."""
    return subprocess.run([sys.executable, "-m", "isoflow.cli", *map(str, args)], capture_output=True, text=True)


def voxels(path: Path, fill: str) -> np.ndarray:
    """``isoflow voxelize`` of the file, run in this process (the console
    entry point itself is run by the genus tests)."""
    out = path.with_name(f"{path.name}.{fill}.npz")
    assert main(["voxelize", str(path), "--resolution", "12", "--fill", fill, "-o", str(out), "-q"]) == 0
    return np.load(out)["volume"]


def test_the_hand_cut_triangles_are_the_shapes():
    for outline, cut in SHAPES.values():
        turn = [_shoelace([outline[a], outline[b], outline[c]]) for a, b, c in cut]
        assert min(turn) > 0 and np.isclose(sum(turn), _shoelace(outline))
        assert len(cut) == len(outline) - 2


@pytest.mark.parametrize("name, first", CASES)
@pytest.mark.parametrize("suffix", FORMATS)
def test_concave_caps_are_cut_inside_the_polygon_and_turned_as_it(name, first, suffix, tmp_path):
    """Each cap's triangles face the cap's way and add up to its shoelace
    area (a fan across the notch has triangles turned the other way, and
    more area); the prism's signed volume is area times height, and trimesh
    and pymeshlab measure the hand-cut prism the same."""
    v, polygons, triangles = prism(name, first)
    path = write(tmp_path / f"p{suffix}", v, polygons)
    if path.suffix == ".obj":  # (which reader reads it: isoflow's, or trimesh's)
        assert (readers.read_simple(path) is None) == (suffix == "materials.obj")
    got_v, got_f = load_mesh(path)
    n = len(SHAPES[name][0])
    assert len(got_f) == len(triangles) == 2 * (n - 2) + 2 * n
    area = _shoelace(SHAPES[name][0])
    a, b, c = got_v[got_f[:, 0]], got_v[got_f[:, 1]], got_v[got_f[:, 2]]
    normal = np.cross(b - a, c - a) / 2
    for cap_z, sign in ((0.0, -1), (HEIGHT, 1)):
        cap = (a[:, 2] == cap_z) & (b[:, 2] == cap_z) & (c[:, 2] == cap_z)
        assert np.count_nonzero(cap) == n - 2
        assert (sign * normal[cap, 2] > 0).all()
        assert np.isclose(np.abs(normal[cap, 2]).sum(), area)
    volume = float(np.einsum("ij,ij->", a, np.cross(b, c))) / 6
    assert np.isclose(volume, area * HEIGHT)
    assert np.isclose(np.linalg.norm(normal, axis=1).sum(), 2 * area + HEIGHT * _perimeter(name))
    ref = trimesh.Trimesh(v, triangles, process=False)
    assert ref.is_watertight and np.isclose(ref.volume, volume) and np.isclose(ref.area, np.linalg.norm(normal, axis=1).sum())
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(got_v, got_f))
    measures = ms.get_geometric_measures()
    assert np.isclose(measures["mesh_volume"], area * HEIGHT) and np.isclose(measures["surface_area"], ref.area)


def _perimeter(name: str) -> float:
    p = np.asarray(SHAPES[name][0], float)
    return float(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1).sum())


@pytest.mark.parametrize("name, first", CASES)
def test_concave_prism_shell_is_its_triangle_twins(name, first, tmp_path):
    """``--fill shell`` of the polygon prism as OBJ (read by isoflow and by
    trimesh), OFF and PLY: the voxels
    of the same prism written as triangles (a fan across the notch adds
    voxels the prism does not have)."""
    v, polygons, triangles = prism(name, first)
    want = voxels(write(tmp_path / "t.obj", v, triangles), "shell")
    for suffix in FORMATS:
        assert np.array_equal(voxels(write(tmp_path / f"p{suffix}", v, polygons), "shell"), want), suffix


def test_concave_prism_flood_is_its_triangle_twins(tmp_path):
    v, polygons, triangles = prism("U", 4)
    want = voxels(write(tmp_path / "t.obj", v, triangles), "flood")
    for suffix in FORMATS:
        assert np.array_equal(voxels(write(tmp_path / f"p{suffix}", v, polygons), "flood"), want), suffix


@pytest.mark.parametrize("suffix", FORMATS)
def test_concave_prism_genus_is_0_without_self_intersection(suffix, tmp_path):
    """``isoflow genus``: a fan across the notch overlaps the cap's other
    triangles, and the prism was called self-intersecting."""
    v, polygons, _ = prism("U", 4)
    r = run("genus", write(tmp_path / f"p{suffix}", v, polygons), "--resolution", "8", "16", "--no-step", "--json", "-q")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["self_intersecting_faces"] == 0 and out["mesh"]["genus"] == 0 and out["solid_genus"] == 0
    assert out["reference"] == 0 and out["kind"] != "self_intersecting"


def test_a_tilted_concave_polygon_is_cut_in_its_own_plane():
    """A U turned out of every axis plane: its triangles still cover its
    area once, each facing the polygon's way."""
    outline = np.array(SHAPES["U"][0], float)
    flat = np.column_stack([outline, np.zeros(len(outline))])
    q, _ = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))
    rotation = q * np.sign(np.linalg.det(q))
    v = flat @ rotation.T * 1e3 + [4e5, -2e3, 7.0]  # far from the origin, as map data are
    for first in range(len(outline)):
        corners = np.roll(np.arange(len(outline)), -first)
        t = triangulate(corners, np.array([len(outline)]), v)
        n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]) / 2
        facing = n @ rotation[:, 2]
        assert (facing > 0).all() and np.isclose(facing.sum(), _shoelace(outline) * 1e6), first


def test_polygons_the_fan_keeps():
    """Convex polygons keep trimesh's fan; so do a non-planar hexagon, a
    bow tie (self-crossing) and a spike of no area, whose ear cut is not
    defined: the fan keeps their winding number."""
    hexagon = np.array([(np.cos(t), np.sin(t), 0.0) for t in np.arange(6) * np.pi / 3])
    fan6 = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]
    assert triangulate(np.arange(6), np.array([6]), hexagon).tolist() == fan6
    bent = np.array([(x, y, 0.0) for x, y in SHAPES["L"][0]])
    bent[[1, 2], 2] = 0.5  # the L folded out of its plane: its fan has a triangle turned back
    assert triangulate(np.arange(6), np.array([6]), bent).tolist() == fan6
    bow = np.array([(0, 0, 0), (2, 2, 0), (2, 0, 0), (0, 1, 0)], float)
    assert triangulate(np.arange(4), np.array([4]), bow).tolist() == [[0, 1, 2], [2, 3, 0]]
    spike = np.array([(0, 0, 0), (1, 0, 0), (2, 0, 0)], float)
    assert triangulate(np.array([0, 1, 2, 1]), np.array([4]), spike).tolist() == [[0, 1, 2], [2, 1, 0]]


def test_random_simple_polygons_of_mixed_sizes_are_each_covered_once():
    """Star-shaped polygons around a random inner point (simple, most of
    them concave, most of their first corners blind to some others) among
    triangles, tilted in space: each polygon's triangles face its way and
    add up to its shoelace area, in the rows its fan had."""
    rng = np.random.default_rng(7)
    sizes = rng.integers(3, 13, 300)
    outlines = []
    for k in sizes.tolist():
        step = np.full(k, 4.0)
        while step.max() >= np.pi:  # the inner point in the polygon's kernel: simple
            step = rng.uniform(0.2, 1.0, k)
            step *= 2 * np.pi / step.sum()
        angle = np.cumsum(step)
        radius = rng.uniform(0.2, 1.0, k)
        outlines.append(np.column_stack([radius * np.cos(angle), radius * np.sin(angle)]))
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))  # a rotation: the outlines stay counter-clockwise about q's third axis
    flat2 = np.vstack(outlines)
    v = np.column_stack([flat2, np.zeros(len(flat2))]) @ q.T + [5.0, -3.0, 2.0]
    corners = np.arange(len(v))
    t = triangulate(corners, sizes, v)
    fan = triangulate(corners, sizes)
    owner = np.repeat(np.arange(len(sizes)), sizes)
    assert np.array_equal(owner[t[:, 0]], owner[fan[:, 0]])  # each polygon's triangles where its fan's were
    facing = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]) @ q[:, 2] / 2
    assert (facing > -1e-12).all()
    area = np.bincount(owner[t[:, 0]], facing, minlength=len(sizes))
    np.testing.assert_allclose(area, [_shoelace(o) for o in outlines], rtol=1e-9)
    assert (fan != t).any(axis=1).sum() > 100  # (most polygons were not fans)


def six_cornered_prism():
    """The L prism (corner 0 first, whose fan crosses the notch) with every
    face a hexagon: each vertical edge has a vertex at mid-height, so each
    side is a rectangle of six corners (trimesh reads a binary PLY only
    when its faces are of one size, "PLY is unexpected length" otherwise)."""
    v, polygons, _ = prism("L", 0)
    n = len(SHAPES["L"][0])
    v = np.vstack([v, v[:n] + [0, 0, HEIGHT / 2]])
    sides = [[i, (i + 1) % n, 2 * n + (i + 1) % n, n + (i + 1) % n, n + i, 2 * n + i] for i in range(n)]
    return v, polygons[:2] + sides


def write_textured_ply(path: Path, v, faces, binary: bool, texture: str) -> Path:
    """A PLY file (float32 coordinates) with texture coordinates per
    ``"vertex"`` (properties ``s t``) or per ``"face"`` (a ``texcoord``
    list beside the corners): isoflow's reader reads both, as trimesh does
    (which splits the vertices at the texture's seams)."""
    v = np.asarray(v, np.float32)
    uv = v[:, :2] / 3
    head = f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\nelement vertex {len(v)}\n"
    head += "property float x\nproperty float y\nproperty float z\n"
    head += "property float s\nproperty float t\n" * (texture == "vertex")
    head += f"element face {len(faces)}\nproperty list uchar int vertex_indices\n"
    head += "property list uchar float texcoord\n" * (texture == "face") + "end_header\n"
    rows = [np.concatenate([v[i], uv[i]]) if texture == "vertex" else v[i] for i in range(len(v))]
    records = [(np.asarray(f), uv[f].reshape(-1)) for f in faces]
    if binary:
        body = b"".join(r.astype("<f4").tobytes() for r in rows)
        for f, t in records:
            body += np.uint8(len(f)).tobytes() + f.astype("<i4").tobytes()
            body += (np.uint8(len(t)).tobytes() + t.astype("<f4").tobytes()) * (texture == "face")
        path.write_bytes(head.encode() + body)
    else:
        text = "".join(" ".join(map(repr, r.tolist())) + "\n" for r in rows)
        for f, t in records:
            text += f"{len(f)} " + " ".join(map(str, f.tolist()))
            text += (f" {len(t)} " + " ".join(map(repr, t.tolist()))) * (texture == "face") + "\n"
        path.write_text(head + text)
    return path


@pytest.mark.parametrize("binary, texture", [(True, "vertex"), (True, "face"), (False, "vertex"), (False, "face")])
def test_textured_ply_read_by_trimesh_is_cut_as_isoflow_cuts(binary, texture, tmp_path, monkeypatch):
    """A PLY with texture coordinates was read by trimesh, which fanned the
    L caps across their notch: ``--fill shell`` then filled the notch and
    ``genus`` called the prism self-intersecting. isoflow's own reader cuts
    them by ears, and so does its reading through trimesh (files isoflow's
    reader leaves to it): the same arrays; the voxels of the prism written
    as triangles (by hand), genus 0 without self-intersection."""
    v, polygons = six_cornered_prism()
    path = write_textured_ply(tmp_path / "p.ply", v, polygons, binary, texture)
    ours = load_mesh(path)
    with monkeypatch.context() as m:
        m.setattr(ply, "read_ply", lambda data, where="": None)
        theirs = load_mesh(path)
    assert all(np.array_equal(a, b) for a, b in zip(ours, theirs, strict=True))
    tv, _, triangles = prism("L", 0)
    assert np.array_equal(voxels(path, "shell"), voxels(write(tmp_path / "t.obj", tv, triangles), "shell"))
    r = run("genus", path, "--resolution", "8", "16", "--no-step", "--json", "-q")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["self_intersecting_faces"] == 0 and out["mesh"]["genus"] == 0 and out["kind"] != "self_intersecting"


def test_textured_ply_of_several_face_sizes_is_cut_as_isoflow_cuts(tmp_path):
    """An ASCII PLY with texture coordinates per vertex whose faces are of
    several sizes (the L caps among quads): trimesh orders its triangles
    otherwise (triangles, quad halves, polygons), and its caps are cut too."""
    v, polygons, triangles = prism("L", 0)
    path = write_textured_ply(tmp_path / "p.ply", v, polygons, False, "vertex")
    assert np.array_equal(voxels(path, "shell"), voxels(write(tmp_path / "t.obj", v, triangles), "shell"))
    assert np.array_equal(voxels(path, "flood"), voxels(tmp_path / "t.obj", "flood"))
