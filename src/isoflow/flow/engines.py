"""The two ways a run of the flow holds its states and steps them: NumPy
arrays (:class:`ArrayFlow`: :mod:`isoflow.flow.motion`,
:mod:`isoflow.flow.guard`, the reference) and bit rows (:class:`BitFlow`:
:mod:`isoflow.flow.bitflow`, :mod:`isoflow.flow.bitguard`, compiled).
Both give the same states and records, step for step; :func:`flow_engine`
chooses one for a run (``method``).
"""

from __future__ import annotations

import numpy as np

from ..digital.analysis import analyze
from ..digital.lattice import DigitalObject
from ..errors import IsoflowError
from ..results import read_only
from ..scale.compiled import METHODS, Method, have_numba
from . import guard as control
from .motion import flow_moves

#: from this many voxels ``auto`` takes the compiled steps: starting numba
#: (once per process) is then paid back within the first few dozen steps; a
#: caller that runs many small flows in one process says
#: ``method="compiled"``
COMPILED_VOXELS = 1 << 18


def step_record(obj: DigitalObject, step: int, conn: int) -> dict:
    """A state's figures: step, voxels, parity, Betti numbers, chi, energy
    (eq. 5.22) and the world bounding box (:func:`isoflow.digital.analysis.analyze`).

    Examples
    --------
    >>> import numpy as np
    >>> r = step_record(DigitalObject(np.ones((2, 2, 2), bool)), 0, 6)
    >>> r["voxels"], r["betti"], r["energy"]
    (8, [1, 0, 0], 8)
    """
    # the figures taken do not depend on the placement: the bare array
    # spares a far one's warning of world measures the record leaves out
    r = analyze(obj.volume, conn, surfaces=False)
    box = obj.bbox()
    return {
        "step": step,
        "voxels": obj.voxels,
        "parity": obj.parity,
        "betti": list(map(int, r["betti"])),
        "euler_characteristic": int(r["euler_characteristic"]),
        "energy": int(r["energy"]),
        "bbox": None if box is None else box[0].tolist() + box[1].tolist(),
    }


def is_box(volume: np.ndarray) -> bool:
    """True when the non-empty volume, cropped, is a full box (a cuboid).

    Examples
    --------
    >>> import numpy as np
    >>> v = np.zeros((4, 4, 4), bool); v[1:3, 1:3, 1:4] = True
    >>> is_box(v), is_box(np.eye(3, dtype=bool))
    (True, False)
    """
    if not volume.any():
        return False
    nz = np.argwhere(volume)
    lo, hi = nz.min(0), nz.max(0) + 1
    return bool(volume[tuple(slice(a, b) for a, b in zip(lo, hi))].all())


class ArrayFlow:
    """States as :class:`DigitalObject` arrays; the NumPy step and guard."""

    def __init__(self, conn: int):
        self.conn = conn

    def start(self, obj: DigitalObject) -> DigitalObject:
        return obj.cropped()

    def record(self, state: DigitalObject, step: int) -> dict:
        return step_record(state, step, self.conn)

    def step(self, state: DigitalObject) -> DigitalObject:
        _, keep = flow_moves(state, self.conn)
        return state.on_dual_lattice(read_only(keep)).cropped()  # handed over: no copy

    def change_region(self, state: DigitalObject, betti: tuple[list, list] | None = None):
        """Where the plain step from ``state`` is no simple deformation
        (:func:`isoflow.flow.guard.change_region`); ``betti``: the Betti
        numbers of ``state`` and of the next state, where known."""
        return control.change_region(state, *flow_moves(state, self.conn), self.conn, betti)

    def guarded(self, state: DigitalObject, betti: list[int], seen: set, may_grow: bool):
        got = control.guarded_step(state, self.conn, betti, seen=seen, may_grow=may_grow)
        return got.new, got.kind, got.reversed_moves

    def key(self, state: DigitalObject) -> bytes:
        return control.shape_key(state)

    def same(self, a: DigitalObject, b: DigitalObject) -> bool:
        return a.volume.shape == b.volume.shape and np.array_equal(a.volume, b.volume)

    def to_object(self, state: DigitalObject) -> DigitalObject:
        return state

    def discard(self, state: DigitalObject) -> None:
        """Let go of a state computed but not taken (the step that
        ``until_topology_change`` stops before); an array is simply dropped."""

    def is_cuboid(self, state: DigitalObject) -> bool:
        return is_box(state.volume)


class BitFlow(ArrayFlow):
    """States as bit rows (:class:`isoflow.flow.bitflow.PackedObject`);
    the compiled step and guard. Where a topology change is reported, the
    place is found on the arrays, as :class:`ArrayFlow` finds it, but for
    the vertices the step leaves stuck, found on the bit rows. (The bit
    row modules are imported on use: they start numba.)"""

    def start(self, obj: DigitalObject):
        from .bitflow import PackedObject

        return PackedObject.of(obj)

    def record(self, state, step: int) -> dict:
        from .bitflow import packed_record

        return packed_record(state, step, self.conn)

    def step(self, state):
        from .bitflow import packed_step

        return packed_step(state, self.conn)

    def change_region(self, state, betti: tuple[list, list] | None = None):
        from .bitguard import packed_stuck

        obj = state.to_object()
        return control.change_region(obj, *flow_moves(obj, self.conn), self.conn, betti, packed_stuck(state, self.conn))

    def guarded(self, state, betti: list[int], seen: set, may_grow: bool):
        from .bitguard import packed_guarded_step

        return packed_guarded_step(state, self.conn, betti, seen=seen, may_grow=may_grow)

    def key(self, state) -> bytes:
        from .bitguard import packed_key

        return packed_key(state)

    def same(self, a, b) -> bool:
        return a.same_shape(b)

    def to_object(self, state) -> DigitalObject:
        return state.to_object()

    def is_cuboid(self, state) -> bool:
        return state.voxels == int(np.prod(state.shape))


def flow_engine(method: Method, obj: DigitalObject, conn: int) -> ArrayFlow:
    """The way a run steps ``obj``: ``numpy`` (arrays), ``compiled`` (bit
    rows, numba), or ``auto``: compiled where numba is installed and the
    object has :data:`COMPILED_VOXELS` voxels in its array.

    Parameters
    ----------
    method : {"auto", "numpy", "compiled"}
        How to hold and step the states.
    obj : DigitalObject
        The run's input (its array's size decides ``auto``).
    conn : int
        The object's connectivity.

    Returns
    -------
    ArrayFlow
        :class:`ArrayFlow` or :class:`BitFlow`.

    Raises
    ------
    IsoflowError
        ``method`` is none of the three, or ``compiled`` without numba.

    Examples
    --------
    >>> import numpy as np
    >>> type(flow_engine("numpy", DigitalObject(np.ones((2, 2, 2), bool)), 6)).__name__
    'ArrayFlow'
    """
    if method not in METHODS:
        raise IsoflowError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if method == "compiled" and not have_numba():
        raise IsoflowError("method='compiled' needs numba (pip install numba)")
    compiled = method == "compiled" or (
        method == "auto" and have_numba() and obj.volume.size >= COMPILED_VOXELS)
    return BitFlow(conn) if compiled else ArrayFlow(conn)
