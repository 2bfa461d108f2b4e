"""Which cells count as neighbours: the object's connectivity and the background's.

The paper takes 6-connectivity for the object and so 26 for the background
(docs/mathematics.md); both pairs are offered wherever the answer depends on
it. In ``n`` dimensions the two are the face adjacency ``2n`` (cells sharing
an (n-1)-face: 2, 4, 6, 8 for n = 1..4) and the full adjacency ``3^n - 1``
(cells sharing any corner: 2, 8, 26, 80); the background always takes the
other one, so that a closed object separates its inside from its outside.
"""

from __future__ import annotations

import numpy as np

from ..errors import IsoflowError, given_text, whole_given

#: (face adjacency 2n, full adjacency 3^n - 1) per dimension
VALID = {1: (2, 2), 2: (4, 8), 3: (6, 26), 4: (8, 80)}


def check_connectivity(ndim: int, connectivity: int | np.integer) -> int:
    """The object's connectivity, checked against the dimension.

    A connectivity counts neighbours: a whole number, as every integer
    argument takes one (:func:`~isoflow.errors.whole_given`: an ``int``, a
    NumPy integer, a whole float such as ``6.0``, or a 0D array of one),
    never a bool (``True`` equals 1), ``6.5`` or the text ``"6"``.

    Examples
    --------
    >>> check_connectivity(3, 26), check_connectivity(3, np.array(26)), check_connectivity(3, 6.0)
    (26, 26, 6)
    >>> check_connectivity(3, 6.5)
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: connectivity 6.5 is not valid in 3D: it must be an integer (use 6 or 26)
    """
    allowed = " or ".join(map(str, sorted(set(VALID.get(ndim, ())))))
    whole = whole_given(connectivity)
    if whole is None:
        # text quoted: "connectivity 6 is not valid in 3D" of '6' contradicts itself
        raise IsoflowError(f"connectivity {given_text(connectivity)} is not valid in {ndim}D: it must be an integer "
                           f"(use {allowed})")
    if whole not in VALID.get(ndim, ()):
        raise IsoflowError(f"connectivity {given_text(connectivity)} is not valid in {ndim}D (use {allowed})")
    return whole


def default_connectivity(ndim: int) -> int:
    """The paper's choice: the face adjacency (4 in the plane, 6 in space)."""
    return VALID[ndim][0]


def resolve_connectivity(ndim: int, connectivity: int | np.integer | None) -> int:
    """The connectivity asked (checked), or the paper's default when None.

    Examples
    --------
    >>> resolve_connectivity(2, None), resolve_connectivity(3, None)
    (4, 6)
    """
    return check_connectivity(ndim, default_connectivity(ndim) if connectivity is None else connectivity)


def complement(ndim: int, connectivity: int) -> int:
    """The background's connectivity for an object's (6 <-> 26, 4 <-> 8, 8 <-> 80).

    Examples
    --------
    >>> complement(3, 6), complement(4, 80)
    (26, 8)
    """
    low, high = VALID[ndim]
    return high if connectivity == low else low


def is_face_connectivity(connectivity: int, ndim: int | None = None) -> bool:
    """Whether the object's pieces that meet only along an edge or at a
    vertex are apart: the face adjacency ``2 * ndim``. Without ``ndim``, for
    2D and 3D objects: 4 or 6 (8 is the face adjacency in 4D but the full
    one in 2D).

    Examples
    --------
    >>> is_face_connectivity(6), is_face_connectivity(8), is_face_connectivity(8, ndim=4)
    (True, False, True)
    """
    if ndim is None:
        return connectivity in (4, 6)
    return connectivity == VALID[ndim][0]
