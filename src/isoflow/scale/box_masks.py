"""Many labels' masks, each in its box, laid into one volume in one
compiled pass (the batches of :mod:`isoflow.digital.label_meshes`): a
label's mask is a comparison over its box, so a batch of thousands of
small boxes would otherwise cost thousands of NumPy calls, each mostly
its own overhead."""

from __future__ import annotations

import numpy as np

from .compiled import read_only_view
from .jit import njit


@njit(cache=True, nogil=True)
def box_masks(image, values, lo, extent, starts, out):
    """Box ``s`` of ``image`` (``lo[s]`` its first voxel, ``extent[s]`` its
    size) compared with ``values[s]``, written into ``out`` from layer
    ``starts[s]`` on along the first axis, at the first voxel of the other
    two: ``out[x:x + e0, :e1, :e2] = image[box] == values[s]``; the rest of
    ``out`` is left as it is.

    ``image`` and ``values`` come as their bytes, a last axis of one
    value's width (:func:`value_bytes`), compared byte by byte: one compile
    serves labels of every width and byte order (one per width was a first
    wait of seconds for each).

    Examples
    --------
    >>> import numpy as np
    >>> image = np.array([[[1, 2], [2, 2]]])
    >>> out = np.zeros((3, 2, 2), bool)
    >>> box_masks(value_bytes(image), value_bytes(np.array([2, 1])), np.array([[0, 0, 0], [0, 0, 0]]),
    ...           np.array([[1, 2, 2], [1, 1, 1]]), np.array([0, 2]), out)
    >>> out[0].astype(int).tolist(), out[2].astype(int).tolist()
    ([[0, 1], [1, 1]], [[1, 0], [0, 0]])
    """
    w = image.shape[3]
    for s in range(len(values)):
        x, value = starts[s], values[s]
        a0, a1, a2 = lo[s, 0], lo[s, 1], lo[s, 2]
        for i in range(extent[s, 0]):
            for j in range(extent[s, 1]):
                for k in range(extent[s, 2]):
                    voxel = image[a0 + i, a1 + j, a2 + k]
                    same = True
                    for b in range(w):
                        if voxel[b] != value[b]:
                            same = False
                            break
                    out[x + i, j, k] = same


def value_bytes(values: np.ndarray) -> np.ndarray:
    """An integer array's values as their bytes (in the array's own byte
    order), along a new last axis: a read-only view, no copy, whatever the
    array's layout, as :func:`box_masks` reads them.

    Examples
    --------
    >>> import numpy as np
    >>> value_bytes(np.array([1, 258], "<u2")).tolist()
    [[1, 0], [2, 1]]
    """
    return read_only_view(values[..., None].view(np.uint8))
