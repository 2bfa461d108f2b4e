"""What placing a plain run's topology change costs: the place is found
from what the run has already (the Betti numbers it records, the stuck
vertices on the bit rows) and on the voxels where the refined grids give
the same. Each shortcut is checked against a reading without it:
scipy.ndimage's labels on the grid of half voxels, and the NumPy sweeps.
"""

import numpy as np
import pytest
from test_change_place import assert_box_holds, closed_off, noisy

from isoflow.flow import guard
from isoflow.flow.guard import appeared_cavities, corners_any
from isoflow.flow.motion import flow_moves
from isoflow.flow.run import run_flow


def half_voxels(volume, keep):
    """The old object (``volume``, padded by one) and the new one (the
    vertex grid ``keep``: new voxel ``w`` is centred at the old array's
    vertex ``w``) on one grid of half-voxel cells, the padded array's
    voxel ``p`` its cells ``2p .. 2p + 1``."""
    old = np.pad(volume, 1)
    new = np.zeros(old.shape, bool)
    new[(slice(0, -1),) * keep.ndim] = keep  # new voxel w: old padded voxels w .. w + 1, half a voxel on
    for axis in range(old.ndim):
        old, new = np.repeat(old, 2, axis=axis), np.repeat(new, 2, axis=axis)
    return old, np.roll(new, 1, axis=tuple(range(new.ndim)))


def per_voxel(cells):
    """Per voxel of the padded array: whether any of its half-voxel cells is set."""
    shape = [d for n in cells.shape for d in (n // 2, 2)]
    return cells.reshape(shape).any(axis=tuple(range(1, cells.ndim * 2, 2)))


@pytest.mark.parametrize("conn", [4, 8, 6, 26])
def test_closed_off_cavities_counted_on_the_voxels_are_those_of_the_half_grid(conn):
    # the cavities (2D: holes) of the new object that hold no cell of a
    # cavity of the old one, labelled by scipy on the grid of half voxels,
    # cover the voxels that appeared_cavities finds from the voxels: for
    # random objects and random new ones, and for the steps of plain runs
    # at 26 that close cavities off (the flow closes none in these at 4, 8
    # and 6)
    nd = 2 if conn in (4, 8) else 3
    rng = np.random.default_rng(conn)
    pairs = []
    for _ in range(300):
        shape = tuple(rng.integers(2, 9 if nd == 2 else 6, nd))
        density = rng.uniform(0.5, 0.98)
        pairs.append((rng.random(shape) < density, rng.random(tuple(n + 1 for n in shape)) < density))
    for seed in ([133, 234, 3, 6, 32] if conn == 26 else []):
        result = run_flow(noisy(seed, nd), connectivity=conn)
        pairs += [(s.volume, flow_moves(s, conn)[1]) for s in result.states if s.voxels]
    made = 0
    for volume, keep in pairs:
        expected = per_voxel(closed_off(*half_voxels(volume, keep), conn))
        assert np.array_equal(corners_any(appeared_cavities(np.pad(volume, 1), keep, conn)), expected)
        made += expected.any()
    assert made >= 5


def test_the_place_takes_the_betti_numbers_the_run_recorded(monkeypatch):
    # a plain run records every state's Betti numbers; placing a change
    # counts them only on the refined grids that split the step (twice
    # the voxels along each axis, and more), not again on either state
    v = np.zeros((12, 12, 12), bool)
    v[1:3, 1:3, 1:3] = True
    v[5:, 5:, 5:] = True
    counted = []
    count = guard.betti_numbers

    def recorded(volume, *args, **kwargs):
        counted.append(np.shape(volume))
        return count(volume, *args, **kwargs)

    monkeypatch.setattr(guard, "betti_numbers", recorded)
    for method in ("numpy", "compiled"):
        counted.clear()
        result = run_flow(v, method=method)
        assert [(c["step"], c["before"], c["after"]) for c in result.topology_changes] == [(2, [2, 0, 0], [1, 0, 0])]
        assert_box_holds(result, result.topology_changes[0], 6)
        state = result.states[1].volume.shape
        assert all(min(np.subtract(shape, state)) > 2 for shape in counted), (counted, state)
