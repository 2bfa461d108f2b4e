"""The guarded flow always finishes, keeps the topology at every step and
ends in a minimal state (issue 10).

Everything is checked independently of isoflow's own topology code: the
Betti numbers of every state come from scipy.ndimage.label (components of
the object and of the background) and skimage.measure.euler_number (b1 from
chi = b0 - b1 + b2); the end state must have no simple point (Bertrand's
test, itself checked against the Betti numbers in test_flow.py) and each
component the size its own Betti numbers allow: one voxel without tunnels or
cavities; closed curves one voxel thick with tunnels (every voxel has at
least two neighbours, no full 2x2x2 block, and a ring's voxels exactly two);
a shell without interior voxels around a cavity.
"""

import json

import numpy as np
import pytest
from scipy import ndimage
from shapes import (
    annulus_prism,
    contacts,
    figure_eight,
    hollow_ball,
    linked_rings,
    planar_annulus,
    planar_disc_ring,
    planar_figure_eight,
    solid_torus,
    union_of_boxes,
)
from skimage.measure import euler_number

from isoflow import DigitalObject
from isoflow.cli import main
from isoflow.digital.simple import simple_points
from isoflow.flow.guard import convexity, guarded_step, thinning_step
from isoflow.flow.run import run_flow


def adjacency(ndim, conn):
    return ndimage.generate_binary_structure(ndim, 1 if conn in (4, 6) else ndim)


def independent_betti(volume, conn):
    """(b0, b1, b2) or (b0, b1) from scipy labelling and skimage's chi."""
    nd = volume.ndim
    v = np.pad(volume, 1)
    b0 = ndimage.label(v, adjacency(nd, conn))[1]
    other = {4: 8, 8: 4, 6: 26, 26: 6}[conn]
    enclosed = ndimage.label(~v, adjacency(nd, other))[1] - 1
    chi = euler_number(v, connectivity=1 if conn in (4, 6) else nd)
    if nd == 2:
        return [b0, b0 - chi]  # chi = b0 - b1; the holes are b1
    return [b0, b0 + enclosed - chi, enclosed]


def check_minimal(volume, conn):
    """The end state has no simple point, and each component the size its
    topology allows: one voxel without tunnels or cavities; closed curves
    one voxel thick (no voxel with fewer than two neighbours, no full 2^n
    block; one tunnel: every voxel has exactly two neighbours) with tunnels;
    a shell without interior voxel around cavities."""
    nd = volume.ndim
    assert not simple_points(volume, np.argwhere(volume), conn).any()
    structure = adjacency(nd, conn)
    labels, n = ndimage.label(volume, structure)
    for c in range(1, n + 1):
        comp = labels == c
        b0, b1, b2 = (independent_betti(comp, conn) + [0])[:3]
        if b1 == 0 and b2 == 0:
            assert comp.sum() == 1
        elif b2 == 0:
            degree = ndimage.convolve(comp.astype(int), structure.astype(int), mode="constant")[comp] - 1
            assert degree.min() >= 2
            assert not ndimage.binary_erosion(comp, np.ones((2,) * nd, bool)).any()
            if b1 == 1:
                assert (degree == 2).all()
        else:
            assert not ndimage.binary_erosion(comp, adjacency(nd, {6: 26, 26: 6}[conn])).any()


FAMILIES_3D = {
    "torus-3-1.2": lambda: solid_torus(3, 1.2),
    "torus-5-2": lambda: solid_torus(5, 2, axis=0),
    "torus-7-3": lambda: solid_torus(7, 3, axis=1),
    "annulus-wall1": lambda: annulus_prism(8, 1, 3),
    "annulus-wall2": lambda: annulus_prism(10, 2, 2),
    "linked-rings": lambda: linked_rings(7, 1),
    "linked-thick": lambda: linked_rings(10, 2),
    "figure-eight": lambda: figure_eight(7, 2, 2),
    "hollow-ball": lambda: hollow_ball(4.5, 2.0),
    "contacts": lambda: contacts(3),
}
FAMILIES_2D = {
    "annulus-wall1": lambda: planar_annulus(9, 1),
    "annulus-wall2": lambda: planar_annulus(10, 2),
    "disc-ring": lambda: planar_disc_ring(6, 2),
    "figure-eight": lambda: planar_figure_eight(7, 1),
    "contacts": lambda: contacts(2),
}


def same_states(a, b) -> bool:
    return len(a) == len(b) and all(
        x.volume.shape == y.volume.shape and np.array_equal(x.volume, y.volume) and (x.offset, x.parity) == (y.offset, y.parity)
        for x, y in zip(a, b))


def check_run(volume, conn):
    """The guarded run on bit rows (compiled) equals the NumPy one state for
    state, and ends minimal with the input's Betti numbers at every state."""
    first = independent_betti(volume, conn)
    r = run_flow(DigitalObject(volume), guard=True, connectivity=conn, method="compiled")
    oracle = run_flow(DigitalObject(volume), guard=True, connectivity=conn, method="numpy")
    assert r.to_dict() == oracle.to_dict() and same_states(r.states, oracle.states)
    assert r.stop_reason == "converged"
    for state in r.states:
        assert independent_betti(state.volume, conn) == first
    check_minimal(r.states[-1].volume, conn)
    assert r.steps[-1]["betti"] == first and r.limit["last_step"] == len(r.steps) - 1
    return r


@pytest.mark.parametrize("connectivity", [6, 26])
@pytest.mark.parametrize("name", sorted(FAMILIES_3D))
def test_guarded_run_ends_minimal_3d(name, connectivity):
    check_run(FAMILIES_3D[name](), connectivity)


@pytest.mark.parametrize("connectivity", [4, 8])
@pytest.mark.parametrize("name", sorted(FAMILIES_2D))
def test_guarded_run_ends_minimal_2d(name, connectivity):
    check_run(FAMILIES_2D[name](), connectivity)


@pytest.mark.parametrize("connectivity", [6, 26, 4, 8])
def test_guarded_random_unions_of_boxes(connectivity):
    # many boxes in a small grid: edge and vertex contacts at every seed
    rng = np.random.default_rng(connectivity)
    nd = 3 if connectivity in (6, 26) else 2
    for _ in range(6):
        v = union_of_boxes(rng, size=9 if nd == 3 else 14, count=6, ndim=nd)
        check_run(v, connectivity)


def test_thin_ring_half_a_voxel_off_converges():
    # the case: a thin 26-connected ring whose step to the other
    # lattice cannot be carried out by simple deformations (the old guard
    # stopped "guard-blocked"); a diagonal ring in the plane
    v = np.zeros((9, 9, 1), bool)
    for i in range(4):
        v[4 + i, i, 0] = v[8 - i, 4 + i, 0] = v[4 - i, 8 - i, 0] = v[i, 4 - i, 0] = True
    r = check_run(v, 26)
    assert r.guard_steps["partial"] + r.guard_steps["thinning"] > 0


def test_convexity_is_the_curvature_at_the_corners():
    # the paper's f (eq. 4.8) summed over a voxel's 8 corners: (+,+,+) = 9,
    # (+,0,0) = 1, flat 0, (-,0,0) = -1, (-,-,-) = -9
    box = np.ones((3, 3, 3), bool)
    c = convexity(box)
    assert c[0, 0, 0] == 9 + 3 and c[1, 0, 0] == 2 and c[1, 1, 0] == 0 and c[1, 1, 1] == 0
    line = np.ones((4, 1, 1), bool)
    assert convexity(line)[:, 0, 0].tolist() == [4 * 9 + 4, 8, 8, 4 * 9 + 4]
    assert convexity(np.ones((1, 1, 1), bool)).tolist() == [[[72]]]
    notch = np.ones((3, 3, 3), bool)
    notch[2, 2, 2] = False  # the centre voxel now has a concave corner
    assert convexity(notch)[1, 1, 1] == -9
    square = np.ones((3, 3), bool)  # eq. 4.2: a corner pixel has one convex vertex
    assert convexity(square).tolist() == [[1, 0, 1], [0, 0, 0], [1, 0, 1]]


def test_thinning_removes_the_most_convex_first(rng):
    # a box: every surface voxel has convexity >= 0 and is simple in turn,
    # so one step removes exactly the outer layer
    box = np.ones((3, 4, 5), bool)
    thin = thinning_step(box, 6)
    core = np.zeros_like(box)
    core[1:-1, 1:-1, 1:-1] = True
    assert np.array_equal(thin, core)
    assert thinning_step(np.ones((1, 1, 1), bool), 26) is None  # the last voxel is not simple
    # concave voxels (convexity < 0) go only when no other voxel is simple
    for conn in (6, 26):
        for _ in range(10):
            v = union_of_boxes(rng, size=8, count=4)
            thin = thinning_step(v, conn)
            if thin is None:
                assert not simple_points(v, np.argwhere(v), conn).any()
                continue
            assert independent_betti(thin, conn) == independent_betti(v, conn)
            gone = v & ~thin
            conv = convexity(v)
            others = np.argwhere(v & (conv >= 0))
            if simple_points(v, others, conn).any():
                assert not (gone & (conv < 0)).any()
            else:
                assert gone.any() and (conv[gone] < 0).all()


def test_guarded_step_kinds():
    one = guarded_step(DigitalObject(np.ones((1, 1, 1), bool)))
    assert one.kind == "fixed-point" and one.new.voxels == 1
    box = guarded_step(DigitalObject(np.ones((3, 3, 3), bool)))
    assert box.kind == "flow" and box.new.voxels == 8 and box.new.parity == 1


def test_cli_guarded_flow_of_a_torus(tmp_path, capsys):
    np.save(tmp_path / "t.npy", solid_torus(4, 1.5))
    assert main(["flow", str(tmp_path / "t.npy"), "--guard", "--connectivity", "26", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["stop_reason"] == "converged" and r["guard"]
    assert {tuple(s["betti"]) for s in r["steps"]} == {(1, 1, 0)}
    assert sum(r["guard_steps"].values()) == len(r["steps"]) - 1
    assert all(s["move"] in ("flow", "partial", "thinning") for s in r["steps"][1:])


@pytest.mark.parametrize("method", ["numpy", "compiled"])
@pytest.mark.parametrize("conn", [6, 26])
@pytest.mark.parametrize("name", ["docs torus", "thin ring", "annulus prism"])
def test_a_guarded_thin_ring_ends_inside_the_input(name, conn, method):
    """The guard reverses the inward moves of a thin ring, and its greedy
    order picks the side that keeps it: the same side on every lattice
    carried the ring half a voxel a step out of the object (docs/flow.md's
    torus at 26 ended at z 6.5-7.5, below its input's 9-15). The end state
    lies in the input's bounding box, taken from the array."""
    if name == "docs torus":
        v = solid_torus(7, 3)
    elif name == "thin ring":
        z, y, x = np.mgrid[:24, :24, :8]
        v = ((np.sqrt((z - 11.5) ** 2 + (y - 11.5) ** 2) - 7) ** 2 + (x - 3.5) ** 2) < 1.6**2
    else:
        v = annulus_prism(outer=10, wall=1, height=3)
    nz = np.nonzero(v)
    lo, hi = [int(i.min()) for i in nz], [int(i.max()) + 1 for i in nz]
    r = run_flow(v, guard=True, connectivity=conn, method=method, keep_states=False)
    assert r.stop_reason == "converged"
    end_lo, end_hi = np.reshape(r.steps[-1]["bbox"], (2, -1))
    assert all(a <= b for a, b in zip(lo, end_lo)) and all(b <= a for a, b in zip(hi, end_hi)), (lo, hi, end_lo, end_hi)


@pytest.mark.parametrize("method", ["numpy", "compiled"])
@pytest.mark.parametrize("ndim", [2, 3])
def test_a_guarded_flow_of_a_fortran_ordered_volume_thins_as_of_its_c_ordered_copy(method, ndim):
    # np.pad kept the Fortran order and the thinning's in-place deletions went
    # to a copy: the first step deleted nothing (778 voxels -> 778)
    from isoflow import run_flow

    volume = np.random.default_rng(1).random((12, 11, 10)) < 0.6
    volume = volume if ndim == 3 else volume[:, :, 3]
    conn = 6 if ndim == 3 else 4
    c_run = run_flow(volume, 3, guard=True, connectivity=conn, method=method)
    f_run = run_flow(np.asfortranarray(volume), 3, guard=True, connectivity=conn, method=method)
    voxels = [s["voxels"] for s in f_run.steps]
    assert voxels == [s["voxels"] for s in c_run.steps] and voxels[1] < voxels[0]
    # the guard keeps the topology: every state's chi is scikit-image's of the input
    chi = euler_number(volume, connectivity=1)
    assert [euler_number(np.pad(s.volume, 1), connectivity=1) for s in f_run.states] == [chi] * 4
