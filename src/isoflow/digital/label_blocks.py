"""The label table of a label image that does not fit in memory, read one
layer of blocks at a time (a zarr store: ``isoflow info LABELS.zarr
--labels``).

The passes of :mod:`isoflow.digital.label_table` run on each layer of
blocks along axis 0, or along the axis of the most blocks where a store's
chunks are thin across it (the rule of the report block by block,
:func:`isoflow.scale.chunks.layer_axes`; the table is put back in the
image's order) (:func:`~isoflow.digital.label_table.slab_rows`, which
also reads an image in memory of more voxels than the pieces' 32-bit
numbers reach) with one voxel layer of each neighbour: the pieces of
the slab (their voxels, sums and boxes counted on the slab's own layers
only), then the vertex pass over the slab's own vertex layers (which read
the voxel layer before the slab, and the one after it for the doubled
edges). A piece cut by a seam gets a number in each slab; the two voxel
layers both slabs read name the same voxels under both numbers, and a
connected-components pass over those pairs makes them one before the graph
of pieces is walked. Memory: two slabs' voxels and pieces, and tables per
piece and per pair of pieces; a layer of chunks cut into thinner slabs
(more voxels than the pieces' numbers reach) is held whole where it fits,
since each read decodes the chunks it crosses whole.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..errors import IsoflowError
from ..scale.chunks import argument_words
from .connectivity import check_connectivity
from .float64 import unheld_columns
from .label_table import (
    as_labels,
    checked_background,
    checked_image,
    columns,
    label_dtype,
    label_table,
    rows_in_image_order,
    slab_rows,
    wanted_labels,
)
from .lattice import DigitalObject


def label_table_blocks(
    array,
    connectivity: int = 6,
    *,
    layers: Sequence[int] | None = None,
    axes: Sequence[int] | None = None,
    pitch=None,
    origin=None,
    labels=None,
    surfaces: bool = True,
    progress: Callable[[int, int], object] | None = None,
    background: bool = False,
) -> dict[str, np.ndarray]:
    """:func:`isoflow.label_table` of a 3D label array read in slabs along
    axis 0, or another (a zarr array, or anything ``array[a:b]`` reads as
    NumPy).

    Parameters
    ----------
    array : array-like
        3D integer label image with ``shape`` and ``dtype``; read as
        ``array[a:b]`` (voxel layers a .. b - 1), never whole.
    connectivity : {6, 26}
        As :func:`isoflow.label_table`.
    layers : sequence of int, optional
        Voxel layers per slab (the array's chunks along the axis read
        across; default: one slab).
    axes : sequence of int, optional
        The order of the array's axes in which it is read: slabs along
        ``axes[0]`` (a store's chunks thin along it are many layers
        there, one along the others; :func:`isoflow.scale.chunks.layer_axes`
        picks it), each read as ``array[index]`` with a slice per axis.
        Default: along axis 0, ``array[a:b]``.
    pitch, origin, labels, surfaces, background
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
    >>> across = label_table_blocks(image, layers=[2, 3], axes=(2, 0, 1))  # slabs along the last axis
    >>> across["b2"].tolist(), across["bbox-2"].tolist() == t["bbox-2"].tolist()
    ([1], True)
    """
    where = argument_words(array, "label_table_blocks")
    checked_image(np.zeros((1,) * len(array.shape), array.dtype), where)  # 3D, of labels
    kind = label_dtype(array.dtype)
    conn = check_connectivity(3, connectivity)
    place = DigitalObject.placement(3, pitch=pitch, origin=origin)
    wanted = None if labels is None else wanted_labels(labels, kind)
    background = checked_background(background, labels, "label_table_blocks")
    across = None if axes is None or list(axes) == [0, 1, 2] else tuple(int(a) for a in axes)
    read = array if across is None else _Across(array, across)
    nx = int(read.shape[0])
    sizes = [nx] if layers is None else [int(n) for n in layers]
    if nx == 0 and not any(sizes):  # no layer to read (a store of shape (0, ...)): the empty image's table
        return label_table(np.zeros(array.shape, kind), conn, pitch=place.spacing, origin=place.origin,
                           labels=labels, surfaces=surfaces, background=background)
    if sum(sizes) != nx or min(sizes) < 1:
        raise IsoflowError(f"label_table_blocks: layers: {sizes} do not add up to the array's {nx} layers")
    try:
        found = slab_rows(read, conn, wanted, surfaces, sizes, progress, axes=across or (0, 1, 2),
                          background=background)
    except IsoflowError as exc:
        # a voxel that is no label, a slab too wide: named after the function and its argument, as label_table's
        # refusals are; the command line, which names the store before them, keeps the words as they were
        raise exc.called(where) from None
    if across is not None:
        found = rows_in_image_order(found, across)
    return unheld_columns(columns(found, place.spacing, place.origin, surfaces), place.origin, place.spacing,
                          tuple(int(n) for n in array.shape))


#: voxels up to which layers of blocks are read together as one slab
#: (:func:`grouped_layers`): a slab below a million voxels runs its passes
#: on one thread and pays their set-up and a seam for each layer of blocks
GROUP_VOXELS = 1 << 23
#: bytes a voxel a slab of a label table may take at the most (its copy,
#: runs, pieces and pairs on a map of many small labels), for the share of
#: memory a group of layers is held to (:func:`grouped_layers`)
GROUP_BYTES_PER_VOXEL = 16


def grouped_layers(layers: Sequence[int], area: int, most: int | None = None, budget: int | None = None) -> list[int]:
    """Consecutive layers of blocks (a store's chunks along the axis it is
    read across) joined into slabs of up to ``most`` voxels, each at most
    a quarter of the memory ``budget`` at :data:`GROUP_BYTES_PER_VOXEL`
    (default: the memory available now); a layer larger than that stays a
    slab of its own. A slab ends where a layer of blocks ends, so each
    chunk is still decoded once (:func:`~isoflow.digital.label_table.one_read_sizes`).

    Parameters
    ----------
    layers : sequence of int
        The voxel layers of each layer of blocks, in order.
    area : int
        The voxels of one voxel layer (the cross-section).
    most : int, optional
        The most voxels of a group (default :data:`GROUP_VOXELS`).
    budget : int, optional
        Bytes of memory (default :func:`isoflow.scale.memory.default_budget`).

    Returns
    -------
    list of int
        The voxel layers of each slab, the same layers in all.

    Examples
    --------
    >>> grouped_layers([16] * 16, 256 * 256, budget=1 << 30)   # chunks 16 layers thick on a 256^2 cross-section
    [128, 128]
    >>> grouped_layers([16] * 4, 256 * 256, budget=32 << 20)  # 32 MiB: a quarter holds half a million voxels
    [16, 16, 16, 16]
    """
    from ..scale.memory import default_budget

    budget = default_budget() if budget is None else int(budget)
    cap = max(1, min(GROUP_VOXELS if most is None else int(most), budget // (4 * GROUP_BYTES_PER_VOXEL)))
    out: list[int] = []
    for n in (int(n) for n in layers):
        if out and (out[-1] + n) * area <= cap:
            out[-1] += n
        else:
            out.append(n)
    return out


class _Across:
    """A 3D array read in slabs along its axis ``axes[0]``, its axes in
    the order ``axes``: ``shape``, ``dtype`` and ``[a:b]`` as
    :func:`~isoflow.digital.label_table.slab_rows` reads them."""

    def __init__(self, array, axes: tuple[int, ...]) -> None:
        self.array, self.axes = array, axes
        self.shape = tuple(int(array.shape[i]) for i in axes)
        self.dtype = array.dtype
        chunks = None if isinstance(array, np.ndarray) else getattr(array, "chunks", None)
        # the chunks a read decodes whole, in the order read (SlabStream counts them)
        self.chunks = tuple(chunks[i] for i in axes) if chunks else None

    def __getitem__(self, layers: slice) -> np.ndarray:
        index = [slice(None)] * 3
        index[self.axes[0]] = layers
        # made labels before the axes move, so that a value that is no label is named at its voxel in the image
        vol = as_labels(self.array[tuple(index)], first_layer=layers.start or 0, axis=self.axes[0],
                        fill=getattr(self.array, "fill_value", None))
        return np.transpose(vol, self.axes)
