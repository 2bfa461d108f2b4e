"""Topology control for the digital curvature flow (introduction and
Theorem 21 of the paper): a flow that keeps the Betti numbers and always
goes on until nothing simple is left to change.

One guarded step is the first of these that makes progress (see docs/flow.md):

1. **The flow step** (Definition 18, eqs. 5.15-5.18), carried out on the
   grid refined twice by simple deformations only (:func:`realise_moves`):
   old voxel ``v`` is a block of ``2^n`` fine cells, and so is the new voxel
   centred at vertex ``w``; the fine cell of the new block in octant ``e`` of
   ``w`` lies in old voxel ``w - 1 + e``. The old object is thus the new
   blocks each holding the octants of its configuration, and a step fills
   the blocks of the outward moves and empties those of the inward moves,
   **one fine cell at a time, a cell only when it is a simple point**
   (:mod:`isoflow.digital.simple`). A block that cannot reach its move is
   *stuck*: its move is reversed (inward <-> outward) once. When no block
   stays stuck, the new object is reached from the old one by simple
   deformations: nothing was split, merged, opened or closed -- not even a
   split and a merge at once that would leave the Betti numbers equal.
2. **The largest part of it that keeps the topology** (``partial``): when
   blocks stay stuck both ways, they are all given their plain move, all
   moved outward or all inward, whichever first keeps the Betti numbers.
3. **A thinning step** on the same lattice (:func:`thinning_step`): simple
   voxels are deleted, subfield by subfield, the most convex first (the
   vertex index ``f`` of eq. 4.8 summed over a voxel's corners): the convex
   and flat ones in one step, the concave ones only when none of those is.

A flow step (1 or 2) is progress when it removes voxels, or, while the run's
allowance of non-shrinking steps lasts (the bar rule and a ball's first
steps grow), when it reaches a shape (up to translation) the run has not had
before. When neither flow nor thinning makes progress, the state is a fixed
point: no simple voxel is left, and the run ends ``converged``.
"""

from __future__ import annotations

import hashlib
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..digital.configurations import configurations
from ..digital.connectivity import complement
from ..digital.indices import f_lut, planar_class_lut
from ..digital.lattice import DigitalObject
from ..digital.simple import delete_simple, neighbourhood_codes, simple_codes
from ..digital.topology import betti_numbers
from ..scale.labels import label
from ..scale.memory import check_fits
from .motion import flow_connectivity, flow_moves

# --------------------------------------------------------------------------
# The flow step as a sequence of simple deformations
# --------------------------------------------------------------------------
#
# On the grid refined twice, old voxel v is the 2^n block of fine cells
# 2v+2 .. 2v+3 (after a one-voxel pad) and new voxel w (centred at vertex w)
# the block 2w+1 .. 2w+2, whose cell 2w+1+e lies in octant e of w. A step
# turns every new block full (kept) or empty (dropped); the old object is the
# same blocks holding exactly the octants of their configuration. Changing
# the blocks one fine cell at a time, each cell only when it is simple,
# deforms the old object into the new one without changing its topology.
# The cells 2w+1+e of one octant e all have the same coordinates modulo 2:
# they are two apart, outside each other's 3^n neighbourhood, so the cells
# of one octant are tested and changed together (8 batches per sweep in 3D).


def _octants(nd: int) -> list[tuple[int, ...]]:
    """Octant ``e`` of configuration bit ``b = e_0 + 2 e_1 + 4 e_2``, in bit order."""
    return [tuple((b >> i) & 1 for i in range(nd)) for b in range(1 << nd)]


def fine_grid(cfg: np.ndarray) -> np.ndarray:
    """The old object on the grid refined twice, indexed so that the block
    of new voxel (vertex) ``w`` is cells ``2w+1 .. 2w+2``: octant ``e`` of
    ``w`` is full iff bit ``e`` of ``cfg[w]`` is set. One cell of pad."""
    nd = cfg.ndim
    shape = tuple(2 * n + 2 for n in cfg.shape)
    check_fits(2 * math.prod(shape), f"topology control's refined grid ({'x'.join(map(str, shape))} cells)",
               hint="run the guarded flow on a smaller or cropped volume")
    fine = np.zeros(shape, bool)
    for b, e in enumerate(_octants(nd)):
        sl = tuple(slice(1 + ei, 1 + ei + 2 * s, 2) for ei, s in zip(e, cfg.shape))
        fine[sl] = (cfg >> b) & 1
    return fine


def realise_moves(cfg: np.ndarray, keep: np.ndarray, connectivity: int, flip: bool = True, max_sweeps: int = 256,
                  by_class: bool = False, backward: bool = False):
    """Carry out the moves ``keep`` of one step by simple deformations.

    Every boundary vertex's block of fine cells is filled (outward) or
    emptied (inward) one cell at a time, a cell only when it is a simple
    point of the current fine object; the cells of one octant of all blocks
    are two fine cells apart, so they are tested at once, and the ``2^n``
    octants go one after the other. Sweeps repeat until nothing changes. A
    block that cannot reach its move is *stuck*; with ``flip`` its move is
    reversed once (inward <-> outward) and the sweeps go on.

    ``by_class`` keeps the order of the first implementation: the blocks of
    one sub-lattice class (``w`` modulo 2) after the other, each class octant
    by octant (64 batches a sweep instead of 8). The greedy order decides
    which vertex of a vanishing part is left stuck; :func:`change_region`
    takes this order, the one the plain runs' reference places
    (tests/flow/plain_reference.json) are written in.

    ``backward`` takes the octants in the reverse order. The greedy order
    decides which side of a thin part keeps it when its inward moves are
    reversed; the same order every step carries a thin ring half a voxel a
    step to one side, out of the object's bounding box, so
    :func:`lattice_step` reverses it on every other lattice.

    Returns ``(done, stuck)``: ``done`` is the realised keep-mask (valid when
    ``stuck`` is empty: the new object is then homotopy equivalent to the old
    one) and ``stuck`` the vertices left half-way.
    """
    nd = cfg.ndim
    full = (1 << (1 << nd)) - 1
    target = keep.copy()
    fine = fine_grid(cfg)
    cells = fine.ravel()
    strides = np.array([int(np.prod(fine.shape[d + 1:])) for d in range(nd)], np.int64)
    octants = [np.array(e) @ strides for e in _octants(nd)]
    if backward:
        octants = octants[::-1]
    pending = np.flatnonzero((cfg != 0) & (cfg != full))
    w = np.stack(np.unravel_index(pending, cfg.shape), axis=1)
    klass = (w & 1) @ (1 << np.arange(nd))[::-1] if by_class else np.zeros(len(pending), np.int64)
    # one class after the other: each class's blocks lie together, and stay
    # so as the blocks done leave; a batch's cells are tested at once, so
    # their order within it changes nothing
    order = np.argsort(klass, kind="stable")
    pending, w, klass = pending[order], w[order], klass[order]
    base = (2 * w + 1) @ strides
    goal = target.ravel()[pending]
    flipped = np.zeros(len(pending), bool)
    classes = np.arange((1 << nd) + 1 if by_class else 2)
    for _ in range(max_sweeps):
        changed = False
        bounds = np.searchsorted(klass, classes)
        for a, b in zip(bounds[:-1], bounds[1:]):
            for off in octants:
                c, want = base[a:b] + off, goal[a:b]
                todo = cells[c] != want
                if not todo.any():
                    continue
                c, want = c[todo], want[todo]
                ok = simple_codes(neighbourhood_codes(fine, c), nd, connectivity)
                if ok.any():
                    cells[c[ok]] = want[ok]
                    changed = True
        # blocks now uniform are done
        left = np.zeros(len(base), bool)
        for off in octants:
            left |= cells[base + off] != goal
        pending, base, klass, goal, flipped = pending[left], base[left], klass[left], goal[left], flipped[left]
        if not changed:
            if not flip or flipped.all():
                break
            goal = np.where(flipped, goal, ~goal)
            target.ravel()[pending] = goal
            flipped[:] = True
    stuck = np.zeros(cfg.shape, bool)
    stuck.ravel()[pending] = True
    return target, stuck


def around_any(voxels: np.ndarray) -> np.ndarray:
    """Per vertex of the grid one smaller than ``voxels`` along each axis:
    whether any of the ``2^n`` voxels around it (``voxels[w + e]``, ``e``
    in ``{0, 1}^n``) is set. On an array padded by one these are the
    vertices of the unpadded array, each the corner the voxels share.

    Examples
    --------
    >>> around_any(np.array([[0, 0, 0], [0, 0, 0], [0, 0, 1]], bool)).astype(int)
    array([[0, 0],
           [0, 1]])
    """
    out = np.zeros(tuple(n - 1 for n in voxels.shape), bool)
    for d in itertools.product((0, 1), repeat=voxels.ndim):
        out |= voxels[tuple(slice(di, di + n) for di, n in zip(d, out.shape))]
    return out


def corners_any(vertices: np.ndarray, outside: bool = False) -> np.ndarray:
    """Per voxel of the object's array padded by one: whether any of its
    ``2^n`` corners is set in ``vertices`` (a vertex-grid mask, one larger
    than the array along each axis, as :func:`flow_moves`' ``keep``); a
    corner off that grid reads ``outside``. The voxels around a vertex are
    those it is a corner of, so this is also the ``2^n`` voxels around
    every set vertex.

    Examples
    --------
    >>> corners_any(np.array([[False, False], [False, True]])).astype(int)
    array([[0, 0, 0],
           [0, 1, 1],
           [0, 1, 1]])
    """
    return around_any(np.pad(np.asarray(vertices, bool), 1, constant_values=outside))


def change_region(obj: DigitalObject, cfg: np.ndarray, keep: np.ndarray, conn: int,
                  betti: tuple[list, list] | None = None, stuck: np.ndarray | None = None):
    """World bbox (min corner then max corner, one flat list) of where the plain move ``keep`` from ``obj``
    changes its topology, None when empty.

    The greedy sweeps of :func:`realise_moves` carry out every move they
    can by simple deformations; the vertices left stuck are where the
    topology changes, but the greedy order decides which fine cell of a
    vanishing part or a closing hole is the last, so a stuck vertex alone
    may miss the part. The region is therefore the ``2^n`` voxels around
    every stuck vertex, together with each part that the step removes or
    fills whole and that meets them: a connected set (``conn``) of voxels
    none of whose corners is kept, or a connected set of background voxels
    (the complementary connectivity) all of whose corners are kept; and
    every cavity (hole in 2D) that the step closes off
    (:func:`appeared_cavities`), which the stuck vertex of its mouth meets
    only at the mouth. Its box is then widened (:func:`box_holding_change`)
    until the step taken inside the box alone gives the new Betti numbers
    and the step taken outside it alone keeps the old ones. When no vertex
    is stuck, the new object's bounding box.

    ``betti``: the Betti numbers of ``obj`` and of the object ``keep``,
    where the caller has them (a run records every state's); ``stuck``:
    the vertices that ``realise_moves(cfg, keep, conn, flip=False,
    by_class=True)`` leaves stuck, where the caller has them (compiled,
    :func:`isoflow.flow.bitguard.packed_stuck`); each is found here
    otherwise.

    Examples
    --------
    >>> from isoflow.flow.motion import flow_moves
    >>> square = np.zeros((7, 7), bool)
    >>> square[1:6, 1:6] = True
    >>> square[3, 3] = False  # a one-pixel hole [3, 4]^2, which the step closes
    >>> change_region(DigitalObject(square), *flow_moves(DigitalObject(square), 4), 4)
    [2.0, 2.0, 4.0, 4.0]
    """
    if stuck is None:
        _, stuck = realise_moves(cfg, keep, conn, flip=False, by_class=True)
    if not stuck.any():
        box = obj.on_dual_lattice(keep).bbox()
        return None if box is None else box[0].tolist() + box[1].tolist()
    region = corners_any(stuck)
    volume = np.pad(obj.volume, 1)
    vanished = volume & ~corners_any(keep)
    filled = ~volume & ~corners_any(~keep, outside=True)  # a vertex off the grid is never kept
    for part, c in ((vanished, conn), (filled, complement(obj.ndim, conn))):
        if part.any():
            labels, _ = label(part, c)
            met = np.unique(labels[region & part])
            region |= np.isin(labels, met[met > 0])
    region |= corners_any(appeared_cavities(volume, keep, conn))  # new voxel w is the voxels around vertex w
    if betti is None:
        betti = betti_numbers(obj.volume, conn), betti_numbers(keep, conn)
    lo, hi = box_holding_change(cfg, keep, conn, region, volume | corners_any(keep), betti)
    inside = np.zeros(region.shape, bool)
    inside[tuple(slice(a, b) for a, b in zip(lo, hi))] = True
    box = replace(obj, volume=inside, offset=tuple(o - 1 for o in obj.offset)).bbox()
    return None if box is None else box[0].tolist() + box[1].tolist()


def enclosed(volume: np.ndarray, conn: int) -> tuple[np.ndarray, np.ndarray]:
    """``(labels, mask)``: the background components of ``volume`` under
    the connectivity complementary to ``conn``, and those of them that do
    not reach the array's first cell (background where ``volume`` is
    padded: its cavities, holes in 2D).

    Examples
    --------
    >>> ring = np.pad(np.ones((3, 3), bool), 1)
    >>> ring[2, 2] = False
    >>> enclosed(ring, 4)[1].astype(int)[2]
    array([0, 0, 1, 0, 0])
    """
    labels, _ = label(~volume, complement(volume.ndim, conn))
    return labels, (labels > 0) & (labels != labels[(0,) * volume.ndim])


def appeared_cavities(volume: np.ndarray, keep: np.ndarray, conn: int) -> np.ndarray:
    """Per vertex (``keep``'s grid): whether new voxel ``keep`` lies in a
    cavity (hole in 2D) of the new object that no cavity of the old one
    overlaps, the old object's array ``volume`` padded by one.

    On the grid refined twice (:func:`fine_grid`) each voxel of either
    object is a ``2^n`` block of cells, and blocks meet as their voxels do
    under every connectivity, so each object's background components are
    its voxels' (each padded by one: the old voxels by ``volume``'s pad,
    the new ones by a pad of ``keep``, both background), and new voxel
    ``w`` shares cells with the old voxels around vertex ``w``: exactly the
    fine grids' cavities that no cavity of the old object overlaps,
    counted on 8 times fewer cells (4 in 2D).

    Examples
    --------
    >>> c_shape = np.array([[1, 1, 1], [1, 0, 0], [1, 1, 1]], bool)  # a pocket, open to the right
    >>> ring = np.array([[0, 0, 0, 0], [0, 1, 1, 1], [0, 1, 0, 1], [0, 1, 1, 1]], bool)  # its mouth closed
    >>> appeared_cavities(np.pad(c_shape, 1), ring, 4).astype(int)[2]
    array([0, 0, 1, 0])
    >>> c_shape[1, 2] = True  # the pocket a hole already: the ring's overlaps it
    >>> bool(appeared_cavities(np.pad(c_shape, 1), ring, 4).any())
    False
    """
    _, was = enclosed(volume, conn)
    labels, now = enclosed(np.pad(keep, 1), conn)
    labels, now = labels[(slice(1, -1),) * keep.ndim], now[(slice(1, -1),) * keep.ndim]
    kept = np.unique(labels[around_any(was) & now])
    return now & ~np.isin(labels, kept)


def box_holding_change(cfg: np.ndarray, keep: np.ndarray, conn: int, region: np.ndarray, extent: np.ndarray,
                       want: tuple[list, list]) -> tuple[np.ndarray, np.ndarray]:
    """The box ``[lo, hi)`` (indices of the old object's array padded by
    one, as ``region``) around ``region`` inside which the step from the
    old object (its configurations ``cfg``) to the new one (``keep``)
    changes the topology: taken inside it alone (the old object outside)
    the step gives the new Betti numbers, taken outside it alone it keeps
    the old ones (``want``: the old and the new). Both objects are laid on
    the grid refined twice (:func:`fine_grid`), where the padded array's
    voxel ``p`` is cells ``2p .. 2p + 1``.

    On that grid an old voxel and a new one are each a ``2^n`` block of
    cells, half a voxel apart. A box that crosses a thin part where the
    two differ joins or cuts it there (a pocket whose mouth the step closes
    inside the box while its far end stays open outside is a hole of
    neither object), so the box of ``region`` grows on every side, by one
    voxel at a time and by half its margin once that is more, until the
    step splits there cleanly. It never grows past the voxels ``extent``
    that either object covers (and ``region``): a box holding them all
    takes the whole step inside, and the refined grids are then never made.

    Examples
    --------
    >>> from isoflow.flow.motion import flow_moves
    >>> obj = DigitalObject(np.array([[1, 0, 0, 0], [0, 0, 1, 1], [0, 0, 1, 1]], bool))
    >>> cfg, keep = flow_moves(obj, 4)
    >>> region = np.zeros((5, 6), bool)
    >>> region[1, 1] = True  # the isolated pixel, which vanishes
    >>> extent = np.pad(obj.volume, 1) | corners_any(keep)
    >>> [b.tolist() for b in box_holding_change(cfg, keep, 4, region, extent, ([2, 0], [1, 0]))]
    [[1, 1], [2, 2]]
    """
    idx = np.argwhere(extent | region)
    floor, ceil = idx.min(0), idx.max(0) + 1
    idx = np.argwhere(region)
    lo, hi = idx.min(0), idx.max(0) + 1
    grids = None
    margin = 0
    while True:
        lo_k, hi_k = np.maximum(lo - margin, floor), np.minimum(hi + margin, ceil)
        if (lo_k == floor).all() and (hi_k == ceil).all():
            return lo_k, hi_k
        if grids is None:
            grids = fine_grid(cfg), fine_grid(np.where(keep, (1 << (1 << keep.ndim)) - 1, 0))
        if step_splits_at(*grids, tuple(slice(2 * a, 2 * b) for a, b in zip(lo_k, hi_k)), conn, want):
            return lo_k, hi_k
        margin += max(1, margin // 2)


def step_splits_at(old: np.ndarray, new: np.ndarray, box: tuple[slice, ...], conn: int,
                   want: tuple[list, list]) -> bool:
    """Whether the step from ``old`` to ``new`` (one grid), taken only
    inside ``box``, gives ``new``'s Betti numbers and, taken only outside
    it, keeps ``old``'s (``want``: the two, in that order).

    Examples
    --------
    >>> old = np.zeros((6, 6), bool)
    >>> old[1:3, 1:3] = old[4, 4] = True
    >>> new = old.copy()
    >>> new[4, 4] = False  # a component vanishes
    >>> step_splits_at(old, new, (slice(3, 6), slice(3, 6)), 4, ([2, 0], [1, 0]))
    True
    >>> step_splits_at(old, new, (slice(0, 3), slice(0, 3)), 4, ([2, 0], [1, 0]))
    False
    """
    inside, outside = old.copy(), new.copy()
    inside[box], outside[box] = new[box], old[box]
    return betti_numbers(inside, conn) == want[1] and betti_numbers(outside, conn) == want[0]


def lattice_step(obj: DigitalObject, conn: int, betti: list[int]):
    """The flow step to the other lattice under topology control (steps 1-2
    of the module docstring): ``(new object, kind, moves reversed)`` with
    kind ``flow`` or ``partial``, or None when no resolution of the stuck
    blocks keeps the Betti numbers."""
    cfg, keep = flow_moves(obj, conn)
    done, stuck = realise_moves(cfg, keep, conn, backward=obj.parity == 1)
    if not stuck.any():
        return obj.on_dual_lattice(done).cropped(), "flow", int((done != keep).sum())
    return resolve_stuck(obj, keep, done, stuck, conn, betti)


def resolve_stuck(obj: DigitalObject, keep: np.ndarray, done: np.ndarray, stuck: np.ndarray, conn: int,
                  betti: list[int]):
    """Step 2 of the module docstring: the stuck blocks all given their
    plain move (``keep``), all moved outward, or all inward, the first that
    keeps the Betti numbers, with the others' realised moves (``done``):
    ``(new object, "partial", moves reversed)``, or None."""
    for vol in (np.where(stuck, keep, done), done | stuck, done & ~stuck):
        if vol.any() and betti_numbers(vol, conn) == betti:
            return obj.on_dual_lattice(vol).cropped(), "partial", int((vol != keep).sum())
    return None


# --------------------------------------------------------------------------
# Thinning on the same lattice
# --------------------------------------------------------------------------


def convexity(volume: np.ndarray) -> np.ndarray:
    """Per voxel: the vertex index ``f`` of its ``2^n`` corners summed
    (eq. 4.8 in 3D, ``f = (sum s(alpha_i)) (sum |s(alpha_i)|)``: 9 at a
    convex corner (+,+,+), 1 on a convex edge, 0 on a flat, -1 on a concave
    edge, -9 at a concave corner; the sign of eq. 4.2 in 2D: 1 convex, 0
    flat, -1 concave). It is the signed curvature concentrated at the voxel:
    72 for an isolated voxel, 12 for a box corner, 2 on a box edge, 0 on a
    face, -9 at a concave corner. Not-well-composed corners count 0."""
    nd = volume.ndim
    if nd == 3:
        lut = f_lut()
    else:
        cls = planar_class_lut()
        lut = np.where(cls >= 0, 1 - cls, 0)
    f = lut[configurations(volume)]
    out = np.zeros(volume.shape, np.int64)
    for e in itertools.product((0, 1), repeat=nd):
        out += f[tuple(slice(ei, ei + s) for ei, s in zip(e, volume.shape))]
    return out


def thinning_step(volume: np.ndarray, connectivity: int) -> np.ndarray | None:
    """Delete simple voxels, the most convex first.

    The voxels next to the background are ordered by :func:`convexity`; the
    convex and flat ones (0 and above: where the flow moves inward) go level
    by level from the most convex down, each level subfield by subfield
    (:func:`isoflow.digital.simple.delete_simple`), the test always on the
    volume left so far. Only when none of them is simple do the concave ones
    (where the flow moves outward) get their turn, the least concave level
    first. The step is a sequence of simple deletions and keeps every Betti
    number. Returns the thinned volume (same shape), or None when no voxel
    is simple.
    """
    # C order whatever the input's: np.pad keeps a Fortran-ordered array's
    # order, and delete_simple deletes through flat indices in place
    padded = np.pad(np.ascontiguousarray(volume, dtype=bool), 1)
    conv = np.pad(convexity(volume), 1)
    # only voxels next to the background can be simple
    inner = np.ones(volume.shape, bool)
    for e in itertools.product((0, 1, 2), repeat=volume.ndim):
        inner &= padded[tuple(slice(ei, ei + s) for ei, s in zip(e, volume.shape))]
    flat = np.flatnonzero(np.pad(volume & ~inner, 1))
    level = conv.ravel()[flat]
    values = np.unique(level)[::-1]
    for tier in (values[values >= 0], values[values < 0]):
        deleted = sum(len(delete_simple(padded, flat[level == v], connectivity)) for v in tier)
        if deleted:
            return padded[(slice(1, -1),) * volume.ndim]
    return None


# --------------------------------------------------------------------------
# One guarded step
# --------------------------------------------------------------------------


def shape_key(obj: DigitalObject) -> bytes:
    """A digest of the object's shape up to translation (and lattice)."""
    h = hashlib.sha1(repr(obj.volume.shape).encode())
    h.update(np.packbits(obj.volume).tobytes())
    return h.digest()


def is_progress(voxels: int, before: int, key: Callable[[], bytes], key_before: Callable[[], bytes],
                seen: set | None, may_grow: bool) -> bool:
    """Whether a flow step is progress (module docstring): it removes
    voxels (``voxels < before``), or (``may_grow``) it reaches a shape
    (``key()``, its :func:`shape_key`) that is neither the current one
    (``key_before()``) nor in ``seen``."""
    if voxels < before:
        return True
    if not may_grow:
        return False
    k = key()
    return k != key_before() and (seen is None or k not in seen)


@dataclass(frozen=True)
class GuardedStep:
    """What :func:`guarded_step` did: ``new`` is the next state (the same
    object at a fixed point); ``kind`` is ``flow`` (the whole flow step),
    ``partial`` (the flow step with its stuck blocks resolved), ``thinning``
    (same lattice) or ``fixed-point``; ``reversed_moves`` counts the vertices
    whose move was reversed."""

    new: DigitalObject
    kind: str
    reversed_moves: int = 0


def guarded_step(
    obj: DigitalObject,
    connectivity: int | None = 6,
    betti: list[int] | None = None,
    *,
    seen: set | None = None,
    may_grow: bool = True,
) -> GuardedStep:
    """One step that keeps the topology (module docstring); never refuses.

    ``seen`` holds the :func:`shape_key` of the states a run has had; a flow
    step that does not remove voxels is taken only with ``may_grow`` and
    when its shape is new (not in ``seen`` and not the current shape).
    """
    obj = DigitalObject.of(obj)
    conn = flow_connectivity(obj.ndim, connectivity)
    if betti is None:
        betti = betti_numbers(obj.volume, conn)
    got = lattice_step(obj, conn, betti)
    if got is not None:
        new, kind, n_reversed = got
        if is_progress(new.voxels, obj.voxels, lambda: shape_key(new), lambda: shape_key(obj), seen, may_grow):
            return GuardedStep(new, kind, n_reversed)
    thinned = thinning_step(obj.volume, conn)
    if thinned is not None:
        return GuardedStep(replace(obj, volume=thinned).cropped(), "thinning")
    return GuardedStep(obj, "fixed-point")
