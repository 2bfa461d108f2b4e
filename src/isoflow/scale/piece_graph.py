"""Per label, the components of the graph of pieces (numba): the label's
own, and those of everything else, without a pass over the voxels.

The nodes are the pieces of :mod:`isoflow.scale.pieces` (node 0 the
region outside the array), each with its label and bounding box; an edge
joins two pieces that touch, with how closely (1 face, 2 edge, 3 vertex).
Under an adjacency that joins up to ``kind``, the components of a label
are those of its pieces over the edges of at most that kind, and the
components of the rest of the image (every other label and the outside)
are those of the graph with the label's pieces taken out.

Those are found from the label's neighbours outward, one label at a time,
and the walk stops early: a piece of the rest that reaches the label's
bounding box (or lies beyond it) is joined to the outside by a straight
line of voxels that leaves the box, so its component is the outside's.
Only the components enclosed by the label are walked whole, and they lie
inside its box; a label's cost is its neighbours and what it encloses,
whatever the number of labels.
"""

from __future__ import annotations

import numpy as np

from .jit import njit


@njit(cache=True, nogil=True, inline="always")
def _open(piece, plo, phi, blo, bhi):
    """Whether a piece of the rest reaches the label's box [blo, bhi]
    (inclusive voxel ranges), or is the outside."""
    if piece == 0:
        return True
    for d in range(3):
        if plo[piece, d] <= blo[d] or phi[piece, d] >= bhi[d]:
            return True
    return False


@njit(cache=True, nogil=True)
def _root(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=True, nogil=True)
def _own_components(own, label, piece_label, local, parent, adj_start, adj_to, adj_kind, kind):
    """Components of the label's pieces ``own`` over edges of at most
    ``kind``: ``parent`` (local roots, one per piece of ``own``; ``local``
    gives a piece's place in ``own``). Returns their number."""
    m = len(own)
    for t in range(m):
        parent[t] = t
        local[own[t]] = t
    count = m
    for t in range(m):
        p = own[t]
        for e in range(adj_start[p], adj_start[p + 1]):
            q = adj_to[e]
            if adj_kind[e] <= kind and piece_label[q] == label:
                ra, rb = _root(parent, t), _root(parent, local[q])
                if ra != rb:
                    parent[max(ra, rb)] = min(ra, rb)
                    count -= 1
    for t in range(m):
        parent[t] = _root(parent, t)
    return count


@njit(cache=True, nogil=True)
def _rest_components(own, label, piece_label, plo, phi, blo, bhi, adj_start, adj_to, adj_kind, kind, mark, stamp,
                     comp, queue):
    """Components of the rest of the image over edges of at most ``kind``
    that touch the label's pieces ``own`` by a face: ``comp[piece]`` (where
    ``stamp[piece] == mark``) is 0 for the outside's component and 1..m for
    the enclosed ones. Returns m."""
    enclosed = 0
    for p in own:
        for e in range(adj_start[p], adj_start[p + 1]):
            seed = adj_to[e]
            if adj_kind[e] != 1 or piece_label[seed] == label or stamp[seed] == mark:
                continue
            stamp[seed] = mark
            comp[seed] = -1
            queue[0] = seed
            head, tail = 0, 1
            outside = _open(seed, plo, phi, blo, bhi)
            while head < tail and not outside:
                x = queue[head]
                head += 1
                for f in range(adj_start[x], adj_start[x + 1]):
                    y = adj_to[f]
                    if adj_kind[f] > kind or piece_label[y] == label:
                        continue
                    if stamp[y] == mark:
                        if comp[y] == 0:  # a piece of the outside's component, walked before
                            outside = True
                            break
                        continue
                    stamp[y] = mark
                    comp[y] = -1
                    queue[tail] = y
                    tail += 1
                    if _open(y, plo, phi, blo, bhi):
                        outside = True
                        break
            if not outside:
                enclosed += 1
            for t in range(tail):
                comp[queue[t]] = 0 if outside else enclosed
    return enclosed


@njit(cache=True, nogil=True)
def label_topology(rows, lab_start, lab_pieces, piece_label, plo, phi, adj_start, adj_to, adj_kind, sh_start, sh_to,
                   sh_n, sh_q, obj_kind, b0_kind, bg_kind, cc_kind):
    """Per label index in ``rows``: b0 (components under ``b0_kind``), b2
    (enclosed components of the rest under ``cc_kind``), and the closed
    surfaces of its boundary mesh: the pairs (component of the label under
    ``obj_kind``, component of the rest under ``bg_kind``) that its sheets
    join, each with its mesh vertices (sheets) and faces.

    ``lab_start``/``lab_pieces``: each label's pieces; ``adj_*``: the
    edges, both ways; ``sh_*``: per object piece, the background pieces of
    its sheets with their sheet and quarter counts. Returns ``b0``, ``b2``
    and the surfaces as ``row`` (index into ``rows``), ``chi``, ``faces``,
    each label's in the report's order (most faces first, then chi).
    """
    npieces = len(piece_label)
    local = np.zeros(npieces, np.int64)
    stamp = np.zeros(npieces, np.int64)
    comp = np.zeros(npieces, np.int64)
    stamp2 = np.zeros(npieces, np.int64)
    comp2 = np.zeros(npieces, np.int64)
    queue = np.zeros(npieces, np.int64)
    b0 = np.zeros(len(rows), np.int64)
    b2 = np.zeros(len(rows), np.int64)
    total = 0
    for r in range(len(rows)):
        for p in lab_pieces[lab_start[rows[r]]:lab_start[rows[r] + 1]]:
            total += sh_start[p + 1] - sh_start[p]
    srow = np.zeros(total, np.int64)
    schi = np.zeros(total, np.int64)
    sfaces = np.zeros(total, np.int64)
    nsurf = 0
    parent = np.zeros(npieces, np.int64)
    parent0 = np.zeros(npieces, np.int64)
    for r in range(len(rows)):
        label = rows[r]
        own = lab_pieces[lab_start[label]:lab_start[label + 1]]
        if len(own) == 0:
            continue
        blo = plo[own[0]].copy()
        bhi = phi[own[0]].copy()
        for p in own:
            for d in range(3):
                blo[d] = min(blo[d], plo[p, d])
                bhi[d] = max(bhi[d], phi[p, d])
        b0[r] = _own_components(own, label, piece_label, local, parent0, adj_start, adj_to, adj_kind, b0_kind)
        _own_components(own, label, piece_label, local, parent, adj_start, adj_to, adj_kind, obj_kind)
        mark = r + 1
        m = _rest_components(own, label, piece_label, plo, phi, blo, bhi, adj_start, adj_to, adj_kind, bg_kind,
                             mark, stamp, comp, queue)
        if cc_kind == bg_kind:
            b2[r] = m
        else:
            b2[r] = _rest_components(own, label, piece_label, plo, phi, blo, bhi, adj_start, adj_to, adj_kind,
                                     cc_kind, mark, stamp2, comp2, queue)
        # the surfaces: sheets summed per (own component, rest component)
        n = 0
        for t in range(len(own)):
            n += sh_start[own[t] + 1] - sh_start[own[t]]
        key = np.empty(n, np.int64)
        verts = np.empty(n, np.int64)
        quarters = np.empty(n, np.int64)
        n = 0
        for t in range(len(own)):
            p = own[t]
            for e in range(sh_start[p], sh_start[p + 1]):
                key[n] = parent[t] * (m + 1) + comp[sh_to[e]]
                verts[n] = sh_n[e]
                quarters[n] = sh_q[e]
                n += 1
        order = np.argsort(key)
        first = nsurf
        for t in range(n):
            e = order[t]
            if t == 0 or key[e] != key[order[t - 1]]:
                srow[nsurf] = r
                schi[nsurf] = 0
                sfaces[nsurf] = 0
                nsurf += 1
            schi[nsurf - 1] += verts[e]
            sfaces[nsurf - 1] += quarters[e]
        for s in range(first, nsurf):
            sfaces[s] //= 4
            schi[s] -= sfaces[s]
        # the report's order: most faces first, ties by chi
        part = np.arange(first, nsurf)
        by_chi = part[np.argsort(schi[first:nsurf], kind="mergesort")]
        ordered = by_chi[np.argsort(-sfaces[by_chi], kind="mergesort")]
        chi_sorted = schi[ordered].copy()
        faces_sorted = sfaces[ordered].copy()
        schi[first:nsurf] = chi_sorted
        sfaces[first:nsurf] = faces_sorted
    return b0, b2, srow[:nsurf], schi[:nsurf], sfaces[:nsurf]
