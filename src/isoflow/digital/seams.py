"""What crosses the faces between the blocks of a volume larger than memory,
for the report block by block (:mod:`isoflow.digital.outofcore`).

For the plane between a block and its upper neighbour along an axis, the
two facing layers of component numbers (:mod:`isoflow.digital.blocks`)
are laid side by side in a two-voxel-thick *seam* that reaches one voxel
into the next blocks along the later axes (so that the vertices at the
block's own edges and corners, and the diagonal contacts there, are in
one seam: along an earlier axis the seam of that axis has them). Numbers
become node keys. In 3D the seam's census
(:func:`isoflow.scale.seams.seam_census`) gives the histogram of the
vertices on the plane, what the surfaces of each key gain there (the
sheets and pinches of those vertices, the cells across the plane that
neither block counted), the pinches, the loose ends of doubled spokes and
the keys to join; in 2D the seam is labelled (cc3d) to find the keys to
join, and its vertices' histogram counted.

The seam under a block's low z face also answers the block's pending
parents: the key of the voxel just below each piece's first voxel.
"""

from __future__ import annotations

import itertools
from functools import cache

import numpy as np

from ..scale.compiled import using
from ..scale.labels import label
from .blocks import OUTSIDE, edge_keys, node_keys, vertex_histogram
from .closed_surfaces import MESH_ADJACENCY, sweep_tables
from .connectivity import complement

#: how many coordinates two neighbours may differ in, per adjacency of the
#: boundary mesh
_REACH = {6: 1, 18: 2}


def _seam(by_offset, block_id, axis: int, ndim: int) -> tuple[np.ndarray, np.ndarray]:
    """The two-voxel-thick seam across the upper face of a block along
    ``axis``: its voxels and their node keys.

    Layer 0 is the upper face of the block (and of its upper neighbours
    along the other axes, one voxel of them), layer 1 the lower face of the
    blocks above. Along every other axis the seam is the block's extent
    plus one voxel where an upper neighbour exists.
    """
    others = [m for m in range(ndim) if m != axis]
    length = list(by_offset[(0,) * ndim]["faces"]["n", axis, 1].shape)
    shape = [2] * ndim
    for j, m in enumerate(others):
        shape[m] = length[j] + int(tuple(int(q == m) for q in range(ndim)) in by_offset)
    vox, keys = np.zeros(shape, dtype=bool), np.zeros(shape, dtype=np.int64)
    for s in (0, 1):  # lower blocks' upper faces, upper blocks' lower faces
        for d_other in itertools.product((0, 1), repeat=ndim - 1):
            d = [0] * ndim
            d[axis] = s
            for j, m in enumerate(others):
                d[m] = d_other[j]
            d = tuple(d)
            if d not in by_offset:
                continue
            part = tuple(slice(0, 1) if dj else slice(None) for dj in d_other)
            dst = [s] * ndim
            for j, m in enumerate(others):
                dst[m] = slice(length[j], length[j] + 1) if d_other[j] else slice(0, length[j])
            faces = by_offset[d]["faces"]
            vox[tuple(dst)] = faces["vox", axis, 1 - s][part]
            keys[tuple(dst)] = node_keys(faces["n", axis, 1 - s][part], block_id[d])
    return vox, keys


def _labelled_joins(seam: np.ndarray, connectivity: int) -> np.ndarray:
    """Pairs of node keys that touch inside a (2D) seam, shape (2, E).

    Labelling the seam joins voxels that touch with the connectivity; all
    keys inside one seam component are the same component of the volume,
    so chaining them (sorted by seam component) gives enough edges.
    """
    mask = seam != 0
    if not mask.any():
        return np.zeros((2, 0), dtype=np.int64)
    comp, _ = label(mask, connectivity, smallest=True)
    c = comp[mask].astype(np.int64)
    k = seam[mask]
    order = np.lexsort((k, c))
    c, k = c[order], k[order]
    new = np.ones(len(c), dtype=bool)
    new[1:] = (c[1:] != c[:-1]) | (k[1:] != k[:-1])
    c, k = c[new], k[new]
    same = c[1:] == c[:-1]
    return np.stack((k[:-1][same], k[1:][same]))


def _blocks_around(index, numblocks) -> tuple[dict, dict]:
    """The offsets ``d`` in ``{0,1}^n`` (C order) of the block's existing
    upper neighbours ``index + d``, and their block numbers."""
    ndim = len(index)
    offsets = [d for d in itertools.product((0, 1), repeat=ndim)
               if all(i + di < n for i, di, n in zip(index, d, numblocks))]
    ids = {d: int(np.ravel_multi_index(tuple(i + di for i, di in zip(index, d)), numblocks)) for d in offsets}
    return offsets, ids


def merge_block(index, numblocks, box, shape, conn: int, surfaces: bool, *summaries) -> dict:
    """What crosses the upper faces of one block, with its own small numbers.

    Parameters
    ----------
    index, numblocks : tuple of int
        The block's place in the grid of blocks, and the grid's size.
    box : tuple of (int, int)
        The block's [start, stop) along each axis of the volume.
    shape : tuple of int
        The volume's shape.
    conn : int
        The connectivity (6 or 26; 4 or 8 in 2D).
    surfaces : bool
        Whether the closed surfaces and the doubled edges are counted (3D).
    *summaries : dict
        Those of :func:`isoflow.digital.blocks.summarize_block` for the
        block and its existing upper neighbours ``index + d``, ``d`` in
        ``{0,1}^n`` (C order of ``d``).

    Returns
    -------
    dict
        The block's summary without its faces (the larger part, which the
        scheduler can then drop), its histogram with the seams' vertices
        added, ``joins`` (per kind, pairs of node keys that touch across a
        face), the seams' pinches, and with ``surfaces`` in 3D their
        ``gains`` (node keys, 4 chi, faces), loose ends and the parents of
        the pending pieces of the block above along z.

    Examples
    --------
    >>> from isoflow.digital.blocks import summarize_block
    >>> from isoflow.digital.configurations import configuration_histogram
    >>> v = np.zeros((4, 3, 3), bool); v[1:3, 1, 1] = True  # across the face x = 2
    >>> low, high = (summarize_block(v[a:a + 2], (i, 0, 0), (2, 1, 1), (a, 0, 0), v.shape, 6, "v", True)
    ...              for i, a in ((0, 0), (1, 2)))
    >>> m = merge_block((0, 0, 0), (2, 1, 1), ((0, 2), (0, 3), (0, 3)), v.shape, 6, True, low, high)
    >>> bool((m["hist"] + high["hist"] == configuration_histogram(v)).all()), m["joins"]["fg"][0].shape
    (True, (2, 1))
    """
    ndim = len(index)
    offsets, ids = _blocks_around(index, numblocks)
    by_offset = dict(zip(offsets, summaries))
    own = by_offset[(0,) * ndim]
    out = {key: (list(value) if isinstance(value, list) else value) for key, value in own.items() if key != "faces"}
    out["hist"] = own["hist"].copy()
    out["joins"] = {"fg": [], "bg": []}
    if surfaces and ndim == 3:
        out["gains"] = []
    with using(1):
        for axis in range(ndim):
            if index[axis] + 1 == numblocks[axis]:
                continue  # no upper neighbour: an array border
            seam = _seam(by_offset, ids, axis, ndim)
            if ndim == 2:
                _add_planar_seam(out, seam, index, numblocks, axis, conn)
            else:
                _add_seam(out, seam, index, numblocks, box, shape, axis, conn, surfaces)
        above = tuple(int(m == 2) for m in range(ndim))
        if ndim == 3 and surfaces and above in by_offset:
            out["parents"].append(_pending_parents(own, by_offset[above], ids[(0, 0, 0)]))
    return out


def _kept(index, numblocks, axis: int, cut_shape) -> tuple[list[int], list[int]]:
    """The box of vertices of the seam across ``axis`` that it counts: the
    layer between its two voxel layers; along another axis those whose
    lower voxel is the block's own (vertex 0 only where the block is the
    first), and those whose upper voxel is in the seam too, the last vertex
    only where the block is the last (its upper voxel is outside)."""
    lo, hi = [], []
    for m, n in enumerate(cut_shape):
        if m == axis:
            lo.append(1)
            hi.append(2)
        else:
            lo.append(0 if index[m] == 0 else 1)
            hi.append(n + 1 if index[m] + 1 == numblocks[m] else n)
    return lo, hi


def _cut(seam: np.ndarray, index, numblocks, axis: int) -> np.ndarray:
    """The seam without its voxel beyond the block along the earlier axes:
    the vertices and cells there are the seam of that axis's."""
    return seam[tuple(slice(0, None if m >= axis or index[m] + 1 == numblocks[m] else -1)
                      for m in range(seam.ndim))]


def _add_planar_seam(out: dict, seam: tuple, index, numblocks, axis: int, conn: int) -> None:
    """A 2D seam's vertices and joins, added to the block's numbers."""
    vox, keys = seam
    cut = _cut(vox, index, numblocks, axis)
    lo, hi = _kept(index, numblocks, axis, cut.shape)
    keep_low = [a == 0 for a in lo]
    keep_high = [b == n + 1 for b, n in zip(hi, cut.shape)]
    keep_low[axis] = keep_high[axis] = False
    out["hist"] += vertex_histogram(cut, keep_low, keep_high)
    out["joins"]["fg"].append(_labelled_joins(np.where(vox, keys, 0), conn))
    out["joins"]["bg"].append(_labelled_joins(np.where(vox, 0, keys), complement(vox.ndim, conn)))


def _add_seam(out: dict, seam: tuple, index, numblocks, box, shape, axis: int, conn: int, surfaces: bool) -> None:
    """A 3D seam's census, added to the block's numbers."""
    from ..scale.seams import seam_census

    vox, keys = (_cut(a, index, numblocks, axis) for a in seam)
    lo, hi = _kept(index, numblocks, axis, vox.shape)
    # the block's own voxels along each axis: the seam less its voxel beyond
    own = [n - int(m > axis and index[m] + 1 < numblocks[m]) for m, n in enumerate(vox.shape)]
    found = seam_census(vox, keys, lo, hi, axis, own, int(OUTSIDE), _tables(conn), conn == 6,
                        tuple(_REACH[a] for a in MESH_ADJACENCY[conn]))
    out["hist"] += found["hist"]
    edges = found["edges"]
    obj = edges[:, 2] == 1
    out["joins"]["fg"].append(edges[obj, :2].T)
    out["joins"]["bg"].append(edges[~obj, :2].T)
    out["pinches"].append(found["pairs"].T)
    if surfaces:
        # the seam's first voxel: the block's last layer along the axis
        start = [b - 1 if m == axis else a for m, (a, b) in enumerate(box)]
        out["loose"].append(edge_keys(found["loose"], start, shape))
        out["gains"].append(np.stack([found["keys"], found["chi4"], found["faces"]]))


@cache
def _tables(conn: int):
    """The sweep's tables for the seams (the object's Euler characteristic
    from its cells under 6, the background's under 26)."""
    from ..scale.sweep import sheet_tables

    return sheet_tables(sweep_tables(conn), conn == 6)


def _pending_parents(own: dict, above: dict, block_id: int) -> np.ndarray:
    """Keys of the pending pieces of the block above along z and of their
    parents, the voxels just below their first voxels, on this block's
    upper z face (2, n)."""
    rows, keys = above["pending"][0]
    return np.stack([keys, node_keys(own["faces"]["n", 2, 1].ravel()[rows], block_id)])
