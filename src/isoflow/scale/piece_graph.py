"""Per label, the components of the graph of pieces (numba): the label's
own, and those of everything else, without a pass over the voxels.

The nodes are the pieces of :mod:`isoflow.scale.pieces` (node 0 the
region outside the array), each with its label and bounding box; an edge
joins two pieces that touch, with how closely (1 face, 2 edge, 3 vertex),
and holds, each way, the sheets of the boundary mesh of the one against
the other, from which a label's surfaces are summed.
Under an adjacency that joins up to ``kind``, the components of a label
are those of its pieces over the edges of at most that kind, and the
components of the rest of the image (every other label and the outside)
are those of the graph with the label's pieces taken out.

Those are found from the label's neighbours outward, one component of
the label at a time, and the walk stops early. The components of a label
and of the rest form a tree by adjacency, each enclosed by its parent
(Kong and Rosenfeld's adjacency tree: the label's components under 6 and
the rest's under 18 or 26, or 18 or 26 and 6, the pairs the mesh and the
Betti numbers take); so a component of the rest that touches a
component K of the label is K's parent, or K's child and then strictly
inside K's bounding box. A walk from K that reaches K's box (or lies
beyond it) has found K's parent, whatever lies beyond; only K's children
are walked whole, and they lie inside its box. Each enclosed component
of the rest is the child of one component of the label, so counted once.
A label's cost is its neighbours and what it encloses, whatever the
number of labels and wherever its components lie: a label scattered
over the whole image (noise) has components of a voxel or two, whose
neighbours all reach their boxes. Most labels of a map of many small
ones are walked not at all: a label's components over faces are its
pieces (a piece is face-connected), and where every piece touching one
by a face reaches that component's box, the label encloses nothing and
each component has one surface: its sheets summed on the pass that
looked at those pieces.
"""

from __future__ import annotations

import numpy as np

from .jit import njit
from .memory import check_fits, mapped
from .ticks import Ticks, silent


@njit(cache=True, nogil=True, inline="always")
def _open(piece, plo, phi, blo, bhi):
    """Whether a piece of the rest reaches the box [blo, bhi] of a
    component of the label (inclusive voxel ranges), or is the outside."""
    if piece == 0:
        return True
    for d in range(3):
        if plo[piece, d] <= blo[d] or phi[piece, d] >= bhi[d]:
            return True
    return False


@njit(cache=True, nogil=True, inline="always")
def _root(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=True, nogil=True, _nrt=False)
def _own_components(own, label, piece_label, local, parent, adj_start, adj_to, adj_kind, kind):
    """Components of the label's pieces ``own`` over edges of at most
    ``kind``: ``parent`` (local roots, one per piece of ``own``; ``local``
    gives a piece's place in ``own``). Returns their number.

    Called twice by :func:`_own_parts` where the kinds differ, so
    compiled once on its own rather than inline at both calls (a shorter
    first compile, the same speed); without reference counting, as its
    caller."""
    m = len(own)
    for t in range(m):
        parent[t] = t
    if kind == 1:  # pieces are face-connected: none touches another of its label by a face
        return m
    for t in range(m):
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


@njit(cache=True, nogil=True, inline="always")
def _depth(piece, plo, phi, blo, bhi):
    """How far a piece of the rest lies inside the box of a component of
    the label: the fewest voxels from its box to a face of that one (at
    least 1 for a piece that is not open, :func:`_open`)."""
    depth = plo[piece, 0] - blo[0]
    for d in range(3):
        depth = min(depth, plo[piece, d] - blo[d], bhi[d] - phi[piece, d])
    return depth


@njit(cache=True, nogil=True, inline="always")
def _push(heap, hkey, n, value, key):
    """Add ``value`` with ``key`` to the binary heap of ``n`` entries
    (least key on top); returns the new size."""
    i = n
    while i > 0:
        up = (i - 1) >> 1
        if hkey[up] <= key:
            break
        heap[i], hkey[i] = heap[up], hkey[up]
        i = up
    heap[i], hkey[i] = value, key
    return n + 1


@njit(cache=True, nogil=True, inline="always")
def _pop(heap, hkey, n):
    """Take the entry of least key off the heap of ``n`` entries: returns
    it and the new size."""
    top = heap[0]
    n -= 1
    value, key = heap[n], hkey[n]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= n:
            break
        if child + 1 < n and hkey[child + 1] < hkey[child]:
            child += 1
        if hkey[child] >= key:
            break
        heap[i], hkey[i] = heap[child], hkey[child]
        i = child
    if n > 0:
        heap[i], hkey[i] = value, key
    return top, n


@njit(cache=True, nogil=True, _nrt=False)
def _rest_components(own, label, piece_label, plo, phi, blo, bhi, adj_start, adj_to, adj_kind, kind, mark, stamp,
                     comp, queue, heap, hkey):
    """Components of the rest of the image over edges of at most ``kind``
    that touch the pieces ``own`` (one component of the label, its box
    [blo, bhi]) by a face: ``comp[piece]`` (where ``stamp[piece] ==
    mark``) is 0 for the component's parent and 1..m for its children,
    those it encloses. Returns m. Compiled on its own, as
    :func:`_own_components`.

    Each walk stops at the first piece that reaches the box (or a piece of
    the parent walked before), and goes nearest the box's faces first
    (:func:`_depth`, a heap): the answer, parent or child, is the walk's
    whatever its order, and a component the size of the image has its
    box's faces only as far as the image's, where a walk in rings around
    its start would cross most of the rest. ``queue`` lists the pieces a
    walk reached."""
    enclosed = 0
    for p in own:
        for e in range(adj_start[p], adj_start[p + 1]):
            seed = adj_to[e]
            if adj_kind[e] != 1 or piece_label[seed] == label or stamp[seed] == mark:
                continue
            stamp[seed] = mark
            comp[seed] = -1
            queue[0] = seed
            tail = 1
            outside = _open(seed, plo, phi, blo, bhi)
            waiting = 0 if outside else _push(heap, hkey, 0, seed, _depth(seed, plo, phi, blo, bhi))
            while waiting > 0 and not outside:
                x, waiting = _pop(heap, hkey, waiting)
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
                    waiting = _push(heap, hkey, waiting, y, _depth(y, plo, phi, blo, bhi))
            if not outside:
                enclosed += 1
            for t in range(tail):
                comp[queue[t]] = 0 if outside else enclosed
    return enclosed


@njit(cache=True, nogil=True, inline="always")
def _group(parent, m, start, fill, members, own):
    """The label's pieces ``own`` grouped by their component (``parent``:
    each piece's root among ``0 .. m - 1``): component ``R``'s pieces are
    ``members[start[R]:start[R + 1]]`` (empty where ``R`` is no root)."""
    for t in range(m + 1):
        start[t] = 0
    for t in range(m):
        start[parent[t] + 1] += 1
    for t in range(m):
        start[t + 1] += start[t]
        fill[t] = start[t]
    for t in range(m):
        members[fill[parent[t]]] = own[t]
        fill[parent[t]] += 1


@njit(cache=True, nogil=True, inline="always")
def _box(part, plo, phi, blo, bhi):
    """The bounding box [blo, bhi] of the pieces ``part`` (inclusive voxel
    ranges)."""
    for d in range(3):
        blo[d] = plo[part[0], d]
        bhi[d] = phi[part[0], d]
    for p in part:
        for d in range(3):
            blo[d] = min(blo[d], plo[p, d])
            bhi[d] = max(bhi[d], phi[p, d])


@njit(cache=True, nogil=True, inline="always")
def _all_open(members, start, m, label, piece_label, plo, phi, blo, bhi, adj_start, adj_to, adj_kind, adj_n, adj_q):
    """Whether every piece of the rest that touches one of the label's
    components (``members[start[R]:start[R + 1]]``) by a face reaches that
    component's box: then every component of the rest that
    :func:`_rest_components` would walk from it is its parent, under any
    kind of edge, and the label encloses nothing. Returns that, and where
    it holds, the sums of the label's sheets and quarters (read on the
    same pass over its edges)."""
    sheets = np.int64(0)
    quarters = np.int64(0)
    for R in range(m):
        if start[R] == start[R + 1]:
            continue
        part = members[start[R]:start[R + 1]]
        _box(part, plo, phi, blo, bhi)
        for p in part:
            for e in range(adj_start[p], adj_start[p + 1]):
                q = adj_to[e]
                if adj_kind[e] == 1 and piece_label[q] != label and not _open(q, plo, phi, blo, bhi):
                    return False, sheets, quarters
                sheets += adj_n[e]
                quarters += adj_q[e]
    return True, sheets, quarters


@njit(cache=True, nogil=True, inline="always")
def _sort_by(order, n, first, second):
    """Sort ``order[:n]`` by ``first`` then ``second`` (insertion sort: a
    label has few entries), stable."""
    for t in range(1, n):
        e = order[t]
        u = t
        while u > 0 and (first[order[u - 1]] > first[e] or (
                first[order[u - 1]] == first[e] and second[order[u - 1]] > second[e])):
            order[u] = order[u - 1]
            u -= 1
        order[u] = e


@njit(cache=True, nogil=True)
def _sift(order, start, end, key):
    root = start
    while 2 * root + 1 < end:
        child = 2 * root + 1
        if child + 1 < end and key[order[child]] < key[order[child + 1]]:
            child += 1
        if key[order[root]] >= key[order[child]]:
            return
        order[root], order[child] = order[child], order[root]
        root = child


@njit(cache=True, nogil=True)
def _heap_sort(order, n, key):
    """Sort ``order[:n]`` by ``key`` in place (a label with many entries)."""
    for start in range(n // 2 - 1, -1, -1):
        _sift(order, start, n, key)
    for end in range(n - 1, 0, -1):
        order[0], order[end] = order[end], order[0]
        _sift(order, np.int64(0), end, key)  # not the literal 0: numba would compile _sift once more for it


@njit(cache=True, nogil=True, inline="always")
def _surface_keys(part, root, comp, walked, adj_start, adj_to, adj_n, adj_q, key, verts, quarters, order, n):
    """The sheets of one component of the label (its pieces ``part``,
    ``root`` its number), each keyed by the pair (this component, the
    component of the rest beyond it: ``comp`` where ``walked``, else the
    parent's, 0), appended at ``n`` for :func:`_surfaces`. Returns the
    new ``n``."""
    for p in part:
        for e in range(adj_start[p], adj_start[p + 1]):
            if adj_n[e] == 0:  # a neighbour that none of its sheets reach
                continue
            key[n] = (np.int64(root) << 32) + (comp[adj_to[e]] if walked else 0)
            verts[n] = adj_n[e]
            quarters[n] = adj_q[e]
            order[n] = n
            n += 1
    return n


@njit(cache=True, nogil=True, inline="always")
def _surfaces(n, key, verts, quarters, order, r, srow, schi, sfaces, nsurf):
    """The label's surfaces from its ``n`` sheets keyed by
    :func:`_surface_keys`: summed per key, appended at ``nsurf`` in the
    report's order (most faces first, then chi). Returns the new
    ``nsurf``."""
    ordered = True  # the keys come grouped by component, each in order where it encloses nothing: no sort then
    for t in range(1, n):
        if key[t] < key[t - 1]:
            ordered = False
            break
    if not ordered and n > 32:
        _heap_sort(order, n, key)
    elif not ordered:
        _sort_by(order, n, key, key)
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
        key[s - first] = -sfaces[s]
        verts[s - first] = schi[s]
        order[s - first] = s - first
    m = nsurf - first
    if m > 32:
        # most faces first, then chi, as one key (faces and |chi| below 2^31): a label of thousands of surfaces of
        # many sizes (noise of a few labels) would make the insertion sort's moves quadratic; surfaces of equal
        # faces and chi are alike, so the order among them is no matter
        for t in range(m):
            key[t] = (key[t] << 32) + (verts[t] + (1 << 31))
        _heap_sort(order, np.int64(m), key)
        for t in range(m):
            sfaces[first + t] = -(key[order[t]] >> 32)
            schi[first + t] = (key[order[t]] & 0xFFFFFFFF) - (1 << 31)
        return nsurf
    _sort_by(order, m, key, verts)
    for t in range(m):
        sfaces[first + t] = -key[order[t]]
        schi[first + t] = verts[order[t]]
    return nsurf


@njit(cache=True, nogil=True, inline="always")
def _one_surface(sheets, quarters, r, srow, schi, sfaces, nsurf):
    """:func:`_surfaces` where the label's ``sheets`` (with their
    ``quarters``) all join one pair of components: their sums make one
    surface, without keys and their sort."""
    if sheets == 0:
        return nsurf
    srow[nsurf] = r
    sfaces[nsurf] = quarters // 4
    schi[nsurf] = sheets - quarters // 4
    return nsurf + 1


@njit(cache=True, nogil=True, inline="always")
def _own_parts(own, label, piece_label, local, parent, parent0, adj_start, adj_to, adj_kind, obj_kind, b0_kind):
    """The label's components under ``b0_kind`` (in ``parent0``) and under
    ``obj_kind`` (in ``parent``, or ``parent0`` where the kinds agree):
    their numbers."""
    if len(own) == 1:  # most labels of a map of many small ones: one piece, no edge to look at
        parent[0] = parent0[0] = 0
        return 1, 1
    b0 = _own_components(own, label, piece_label, local, parent0, adj_start, adj_to, adj_kind, b0_kind)
    if obj_kind == b0_kind:
        return b0, b0
    return b0, _own_components(own, label, piece_label, local, parent, adj_start, adj_to, adj_kind, obj_kind)


#: the walks' stamps are int32: past this many walks on one thread they
#: start again from 1 on cleared stamps (read when the walks start)
MOST_WALKS = 2**31 - 2


@njit(cache=True, nogil=True, inline="always")
def _next_walk(walk, most, stamp, stamp2):
    """The stamp of the next walk: ``walk + 1``, or 1 on cleared stamps
    past ``most`` walks (:data:`MOST_WALKS`, where the int32 stamps would
    wrap: an image of billions of pieces)."""
    if walk < most:
        return walk + 1
    stamp[:] = 0
    stamp2[:] = 0
    return 1


@njit(cache=True, nogil=True, _nrt=False)
def _label_loop(rows, lab_start, lab_pieces, piece_label, plo, phi, adj_start, adj_to, adj_kind, adj_n, adj_q,
                obj_kind, b0_kind, bg_kind, cc_kind, local, stamp, comp, stamp2, comp2, queue, heap, hkey, parent,
                parent0, start, fill, members, blo, bhi, key, verts, quarters, order, b0, b2, srow, schi, sfaces,
                most_walks, done, stop):
    """The loop of :func:`label_topology` over its rows, on scratch arrays
    (compiled without reference counting: nothing is allocated here).
    Returns the number of surfaces. ``done[0]``: the rows done so far (for
    a progress bar); it returns early, its rows unfinished, once
    ``stop[0]`` is set (a signal: :data:`isoflow.scale.cancel.STOP`).

    The rest's components are walked from each of the label's components
    in turn, against that component's box; each walk's stamps are its
    own (``walk`` counts them), since one piece of the rest can lie in one
    component's parent and in another's child."""
    nsurf = 0
    walk = 0
    for r in range(len(rows)):
        done[0] = r
        if stop[0]:
            return nsurf
        label = rows[r]
        own = lab_pieces[lab_start[label]:lab_start[label + 1]]
        m = len(own)
        if m == 0:
            continue
        joined = parent if obj_kind != b0_kind else parent0  # the same components: found once
        b0[r], parts = _own_parts(own, label, piece_label, local, parent, parent0, adj_start, adj_to, adj_kind,
                                  obj_kind, b0_kind)
        _group(joined, m, start, fill, members, own)
        is_open, sheet_sum, quarter_sum = _all_open(members, start, m, label, piece_label, plo, phi, blo, bhi,
                                                    adj_start, adj_to, adj_kind, adj_n, adj_q)
        if is_open and parts == 1:  # one component, nothing enclosed: every sheet is on one surface
            nsurf = _one_surface(sheet_sum, quarter_sum, r, srow, schi, sfaces, nsurf)
            b2[r] = 0
            continue
        enclosed = 0
        n = np.int64(0)
        for R in range(m):
            if start[R] == start[R + 1]:
                continue
            part = members[start[R]:start[R + 1]]
            children = 0
            if not is_open:
                _box(part, plo, phi, blo, bhi)
                walk = _next_walk(walk, most_walks, stamp, stamp2)
                children = _rest_components(part, label, piece_label, plo, phi, blo, bhi, adj_start, adj_to,
                                            adj_kind, bg_kind, walk, stamp, comp, queue, heap, hkey)
                enclosed += children
            n = _surface_keys(part, R, comp, children > 0, adj_start, adj_to, adj_n, adj_q, key, verts, quarters,
                              order, n)
        nsurf = _surfaces(n, key, verts, quarters, order, r, srow, schi, sfaces, nsurf)
        if cc_kind == bg_kind or enclosed == 0:
            # the rest's components over edges up to cc_kind (>= bg_kind) are unions of those up to bg_kind:
            # where each of these reaches the outside, so does each of those
            b2[r] = enclosed
            continue
        _group(parent0, m, start, fill, members, own)  # the components of b0, each the parent of those it encloses
        b2[r] = 0
        for R in range(m):
            if start[R] < start[R + 1]:
                part = members[start[R]:start[R + 1]]
                _box(part, plo, phi, blo, bhi)
                walk = _next_walk(walk, most_walks, stamp, stamp2)
                b2[r] += _rest_components(part, label, piece_label, plo, phi, blo, bhi, adj_start, adj_to, adj_kind,
                                          cc_kind, walk, stamp2, comp2, queue, heap, hkey)
    return nsurf


#: bytes per edge of the graph, each way (the piece it leads to, how they
#: touch, the sheets and quarters of faces over it)
GRAPH_EDGE_BYTES = 4 + 1 + 4 + 4
#: bytes per piece of a thread's scratch in :func:`label_topology` (a
#: piece's place among its label's, two stamps, two components, the walk's
#: pieces, its heap and their keys)
TOPOLOGY_BYTES = 8 * 4
#: and per piece of the label of most pieces (its components twice, their
#: pieces grouped: where each group starts, where it is filled, the pieces)
OWN_BYTES = 4 + 4 + 4 + 4 + 8


def label_topology(rows, lab_start, lab_pieces, piece_label, plo, phi, adj_start, adj_to, adj_kind, adj_n, adj_q,
                   obj_kind, b0_kind, bg_kind, cc_kind, ticks: Ticks | None = None) -> tuple[np.ndarray, ...]:
    """Per label index in ``rows``: b0 (components under ``b0_kind``), b2
    (enclosed components of the rest under ``cc_kind``), and the closed
    surfaces of its boundary mesh: the pairs (component of the label under
    ``obj_kind``, component of the rest under ``bg_kind``) that its sheets
    join, each with its mesh vertices (sheets) and faces.

    ``lab_start``/``lab_pieces``: each label's pieces; ``adj_*``: the
    edges, both ways, each with the sheets and quarters of its first piece
    as the object and its second as the background (:func:`pair_graph`).
    Returns ``b0``, ``b2``
    and the surfaces as ``row`` (index into ``rows``), ``chi``, ``faces``,
    each label's in the report's order (most faces first, then chi).
    ``cc_kind`` joins at least what ``bg_kind`` does (the rest's components
    under it are unions of those under ``bg_kind``), as every
    connectivity's does.

    The labels are independent: the rows are cut into runs of about equal
    work (pieces and edges), each walked on a thread of its own
    with scratch of its own (:data:`TOPOLOGY_BYTES` per piece, :data:`OWN_BYTES`
    per piece of the label of most pieces). ``ticks``: the stage
    ``"walks"`` of the progress, counted in labels, and where the walks
    stop on a signal.
    """
    from .cancel import STOP
    from .compiled import run, thread_count

    rows = np.asarray(rows, np.int64)
    npieces = len(piece_label)
    sizes = np.diff(lab_start)
    per_label = np.add.reduceat(np.diff(adj_start)[lab_pieces], lab_start[:-1]) if len(lab_pieces) else np.zeros(0)
    per_label = np.where(sizes > 0, per_label, 0)
    work = np.cumsum(per_label[rows] + sizes[rows]) if len(rows) else np.zeros(0, np.int64)
    # a thread per run of rows where the walks outweigh its scratch's pages
    threads = max(1, min(thread_count(), int(work[-1] // max(npieces, 1)) if len(work) else 1, len(rows)))
    check_fits((TOPOLOGY_BYTES * npieces + OWN_BYTES * int(sizes.max(initial=0))) * threads,
               f"the graph walks of {len(rows):,} labels")
    cuts = [0] + [int(np.searchsorted(work, work[-1] * t / threads)) for t in range(1, threads)] + [len(rows)]
    other = cc_kind != bg_kind

    ticks = silent(ticks)
    ticks.stage("walks", len(rows))

    def walk(a: int, b: int, call: int) -> tuple[np.ndarray, ...]:
        """Rows a .. b - 1 on scratch of their own, call ``call`` of the ticks."""
        part = rows[a:b]
        total = int(per_label[part].sum()) if len(part) else 0
        most = int(per_label[part].max(initial=0))
        own = int(sizes[part].max(initial=0))
        local, queue = np.zeros(npieces, np.int32), np.zeros(npieces, np.uint32)
        heap, hkey = np.zeros(npieces, np.uint32), np.zeros(npieces, np.int32)
        parent, parent0 = np.zeros(own, np.int32), np.zeros(own, np.int32)  # per piece of one label
        grouping = np.zeros(own + 1, np.int32), np.zeros(own, np.int32), np.zeros(own, np.int64)  # start, fill, members
        stamps = [np.zeros(npieces if k < 2 or other else 1, np.int32) for k in range(4)]  # stamp, comp, stamp2, comp2
        small = [np.zeros(3, np.int64) for _ in range(2)] + [np.zeros(most, np.int64) for _ in range(4)]
        b0, b2 = np.zeros(len(part), np.int64), np.zeros(len(part), np.int64)
        surf = [np.empty(total, np.int64) for _ in range(3)]  # written up to the surfaces found, read no further
        nsurf = _label_loop(part, lab_start, lab_pieces, piece_label, plo, phi, adj_start, adj_to, adj_kind, adj_n,
                            adj_q, obj_kind, b0_kind, bg_kind, cc_kind, local, *stamps, queue, heap, hkey, parent,
                            parent0, *grouping, *small, b0, b2, *surf, MOST_WALKS, ticks.slot(call), STOP)
        ticks.reached(call, len(part))  # (where the loop stopped early, Stopped)
        surf[0][:nsurf] += a  # rows of the whole
        return (b0, b2) + tuple(s[:nsurf] for s in surf)

    found = run([(walk, a, b, t) for t, (a, b) in enumerate(zip(cuts[:-1], cuts[1:]))], ticks)
    return tuple(np.concatenate([f[k] for f in found]) for k in range(5))


def add_by_label(of: np.ndarray, counts: np.ndarray, sums: np.ndarray, features: np.ndarray, doubled: np.ndarray,
                 out_counts: np.ndarray, out_sums: np.ndarray, out_features: np.ndarray, out_doubled: np.ndarray) -> None:
    """Per label, the sums of its pieces' voxel counts, coordinate sums,
    features and doubled edges (``of[p]``: piece p's label), in one pass
    over the pieces.

    ``out_features`` may be held in either order (a label table holds it
    transposed, so that each feature is one run of memory): the compiled
    pass reads it as its memory, one value after another, and steps of a
    row and of a column, so that both orders share one compile.

    Examples
    --------
    >>> t = [np.zeros(2, np.int64), np.zeros((2, 3), np.int64), np.zeros((2, 1), np.int64), np.zeros(2, np.int64)]
    >>> add_by_label(np.array([1, 0, 1]), np.array([2, 3, 4]), np.ones((3, 3), np.int64),
    ...              np.ones((3, 1), np.int64), np.zeros(3, np.int64), *t)
    >>> t[0].tolist(), t[2].ravel().tolist()
    ([3, 6], [1, 2])
    """
    if not (out_features.flags.c_contiguous or out_features.flags.f_contiguous):
        raise ValueError("add_by_label adds into features held in C or Fortran order")
    flat = out_features.ravel(order="K")  # a view in either order
    row, column = (step // out_features.itemsize for step in out_features.strides)
    _add_by_label(of, counts, sums, features, doubled, out_counts, out_sums, flat, row, column, out_doubled)


@njit(cache=True, nogil=True)
def _add_by_label(of, counts, sums, features, doubled, out_counts, out_sums, out_features, row, column, out_doubled):
    """:func:`add_by_label`, ``out_features`` as its memory: label l's
    feature f at ``l * row + f * column``."""
    for p in range(len(of)):
        label = of[p]
        out_counts[label] += counts[p]
        out_doubled[label] += doubled[p]
        for d in range(3):
            out_sums[label, d] += sums[p, d]
        at = label * row
        for f in range(features.shape[1]):
            out_features[at + f * column] += features[p, f]


@njit(cache=True, nogil=True)
def box_by_label(of, lo, hi, out_lo, out_hi):
    """Per label, the box of its pieces' boxes (``of[p]``: piece p's
    label; ``out_lo`` and ``out_hi`` start above and below every voxel),
    in one pass over the pieces.

    Examples
    --------
    >>> lo, hi = np.full((2, 3), 99), np.full((2, 3), -1)
    >>> box_by_label(np.array([1, 0, 1]), np.array([[0, 0, 0], [1, 1, 1], [2, 0, 5]]),
    ...              np.array([[1, 1, 1], [2, 2, 2], [3, 4, 6]]), lo, hi)
    >>> lo[1].tolist(), hi[1].tolist()
    ([0, 0, 0], [3, 4, 6])
    """
    for p in range(len(of)):
        label = of[p]
        for d in range(3):
            out_lo[label, d] = min(out_lo[label, d], lo[p, d])
            out_hi[label, d] = max(out_hi[label, d], hi[p, d])


@njit(cache=True, nogil=True)
def _counting_order(source, n):
    """Where each row goes when rows are grouped by ``source`` (0..n-1),
    keeping their order within a group, and the groups' starts."""
    start = np.zeros(n + 1, np.int64)
    for s in source:
        start[s + 1] += 1
    for g in range(n):
        start[g + 1] += start[g]
    fill = start[:-1].copy()
    order = np.empty(len(source), np.int64)
    for r in range(len(source)):
        order[fill[source[r]]] = r
        fill[source[r]] += 1
    return start, order


def grouped(source: np.ndarray, n: int, *columns: np.ndarray) -> tuple[np.ndarray, ...]:
    """Rows grouped by ``source`` (0..n-1, a counting sort): the start of
    each group (n + 1) and the columns in that order."""
    start, order = _counting_order(np.asarray(source, np.int64), n)
    return (start,) + tuple(np.ascontiguousarray(np.take(c, order)) for c in columns)


@njit(cache=True, nogil=True, inline="always")
def _listed(kind, sums, r, none):
    """Whether pair ``r`` is an edge of the graph: its pieces touch, or
    sheets join them (the pass gives sheets only to pieces that touch; an
    edge holds them all the same, unread by the walks past ``none``)."""
    low = np.uint64(0xFFFFFFFF)
    return kind[r] < none or (sums[r, 0] & low) != 0 or (sums[r, 1] & low) != 0


@njit(cache=True, nogil=True)
def _fill_pair_graph(keys, kind, sums, none, adj_fill, adj_to, adj_kind, adj_n, adj_q):
    """The edges of :func:`pair_graph` of these pairs, each at its piece's
    next place ``adj_fill[piece]`` (which moves past it)."""
    low = np.uint64(0xFFFFFFFF)
    for r in range(len(keys)):
        if not _listed(kind, sums, r, none):
            continue
        a, b = np.int64(keys[r] >> np.uint64(32)), np.int64(keys[r] & low)
        for p, q, c in ((a, b, 0), (b, a, 1)):
            f = adj_fill[p]
            adj_to[f] = q
            adj_kind[f] = kind[r]
            sheets = sums[r, c] & low
            adj_n[f] = sheets
            adj_q[f] = sums[r, c] >> np.uint64(32) if sheets else np.uint64(0)  # quarters go with a sheet
            adj_fill[p] = f + 1


@njit(cache=True, nogil=True)
def _pair_degrees(keys, kind, sums, none, adj_start):
    """Each piece's edges, counted at its start + 1; returns their number
    (both ways)."""
    touching = 0
    for r in range(len(keys)):
        if _listed(kind, sums, r, none):
            adj_start[np.int64(keys[r] >> np.uint64(32)) + 1] += 1
            adj_start[np.int64(keys[r] & np.uint64(0xFFFFFFFF)) + 1] += 1
            touching += 2
    return touching


@njit(cache=True, nogil=True)
def renumbered_pairs(one: np.ndarray, keys: np.ndarray, kind: np.ndarray, sums: np.ndarray, out_keys: np.ndarray,
                     out_kind: np.ndarray, out_sums: np.ndarray, at: int) -> int:
    """The pairs of pieces of the vertex pass (``keys``: the smaller piece
    in the high 32 bits; ``kind``; ``sums``, two columns, one each way)
    with piece ``p`` renumbered ``one[p]``, written to the ``out_`` arrays
    from entry ``at`` on, in order: the smaller number high again (the two
    columns of ``sums`` swapped where the order turns), a pair whose two
    pieces become one left out (it touches nothing else). Returns the
    entry after the last one written.

    Examples
    --------
    >>> keys = np.array([(1 << 32) | 2, (1 << 32) | 3, (2 << 32) | 3], np.uint64)
    >>> sums = np.array([[5, 6], [7, 8], [9, 10]], np.uint64)
    >>> out = np.zeros(3, np.uint64), np.zeros(3, np.uint8), np.zeros((3, 2), np.uint64)
    >>> renumbered_pairs(np.array([0, 3, 1, 1]), keys, np.array([1, 2, 3], np.uint8), sums, *out, 0)  # 2, 3 one
    2
    >>> [(int(k) >> 32, int(k) & 0xFFFFFFFF) for k in out[0][:2]], out[1][:2].tolist(), out[2][:2].tolist()
    ([(1, 3), (1, 3)], [1, 2], [[6, 5], [8, 7]])
    """
    low = np.uint64(0xFFFFFFFF)
    for r in range(len(keys)):
        p, q = one[np.int64(keys[r] >> np.uint64(32))], one[np.int64(keys[r] & low)]
        if p == q:
            continue
        turn = 1 if p > q else 0
        out_keys[at] = (np.uint64(min(p, q)) << np.uint64(32)) | np.uint64(max(p, q))
        out_kind[at] = kind[r]
        out_sums[at, 0], out_sums[at, 1] = sums[r, turn], sums[r, 1 - turn]
        at += 1
    return at


#: pairs per thread of :func:`entries_graph` at the least (fewer: one thread,
#: which places them sooner than threads start)
PAIRS_PER_THREAD = 1 << 16


def pair_graph(keys: np.ndarray, kind: np.ndarray, sums: np.ndarray, n: int,
               none: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The graph of pieces from the vertex pass' pairs (keys: the smaller
    piece in the high 32 bits; ``kind`` below ``none`` where they touch;
    ``sums``: sheets plus quarters times 2^32, each way), grouped by piece
    in one counting pass: the edges both ways (``adj_start``, ``adj_to``,
    ``adj_kind``), each with the sheets (``adj_n``) and quarters
    (``adj_q``) of the mesh of its piece as the object where the other is
    the background, so that a label's surfaces are summed over the edges
    its walks read. Piece numbers and counts are held in 32 bits (the pass
    packs them so). :func:`entries_graph` of the pairs in one set of arrays.

    Examples
    --------
    >>> keys = np.array([(1 << 32) | 2, (1 << 32) | 3], np.uint64)  # pieces 1-2 and 1-3
    >>> sums = np.array([[(4 << 32) | 2, 0], [0, 0]], np.uint64)  # 1 over 2: 2 sheets, 4 quarters
    >>> start, to, kind, sheets, quarters = pair_graph(keys, np.array([1, 2], np.uint8), sums, 4, 4)
    >>> start.tolist(), to.tolist(), sheets.tolist(), quarters.tolist()
    ([0, 0, 2, 3, 4], [2, 3, 1, 1], [2, 0, 0, 0], [4, 0, 0, 0])
    """
    return entries_graph([(keys, kind, sums)], n, none)


def entries_graph(entries: list, n: int, none: int,
                  ticks: Ticks | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`pair_graph` of pairs held in several sets of arrays
    (``entries``: ``(keys, kind, sums)`` each, in order; the blocks of
    entries that the vertex pass writes out, read where they are rather
    than copied into one set first). The pairs are cut into runs of about
    equal length, each counted and then placed on a thread of its own; a
    piece's edges from an earlier run come first, as one pass over all of
    them would place them.

    The list is taken over: it is empty on return, and once the pairs are
    counted only the runs that still have to place a block hold it, each
    letting go of its part of a block as soon as that is placed. A block
    that nothing else holds (the vertex pass' blocks, each in pages of its
    own) is then given back to the system while the graph's pages fill,
    so that the pairs and the whole graph are not held at once.
    ``ticks``: the stage ``"graph"`` of the progress, counted in pairs
    (each twice: counted, then placed), and where the work stops on a
    signal.

    Examples
    --------
    >>> keys = np.array([(1 << 32) | 2, (1 << 32) | 3], np.uint64)
    >>> sums = np.array([[(4 << 32) | 2, 0], [0, 0]], np.uint64)
    >>> kind = np.array([1, 2], np.uint8)
    >>> one = entries_graph([(keys, kind, sums)], 4, 4)
    >>> blocks = [(keys[:1], kind[:1], sums[:1]), (keys[1:], kind[1:], sums[1:])]
    >>> two = entries_graph(blocks, 4, 4)
    >>> all((a == b).all() for a, b in zip(one, two)), blocks  # the list is taken over
    (True, [])
    """
    from .compiled import run, thread_count

    sizes = [len(keys) for keys, _, _ in entries]
    total = sum(sizes)
    threads = max(1, min(thread_count(), total // PAIRS_PER_THREAD))
    parts = _cut_entries(entries, sizes, [total * t // threads for t in range(threads + 1)])
    entries.clear()  # the runs' parts hold the blocks now, each let go where it is placed
    degrees = [np.zeros(n + 1, np.int64) for _ in parts]
    ticks = silent(ticks)
    ticks.stage("graph", 2 * total)

    def count(part: list, counts: np.ndarray, call: int) -> int:
        """The edges of a run of pairs, counted per piece."""
        edges = 0
        for keys, kind, sums in part:
            edges += _pair_degrees(keys, kind, sums, none, counts)
            ticks.add(call, len(keys))
        return edges

    touching = sum(run([(count, part, counts, t) for t, (part, counts) in enumerate(zip(parts, degrees))], ticks))
    adj_start = np.cumsum(degrees[0] if len(degrees) == 1 else np.sum(degrees, axis=0))
    fills = [adj_start[:-1].copy()]
    for counts in degrees[:-1]:  # a run's edges of a piece after those of the runs before
        fills.append(fills[-1] + counts[1:])
    del degrees
    # the pieces' need was reckoned with a number of pairs a piece (label_table.PAIRS_PER_PIECE); here it is known
    check_fits(GRAPH_EDGE_BYTES * touching, f"the graph of {n - 1:,} pieces ({touching // 2:,} pairs)",
               hint="crop the label image")
    adj = (adj_start, mapped(touching, np.uint32), mapped(touching, np.uint8), mapped(touching, np.uint32),
           mapped(touching, np.uint32))

    def place(part: list, fill: np.ndarray, call: int) -> None:
        """The edges of a run of pairs at their pieces' places, each part
        of a block let go once placed (the block's pages go with the last)."""
        while part:
            keys, kind, sums = part.pop(0)
            _fill_pair_graph(keys, kind, sums, none, fill, *adj[1:])
            ticks.add(call, len(keys))
            del keys, kind, sums

    run([(place, part, fill, t) for t, (part, fill) in enumerate(zip(parts, fills))], ticks)
    return adj


def _cut_entries(entries: list, sizes: list[int], cuts: list[int]) -> list[list]:
    """``entries`` (of ``sizes`` pairs each) cut at the pairs ``cuts``
    (counted over all of them, in order): per run between two cuts, the
    slices of the arrays that it holds."""
    parts: list[list] = [[] for _ in cuts[1:]]
    at = 0
    for (keys, kind, sums), size in zip(entries, sizes):
        for t, (a, b) in enumerate(zip(cuts[:-1], cuts[1:])):
            lo, hi = max(a, at) - at, min(b, at + size) - at
            if lo < hi:
                parts[t].append((keys[lo:hi], kind[lo:hi], sums[lo:hi]))
        at += size
    return parts
