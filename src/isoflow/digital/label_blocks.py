"""The label table of a label image that does not fit in memory, read one
layer of blocks at a time (a zarr store: ``isoflow info LABELS.zarr
--labels``).

The passes of :mod:`isoflow.digital.label_table` run on each layer of
blocks along axis 0 (:func:`~isoflow.digital.label_table.slab_rows`, which
also reads an image in memory of more voxels than the pieces' 32-bit
numbers reach) with one voxel layer of each neighbour: the pieces of
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

from .connectivity import check_connectivity
from .float64 import unheld_columns
from .label_table import checked_image, columns, label_dtype, label_table, slab_rows, wanted_labels
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
    found = slab_rows(array, conn, wanted, surfaces, sizes, progress)
    return unheld_columns(columns(found, place.spacing, place.origin, surfaces), place.origin, place.spacing,
                          tuple(int(n) for n in array.shape))
