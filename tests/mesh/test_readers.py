"""The NumPy readers of plain STL, OBJ and PLY files against trimesh's path:
every file the fast path accepts loads to the same arrays as through
trimesh (after the weld), and a command on a plain file never imports
trimesh."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import without_compile_note
from in_process import isoflow_here

from isoflow.errors import IsoflowError
from isoflow.mesh import ply, readers
from isoflow.mesh.genus import mesh_topology
from isoflow.mesh.load import load_mesh

ROOT = Path(__file__).resolve().parents[2]
#: A folder of more mesh files to compare (a sweep of public meshes), if set.
EXTRA = os.environ.get("ISOFLOW_EXTRA_MESHES")
SUFFIXES = (".obj", ".stl", ".ply", ".off")


def _files():
    dirs = [ROOT / "meshes", ROOT / "tests" / "mesh" / "data"] + ([Path(EXTRA)] if EXTRA else [])
    return sorted(p for d in dirs for p in d.rglob("*") if p.suffix.lower() in SUFFIXES)


def _through_trimesh(p: Path, monkeypatch):
    with monkeypatch.context() as m:
        m.setattr(readers, "read_simple", lambda path: None)
        m.setattr(ply, "read_ply", lambda data, where="": None)
        return _load(p)


def _fast(p: Path):
    """What the NumPy reader of the file's kind gives (None: trimesh's turn)."""
    return ply.read_ply(p.read_bytes()) if p.suffix.lower() == ".ply" else readers.read_simple(p)


def _load(p: Path):
    stats: dict = {}
    try:
        v, f = load_mesh(p, stats=stats)
    except IsoflowError as exc:
        return str(exc)
    return v, f, stats


def _same(p: Path, monkeypatch, *, fast: bool | None = None):
    """Both paths give the same arrays, stats or error line; ``fast`` says
    whether the NumPy reader must accept the file."""
    if fast is not None:
        assert (_fast(p) is not None) == fast, p
    a, b = _load(p), _through_trimesh(p, monkeypatch)
    if isinstance(b, str):
        assert a == b
        return
    assert not isinstance(a, str), a
    assert a[0].dtype == b[0].dtype and a[1].dtype == b[1].dtype
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert a[2] == b[2]


@pytest.mark.parametrize("path", _files(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_mesh_files_load_as_through_trimesh(path, monkeypatch):
    _same(path, monkeypatch)


def test_the_sample_obj_stl_and_ply_files_take_the_fast_path():
    taken = [p.name for p in _files() if _fast(p) is not None]
    assert {"soup.obj", "rabbit.obj", "torus.obj", "panel.obj", "featuretype.STL", "bob_small.ply",
            "spot.ply"} <= set(taken)


QUAD = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
BOX = "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"
OBJ_CASES = {
    "triangles": (QUAD + "f 1 2 3\nf 1 3 4\nf 1 2 5\n", True),
    "quads": (QUAD + BOX, True),
    "pentagons": (QUAD + "v 2 2 2\nf 1 2 3 4 5\nf 5 6 7 8 9\nf 2 3 4 5 6\n", True),
    "mixed polygons": (QUAD + "v 2 2 2\nf 1 2 3 4 5 9\nf 1 2 6\nf 3 4 8 7\nf 1 5 8 4 2\n", True),
    "negative indices": (QUAD + "f -8 -7 -6 -5\nf -4 -3 -2 -1\nf 1 2 -3\n", True),
    "vt": (QUAD + "vt 0 0\nvt 1 0\nvt 1 1\n" + BOX.replace(" 1", " 1/1").replace(" 2", " 2/2")
           .replace(" 3", " 3/3").replace(" 4", " 4/1").replace(" 5", " 5/2").replace(" 6", " 6/3")
           .replace(" 7", " 7/1").replace(" 8", " 8/2"), True),
    "vt per corner": (QUAD + "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                      "f 1/1 2/2 3/3\nf 1/4 3/2 4/3\nf 3/1 2/4 5/2 6/3\n", True),
    "vn": (QUAD + "vn 0 0 1\nvn 0 1 0\n" + "".join(
        f"f {a}//1 {b}//2 {c}//1\n" for a, b, c in [(1, 2, 3), (1, 3, 4), (5, 6, 7), (8, 2, 4)]), True),
    "vt and vn": (QUAD + "vt 0 0\nvn 0 0 1\n" + "".join(
        f"f {a}/1/1 {b}/1/1 {c}/1/1\n" for a, b, c in [(1, 2, 3), (4, 3, 2), (8, 7, 6)]), True),
    "comments and groups": ("# a comment\nmtllib x.mtl\no box\n" + QUAD + "g side\ns 1\nusemtl red\n"
                            + BOX + "# end\n", True),
    "CRLF": ((QUAD + BOX).replace("\n", "\r\n"), True),
    "unused vertices": ("v 0 0 1e-13\n" + QUAD + "v 9 9 9\nf 2 3 4\nf 2 4 5\nf 3 4 6\n", True),
    "weld in tolerance": (QUAD + "v 1e-12 0 0\nf 9 2 3\nf 1 3 4\nf 1 2 5\n", True),
    "interleaved negatives": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -4 -3 -1\n", False),
    "two materials": (QUAD + "usemtl a\nf 1 2 3\nusemtl b\nf 1 3 4\n", False),
    "faces before the material": (QUAD + "f 1 2 3\nusemtl a\nf 1 3 4\n", False),
    "vertex colours": (QUAD.replace("\n", " 1 0 0\n") + "f 1 2 3\n", False),
    "lines": (QUAD + "f 1 2 3\nl 1 2\n", False),
    "trailing comment": (QUAD + "f 1 2 3 # one\n", False),
    "mixed face words": (QUAD + "vt 0 0\nf 1/1 2/1 3/1\nf 1 3 4\n", False),
    "tabs and spaces": (QUAD.replace("v ", "v  ").replace(" 0\n", "\t0 \n") + "f 1\t2  3 \nf  1 3 4\n", True),
    "negative with //": (QUAD + "vn 0 0 1\nf -1//1 -2//1 -3//1\nf -8//1 -7//1 -6//1\n", True),
    "negative with vt": (QUAD + "vt 0 0\nvt 1 1\nf -1/-1 -2/-1 -3/-2\nf -8/-2 -7/-1 -6/-1\nf -1/-1 -2/-2 -3/-2\n", True),
    "signs mixed with vt": (QUAD + "vt 0 0\nvt 1 1\nf -1/1 2/1 -3/2\nf 1/2 7/1 -6/1\n", False),
    "a word 1-2": (QUAD + "f 1 2 3\nf 1-2 3 4\n", False),
    "a word ending in /": (QUAD + "f 1/ 2/ 3/\n", False),
    "a word 1///2": (QUAD + "vn 0 0 1\nf 1///1 2///1 3///1\n", False),
    "forms mixed in a line": (QUAD + "vt 0 0\nvn 0 0 1\nf 1//1 2/1/1 3//1\n", False),
    "vt not numbers": (QUAD + "vt 0 x\nf 1/1 2/1 3/1\n", False),
    "vt of two sizes": (QUAD + "vt 0 0\nvt 1 1 1\nf 1/1 2/1 3/2\n", False),
    "two-corner face": (QUAD + "f 1 2 3\nf 1 2\n", False),
    "empty": ("", False),
    "vertices only": (QUAD, False),
}


@pytest.mark.parametrize("name", OBJ_CASES)
def test_generated_obj_loads_as_through_trimesh(name, tmp_path, monkeypatch):
    text, fast = OBJ_CASES[name]
    p = tmp_path / "m.obj"
    p.write_bytes(text.encode())
    _same(p, monkeypatch, fast=fast)


def _objects_with_relative_indices(faces_word) -> str:
    """Two unit cubes, three apart along x, each an ``o`` of its own with
    its vertices and then its quads by relative indices, as exporters that
    write each object on its own do."""
    text = "mtllib none.mtl\n"
    for k, x in enumerate((0, 3)):
        text += f"o cube{k}\nusemtl m{k}\n" + QUAD.replace("v 0 ", f"v {x} ").replace("v 1 ", f"v {x + 1} ")
        text += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        for line in BOX.splitlines():
            text += "f " + " ".join(faces_word(int(i) - 9, j - 4) for j, i in enumerate(line.split()[1:])) + "\n"
    return text


@pytest.mark.parametrize("form", ["i", "i/j"])
def test_relative_obj_indices_count_back_from_their_face(form, tmp_path, monkeypatch):
    """OBJ counts -1 as the last vertex above the face; trimesh counts from
    the end of the file, which gave both objects the second cube's
    vertices: one cube, its faces twice."""
    word = (lambda i, j: f"{i}") if form == "i" else (lambda i, j: f"{i}/{j}")
    p = tmp_path / "two.obj"
    p.write_text(_objects_with_relative_indices(word))
    v, f = load_mesh(p)
    assert len(v) == 16 and len(f) == 24
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.body_count == 2
    assert mesh.volume == pytest.approx(2.0)
    np.testing.assert_array_equal(mesh.bounds, [[0, 0, 0], [4, 1, 1]])
    _same(p, monkeypatch, fast=False)


def test_relative_obj_indices_split_into_their_objects(tmp_path):
    from isoflow.mesh.bodies import file_bodies

    p = tmp_path / "two.obj"
    p.write_text(_objects_with_relative_indices(lambda i, j: f"{i}"))
    bodies = file_bodies(p, split=True)
    assert sorted(b.vertices[:, 0].min() for b in bodies) == [0, 3]


def test_an_obj_face_with_index_0_is_refused_with_its_line(tmp_path):
    p = tmp_path / "zero.obj"
    p.write_text(QUAD + "f 1 2 3\nf 0 1 2\n")
    with pytest.raises(IsoflowError, match=r"zero.obj:10: face 'f 0 1 2' uses vertex index 0"):
        load_mesh(p)


#: OBJ files with a face index that names no vertex: the file, its bad face line
#: (found by its text, not by the reader), the index as written and what the
#: message says of it. trimesh fails with an IndexError on the first two kinds
#: and reads index 0 as vertex 1; the fast reader and trimesh's path (a file
#: of two materials is trimesh's) must both name the line.
BAD_INDEX = {
    "past the end": (QUAD + "f 1 2 3\n# a comment\n\nf 1 2 9\nf 1 2 3\n", "f 1 2 9", "9",
                     "past the file's 8 vertices"),
    "past the end, CRLF": ((QUAD + "f 1 2 3\nf 1 9 3\n").replace("\n", "\r\n"), "f 1 9 3", "9",
                           "past the file's 8 vertices"),
    "past the end, vt": (QUAD + "vt 0 0\nf 1/1 2/1 3/1\nf 1/1 2/1 12/1\n", "f 1/1 2/1 12/1", "12",
                         "past the file's 8 vertices"),
    "past the end, two materials": (QUAD + "usemtl a\nf 1 2 3\nusemtl b\nf 4 5 9\n", "f 4 5 9", "9",
                                    "past the file's 8 vertices"),
    "before the first": (QUAD + "f -1 -2 -3\nf -1 -2 -9\n", "f -1 -2 -9", "-9",
                         "before the first vertex (8 vertices come before the face; -1 is the last of them)"),
    "before the first, interleaved": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -5 -3 -1\n",
                                      "f -5 -3 -1", "-5", "before the first vertex (4 vertices come before"),
    "index 0": (QUAD + "f 1 2 3\nf 0 2 3\n", "f 0 2 3", "0", "but OBJ numbers vertices from 1 (-1 for the last)"),
    "index -0": (QUAD + "f 1 2 3\nf 2 -0 3\n", "f 2 -0 3", "-0", "but OBJ numbers vertices from 1"),
    "index 0, two materials": (QUAD + "usemtl a\nf 1 2 3\nusemtl b\nf 0 2 3\n", "f 0 2 3", "0",
                               "but OBJ numbers vertices from 1"),
}


@pytest.mark.parametrize("name", BAD_INDEX)
def test_an_obj_face_index_that_names_no_vertex_is_refused_with_its_line(name, tmp_path, monkeypatch):
    text, bad, index, words = BAD_INDEX[name]
    p = tmp_path / "m.obj"
    p.write_bytes(text.encode())
    line = text.splitlines().index(bad) + 1
    expected = f"{p}:{line}: face {bad!r} uses vertex index {index}, {words}"
    fast, through_trimesh = _load(p), _through_trimesh(p, monkeypatch)
    assert isinstance(fast, str) and fast.startswith(expected), (fast, expected)
    assert through_trimesh == fast


def test_a_bad_obj_index_is_found_without_a_line_scan_of_good_files(monkeypatch):
    """The line-by-line search runs only once an index is known bad (or a
    trimesh-read file may hold a 0): never on a good file."""
    monkeypatch.setattr(readers, "obj_index_error", lambda *a: pytest.fail("searched a good file"))
    for p in _files():
        if p.suffix == ".obj":
            _load(p)


def test_may_name_vertex_0_sees_a_zero_word_on_face_lines_only():
    seen = [b"f 0 1 2", b"v 0 0 0\nf 1 -0 2\n", b"v 1 0 0\nf 1 2 0", b"v 0 0 0\nf 1 2 0/1 4\n",
            b"v 0 0 0\r\nf 1 0 3\r\n", b"v 0 0 0\nf\t1\t0\t3\n"]
    not_seen = [b"v 0 0 0\nf 1 2 3\n", b"v 0 0 0\nf 1 2 1/0 4\n", b"v 0 0 0\nf 1 2 10\n", b"0", b"-0",
                b"vt 0 0\n", b"", b"\n", b"v 0.0 0 0\nf 1 2 3\n"]
    assert all(readers.may_name_vertex_0(d) for d in seen)
    assert not any(readers.may_name_vertex_0(d) for d in not_seen)


def _box_mesh():
    return trimesh.creation.box(extents=(1.0, 2.0, 3.0))


@pytest.mark.parametrize("kind", ["binary", "ascii"])
def test_stl_loads_as_through_trimesh(kind, tmp_path, monkeypatch):
    rng = np.random.default_rng(7)
    mesh = trimesh.util.concatenate([_box_mesh(), trimesh.Trimesh(rng.random((6, 3)) * 1e3 - 400, [[0, 1, 2], [3, 4, 5]])])
    p = tmp_path / "m.stl"
    data = mesh.export(file_type="stl" if kind == "binary" else "stl_ascii")
    p.write_bytes(data if isinstance(data, bytes) else data.encode())
    _same(p, monkeypatch, fast=True)
    if kind == "ascii":
        text = p.read_bytes()
        p.write_bytes(text.replace(b"\n", b"\r\n"))
        _same(p, monkeypatch, fast=True)
        p.write_bytes(b"solid Solid1 of SolidPart\n" + text.split(b"\n", 1)[1].replace(b"endsolid", b"endsolid Solid1"))
        _same(p, monkeypatch, fast=True)
        p.write_bytes(text + text)  # two solids: a scene in trimesh
        _same(p, monkeypatch, fast=False)


def test_binary_stl_with_a_solid_header_and_bad_files(tmp_path, monkeypatch):
    body = _box_mesh().export(file_type="stl")
    p = tmp_path / "m.stl"
    p.write_bytes(b"solid looks like text".ljust(80) + body[80:])
    _same(p, monkeypatch, fast=True)
    for data in (body[:-7], body[:80] + b"\0\0\0\0", b"", b"solid a\nendsolid a\nsolid b\nendsolid b\n"):
        p.write_bytes(data)
        _same(p, monkeypatch, fast=False)
        with pytest.raises(IsoflowError, match=str(p)):
            load_mesh(p)


def test_ascii_stl_without_endsolid_is_read(tmp_path):
    """An ASCII STL whose last facet is whole but whose "endsolid" line is
    missing was "not a valid STL file" (trimesh reads no triangles of it;
    pymeshlab reads them all); one cut inside a facet is refused, naming
    the facet."""
    torus = trimesh.creation.torus(1, 0.3)
    text = torus.export(file_type="stl_ascii")
    p = tmp_path / "t.stl"
    p.write_text(text.rsplit("endsolid", 1)[0])
    v, f = load_mesh(p)
    assert len(f) == len(torus.faces)
    r = mesh_topology(v, f)
    assert r["euler_number"] == torus.euler_number and r["genus"] == (2 - torus.euler_number) // 2
    p.write_text(text[:text.find("endloop", 2000)])
    with pytest.raises(IsoflowError, match=r"t\.stl: the file ends inside facet \d+ \(line \d+, its last\): cut short"):
        load_mesh(p)


def test_a_command_on_a_plain_obj_does_not_import_trimesh(tmp_path):
    """Nor the scipy modules of a weld or a graph's components (sparse,
    csgraph, spatial): each of those imports is a share of a short command."""
    out = tmp_path / "x.npy"
    code = ("import sys; from isoflow.cli import main\n"
            "try:\n    main(sys.argv[1:])\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'trimesh'"
            " or m.split('.')[:2] in (['scipy', 'sparse'], ['scipy', 'spatial'])))")
    r = subprocess.run([sys.executable, "-c", code, "voxelize", str(ROOT / "tests/mesh/data/soup.obj"),
                        "--resolution", "16", "-o", str(out), "--quiet"],
                       capture_output=True, text=True, env=dict(os.environ), check=True)
    assert out.exists()
    assert r.stdout.strip().splitlines()[-1] == "[]"


# PLY: a header, then the vertex and face elements as text or binary records

PLY_TYPES = {"float": "f4", "double": "f8", "uchar": "u1", "ushort": "u2", "int": "i4", "uint": "u4", "uint64": "u8"}


def _ply(v, faces, form="ascii", vtype="float", count="uchar", index="int", extra=(), face_extra="",
         texture=False, more="", newline="\n") -> bytes:
    """A PLY file of vertices (with ``extra`` properties of value 7) and
    polygons; ``face_extra`` and ``more`` add a face property and an
    element, ``texture`` texture coordinates."""
    names = ["x", "y", "z", *extra] + (["s", "t"] if texture else [])
    cols = np.column_stack([np.asarray(v, float)] + [np.full(len(v), 7.0)] * (len(names) - 3))
    head = ["ply", f"format {form} 1.0", "comment generated", f"element vertex {len(v)}"]
    head += [f"property {vtype} {n}" for n in names]
    head += [f"element face {len(faces)}", f"property list {count} {index} vertex_indices"]
    head += [f"property uchar {face_extra}"] if face_extra else []
    head += [more] if more else []
    head += ["end_header"]
    data = (newline.join(head) + newline).encode()
    if form == "ascii":
        rows = [" ".join(repr(float(x)) for x in row) for row in cols]
        rows += [" ".join(map(str, [len(f), *f] + ([1] if face_extra else []))) for f in faces]
        return data + (newline.join(rows) + newline).encode()
    e = "<" if form == "binary_little_endian" else ">"
    data += np.asarray(cols, e + PLY_TYPES[vtype]).tobytes()
    for f in faces:
        data += np.asarray([len(f)], e + PLY_TYPES[count]).tobytes() + np.asarray(f, e + PLY_TYPES[index]).tobytes()
        data += b"\1" if face_extra else b""
    return data


def _polygons(rng, nv: int, sizes) -> list:
    return [rng.choice(nv, int(s), replace=False).tolist() for s in sizes]


@pytest.mark.parametrize("form", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_generated_ply_loads_as_trimesh_reads_it(form, tmp_path, monkeypatch):
    """Random files of every kind trimesh reads: the same arrays (each
    coordinate rounded to its declared type, the polygons split in
    trimesh's order), checked on the reader's output itself and after
    load_mesh's weld."""
    rng = np.random.default_rng(11)
    p = tmp_path / "m.ply"
    for trial in range(24):
        nv = int(rng.integers(6, 30))
        v = rng.normal(size=(nv, 3)) * 10.0 ** int(rng.integers(-3, 4))
        sizes = [np.full(9, 3), np.full(9, 4), np.full(7, 5), rng.integers(3, 7, 12)][trial % 4]
        if form != "ascii" and trial % 4 == 3:
            continue  # polygons of several sizes: trimesh cannot read them binary (below)
        kw = dict(vtype=("float", "double")[trial % 2], count=("uchar", "int", "ushort")[trial % 3],
                  index=("int", "uint")[trial // 3 % 2], extra=("quality",) * (trial % 3 == 1),
                  newline="\r\n" if trial % 5 == 4 and form == "ascii" else "\n")
        p.write_bytes(_ply(v, _polygons(rng, nv, sizes), form, **kw))
        ours = ply.read_ply(p.read_bytes())
        theirs = trimesh.load(p, process=False, force="mesh")
        assert ours is not None, (trial, kw)
        assert ours[0].dtype == np.float64 and ours[1].dtype == np.int64
        np.testing.assert_array_equal(ours[0], theirs.vertices)
        np.testing.assert_array_equal(ours[1], theirs.faces)
        _same(p, monkeypatch, fast=True)


def test_binary_ply_of_polygons_of_several_sizes_reads_as_its_ascii_twin(tmp_path):
    """trimesh reads a binary file's faces as all the size of the first
    ("PLY is unexpected length"): isoflow reads it, to what trimesh gives
    for the same file in ASCII."""
    rng = np.random.default_rng(5)
    v = rng.normal(size=(20, 3))
    faces = _polygons(rng, 20, rng.integers(3, 8, 15))
    (tmp_path / "a.ply").write_bytes(_ply(v, faces, "ascii", "double"))
    (tmp_path / "b.ply").write_bytes(_ply(v, faces, "binary_big_endian", "double", "ushort", "uint"))
    with pytest.raises(Exception, match="unexpected length"):
        trimesh.load(tmp_path / "b.ply", process=False, force="mesh")
    twin = trimesh.load(tmp_path / "a.ply", process=False, force="mesh")
    v2, f2 = ply.read_ply((tmp_path / "b.ply").read_bytes())
    np.testing.assert_array_equal(v2, twin.vertices)
    np.testing.assert_array_equal(f2, twin.faces)
    # a 64-bit count past any file (damaged): one line, not an OverflowError
    head = _ply(v[:3], [[0, 1, 2]], "binary_little_endian", count="uint64")
    tail = np.array([2**64 - 1], "<u8").tobytes() + np.array([0, 1, 2], "<i4").tobytes()
    damaged = head.replace(b"element face 1", b"element face 2") + tail
    assert ply.read_ply(head) is not None
    with pytest.raises(IsoflowError, match="^m.ply: the binary body ends inside row 1 of element 'face' "):
        ply.read_ply(damaged, "m.ply")


@pytest.mark.parametrize("case", ["texture", "face property", "edge element", "two-corner face"])
def test_ply_with_more_than_vertices_and_faces_loads_as_through_trimesh(case, tmp_path, monkeypatch):
    """Texture coordinates (trimesh splits the vertices at their seams; the
    weld joins them again), a face property, another element, a face of two
    corners (trimesh drops it): isoflow's reader reads them, to trimesh's
    arrays."""
    rng = np.random.default_rng(2)
    v = rng.normal(size=(8, 3))
    faces = _polygons(rng, 8, [3, 3, 3])
    kw: dict = {"texture": dict(texture=True), "face property": dict(face_extra="flags"),
                "edge element": dict(more="element edge 0\nproperty int vertex1\nproperty int vertex2")}.get(case, {})
    if case == "two-corner face":
        faces[1] = faces[1][:2]
    p = tmp_path / "m.ply"
    p.write_bytes(_ply(v, faces, "binary_little_endian" if case != "two-corner face" else "ascii", **kw))
    _same(p, monkeypatch, fast=True)


def test_ply_without_faces_is_left_to_trimesh(tmp_path, monkeypatch):
    p = tmp_path / "m.ply"
    p.write_bytes(_ply(np.eye(3), [], "binary_little_endian"))
    _same(p, monkeypatch, fast=False)


def test_a_command_on_a_plain_ply_does_not_import_trimesh(tmp_path):
    code = ("import sys; from isoflow.cli import main\n"
            "assert main(sys.argv[1:]) == 0\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'trimesh'))")
    r = subprocess.run([sys.executable, "-c", code, "info", str(ROOT / "meshes/bob_small.ply"), "--resolution", "16",
                        "--quiet"], capture_output=True, text=True, env=dict(os.environ), check=True)
    assert r.stdout.strip().splitlines()[-1] == "[]"


@pytest.mark.parametrize("rtol", [1, 2.5, -1e-9, "x", None, float("nan")])
def test_a_weld_tolerance_outside_0_1_is_refused_for_a_file_and_a_mesh_in_memory(rtol):
    """1 or more would weld every vertex into one, whatever the mesh."""
    from isoflow.mesh.load import mesh_input

    box = trimesh.creation.box()
    for given in (ROOT / "meshes" / "torus.obj", box, (box.vertices, box.faces)):
        with pytest.raises(IsoflowError, match=r"merge_rtol must be a number in \[0, 1\)"):
            mesh_input(given, merge_rtol=rtol)


# PLY files of every kind of property and element (any header: _write_ply)

PLY_FORMS = ["ascii", "binary_little_endian", "binary_big_endian"]
PLY_FLOATS = {"float", "double", "float32", "float64"}


def _write_ply(path: Path, form: str, elements: list) -> Path:
    """A PLY file of ``elements``, each ``(name, properties, rows)``: a
    property is ``(type, name)`` or ``(("list", count type, item type),
    name)``, a row a value per property (a sequence for a list)."""
    head = ["ply", f"format {form} 1.0", "comment written by test_readers"]
    for name, props, rows in elements:
        head.append(f"element {name} {len(rows)}")
        head += [f"property {t} {n}" if isinstance(t, str) else f"property list {t[1]} {t[2]} {n}" for t, n in props]
    data = ("\n".join(head + ["end_header"]) + "\n").encode()
    e = ">" if form == "binary_big_endian" else "<"
    for _, props, rows in elements:
        for row in rows:
            words, cells = [], b""
            for (t, _), x in zip(props, row):
                kind = t if isinstance(t, str) else t[2]
                items = list(x) if not isinstance(t, str) else [x]
                word = (lambda y: repr(float(y))) if kind in PLY_FLOATS else (lambda y: str(int(y)))
                words += ([str(len(items))] if not isinstance(t, str) else []) + [word(y) for y in items]
                if not isinstance(t, str):
                    cells += np.asarray(len(items), e + ply.TYPES[t[1]]).tobytes()
                cells += np.asarray(items, e + ply.TYPES[kind]).tobytes()
            data += (" ".join(words) + "\n").encode() if form == "ascii" else cells
    path.write_bytes(data)
    return path


#: an L-shaped prism: the L's corners at z = 0 and at z = 1
L_CAP = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
L_PRISM = np.array([(x, y, z) for z in (0, 1) for x, y in L_CAP], float) * 1.5 + 0.25
#: its polygons: the concave L caps (6 corners), five sides as quads, one as two triangles
L_FACES = [[5, 4, 3, 2, 1, 0], [6, 7, 8, 9, 10, 11], [0, 1, 7], [0, 7, 6]] + [
    [i, (i + 1) % 6, (i + 1) % 6 + 6, i + 6] for i in range(1, 6)]
#: the same prism as triangles, cut by hand (the L as four triangles inside it)
L_TRIANGLES = [[0, 2, 1], [0, 3, 2], [0, 5, 3], [3, 5, 4], [6, 7, 8], [6, 8, 9], [6, 9, 11], [9, 10, 11]] + [
    t for i in range(6) for t in ([i, (i + 1) % 6, (i + 1) % 6 + 6], [i, (i + 1) % 6 + 6, i + 6])]
PLY_VARIANTS = ["u v", "s t", "texcoord", "normals, colours, edges, materials"]


def _prism_elements(variant: str | None, triangles: bool = False, trimesh_reads: bool = False) -> list:
    """The L prism's elements with the properties and elements of
    ``variant`` beside its positions and corner lists (None: none). Unless
    ``trimesh_reads``, the materials' names are lists of two lengths and
    the edges have a colour: trimesh cannot read either in a binary file
    ("PLY is unexpected length", "edges are not (n, 2)")."""
    faces = L_TRIANGLES if triangles else L_FACES
    xyz_type, corner_type = {"u v": ("float", ("list", "uchar", "int")), "s t": ("double", ("list", "ushort", "uint32")),
                             "texcoord": ("float32", ("list", "uint8", "int32")),
                             "normals, colours, edges, materials": ("float", ("list", "int", "uint"))}.get(
                                 variant or "", ("float", ("list", "uchar", "int")))
    vprops: list = [(xyz_type, c) for c in "xyz"]
    vrows = [list(p) for p in L_PRISM]
    fprops: list = [(corner_type, "vertex_indices")]
    frows: list = [[f] for f in faces]
    before, after = [], []
    if variant in ("u v", "s t"):
        vprops += [("float" if variant == "u v" else "float32", c) for c in variant.split()]
        vrows = [r + [0.25 * i, 1 - 0.125 * i] for i, r in enumerate(vrows)]
    if variant == "texcoord":  # a texture coordinate per corner: every corner its own
        fprops.append((("list", "uchar", "float"), "texcoord"))
        frows = [r + [[0.01 * (7 * j + k) for k in range(2 * len(r[0]))]] for j, r in enumerate(frows)]
    if variant == "normals, colours, edges, materials":
        vprops += [("float", n) for n in ("nx", "ny", "nz")] + [("uchar", c) for c in ("red", "green", "blue", "alpha")]
        vrows = [r + [0.0, 0.0, 1.0, 200, 100, 50, 255] for r in vrows]
        fprops = [("uchar", "red"), ("int16", "flags")] + fprops + [("uchar", "green")]
        frows = [[9, -3] + r + [7] for r in frows]
        names = [b"steel", b"brass" if trimesh_reads else b"wood"]
        before = [("material", [("uchar", "ambient_red"), ("float", "ambient_coeff"), (("list", "uchar", "char"), "name")],
                   [[255, 0.5, names[0]], [0, 1.0, names[1]]])]
        edges = [("int", "vertex1"), ("int", "vertex2")] + [("uchar", "red")] * (not trimesh_reads)
        after = [("edge", edges, [[0, 1, 5], [1, 2, 5], [2, 8, 5]])]
    return before + [("vertex", vprops, vrows), ("face", fprops, frows)] + after


def _info(path: Path) -> dict:
    r = isoflow_here("info", str(path), "--resolution", "16", "--json")  # the report is tested, not the shell
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    got.pop("input")
    return got


@pytest.mark.parametrize("form", PLY_FORMS)
def test_ply_with_texture_normals_colours_and_more_elements_reads_as_the_plain_file(form, tmp_path):
    """A PLY holding, beside its positions and corner lists, texture
    coordinates (per vertex, ``u v`` or ``s t``, or per face), normals,
    colours, face properties, an ``edge`` and a ``material`` element, with
    faces of 3, 4 and 6 corners (the L caps, concave): ``isoflow info``
    reads each as it reads the same prism written with nothing else, a
    solid of one piece without tunnels. trimesh fails on several (a
    binary file "of unexpected length", per-face texture lists of several
    lengths a shape mismatch), and isoflow said "cannot read as a mesh"."""
    plain = _info(_write_ply(tmp_path / "plain.ply", "ascii", _prism_elements(None)))
    assert plain["betti"] == [1, 0, 0] and plain["surfaces"][0]["genus"] == 0
    for variant in PLY_VARIANTS:
        path = _write_ply(tmp_path / f"{variant.split(',')[0].replace(' ', '_')}.ply", form, _prism_elements(variant))
        assert _info(path) == plain, variant


@pytest.mark.parametrize("form", PLY_FORMS)
@pytest.mark.parametrize("variant", PLY_VARIANTS)
def test_ply_with_every_kind_of_property_loads_as_trimesh_reads_it(form, variant, tmp_path, monkeypatch):
    """Where trimesh reads the file, the same arrays: its triangles'
    corners (trimesh splits textured vertices at their seams), all its
    vertices where it keeps the file's, and the same arrays after
    load_mesh's weld; where it fails, the failures isoflow no longer
    shares."""
    for triangles in (True, False):
        p = _write_ply(tmp_path / "m.ply", form, _prism_elements(variant, triangles, trimesh_reads=True))
        ours = ply.read_ply(p.read_bytes())
        assert ours is not None
        try:
            theirs = trimesh.load(p, process=False, force="mesh")
        except Exception as exc:  # faces of several sizes, binary; per-face texture lists of several lengths
            assert not triangles and (form != "ascii" or variant == "texcoord"), exc
            assert "unexpected length" in str(exc) or "shape" in str(exc)
            continue
        assert not (not triangles and variant == "texcoord")
        if triangles:  # (polygons: trimesh fans the concave L across its notch)
            np.testing.assert_array_equal(ours[0][ours[1]], theirs.vertices[theirs.faces])
            np.testing.assert_array_equal(ours[1], L_TRIANGLES)
        if variant in ("normals, colours, edges, materials", ):
            np.testing.assert_array_equal(ours[0], theirs.vertices)
        _same(p, monkeypatch, fast=True)


def _broken(case: str, path: Path) -> Path:
    """The L prism's file (texture coordinates per face: lists of several
    lengths) spoiled as ``case`` says."""
    form = "ascii" if case.startswith("ASCII") else "binary_big_endian" if "big" in case else "binary_little_endian"
    elements = _prism_elements("texcoord")
    if "index" in case:
        elements[1][2][2][0] = [0, 1, 99 if "past" in case else -1]
    data = _write_ply(path, form, elements).read_bytes()
    body = data.index(b"end_header\n") + 11
    data = {"binary cut short": data[:-3], "binary big-endian cut in the vertices": data[:body + 100],
            "ASCII cut short": data[:data.rindex(b"\n", 0, -1) + 1],
            "ASCII vertex row too long": data[:body] + data[body:].replace(b"\n", b" 7.0\n", 1),
            "ASCII one face more than the header's": data.replace(b"element face 9", b"element face 8"),
            "ASCII word not a number": data[:body] + data[body:].replace(b" ", b" x", 1)}.get(case, data)
    path.write_bytes(data)
    return path


#: PLY files that do not match their headers, and the line saying what is wrong
PLY_BROKEN = {
    "binary cut short": "the binary body ends inside row 8 of element 'face' (of 9): the file is cut short, or the "
                        "header's counts do not match the data",
    "binary big-endian cut in the vertices": "the binary body ends inside row 8 of element 'vertex' (of 12)",
    "binary index past the vertices": "face 2 names vertex 99, but the file's vertices are numbered 0 to 11",
    "binary big-endian negative index": "face 2 names vertex -1, but the file's vertices are numbered 0 to 11",
    "ASCII index past the vertices": "face 2 names vertex 99, but the file's vertices are numbered 0 to 11",
    "ASCII cut short": "the ASCII body ends inside row 8 of element 'face' (of 9)",
    "ASCII vertex row too long": "line 12 holds 4 numbers, but row 0 of element 'vertex' takes 3 (the header's "
                                 "properties or counts do not match the data)",
    "ASCII one face more than the header's": "the header's rows take 154 numbers, but the body holds 168 (the "
                                             "header's counts do not match the data)",
    "ASCII word not a number": "line 12: 'x",  # the word named: was "line 12: a word that is not a number"
}


@pytest.mark.parametrize("case", PLY_BROKEN)
def test_a_ply_that_does_not_match_its_header_is_refused_in_one_line(case, tmp_path):
    p = _broken(case, tmp_path / "m.ply")
    with pytest.raises(IsoflowError) as exc:
        load_mesh(p)
    assert str(exc.value).startswith(f"{p}: {PLY_BROKEN[case]}"), str(exc.value)


def test_an_ascii_ply_with_a_decimal_comma_names_the_word(tmp_path):
    """A vertex row ``1,5 0 0`` (a writer in a locale with decimal commas):
    the line named the line alone, not the word; trimesh cannot read it."""
    import trimesh

    rows = ["0 0 0", "1,5 0 0", "0 1 0", "0 0 1"]
    text = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 4\nproperty list uchar int vertex_indices\nend_header\n" + "\n".join(rows)
            + "\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
    p = tmp_path / "m.ply"
    p.write_text(text)
    with pytest.raises(ValueError):
        trimesh.load(p, process=False)
    line = text.splitlines().index("1,5 0 0") + 1
    with pytest.raises(IsoflowError) as exc:
        load_mesh(p)
    assert str(exc.value) == f"{p}: line {line}: '1,5' is not a number (PLY writes decimals with a point: 1.5)"


@pytest.mark.parametrize("case", ["binary cut short", "binary index past the vertices"])
def test_the_cli_refuses_a_broken_ply_in_one_line_with_exit_2(case, tmp_path):
    p = _broken(case, tmp_path / "m.ply")
    r = subprocess.run([sys.executable, "-m", "isoflow", "info", str(p), "--resolution", "16"],
                       capture_output=True, text=True, env=dict(os.environ), timeout=300)
    assert r.returncode == 2
    assert without_compile_note(r.stderr).strip() == f"isoflow info: error: {p}: {PLY_BROKEN[case]}"


@pytest.mark.parametrize("form", ["ascii", "binary_little_endian"])
@pytest.mark.parametrize("kept", ["xz", "xy", ""])
def test_a_ply_whose_vertices_lack_a_coordinate_says_which(form, kept, tmp_path):
    """A vertex element without x, y or z was handed to trimesh, which
    fails on a KeyError ("cannot read as a mesh (KeyError: 'y')"): the line
    now names the missing coordinate and the properties there are."""
    import struct

    import trimesh

    props = "".join(f"property float {c}\n" for c in kept) + "property uchar red\n"
    head = (f"ply\nformat {form} 1.0\nelement vertex 3\n{props}element face 1\n"
            "property list uchar int vertex_indices\nend_header\n").encode()
    rows = [[0.0] * len(kept) + [9], [1.0] * len(kept) + [9], [2.0] * len(kept) + [9]]
    if form == "ascii":
        body = "".join(" ".join(map(str, r)) + "\n" for r in rows).encode() + b"3 0 1 2\n"
    else:
        body = b"".join(struct.pack(f"<{len(kept)}fB", *r) for r in rows) + struct.pack("<B3i", 3, 0, 1, 2)
    p = tmp_path / "m.ply"
    p.write_bytes(head + body)
    with pytest.raises((KeyError, ValueError)):  # the independent reader cannot place these vertices either
        trimesh.load(p, process=False)
    lost = ", ".join(repr(c) for c in "xyz" if c not in kept)
    listed = ", ".join([*kept, "red"])
    r = subprocess.run([sys.executable, "-m", "isoflow", "info", str(p), "--resolution", "8"],
                       capture_output=True, text=True, env=dict(os.environ), timeout=300)
    assert r.returncode == 2
    assert r.stderr.strip() == (f"isoflow info: error: {p}: the header's element 'vertex' has no property {lost} "
                                f"(its properties: {listed}), so its vertices have no positions")


def test_obj_polygons_fanned_as_trimesh_fans_them_where_asked(tmp_path):
    """``read_obj(ears=False)`` gives trimesh.load's triangles for every
    polygon, a concave L too (whose fan from its first corner leaves it,
    and which the reader otherwise cuts by ears), among quads and
    triangles."""
    text = (b"v 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 0 0 1\nv 2 0 1\n"
            b"f 1 2 3 4 5 6\nf 1 6 7 8\nf 2 1 8\n")
    path = tmp_path / "l.obj"
    path.write_bytes(text)
    tm = trimesh.load(path, force="mesh", process=False)
    vertices, faces = readers.read_obj(text, ears=False)
    np.testing.assert_array_equal(vertices, tm.vertices)
    np.testing.assert_array_equal(faces, tm.faces)
    assert not np.array_equal(readers.read_obj(text)[1], tm.faces)  # cut by ears there
