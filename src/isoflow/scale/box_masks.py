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

    ``image`` and ``values`` come as unsigned integers of their width in
    the machine's byte order (:func:`as_unsigned`, a view): equality is of
    the bytes alone, so one compile for each width serves signed and
    unsigned labels in either byte order.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.array([[[1, 2], [2, 2]]])
    >>> out = np.zeros((3, 2, 2), bool)
    >>> box_masks(as_unsigned(image), as_unsigned(np.array([2, 1])), np.array([[0, 0, 0], [0, 0, 0]]),
    ...           np.array([[1, 2, 2], [1, 1, 1]]), np.array([0, 2]), out)
    >>> out[0].astype(int).tolist(), out[2].astype(int).tolist()
    ([[0, 1], [1, 1]], [[1, 0], [0, 0]])
    """
    for s in range(len(values)):
        x, value = starts[s], values[s]
        a0, a1, a2 = lo[s, 0], lo[s, 1], lo[s, 2]
        for i in range(extent[s, 0]):
            for j in range(extent[s, 1]):
                for k in range(extent[s, 2]):
                    out[x + i, j, k] = image[a0 + i, a1 + j, a2 + k] == value


def as_unsigned(values: np.ndarray) -> np.ndarray:
    """An integer array as unsigned integers of its width in the machine's
    byte order: a read-only view of the same bytes, no copy, as
    :func:`box_masks` compares them (two values are equal iff their
    bytes are).

    Examples
    --------
    >>> import numpy as np
    >>> v = as_unsigned(np.array([-1, 258], ">i2"))
    >>> v.dtype.name, v.dtype.isnative, v.flags.writeable
    ('uint16', True, False)
    """
    return read_only_view(values.view(np.dtype(f"u{values.dtype.itemsize}").newbyteorder("=")))
