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

from isoflow.scale.compiled import COMPILE_NOTE


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


def box_store(path, pitch: float, x: float) -> None:
    """A box of voxels as zarr-python writes an OME-Zarr image, voxel 0's
    centre at (``x``, 0, 0) in voxels of ``pitch``."""
    zarr = pytest.importorskip("zarr")
    v = np.zeros((7, 8, 9), np.uint8)
    v[1:6, 2:7, 1:8] = 1
    group = zarr.open_group(str(path), mode="w")
    group.create_array("0", data=v, chunks=(4, 4, 4))
    group.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": a, "type": "space"} for a in "xyz"],
                                   "datasets": [{"path": "0", "coordinateTransformations": [
                                       {"type": "scale", "scale": [pitch] * 3},
                                       {"type": "translation", "translation": [x, 0.0, 0.0]}]}]}]


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


def test_flow_without_out_where_float64_cannot_place_the_voxels_answers_as_info_does(tmp_path):
    # refused (exit 2), while info answers there: the flow works on the voxels, and only the world
    # coordinates it prints are lost; they are null (? in the table), said in one warning
    from skimage.measure import euler_number

    nrrd = pytest.importorskip("nrrd")
    v = ring_nrrd(tmp_path / "ring.nrrd")
    data, header = nrrd.read(str(tmp_path / "ring.nrrd"))
    runs = {}
    for name, x in (("far", 1e43), ("near", 0.0)):
        header["space origin"] = np.array([x, 0.0, 0.0])
        nrrd.write(str(tmp_path / f"{name}.nrrd"), data, header)
        p = isoflow("flow", tmp_path / f"{name}.nrrd", "--json")
        assert p.returncode == 0, p.stderr
        runs[name] = (json.loads(p.stdout), p.stderr)
    assert np.float64(1e43) + PITCH[0] == np.float64(1e43)  # a voxel apart is one float64 there
    (far, said), (near, _) = runs["far"], runs["near"]
    line = said.strip()
    assert "\n" not in line and line.startswith("isoflow flow: warning: ") and "along axis 0" in line, said
    assert f"{np.spacing(1e43):.3g} apart (np.spacing)" in line
    # the numbers of the flow are those of the same voxels at the origin, step by step
    assert far["steps"][0]["euler_characteristic"] == euler_number(np.pad(v, 1), 1)
    numbers = ("voxels", "betti", "euler_characteristic", "energy")
    assert [[s[k] for k in numbers] for s in far["steps"]] == [[s[k] for k in numbers] for s in near["steps"]]
    assert far["stop_reason"] == near["stop_reason"] and len(far["topology_changes"]) == len(near["topology_changes"])
    # x is null, y and z as at the origin
    for f, n in zip(far["steps"], near["steps"]):
        assert (f["bbox"] is None) == (n["bbox"] is None)
        if f["bbox"] is not None:
            assert f["bbox"] == [None, *n["bbox"][1:3], None, *n["bbox"][4:]]
    assert far["limit"]["center"] == [None, *near["limit"]["center"][1:]]
    assert all(c["where"][0] is None for c in far["topology_changes"])
    text = isoflow("flow", tmp_path / "far.nrrd")
    assert text.returncode == 0 and "limit: [?, " in text.stdout and text.stderr.count("\n") == 1, text.stderr


def test_a_store_flowed_block_by_block_where_float64_cannot_place_it_is_refused(tmp_path):
    # flow.csv was written with every box 0 wide along x (bbox_min_x = bbox_max_x = 1e+43),
    # the step stores beside it, exit 0
    box_store(tmp_path / "far.zarr", 1.0, 1e43)
    p = isoflow("flow", tmp_path / "far.zarr", "--out", tmp_path / "run", "--volumes", ".zarr")
    line = p.stderr.strip()
    assert p.returncode == 2 and "\n" not in line and "Traceback" not in line, p.stderr
    assert "not distinct in float64" in line and f"{np.spacing(1e43):.3g} apart (np.spacing)" in line
    assert not (tmp_path / "run").exists()


def solid_torus() -> np.ndarray:
    """A solid torus about the x axis: one component, one tunnel all along its flow."""
    x, y, z = np.indices((12, 20, 20))
    return np.hypot(np.hypot(y - 9.5, z - 9.5) - 6, x - 5.5) <= 2.6


def test_flow_png_shows_b0_where_it_equals_b1(tmp_path):
    # a solid torus keeps b0 = b1 = 1 until it vanishes: b1's line was drawn
    # over b0's, the same width, and the panel showed no b0 at all
    from PIL import Image

    v = solid_torus()
    measure = pytest.importorskip("skimage.measure")
    assert measure.euler_number(v, connectivity=1) == 0  # b0 - b1 + b2 = 1 - 1 + 0, as scikit-image counts it
    np.save(tmp_path / "torus.npy", v)
    p = isoflow("flow", tmp_path / "torus.npy", "--out", tmp_path / "run", "--json", "-q")
    assert p.returncode == 0, p.stderr
    assert {tuple(s["betti"][:2]) for s in json.loads(p.stdout)["steps"][:-1]} == {(1, 1)}
    picture = np.asarray(Image.open(tmp_path / "run" / "flow.png").convert("RGB")).astype(int)
    height, width = picture.shape[:2]
    betti_panel = picture[height * 63 // 100: height * 93 // 100, width // 8: width * 3 // 4]  # (the legend is right)
    for rgb in ([31, 119, 180], [255, 127, 14]):  # b0, b1: tab:blue, tab:orange
        assert (np.abs(betti_panel - np.array(rgb)).sum(-1) < 60).sum() > 50, rgb


def test_flow_png_ticks_the_betti_numbers_in_whole_numbers(tmp_path, monkeypatch):
    # the Betti axis of a ring whose holes close one by one was ticked 0.5, 1.5, 2.5
    import isoflow
    from isoflow.flow import pictures

    v = np.zeros((30, 22), bool)
    v[2:28, 2:20] = True
    v[6:12, 6:16] = v[16:24, 5:9] = v[17, 14] = False
    ndimage = pytest.importorskip("scipy.ndimage")
    assert ndimage.label(~v)[1] - 1 == 3  # three holes, as scipy counts the background's parts
    drawn = []
    monkeypatch.setattr(pictures, "save_figure", lambda fig, path: drawn.append(fig) or path)
    pictures.render_flow(isoflow.run_flow(v, connectivity=4), tmp_path / "flow.png")
    axis = drawn[0].axes[2]
    low, high = axis.get_ylim()
    ticks = [t for t in axis.get_yticks() if low <= t <= high]
    assert len(ticks) > 1 and all(float(t).is_integer() for t in ticks), ticks


@pytest.mark.parametrize("shape", [(2, 2, 2), (2, 2)])
def test_shapes_png_says_one_voxel_or_pixel_in_the_singular(tmp_path, monkeypatch, shape):
    # the last panel of a cube's flow was titled "step 1: 1 voxels"
    import isoflow
    from isoflow.flow import pictures

    run = isoflow.run_flow(np.ones(shape, bool))
    last = run.states[1]
    ndimage = pytest.importorskip("scipy.ndimage")
    assert ndimage.sum(last.volume) == 1  # one cell left, as scipy counts it
    drawn = []
    monkeypatch.setattr(pictures, "save_figure", lambda fig, path: drawn.append(fig) or path)
    pictures.render_flow_shapes([(s, r) for s, r in zip(run.states, run.steps) if r["voxels"]], tmp_path / "s.png", 6)
    cell = "voxel" if len(shape) == 3 else "pixel"
    assert [ax.get_title() for ax in drawn[0].axes][-1] == f"step 1: 1 {cell}, betti {(1,) + (0,) * (len(shape) - 1)}"


@pytest.mark.parametrize("json_out", [[], ["--json"]])
def test_flow_without_out_where_float64_moves_the_corners_says_how_far(tmp_path, json_out):
    # the boxes and the limit point were printed to digits float64 does not
    # hold there ("limit: [1000000.0000000026, ...]"), without a word, where
    # flow --out and surface say how far float64 moves the corners
    nib = pytest.importorskip("nibabel")
    mask = np.zeros((6, 6, 6), np.uint8)
    mask[1:5, 1:5, 1:5] = 1
    affine = np.diag([1e-9, 1e-9, 1e-9, 1.0])
    affine[:3, 3] = (1e6, 0.0, 0.0)
    nib.save(nib.Nifti1Image(mask, affine), str(tmp_path / "far.nii.gz"))
    zoom = float(nib.load(str(tmp_path / "far.nii.gz")).header.get_zooms()[0])  # float32, as nibabel reads it
    p = isoflow("flow", tmp_path / "far.nii.gz", "--steps", "1", *json_out)
    assert p.returncode == 0, p.stderr
    # (where numba's cache is cold the process says so first, in a note line of its own)
    lines = [line for line in p.stderr.strip().splitlines() if not line.endswith(COMPILE_NOTE)]
    assert len(lines) == 1 and lines[0].startswith("isoflow flow: warning: "), p.stderr
    line = lines[0]
    assert f"{np.spacing(1e6):.3g} (np.spacing)" in line
    assert f"the boxes and the limit point printed move by up to {np.spacing(1e6) / zoom:.2g} voxels" in line
    nib.save(nib.Nifti1Image(mask, np.diag([1e-9, 1e-9, 1e-9, 1.0])), str(tmp_path / "near.nii.gz"))
    near = isoflow("flow", tmp_path / "near.nii.gz", "--steps", "1", *json_out)
    assert near.returncode == 0 and near.stderr == ""  # at the origin float64 holds them


def test_a_store_flowed_block_by_block_where_float64_moves_the_corners_says_how_far(tmp_path):
    # flow.csv's boxes and the step stores' origins moved by float64 without a word,
    # where the same store flowed in memory with --out warns
    box_store(tmp_path / "far.zarr", 1e-9, 1e6)
    p = isoflow("flow", tmp_path / "far.zarr", "--out", tmp_path / "run", "--volumes", ".zarr", "--steps", "1")
    assert p.returncode == 0, p.stderr
    # (where numba's cache is cold the process says so first, in a note line of its own)
    lines = [line for line in p.stderr.strip().splitlines() if not line.endswith(COMPILE_NOTE)]
    assert len(lines) == 1 and lines[0].startswith("isoflow flow: warning: "), p.stderr
    line = lines[0]
    assert f"{np.spacing(1e6):.3g} (np.spacing)" in line and f"by up to {np.spacing(1e6) / 1e-9:.2g} voxels" in line


def test_a_guarded_runs_table_names_each_steps_move_as_its_json_does(tmp_path):
    """A guarded run's text gave no sign of which steps were whole flow
    steps, partial ones or thinning, which ``--json`` gives per step: the
    table now has a ``move`` column and a ``moves:`` line of the counts.
    The thin diagonal ring at 26 needs partial or thinning steps (it cannot
    reach the other lattice by whole steps); every row's move and the
    counts are the JSON's, and the voxels of each row NumPy's count of the
    states the JSON reports."""
    from collections import Counter

    v = np.zeros((9, 9, 1), bool)
    for i in range(4):
        v[4 + i, i, 0] = v[8 - i, 4 + i, 0] = v[4 - i, 8 - i, 0] = v[i, 4 - i, 0] = True
    np.save(tmp_path / "ring.npy", v)
    args = ("flow", tmp_path / "ring.npy", "--guard", "--connectivity", "26")
    text, printed = isoflow(*args), isoflow(*args, "--json")
    assert text.returncode == printed.returncode == 0, text.stderr + printed.stderr
    steps = json.loads(printed.stdout)["steps"]
    rows = [line.split() for line in text.stdout.splitlines() if line.strip()[:1].isdigit()]
    assert [r[0] for r in rows] == [str(s["step"]) for s in steps]
    assert rows[0][1] == str(int(v.sum()))
    # a row: step, cells, parity, betti (three words), chi, energy, then the move (none at step 0)
    assert [r[8] if len(r) > 8 else None for r in rows] == [s.get("move") for s in steps]
    counts = Counter(s["move"] for s in steps[1:])
    assert counts["partial"] + counts["thinning"] > 0
    said = [line for line in text.stdout.splitlines() if line.strip().startswith("moves:")]
    assert said == ["  moves: " + ", ".join(f"{counts[k]} {k}" for k in ("flow", "partial", "thinning"))]


def test_the_limit_of_a_mesh_symmetric_about_0_prints_as_trimesh_places_its_centre():
    """The sample torus is centred on the origin (trimesh's bounds), and so
    are its voxels: the limit printed was ``[1.11022e-16, -1.38778e-17,
    1.11022e-16]``, float64's rounding of ``origin + pitch * lattice``,
    where a user reads the place trimesh gives, ``[0, 0, 0]``."""
    trimesh = pytest.importorskip("trimesh")
    from isoflow import data

    centre = trimesh.load(data.torus(), force="mesh").bounds.mean(axis=0)
    assert centre.tolist() == [0.0, 0.0, 0.0]
    p = isoflow("flow", data.torus(), "--resolution", 24, "-q")
    assert p.returncode == 0, p.stderr
    (limit,) = [line for line in p.stdout.splitlines() if line.strip().startswith("limit:")]
    assert limit.split(", the centre")[0].strip() == "limit: [0, 0, 0]", limit
