"""The moves of one step of the digital curvature flow (section 5 of the paper).

One step (Definition 18, eq. 5.15-5.18) maps an object on one lattice to an
object on the other: the new voxels are centred at the old lattice vertices,
and vertex ``w`` becomes a voxel iff its configuration is 255 (interior) or it
is a boundary vertex that *moves outward* (docs/flow.md, "One step"):

=====================================================  =========================
class                                                  moves
=====================================================  =========================
convex corner (+,+,+), n=3 (+,+,-), saddle (-,-,-)-    inward
(+,-,-)+, n=5 (+,-,-), concave edge, concave corner    outward
convex edge (+,0,0)                                    outward iff *both* ends of
                                                       its edge segment are
                                                       negative (the bar rule)
flat (0,0,∅)                                           outward iff *any* end of
                                                       its two in-face segments
                                                       is negative (Def. 16)
not well-composed                                      inward under 6-, outward
                                                       under 26-connectivity
=====================================================  =========================

A *segment* through a vertex is the maximal run of vertices with the same
configuration along one axis: the edge's axis for a convex edge (the axis
whose code is ``+``), the two in-face axes for a flat vertex (the axes whose
code is ``0``; the ``∅`` axis is the normal). Its *ends* are the first
vertices past the run on either side; an end is *negative* when its index
``f`` (eq. 4.8) is below zero. Runs are found with a constant number of
whole-array passes per axis (:func:`~isoflow.flow.segments.segment_end_signs`: run starts by
comparison with the shifted array, a cumulative sum that numbers the runs,
then a look-up per edge or flat vertex); nothing loops over voxels.
(:mod:`isoflow.flow.segments`).

Vertices that are not well-composed
-----------------------------------
At such a vertex the eight octants are several face-connected pieces of
object or of background that touch only along an edge or at the vertex. The
connectivity pair says which side the contact belongs to: under
6-connectivity the *object* pieces are separate sheets (each a convex corner,
convex edge or n=3 piece, which move inward on their own) and the
*background* pieces are one pinched piece; under 26-connectivity it is the
other way round. The rule is therefore: **the vertex goes to the side that
the contact joins** -- it is dropped (inward) under 6-connectivity, so that
the new voxel centred there cannot fuse the separate object sheets, and kept
(outward) under 26-connectivity, so that the pinched object piece stays one
piece. As a segment end, such a vertex counts as negative exactly when it
moves outward (26). Where this local rule is not enough, topology control
(:mod:`isoflow.flow.guard`) catches the rest. In 2D the same rule holds for 4 (inward) and 8
(outward).

Lattices
--------
The new object lives on the other lattice: ``parity' = 1 - parity`` and
``offset' = offset - 1`` from parity 0, ``offset' = offset`` from parity 1, so
that new voxel ``w`` (array index = vertex index of the configuration array)
is the cube centred at old vertex ``w`` in world coordinates
(:meth:`DigitalObject.on_dual_lattice`). The result is cropped to its
bounding box.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from ..digital.configurations import configurations
from ..digital.connectivity import check_connectivity, is_face_connectivity
from ..digital.indices import (
    CONVEX,
    FLAT,
    NONE,
    NOT_WELL_COMPOSED,
    class_lut,
    code_lut,
    f_lut,
)
from ..digital.lattice import DigitalObject
from ..errors import IsoflowError, whole_given
from ..results import read_only
from .planar import planar_moves
from .segments import segment_moves

#: concave edge, concave corner
_OUTWARD_CLASSES = (8, 1, 2, 3)
_CONVEX_EDGE = 6
_FLAT = 4


# --------------------------------------------------------------------------
# Connectivity
# --------------------------------------------------------------------------


def flow_connectivity(ndim: int, connectivity: int | np.integer | None) -> int:
    """The object's connectivity for this dimension. In 2D, 6 and 26 (the 3D
    names of the smaller and the larger adjacency) read as 4 and 8."""
    if ndim not in (2, 3):
        raise IsoflowError(f"the digital curvature flow is defined for 2D and 3D objects, not {ndim}D")
    if connectivity is None:
        connectivity = 6
    planar = {6: 4, 26: 8}.get(whole_given(connectivity)) if ndim == 2 else None  # type: ignore[arg-type]  # None: no key
    if planar is not None:
        connectivity = planar
    return check_connectivity(ndim, connectivity)


# --------------------------------------------------------------------------
# Lookup tables of the motion (docs/flow.md, "One step")
# --------------------------------------------------------------------------


@cache
def motion_luts(connectivity: int = 6):
    """Tables over the 256 configurations that drive one 3D step.

    Returns ``(keep, negative, role)``: ``keep`` is True where the vertex
    moves outward whatever its segments (255, the four outward classes, and
    the not-well-composed configurations under 26); ``negative`` marks
    segment ends with ``f < 0`` (and the not-well-composed configurations
    under 26); ``role`` is ``1 + a`` for a convex edge along axis ``a`` (the
    axis whose code is ``+``), ``4 + a`` for a flat vertex with normal axis
    ``a`` (the ``∅`` axis), 0 elsewhere.
    """
    connectivity = check_connectivity(3, connectivity)
    cls, codes, f = class_lut(), code_lut(), f_lut()
    nwc = cls == NOT_WELL_COMPOSED
    keep = np.isin(cls, _OUTWARD_CLASSES)
    keep[255] = True
    negative = (cls >= 0) & (f < 0)
    if not is_face_connectivity(connectivity):
        keep |= nwc
        negative |= nwc
    role = np.zeros(256, np.int8)
    e = np.flatnonzero(cls == _CONVEX_EDGE)
    role[e] = 1 + np.argmax(codes[e] == CONVEX, axis=1)
    fl = np.flatnonzero(cls == _FLAT)
    assert np.all((codes[fl] == FLAT).sum(axis=1) == 2)
    role[fl] = 4 + np.argmax(codes[fl] == NONE, axis=1)
    for t in (keep, negative, role):
        t.setflags(write=False)
    return keep, negative, role



def flow_moves(obj: DigitalObject, connectivity: int | np.integer | None = 6) -> tuple[np.ndarray, np.ndarray]:
    """Configurations and outward moves of every lattice vertex (3D or 2D).

    Returns ``(cfg, keep)``, both shaped ``volume.shape + 1``: ``keep`` is
    True at the vertices that become voxels of the next object (interior or
    moving outward). ``cfg != 0 and cfg != full`` are the boundary vertices.
    """
    conn = flow_connectivity(obj.ndim, connectivity)
    if obj.ndim == 2:
        return planar_moves(obj.volume, conn)
    cfg = configurations(obj.volume)
    keep_lut, negative, role = motion_luts(conn)
    keep = keep_lut[cfg]
    segment_moves(cfg, keep, negative, role)
    return cfg, keep


def flow_step(obj: DigitalObject | ArrayLike, connectivity: int | np.integer | None = 6) -> DigitalObject:
    """One step of the digital curvature flow (Definition 18, eq. 5.15).

    Every lattice vertex becomes a voxel of the new object on the dual
    lattice (eq. 5.1) iff it is interior or a boundary vertex that moves
    outward: 3D objects by the table of the module docstring (eqs.
    5.15-5.18), 2D objects by the planar flow of eq. 5.8
    (:mod:`isoflow.flow.planar`).

    Parameters
    ----------
    obj : DigitalObject or array_like of bool
        A 2D or 3D object (a bare array sits at the origin of the lattice).
    connectivity : int, optional
        The object's: 6 or 26 in 3D, 4 or 8 in 2D, where 6 and 26 (the
        default 6 among them) are read as 4 and 8; None is the default.

    Returns
    -------
    DigitalObject
        On the other lattice (``parity`` flipped), cropped to its bounding box.

    Raises
    ------
    IsoflowError
        When the object is not 2D or 3D, or the connectivity is none of
        those.

    Examples
    --------
    The paper's Example 19: four cubes (a corner cube and its three face
    neighbours) become the cube centred at (1, 1, 1), then its point.

    >>> import numpy as np
    >>> v = np.zeros((2, 2, 2), bool)
    >>> v[0, 0, 0] = v[1, 0, 0] = v[0, 1, 0] = v[0, 0, 1] = True
    >>> step = flow_step(v)
    >>> step.voxels, step.parity, step.offset
    (1, 1, (0, 0, 0))

    A 2D object takes the default too, as 4-connectivity: an L of five
    pixels becomes an L of three on the dual lattice.

    >>> ell = np.zeros((3, 3), bool)
    >>> ell[0, :] = ell[:, 0] = True
    >>> flow_step(ell).volume.astype(int).tolist() == flow_step(ell, 4).volume.astype(int).tolist() == [[1, 1], [1, 0]]
    True
    """
    obj = DigitalObject.of(obj, "flow_step")  # a label image is offered flow_step of one label: a table is no flow
    if obj.volume.size == 0:
        # no voxel, so no vertex that stays: the empty object on the other
        # lattice, without the configurations of a volume long along its other axes
        flow_connectivity(obj.ndim, connectivity)  # refused as for any object
        return obj.on_dual_lattice().cropped()
    cfg, keep = flow_moves(obj, connectivity)
    return obj.on_dual_lattice(read_only(keep)).cropped()  # handed over: no copy
