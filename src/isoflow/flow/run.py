"""Running the digital curvature flow (Definition 18) step after step.

:func:`run_flow` repeats the step of :mod:`isoflow.flow.motion` until the
object vanishes, for a number of steps, or until the topology would change,
and records per step the voxels, parity, Betti numbers, chi, energy
(eq. 5.22) and bounding box.

* **Without** ``guard`` consecutive states' Betti numbers are compared and
  each change is reported with the step and *where*: the world bounding box
  of the voxels around the vertices whose plain move is not a simple
  deformation, of the parts that vanish or fill whole there and of the
  cavities closed off, grown until the step taken inside it alone gives
  the new Betti numbers and outside it alone keeps the old ones
  (:func:`isoflow.flow.guard.change_region`); the bounding box of the new
  object when none is found. The last step, to the empty set, is the limit
  of the flow and not reported.
* **With** ``guard=True`` every step is
  :func:`isoflow.flow.guard.guarded_step`: the flow step carried out by
  simple deformations, else the part of it that keeps the Betti numbers,
  else a curvature-ordered thinning step on the same lattice; **no guarded
  step changes the Betti numbers**, and the run never stops half-way: it
  ends ``converged`` at a fixed point, a state with no simple voxel left
  that no flow step makes smaller or new (docs/flow.md). Each guarded
  step's record says which kind of step it was (``move``).

The states are held and stepped by one of :mod:`isoflow.flow.engines`
(NumPy arrays or bit rows, the same states); this module only decides when
to stop and what to report.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..digital.lattice import DigitalObject
from ..digital.measures import unheld_dropped
from ..errors import IsoflowError, check_callable, check_switch, given_text, whole_given
from ..results import Result
from .engines import ArrayFlow, Method, flow_engine
from .motion import flow_connectivity

__all__ = ["FlowResult", "GuardKind", "StopReason", "default_max_steps", "max_steps_for", "run_engine", "run_flow"]

#: why a run ended: the object became empty (``vanished``); the number of
#: steps asked was done (``steps``); ``until_topology_change`` stopped before
#: a step that changes the Betti numbers (``topology-change``); a guarded run
#: reached a fixed point (``converged``); a plain run's shape repeats with
#: period 2 (``cycle``); a plain run reached its safety cap (``max-steps``)
StopReason = Literal["vanished", "steps", "topology-change", "converged", "cycle", "max-steps"]
#: a guarded step: the whole flow step, the flow step with its stuck blocks
#: resolved, or a thinning step on the same lattice (isoflow.flow.guard)
GuardKind = Literal["flow", "partial", "thinning"]
#: what ``isoflow flow --json`` prints beside a result's fields: the input as
#: given (docs/flow.md)
FLOW_INPUT_KEYS = ("input",)


@dataclass(frozen=True, eq=False, repr=False)
class FlowResult(Result):
    """What :func:`run_flow` returns; it also reads as the mapping that
    ``isoflow flow --json`` prints (``r["steps"]`` is ``r.steps``; the
    states are an attribute only).

    Attributes
    ----------
    steps : list of dict
        One record per state, step 0 the input: step, voxels, parity,
        betti, euler_characteristic, energy, bbox (world: the min corner,
        then the max corner, one flat list as :func:`isoflow.analyze` gives), and
        in guarded runs the kind of step (``move``).
    states : list of DigitalObject
        The states themselves, when kept.
    stop_reason : StopReason
        Why the run ended (:data:`StopReason`).
    limit : dict
        ``center`` (world centre of the last non-empty state's bbox),
        ``last_shape`` (``cuboid`` when that state is a full box,
        ``other``, or ``not-reached`` when the run stopped before vanishing
        or converging, or had no non-empty state at all: an empty input,
        whose ``stop_reason`` is ``vanished``) and ``last_step``.
    topology_changes : list of dict
        One per change of the Betti numbers in a plain run: step, before,
        after, where (world bbox, as ``bbox``), applied.
    connectivity : int
        The object's connectivity (4 or 8 in 2D).
    guard : bool
        Whether topology control ran.
    reversed_moves : int
        Guarded runs: vertices whose move was reversed, over all steps.
    guard_steps : dict or None
        Guarded runs: how many steps were ``flow``, ``partial`` and
        ``thinning``.
    unit : str or None
        The length unit of the world coordinates (``bbox``, ``where``,
        ``center``): the input object's, None where it has none.
    space : str or None
        The anatomical frame of those coordinates (``"RAS"``, ``"LPS"``:
        :mod:`isoflow.digital.frames`): the input object's, None where it
        has none.

    Examples
    --------
    A 3x3x3 cube shrinks by one layer a step, from one lattice to the
    other, until it vanishes:

    >>> import numpy as np
    >>> r = run_flow(np.ones((3, 3, 3), bool))
    >>> r.stop_reason, [s["voxels"] for s in r.steps], [s.parity for s in r.states]
    ('vanished', [27, 8, 1, 0], [0, 1, 0, 1])
    >>> r["limit"]["last_shape"], r.to_dict()["guard"], r.unit
    ('cuboid', False, None)
    """

    steps: list[dict]
    states: list[DigitalObject]
    stop_reason: StopReason
    limit: dict
    topology_changes: list[dict]
    connectivity: int
    guard: bool
    reversed_moves: int = 0
    guard_steps: dict | None = None
    unit: str | None = None
    space: str | None = None

    def _keys(self) -> list[str]:
        # what ``isoflow flow --json`` prints (without ``input``), in its
        # order: the states are an attribute only, the guard's counts only
        # for guarded runs
        keys = ["unit", "space", "connectivity", "guard", "stop_reason", "steps", "limit", "topology_changes", "reversed_moves"]
        return keys + ["guard_steps"] if self.guard else keys

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> FlowResult:
        """The result of :meth:`to_dict`'s JSON (``isoflow flow --json``):
        the states are not in it, so none are kept, as with
        ``keep_states=False`` (``states`` given is taken). What the command
        prints about its input beside the result (:data:`FLOW_INPUT_KEYS`)
        is left out.

        Examples
        --------
        >>> import json, numpy as np
        >>> r = run_flow(np.ones((3, 3, 3), bool))
        >>> back = FlowResult.from_dict(json.loads(json.dumps(r.to_dict())))
        >>> back.to_dict() == r.to_dict(), back.states
        (True, [])
        """
        # the JSON holds no states, and states is a field without a default
        return super().from_dict({"states": [], **{k: v for k, v in values.items() if k not in FLOW_INPUT_KEYS}})


def default_max_steps(obj: DigitalObject) -> int:
    """Safety cap when no step count is given: a box of side s vanishes in
    s steps; four times the largest side plus 16 leaves room for the bar
    rule's growth."""
    return max_steps_for(obj.volume.shape)


def max_steps_for(shape: tuple[int, ...]) -> int:
    """:func:`default_max_steps` of an array of ``shape``.

    Examples
    --------
    >>> max_steps_for((10, 20, 5))
    96
    """
    return 4 * max(shape, default=0) + 16


def reachable_steps(steps: int | None, shape: tuple[int, ...]) -> int:
    """The last step a run of an array of ``shape`` is taken to reach, for
    the width of its file names and the length of its progress bar:
    ``steps`` where given, but never more than the plain run's cap
    (:func:`max_steps_for`), which a flow of that array ends before in
    every run measured (a box of side s vanishes in s steps); ``--steps
    1000000000000`` asks for far more steps than the object lasts.

    Parameters
    ----------
    steps : int or None
        The steps asked (None: until the object vanishes).
    shape : tuple of int
        The input array's shape.

    Returns
    -------
    int
        ``min(steps, max_steps_for(shape))``.

    Examples
    --------
    >>> reachable_steps(None, (10, 20, 5)), reachable_steps(10**12, (10, 20, 5)), reachable_steps(7, (10, 20, 5))
    (96, 96, 7)
    """
    cap = max_steps_for(shape)
    return cap if steps is None else min(steps, cap)


@dataclass
class _Trace:
    """What a run keeps as it goes: the records, the states (when kept), the
    last non-empty state; it tells ``progress`` of every new state."""

    engine: ArrayFlow
    keep_states: bool
    progress: Callable[[int, DigitalObject], object] | None
    records: list[dict] = field(default_factory=list)
    states: list[DigitalObject] = field(default_factory=list)
    last: Any = None

    def add(self, state, record: dict) -> None:
        self.records.append(record)
        if state.voxels:
            self.last = state
        tell = self.progress is not None and record["step"] > 0
        if self.keep_states or tell:
            obj = self.engine.to_object(state)
            if self.keep_states:
                self.states.append(obj)
            if tell and self.progress is not None:
                self.progress(record["step"], obj)


@dataclass
class _Guarded:
    """A guarded run's tallies: steps of each kind, moves reversed."""

    kinds: dict = field(default_factory=lambda: {"flow": 0, "partial": 0, "thinning": 0})
    reversed_moves: int = 0


def check_count(name: str, value) -> int | None:
    """A count of steps as a Python int (None as None), refused where it
    is no whole number >= 0 (a bool, ``1.5``, a negative number), naming
    the argument; ``3.0`` is 3, as :func:`~isoflow.errors.whole_given`
    takes every integer argument.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : object
        What was given.

    Returns
    -------
    int or None

    Raises
    ------
    IsoflowError
        One line naming ``name`` and ``value``.

    Examples
    --------
    >>> check_count("steps", 3), check_count("steps", np.array(3)), check_count("steps", 3.0), check_count("steps", None)
    (3, 3, 3, None)
    >>> check_count("steps", 1.5)
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: steps must be an integer >= 0, got 1.5
    """
    if value is None:
        return None
    whole = whole_given(value)
    if whole is None or whole < 0:
        raise IsoflowError(f"{name} must be an integer >= 0, got {given_text(value)}")
    return whole


def _plain(engine: ArrayFlow, state, trace: _Trace, cap: int | None, capped: StopReason,
           until_topology_change: bool) -> tuple[StopReason, list[dict]]:
    """Plain steps until the object vanishes, the cap, a cycle of period 2,
    or (``until_topology_change``) a change of the Betti numbers."""
    changes: list[dict] = []
    two_back = None
    step = 0
    while True:
        if state.voxels == 0:
            return "vanished", changes
        if cap is not None and step >= cap:
            return capped, changes
        new = engine.step(state)
        record = engine.record(new, step + 1)
        before = trace.records[-1]["betti"]
        if record["betti"] != before and new.voxels:
            where = engine.change_region(state, (before, record["betti"]))
            changes.append({"step": step + 1, "before": before, "after": record["betti"], "where": where,
                            "applied": not until_topology_change})
            if until_topology_change:
                engine.discard(new)  # not taken: a store the engine wrote for it goes too
                return "topology-change", changes
        step += 1
        trace.add(new, record)
        if two_back is not None and new.voxels and engine.same(two_back, new):
            return "cycle", changes
        two_back, state = state, new


def _guarded(engine: ArrayFlow, state, trace: _Trace, cap: int | None, capped: StopReason, allowance: int,
             tally: _Guarded) -> StopReason:
    """Guarded steps until the object vanishes, the cap, or a fixed point;
    ``allowance``: flow steps that may leave the object as large."""
    seen = {engine.key(state)}
    step = 0
    while True:
        if state.voxels == 0:
            return "vanished"
        if cap is not None and step >= cap:
            return capped
        before = trace.records[-1]["betti"]
        new, kind, n_reversed = engine.guarded(state, before, seen, allowance > 0)
        if kind == "fixed-point":
            return "converged"
        tally.reversed_moves += n_reversed
        tally.kinds[kind] += 1
        if new.voxels >= state.voxels:
            allowance -= 1
        seen.add(engine.key(new))
        record = engine.record(new, step + 1)
        record["move"] = kind
        if record["betti"] != before:  # simple deformations cannot do this
            raise RuntimeError(f"guarded {kind} step {step + 1} changed the Betti numbers {before} -> {record['betti']}")
        step += 1
        trace.add(new, record)
        state = new


def _limit(trace: _Trace, reached: bool) -> dict:
    last = next((s for s in reversed(trace.records) if s["voxels"] > 0), None)
    if last is None or not reached:
        return {"center": None, "last_shape": "not-reached", "last_step": None if last is None else last["step"]}
    box = np.array(last["bbox"])
    lo, hi = np.split(box, 2)
    return {
        "center": ((lo + hi) / 2).tolist(),
        "last_shape": "cuboid" if trace.engine.is_cuboid(trace.last) else "other",
        "last_step": last["step"],
    }


def run_flow(
    obj: DigitalObject | ArrayLike,
    steps: int | np.integer | None = None,
    guard: bool = False,
    connectivity: int | np.integer | None = 6,
    until_topology_change: bool = False,
    progress: Callable[[int, DigitalObject], object] | None = None,
    *,
    max_steps: int | np.integer | None = None,
    keep_states: bool = True,
    method: Method = "auto",
) -> FlowResult:
    """Run the digital curvature flow (Definition 18).

    Parameters
    ----------
    obj : DigitalObject or array_like
        A 2D or 3D object (a bare binary array sits at the origin).
    steps : int, optional
        Run this many steps at most; by default until the object vanishes
        (plain runs stop at :func:`default_max_steps`, guarded runs at
        their fixed point).
    guard : bool
        Topology control (module docstring): no step changes the Betti
        numbers.
    connectivity : int, optional
        6 or 26 (4 or 8 in 2D; 6 and 26 are read as those there).
    until_topology_change : bool
        Plain runs: stop before the first step that changes the Betti
        numbers.
    progress : callable, optional
        ``progress(step, state)`` after every step; what it returns is not
        used (a progress bar's ``update`` may return anything).
    max_steps : int, optional
        The cap of a run without ``steps``.
    keep_states : bool
        Keep every state in the result (``states``).
    method : {"auto", "numpy", "compiled"}
        How the states are held and stepped (:func:`isoflow.flow.engines.flow_engine`;
        ``auto``: the NumPy steps until their work in the process reaches
        numba's start, :func:`isoflow.flow.engines.weigh_flow`); every
        method gives the same result.

    Returns
    -------
    FlowResult
        The records of every state, why the run stopped, its limit and the
        topology changes.

    Raises
    ------
    IsoflowError
        A bad connectivity, dimension, step count or method.

    Notes
    -----
    One step is eqs. 5.15-5.18 (3D) or eq. 5.8 (2D); the energy is
    ``E = k^T n`` (eq. 5.22); the guard is built on Theorem 21.

    Examples
    --------
    >>> import numpy as np
    >>> r = run_flow(np.ones((3, 3, 3), bool), keep_states=False)
    >>> r.stop_reason, [s["voxels"] for s in r["steps"]]
    ('vanished', [27, 8, 1, 0])
    """
    obj = DigitalObject.of(obj, "run_flow")  # a label image is offered run_flow of one label: a table is no flow
    conn = flow_connectivity(obj.ndim, connectivity)
    check_callable(progress, "progress", "progress(step, state)")
    steps, max_steps = check_count("steps", steps), check_count("max_steps", max_steps)
    guard, until_topology_change, keep_states = (
        check_switch(guard, "guard", "run_flow"), check_switch(until_topology_change, "until_topology_change", "run_flow"),
        check_switch(keep_states, "keep_states", "run_flow"))
    cap: int | None = int(steps) if steps is not None else (default_max_steps(obj) if max_steps is None else int(max_steps))
    if guard and steps is None and max_steps is None:
        cap = None  # a guarded run reaches its fixed point (guard.py): no cap needed
    engine = flow_engine(method, obj, conn, cap, guard)
    result = run_engine(engine, engine.start(obj), cap=cap, capped="steps" if steps is not None else "max-steps",
                        guard=guard, until_topology_change=until_topology_change,
                        allowance=default_max_steps(obj), progress=progress, keep_states=keep_states, unit=obj.unit,
                        space=obj.space)
    return held_boxes(result, obj)


def held_boxes(result: FlowResult, obj: DigitalObject) -> FlowResult:
    """``result`` with the coordinates of its boxes (``bbox``, ``where``)
    and its limit point None along the axes where float64 cannot keep the
    voxel corners of ``obj``'s grid apart, said in one warning
    (:mod:`isoflow.digital.float64`); ``result`` itself elsewhere.

    Parameters
    ----------
    result : FlowResult
        A run of ``obj``.
    obj : DigitalObject
        The run's input, whose placement the boxes have.

    Returns
    -------
    FlowResult

    Examples
    --------
    >>> import warnings
    >>> far = DigitalObject(np.ones((2, 2, 2), bool), origin=(1e43, 0, 0))
    >>> with warnings.catch_warnings(record=True):
    ...     warnings.simplefilter("always")
    ...     held_boxes(run_flow(far, keep_states=False), far).steps[0]["bbox"]
    [None, 0.0, 0.0, None, 2.0, 2.0]
    """
    boxes = [s["bbox"] for s in result.steps] + [c["where"] for c in result.topology_changes] + [result.limit["center"]]
    kept = unheld_dropped(boxes, "the boxes and the limit point of the flow", obj.world(np.zeros(obj.ndim)),
                          obj.spacing, obj.volume.shape)
    if kept is boxes:
        return result
    steps = len(result.steps)
    return replace(result, steps=[{**s, "bbox": b} for s, b in zip(result.steps, kept[:steps])],
                   topology_changes=[{**c, "where": w} for c, w in zip(result.topology_changes, kept[steps:-1])],
                   limit={**result.limit, "center": kept[-1]})


def run_engine(engine: ArrayFlow, state, *, cap: int | None, capped: StopReason, guard: bool = False,
               until_topology_change: bool = False, allowance: int = 0,
               progress: Callable[[int, Any], object] | None = None, keep_states: bool = False,
               unit: str | None = None, space: str | None = None) -> FlowResult:
    """The run of :func:`run_flow` from a first state that ``engine`` holds
    (one of :mod:`isoflow.flow.engines`, or the stores of
    :mod:`isoflow.flow.chunked`): records, stops and the result.

    Parameters
    ----------
    engine : ArrayFlow
        Steps and records the states.
    state
        The first state, as ``engine.start`` gives it.
    cap : int or None
        The most steps; ``capped`` is the stop reason when it is reached.
    capped : StopReason
        ``steps`` or ``max-steps``.
    guard, until_topology_change, progress, keep_states
        As in :func:`run_flow`.
    allowance : int
        Guarded runs: flow steps that may leave the object as large.
    unit : str, optional
        The length unit of the first state's world coordinates.
    space : str, optional
        Their anatomical frame (``"LPS"``).

    Returns
    -------
    FlowResult

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow.flow.engines import ArrayFlow
    >>> engine = ArrayFlow(6)
    >>> r = run_engine(engine, engine.start(DigitalObject(np.ones((2, 2, 2), bool))), cap=5, capped="max-steps")
    >>> r.stop_reason, [s["voxels"] for s in r.steps]
    ('vanished', [8, 1, 0])
    """
    conn = engine.conn
    trace = _Trace(engine, keep_states, progress)
    trace.add(state, engine.record(state, 0))
    changes: list[dict] = []
    tally = _Guarded()
    if guard:
        stop = _guarded(engine, state, trace, cap, capped, allowance, tally)
    else:
        stop, changes = _plain(engine, state, trace, cap, capped, until_topology_change)
    return FlowResult(
        steps=trace.records,
        states=trace.states,
        stop_reason=stop,
        limit=_limit(trace, stop in ("vanished", "converged")),
        topology_changes=changes,
        connectivity=conn,
        guard=guard,
        reversed_moves=tally.reversed_moves,
        guard_steps=tally.kinds if guard else None,
        unit=unit,
        space=space,
    )
