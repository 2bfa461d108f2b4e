"""The scripts in examples/ run as a user runs them, and what they print and
write agrees with independently known values: the genus in
meshes/manifest.json, trimesh's V - E + F of the files written, and
scikit-image's Euler number of the volumes written."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from skimage.measure import euler_number

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
MANIFEST = {m["filename"]: m for m in json.loads((ROOT / "meshes" / "manifest.json").read_text())["meshes"]}


def genus(name: str) -> int:
    return MANIFEST[name]["genus"]


def run_example(name: str, out: Path, *args) -> str:
    """Run examples/NAME.py OUT ARGS from another directory; its stdout."""
    proc = subprocess.run([sys.executable, str(EXAMPLES / name), str(out), *map(str, args)],
                          capture_output=True, text=True, cwd=out.parent)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def test_every_example_is_tested_and_listed():
    scripts = {p.name for p in EXAMPLES.glob("[a-z]*.py")}
    tested = {n for n in globals() if n.startswith("test_")}
    assert {f"test_{Path(s).stem}" for s in scripts} <= tested
    listing = (EXAMPLES / "README.md").read_text()
    assert all(f"`{s}`" in listing for s in scripts)
    assert len(scripts) >= 6


def test_voxelize_topology(tmp_path):
    g = genus("torus.obj")
    out = run_example("voxelize_topology.py", tmp_path / "out")
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert report["betti"] == [1, g, 0]
    assert report["euler_characteristic"] == 1 - g and report["a_dot_n"] == 8 * (1 - g)
    assert [s["genus"] for s in report["surfaces"]] == [g]
    assert f"1 components, {g} tunnels, 0 cavities" in out
    with np.load(tmp_path / "out" / "solid.npz") as z:
        volume = z["volume"]
    assert int(volume.sum()) == report["voxels"]
    assert euler_number(volume, 1) == 1 - g
    # a second run does not replace the outputs: one line, exit 2
    again = subprocess.run([sys.executable, str(EXAMPLES / "voxelize_topology.py"), str(tmp_path / "out")],
                           capture_output=True, text=True)
    assert again.returncode == 2 and "exists" in again.stderr and "Traceback" not in again.stderr


def test_curvature_surface(tmp_path):
    g = genus("eight.off")  # genus 2: V - E + F = -2, sum of a = 8 chi = -8
    out = run_example("curvature_surface.py", tmp_path / "out", "--mesh", ROOT / "meshes" / "eight.off",
                      "--resolution", 32)
    ply = trimesh.load(tmp_path / "out" / "surface.ply", process=False)
    assert ply.euler_number == 2 - 2 * g
    columns = ply.metadata["_ply_raw"]["vertex"]["data"]
    assert int(columns["a"].sum()) == 8 * (1 - g)
    assert {"config", "class", "gamma", "a", "f", "red", "green", "blue"} <= set(columns.dtype.names)
    assert ply.visual.kind == "vertex"
    lo, hi = trimesh.load(ROOT / "meshes" / "eight.off").bounds
    assert np.all(ply.bounds[0] > lo - 0.1 * (hi - lo)) and np.all(ply.bounds[1] < hi + 0.1 * (hi - lo))
    import matplotlib.image

    assert matplotlib.image.imread(tmp_path / "out" / "surface.png").ndim == 3
    assert f"= {8 * (1 - g)} = 8 chi" in out and f"genus {g}" in out


def test_flow_export(tmp_path):
    g = genus("torus.obj")
    out = run_example("flow_export.py", tmp_path / "out")
    with open(tmp_path / "out" / "flow.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [int(rows[0][k]) for k in ("b0", "b1", "b2")] == [1, g, 0]
    assert int(rows[-1]["voxels"]) == 0 and "stopped: vanished" in out
    assert [int(r["step"]) for r in rows] == list(range(len(rows)))
    assert len(out.splitlines()) >= len(rows) + 3  # a line per step
    plys = sorted((tmp_path / "out").glob("step_*.ply"))
    assert len(plys) == sum(int(r["voxels"]) > 0 for r in rows)
    assert trimesh.load(plys[0], process=False).euler_number == 2 - 2 * g
    for name in ("flow.png", "shapes.png"):
        assert (tmp_path / "out" / name).stat().st_size > 0
    # the torus is symmetric: the flow ends at its centre (in mesh units)
    centre = trimesh.load(ROOT / "meshes" / "torus.obj").bounds.mean(axis=0)
    limit = [float(c) for c in out.split("limit point (")[1].split(")")[0].split(",")]
    assert np.allclose(limit, centre, atol=0.1)


def test_genus_table(tmp_path):
    run_example("genus_table.py", tmp_path / "out")
    with open(tmp_path / "out" / "genus.csv") as fh:
        rows = {r["mesh"]: r for r in csv.DictReader(fh)}
    meshes = {p.name for p in (ROOT / "meshes").iterdir() if p.suffix.lower() in (".stl", ".obj", ".ply", ".off")}
    assert set(rows) == meshes == set(MANIFEST)
    for name, m in MANIFEST.items():
        assert rows[name]["genus"] == ("-" if m["genus"] is None else str(m["genus"])), name
        assert rows[name]["components"] == str(m["components"]), name
    for name in ("bob_small.ply", "torus.obj", "eight.off", "spot.ply"):
        assert rows[name]["digital_64"] == str(genus(name)) and rows[name]["agree"] == "True"
    assert rows["plane_holes.obj"]["agree"] == "False"  # open: no genus to agree with


def test_zarr_cluster(tmp_path):
    pytest.importorskip("distributed")
    zarr = pytest.importorskip("zarr")
    g = genus("eight.off")
    out = run_example("zarr_cluster.py", tmp_path / "out")
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert report["chunked"] == report["in_memory"]
    assert report["chunked"]["betti"] == [1, g, 0]
    z = zarr.open_array(str(tmp_path / "out" / "solid.zarr"), mode="r")
    assert tuple(z.chunks) == (19, 29, 13) and all(s % c for s, c in zip(z.shape, z.chunks))
    volume = np.asarray(z[:])
    assert euler_number(volume, 1) == 1 - g == report["chunked"]["euler_characteristic"]
    assert "identical" in out and "2 worker processes" in out


def test_four_d(tmp_path):
    g = genus("eight.off")
    run_example("four_d.py", tmp_path / "out")
    reports = json.loads((tmp_path / "out" / "report.json").read_text())
    moving = np.load(tmp_path / "out" / "moving.npy")
    assert moving.ndim == 4 and all(euler_number(frame, 1) == 1 - g for frame in moving)
    for conn in (8, 80):
        m, s = reports[f"moving_{conn}"], reports[f"shell_{conn}"]
        # the moving solid is the solid itself up to homotopy; the shell is S^3
        assert (m["betti"][0], m["betti"][3], m["euler_characteristic"]) == (1, 0, 1 - g)
        assert (s["betti"][0], s["betti"][3], s["euler_characteristic"]) == (1, 1, 0)
        assert m["a_dot_n"] == 16 * m["euler_characteristic"]


def test_label_table(tmp_path):
    out = run_example("label_table.py", tmp_path / "out", "--size", "32", "--grains", "12")
    with open(tmp_path / "out" / "labels.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    image = np.load(tmp_path / "out" / "labels.npy")
    assert [int(r["label"]) for r in rows] == sorted(set(np.unique(image).tolist()) - {0})
    for row in rows:
        mask = image == int(row["label"])
        # scikit-image's Euler number of each label (6-connected), its voxels in units of 0.5
        assert int(row["euler_characteristic"]) == euler_number(mask, 1)
        assert float(row["volume"]) == mask.sum() * 0.125
    # the hollowed grain has its cavity, the drilled one its tunnel
    assert (int(rows[0]["b2"]), int(rows[1]["b1"])) == (1, 1)
    assert rows[0]["genera"] == "0;0" and "12 labels" in out
