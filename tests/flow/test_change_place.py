"""Where a plain run says its topology changes (``topology_changes[i]["where"]``).

The box must hold the change. That is checked without isoflow's topology
code: both states are laid on one grid of half-voxel cells (a voxel of
either lattice is a 2^n block of them), and the Betti numbers are counted
by scipy.ndimage.label (components, holes, cavities) and
skimage.measure.euler_number (b1 in 3D from chi). Carrying out the step
inside the box only must give the new Betti numbers, and carrying it out
outside the box only must keep the old ones; a cavity (2D: hole) that the
step closes off must lie in the box whole.
"""

import json

import numpy as np
import pytest
from scipy import ndimage

from isoflow import DigitalObject
from isoflow.cli import main
from isoflow.flow.run import run_flow


def background(conn, nd):
    """The background's structuring element: the complementary connectivity."""
    return ndimage.generate_binary_structure(nd, nd if conn in (4, 6) else 1)


def betti(volume, conn):
    """Betti numbers of a 2D/3D boolean array; the background takes the
    complementary connectivity."""
    from skimage.measure import euler_number

    nd, small = volume.ndim, conn in (4, 6)
    b0 = ndimage.label(volume, ndimage.generate_binary_structure(nd, 1 if small else nd))[1]
    enclosed = ndimage.label(~np.pad(volume, 1), background(conn, nd))[1] - 1
    if nd == 2:
        return [b0, enclosed]
    chi = euler_number(np.pad(volume, 1), connectivity=1 if small else 3)
    return [b0, b0 + enclosed - chi, enclosed]


def on_half_grid(state, lo, shape):
    """A state's voxels on the grid of half-voxel cells whose cell 0 starts
    at ``lo`` half voxels: a voxel's lowest corner is ``offset + index +
    parity / 2`` voxels (docs/flow.md)."""
    fine = state.volume
    for axis in range(fine.ndim):
        fine = np.repeat(fine, 2, axis=axis)
    out = np.zeros(shape, bool)
    start = 2 * np.array(state.offset) + state.parity - lo
    out[tuple(slice(s, s + n) for s, n in zip(start, fine.shape))] = fine
    return out


def half_grids(before, after, where):
    """``(A, B, R)``: the two states and the box on one half-voxel grid."""
    box = np.rint(2 * np.array(where)).astype(int).reshape(2, -1)  # (the record's flat lo..., hi...)
    corners = [2 * np.array(s.offset) + s.parity for s in (before, after)]
    lo = np.min([*corners, box[0]], axis=0) - 2
    hi = np.max([*(c + 2 * np.array(s.volume.shape) for c, s in zip(corners, (before, after))), box[1]], axis=0) + 2
    shape = tuple(hi - lo)
    box_mask = np.zeros(shape, bool)
    box_mask[tuple(slice(a - o, b - o) for a, b, o in zip(box[0], box[1], lo))] = True
    return on_half_grid(before, lo, shape), on_half_grid(after, lo, shape), box_mask


def cavities(volume, conn):
    """``(labels, mask)``: the background components and those of them
    that do not reach the outside (the array is padded by one)."""
    labels = ndimage.label(~np.pad(volume, 1), background(conn, volume.ndim))[0]
    outside = labels.flat[0]
    labels = labels[(slice(1, -1),) * volume.ndim]
    return labels, (labels > 0) & (labels != outside)


def closed_off(a, b, conn):
    """The cavities (2D: holes) of ``b`` that hold no cell of a cavity of
    ``a`` (one grid): the ones the step from ``a`` to ``b`` makes."""
    was = cavities(a, conn)[1]
    labels, now = cavities(b, conn)
    return now & ~np.isin(labels, np.unique(labels[was & now]))


def assert_box_holds(result, change, conn, why=""):
    before, after = result.states[change["step"] - 1], result.states[change["step"]]
    a, b, box = half_grids(before, after, change["where"])
    assert betti(a, conn) == change["before"] and betti(b, conn) == change["after"]
    assert betti(np.where(box, b, a), conn) == change["after"], (why, change)  # the step inside the box only
    assert betti(np.where(box, a, b), conn) == change["before"], (why, change)  # outside it only
    assert not (closed_off(a, b, conn) & ~box).any(), (why, change)


def assert_box_holds_each_change(result, conn):
    assert result.topology_changes
    for change in result.topology_changes:
        assert_box_holds(result, change, conn)


def world_box(state, mask):
    """World [min, max] corners of the voxels ``mask`` of a state (pitch 1)."""
    idx = np.argwhere(mask) + np.array(state.offset) + state.parity / 2
    return idx.min(0), idx.max(0) + 1


def inside(inner, outer):
    lo, hi = np.reshape(outer, (2, -1))  # (the record's flat lo..., hi...)
    return bool(np.all(inner[0] >= lo) and np.all(inner[1] <= hi))


def test_a_closing_hole_is_inside_its_box(tmp_path, capsys):
    # a 5x5 square with a one-pixel hole: the box was the single cell
    # [3.5, 4.5]^2 of the vertex left stuck, beside the hole [3, 4]^2
    v = np.zeros((7, 7), bool)
    v[1:6, 1:6] = True
    v[3, 3] = False
    np.save(tmp_path / "square.npy", v)
    assert main(["flow", str(tmp_path / "square.npy"), "--json"]) == 0
    changes = json.loads(capsys.readouterr().out)["topology_changes"]
    assert [(c["step"], c["before"], c["after"]) for c in changes] == [(1, [1, 1], [1, 0])]
    labels, n = ndimage.label(~v)  # the hole: the background part off the border
    hole = labels == labels[3, 3]
    assert n == 2 and not (hole[0].any() or hole[-1].any() or hole[:, 0].any() or hole[:, -1].any())
    assert inside(world_box(DigitalObject(v), hole), changes[0]["where"]), changes[0]["where"]
    assert_box_holds_each_change(run_flow(v), 4)


def test_a_vanishing_part_is_inside_its_box():
    # a 2x2x2 cube beside a larger box: its last voxel [1.5, 2.5]^3 was
    # reported as [2, 3]^3, an eighth of it
    v = np.zeros((12, 12, 12), bool)
    v[1:3, 1:3, 1:3] = True
    v[5:, 5:, 5:] = True
    r = run_flow(v)
    assert [(c["step"], c["before"], c["after"]) for c in r.topology_changes] == [(2, [2, 0, 0], [1, 0, 0])]
    last = r.states[1]
    labels, n = ndimage.label(last.volume)
    small = [i for i in range(1, n + 1) if (labels == i).sum() == 1]
    assert n == 2 and len(small) == 1
    lo, hi = world_box(last, labels == small[0])
    assert lo.tolist() == [1.5] * 3 and hi.tolist() == [2.5] * 3
    assert inside((lo, hi), r.topology_changes[0]["where"]), r.topology_changes[0]["where"]
    assert_box_holds_each_change(r, 6)


def test_a_lost_handle_is_placed_near_it():
    # a ball of radius 10 with a thin staple: the box holds the staple's
    # lost voxels, and is a small part of the object's bounding box
    z, y, x = np.indices((30, 30, 30))
    v = (x - 13) ** 2 + (y - 15) ** 2 + (z - 15) ** 2 <= 100
    v[15, 12, 22:27] = v[15, 18, 22:27] = v[15, 12:19, 26] = True
    r = run_flow(v)
    assert [(c["step"], c["before"], c["after"]) for c in r.topology_changes] == [(1, [1, 1, 0], [1, 0, 0])]
    where = r.topology_changes[0]["where"]
    before, after = r.states[0], r.states[1]
    # the voxels of the old state none of whose half-cells the new one
    # keeps, by part: the part whose loss alone changes the Betti numbers
    # is the change
    grid_lo = np.min([2 * np.array(s.offset) + s.parity for s in (before, after)], axis=0) - 2
    shape = tuple(np.max([2 * np.array(s.offset) + s.parity + 2 * np.array(s.volume.shape)
                          for s in (before, after)], axis=0) + 2 - grid_lo)
    b = on_half_grid(after, grid_lo, shape)
    start = 2 * np.array(before.offset) + before.parity - grid_lo
    blocks = b[tuple(slice(s, s + 2 * n) for s, n in zip(start, before.volume.shape))]
    kept = blocks.reshape([d for n in before.volume.shape for d in (n, 2)]).any(axis=(1, 3, 5))
    labels, k = ndimage.label(before.volume & ~kept)
    changed = [i for i in range(1, k + 1) if betti(before.volume & (labels != i), 6) != [1, 1, 0]]
    assert len(changed) == 1
    assert inside(world_box(before, labels == changed[0]), where), where
    extent = np.prod(np.subtract(*np.reshape(r.steps[0]["bbox"], (2, -1))[::-1]))
    assert np.prod(np.subtract(*np.reshape(where, (2, -1))[::-1])) < extent / 50
    assert_box_holds_each_change(r, 6)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("nd", [2, 3])
def test_random_unions_of_boxes_changes_are_inside_their_boxes(seed, nd):
    rng = np.random.default_rng(seed)
    v = np.zeros((20,) * nd, bool)
    for _ in range(8):
        lo, size = rng.integers(0, 17, nd), rng.integers(1, 7, nd)
        v[tuple(slice(a, a + s) for a, s in zip(lo, size))] = True
    for conn in ((4, 8) if nd == 2 else (6, 26)):
        assert_box_holds_each_change(run_flow(v, connectivity=conn), conn)


def noisy(seed, nd):
    """Up to three boxes with 5-30 % of the voxels flipped: isolated
    voxels, one-voxel holes and voxels touching only by an edge or a
    vertex, in a 9x9 image or a 6x6x6 volume."""
    rng = np.random.default_rng(seed)
    n = 9 if nd == 2 else 6
    v = np.zeros((n,) * nd, bool)
    for _ in range(rng.integers(0, 4)):
        lo, size = rng.integers(0, n - 1, nd), rng.integers(1, 5, nd)
        v[tuple(slice(a, a + s) for a, s in zip(lo, size))] = True
    v ^= rng.random(v.shape) < rng.uniform(0.05, 0.3)
    return v


def touching_only_diagonally(v):
    """Whether some 2^n window of ``v`` holds just two voxels, and they
    share only an edge or a vertex (their places in the window differ in
    two axes or more)."""
    windows = np.lib.stride_tricks.sliding_window_view(v, (2,) * v.ndim).reshape(-1, 2**v.ndim)
    pairs = [np.flatnonzero(w) for w in windows[windows.sum(1) == 2]]
    return any(bin(i ^ j).count("1") >= 2 for i, j in pairs)


@pytest.mark.parametrize("conn", [4, 8, 6, 26])
def test_changes_on_noise_are_inside_their_boxes(conn):
    # a box edge that crosses a thin part the step moves can join or cut
    # it there: a pocket whose mouth the step closes inside the box, left
    # open outside, is a hole of neither state (2D, seed 7); a voxel of a
    # component cut off inside the box is a component of neither (3D at 6,
    # seed 71). The voxels around the stuck vertices alone are such a box.
    nd, seeds = (2 if conn in (4, 8) else 3), 80
    changes = contacts = 0
    for seed in range(seeds):
        v = noisy(seed, nd)
        contacts += touching_only_diagonally(v)
        result = run_flow(v, connectivity=conn)
        for change in result.topology_changes:
            assert_box_holds(result, change, conn, f"seed {seed}")
        changes += len(result.topology_changes)
    assert changes >= seeds and contacts >= seeds // 2


@pytest.mark.parametrize("seed", [133, 234])
def test_a_closed_off_cavity_is_inside_its_box(seed):
    # the step closes the cavity off at one stuck vertex, its mouth: the
    # 2x2x2 voxels around it do not hold the cavity, though the step splits
    # cleanly at their edge
    result = run_flow(noisy(seed, 3), connectivity=26)
    made = [c for c in result.topology_changes if c["after"][2] > c["before"][2]]
    assert made
    for change in made:
        before, after = result.states[change["step"] - 1], result.states[change["step"]]
        a, b, box = half_grids(before, after, change["where"])
        cavity = closed_off(a, b, 26)
        assert cavity.any() and not (cavity & ~box).any(), change
