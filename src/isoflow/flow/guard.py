"""Topology control for the digital curvature flow (introduction and
Theorem 21 of the paper): a step carried out as a sequence of simple
deformations, so that it keeps the Betti numbers.

Refine the grid twice: old voxel ``v`` is a block of ``2^n`` fine cells, and
so is the new voxel centred at vertex ``w``; the fine cell of the new block
in octant ``e`` of ``w`` lies in old voxel ``w - 1 + e``. The old object is
thus the new blocks each holding the octants of its configuration, and a
step fills the blocks of the outward moves and empties those of the inward
moves. :func:`realise_moves` does that **one fine cell at a time, a cell only
when it is a simple point** (Bertrand's topological numbers in its 3^n
neighbourhood are 1 for the object and for the background, with the
connectivity pair asked; :mod:`isoflow.digital.simple`). Blocks of one
sub-lattice class (``w`` modulo 2) are two fine cells apart, so a whole class
is tested at once, and a block's ``2^n`` octants go one after the other;
sweeps repeat until nothing changes. A block that cannot reach its move is
*stuck*: its move is reversed (inward <-> outward) once and the sweeps go on.
When no block is left stuck, the new object is reached from the old one by
simple deformations only, so nothing was split, merged, opened or closed --
not even a split and a merge at once that would leave the Betti numbers
equal. When blocks stay stuck, :func:`guarded_step` tries three last resorts
checked by the Betti numbers, and refuses the step (returns None) when none
keeps them: the run stops as ``guard-blocked``. See docs/flow.md.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..digital.lattice import DigitalObject
from ..digital.simple import neighbour_bits, topological_numbers
from ..digital.topology import betti_numbers
from .motion import flow_connectivity, flow_moves

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
                t_obj, t_bg = topological_numbers(neighbour_bits(fine, c), connectivity)
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
            return obj.on_dual_lattice(vol).cropped(), int((vol != keep).sum())
    return None


def change_region(obj: DigitalObject, cfg: np.ndarray, keep: np.ndarray, conn: int):
    """World bbox [min, max] of the vertices whose plain move is not a simple
    deformation (module docstring), or of the new object when none is."""
    _, stuck = realise_moves(cfg, keep, conn, flip=False)
    where = stuck if stuck.any() else keep
    box = obj.on_dual_lattice(where).bbox()
    return None if box is None else [box[0].tolist(), box[1].tolist()]
