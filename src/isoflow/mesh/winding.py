"""The generalised winding number (Jacobson et al. 2013) of voxel centres,
exactly, with a tree over the cap so that soups and meshes with many
boundaries cost about what closed meshes cost.

The generalised winding number of a triangle mesh M at a point p is
``w(p) = sum over triangles of Omega_t(p) / 4 pi`` (signed solid angles); a
voxel is in iff ``|w(centre)| > 1/2``.  On a closed, consistently oriented
mesh w is the integer winding number and the rule is the nonzero rule.

How it is computed (no approximation that can flip a voxel):

1. **Cap.** The boundary of M as an integer 1-chain (every edge with its net
   multiplicity, uses one way minus uses the other way) is a cycle.  A cap C
   with boundary ``-boundary(M)`` makes ``M + C`` closed: its winding number
   W is an integer that the exact scanline (:mod:`isoflow.mesh.scanline`)
   computes at every centre, and ``w_M = W - w_C``.  The faces of M fall
   into *groups* (face components joined by shared boundary pieces); each
   group is capped by the cheaper of two caps, by area: cones over its
   boundary pieces (from each piece's centroid, lifted by 1 % of its size
   along its vector area and 0.1 % along a fixed generic direction, so
   that a planar hole in a plane of voxel centres does not put a layer of
   centres on the cap), or the group itself reversed.  A scanned surface
   with a few holes gets cones; a triangle soup, or a mesh whose boundary
   runs everywhere (a tetrahedral mesh's faces written as quads), gets
   itself: its faces then cancel out of the scanline, which reads zero
   there, and the cap carries all of w.
2. **Rounding to an integer.** ``|W - w_C| > 1/2`` iff ``W != round(w_C)``
   (W is an integer; equality only at |w| = 1/2 exactly).  So only
   ``R = round(w_C)`` is needed.
3. **Blocks with a bound.** Blocks of voxels are evaluated at their centre
   by :func:`isoflow.mesh.captree.evaluate` (a cap of at most
   :data:`~isoflow.mesh.cap_lanes.FLAT_MAX` triangles, a soup, by
   :func:`isoflow.mesh.cap_lanes.evaluate_lanes`, all its triangles at
   once; the sums at each centre run in SIMD lanes,
   :mod:`isoflow.mesh.block_lanes`): the cap's triangles in a tree
   of balls, near ones summed exactly, far ones by Barill et al.'s
   expansion with a proven remainder, plus a bound on the variation over
   the block (the Biot-Savart field of the chain).  A cap triangle that
   cuts the block along its plane without an edge in it adds its integer
   crossing per voxel (the side of its plane).  A block whose interval
   ``w_C(q) +- (remainder + variation)`` holds no half-integer gets one R
   (plus the crossings); a block that is undecided because of the
   remainder is evaluated again with a tighter tree (``theta / 3``, then
   exactly); other blocks, and blocks that a cap edge meets, are split in
   eight, down to single voxels, whose ``w_C`` is exact at the last try.
   A centre within ``1e-6`` pitch of the cap (where the scanline's tie
   rule and the sign of a solid angle could disagree), and one whose
   ``w_C`` is within ``1e-9`` of a half-integer (where rounding it
   decides nothing: on a planar part of M that lies in a plane of
   centres, ``w_C`` is exactly 1/2 inside the boundary), gets ``w_M``
   summed over M's own triangles instead, at the point the scanline's tie
   rule stands for (the centre moved by ``(eta, eps, -delta)``, ``0 < eps
   << eta << delta``, here 1e-9, 1e-7 and 1e-5 pitch): on a planar sheet
   ``|w_M|`` is then just under 1/2, so its centres are out, whichever way
   it faces.

Cost: the scanline's, plus the blocks evaluated, each at about the
logarithm of the cap's size.  Near a hole w passes 1/2 on a
soap-film-like sheet across it, and there every voxel needs its own
value: a hole n voxels wide costs about n^2 such voxels.  The work runs
in pieces of blocks on two threads, polling :mod:`isoflow.scale.cancel`,
so that an interrupt ends it at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import IsoflowError
from ..scale.cancel import STOP, Stopped, run_pieces
from ..scale.jit import njit
from .block_lanes import (
    FORCE_IN,
    FORCE_OUT,
    MAX_R,
    PAINT_LANES,
    QUEUE,
    TIE_PENDING,
    TIE_WINDING,
    UNDECIDED,
    exact_queue,
    paint_lanes,
    queue_centres,
)
from .cap_lanes import FLAT_MAX, evaluate_lanes, lanes_arrays
from .captree import HIT, MAX_NEAR, CapTree, evaluate, near_range
from .solid_angles import winding_lanes

#: centres closer than this (in pitches) to the cap, and those whose w_C
#: is within TIE_WINDING of a half-integer, are summed over M itself
TIE_PITCHES = 1e-6
#: where they are summed: the centre moved as the scanline's tie rule moves
#: it, (x + eta, y + eps, -delta) with 0 < eps << eta << delta (pitches)
TIE_STEP = np.array([1e-7, 1e-9, -1e-5])
#: blocks at the coarsest level are about this many per axis
TOP_BLOCKS = 16
#: triangles with an edge within this many block radii (beyond the block) are summed at each centre
REACH = 4.0
#: a block of at most this many centres that leaves at most a quarter of
#: them undecided has those evaluated one by one instead of being split
SMALL = 64
#: a block of more than SMALL centres with more near and crossing triangles is split, not painted
NEAR_PAINT = 4
#: far nodes are expanded when their radius is at most this share of their distance
THETA = 0.3
#: pieces of top blocks per slab (the unit of progress and of the threads' work)
PIECES = 512
#: blocks of at most this many centres are painted to the end (their few
#: undecided centres then summed exactly); larger ones stop at the first
PAINT_ALL = 512
#: an undecided block with at most this many (centre, cap triangle) pairs
#: is summed exactly at every centre, in SIMD lanes, instead of being split
EXACT_PAIRS = 1 << 16
_GENERIC = np.array([0.5773, 0.3141, 0.7537]) / np.linalg.norm([0.5773, 0.3141, 0.7537])


# ---------------------------------------------------------------------------
# caps
# ---------------------------------------------------------------------------

@dataclass
class Cap:
    """A cap that closes a mesh (module docstring, step 1).

    ``T`` (K, 3, 3) its triangles, ``E`` (E, 2, 3) the chain (the mesh's
    boundary, repeated by multiplicity), ``owner`` (E,) the cap triangle
    that has each chain edge as an edge of its own, and ``reversed_faces``
    the mesh's faces that the cap holds reversed (they cancel out of the
    closed mesh, so the scanline skips them).
    """

    T: np.ndarray
    E: np.ndarray
    owner: np.ndarray
    reversed_faces: np.ndarray

    def cones(self) -> np.ndarray:
        """The cap's triangles that are not reversed faces (those come first)."""
        return self.T[int(self.reversed_faces.sum()):]


def close_mesh(v: np.ndarray, faces: np.ndarray, a: np.ndarray, b: np.ndarray) -> Cap:
    """The cap over the boundary chain ``a[e] -> b[e]`` of ``faces``.

    Parameters
    ----------
    v : (N, 3) float array
        Vertex positions.
    faces : (M, 3) int array
        The mesh's faces (oriented as they will be read).
    a, b : (E,) int arrays
        The chain: directed edges repeated by their net multiplicity
        (:func:`isoflow.mesh.load.boundary_chain`).

    Returns
    -------
    Cap
        Cones over the boundary pieces of each group of faces, or the group
        reversed, whichever has the smaller area.

    Examples
    --------
    >>> v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> cap = close_mesh(v, np.array([[0, 1, 2]]), np.array([0, 1, 2]), np.array([1, 2, 0]))
    >>> cap.T.shape, cap.reversed_faces.tolist()
    ((1, 3, 3), [True])
    """
    faces = np.asarray(faces, dtype=np.int64)
    m = len(faces)
    if len(a) == 0:
        return Cap(np.zeros((0, 3, 3)), np.zeros((0, 2, 3)), np.zeros(0, np.int64), np.zeros(m, bool))
    piece, face_of_edge, face_group, ngroups = _groups(faces, len(v), a, b)
    apex, cone_area = _cones(v, a, b, piece)
    fa = 0.5 * np.linalg.norm(np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]]), axis=1)
    fgroup = face_group[face_of_edge]  # the group of each chain edge
    cone_by_group = np.bincount(fgroup, weights=cone_area, minlength=ngroups)
    inside = face_group >= 0
    area_by_group = np.bincount(face_group[inside], weights=fa[inside], minlength=ngroups)
    own = area_by_group <= cone_by_group  # cap the group by itself, reversed
    rev = inside & own[np.maximum(face_group, 0)]
    cone_edges = ~own[fgroup]
    Tr = v[faces[rev][:, ::-1]]
    Tk = np.stack([apex[piece[cone_edges]], v[b[cone_edges]], v[a[cone_edges]]], axis=1)
    T = np.concatenate([Tr, Tk])
    owner = np.empty(len(a), dtype=np.int64)
    rank = np.cumsum(rev) - 1  # index of a reversed face among the cap's triangles
    owner[~cone_edges] = rank[face_of_edge[~cone_edges]]
    owner[cone_edges] = len(Tr) + np.arange(int(cone_edges.sum()))
    E = np.stack([v[a], v[b]], axis=1)
    return Cap(T, E, owner, rev)


def _groups(faces, n, a, b):
    """Pieces of the chain (connected edges), a face holding each chain
    edge, and each face's group (-1 for a closed face component): the face
    components joined by the pieces they share; and the number of labels."""
    from ..scale.graphs import components

    m = len(faces)
    e0 = faces.reshape(-1)
    e1 = faces[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(e0, e1) * np.int64(n) + np.maximum(e0, e1)
    order = np.argsort(key, kind="stable")
    sk = key[order]
    ck = np.minimum(a, b) * np.int64(n) + np.maximum(a, b)
    face_of_edge = order[np.searchsorted(sk, ck)] // 3
    # face components through shared edges
    same = sk[1:] == sk[:-1]
    fo = order // 3
    nc, comp = components(m, fo[:-1][same], fo[1:][same])
    # chain pieces
    used, inv = np.unique(np.concatenate([a, b]), return_inverse=True)
    k = len(used)
    _, lab = components(k, inv[: len(a)], inv[len(a):])
    piece = lab[inv[: len(a)]]
    # groups: components and pieces, joined where a piece bounds a component
    npc = int(piece.max()) + 1
    ngroups, glab = components(nc + npc, comp[face_of_edge], nc + piece)
    bounded = np.zeros(nc, dtype=bool)
    bounded[comp[face_of_edge]] = True
    return piece, face_of_edge, np.where(bounded[comp], glab[:nc][comp], -1), ngroups


def _cones(v, a, b, piece):
    """The apex of each piece's cone and the area of each chain edge's cone
    triangle."""
    npc = int(piece.max()) + 1
    pts_a = v[a]
    cnt = np.bincount(piece, minlength=npc).astype(np.float64)
    centroid = np.stack([np.bincount(piece, weights=pts_a[:, d], minlength=npc) for d in range(3)], 1) / cnt[:, None]
    lo = np.full((npc, 3), np.inf)
    hi = np.full((npc, 3), -np.inf)
    np.minimum.at(lo, piece, pts_a)
    np.maximum.at(hi, piece, pts_a)
    size = np.linalg.norm(hi - lo, axis=1)
    area = 0.5 * np.cross(v[a] - centroid[piece], v[b] - centroid[piece])
    normal = np.stack([np.bincount(piece, weights=area[:, d], minlength=npc) for d in range(3)], 1)
    nlen = np.linalg.norm(normal, axis=1)
    flat = nlen <= 1e-12 * size**2
    unit = np.where(flat[:, None], _GENERIC, normal / np.where(flat, 1.0, nlen)[:, None])
    apex = centroid + size[:, None] * (0.01 * unit + 0.001 * _GENERIC)
    tri = 0.5 * np.linalg.norm(np.cross(v[b] - apex[piece], v[a] - apex[piece]), axis=1)
    return apex, tri


# ---------------------------------------------------------------------------
# the rule R = round(w_C) on a box of the grid
# ---------------------------------------------------------------------------

@njit(cache=True, nogil=True)
def _decide_blocks(tops, rule, box, origin, pitch, theta, reach_factor, tol, T, nlen, E, elen, owner, lo, hi, child,
                   centre, rho, A, Mo, S, L, C, D, eo, flags, stop):
    """R on every centre of the blocks ``tops`` (rows ``i0, i1, j0, j1, k0,
    k1`` in grid coordinates), written into ``rule`` whose voxel (0, 0, 0)
    is grid voxel ``box``; centres left for M's own sum get
    :data:`TIE_PENDING`; blocks are modelled in lanes over all the cap's
    triangles (``C, D, eo``, :func:`isoflow.mesh.cap_lanes.lanes_arrays`)
    where ``C`` holds any, through the tree otherwise.  ``flags[0]`` is set where |R| would exceed
    :data:`MAX_R`; ``flags[1:]`` count blocks evaluated, single centres
    evaluated, retries with a tighter tree, hits, splits, near triangles
    and crossing triangles summed at centres, and centres summed exactly
    over the whole cap.  Returns early
    (work undone) once ``stop[0]`` is set."""
    blocks = np.empty((512, 6), dtype=np.int64)
    stack = np.empty(64, dtype=np.int64)
    near = np.empty(MAX_NEAR, dtype=np.int64)
    cross = np.empty(MAX_NEAR, dtype=np.int64)
    edges = np.empty((6 * MAX_NEAR, 2, 3))
    grad = np.empty(4)  # the gradient, and scratch for the derivative bound
    m = PAINT_LANES  # centres in lanes at once
    X, Y, Z, wl, gap, J = np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    Tn, ln = np.empty((MAX_NEAR, 3, 3)), np.empty(MAX_NEAR)
    Q, at = np.empty((3, QUEUE)), np.empty((QUEUE, 3), dtype=np.int64)  # centres for the exact sum
    nq = np.int64(0)  # not the literal 0: numba would compile the callees once more for it
    wq, gq = np.empty(QUEUE), np.empty(QUEUE)
    flat = C.shape[1] > 0
    ang, dets, keep = np.empty(C.shape[1]), np.empty(C.shape[1]), np.empty(C.shape[1], dtype=np.bool_)
    dtri, dedge = np.empty(C.shape[1]), np.empty(C.shape[1])
    for q in range(tops.shape[0]):
        if stop[0]:
            return
        for c in range(6):  # (element by element: an array assigned to a row compiles numba's message)
            blocks[0, c] = tops[q, c]
        nb = 1
        while nb:
            nb -= 1
            i0, i1, j0, j1, k0, k1 = (blocks[nb, 0], blocks[nb, 1], blocks[nb, 2], blocks[nb, 3],
                                      blocks[nb, 4], blocks[nb, 5])
            px = origin[0] + pitch * (0.5 * (i0 + i1))
            py = origin[1] + pitch * (0.5 * (j0 + j1))
            pz = origin[2] + pitch * (0.5 * (k0 + k1))
            di, dj, dk = i1 - i0 - 1, j1 - j0 - 1, k1 - k0 - 1
            h = 0.5 * pitch * math.sqrt(di * di + dj * dj + dk * dk)
            # near triangles: within the ball and a margin, so that the far part's edges keep away
            reach = h + max(reach_factor * h, 2 * pitch) if h > 0 else tol
            th = theta
            left = -1  # centres of the block still undecided (-1: the block is a hit)
            flags[1] += 1
            flags[2] += h == 0
            while True:
                if flat:
                    w, err, var, hess, status, nn, nc = evaluate_lanes(px, py, pz, h, reach, tol, T, nlen, E, owner,
                                                                       C, D, eo, near, cross, edges, grad, ang, dets,
                                                                       keep, dtri, dedge)
                else:
                    w, err, var, hess, status, nn, nc = evaluate(px, py, pz, h, reach, th, tol, T, nlen, E, elen,
                                                                 owner, lo, hi, child, centre, rho, A, Mo, S, L,
                                                                 stack, near, cross, edges, grad)
                if status == HIT:
                    flags[4] += 1
                    break
                rest = var + 0.5 * h * h * hess
                base = err + var + TIE_WINDING
                left = _paint(rule, box, i0, i1, j0, j1, k0, k1, w, grad, base + 0.5 * h * h * hess, base, 0.5 * hess,
                              px, py, pz, T, nlen, near, nn, cross, nc, origin, pitch, tol, flags, X, Y, Z, wl, gap, J,
                              Tn, ln)
                if left == 0 or th == 0 or rest > err:  # a tighter tree cannot help
                    break
                if h == 0 and err >= 0.25:
                    # a single centre whose remainder is hopeless (a cap of many layers that cancel,
                    # which the bound cannot see): the exact sum in lanes below, over many queued
                    # centres at once, costs less than the tree's walk over every triangle
                    break
                # a remainder far beyond the margin: straight to the exact sum
                th = th / 3.0 if th == theta and err < 0.25 else 0.0
                flags[3] += 1
            n = (i1 - i0) * (j1 - j0) * (k1 - k0)
            if left == 0:
                pass
            elif (left > 0 and h == 0 or n <= PAINT_LANES and (n if left < 0 else left) * T.shape[0] <= EXACT_PAIRS
                  or 0 < left <= n // 8 and left * T.shape[0] <= EXACT_PAIRS):
                every = left < 0 or left == n  # (a block the model could not paint holds no codes)
                if nq + (n if every else left) > QUEUE:
                    flags[0] |= exact_queue(rule, Q, at, nq, tol, T, nlen, wq, gq) < 0
                    flags[8] += nq
                    nq = np.int64(0)
                nq = queue_centres(rule, box, i0, i1, j0, j1, k0, k1, every, origin, pitch, Q, at, nq)
            elif h == 0:
                rule[i0 - box[0], j0 - box[1], k0 - box[2]] = TIE_PENDING
            elif left > 0 and (left * 4 <= n <= SMALL or left <= 8):
                for i in range(i0, i1):  # the undecided centres on their own
                    for j in range(j0, j1):
                        for k in range(k0, k1):
                            if rule[i - box[0], j - box[1], k - box[2]] == UNDECIDED:
                                blocks[nb, 0], blocks[nb, 1], blocks[nb, 2] = i, i + 1, j
                                blocks[nb, 3], blocks[nb, 4], blocks[nb, 5] = j + 1, k, k + 1
                                nb += 1
            else:
                flags[5] += 1
                nb = _push_children(blocks, nb, i0, i1, j0, j1, k0, k1)
            if stop[0]:
                return
    if nq:
        flags[0] |= exact_queue(rule, Q, at, nq, tol, T, nlen, wq, gq) < 0
        flags[8] += nq


@njit(cache=True, nogil=True)
def _push_children(blocks, nb, i0, i1, j0, j1, k0, k1):
    """The block cut at the middle of every axis longer than one."""
    mi, mj, mk = (i0 + i1) // 2, (j0 + j1) // 2, (k0 + k1) // 2
    for a in range(2):
        ia, ib = (i0, mi) if a == 0 else (mi, i1)
        if ia == ib:
            continue
        for b in range(2):
            ja, jb = (j0, mj) if b == 0 else (mj, j1)
            if ja == jb:
                continue
            for c in range(2):
                ka, kb = (k0, mk) if c == 0 else (mk, k1)
                if ka == kb:
                    continue
                blocks[nb, 0], blocks[nb, 1], blocks[nb, 2] = ia, ib, ja
                blocks[nb, 3], blocks[nb, 4], blocks[nb, 5] = jb, ka, kb
                nb += 1
    return nb


@njit(cache=True, nogil=True)
def _paint(rule, box, i0, i1, j0, j1, k0, k1, w, grad, bound, base, curv, qx, qy, qz, T, nlen, near, nn, cross, nc,
           origin, pitch, tol, flags, X, Y, Z, wl, gap, J, Tn, ln):
    """R on the block's centres p from the model at its centre q:
    ``round(w + grad . (p - q) + w_near(p) +- bound)`` (w_near summed over
    the near triangles at p), ``bound`` the model's error on the block and
    ``base + curv |p - q|^2`` at p (the first-order remainder grows as
    the square of the distance from q).  Centres where the interval holds a
    half-integer get :data:`UNDECIDED`, those on a near triangle
    :data:`TIE_PENDING`; returns how many are undecided.  A block of more
    than :data:`PAINT_ALL` centres stops at its first undecided one (it is
    split, and its children paint it again) and returns all of them."""
    n = (i1 - i0) * (j1 - j0) * (k1 - k0)
    slope = math.sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]) * 0.5 * pitch * math.sqrt(
        (i1 - i0 - 1) ** 2 + (j1 - j0 - 1) ** 2 + (k1 - k0 - 1) ** 2)
    ok = 2 * bound < 1 and abs(w) + slope < 1e6  # false for NaN or inf too
    if not ok:  # no centre can be decided
        if n <= 8:  # (the caller takes them one by one)
            rule[i0 - box[0]:i1 - box[0], j0 - box[1]:j1 - box[1], k0 - box[2]:k1 - box[2]] = UNDECIDED
        return n
    wq, spread = w, bound + slope
    if nc == 0 and nn:  # the near triangles too, if they keep off the block: the whole block at once
        wn, var, apart = near_range(T, near, nn, qx, qy, qz, 0.5 * pitch * math.sqrt(
            (i1 - i0 - 1) ** 2 + (j1 - j0 - 1) ** 2 + (k1 - k0 - 1) ** 2))
        wq, spread = (w + wn, spread + var) if apart else (w, math.inf)
    constant = nc == 0 and spread < 0.5 and math.floor(wq - spread + 0.5) == math.floor(wq + spread + 0.5)
    if not constant and nn + nc > NEAR_PAINT and n > max(SMALL, PAINT_LANES):  # cheaper split: the children have fewer
        return n
    if constant:  # one R for the block
        r = math.floor(wq + 0.5)
        if r > MAX_R or r < -MAX_R:
            flags[0] = 1
        else:
            rule[i0 - box[0]:i1 - box[0], j0 - box[1]:j1 - box[1], k0 - box[2]:k1 - box[2]] = r
        return 0
    # the near triangles summed at every centre, in lanes
    flags[6] += n * nn
    flags[7] += n * nc
    left = paint_lanes(rule, box, i0, i1, j0, j1, k0, k1, w, grad, base, curv, qx, qy, qz, T, nlen, near, nn, cross,
                       nc, origin, pitch, tol, X, Y, Z, wl, gap, J, Tn, ln, n > PAINT_ALL)
    flags[0] |= left < 0
    return max(left, 0)


def _decided_ties(Tm: np.ndarray, nlen: np.ndarray, P: np.ndarray) -> np.ndarray:
    """FORCE_IN or FORCE_OUT for the centres whose tie points are ``P``
    ((m, 3)) by the mesh's own winding number there, summed in pieces of
    about 4M solid angles (so that a stop is heard between them)."""
    X, Y, Z = (np.ascontiguousarray(P[:, d]) for d in range(3))
    w, gap = np.empty(len(P)), np.empty(len(P))
    step = max(1, (1 << 22) // max(1, len(Tm)))
    for a in range(0, len(P), step):
        if STOP[0]:
            raise Stopped
        b = min(len(P), a + step)
        winding_lanes(Tm, nlen, X[a:b], Y[a:b], Z[a:b], b - a, 0.0, w[a:b], gap[a:b])
    return np.where(np.abs(w) > 0.5, FORCE_IN, FORCE_OUT).astype(np.int8)


def top_blocks(box) -> np.ndarray:
    """The coarsest blocks over ``box = (i0, i1, j0, j1, k0, k1)``: about
    :data:`TOP_BLOCKS` per axis, a power of two voxels wide."""
    i0, i1, j0, j1, k0, k1 = (int(x) for x in box)
    ext = max(i1 - i0, j1 - j0, k1 - k0)
    s = 1 << max(0, math.ceil(math.log2(max(1, ext / TOP_BLOCKS))))
    edges = [np.append(np.arange(lo, hi, s), hi) for lo, hi in ((i0, i1), (j0, j1), (k0, k1))]
    gi, gj, gk = np.meshgrid(np.arange(len(edges[0]) - 1), np.arange(len(edges[1]) - 1),
                             np.arange(len(edges[2]) - 1), indexing="ij")
    gi, gj, gk = gi.ravel(), gj.ravel(), gk.ravel()
    return np.stack([edges[0][gi], edges[0][gi + 1], edges[1][gj], edges[1][gj + 1],
                     edges[2][gk], edges[2][gk + 1]], axis=1).astype(np.int64)


def winding_rule(tree: CapTree, Tm, origin, pitch, box, threads: int = 1, progress=None, counts=None):
    """``R = round(w_C)`` for every centre of ``box = (i0, i1, j0, j1, k0, k1)``
    as ``(array, (i0, j0, k0))`` (int8, with the codes FORCE_IN / FORCE_OUT
    where the centre is so close to the cap, or its w_C to a half-integer,
    that the mesh's own winding number decided), or None where the cap is
    empty.

    ``tree`` holds the cap's triangles and chain, ``Tm`` the mesh's
    triangles (for the ties), all in the frame of ``origin`` and ``pitch``.
    ``progress(done, total)`` is called after each piece of blocks;
    ``counts`` (int64 (8,)), if given, is incremented with the work done
    (see :func:`_decide_blocks`).
    """
    if len(tree.T) == 0:
        return None
    origin = np.asarray(origin, dtype=np.float64)
    i0, i1, j0, j1, k0, k1 = (int(x) for x in box)
    rule = np.zeros((i1 - i0, j1 - j0, k1 - k0), dtype=np.int8)
    tops = top_blocks(box)
    # pieces in a scattered order: progress (and the time left) grows evenly
    tops = tops[np.random.default_rng(0).permutation(len(tops))]
    # a piece holds at least a queue's worth of centres: the exact sums run in lanes over a piece's
    # queued centres at once, and a short queue wastes the lanes
    voxels = (i1 - i0) * (j1 - j0) * (k1 - k0)
    pieces = np.array_split(tops, max(1, min(PIECES, len(tops), voxels // QUEUE)))
    flags = np.zeros(9, dtype=np.int64)
    corner = np.array([i0, j0, k0], dtype=np.int64)
    flat = lanes_arrays(tree) if len(tree.T) <= FLAT_MAX else (np.zeros((9, 0)), np.zeros((6, 0)),
                                                                 np.zeros(0, dtype=np.int64))
    args = (rule, corner, origin, float(pitch), THETA, REACH, TIE_PITCHES * pitch) + tree.arrays() + flat + (flags, STOP)
    Tm = np.ascontiguousarray(Tm, dtype=np.float64)
    nlen = np.ones(len(Tm))  # (gap, the distance to the planes, is not read)

    def piece(n: int) -> None:
        # a piece's ties are its own work: on a mesh whose faces hold many
        # centres they cost as much as its blocks, and progress counts them
        _decide_blocks(pieces[n], *args)
        # the piece's ties summed at once: the sum runs in lanes over the points, and a top
        # block may hold a single tie
        ties = []
        for top in pieces[n]:
            part = rule[top[0] - i0:top[1] - i0, top[2] - j0:top[3] - j0, top[4] - k0:top[5] - k0]
            ties.append(np.argwhere(part == TIE_PENDING) + top[0::2])
        at = np.concatenate(ties)
        if len(at):
            rule[tuple((at - corner).T)] = _decided_ties(Tm, nlen, origin + pitch * (at + 0.5 + TIE_STEP))

    run_pieces(piece, len(pieces), threads=threads, progress=progress)
    if counts is not None:
        counts += flags[1:]
    if flags[0]:
        raise IsoflowError(f"voxelize: the cap's winding number exceeds {MAX_R} (more than {MAX_R} "
                           "overlapping layers of boundary): not supported")
    return rule, (i0, j0, k0)
