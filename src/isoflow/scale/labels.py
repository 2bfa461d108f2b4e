"""Connected-component labels of host volumes, for the passes that label a
volume whole (small volumes, out-of-core blocks); large volumes take the
run-based union-find of :mod:`isoflow.scale.kernels` instead.

2D and 3D arrays are labelled by cc3d (connected-components-3d), other
dimensions by ``scipy.ndimage.label``. cc3d imports at once, where
``import scipy.ndimage`` parses the docstrings of its functions when the
package loads, a large share of what ``isoflow info`` waits for on a small
volume; cc3d also labels faster. Both number the components 1..n and give the same partition (the
tests compare them).

Two cc3d 4.1 bugs shape this: on *bool* input with 8-connectivity it may give
a background pixel a label (the count stays right), hence the uint8 view;
on arrays one voxel thick it may miscount or fail with 8- or
26-connectivity, hence scipy for those.
"""

from __future__ import annotations

import numpy as np


def rank(ndim: int, connectivity: int) -> int:
    """How many coordinates two neighbours may differ in (scipy's
    ``generate_binary_structure`` rank): 1 for the 2n-adjacency (4, 6, 8 in
    4D), 2 for 18 in 3D, n for the whole 3^n block."""
    if connectivity == 2 * ndim:
        return 1
    if (ndim, connectivity) == (3, 18):
        return 2
    if connectivity == 3**ndim - 1:
        return ndim
    raise ValueError(f"no {connectivity}-adjacency in {ndim}D")


def structure(ndim: int, connectivity: int) -> np.ndarray:
    """The 3^n neighbourhood of a connectivity as a boolean array (what
    ``scipy.ndimage.generate_binary_structure`` gives, without importing
    scipy.ndimage): the offsets with at most :func:`rank` nonzero
    coordinates."""
    offsets = np.indices((3,) * ndim) - 1
    return np.abs(offsets).sum(axis=0) <= rank(ndim, connectivity)


def label(mask: np.ndarray, connectivity: int, smallest: bool = False) -> tuple[np.ndarray, int]:
    """``(labels, n)``: the components of a boolean host array's True
    voxels under ``connectivity``, numbered 1..n (0 elsewhere), in C order
    whatever the mask's layout (as scipy's; cc3d keeps a Fortran-ordered
    mask's order). The labels are int32 (as scipy's; the compiled passes
    that read them are compiled for it), or with ``smallest`` the smallest
    unsigned type that holds them (cc3d's choice; scipy's int32 where scipy
    labels)."""
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim in (2, 3) and min(mask.shape) >= 2:
        import cc3d

        data = mask.view(np.uint8)
        # cc3d labels each nonzero value apart (a bool array made by
        # .view(bool) may hold bytes other than 1), and takes only writable
        # buffers (read-only arrays, np.load's memory maps)
        if not data.flags.writeable or (data.size and data.max() > 1):
            data = (data != 0).view(np.uint8)
        labels, n = cc3d.connected_components(data, connectivity=connectivity, return_N=True,
                                              out_dtype=None if smallest else np.uint32)
        if not smallest:  # signed, so that label arithmetic never wraps around
            labels = labels.view(np.int32) if n < 2**31 else labels.astype(np.int64)
        return np.ascontiguousarray(labels), int(n)
    from scipy.ndimage import label as scipy_label

    labels, n = scipy_label(mask, structure(mask.ndim, connectivity))
    return labels, int(n)
