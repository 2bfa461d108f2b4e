"""Topology control for the digital curvature flow (introduction and
Theorem 21 of the paper): a step carried out as a sequence of simple
deformations, so that it keeps the Betti numbers.

On the grid refined twice, every step of the flow (the old object on one
lattice, the new one on the other) is a change of fine cells. The guard makes
that change one fine cell at a time and lets a cell change only when it is a
*simple point* (Bertrand's topological numbers T = T_bar = 1 in its 3^n
neighbourhood, for the connectivity pair asked), sub-lattice by sub-lattice so
that cells changed together never see each other. Moves that cannot be
completed are reversed; the result is checked against the Betti numbers, and
when nothing keeps them the step is refused (:func:`guarded_step` returns
None and the run stops as ``guard-blocked``). See docs/flow.md.
"""

from __future__ import annotations

import itertools
from functools import lru_cache

import numpy as np

from .flow import _bbox_list, _is_min, flow_connectivity, _shifted_object, flow_moves
from .lattice import DigitalObject
from .topology import betti_numbers


# --------------------------------------------------------------------------
# Simple points: Bertrand's topological numbers, vectorised over candidates
# --------------------------------------------------------------------------


@lru_cache(maxsize=None)
def _neighbourhood(ndim: int):
    """The 3^n - 1 neighbour offsets and the bit masks of the 3^n bitboard.

    A neighbourhood is stored as an integer whose bit ``sum_d (o_d + 1) 3^d``
    is offset ``o``; dilations are shifts by ``3^d`` with masks that stop
    them at the border of the 3^n block (as chess engines do on bitboards).
    """
    offs = np.array([o for o in itertools.product((-1, 0, 1), repeat=ndim) if any(o)], np.int64)
    pos = (offs + 1) @ (3 ** np.arange(ndim))
    coords = np.array([[(i // 3**d) % 3 for d in range(ndim)] for i in range(3**ndim)])
    l1 = np.abs(coords - 1).sum(1)

    def mask(sel):
        return int(sum(1 << int(i) for i in np.flatnonzero(sel)))

    return {
        "offsets": offs,
        "bitpos": pos.astype(np.uint32),
        "shifts": [
            (np.uint32(3**d), np.uint32(mask(coords[:, d] < 2)), np.uint32(mask(coords[:, d] > 0)))
            for d in range(ndim)
        ],
        "face": mask(l1 == 1),
        "n18": mask((l1 >= 1) & (l1 <= 2)),
        "all": mask(l1 >= 1),
    }


def _dilate(s: np.ndarray, shifts, full: bool) -> np.ndarray:
    """One step of face (``full=False``) or full adjacency on bitboards."""
    out = s
    for step, lo, hi in shifts:
        src = out if full else s
        out = out | ((src & lo) << step) | ((src & hi) >> step)
    return out


def _count_components(present: np.ndarray, seeds_mask: int, shifts, full: bool) -> np.ndarray:
    """Per row: the components of ``present`` (bitboards) that meet ``seeds_mask``."""
    count = np.zeros(len(present), np.int64)
    left = present.copy()
    seeds = np.uint32(seeds_mask)
    while True:
        cand = left & seeds
        active = cand != 0
        if not active.any():
            return count
        comp = cand & (~cand + np.uint32(1))  # lowest set bit
        while True:
            grown = _dilate(comp, shifts, full) & left
            if np.array_equal(grown, comp):
                break
            comp = grown
        count += active
        left &= ~comp


def topological_numbers(bits: np.ndarray, connectivity: int) -> tuple[np.ndarray, np.ndarray]:
    """Bertrand's topological numbers of the object and of the background.

    ``bits`` is ``(K, 3^n - 1)``: the neighbours of K points in the order of
    ``_neighbourhood(n)['offsets']``. Face connectivity (6 / 4): the object's
    number counts the face-components of the object in the 18- (3D) or
    8-neighbourhood (2D) that touch a face neighbour, the background's the
    full-adjacency components of the background in the whole neighbourhood;
    the larger connectivity swaps the roles. A point is simple (adding or
    deleting it changes no Betti number) iff both numbers are 1.
    """
    ndim = 3 if bits.shape[1] == 26 else 2
    nb = _neighbourhood(ndim)
    board = (bits.astype(np.uint32) << nb["bitpos"][None, :]).sum(axis=1, dtype=np.uint32)
    background = ~board & np.uint32(nb["all"])
    sh = nb["shifts"]

    def face_number(present):
        return _count_components(present & np.uint32(nb["n18"]), nb["face"], sh, full=False)

    def full_number(present):
        return _count_components(present, nb["all"], sh, full=True)

    if _is_min(connectivity):
        return face_number(board), full_number(background)
    return full_number(board), face_number(background)


def _gather(vol_padded: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Neighbour bits of points ``idx`` (K, n) of a padded volume."""
    nb = _neighbourhood(vol_padded.ndim)
    strides = np.array([int(np.prod(vol_padded.shape[d + 1:])) for d in range(vol_padded.ndim)], np.int64)
    flat = idx @ strides
    return vol_padded.ravel()[flat[:, None] + nb["offsets"] @ strides]


def simple_points(volume: np.ndarray, points: np.ndarray, connectivity: int) -> np.ndarray:
    """Which of ``points`` (K, n array indices) are simple for ``volume``.

    A point is simple when adding it to or deleting it from the object leaves
    every Betti number of object and background unchanged: both topological
    numbers equal 1 (the point itself is ignored, so the same test serves
    for deletion and addition).
    """
    vol = np.pad(np.asarray(volume, bool), 1)
    pts = np.asarray(points, np.int64).reshape(-1, vol.ndim) + 1
    if len(pts) == 0:
        return np.zeros(0, bool)
    t_obj, t_bg = topological_numbers(_gather(vol, pts), connectivity)
    return (t_obj == 1) & (t_bg == 1)


# --------------------------------------------------------------------------
# Topology control: the step as a sequence of simple deformations
# --------------------------------------------------------------------------
#
# On the grid refined twice, old voxel v is the 2^n block of fine cells
# 2v+2 .. 2v+3 (after a one-voxel pad) and new voxel w (centred at vertex w)
# the block 2w+1 .. 2w+2, whose cell 2w+1+e lies in octant e of w. A step
# turns every new block full (kept) or empty (dropped); the old object is the
# same blocks holding exactly the octants of their configuration. Changing
# the blocks one fine cell at a time, each cell only when it is simple,
# deforms the old object into the new one without changing its topology.


def realise_moves(cfg: np.ndarray, keep: np.ndarray, connectivity: int, flip: bool = True, max_sweeps: int = 256):
    """Carry out the moves ``keep`` of one step by simple deformations.

    Every boundary vertex's block of fine cells is filled (outward) or
    emptied (inward) one cell at a time, a cell only when it is a simple
    point of the current fine object; blocks of one sub-lattice class (``w``
    modulo 2) are 2 fine cells apart, so a whole class is tested at once, and
    the 2^n octants of a block go one after the other. Sweeps repeat until
    nothing changes. A block that cannot reach its move is *stuck*; with
    ``flip`` its move is reversed once (inward <-> outward) and the sweeps go
    on.

    Returns ``(done, stuck)``: ``done`` is the realised keep-mask (valid when
    ``stuck`` is empty: the new object is then homotopy equivalent to the old
    one) and ``stuck`` the vertices left half-way.
    """
    nd = cfg.ndim
    full = (1 << (1 << nd)) - 1
    target = keep.copy()
    boundary = (cfg != 0) & (cfg != full)
    fine = np.zeros(tuple(2 * n + 2 for n in cfg.shape), bool)  # one fine cell of pad
    octs = [tuple((b >> i) & 1 for i in range(nd)) for b in range(1 << nd)]
    # the fine object of the old volume: block w holds the octants of cfg[w]
    for b, e in enumerate(octs):
        sl = tuple(slice(1 + ei, 1 + ei + 2 * s, 2) for ei, s in zip(e, cfg.shape))
        fine[sl] = (cfg >> b) & 1
    pending = boundary.copy()
    flipped = np.zeros(cfg.shape, bool)
    classes = list(itertools.product((0, 1), repeat=nd))
    for _ in range(max_sweeps):
        changed = False
        for cls in classes:
            sub = tuple(slice(c, None, 2) for c in cls)
            w_cls = np.argwhere(pending[sub]) * 2 + np.array(cls)
            if len(w_cls) == 0:
                continue
            tgt = target[tuple(w_cls.T)]
            for e in octs:
                cells = 2 * w_cls + 1 + np.array(e)
                state = fine[tuple(cells.T)]
                todo = state != tgt
                if not todo.any():
                    continue
                c = cells[todo]
                t_obj, t_bg = topological_numbers(_gather(fine, c), connectivity)
                ok = (t_obj == 1) & (t_bg == 1)
                if ok.any():
                    fine[tuple(c[ok].T)] = tgt[todo][ok]
                    changed = True
            # blocks now uniform are done
            blocks = np.stack([fine[tuple((2 * w_cls + 1 + np.array(e)).T)] for e in octs], axis=1)
            uniform = (blocks == tgt[:, None]).all(axis=1)
            pending[tuple(w_cls[uniform].T)] = False
        if not changed:
            if not flip:
                break
            todo = pending & ~flipped
            if not todo.any():
                break
            target[todo] = ~target[todo]
            flipped |= todo
    return target, pending


def guarded_step(obj: DigitalObject, connectivity: int | None = 6, betti: list[int] | None = None):
    """One step that keeps the topology, or None when the guard blocks.

    Returns ``(new_object, moves_reversed)``: the plain moves carried out as
    simple deformations (:func:`realise_moves`), with the moves that could not
    be carried out reversed; ``moves_reversed`` counts those vertices. None
    when some vertex can go neither way, or (a safety net that the
    construction should never need) when the Betti numbers differ.
    """
    conn = flow_connectivity(obj.ndim, connectivity)
    if betti is None:
        betti = betti_numbers(obj.volume, conn)
    cfg, keep = flow_moves(obj, conn)
    done, stuck = realise_moves(cfg, keep, conn)
    tries = [done]
    if stuck.any():
        # last resort, checked by the Betti numbers only: the stuck vertices
        # all with their plain move, all outward, all inward
        tries = [np.where(stuck, keep, done), done | stuck, done & ~stuck]
    for vol in tries:
        if betti_numbers(vol, conn) == betti:
            return _shifted_object(obj, vol).cropped(), int((vol != keep).sum())
    return None


def change_region(obj: DigitalObject, cfg: np.ndarray, keep: np.ndarray, conn: int):
    """World bbox [min, max] of the vertices whose plain move is not a simple
    deformation (module docstring), or of the new object when none is."""
    _, stuck = realise_moves(cfg, keep, conn, flip=False)
    where = stuck if stuck.any() else keep
    return _bbox_list(_shifted_object(obj, where))


