"""The digital curvature flow (section 5, docs/flow.md) and topology control.

Expected values are known independently of the code: Example 19 of the paper,
boxes and rectangles (one layer per axis per step), the L of five squares,
shapes whose topology is known by construction, and a slow per-vertex
re-implementation of the rule table.
"""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import ball

from isoflow import DigitalObject, read_object
from isoflow.cli import main
from isoflow.digital.configurations import configurations
from isoflow.digital.indices import CONVEX, FLAT, NONE, class_lut, code_lut, f_lut, planar_class_lut
from isoflow.digital.simple import simple_points
from isoflow.digital.topology import betti_numbers
from isoflow.errors import IsoflowError
from isoflow.flow.guard import guarded_step
from isoflow.flow.motion import flow_moves, flow_step
from isoflow.flow.planar import planar_flow_step
from isoflow.flow.run import run_flow

ROOT = Path(__file__).resolve().parents[2]


def voxel_counts(result):
    return [s["voxels"] for s in result.steps]


def dumbbell(n=6, bar=4):
    v = np.zeros((2 * n + bar, n, n), bool)
    v[:n] = v[n + bar:] = True
    v[n:n + bar, n // 2, n // 2] = True
    return v


def annulus_prism(outer=12, hole=6, height=4):
    v = np.ones((outer, outer, height), bool)
    a = (outer - hole) // 2
    v[a:a + hole, a:a + hole] = False
    return v


def union_of_boxes(rng, size=10, count=4):
    v = np.zeros((size,) * 3, bool)
    for _ in range(count):
        lo = rng.integers(0, size - 1, 3)
        hi = lo + rng.integers(1, 6, 3)
        v[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]] = True
    return v


def blob(rng, size=10):
    from scipy.ndimage import gaussian_filter

    f = gaussian_filter(rng.random((size,) * 3), 1.2)
    return f > np.quantile(f, rng.uniform(0.5, 0.7))


# --------------------------------------------------------------------------
# Known flows
# --------------------------------------------------------------------------


def test_example_19_cube_then_point():
    obj = read_object(ROOT / "meshes" / "example19.txt")
    r = run_flow(obj)
    assert voxel_counts(r) == [4, 1, 0]
    one = r.states[1]
    lo, hi = one.bbox()
    assert lo.tolist() == [0.5, 0.5, 0.5] and hi.tolist() == [1.5, 1.5, 1.5]  # eq. 5.21
    assert r.stop_reason == "vanished"
    assert r.limit["center"] == [1.0, 1.0, 1.0]  # "P converges to the point (1,1,1)"
    assert r.limit["last_shape"] == "cuboid"


def test_box_loses_one_layer_per_axis_per_step():
    r = run_flow(DigitalObject(np.ones((3, 4, 5), bool)))
    assert voxel_counts(r) == [60, 24, 6, 0]
    assert r.limit["center"] == [1.5, 2.0, 2.5]
    assert all(r.steps[k]["betti"] == [1, 0, 0] for k in range(3))
    assert r.topology_changes == []  # vanishing is the limit, not a change


@pytest.mark.parametrize("connectivity", [6, 26])
def test_box_with_world_placement(connectivity):
    obj = DigitalObject(np.ones((4, 4, 6), bool), offset=(3, -2, 5), pitch=0.5, origin=(10.0, 0.0, -1.0))
    r = run_flow(obj, connectivity=connectivity)
    assert voxel_counts(r) == [96, 45, 16, 3, 0]
    # the box [3,7]x[-2,2]x[5,11] (lattice) shrinks about its centre (5, 0, 8)
    assert r.limit["center"] == [10 + 0.5 * 5, 0.0, -1 + 0.5 * 8]


def test_planar_l_of_five_squares():
    v = np.zeros((3, 3), bool)
    v[:, 0] = v[0, :] = True  # arms of length 3
    r = run_flow(DigitalObject(v))
    assert voxel_counts(r) == [5, 3, 1, 0]
    assert r.steps[1]["bbox"] == [0.5, 0.5, 2.5, 2.5]
    assert r.limit["center"] == [1.5, 1.5]


def test_rectangle_loses_one_row_and_one_column():
    obj = DigitalObject(np.ones((4, 7), bool))
    shapes = []
    while obj.voxels:
        shapes.append(obj.volume.shape)
        assert obj.volume.all()
        obj = planar_flow_step(obj)
    assert shapes == [(4, 7), (3, 6), (2, 5), (1, 4)]


@pytest.mark.parametrize("connectivity", [6, 26])
def test_dumbbell_stays_connected(connectivity):
    r = run_flow(DigitalObject(dumbbell()), connectivity=connectivity)
    assert r.stop_reason == "vanished"
    assert all(s["betti"] == [1, 0, 0] for s in r.steps if s["voxels"])
    assert r.steps[1]["voxels"] > 2 * 5**3  # the bar is kept (both ends negative)


def test_annulus_prism_keeps_its_tunnel():
    r = run_flow(DigitalObject(annulus_prism()))
    assert len(r.steps) > 3
    assert all(s["betti"] == [1, 1, 0] for s in r.steps if s["voxels"])
    assert all(s["euler_characteristic"] == 0 for s in r.steps if s["voxels"])


def test_parity_alternates_and_bbox_on_its_lattice():
    r = run_flow(DigitalObject(ball(5)))
    assert r.stop_reason == "vanished" and len(r.steps) > 5
    for s in r.steps:
        assert s["parity"] == s["step"] % 2
        if s["bbox"] is None:
            continue
        corners = np.array(s["bbox"])
        frac = corners - np.floor(corners)
        assert np.all(frac == (0.0 if s["parity"] == 0 else 0.5))


def test_offset_follows_the_half_voxel_shift():
    obj = DigitalObject(np.ones((3, 3, 3), bool), offset=(2, 2, 2))
    one = flow_step(obj)
    assert one.parity == 1 and one.offset == (2, 2, 2)  # cropped from offset - 1
    assert one.bbox()[0].tolist() == [2.5, 2.5, 2.5]
    two = flow_step(one)
    assert two.parity == 0 and two.offset == (3, 3, 3) and two.voxels == 1
    assert two.bbox()[0].tolist() == [3.0, 3.0, 3.0]


# --------------------------------------------------------------------------
# The rule table, re-implemented slowly
# --------------------------------------------------------------------------


def _slow_keep(volume, connectivity):
    """Per-vertex loops over the table of docs/flow.md (3D) or eq. 5.8 (2D)."""
    cfg = configurations(volume)
    nd = volume.ndim
    if nd == 3:
        cls, codes, f = class_lut(), code_lut(), f_lut()
        full = 255
    else:
        pcls = planar_class_lut()
        full = 15
    joined = connectivity in (26, 8)

    def negative(c):
        if nd == 3:
            return bool(f[c] < 0) if cls[c] >= 0 else (joined and cls[c] == -1)
        return pcls[c] == 2 or (joined and pcls[c] == -1)

    def ends(w, axis):
        c = cfg[w]
        out = []
        for step in (-1, 1):
            p = list(w)
            while 0 <= p[axis] < cfg.shape[axis] and cfg[tuple(p)] == c:
                p[axis] += step
            out.append(0 <= p[axis] < cfg.shape[axis] and negative(cfg[tuple(p)]))
        return out

    keep = np.zeros(cfg.shape, bool)
    for w in np.ndindex(*cfg.shape):
        c = int(cfg[w])
        if c == full:
            keep[w] = True
        elif c == 0:
            continue
        elif nd == 2:
            k = pcls[c]
            if k == 2 or (k == -1 and joined):
                keep[w] = True
            elif k == 1:
                bits = [b for b in range(4) if c >> b & 1]
                axis = 0 if bits[0] ^ bits[1] == 1 else 1
                keep[w] = any(ends(w, axis))
        else:
            k = cls[c]
            if k == -1:
                keep[w] = joined
            elif k in (8, 1, 2, 3):
                keep[w] = True
            elif k == 6:  # convex edge: both ends of the edge segment negative
                keep[w] = all(ends(w, int(np.flatnonzero(codes[c] == CONVEX)[0])))
            elif k == 4:  # flat: any end of the two in-face segments negative
                axes = np.flatnonzero(codes[c] == FLAT)
                assert np.flatnonzero(codes[c] == NONE).size == 1
                keep[w] = any(e for a in axes for e in ends(w, int(a)))
    return keep


@pytest.mark.parametrize("connectivity", [6, 26])
def test_vectorised_rules_match_slow_rules(rng, connectivity):
    for _ in range(12):
        v = union_of_boxes(rng, size=7, count=3) if rng.random() < 0.5 else rng.random((6, 7, 5)) < 0.6
        _, keep = flow_moves(DigitalObject(v), connectivity)
        assert np.array_equal(keep, _slow_keep(v, connectivity))


@pytest.mark.parametrize("connectivity", [4, 8])
def test_vectorised_planar_rules_match_slow_rules(rng, connectivity):
    for _ in range(20):
        v = rng.random((9, 8)) < 0.6
        _, keep = flow_moves(DigitalObject(v), connectivity)
        assert np.array_equal(keep, _slow_keep(v, connectivity))


def test_edge_contact_follows_the_connectivity():
    v = np.zeros((4, 4, 2), bool)
    v[:2, :2] = v[2:, 2:] = True  # two 2x2x2 cubes sharing an edge
    r6 = run_flow(DigitalObject(v), connectivity=6)  # apart: each cube becomes its centre
    assert r6.steps[1]["voxels"] == 2 and r6.steps[1]["betti"] == [2, 0, 0]
    r26 = run_flow(DigitalObject(v), connectivity=26)  # joined at the contact, which stays
    assert r26.steps[0]["betti"] == [1, 0, 0]
    assert all(s["betti"] == [1, 0, 0] for s in r26.steps if s["voxels"])
    assert r26.states[1].volume[1, 1, :].all()  # the three vertices of the shared edge


# --------------------------------------------------------------------------
# Topology control
# --------------------------------------------------------------------------


def two_boxes():
    v = np.zeros((12, 6, 6), bool)
    v[:6] = True
    v[9:11, :2, :2] = True  # a 2x2x2 box vanishes at step 2
    return v


def test_topology_change_is_reported_with_its_place():
    r = run_flow(DigitalObject(two_boxes()))
    assert r.topology_changes and r.topology_changes[0]["step"] == 2
    change = r.topology_changes[0]
    assert change["before"] == [2, 0, 0] and change["after"] == [1, 0, 0] and change["applied"]
    lo, hi = np.reshape(change["where"], (2, -1))
    from scipy import ndimage

    labels, n = ndimage.label(r.states[1].volume)  # the large box and the small box's last voxel
    sizes = np.bincount(labels.ravel())[1:]
    assert n == 2 and sorted(sizes)[0] == 1
    last = np.argwhere(labels == 1 + int(np.argmin(sizes)))[0]
    corner = last + np.array(r.states[1].offset) + 0.5 * r.states[1].parity
    assert np.all(lo <= corner) and np.all(corner + 1 <= hi) and lo[0] >= 6  # it, and not the large box


def test_until_topology_change_stops_before_it():
    r = run_flow(DigitalObject(two_boxes()), until_topology_change=True)
    assert r.stop_reason == "topology-change"
    assert len(r.steps) == 2 and r.steps[-1]["betti"] == [2, 0, 0]
    assert r.limit["last_shape"] == "not-reached" and r.limit["center"] is None
    assert r.topology_changes[0]["applied"] is False


def test_guard_keeps_the_small_box():
    r = run_flow(DigitalObject(two_boxes()), guard=True)
    assert all(s["betti"] == [2, 0, 0] for s in r.steps)
    assert r.stop_reason == "converged" and r.steps[-1]["voxels"] == 2  # one point each


def test_guard_changes_nothing_where_the_flow_keeps_topology():
    for v in (np.ones((3, 4, 5), bool), dumbbell()):
        plain = run_flow(DigitalObject(v))
        guarded = run_flow(DigitalObject(v), guard=True)
        n = len(plain.steps) - 1  # all but the vanishing step
        assert voxel_counts(guarded)[:n] == voxel_counts(plain)[:n]
        assert all(np.array_equal(a.volume, b.volume) for a, b in zip(plain.states[:n], guarded.states[:n]))


@pytest.mark.parametrize("connectivity", [6, 26])
def test_guard_never_changes_betti_numbers(rng, connectivity):
    for i in range(10):
        v = union_of_boxes(rng) if i % 2 == 0 else blob(rng)
        r = run_flow(DigitalObject(v), guard=True, connectivity=connectivity)
        first = betti_numbers(v, connectivity)
        assert all(s["betti"] == first for s in r.steps), (i, r.stop_reason)
        assert r.stop_reason == "converged"  # the guard never blocks (issue 10)
        assert r.steps[-1]["voxels"] > 0


def test_guarded_planar_flow(rng):
    for _ in range(10):
        v = rng.random((12, 12)) < 0.55
        r = run_flow(DigitalObject(v), guard=True, connectivity=4)
        assert all(s["betti"] == betti_numbers(v, 4) for s in r.steps)


def test_guarded_step_of_one_voxel_keeps_a_voxel():
    # the step to the other lattice gives back one voxel (one of its 8
    # inward moves reversed): no progress, and no voxel is simple
    step = guarded_step(DigitalObject(np.ones((1, 1, 1), bool)))
    assert step.new.voxels == 1 and step.kind == "fixed-point"


@pytest.mark.parametrize("connectivity", [4, 8])
def test_simple_points_match_betti_numbers_in_2d(rng, connectivity):
    for _ in range(300):
        v = rng.random((5, 5)) < rng.uniform(0.2, 0.8)
        v[[0, -1]] = False
        v[:, [0, -1]] = False
        with_p, without = v.copy(), v.copy()
        with_p[2, 2], without[2, 2] = True, False
        same = betti_numbers(with_p, connectivity) == betti_numbers(without, connectivity)
        assert simple_points(v, np.array([[2, 2]]), connectivity)[0] == same


@pytest.mark.parametrize("connectivity", [6, 26])
def test_simple_points_never_change_betti_numbers_in_3d(rng, connectivity):
    for _ in range(300):
        v = rng.random((5, 5, 5)) < rng.uniform(0.2, 0.8)
        v[[0, -1]] = False
        v[:, [0, -1]] = False
        v[:, :, [0, -1]] = False
        if simple_points(v, np.array([[2, 2, 2]]), connectivity)[0]:
            with_p, without = v.copy(), v.copy()
            with_p[2, 2, 2], without[2, 2, 2] = True, False
            assert betti_numbers(with_p, connectivity) == betti_numbers(without, connectivity)


# --------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------


def test_cli_flow_json_contract(capsys):
    assert main(["flow", str(ROOT / "meshes" / "example19.txt"), "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert [s["step"] for s in r["steps"]] == [0, 1, 2]
    for s in r["steps"]:
        assert set(s) >= {"step", "voxels", "parity", "betti", "euler_characteristic", "energy", "bbox"}
    assert r["steps"][0]["voxels"] == 4 and r["steps"][0]["energy"] == 20  # as `info` reports
    assert r["steps"][1]["bbox"] == [0.5, 0.5, 0.5, 1.5, 1.5, 1.5]
    assert r["steps"][2]["bbox"] is None
    assert r["limit"]["center"] == [1.0, 1.0, 1.0] and r["limit"]["last_shape"] == "cuboid"
    assert r["topology_changes"] == [] and r["stop_reason"] == "vanished"


def test_cli_flow_steps_guard_and_connectivity(tmp_path, capsys):
    np.save(tmp_path / "b.npy", two_boxes())
    assert main(["flow", str(tmp_path / "b.npy"), "--steps", "1", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert len(r["steps"]) == 2 and r["limit"]["last_shape"] == "not-reached"
    assert main(["flow", str(tmp_path / "b.npy"), "--guard", "--connectivity", "26", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["guard"] and r["connectivity"] == 26
    assert {tuple(s["betti"]) for s in r["steps"]} == {(2, 0, 0)}
    assert main(["flow", str(tmp_path / "b.npy")]) == 0
    assert "topology change at step 2" in capsys.readouterr().out


def test_cli_flow_text_says_boxes_and_limit_as_info_prints_coordinates(tmp_path, capsys):
    # a NIfTI's zooms are float32 (0.7 is 0.699999988...): the text printed
    # the boxes as Python lists, [5.5, 6.299999892711639, ...]
    import re

    nib = pytest.importorskip("nibabel")
    rng = np.random.default_rng(1)
    labels = rng.integers(0, 4, (12, 10, 8)).astype(np.int16)
    nib.save(nib.Nifti1Image(labels, np.diag([0.5, 0.7, 1.2, 1])), tmp_path / "seg.nii.gz")
    args = ["flow", str(tmp_path / "seg.nii.gz"), "--label", "2"]
    assert main([*args, "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert main(args) == 0
    text = capsys.readouterr().out
    said = re.findall(r"topology change at step (\d+): .* in the box \[(.*)\] to \[(.*)\]", text)
    assert len(said) == len(r["topology_changes"]) > 0, text
    for (step, lo, hi), change in zip(said, r["topology_changes"]):
        assert int(step) == change["step"]
        for printed, value in zip(lo.split(", ") + hi.split(", "), change["where"]):
            assert len(printed.replace("-", "").replace(".", "").lstrip("0")) <= 6, printed
            assert float(printed) == pytest.approx(value, rel=1e-5)
    limit = re.search(r"limit: \[(.*)\], the centre of the last non-empty state \(step (\d+): ", text)
    assert limit and int(limit.group(2)) == r["limit"]["last_step"], text
    assert [float(c) for c in limit.group(1).split(", ")] == pytest.approx(r["limit"]["center"], rel=1e-5)


def test_cli_flow_out_files(tmp_path, capsys):
    np.save(tmp_path / "d.npy", dumbbell())
    out = tmp_path / "run"
    assert main(["flow", str(tmp_path / "d.npy"), "--out", str(out)]) == 0
    capsys.readouterr()
    with open(out / "flow.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [int(row["step"]) for row in rows] == list(range(len(rows)))
    assert int(rows[0]["voxels"]) == int(dumbbell().sum()) and int(rows[-1]["voxels"]) == 0
    plys = sorted(out.glob("step_*.ply"))
    assert len(plys) == len(rows) - 1  # every non-empty state
    for ply in plys[:3]:
        mesh = trimesh.load(ply, process=False)
        assert mesh.is_watertight and mesh.is_winding_consistent
    first = trimesh.load(plys[0], process=False)
    assert np.allclose(first.bounds, [[0, 0, 0], dumbbell().shape])
    assert (out / "flow.png").stat().st_size > 1000
    assert (out / "shapes.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # an existing non-empty directory is refused without --force
    assert main(["flow", str(tmp_path / "d.npy"), "--out", str(out)]) == 2
    assert "not empty" in capsys.readouterr().err
    assert main(["flow", str(tmp_path / "d.npy"), "--out", str(out), "--force"]) == 0
    assert "step_*.ply" in capsys.readouterr().out


def test_cli_flow_out_of_a_2d_object_names_the_files_it_writes(tmp_path, capsys):
    disc = np.hypot(*np.indices((21, 21)) - 10.0) <= 7
    np.save(tmp_path / "disc.npy", disc)
    assert main(["flow", str(tmp_path / "disc.npy"), "--out", str(tmp_path / "run")]) == 0
    said = capsys.readouterr().out.strip().splitlines()[-1]
    assert said == f"{tmp_path / 'run'}: flow.csv, flow.png (figures), shapes.png (the object at a few steps)"
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == ["flow.csv", "flow.png", "shapes.png"]


def test_cli_flow_bad_input(tmp_path, capsys):
    assert main(["flow", str(tmp_path / "missing.npy")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("isoflow flow: error:") and "\n" not in err
    np.save(tmp_path / "v.npy", np.ones((3, 3, 3), bool))
    assert main(["flow", str(tmp_path / "v.npy"), "--connectivity", "4"]) == 2
    with pytest.raises(SystemExit) as stop:  # refused as the command line is read
        main(["flow", str(tmp_path / "v.npy"), "--steps", "-1"])
    assert stop.value.code == 2 and "--steps" in capsys.readouterr().err
    np.save(tmp_path / "e.npy", np.zeros((3, 3, 3), bool))
    assert main(["flow", str(tmp_path / "e.npy")]) == 2
    assert "empty" in capsys.readouterr().err


def test_cli_flow_of_a_2d_image(tmp_path, capsys):
    v = np.ones((4, 7), bool)
    np.save(tmp_path / "r.npy", v)
    out = tmp_path / "run"
    assert main(["flow", str(tmp_path / "r.npy"), "--json", "--out", str(out)]) == 0
    r = json.loads(capsys.readouterr().out)
    assert [s["voxels"] for s in r["steps"]] == [28, 18, 10, 4, 0] and r["connectivity"] == 4
    assert r["limit"] == {"center": [2.0, 3.5], "last_shape": "cuboid", "last_step": 3}
    assert sorted(p.name for p in out.iterdir()) == ["flow.csv", "flow.png", "shapes.png"]  # no surfaces in 2D


def test_cli_flow_force_removes_the_previous_runs_steps(tmp_path, capsys):
    # a box of side s vanishes in s steps (Theorem 20): 10 PLYs, then 4
    np.save(tmp_path / "b10.npy", np.ones((10, 10, 10), bool))
    np.save(tmp_path / "b4.npy", np.ones((4, 4, 4), bool))
    out = tmp_path / "run"
    assert main(["flow", str(tmp_path / "b10.npy"), "--out", str(out)]) == 0
    assert len(list(out.glob("step_*.ply"))) == 10
    assert main(["flow", str(tmp_path / "b4.npy"), "--out", str(out), "--force"]) == 0
    assert len(list(out.glob("step_*.ply"))) == 4


def test_streamed_flow_files_equal_the_exported_ones(tmp_path, capsys):
    # the CLI writes while the flow runs (keep_states=False); export_flow
    # writes from the kept states: same PLYs byte for byte, same CSV
    from isoflow.flow.files import export_flow
    from isoflow.flow.run import run_flow

    v = dumbbell()
    np.save(tmp_path / "d.npy", v)
    assert main(["flow", str(tmp_path / "d.npy"), "--out", str(tmp_path / "cli")]) == 0
    export_flow(run_flow(DigitalObject(v)), tmp_path / "api", plot=False)
    cli = sorted(p.name for p in (tmp_path / "cli").glob("step_*.ply"))
    api = sorted(p.name for p in (tmp_path / "api").glob("step_*.ply"))
    assert len(cli) == len(api) > 3
    for a, b in zip(cli, api):
        assert (tmp_path / "cli" / a).read_bytes() == (tmp_path / "api" / b).read_bytes()
    assert (tmp_path / "cli" / "flow.csv").read_text() == (tmp_path / "api" / "flow.csv").read_text()


def test_flow_writer_keeps_a_bounded_evenly_spaced_sample(tmp_path):
    # what replaces keeping every state: at most 2 x PANELS frames, evenly
    # spaced from step 0, plus the last non-empty state (2D: no PLYs)
    from isoflow.flow.files import FlowWriter

    square = DigitalObject(np.ones((2, 2), bool))
    writer = FlowWriter(tmp_path / "w", 4, last_step=1000)
    for step in range(201):
        writer.add(step, square)
    steps = [s for s, _ in writer.frames]
    assert len(steps) <= 2 * FlowWriter.PANELS and steps[0] == 0
    assert len(set(np.diff(steps))) == 1 and steps[-1] + writer.stride > 200
    assert writer.last[0] == 200


def test_flow_api_takes_arrays_and_checks_its_counts():
    # a bare array is the object at the origin: same run as its DigitalObject
    box = np.ones((3, 4, 5), bool)
    assert [s["voxels"] for s in run_flow(box).steps] == [60, 24, 6, 0]
    assert flow_step(box).voxels == 24
    for kw in ({"steps": 1.5}, {"steps": -1}, {"max_steps": -2}, {"steps": True}):
        with pytest.raises(IsoflowError, match="must be an integer"):
            run_flow(box, **kw)
    # max_steps=0 means no step, not the default cap
    assert run_flow(box, max_steps=0).stop_reason == "max-steps"
