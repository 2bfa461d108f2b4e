"""The label table of a label image that does not fit in memory, read one
layer of blocks at a time (a zarr store: ``isoflow info LABELS.zarr
--labels``).

The passes of :mod:`isoflow.digital.label_table` run on each layer of
blocks along axis 0 with one voxel layer of each neighbour: the pieces of
the slab (their voxels, sums and boxes counted on the slab's own layers
only), then the vertex pass over the slab's own vertex layers (which read
the voxel layer before the slab, and the one after it for the doubled
edges). A piece cut by a seam gets a number in each slab; the two voxel
layers both slabs read name the same voxels under both numbers, and a
connected-components pass over those pairs makes them one before the graph
of pieces is walked. Memory: two slabs' voxels and pieces, and tables per
piece and per pair of pieces.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..errors import IsoflowError
from ..scale.memory import check_fits
from .connectivity import check_connectivity
from .label_table import (
    PIECE_BYTES_PER_VOXEL,
    as_labels,
    checked_image,
    columns,
    feature_table,
    label_dtype,
    label_table,
    pass_tables,
    rows_of_pieces,
    wanted_labels,
    wanted_pieces,
)
from .lattice import DigitalObject


def label_table_blocks(
    array,
    connectivity: int = 6,
    *,
    layers: Sequence[int] | None = None,
    pitch=None,
    origin=None,
    labels=None,
    surfaces: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> dict[str, np.ndarray]:
    """:func:`isoflow.label_table` of a 3D label array read in slabs along
    axis 0 (a zarr array, or anything ``array[a:b]`` reads as NumPy).

    Parameters
    ----------
    array : array-like
        3D integer label image with ``shape`` and ``dtype``; read as
        ``array[a:b]`` (voxel layers a .. b - 1), never whole.
    connectivity : {6, 26}
        As :func:`isoflow.label_table`.
    layers : sequence of int, optional
        Voxel layers per slab (the array's chunks along axis 0; default:
        one slab).
    pitch, origin, labels, surfaces
        As :func:`isoflow.label_table`.
    progress : callable, optional
        ``progress(done, total)`` after each slab.

    Returns
    -------
    dict of str to numpy.ndarray
        The table of :func:`isoflow.label_table`, equal to it.

    Raises
    ------
    IsoflowError
        As :func:`isoflow.label_table`; a slab that would not fit in memory.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.zeros((6, 5, 5), np.uint8)
    >>> image[1:5, 1:4, 1:4] = 2
    >>> image[2:4, 2, 2] = 0                    # a cavity cut by the seam at layer 3
    >>> t = label_table_blocks(image, layers=[3, 3])
    >>> t["label"].tolist(), t["voxels"].tolist(), t["b2"].tolist()
    ([2], [34], [1])
    """
    checked_image(np.zeros((1,) * len(array.shape), array.dtype))  # 3D, of labels
    kind = label_dtype(array.dtype)
    conn = check_connectivity(3, connectivity)
    place = DigitalObject.placement(3, pitch=pitch, origin=origin)
    wanted = None if labels is None else wanted_labels(labels, kind)
    nx = int(array.shape[0])
    sizes = [nx] if layers is None else [int(n) for n in layers]
    if nx == 0 and not any(sizes):  # no layer to read (a store of shape (0, ...)): the empty image's table
        return label_table(np.zeros(array.shape, kind), conn, pitch=place.spacing, origin=place.origin,
                           labels=labels, surfaces=surfaces)
    if sum(sizes) != nx or min(sizes) < 1:
        raise ValueError(f"layers {sizes} do not add up to the array's {nx} layers")
    sizes = _numbered_at_once(sizes, array.shape)
    stream = _Stream(array, conn, wanted, surfaces)
    stops = np.cumsum(sizes)
    for t, (x0, x1) in enumerate(zip(stops - sizes, stops)):
        stream.slab(int(x0), int(x1))
        if progress is not None:
            progress(t + 1, len(sizes))
    found = rows_of_pieces(*stream.joined(), kind, conn, wanted)
    return columns(found, place.spacing, place.origin, surfaces)


def _numbered_at_once(sizes: list[int], shape) -> list[int]:
    """The slabs cut where one, with its voxel layer either side, would hold
    more voxels than the pieces' 32-bit numbers reach: a store whose chunks
    are 256 layers of 4096 x 4096 voxels is read in slabs of 253 layers.
    The table is the same for any slabs, so only their size changes."""
    from ..scale.pieces import MAX_PIECE_VOXELS

    area = int(np.prod([int(n) for n in shape[1:]], dtype=np.int64))
    most = MAX_PIECE_VOXELS // max(area, 1) - 2
    if most < 1:
        raise IsoflowError(f"a label image whose layers hold {area} voxels each is read three layers at a time, "
                           f"more than the {MAX_PIECE_VOXELS} voxels its pieces are numbered in; "
                           "crop or split it along its last two axes")
    return [part for n in sizes for part in [most] * (n // most) + [n % most] if part]


class _Stream:
    """What the slabs found so far: per piece (numbered across slabs) its
    statistics, features and doubled edges, the pairs of pieces, and the
    pairs of numbers that name one piece in two slabs."""

    def __init__(self, array, conn: int, wanted, surfaces: bool):
        self.array, self.conn, self.wanted, self.surfaces = array, conn, wanted, surfaces
        self.nx = int(array.shape[0])
        self.total = 0  # pieces numbered so far (0: the outside)
        self.parts: dict[str, list] = {k: [] for k in ("values", "counts", "sums", "lo", "hi", "features",
                                                       "doubled", "keys", "kind", "sums_pairs", "same")}
        self.tail = None  # the previous slab's last two voxel layers, numbered across slabs

    def slab(self, x0: int, x1: int) -> None:
        """The pieces and the vertex pass of voxel layers x0 .. x1 - 1."""
        from ..scale.pieces import piece_ids, piece_runs, vertex_pass

        a, b = max(x0 - 1, 0), min(x1 + 1, self.nx)
        shape = (b - a,) + tuple(int(s) for s in self.array.shape[1:])
        stored = np.dtype(self.array.dtype)
        converted = label_dtype(stored).itemsize if stored.kind == "f" else 0  # a float slab's int64 copy
        check_fits((PIECE_BYTES_PER_VOXEL + stored.itemsize + converted) * int(np.prod(shape)),
                   f"a slab of {'x'.join(map(str, shape))} voxels of the label image",
                   hint="write the store with smaller chunks along its first axis")
        vol = np.ascontiguousarray(as_labels(np.asarray(self.array[a:b]), first_layer=a))
        pieces = piece_runs(vol, first=x0 - a, last=x1 - a, x0=a)
        want = wanted_pieces(pieces["values"], vol.dtype, self.wanted)
        passed = vertex_pass(vol, pieces, want, feature_table(self.conn), pass_tables(self.conn, self.surfaces),
                             layers=(x0, x1 + (x1 == self.nx)), nx=self.nx, x0=a, base=self.total)
        if self.tail is not None:  # voxel layers x0 - 1 and x0, read by both slabs: one piece, two numbers
            head = piece_ids(pieces, vol.shape, (0, 2)).astype(np.int64) + self.total
            pairs = np.stack([self.tail.reshape(-1), head.reshape(-1)], axis=1)
            self.parts["same"].append(np.unique(pairs, axis=0))
        self.tail = None
        if x1 < self.nx:
            self.tail = piece_ids(pieces, vol.shape, (x1 - 1 - a, x1 + 1 - a)).astype(np.int64) + self.total
        for key in ("values", "counts", "sums", "lo", "hi"):
            self.parts[key].append(pieces[key][1:])
        self.parts["features"].append(passed["features"][1:])
        self.parts["doubled"].append(passed["doubled"][1:])
        self.parts["keys"].append(passed["keys"])
        self.parts["kind"].append(passed["kind"])
        self.parts["sums_pairs"].append(passed["sums"])
        self.total += pieces["n"]

    def joined(self) -> tuple[dict, dict]:
        """The pieces and the vertex pass's findings of the whole image:
        pieces named in two slabs made one (numbered 1.. in order of their
        first number), their sums added, their boxes joined."""
        from ..scale.pieces import merge_pairs

        one = _same_pieces(self.total, self.parts["same"])
        n = int(one.max(initial=0))
        cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in self.parts.items() if k != "same"}
        at = one[1:]
        pieces = {"values": np.zeros(n + 1, np.uint64), "counts": np.zeros(n + 1, np.int64),
                  "sums": np.zeros((n + 1, 3), np.int64), "lo": np.full((n + 1, 3), np.iinfo(np.int64).max),
                  "hi": np.full((n + 1, 3), -1, np.int64)}
        pieces["values"][at] = cat["values"]
        np.add.at(pieces["counts"], at, cat["counts"])
        np.add.at(pieces["sums"], at, cat["sums"])
        np.minimum.at(pieces["lo"], at, cat["lo"])
        np.maximum.at(pieces["hi"], at, cat["hi"])
        features = np.zeros((n + 1, cat["features"].shape[1]), np.int64)
        np.add.at(features, at, cat["features"])
        doubled = np.bincount(at, cat["doubled"], n + 1).astype(np.int64)
        keys = cat["keys"].astype(np.uint64)
        p = one[(keys >> np.uint64(32)).astype(np.int64)]
        q = one[(keys & np.uint64(0xFFFFFFFF)).astype(np.int64)]
        sums = cat["sums_pairs"].astype(np.uint64).reshape(-1, 2)
        keep = p != q  # pairs within one piece (named in two slabs) touch nothing else
        flip = p > q
        sums = np.where(flip[:, None], sums[:, ::-1], sums)
        lo, hi = np.minimum(p, q), np.maximum(p, q)
        keys = (lo.astype(np.uint64) << np.uint64(32)) | hi.astype(np.uint64)
        keys, kind, sums = merge_pairs(keys[keep], cat["kind"][keep].astype(np.uint8), sums[keep])
        return pieces, {"features": features, "doubled": doubled, "keys": keys, "kind": kind, "sums": sums}


def _same_pieces(total: int, same: list) -> np.ndarray:
    """Per piece number (0 .. total), the number of the piece it is once
    the numbers that name one piece in two slabs are made one: 0 for the
    outside, then 1.. in order of each piece's first number."""
    from ..scale.graphs import components

    pairs = np.concatenate(same) if same else np.zeros((0, 2), np.int64)
    _, comp = components(total + 1, pairs[:, 0], pairs[:, 1])
    first = np.full(comp.max(initial=0) + 1, total + 1)
    np.minimum.at(first, comp, np.arange(total + 1))
    order = np.argsort(first)  # components by their first number: the outside's (0) first
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return rank[comp]
