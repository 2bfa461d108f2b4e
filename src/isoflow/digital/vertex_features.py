"""What one lattice vertex adds to the row of each label it sees: the
feature table of the label table (:mod:`isoflow.digital.label_table`),
indexed by the vertex's configuration for that label (section 4).

A label's row of features is the product of its configuration histogram
with this table, whichever pass counts the configurations: the one vertex
pass over every label, or each label's own census
(:mod:`isoflow.digital.label_by_label`).
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .connectivity import check_connectivity
from .indices import NOT_WELL_COMPOSED, a_lut, class_lut, euler_lut
from .surface import face_slots, pinch_lut, slot_octants

#: the feature table's columns: the Euler share, the nine classes of ``n``,
#: not well-composed, ``a`` where well-composed, the energy, the pinches,
#: the face slots per normal axis
EULER, CLASSES, NWC, A_WC, ENERGY, PINCH, FACES = 0, slice(1, 10), 10, 11, 12, 13, slice(14, 17)
#: the feature table's width: a label's row of features
WIDTH = FACES.stop


@cache
def feature_table(connectivity: int = 6) -> np.ndarray:
    """(256, 17) int64: what one vertex of each configuration adds to its
    label's row: the Euler share ``8 x`` (eq. 4.10), one in its class's
    column of ``n`` (nine, eq. 4.9), one if it is not well-composed, ``a``
    and ``k = a^2`` where it is well-composed (eq. 4.12, 5.22), one at a
    pinch (:func:`~isoflow.digital.surface.pinch_lut`), and its boundary
    face slots per normal axis (four per face).

    Examples
    --------
    >>> from isoflow.digital.configurations import configuration_histogram
    >>> cube = np.ones((2, 2, 2), bool)
    >>> row = configuration_histogram(cube) @ feature_table(6)
    >>> int(row[EULER]) // 8, (row[FACES] // 4).tolist()  # chi of a cube, its faces per axis
    (1, [8, 8, 8])
    """
    check_connectivity(3, connectivity)
    cls = class_lut()
    a = a_lut(connectivity).astype(np.int64)
    on = cls >= 0
    out = np.zeros((256, WIDTH), np.int64)
    out[:, EULER] = euler_lut(3, connectivity)
    out[np.flatnonzero(on), 1 + cls[on]] = 1
    out[:, NWC] = cls == NOT_WELL_COMPOSED
    out[:, A_WC] = np.where(on, a, 0)
    out[:, ENERGY] = np.where(on, a * a, 0)
    out[:, PINCH] = pinch_lut(connectivity)
    codes = np.arange(256)
    for slot in range(12):
        lo, hi = slot_octants(slot)
        out[:, FACES.start + slot // 4] += ((codes >> lo) & 1) != ((codes >> hi) & 1)
    assert (out[:, FACES].sum(axis=1) == face_slots()).all()
    return out
