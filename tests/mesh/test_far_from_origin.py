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


def isoflow(*args):
    """The command as a user runs it."""
    return subprocess.run([sys.executable, "-m", "isoflow", *map(str, args)], capture_output=True, text=True)


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
