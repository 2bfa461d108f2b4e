"""The records of the finished layers of blocks of the report block by
block (:mod:`isoflow.digital.outofcore`), settled into one small record.

Each block's merged record names its components on its faces (node keys
``block << 32 | number``), the pairs of keys that touch across the faces,
the pieces of the closed surfaces' tree and what the seams add to them.
Kept for every block until the end, they grow with the faces of all the
blocks: thin blocks (chunks of ``(N, N, 4)``) have nearly all their
components on their faces, and the records of a 1024^3 volume then take
more memory than its blocks.

Once layer ``i`` of blocks is merged, the records that come later name
only the keys of the blocks of layers ``i + 1`` on (the *open* keys) and
the outside. So a component of the records so far that has no open key
is finished: it never grows again, and it encloses only finished
components (in the tree of surfaces, the path from an open component to
the outside runs through the later layers, past each of its ancestors).
Settling keeps of it only what the report needs: one node for the Betti
numbers, its closed surface (the signed sums of its subtree), and that
subtree's sums added to its open parent. An open component keeps its
open keys, chained, and one piece under a key of its own that carries
its first piece's order and parent and its sums so far. The report of
the settled record and the later ones is that of all the records, to
the last bit; memory is the open components and keys of one layer of
faces.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .blocks import OUTSIDE, SHIFT
from .closed_surfaces import subtree_sums, surface_counts
from .measures import joined

#: the keys of the pieces that stand for settled components, above every
#: block's (``block << 32``) and below :data:`OUTSIDE`
SETTLED = np.int64(1) << 61
#: the fields of a piece (see :mod:`isoflow.digital.blocks`)
PIECE_FIELDS = ("key", "obj", "sums", "order", "parent")


def key_components(pairs: np.ndarray, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The components of node keys under edges between them.

    Parameters
    ----------
    pairs : numpy.ndarray
        (2, E) int64 edges.
    keys : numpy.ndarray
        More keys (int64), with or without edges.

    Returns
    -------
    nodes, comp : numpy.ndarray
        The distinct keys of ``pairs`` and ``keys``, sorted, and the
        component of each (0 .. in order of their smallest key): the
        union-find of the sweep's pinches.

    Examples
    --------
    >>> nodes, comp = key_components(np.array([[5, 9], [7, 5]]), np.array([3]))
    >>> nodes.tolist(), comp.tolist()
    ([3, 5, 7, 9], [0, 1, 1, 1])
    """
    from ..scale.kernels import join_pairs

    nodes, inverse = np.unique(np.concatenate([pairs.ravel(), keys]), return_inverse=True)
    e = pairs.shape[1]
    roots = np.arange(len(nodes), dtype=np.int64 if len(nodes) >= 1 << 31 else np.int32)
    join_pairs(roots, np.stack([inverse[:e], inverse[e:2 * e]], axis=1))
    return nodes, np.unique(roots, return_inverse=True)[1]


def resolved_pieces(records: list[dict]) -> dict:
    """The pieces of every record, with the pending parents filled in.

    Parameters
    ----------
    records : list of dict
        Merged records (:func:`isoflow.digital.seams.merge_block`) with
        ``pieces`` and ``parents``.

    Returns
    -------
    dict
        The fields of the pieces (``key``, ``obj``, ``sums``, ``order``,
        ``parent``), each one array over all the records.

    Examples
    --------
    >>> piece = {"key": np.array([7]), "obj": np.array([True]), "sums": np.zeros((1, 2), np.int64),
    ...          "order": np.array([3]), "parent": np.array([-2])}  # pending
    >>> resolved_pieces([{"pieces": [piece], "parents": [np.array([[7], [5]])]}])["parent"].tolist()
    [5]
    """
    pieces = {name: np.concatenate([p[name] for m in records for p in m["pieces"]]) for name in PIECE_FIELDS}
    resolved = np.concatenate([p for m in records for p in m["parents"]] or [np.zeros((2, 0), np.int64)], axis=1)
    order = np.argsort(pieces["key"])
    at = order[np.searchsorted(pieces["key"], resolved[0], sorter=order)]
    pieces["parent"][at] = resolved[1]
    return pieces


def settle(records: list[dict], open_from: int, conn: int) -> dict:
    """One record that stands for ``records`` in the report.

    Parameters
    ----------
    records : list of dict
        The merged records of every block up to a layer (and the record
        settled before them).
    open_from : int
        The first block of the next layer: every later record names only
        the keys of blocks from it on, and the outside.
    conn : int
        The connectivity (6 or 26; 4 or 8 in 2D).

    Returns
    -------
    dict
        A record of the fields of the merged ones: the sums of the
        histograms, voxels, extents and doubled edges, the nodes and keys
        of the open components, and with the surfaces their pieces, gains
        and the closed surfaces of the finished ones.

    Examples
    --------
    >>> one = {"hist": np.ones(16, np.int64), "voxels": 2, "extent": None, "nodes": {"fg": 1, "bg": 0},
    ...        "joins": {"fg": [np.array([[5], [(1 << 32) | 2]])], "bg": []}, "pinches": []}
    >>> s = settle([one, one], 1, 4)  # key 5 (block 0) joined to block 1 twice: block 1's key stays
    >>> int(s["voxels"]), s["nodes"], [j.tolist() for j in s["joins"]["fg"]]
    (4, {'fg': 1, 'bg': 0}, [[[], []]])
    """
    out = {"hist": np.sum([m["hist"] for m in records], axis=0), "voxels": sum(m["voxels"] for m in records),
           "extent": joined([m["extent"] for m in records])}
    joins = {kind: _pairs([e for m in records for e in m["joins"][kind]]) for kind in ("fg", "bg")}
    if "pieces" in records[0]:
        out.update(_settled_surfaces(records, joins, open_from))
        chains = out.pop("chains")
    else:
        chains = {kind: _chains(joins[kind], open_from) for kind in ("fg", "bg")}
    pinched = "fg" if conn == 26 else "bg"  # as the report reads them (a 2D block has no pinches)
    pinches = _pairs([p for m in records for p in m["pinches"]])
    pinch_chains = _chains(np.concatenate([joins[pinched], pinches], axis=1), open_from)
    out["nodes"] = {}
    for kind in ("fg", "bg"):
        before = joins[kind] if kind != pinched else np.concatenate([joins[kind], pinches], axis=1)
        after = chains[kind] if kind != pinched else np.concatenate([chains[kind], pinch_chains], axis=1)
        # the components (nodes less merges) of the edges kept equal those of the edges settled
        out["nodes"][kind] = sum(m["nodes"][kind] for m in records) - _merges(before) + _merges(after)
    out["joins"], out["pinches"] = {kind: [chains[kind]] for kind in ("fg", "bg")}, [pinch_chains]
    return out


def _pairs(edges: list) -> np.ndarray:
    """(2, E) int64 edges of a list of them."""
    return np.concatenate([np.asarray(e, np.int64).reshape(2, -1) for e in edges] or [np.zeros((2, 0), np.int64)],
                          axis=1)


def _merges(pairs: np.ndarray) -> int:
    """The keys of the edges less their components."""
    nodes, comp = key_components(pairs, np.zeros(0, np.int64))
    return len(nodes) - int(comp.max(initial=-1) + 1)


def _is_open(keys: np.ndarray, open_from: int) -> np.ndarray:
    """The keys that later records name: of the blocks from ``open_from``
    on, and the outside."""
    return (keys == OUTSIDE) | ((keys < SETTLED) & ((keys >> SHIFT) >= open_from))


def _chains(pairs: np.ndarray, open_from: int) -> np.ndarray:
    """Edges that keep the components of ``pairs`` among their open keys:
    each component's open keys in a chain."""
    nodes, comp = key_components(pairs, np.zeros(0, np.int64))
    keep = _is_open(nodes, open_from)
    return _chained(nodes[keep], comp[keep])


def _chained(keys: np.ndarray, comp: np.ndarray) -> np.ndarray:
    """(2, E) edges joining the keys of each component one after another."""
    order = np.argsort(comp, kind="stable")
    keys, comp = keys[order], comp[order]
    same = comp[1:] == comp[:-1]
    return np.stack([keys[:-1][same], keys[1:][same]])


class _Tree(NamedTuple):
    """The components of the records' keys (``nodes``, sorted, each one's
    ``comp``), and per component its signed sums (``total``), parent
    (``up``; itself where it has no piece), side (``obj``), whether it has
    an open key (``is_open``), and its first piece (``first``, -1 for
    none); the ``root``, the outside's."""

    nodes: np.ndarray
    comp: np.ndarray
    total: np.ndarray
    up: np.ndarray
    obj: np.ndarray
    is_open: np.ndarray
    first: np.ndarray
    root: int


def _tree(pieces: dict, gains: np.ndarray, joins: dict, open_from: int) -> _Tree:
    """The tree of the components of the records (as the report builds
    it at the end, :func:`isoflow.digital.outofcore.analyze_chunked`)."""
    pairs = np.concatenate([joins["fg"], joins["bg"]], axis=1)
    nodes, comp = key_components(pairs, np.concatenate([pieces["key"], gains[0], [OUTSIDE]]))
    count = int(comp.max()) + 1
    mine = comp[np.searchsorted(nodes, pieces["key"])]
    total = np.zeros((count, 2), np.int64)
    np.add.at(total, mine, pieces["sums"])
    np.add.at(total, comp[np.searchsorted(nodes, gains[0])], gains[1:].T)
    is_open = np.zeros(count, bool)
    is_open[comp[_is_open(nodes, open_from)]] = True
    ranked = np.lexsort((pieces["order"], mine))
    ranked = ranked[np.diff(mine[ranked], prepend=-1) != 0]
    first = np.full(count, -1, np.int64)
    first[mine[ranked]] = ranked
    up = np.arange(count)
    up[mine[ranked]] = comp[np.searchsorted(nodes, pieces["parent"][ranked])]
    obj = np.zeros(count, bool)
    obj[comp[np.isin(nodes, joins["fg"])]] = True
    obj[mine] = pieces["obj"]
    return _Tree(nodes, comp, total, up, obj, is_open, first, int(comp[np.searchsorted(nodes, OUTSIDE)]))


def _settled_surfaces(records: list[dict], joins: dict, open_from: int) -> dict:
    """The surfaces' part of the settled record (see the module docs):
    ``pieces``, ``parents``, ``gains``, ``surfaces``, ``loose``,
    ``doubled``, and ``chains``, per kind the edges that keep the open
    components' keys together."""
    pieces = resolved_pieces(records)
    gains = np.concatenate([g for m in records for g in m["gains"]] or [np.zeros((3, 0), np.int64)], axis=1)
    tree = _tree(pieces, gains, joins, open_from)
    finished = _finished_surfaces(tree.total, tree.up, tree.is_open, tree.obj)  # (their sums added to open parents)
    held, head = _heads(tree)
    parent = head[tree.up[held]]
    assert (parent >= 0).all(), "an open component's parent is open and has pieces"
    settled = {"key": head[held], "obj": tree.obj[held], "sums": tree.total[held],
               "order": pieces["order"][tree.first[held]], "parent": parent}
    keyed = _is_open(tree.nodes, open_from)
    # per kind, each open component's open keys and settled key in a chain
    keys, owner = np.concatenate([tree.nodes[keyed], head[held]]), np.concatenate([tree.comp[keyed], held])
    chains = {kind: _chained(keys[tree.obj[owner] == want], owner[tree.obj[owner] == want])
              for kind, want in (("fg", True), ("bg", False))}
    loose, doubled = _paired_ends(records)
    inner = [s for m in records for s in m["surfaces"]]  # those inside one block each
    return {"pieces": [settled], "parents": [], "gains": [_bare_gains(tree, head, keyed)],
            "surfaces": [np.concatenate([*inner, finished])], "loose": [loose], "doubled": doubled, "chains": chains}


def _heads(tree: _Tree) -> tuple[np.ndarray, np.ndarray]:
    """The open components with pieces but the outside's, and per
    component the key of its settled piece (the outside's: the outside;
    -1 for the others)."""
    count = len(tree.up)
    held = np.flatnonzero((tree.first >= 0) & tree.is_open & (np.arange(count) != tree.root))
    head = np.full(count, -1, np.int64)
    head[held] = SETTLED + np.arange(len(held))
    head[tree.root] = OUTSIDE
    return held, head


def _bare_gains(tree: _Tree, head: np.ndarray, keyed: np.ndarray) -> np.ndarray:
    """(3, n) the sums of the open components without pieces, each on the
    smallest of its open keys (``keyed``), as the seams' gains are."""
    bare = np.flatnonzero(tree.is_open & (head < 0))
    smallest = np.full(len(tree.up), -1, np.int64)
    smallest[tree.comp[keyed][::-1]] = tree.nodes[keyed][::-1]
    return np.stack([smallest[bare], tree.total[bare, 0], tree.total[bare, 1]])


def _finished_surfaces(total: np.ndarray, up: np.ndarray, is_open: np.ndarray, obj: np.ndarray) -> np.ndarray:
    """(n, 2) mesh vertices and faces of the surfaces of the finished
    components (signed sums ``total``, parents ``up``), each the sums of
    its subtree; those of a finished subtree whose parent is open are
    added to that parent's ``total`` (in place)."""
    count = len(up)
    # the finished forest under one more node, which stands for the open components
    forest = np.append(np.where(is_open, count, up), count)
    sums = subtree_sums(forest, count, np.concatenate([np.where(is_open[:, None], 0, total), np.zeros((1, 2), np.int64)]))
    done = np.flatnonzero(~is_open)
    tops = done[is_open[up[done]]]
    np.add.at(total, up[tops], sums[tops])
    vertices, faces = surface_counts(sums[done] * np.where(obj[done], 1, -1)[:, None])
    return np.stack([vertices, faces], axis=1)


def _paired_ends(records: list[dict]) -> tuple[np.ndarray, int]:
    """The loose ends of doubled edges that are still alone, and the edges
    whose two ends both were handed on (doubled, counted once)."""
    keys, seen = np.unique(np.concatenate([e for m in records for e in m["loose"]]), return_counts=True)
    assert (seen <= 2).all(), "an edge has two ends"
    return keys[seen == 1], sum(m["doubled"] for m in records) + int(np.count_nonzero(seen == 2))
