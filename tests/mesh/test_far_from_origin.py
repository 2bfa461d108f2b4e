"""A mesh far from the origin voxelises as it does at the origin, from the
command line, wherever float64 places its voxels; where it cannot (a voxel
finer than the spacing of the coordinates) the grid is refused in one line.

The reference counts are closed forms: a box fills every layer of the grid
centred on it, ``ceil(side / pitch)`` of them along each side.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from in_process import isoflow_here

#: the 12 triangles of the box [0, 1]^3, outward
BOX_FACES = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
             [2, 3, 7], [2, 7, 6], [1, 2, 6], [1, 6, 5], [3, 0, 4], [3, 4, 7]]


def box_obj(path, offset: float, sides) -> None:
    """An OBJ of the box ``[offset, offset + sides]`` (each corner exact in
    float64 for the offsets used here)."""
    unit = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    corners = offset + unit * np.asarray(sides, float)
    assert np.array_equal(corners - offset, unit * np.asarray(sides, float))  # the box as written, exactly
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in corners.tolist())
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in BOX_FACES)
    path.write_text(text)


def isoflow(*args: object) -> subprocess.CompletedProcess:
    """The command's exit status, stdout and stderr, run in this process
    (what it reports is tested, not the shell: tests/in_process.py)."""
    return isoflow_here(*args)


def test_far_boxes_keep_the_count_at_the_origin(tmp_path):
    """A 400 x 125.25 x 62.625 box at 32 across: pitch 12.5, 32 x 11 x 6
    layers, every one inside, so 2112 voxels at any offset; its outermost
    centres lie 0.125 and 0.0625 from the faces, no more than the float64
    spacing near 1e15 (0.125), so the centres placed in absolute coordinates
    there fell on or past the faces. A 4 x 2 x 1 box (the case reported) at
    1e15: 32 x 16 x 8 = 4096 voxels; 3255 were counted."""
    for offset in (0.0, 1e6, 1e12, 1e15):
        path = tmp_path / f"box_{offset:g}.obj"
        box_obj(path, offset, (400, 125.25, 62.625))
        r = isoflow("info", path, "--resolution", 32, "--json")
        assert r.returncode == 0, r.stderr
        report = json.loads(r.stdout)
        assert (report["voxels"], report["voxelised"]["pitch"]) == (32 * 11 * 6, 12.5), offset
        assert report["voxels"] == 32 * math.ceil(125.25 / 12.5) * math.ceil(62.625 / 12.5)
    path, out = tmp_path / "box_4x2x1.obj", tmp_path / "box.npy"
    box_obj(path, 1e15, (4, 2, 1))
    r = isoflow("voxelize", path, "--resolution", 32, "-o", out)
    assert r.returncode == 0, r.stderr
    assert np.load(out).sum() == 32 * 16 * 8


@pytest.mark.parametrize("command", ["info", "voxelize"])
def test_voxels_finer_than_the_coordinates_are_refused(tmp_path, command):
    """A 64 x 32 x 16 box at 1e17, where float64 spaces numbers 16 apart:
    voxels of 2 cannot be placed there (resolution 4, voxels of 16, can)."""
    path = tmp_path / "far.obj"
    box_obj(path, 1e17, (64, 32, 16))
    r = isoflow(command, path, "--resolution", 32, *(["-o", tmp_path / "far.npy"] if command == "voxelize" else []))
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.splitlines() == [
        f"isoflow {command}: error: {path}: voxelize: --resolution 32 makes voxels of 2, finer than the float64 "
        "spacing 16.0 of the coordinates near 1e+17: the grid cannot be placed there; at most --resolution 4 can "
        "be, or move the mesh nearer the origin"]
    assert not (tmp_path / "far.npy").exists()


@pytest.mark.parametrize("scale", [2.0 ** 500, 2.0 ** -500])
def test_genus_json_of_a_volume_beyond_float64(scale, tmp_path, capsys):
    """A torus scaled by 2^500 has volume about 1.75 * 2^1500, past
    float64: --json printed "volume": Infinity, which no JSON parser
    reads (2^-500: "volume": 0, for a solid of one body). Its genus is
    manifold3d's, 1, at any scale."""
    import trimesh

    from isoflow.cli import main

    torus = trimesh.creation.torus(1, 0.3)
    path = tmp_path / "t.obj"
    path.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in (torus.vertices * scale).tolist())
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in torus.faces.tolist()))
    assert main(["genus", str(path), "--resolution", "24", "48", "--no-step", "--json", "-q"]) == 0

    def refuse(constant):
        raise ValueError(f"not a JSON number: {constant}")

    r = json.loads(capsys.readouterr().out, parse_constant=refuse)
    assert r["manifold3d"]["genus"] == r["solid"]["genus"] == 1 and r["kind"] == "agree"
    assert r["solid"]["volume"] is None and r["manifold3d"]["volume"] is None
    assert main(["genus", str(path), "--resolution", "24", "48", "--no-step", "-q"]) == 0
    assert "volume beyond float64's range" in capsys.readouterr().out


@pytest.mark.parametrize("suffix", [".npz", ".zarr"])
def test_a_volume_beyond_float64_is_compared_in_voxel_units(tmp_path, suffix):
    """A 4^3 cube of voxels 1e150 across at 1e150: its volume, 64e450, is
    past float64 (inf), and "volume inf: as isoflow counts" said that inf
    equals inf. The line gives the volume in exact decimal (Python
    integers: 64 times the cube of the float 1e150) and the unit it was
    compared in."""
    from fractions import Fraction

    import isoflow as api

    volume = np.zeros((6, 6, 6), bool)
    volume[1:5, 1:5, 1:5] = True
    obj = api.DigitalObject(volume, pitch=1e150, origin=(1e150, 1e150, 1e150))
    source = api.write_volume(obj, tmp_path / f"cube{suffix}")
    p = isoflow("surface", source, "-o", tmp_path / "cube.ply")
    assert p.returncode == 0, p.stderr
    exact = 64 * int(1e150) ** 3
    assert exact > sys.float_info.max  # inf in float64
    mantissa = float(Fraction(exact, 10**451))
    assert f"volume {mantissa:.6g}e+451 (beyond float64: compared in voxel units, " in p.stdout
    assert "volume inf" not in p.stdout


@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")  # trimesh's face normals of the file
@pytest.mark.parametrize("suffix", [".ply", ".obj", ".glb"])
def test_a_surface_near_float64s_largest_coordinates_is_read_back(tmp_path, suffix):
    """A 4^3 cube of voxels 1e306 across at 1e307: every coordinate is a
    float64 (at most 1.5e307), but the corners' sum is past float64's
    largest (1.8e308), and the read-back, which measures the volume about
    the corners' mean, made the mean inf and the volume NaN: "trimesh reads
    volume NaN", exit 1, for a file that holds the cube. The volume is the
    exact 6.4e919 (Python integers), genus 0, as trimesh reads the file
    scaled by an exact power of two."""
    from fractions import Fraction

    import trimesh

    import isoflow as api

    volume = np.zeros((6, 6, 6), bool)
    volume[1:5, 1:5, 1:5] = True
    obj = api.DigitalObject(volume, pitch=1e306, origin=(1e307, 1e307, 1e307))
    source = api.write_volume(obj, tmp_path / "cube.npz")
    out = tmp_path / f"cube{suffix}"
    p = isoflow("surface", source, "-o", out)
    assert p.returncode == 0, p.stderr
    exact = 64 * int(1e306) ** 3
    mantissa = float(Fraction(exact, 10**919))
    assert f"genus 0, volume {mantissa:.6g}e+919 (beyond float64: compared in voxel units, " in p.stdout
    read = trimesh.load(out, force="mesh", process=False)  # its merge rounds positions times 1e8: inf here
    scaled = trimesh.Trimesh(np.asarray(read.vertices) / 2.0 ** 1000, read.faces)  # exact: a power of two
    assert scaled.is_watertight and scaled.euler_number == 2
    assert math.isclose(scaled.volume, exact / 2 ** 3000, rel_tol=1e-9)


def far_torus_obj(path, offset: float) -> None:
    """trimesh's torus (radii 1 and 0.3) moved by ``offset`` along x, written
    with every float64 digit: far out, the file's coordinates are the
    torus rounded onto float64's grid there."""
    import trimesh

    m = trimesh.creation.torus(1.0, 0.3)
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in (m.vertices + [offset, 0, 0]).tolist())
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in m.faces.tolist())
    path.write_text(text)


def test_genus_names_coordinates_rounded_to_a_share_of_an_edge(tmp_path):
    """At 1e15 float64 spaces numbers 0.125 apart (np.spacing), most of the
    torus's median edge as trimesh reads the file: the verdict names that
    spacing and its share of the median edge as the likely cause of the
    crossings, welds and non-manifold edges it reports."""
    import trimesh

    path = tmp_path / "far15.obj"
    far_torus_obj(path, 1e15)
    # process=False: trimesh's own merge of close vertices fails at 1e15;
    # isoflow welds 3 of the rounded vertices, which moves the median by
    # about 3e-5 of itself
    read = trimesh.load(path, process=False)
    median = float(np.median(read.edges_unique_length))
    spacing = float(np.spacing(np.abs(read.vertices).max()))
    assert spacing == np.spacing(1e15) == 0.125
    r = isoflow("genus", path, "--json")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    [note] = [n for n in report["notes"] if n["kind"] == "float64_rounding"]
    assert note["facts"]["spacing"] == spacing
    assert note["facts"]["median_edge"] == pytest.approx(median, rel=1e-3)
    said = (f"coordinates near 1e+15 are held by float64 to 0.125, {100 * spacing / median:.0f} % of the median "
            f"edge ({median:.3g}): the crossings, welds and non-manifold edges above may be that rounding; move "
            "the mesh nearer the origin (subtract its centre) before saving it")
    assert report["verdict"].startswith("self-intersecting:")
    assert report["verdict"].count(said) == 1
    r = isoflow("genus", path)
    assert r.returncode == 0 and r.stdout.count(said) == 1
    # a grid coarser than the spacing is allowed, and says the same once
    r = isoflow("info", path, "--resolution", 16)
    assert r.returncode == 0 and r.stderr.count("coordinates near 1e+15 are held by float64 to 0.125,") == 1


@pytest.mark.parametrize("path", ["far9", "meshes/torus.obj"])
def test_genus_of_coordinates_held_finely_says_nothing_of_rounding(path, tmp_path):
    """At 1e9 float64's spacing (np.spacing: 1.2e-7) is a millionth of the
    torus's edges: the torus is a torus, genus 1, and no note of rounding;
    so for the torus at the origin."""
    if path == "far9":
        path = tmp_path / "far9.obj"
        far_torus_obj(path, 1e9)
    r = isoflow("genus", path, "--json")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert report["verdict"] == "agree: genus 1"
    assert not [n for n in report["notes"] if n["kind"] == "float64_rounding"]
    r = isoflow("info", path, "--resolution", 16)
    assert r.returncode == 0 and "float64" not in r.stderr


def test_printed_origin_of_a_far_grid_is_the_files(tmp_path):
    """A box at x = 999998.5 in voxels of 0.039: the origin printed by
    voxelize and info is the one pynrrd reads from the written file (NRRD's
    space origin is voxel 0's centre) to a hundredth of a voxel, not
    999998 (6 significant digits: 13 voxels away)."""
    nrrd = pytest.importorskip("nrrd")
    path, out = tmp_path / "far.obj", tmp_path / "far.nrrd"
    box_obj(path, 999998.5, (2.5, 2.5, 0.625))
    r = isoflow("voxelize", path, "--resolution", 64, "-o", out)
    assert r.returncode == 0, r.stderr
    data, header = nrrd.read(str(out))
    pitch = np.abs(np.diag(header["space directions"]))
    corner = header["space origin"] - pitch / 2
    info = isoflow("info", path, "--resolution", 64)
    assert info.returncode == 0, info.stderr
    for text in (r.stdout, info.stdout):
        printed = [float(x) for x in text.split("origin [", 1)[1].split("]", 1)[0].split(",")]
        assert np.abs(np.array(printed) - corner).max() < pitch.min() / 100, text


def test_genus_names_coordinates_a_float32_file_rounded(tmp_path):
    """A PLY of float properties (trimesh writes float32) stores a torus
    at 2e6 on float32's grid there, 0.125 apart (np.spacing): trimesh reads
    the file as not watertight, where the torus is, and genus called it
    self-intersecting without a word of why, as float64 holds 2e6 finely.
    The note names float32's spacing as the likely cause."""
    import trimesh

    torus = trimesh.creation.torus(1.0, 0.3)
    assert torus.is_watertight
    path = tmp_path / "far.ply"
    trimesh.Trimesh(torus.vertices + [1e6, -2e6, 5e5], torus.faces, process=False).export(path)
    read = trimesh.load(path, process=False)
    assert b"property float x" in path.read_bytes()[:300]  # the file's own type
    assert not trimesh.Trimesh(read.vertices, read.faces).is_watertight  # trimesh: the rounding opened it
    spacing = float(np.spacing(np.float32(np.abs(read.vertices).max())))
    assert spacing == 0.125
    median = float(np.median(read.edges_unique_length))
    r = isoflow("genus", path, "--json", "--resolution", 32, 64, "--no-step")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    [note] = [n for n in report["notes"] if n["kind"] == "float64_rounding"]
    assert (note["facts"]["precision"], note["facts"]["spacing"]) == ("float32", spacing)
    assert note["facts"]["median_edge"] == pytest.approx(median, rel=0.05)
    assert "are held by float32 (every coordinate is one, as the file stores them) to 0.125, " in report["verdict"]
    assert "or store float64 coordinates, before saving it" in report["verdict"]


def significant_digits(number: str) -> int:
    """How many significant digits a printed number shows."""
    mantissa = number.lower().split("e")[0].lstrip("+-").replace(".", "").lstrip("0")
    return len(mantissa)


@pytest.mark.parametrize("centre, side", [((1e9, 1e9, 1e9), 2.0 ** -20), ((1e6, 0.0, 0.0), 1e-30)])
def test_rounding_note_prints_numbers_a_reader_needs(centre, side, tmp_path):
    """A box of side 2^-20 at 1e9 (float64 spacing there 2^-23, np.spacing)
    and, the other way round, a box of side 1e-30 at x = 1e6 (its corners
    differ in y and z only): the note printed the spacing with every float64
    digit (1.1920928955078125e-07) and the second share as a percent of 23
    digits. Each number it prints has at most 6 significant digits and
    reads back as numpy's spacing and its share of trimesh's median edge."""
    import re

    import trimesh

    box = trimesh.creation.box(extents=(side, side, side))
    vertices = box.vertices + np.asarray(centre)
    path = tmp_path / "far.obj"
    path.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in vertices.tolist())
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in box.faces.tolist()))
    read = trimesh.load(path, process=False)
    spacing = float(np.spacing(np.abs(read.vertices).max()))
    share = spacing / float(np.median(read.edges_unique_length))
    r = isoflow("voxelize", path, "--resolution", 8, "-o", tmp_path / "far.npz")
    assert r.returncode == 0, r.stderr
    said = re.search(r"held by float64 to (\S+), (\S+) (% of|times) the median edge \((\S+)\)", r.stderr)
    assert said, r.stderr
    assert all(significant_digits(n) <= 6 for n in re.findall(r"\d[\d.]*(?:e[-+]\d+)?", said.group(0))), said.group(0)
    assert float(said.group(1)) == pytest.approx(spacing, rel=1e-5)
    printed = float(said.group(2)) / (100 if said.group(3) == "% of" else 1)
    assert printed == pytest.approx(share, rel=0.05)
    assert (said.group(3) == "times") == (100 * share >= 1e6)
