"""The two ways a run of the flow holds its states and steps them: NumPy
arrays (:class:`ArrayFlow`: :mod:`isoflow.flow.motion`,
:mod:`isoflow.flow.guard`, the reference) and bit rows (:class:`BitFlow`:
:mod:`isoflow.flow.bitflow`, :mod:`isoflow.flow.bitguard`, compiled).
Both give the same states and records, step for step; :func:`flow_engine`
chooses one for a run (``method``), and ``"auto"`` may move a plain run
from the first to the second between two steps (:class:`AutoFlow`).
"""

from __future__ import annotations

import numpy as np

from ..digital.analysis import analyze
from ..digital.lattice import DigitalObject
from ..errors import IsoflowError
from ..results import read_only
from ..scale.compiled import Method, add_to_tally, check_method, have_numba, tallied
from . import guard as control
from .motion import flow_moves

#: a flow of this many voxels in its array takes the compiled steps from its
#: first one (unless capped at fewer than :data:`PAYBACK_STEPS` steps):
#: numba's start is paid back within its first few dozen steps
COMPILED_VOXELS = 1 << 18

#: the steps of a :data:`COMPILED_VOXELS` flow on the arrays that cost what
#: numba's start for the compiled step does (importing numba and loading the
#: step's and the record's machine code from its cache, once per process),
#: beyond what its compiled steps cost: a NumPy step with its record costs
#: a fixed part and about twenty times a compiled one's per voxel
#: (measured by ``benchmarks/bench_flow.py --only small``, the figures in
#: docs/flow.md); also the most steps ahead that ``"auto"`` counts on in a
#: run (:func:`weigh_flow`)
PAYBACK_STEPS = 32

#: a NumPy step's fixed cost over a compiled one's, in voxels of the
#: difference per voxel: small arrays cost more per voxel
STEP_VOXELS = 1 << 15

#: the work, in voxel-steps, whose NumPy steps cost what numba's start does
#: (:func:`weigh_flow`)
FLOW_WORK = COMPILED_VOXELS * PAYBACK_STEPS

#: the kind under which ``"auto"`` tallies the flow's NumPy steps
#: (:func:`isoflow.scale.compiled.tallied`), in voxel-steps
FLOW_TALLY = "flow steps"


def step_work(voxels: int) -> int:
    """The work of one NumPy flow step over an array of ``voxels`` voxels,
    in the voxel-steps of :data:`FLOW_WORK`.

    Examples
    --------
    >>> step_work(0) == STEP_VOXELS
    True
    """
    return int(voxels) + STEP_VOXELS


def weigh_flow(voxels: int, steps_ahead: int | None = None, record: bool = False) -> bool:
    """``"auto"``'s choice for the next flow step over an array of
    ``voxels`` voxels (numba installed): the compiled step where the work
    that ``"auto"`` has sent down the NumPy steps in this process
    (:func:`isoflow.scale.compiled.tallied` of :data:`FLOW_TALLY`) and the
    work this run has still ahead, ``steps_ahead`` steps of this array (at
    most :data:`PAYBACK_STEPS`; None: no cap), reach :data:`FLOW_WORK`.

    This is the ski-rental rule of :mod:`isoflow.scale.compiled`, in the
    unit that the cost of a flow is measured in. numba's start is paid once
    per process and each compiled step then saves about the same share of
    a NumPy step's cost per voxel, so what decides is the work of the NumPy
    steps, steps times voxels, not the voxels of one input: the threshold
    is where that work costs what the start does (:data:`PAYBACK_STEPS`
    steps of :data:`COMPILED_VOXELS` voxels, measured on whole steps with
    their records). So the question is asked before every step, not once
    per flow: a plain run of many steps over one small volume takes the
    compiled step from the step at which its own work reaches the
    threshold, and a loop of small flows from the step at which theirs
    does (:class:`AutoFlow`; a guarded run only at its start). The work
    ahead, up to :data:`PAYBACK_STEPS` steps, lets a large uncapped flow
    start compiled, as its first few dozen steps pay numba's start back,
    and keeps a run capped at a few steps on the arrays. ``record``: the
    step runs now, and a NumPy step's work is counted, as is the step that
    takes the tally past the threshold (so that it stays past it for the
    next flows).

    Parameters
    ----------
    voxels : int
        The voxels of the state's array.
    steps_ahead : int, optional
        The steps the run may still take (None: no cap).
    record : bool
        Count the step in the tally.

    Returns
    -------
    bool
        True: the compiled step.

    Examples
    --------
    >>> from isoflow.scale.compiled import reset_tally
    >>> reset_tally()  # (as a fresh process starts)
    >>> weigh_flow(COMPILED_VOXELS), weigh_flow(COMPILED_VOXELS, steps_ahead=1), weigh_flow(0)
    (True, False, False)
    """
    ahead = PAYBACK_STEPS if steps_ahead is None else max(1, min(int(steps_ahead), PAYBACK_STEPS))
    done = tallied(FLOW_TALLY)
    compiled = voxels > 0 and done + step_work(voxels) * ahead >= FLOW_WORK
    if record and compiled:
        paid()  # the later flows of the process take the compiled step at any size
    elif record and done < FLOW_WORK:
        add_to_tally(FLOW_TALLY, step_work(voxels))
    return compiled


def paid() -> None:
    """Mark numba's start for the flow step as paid in this process, as a
    compiled step (``method="compiled"``, or ``"auto"`` once it moved)
    pays it: the later ``"auto"`` flows take the compiled step from their
    first (:func:`weigh_flow`).

    Examples
    --------
    >>> from isoflow.scale.compiled import reset_tally
    >>> reset_tally(); paid(); weigh_flow(8)
    True
    """
    done = tallied(FLOW_TALLY)
    if done < FLOW_WORK:
        add_to_tally(FLOW_TALLY, FLOW_WORK - done)


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

        paid()
        return packed_step(state, self.conn)

    def change_region(self, state, betti: tuple[list, list] | None = None):
        from .bitguard import packed_stuck

        obj = state.to_object()
        return control.change_region(obj, *flow_moves(obj, self.conn), self.conn, betti, packed_stuck(state, self.conn))

    def guarded(self, state, betti: list[int], seen: set, may_grow: bool):
        from .bitguard import packed_guarded_step

        paid()
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


class AutoFlow(ArrayFlow):
    """``method="auto"`` (numba installed): a run on the arrays that asks
    :func:`weigh_flow` before each step (recording the NumPy steps in the
    tally) and holds its states as bit rows (:class:`BitFlow`) from the
    step that takes the compiled path on, or from its start where the
    first question says so. Both engines hold the same states and give the
    same records, so the run is the same whichever step it moves at; a
    state is stepped, recorded and compared by the engine that holds its
    kind. A guarded run (``move=False``) keeps the engine it starts with,
    as the shapes it has seen are keyed in that engine's form, and still
    counts its NumPy steps for the runs after it.

    Parameters
    ----------
    conn : int
        The object's connectivity.
    cap : int, optional
        The most steps the run takes (None: no cap).
    move : bool
        Move to bit rows between two steps.

    Examples
    --------
    >>> import numpy as np
    >>> engine = AutoFlow(6, cap=3)
    >>> state = engine.start(DigitalObject(np.ones((3, 3, 3), bool)))
    >>> engine.step(state).voxels
    8
    """

    def __init__(self, conn: int, cap: int | None = None, move: bool = True):
        super().__init__(conn)
        self.cap = cap
        self.move = move
        self.taken = 0
        self.bits = BitFlow(conn)

    def _holds_bits(self, state) -> bool:
        return not isinstance(state, DigitalObject)

    def _weigh(self, state: DigitalObject) -> bool:
        """Whether the step from ``state`` on the arrays moves to bit rows
        (the step is counted either way)."""
        ahead = None if self.cap is None else self.cap - self.taken
        self.taken += 1
        if self.move:
            return weigh_flow(state.volume.size, ahead, record=True)
        if tallied(FLOW_TALLY) < FLOW_WORK:
            # the step runs on the arrays whatever the rule says: its work
            # is counted as done, not numba's start as paid
            add_to_tally(FLOW_TALLY, step_work(state.volume.size))
        return False

    def start(self, obj: DigitalObject):
        state = obj.cropped()
        if weigh_flow(state.volume.size, self.cap):
            paid()
            return self.bits.start(state)
        return state

    def step(self, state):
        if self._holds_bits(state):
            return self.bits.step(state)
        if self._weigh(state):
            return self.bits.step(self.bits.start(state))
        return super().step(state)

    def guarded(self, state, betti: list[int], seen: set, may_grow: bool):
        if self._holds_bits(state):
            return self.bits.guarded(state, betti, seen, may_grow)
        self._weigh(state)
        return super().guarded(state, betti, seen, may_grow)

    def record(self, state, step: int) -> dict:
        return self.bits.record(state, step) if self._holds_bits(state) else super().record(state, step)

    def change_region(self, state, betti: tuple[list, list] | None = None):
        if self._holds_bits(state):
            return self.bits.change_region(state, betti)
        return super().change_region(state, betti)

    def key(self, state) -> bytes:
        return self.bits.key(state) if self._holds_bits(state) else super().key(state)

    def same(self, a, b) -> bool:
        if self._holds_bits(a) and self._holds_bits(b):
            return self.bits.same(a, b)
        return super().same(self.to_object(a), self.to_object(b))

    def to_object(self, state) -> DigitalObject:
        return self.bits.to_object(state) if self._holds_bits(state) else state

    def is_cuboid(self, state) -> bool:
        return self.bits.is_cuboid(state) if self._holds_bits(state) else super().is_cuboid(state)


def flow_engine(method: Method, obj: DigitalObject, conn: int, cap: int | None = None,
                guard: bool = False) -> ArrayFlow:
    """The way a run steps ``obj``: ``numpy`` (arrays), ``compiled`` (bit
    rows, numba), or ``auto``: where numba is installed, :class:`AutoFlow`,
    which takes the compiled steps from the step at which
    :func:`weigh_flow` says so (a guarded run: from its start or never),
    else the arrays.

    Parameters
    ----------
    method : {"auto", "numpy", "compiled"}
        How to hold and step the states.
    obj : DigitalObject
        The run's input.
    conn : int
        The object's connectivity.
    cap : int, optional
        The most steps the run takes (None: no cap), weighed by ``auto``.
    guard : bool
        The run is guarded.

    Returns
    -------
    ArrayFlow
        :class:`ArrayFlow`, :class:`AutoFlow` or :class:`BitFlow`.

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
    method = check_method(method)
    if method == "compiled" and not have_numba():
        raise IsoflowError("method='compiled' needs numba (pip install numba)")
    if method == "compiled":
        return BitFlow(conn)
    if method == "numpy" or not have_numba():
        return ArrayFlow(conn)
    return AutoFlow(conn, cap, move=not guard)
