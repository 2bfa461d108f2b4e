"""The planar digital curvature flow (eq. 5.8, Definitions 12-13).

A 2D object is a set of unit squares; each lattice vertex has a 4-bit
configuration (bit ``d0 + 2 d1`` for pixel ``w - 1 + d``) and is convex (one
pixel of four), flat (two adjacent), concave (three) or not well-composed (two
diagonal pixels). One step centres the new pixels at the old vertices, on the
dual lattice (eq. 5.1), and keeps vertex ``w`` iff it is interior (all four
pixels) or moves outward:

* convex vertices move inward, concave vertices outward (eq. 5.8, first line);
* a flat vertex lies on a *segment*: the maximal run of equal configurations
  along the boundary's direction (the axis along which its two pixels lie).
  The segment is *negative* when an end (the first vertex past the run on
  either side) is concave, *positive* when both ends are convex (Definition
  13); negative segments move outward, positive ones inward (N- and N+ of
  eqs. 5.5-5.7);
* a not-well-composed vertex (two diagonal pixels, or two diagonal holes)
  follows the 3D rule: it goes to the side the contact joins -- inward under
  4-connectivity (the pixels are apart), outward under 8 (they are one
  pinched piece) -- and as a segment end it is negative exactly under 8.

A rectangle of a x b pixels becomes (a-1) x (b-1): it loses one row and one
column per step and vanishes at its centre.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from ..digital.configurations import configurations
from ..digital.indices import NOT_WELL_COMPOSED, planar_class_lut
from ..digital.lattice import DigitalObject
from ..errors import IsoflowError
from ..results import read_only
from .segments import segment_moves

__all__ = ["planar_flow_step", "planar_moves", "planar_motion_luts"]

_CONVEX, _FLAT, _CONCAVE = 0, 1, 2


@cache
def planar_motion_luts(connectivity: int = 4):
    """Tables over the 16 planar configurations: ``(keep, negative, role)``.

    ``keep``: moves outward whatever its segment (interior, concave, and the
    not-well-composed ones under 8); ``negative``: a negative segment end;
    ``role``: ``1 +`` the segment axis of a flat vertex (the axis along which
    its two pixels lie), 0 elsewhere.
    """
    if connectivity not in (4, 8):
        raise IsoflowError(f"planar connectivity is 4 or 8, got {connectivity}")
    cls = planar_class_lut()
    nwc = cls == NOT_WELL_COMPOSED
    keep = cls == _CONCAVE
    keep[15] = True
    negative = cls == _CONCAVE
    if connectivity == 8:
        keep |= nwc
        negative |= nwc
    role = np.zeros(16, np.int8)
    for c in np.flatnonzero(cls == _FLAT):
        a, b = [i for i in range(4) if c >> i & 1]
        role[c] = 1 if (a ^ b) == 1 else 2  # pixels differ in bit 0 (d0) or bit 1 (d1)
    for t in (keep, negative, role):
        t.setflags(write=False)
    return keep, negative, role


def planar_moves(volume: np.ndarray, connectivity: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """``(cfg, keep)`` of every vertex of a 2D volume (shape + 1)."""
    cfg = configurations(np.asarray(volume, bool))
    keep_lut, negative, role = planar_motion_luts(connectivity)
    keep = keep_lut[cfg]
    segment_moves(cfg, keep, negative, role)
    return cfg, keep


def planar_flow_step(obj: DigitalObject, connectivity: int = 4) -> DigitalObject:
    """One step of the planar flow (eq. 5.8) on a 2D object; the result is on
    the other lattice, cropped."""
    if obj.ndim != 2:
        raise IsoflowError(f"planar_flow_step needs a 2D object, got {obj.ndim}D")
    _, keep = planar_moves(obj.volume, connectivity)
    return obj.on_dual_lattice(read_only(keep)).cropped()  # handed over: no copy
