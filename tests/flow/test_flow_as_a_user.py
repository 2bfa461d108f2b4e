"""``isoflow flow`` as a user reads it: the boxes it prints next to other
libraries' reading of the step volumes it writes, the step surfaces read
back by trimesh and pymeshlab, and what it says where it cannot do what
it is asked. The inputs are written by their own libraries (pynrrd,
NumPy) and the steps read back by them."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest


def isoflow(*args) -> subprocess.CompletedProcess:
    """The command as a user runs it."""
    return subprocess.run([sys.executable, "-m", "isoflow", *map(str, args)], capture_output=True, text=True)


#: voxel size and voxel 0's centre per axis (x, y, z), as a NRRD header holds them
PITCH, CENTRE = np.array([0.5, 0.25, 2.0]), np.array([10.0, -3.0, 7.0])


def ring_nrrd(path) -> np.ndarray:
    """A box with a tunnel along z, as pynrrd writes it (array axis 0 is x)."""
    nrrd = pytest.importorskip("nrrd")
    v = np.zeros((7, 8, 9), np.uint8)
    v[1:6, 2:7, 1:8] = 1
    v[3, 4, :] = 0
    nrrd.write(str(path), v, {"space": "left-posterior-superior", "space directions": np.diag(PITCH),
                              "space origin": CENTRE})
    return v


def skimage_world_box(path) -> list[float]:
    """The object's world box in a step volume, as pynrrd and scikit-image
    read it: regionprops' flat (min..., max...) voxel box, placed by the
    header (voxel i spans centre + pitch * (i -/+ 1/2))."""
    nrrd = pytest.importorskip("nrrd")
    measure = pytest.importorskip("skimage.measure")
    data, header = nrrd.read(str(path))
    (props,) = measure.regionprops((data > 0).astype(np.uint8))
    pitch, centre = np.diag(header["space directions"]), header["space origin"]
    lo, hi = np.reshape(props.bbox, (2, -1))
    return (centre + pitch * (lo - 0.5)).tolist() + (centre + pitch * (hi - 0.5)).tolist()


def test_flow_json_gives_a_box_as_info_and_scikit_image_do(tmp_path):
    # every step's bbox was [[lo...], [hi...]], where info --json, the
    # label table and scikit-image's regionprops give one flat list
    ring_nrrd(tmp_path / "ring.nrrd")
    p = isoflow("flow", tmp_path / "ring.nrrd", "--json", "--out", tmp_path / "run", "--volumes", ".nrrd")
    assert p.returncode == 0, p.stderr
    run = json.loads(p.stdout)
    info = json.loads(isoflow("info", tmp_path / "ring.nrrd", "--json").stdout)
    assert run["steps"][0]["bbox"] == pytest.approx(info["bbox"], abs=1e-12)
    for s in run["steps"]:
        if s["voxels"]:
            box = skimage_world_box(tmp_path / "run" / f"step_{s['step']:03d}.nrrd")
            assert s["bbox"] == pytest.approx(box, abs=1e-12), s["step"]
    (change,) = run["topology_changes"]
    assert len(change["where"]) == 6 and all(isinstance(x, float) for x in change["where"])

