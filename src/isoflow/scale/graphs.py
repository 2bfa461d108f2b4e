"""Connected components of a graph given as an edge list, compiled.

The welds, caps, face components and seams of the mesh layer each need the
components of a graph of up to a few million nodes. scipy's
``connected_components`` of a sparse matrix gives them, but importing
``scipy.sparse`` and ``csgraph`` is a large share of a short command's
start-up; the sweep's union-find (:func:`isoflow.scale.kernels.join_pairs`)
over the edge list gives the same numbering without it.
"""

from __future__ import annotations

import numpy as np

from .kernels import join_pairs


def components(n: int, a: np.ndarray, b: np.ndarray) -> tuple[int, np.ndarray]:
    """The connected components of the undirected graph on nodes ``0 .. n-1``
    with edges ``a[i] - b[i]``.

    Parameters
    ----------
    n : int
        Number of nodes.
    a, b : numpy.ndarray
        Integer arrays of equal length: the edges' ends (loops and repeated
        edges allowed).

    Returns
    -------
    count : int
        Number of components.
    labels : numpy.ndarray
        ``int64`` per node: its component, numbered ``0 .. count-1`` in the
        order of each component's smallest node (scipy's
        ``connected_components`` numbers them so too).

    Examples
    --------
    >>> import numpy as np
    >>> count, labels = components(5, np.array([3, 1]), np.array([4, 0]))
    >>> count, labels.tolist()
    (3, [0, 0, 1, 2, 2])
    """
    if n == 0:
        return 0, np.zeros(0, np.int64)
    # int32 below 2^31 nodes, as every other caller's parent array: one compile of the union-find
    roots = np.arange(n, dtype=np.int32 if n < 1 << 31 else np.int64)
    # joined under the smaller root and flattened: each node's root is its
    # component's smallest node
    join_pairs(roots, np.stack([np.asarray(a, np.int64), np.asarray(b, np.int64)], axis=1))
    is_root = roots == np.arange(n)
    rank = np.cumsum(is_root) - 1  # roots are their components' smallest nodes: rank in node order
    return int(is_root.sum()), rank[roots]
