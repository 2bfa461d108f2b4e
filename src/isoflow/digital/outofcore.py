"""The shape report of volumes larger than memory: dask arrays and zarr stores.

:func:`analyze_chunked` returns exactly the dict of
``analyze(DigitalObject(np.asarray(array)), connectivity, surfaces=False)``
while holding only a few blocks at a time. Everything in the report comes
from three numbers per block, so the volume is read once, block by block:

* **The configuration histogram.** Vertex ``w`` sees the voxels ``w-1`` and
  ``w`` along every axis. The block ``[a, b)`` owns the vertices ``a+1 ..
  b`` (and ``0`` if it is the first block): those below ``b`` need only its
  own voxels and are counted when the block is read; those at ``b`` need
  the first voxel layer of the next block, which the merge step below has
  anyway (unless the block is the last one, where the voxel ``b`` is outside
  and background). Each vertex is counted exactly once, no block is read
  twice or with a halo, and the 256 (16 in 2D) bins of all blocks add up to
  the whole volume's histogram, from which chi, ``n``, ``a^T n`` and the
  energy follow (:func:`isoflow.digital.analysis.report_from_histogram`).
* **Components of the object (b0).** Each block is labelled on its own; a
  label is a node ``(block, local label)``. Two nodes are the same component
  when voxels of theirs touch across a block face, so every block also keeps
  the labels on its internal faces (a few MB, not the label volume). For the
  plane between a block and its upper neighbour along an axis, the two facing
  label layers are laid side by side in a two-voxel-thick tile that reaches
  one voxel into the next blocks along the other axes (so that diagonal
  contacts across block edges and corners are seen with 26/8-connectivity);
  labelling that tile with the same connectivity joins exactly the nodes
  that touch. The union-find over those edges (a sparse graph, scipy's
  ``connected_components``) gives ``b0 = nodes - merges``.
* **Enclosed background components** (cavities in 3D, holes in 2D). The same
  on the complement with the complementary connectivity; a node is on the
  outside when one of its voxels lies on the array's border faces (the
  region outside the array is background and joins them all), and the
  enclosed components are those with no such node.

Why not ``dask_image.ndmeasure.label``: it offsets every block's labels by
the counts of all earlier blocks and relabels the blocks after the global
merge, so every label block stays in memory until the merge is done: the
whole int32 label volume (32 GiB at 2048^3) for the border slices and the
component count. Counting needs only the face labels, which is what this
module keeps; the tests check the two against each other.

Zarr input is read block by block inside each block's task, a block being
a chunk (or shard); a dask array is processed along its chunks. Each block
task returns its faces (labels and voxels) and 256 counts, and the blocks go
layer by layer along the first axis, so peak memory is a few blocks per
worker plus the faces of two layers of blocks (plus the cross-block edges,
a few per component crossing a face), never the volume or a label volume.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..errors import IsoflowError
from ..scale.arrays import binary
from ..scale.compiled import thread_count, using
from ..scale.chunks import block_bounds, import_dask, is_zarr_array, open_zarr, zarr_blocks
from ..scale.labels import label
from .analysis import report_from_histogram
from .report import Report
from .closed_surfaces import MESH_ADJACENCY, box_sheets, surfaces_from_counts
from .configurations import configuration_histogram, configurations
from .surface import pinch_lut
from .connectivity import complement, resolve_connectivity
from .topology import euler_from_histogram

#: local labels live in the low 32 bits of a node key, the block in the high bits
_SHIFT = 32
#: below this many voxels a block's histogram is one configuration array
_DIRECT_HISTOGRAM = 1 << 18
#: the node of the region outside the array (background), when surfaces are
#: counted: no block has this number
OUTSIDE = np.int64(1) << 62


def adjacencies(ndim: int, conn: int, surfaces: bool) -> dict:
    """The adjacencies the blocks are labelled with: the connectivity and its
    complement, or, when the surfaces are counted (3D), those of the
    boundary mesh's solid (:data:`~isoflow.digital.closed_surfaces.MESH_ADJACENCY`);
    the pinches then join the labels into the connectivity's components."""
    if surfaces and ndim == 3:
        fg, bg = MESH_ADJACENCY[conn]
        return {"fg": fg, "bg": bg}
    return {"fg": conn, "bg": complement(ndim, conn)}


# --------------------------------------------------------------------------
# per-block work (module-level functions so that process workers can run them)
# --------------------------------------------------------------------------


def _label(mask: np.ndarray, connectivity: int) -> tuple[np.ndarray, int]:
    """Connected-component labels of a 2D/3D boolean block, in the smallest
    type that holds them (a block keeps the labels of its faces until the
    merge)."""
    return label(mask, connectivity, smallest=True)


def _vertex_histogram(vox: np.ndarray, keep_low, keep_high) -> np.ndarray:
    """Configuration counts of a box of vertices around ``vox``.

    ``configurations(vox)`` covers the vertices ``0 .. E`` along each axis
    (``E = vox.shape[axis]``, zeros outside ``vox``); this counts those with
    index ``0`` only where ``keep_low[axis]`` and index ``E`` only where
    ``keep_high[axis]``. The whole box is counted by
    :func:`configuration_histogram` (the project's fastest path: a compiled
    streaming kernel on large blocks) and the dropped vertex layers, a thin
    shell, are subtracted; layer ``k`` along an axis needs only the voxel
    layers ``k-1`` and ``k``, and a layer leaves out the vertices already
    dropped along the axes before it, so that none is subtracted twice.
    """
    ndim = vox.ndim
    size = 1 << (1 << ndim)
    if vox.size < _DIRECT_HISTOGRAM:
        # small (tiles, small blocks): one configuration array is cheapest
        keep = tuple(slice(0 if lo else 1, None if hi else -1) for lo, hi in zip(keep_low, keep_high))
        return np.bincount(configurations(vox)[keep].ravel(), minlength=size).astype(np.int64)
    hist = configuration_histogram(vox).astype(np.int64)
    kept = []  # per axis, the kept index range of the axes already done
    for axis in range(ndim):
        end = vox.shape[axis]
        for k, keep in ((0, keep_low[axis]), (end, keep_high[axis])):
            if keep:
                continue
            voxels = slice(0, 1) if k == 0 else slice(end - 1, end)
            slab = vox[tuple(voxels if m == axis else slice(None) for m in range(ndim))]
            pick = [slice(None)] * ndim
            pick[axis] = 0 if k == 0 else -1
            for m, rng in enumerate(kept):
                pick[m] = rng
            hist -= np.bincount(configurations(slab)[tuple(pick)].ravel(), minlength=size)
        kept.append(slice(0 if keep_low[axis] else 1, None if keep_high[axis] else -1))
    return hist


def _face(labels: np.ndarray, axis: int, end: int) -> np.ndarray:
    return np.ascontiguousarray(np.take(labels, end, axis=axis))


def _summarize(block, index, numblocks, origin, conn, where, surfaces=False) -> dict:
    """Everything the report needs from one block, and nothing voxel-sized.

    Vertex ``w`` needs the voxels ``w-1`` and ``w``; the block ``[a, b)``
    owns the vertices ``a+1 .. b`` along each axis (and ``0`` when it is the
    first block). Those below ``b`` need only the block's voxels and are
    counted here; those at ``b`` (unless the block is the last one along
    that axis, where the voxel ``b`` is outside and background) need the
    next block's first voxel layer and are counted in :func:`_merge`.

    Returns that histogram and the voxel count, the number of object and
    background labels, the labels and voxels on the block's internal faces
    (for the merge with its neighbours) and the background labels on the
    array's border faces. With ``surfaces`` (3D), also the sheets of the
    block's own vertices per pair of node keys and the pinches
    (:func:`isoflow.digital.closed_surfaces.box_sheets`).
    """
    with using(1):  # the blocks run in parallel; one thread each
        return _summarize_block(block, index, numblocks, origin, conn, where, surfaces)


def _summarize_block(block, index, numblocks, origin, conn, where, surfaces) -> dict:
    ndim = len(index)
    surfaces = surfaces and ndim == 3
    core = binary(block, where, near=origin)
    first = tuple(i == 0 for i in index)
    last = tuple(i == n - 1 for i, n in zip(index, numblocks))
    hist = _vertex_histogram(core, first, last)
    voxels = int(np.count_nonzero(core))
    adj = adjacencies(ndim, conn, surfaces)
    faces: dict = {}
    counts = {}
    kept = {}
    border = np.zeros(0, dtype=np.int64)
    for kind, mask in (("vox", core), ("fg", core), ("bg", ~core)):
        if kind == "vox":
            labels = mask
        else:
            labels, counts[kind] = _label(mask, adj[kind])
        mine, outside = {}, []
        for axis in range(ndim):
            for side, end in ((0, 0), (1, -1)):
                if not (last[axis] if side else first[axis]):
                    mine[kind, axis, side] = _face(labels, axis, end)
                elif kind == "bg":
                    outside.append(_face(labels, axis, end))
        if kind == "vox":
            faces.update(mine)
            continue
        # Only labels seen on a face can take part in a merge or touch the
        # border: number those 1 .. m (the count n stays the block's), so that
        # the faces held for the merge are as small as they can be.
        seen = np.unique(np.concatenate([f.ravel() for f in (*mine.values(), *outside)] or [np.zeros(0, int)]))
        seen = seen[seen > 0]
        dtype = np.uint16 if len(seen) < (1 << 16) else np.uint32
        for key, f in mine.items():
            faces[key] = np.where(f > 0, np.searchsorted(seen, f) + 1, 0).astype(dtype)
        if kind == "bg" and outside:
            on_border = np.unique(np.concatenate([f.ravel() for f in outside]))
            border = np.searchsorted(seen, on_border[on_border > 0]).astype(np.int64) + 1
        if surfaces:
            kept[kind] = (labels, seen)
        del labels, mask
    out = {"hist": hist, "voxels": voxels, "counts": counts, "faces": faces, "border": border}
    if surfaces:
        block_id = int(np.ravel_multi_index(index, numblocks))
        (fg, fg_seen), (bg, bg_seen) = kept["fg"], kept["bg"]
        marker = np.iinfo(bg.dtype).max  # no label: the outside, in the block's numbering
        keep = tuple(slice(0 if f else 1, None if lst else -1) for f, lst in zip(first, last))
        found = box_sheets(core, fg, bg, keep, conn, marker, compiled=True)
        del kept, fg, bg
        out["sheets"] = [(_node_keys(found["obj"], fg_seen, block_id),
                          _node_keys(found["bg"], bg_seen, block_id, marker),
                          found["vertices"], found["quarters"])]
        pinch_seen, pinch_marker = (fg_seen, None) if conn == 26 else (bg_seen, marker)
        out["pinches"] = [_node_keys(found["pairs"].ravel(), pinch_seen, block_id, pinch_marker).reshape(2, -1, order="F")]
    return out


def _node_keys(local: np.ndarray, seen: np.ndarray, block: int, outside=None) -> np.ndarray:
    """Global node keys of a block's own labels: a label seen on a face is
    ``block << 32 | its number among those + 1``, as in the face arrays (and
    so in the merge's edges); any other label is private to the block and
    gets ``-(block << 32 | label) - 1``; ``outside`` becomes :data:`OUTSIDE`."""
    local = np.asarray(local, dtype=np.int64)
    pos = np.searchsorted(seen, local)
    hit = pos < len(seen)
    hit[hit] = seen[pos[hit]] == local[hit]
    base = np.int64(block) << _SHIFT
    keys = np.where(hit, (pos + 1) | base, -(local | base) - 1)
    if outside is not None:
        keys[local == outside] = OUTSIDE
    return keys


def _read_zarr_block(z, index, box, numblocks, conn, where, surfaces=False) -> dict:
    """Read one block of a zarr array and summarise it.

    Reading inside the task (rather than through dask-array chunks) means a
    chunk is decoded where it is needed and dropped at once, whatever order
    the scheduler picks; blocks follow the chunk grid, so each chunk is
    decoded once.
    """
    region = tuple(slice(a, b) for a, b in box)
    origin = tuple(a for a, _ in box)
    try:
        data = np.asarray(z[region])
    except Exception as exc:  # a damaged or missing chunk
        raise IsoflowError(f"{where}: cannot read the block at voxel {origin} ({exc})") from None
    return _summarize(data, index, numblocks, origin, conn, where, surfaces)


def _dask_block(chunk, index, origin, numblocks, conn, where, surfaces=False) -> dict:
    """Summarise one chunk of a dask array (no halo needed, see _summarize)."""
    return _summarize(chunk, index, numblocks, origin, conn, where, surfaces)


def _keys(labels: np.ndarray, block: int) -> np.ndarray:
    """Global node keys of local labels (0 stays 0: no node)."""
    lab = labels.astype(np.int64)
    return np.where(lab > 0, lab | (np.int64(block) << _SHIFT), 0)


def _tile_edges(tile: np.ndarray, connectivity: int) -> np.ndarray:
    """Pairs of node keys that touch inside a face tile, shape (2, E).

    Labelling the tile joins voxels that touch with the connectivity; all
    keys inside one tile component are the same component of the volume, so
    chaining them (sorted by tile component) gives enough edges.
    """
    mask = tile > 0
    if not mask.any():
        return np.zeros((2, 0), dtype=np.int64)
    comp, _ = _label(mask, connectivity)
    c = comp[mask].astype(np.int64)
    k = tile[mask]
    order = np.lexsort((k, c))
    c, k = c[order], k[order]
    new = np.ones(len(c), dtype=bool)
    new[1:] = (c[1:] != c[:-1]) | (k[1:] != k[:-1])
    c, k = c[new], k[new]
    same = c[1:] == c[:-1]
    return np.stack((k[:-1][same], k[1:][same]))


def _tile(by_offset, block_id, kind: str, axis: int, ndim: int) -> np.ndarray:
    """The two-voxel-thick tile across the upper face of a block along ``axis``.

    Layer 0 is the upper face of the block (and of its upper neighbours
    along the other axes, one voxel of them), layer 1 the lower face of the
    blocks above. Along every other axis the tile is the block's extent plus
    one voxel where an upper neighbour exists. Labels become node keys;
    voxels stay bool.
    """
    others = [m for m in range(ndim) if m != axis]
    own = by_offset[(0,) * ndim]["faces"][kind, axis, 1]
    length = list(own.shape)
    shape = [2] * ndim
    for j, m in enumerate(others):
        shape[m] = length[j] + int(tuple(int(q == m) for q in range(ndim)) in by_offset)
    tile = np.zeros(shape, dtype=bool if kind == "vox" else np.int64)
    for s in (0, 1):  # lower blocks' upper faces, upper blocks' lower faces
        for d_other in itertools.product((0, 1), repeat=ndim - 1):
            d = [0] * ndim
            d[axis] = s
            for j, m in enumerate(others):
                d[m] = d_other[j]
            d = tuple(d)
            if d not in by_offset:
                continue
            face = by_offset[d]["faces"][kind, axis, 1 - s]
            face = face[tuple(slice(0, 1) if dj else slice(None) for dj in d_other)]
            dst = [s] * ndim
            for j, m in enumerate(others):
                dst[m] = slice(length[j], length[j] + 1) if d_other[j] else slice(0, length[j])
            tile[tuple(dst)] = face if kind == "vox" else _keys(face, block_id[d])
    return tile


def _merge(index, numblocks, conn, surfaces, *summaries) -> dict:
    """What crosses the upper faces of one block, plus its small numbers.

    ``summaries`` are those of the block and of its existing upper
    neighbours ``index + d``, ``d`` in ``{0,1}^n`` (C order of ``d``). For
    each axis with an upper neighbour, the tile across that face (see
    :func:`_tile`) gives the edges between object labels, between background
    labels, and the configurations of the block's vertices on that face
    (those :func:`_summarize` left out), with their sheets when ``surfaces``
    (the tile's labels are node keys already). The block's own numbers are
    passed on so that the final step never needs the (larger) summaries,
    which the scheduler can then drop.
    """
    ndim = len(index)
    surfaces = surfaces and ndim == 3
    offsets = [
        d for d in itertools.product((0, 1), repeat=ndim)
        if all(i + di < n for i, di, n in zip(index, d, numblocks))
    ]
    by_offset = dict(zip(offsets, summaries))
    block_id = {d: int(np.ravel_multi_index(tuple(i + di for i, di in zip(index, d)), numblocks)) for d in offsets}
    own = by_offset[(0,) * ndim]
    first = [i == 0 for i in index]
    last = [i == n - 1 for i, n in zip(index, numblocks)]
    hist = own["hist"].copy()
    adj = adjacencies(ndim, conn, surfaces)
    out = {
        "voxels": own["voxels"],
        "counts": own["counts"],
        "border": own["border"] | (np.int64(block_id[(0,) * ndim]) << _SHIFT),
        "fg": [],
        "bg": [],
        "sheets": list(own.get("sheets", [])),
        "pinches": list(own.get("pinches", [])),
    }
    for axis in range(ndim):
        if last[axis]:
            continue  # no upper neighbour: an array border
        tiles = {kind: _tile(by_offset, block_id, kind, axis, ndim) for kind in ("fg", "bg", "vox")}
        for kind in ("fg", "bg"):
            out[kind].append(_tile_edges(tiles[kind], adj[kind]))
        # Vertices at the upper face along this axis (index 1 of the tile's
        # vertex layers). Along an earlier axis the face vertices were
        # counted by that axis's tile: drop the tile's extra voxel there, so
        # that index E is left out; along a later axis keep it, it is the
        # voxel the vertex at the block's end needs.
        cut = tuple(slice(0, None if m >= axis or last[m] else -1) for m in range(ndim))
        vox = tiles["vox"][cut]
        keep_low = [False if m == axis else first[m] for m in range(ndim)]
        keep_high = [False if m == axis else last[m] for m in range(ndim)]
        hist += _vertex_histogram(vox, keep_low, keep_high)
        if surfaces:
            keep = tuple(slice(0 if lo else 1, None if hi else -1) for lo, hi in zip(keep_low, keep_high))
            found = box_sheets(vox, tiles["fg"][cut], tiles["bg"][cut], keep, conn, OUTSIDE, compiled=True)
            out["sheets"].append((found["obj"], found["bg"], found["vertices"], found["quarters"]))
            out["pinches"].append(found["pairs"].T)
    out["hist"] = hist
    return out


def _component_ids(edges: list[np.ndarray], keys: np.ndarray) -> np.ndarray:
    """The component of every node key in ``keys`` under the cross-block
    ``edges`` (2, E); a key in no edge is a component by itself."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pairs = np.concatenate(edges, axis=1) if edges else np.zeros((2, 0), np.int64)
    nodes, inverse = np.unique(np.concatenate([pairs.ravel(), keys]), return_inverse=True)
    e = pairs.shape[1]
    graph = coo_matrix((np.ones(e, dtype=np.int8), (inverse[:e], inverse[e:2 * e])), shape=(len(nodes),) * 2)
    return connected_components(graph, directed=False)[1][inverse[2 * e:]]


def _closed_surfaces(merged, conn: int) -> list[dict]:
    """The surfaces: every sheet's pair of node keys becomes the pair of
    their components (under the mesh's adjacencies: the edges found in the
    tiles, and the border background joined with the outside), summed."""
    sheets = [t for m in merged for t in m["sheets"]]
    if not sheets:
        return []
    obj, bg, vertices, quarters = (np.concatenate(col) for col in zip(*sheets))
    border = np.concatenate([m["border"] for m in merged])
    outside = np.stack([border, np.full(len(border), OUTSIDE)])
    obj = _component_ids([e for m in merged for e in m["fg"]], obj)
    bg = _component_ids([e for m in merged for e in m["bg"]] + [outside], bg)
    pair, inverse = np.unique(obj.astype(np.int64) * (int(bg.max(initial=0)) + 1) + bg, return_inverse=True)
    return surfaces_from_counts(np.bincount(inverse, weights=vertices, minlength=len(pair)).astype(np.int64),
                                np.bincount(inverse, weights=quarters, minlength=len(pair)).astype(np.int64))


def _components(nodes: int, edges: list[np.ndarray], border: np.ndarray | None = None) -> int:
    """Components of a graph with ``nodes`` nodes given by its cross-block edges.

    Only nodes that appear in an edge need the union-find; every other node
    is a component by itself. With ``border``, return the number of
    components containing no border node (the enclosed ones).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pairs = np.concatenate(edges, axis=1) if edges else np.zeros((2, 0), np.int64)
    keys, inverse = np.unique(pairs.ravel(), return_inverse=True)
    m = len(keys)
    if m:
        e = pairs.shape[1]
        graph = coo_matrix((np.ones(e, dtype=np.int8), (inverse[:e], inverse[e:])), shape=(m, m))
        k, comp = connected_components(graph, directed=False)
    else:
        k, comp = 0, np.zeros(0, dtype=np.int64)
    total = nodes - m + k
    if border is None:
        return int(total)
    border = np.unique(border[border > 0])
    pos = np.searchsorted(keys, border)
    merged = pos < m
    merged[merged] = keys[pos[merged]] == border[merged]
    touching = len(np.unique(comp[pos[merged]])) + int(np.count_nonzero(~merged))
    return int(total - touching)


def _finish(ndim, conn, shape, surfaces, *merged) -> dict:
    """Add up the blocks and build the report."""
    surfaces = surfaces and ndim == 3
    hist = np.sum([m["hist"] for m in merged], axis=0)
    voxels = sum(m["voxels"] for m in merged)
    fg_edges = [e for m in merged for e in m["fg"]]
    bg_edges = [e for m in merged for e in m["bg"]]
    if surfaces:
        found = _closed_surfaces(merged, conn)
        # the pinches join what the mesh's adjacencies split: object pieces
        # under 26, background pieces under 6
        pinches = [p for m in merged for p in m["pinches"]]
        (fg_edges if conn == 26 else bg_edges).extend(pinches)
    b0 = _components(sum(m["counts"]["fg"] for m in merged), fg_edges)
    enclosed = _components(
        sum(m["counts"]["bg"] for m in merged),
        bg_edges,
        np.concatenate([m["border"] for m in merged]),
    )
    chi = euler_from_histogram(hist, ndim, conn)
    if ndim == 2:
        # as in topology.betti_numbers: b1 counts the holes, chi = b0 - b1
        assert b0 - enclosed == chi, "2D: chi must equal components minus holes"
        betti = [b0, enclosed]
    else:
        betti = [b0, b0 + enclosed - chi, enclosed]
    report = report_from_histogram(hist, ndim, conn, voxels=voxels, shape=shape, betti=betti, parity=0)
    if surfaces:
        pinched = int(hist[pinch_lut(conn)].sum())
        assert sum(s["euler_characteristic"] for s in found) == 2 * chi + 2 * pinched
        # doubled edges need the configurations at both ends of an edge,
        # which for an edge across a block face no single task has
        report.update(surfaces=found, pinched_vertices=pinched, doubled_edges=None)
    return report


# --------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------


def analyze_chunked(
    array,
    connectivity: int | None = None,
    *,
    block_shape=None,
    scheduler=None,
    where: str | None = None,
    progress=None,
    surfaces: bool = True,
    threads: int | None = None,
) -> Report:
    """The report of :func:`isoflow.digital.analysis.analyze`, computed block
    by block.

    ``array`` is a 2D or 3D ``dask.array.Array`` or zarr array of bools or
    0/1 numbers; the result equals
    ``analyze(DigitalObject(np.asarray(array)), connectivity, surfaces)``
    key for key, except that ``doubled_edges`` is None (an edge across a
    block face has its two ends in different tasks). With ``surfaces`` (3D)
    the blocks are labelled under the boundary mesh's adjacencies and every
    vertex's sheets are counted per pair of labels where the vertex is
    counted in the histogram (:func:`isoflow.digital.closed_surfaces.box_sheets`);
    the pairs become the surfaces once the labels are joined across blocks. A dask array is processed along its own chunks; a zarr array
    along its chunks (or shards; tiny chunks are grouped), or along
    ``block_shape`` when given (a dask array is rechunked to it). Memory is a
    few blocks per worker plus the faces of two layers of blocks; the voxels
    are read once. An array with no voxels raises IsoflowError (``analyze``
    has no report for it either).

    ``scheduler`` is passed to ``dask.compute`` (default: dask's configured
    one, threads). The labelling holds the GIL, so threads overlap mostly
    the reading and the histogram; ``"processes"`` runs blocks truly in
    parallel at the cost of starting workers and pickling the face labels
    (worth it only for large volumes on idle cores, and only from code
    under ``if __name__ == "__main__":``), on ``threads`` workers (default:
    :func:`isoflow.scale.compiled.thread_count`); each block's own passes
    then run on one thread. A ``dask.distributed`` client's ``get`` works as
    a scheduler too. ``where`` names the input in error messages.
    ``progress(done, total)`` is called after each layer of blocks along the
    first axis (``total`` layers), the unit of work between two computes.
    """
    dask, da = import_dask()
    is_zarr = is_zarr_array(array)
    if not is_zarr and not isinstance(array, da.Array):
        raise IsoflowError(
            f"analyze_chunked needs a dask or zarr array, got {type(array).__name__}; "
            "use isoflow.analyze for in-memory arrays"
        )
    if where is None:
        where = str(getattr(array, "store_path", None) or getattr(array, "path", "zarr array")) if is_zarr else "dask array"
    if any(np.isnan(s) for s in array.shape):
        raise IsoflowError(f"{where}: array shape {array.shape} is not known (call compute_chunk_sizes first)")
    shape = tuple(int(s) for s in array.shape)
    ndim = len(shape)
    if ndim not in (2, 3):
        raise IsoflowError(f"{where}: a volume must be 2D or 3D, this array is {ndim}D with shape {shape}")
    dtype = np.dtype(array.dtype)
    if dtype.kind not in "biuf":
        raise IsoflowError(f"{where}: array of type {dtype} is not a binary volume")
    conn = resolve_connectivity(ndim, connectivity)
    if 0 in shape:
        raise IsoflowError(f"{where}: the array has no voxels (shape {shape})")

    if is_zarr:
        chunks = zarr_blocks(array, block_shape)
    else:
        if block_shape is not None:
            array = array.rechunk(tuple(int(b) for b in block_shape))
        if any(np.isnan(c) for sizes in array.chunks for c in sizes):
            raise IsoflowError(f"{where}: chunk sizes are not known (call compute_chunk_sizes first)")
        chunks = array.chunks
    bounds = block_bounds(chunks)
    numblocks = tuple(len(c) for c in chunks)
    if max(int(np.prod([max(c) for c in chunks])), 1) >= 1 << _SHIFT:
        raise IsoflowError(f"{where}: blocks of {tuple(max(c) for c in chunks)} voxels are too large; use smaller chunks")

    delayed = dask.delayed
    blocks = None if is_zarr else array.to_delayed()
    with using(threads):
        workers = thread_count()

    def block_task(index):
        if is_zarr:
            box = tuple(bounds[axis][i] for axis, i in enumerate(index))
            return delayed(_read_zarr_block, pure=False)(array, index, box, numblocks, conn, where, surfaces)
        origin = tuple(bounds[axis][i][0] for axis, i in enumerate(index))
        return delayed(_dask_block, pure=False)(blocks[index], index, origin, numblocks, conn, where, surfaces)

    def layer(i):
        rest = [range(n) for n in numblocks[1:]]
        return {(i, *tail): block_task((i, *tail)) for tail in itertools.product(*rest)}

    def uppers(index):
        return [
            tuple(i + di for i, di in zip(index, d))
            for d in itertools.product((0, 1), repeat=ndim)
            if all(i + di < n for i, di, n in zip(index, d, numblocks))
        ]

    # Layer by layer along axis 0: merging layer i needs the summaries of
    # layers i and i+1 only, so at most two layers of faces are held,
    # whatever order dask would pick for one big graph (it tends to read
    # most blocks before merging any). Within a layer the blocks and merges
    # run in parallel.
    merged = []
    try:
        (current,) = dask.compute(layer(0), scheduler=scheduler, num_workers=workers)
        for i in range(numblocks[0]):
            upper = layer(i + 1) if i + 1 < numblocks[0] else {}
            both = {**current, **upper}
            tasks = [
                delayed(_merge, pure=False)(index, numblocks, conn, surfaces, *(both[u] for u in uppers(index)))
                for index in current
            ]
            done, current = dask.compute(tasks, upper, scheduler=scheduler, num_workers=workers)
            merged.extend(done)
            if progress is not None:
                progress(i + 1, numblocks[0])
    except IsoflowError as exc:
        # a process worker's error comes back with its traceback in str();
        # keep the one-line message
        raise IsoflowError(str(exc.args[0]) if exc.args else str(exc)) from None
    return Report.from_dict(_finish(ndim, conn, list(shape), surfaces, *merged))


def analyze_zarr(path, connectivity: int | None = None, *, block_shape=None, scheduler=None,
                 surfaces: bool = True, threads: int | None = None, progress=None) -> Report:
    """:func:`analyze_chunked` on the volume of a zarr store (v2 or v3).

    Before the full pass, the dtype and the first block's values are
    checked, so that a non-binary volume fails at once with the path in the
    message (every block is checked again as it is read).
    """
    z = open_zarr(path)
    where = str(path)
    if z.ndim not in (2, 3):
        raise IsoflowError(f"{where}: a volume must be 2D or 3D, this array is {z.ndim}D with shape {tuple(z.shape)}")
    dtype = np.dtype(z.dtype)
    if dtype.kind not in "biuf":
        raise IsoflowError(f"{where}: array of type {dtype} is not a binary volume")
    if dtype.kind != "b" and 0 not in z.shape:
        try:
            first = np.asarray(z[tuple(slice(0, int(c)) for c in z.chunks)])
        except Exception as exc:  # a damaged or missing chunk, as _read_zarr_block says
            raise IsoflowError(f"{where}: cannot read the block at voxel {(0,) * z.ndim} ({exc})") from None
        binary(first, where, near=(0,) * z.ndim)
    return analyze_chunked(z, connectivity, block_shape=block_shape, scheduler=scheduler, where=where,
                           surfaces=surfaces, threads=threads, progress=progress)
