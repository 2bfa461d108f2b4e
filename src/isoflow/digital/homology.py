"""Exact Betti numbers of small 1D..4D images by GF(2) cubical homology, and
small images whose topology is known.

An independent check of the local tables (:mod:`isoflow.digital.indices`,
:mod:`isoflow.digital.ndim`):
``sum (-1)^i b_i`` from the boundary matrices of the cubical complex must
equal the Euler characteristic that the tables sum (eq. 6.2's exact form).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError
from ..scale import arrays
from .configurations import DIMENSIONS, check_dimension
from .connectivity import is_face_connectivity, resolve_connectivity
from .ndim import gf2_rank


def _cubical_faces(x: np.ndarray, face: bool) -> dict:
    """Present faces of the complex of ``x``: {axis subset A: bool grid}.

    A face is ``(p, A)``: base point ``p`` spanning the unit steps in the
    axes ``A``. Under the full adjacency the complex is the union of the
    closed cells (lattice faces, present iff ANY cell containing them is in
    X); under the face adjacency (``face``) it is the block complex on the
    cell centres (present iff ALL ``2^|A|`` cells are in X).
    """
    n = x.ndim
    faces = {}
    if not face:
        p = np.pad(x, 1)
        for A in itertools.product((0, 1), repeat=n):
            # base point p in original vertex coordinates. Along i in A the
            # face spans [p_i, p_i + 1], an edge of cell p_i only (p_i < S_i;
            # padded index p_i + 1); along i not in A it lies in cells p_i - 1
            # and p_i (p_i <= S_i; padded indices p_i and p_i + 1).
            shape = tuple(s if a else s + 1 for s, a in zip(x.shape, A))
            present = np.zeros(shape, dtype=bool)
            choices = [((1,) if a else (0, 1)) for a in A]
            for off in itertools.product(*choices):
                sl = tuple(slice(o, o + s) for o, s in zip(off, shape))
                present |= p[sl]
            faces[A] = present
    else:
        for A in itertools.product((0, 1), repeat=n):
            shape = tuple(max(s - a, 0) for s, a in zip(x.shape, A))
            present = np.ones(shape, dtype=bool)
            for off in itertools.product(*[((0, 1) if a else (0,)) for a in A]):
                sl = tuple(slice(o, o + s) for o, s in zip(off, shape))
                present &= x[sl]
            faces[A] = present
    return faces


def gf2_betti_numbers(volume: ArrayLike, connectivity: int | None = None,
                      max_faces: int = 200_000) -> tuple[int, ...]:
    """Betti numbers ``(b_0, ..., b_n)`` over GF(2) of a small 1D..4D image.

    Computed globally from the boundary matrices of the cubical complex that
    each connectivity reads (the two readings of
    :func:`isoflow.digital.indices.euler_lut`; no local table involved), so
    that ``sum (-1)^i b_i == euler_characteristic(X)`` is an independent
    check of the tables. Over GF(2) a 2-complex in R^4 can have
    torsion-dependent b_1, b_2 (e.g. a projective plane); chi never depends
    on the field. For 2D and 3D volumes of any size use
    :func:`isoflow.digital.topology.betti_numbers`.

    Parameters
    ----------
    volume : array_like of bool, 1 to 4 dimensions
    connectivity : int, optional
        The object's: ``2n`` (default) or ``3^n - 1``.
    max_faces : int
        The cost grows like the cube of the number of faces: more are refused.

    Returns
    -------
    tuple of int
        ``n + 1`` Betti numbers.

    Raises
    ------
    IsoflowError
        When the complex has more than ``max_faces`` faces.

    Examples
    --------
    A 4D box with a box-shaped hole through its middle: one component and one
    enclosed 4D cavity.

    >>> gf2_betti_numbers(box_minus_box(5, 1, 4))
    (1, 0, 0, 1, 0)
    """
    x = np.asarray(arrays.to_host(arrays.as_volume(volume, dims=DIMENSIONS)[1]))
    n = check_dimension(x.ndim)
    face = is_face_connectivity(resolve_connectivity(n, connectivity), n)
    faces = _cubical_faces(x, face)
    total = sum(int(f.sum()) for f in faces.values())
    if total > max_faces:
        raise IsoflowError(f"complex has {total} faces, more than max_faces={max_faces}")
    # index the present faces of each dimension
    index = {}
    counts = [0] * (n + 1)
    for A, present in faces.items():
        k = sum(A)
        ids = np.full(present.shape, -1, dtype=np.int64)
        nz = present.nonzero()
        ids[nz] = counts[k] + np.arange(len(nz[0]))
        counts[k] += len(nz[0])
        index[A] = ids
    ranks = [0] * (n + 2)
    for k in range(1, n + 1):
        columns = []
        for A, present in faces.items():
            if sum(A) != k:
                continue
            ids_by_face = []
            for axis in [i for i in range(n) if A[i]]:
                B = tuple(0 if i == axis else a for i, a in enumerate(A))
                sub = index[B]
                for off in (0, 1):
                    sl = [slice(None)] * n
                    # facet at p (off 0) and at p + e_axis (off 1)
                    sl[axis] = slice(off, off + present.shape[axis])
                    ids_by_face.append(sub[tuple(sl)][present])
            for row in zip(*ids_by_face):
                v = 0
                for i in row:
                    assert i >= 0, "a face of a present face must be present"
                    v ^= 1 << int(i)
                columns.append(v)
        ranks[k] = gf2_rank(columns)
    return tuple(counts[k] - ranks[k] - ranks[k + 1] for k in range(n + 1))


# --------------------------------------------------------------------------
# small constructors used by the docs and the tests


def product_image(*images) -> np.ndarray:
    """Cartesian product of binary images (dimensions add, chi multiplies)."""
    out = np.ones((), dtype=bool)
    for im in images:
        out = np.logical_and.outer(out, np.asarray(im, dtype=bool))
    check_dimension(out.ndim)
    return out


def box_minus_box(outer: int, inner: int, n: int) -> np.ndarray:
    """An ``outer^n`` box with a centred ``inner^n`` box removed (a cavity)."""
    n = check_dimension(n)
    if not 0 < inner <= outer - 2 or (outer - inner) % 2:
        raise IsoflowError("need 0 < inner <= outer - 2 with outer - inner even")
    x = np.ones((outer,) * n, dtype=bool)
    lo = (outer - inner) // 2
    x[(slice(lo, lo + inner),) * n] = False
    return x


def ball(radius: float, n: int) -> np.ndarray:
    """Cells whose centres lie within ``radius`` of the centre of the array."""
    n = check_dimension(n)
    size = 2 * math.ceil(radius) + 1
    g = np.indices((size,) * n) - (size - 1) / 2
    return (g**2).sum(axis=0) <= radius**2
