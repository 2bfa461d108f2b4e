"""Running the digital curvature flow (Definition 18) step after step.

:func:`run_flow` repeats the step of :mod:`isoflow.flow.motion` until the
object vanishes, for a number of steps, or until the topology would change,
and records per step the voxels, parity, Betti numbers, chi, energy
(eq. 5.22) and bounding box.

* **Without** ``guard`` consecutive states' Betti numbers are compared and
  each change is reported with the step and *where*: the world bounding box
  of the vertices whose plain move is not a simple deformation
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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..digital.analysis import analyze
from ..digital.lattice import DigitalObject
from ..errors import IsoflowError
from . import guard as control
from .motion import flow_connectivity, flow_moves


def _bbox_list(obj: DigitalObject):
    box = obj.bbox()
    return None if box is None else [box[0].tolist(), box[1].tolist()]


def _record(obj: DigitalObject, step: int, conn: int) -> dict:
    """Per-step figures: voxels, parity, Betti numbers, chi, energy, bbox."""
    r = analyze(obj, conn, surfaces=False)
    betti, chi, energy = r["betti"], r["euler_characteristic"], r["energy"]
    return {
        "step": step,
        "voxels": obj.voxels,
        "parity": obj.parity,
        "betti": list(map(int, betti)),
        "euler_characteristic": int(chi),
        "energy": int(energy),
        "bbox": _bbox_list(obj),
    }


def is_box(volume: np.ndarray) -> bool:
    """True when the non-empty volume, cropped, is a full box (a cuboid)."""
    if not volume.any():
        return False
    nz = np.argwhere(volume)
    lo, hi = nz.min(0), nz.max(0) + 1
    return bool(volume[tuple(slice(a, b) for a, b in zip(lo, hi))].all())


@dataclass
class FlowResult:
    """What :func:`run_flow` returns.

    ``steps``: one dict per state, step 0 the input (see :func:`_record`).
    ``states``: the objects themselves (when kept). ``stop_reason``:
    ``vanished`` (the object became empty), ``steps`` (the number of steps
    asked was done), ``topology-change`` (``until_topology_change``: stopped
    before the step that would change the Betti numbers), ``converged``
    (guarded: a fixed point, see :mod:`isoflow.flow.guard`), ``cycle``
    (plain: the shape repeats with period 2) or ``max-steps`` (safety cap of
    plain runs). ``limit``: ``center`` (world coordinates of
    the centre of the last non-empty state's bbox) and ``last_shape``
    (``cuboid`` when that state is a full box, ``other`` otherwise,
    ``not-reached`` when the run stopped before vanishing or converging).
    ``topology_changes``: one dict per change of the Betti numbers (step,
    before, after, where = world bbox, applied). ``guard_steps`` (guarded
    runs): how many steps were ``flow``, ``partial`` and ``thinning``.
    """

    steps: list[dict]
    states: list[DigitalObject]
    stop_reason: str
    limit: dict
    topology_changes: list[dict]
    connectivity: int
    guard: bool
    reversed_moves: int = 0
    guard_steps: dict | None = None

    def to_dict(self) -> dict:
        return {
            "connectivity": self.connectivity,
            "guard": self.guard,
            "stop_reason": self.stop_reason,
            "steps": self.steps,
            "limit": self.limit,
            "topology_changes": self.topology_changes,
            "reversed_moves": self.reversed_moves,
            **({"guard_steps": self.guard_steps} if self.guard else {}),
        }


def _limit(steps: list[dict], last_volume: np.ndarray | None, reached: bool) -> dict:
    last = next((s for s in reversed(steps) if s["voxels"] > 0), None)
    if last is None or not reached:
        return {"center": None, "last_shape": "not-reached", "last_step": None if last is None else last["step"]}
    lo, hi = np.array(last["bbox"][0]), np.array(last["bbox"][1])
    return {
        "center": ((lo + hi) / 2).tolist(),
        "last_shape": "cuboid" if is_box(last_volume) else "other",
        "last_step": last["step"],
    }


def default_max_steps(obj: DigitalObject) -> int:
    """Safety cap when no step count is given: a box of side s vanishes in
    s steps; four times the largest side plus 16 leaves room for the bar
    rule's growth."""
    return 4 * max(obj.volume.shape, default=0) + 16


def run_flow(
    obj: DigitalObject,
    steps: int | None = None,
    guard: bool = False,
    connectivity: int | None = 6,
    until_topology_change: bool = False,
    progress: Callable[[int, DigitalObject], None] | None = None,
    *,
    max_steps: int | None = None,
    keep_states: bool = True,
) -> FlowResult:
    """Run the digital curvature flow (Definition 18).

    Until the object vanishes (``steps=None``), or for ``steps`` steps, or,
    with ``until_topology_change``, until the next step would change the Betti
    numbers. ``guard`` applies topology control (module docstring).
    ``progress(step, obj)`` is called after every step.
    """
    obj = DigitalObject.of(obj)
    conn = flow_connectivity(obj.ndim, connectivity)
    for name, value in (("steps", steps), ("max_steps", max_steps)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0):
            raise IsoflowError(f"{name} must be an integer >= 0, got {value!r}")
    cap = steps if steps is not None else (default_max_steps(obj) if max_steps is None else max_steps)
    if guard and steps is None and max_steps is None:
        cap = None  # a guarded run reaches its fixed point (guard.py): no cap needed
    # guarded: flow steps that do not shrink the object, and the shapes seen
    allowance, seen = default_max_steps(obj), set()
    current = obj.cropped()
    records = [_record(current, 0, conn)]
    states = [current] if keep_states else []
    changes: list[dict] = []
    reversed_moves = 0
    kinds = {"flow": 0, "partial": 0, "thinning": 0}
    if guard:
        seen.add(control.shape_key(current))
    history = [current.volume]
    last_nonempty = current.volume if current.voxels else None
    stop = None
    step = 0
    while stop is None:
        if current.voxels == 0:
            stop = "vanished"
            break
        if cap is not None and step >= cap:
            stop = "steps" if steps is not None else "max-steps"
            break
        before = records[-1]["betti"]
        if guard:
            got = control.guarded_step(current, conn, before, seen=seen, may_grow=allowance > 0)
            if got.kind == "fixed-point":
                stop = "converged"
                break
            new = got.new
            reversed_moves += got.reversed_moves
            kinds[got.kind] += 1
            if new.voxels >= current.voxels:
                allowance -= 1
            seen.add(control.shape_key(new))
        else:
            cfg, keep = flow_moves(current, conn)
            new = current.on_dual_lattice(keep).cropped()
        rec = _record(new, step + 1, conn)
        if guard:
            rec["move"] = got.kind
            if rec["betti"] != before:  # simple deformations cannot do this
                raise RuntimeError(f"guarded {got.kind} step {step + 1} changed the Betti numbers {before} -> {rec['betti']}")
        elif rec["betti"] != before and new.voxels:
            change = {
                "step": step + 1,
                "before": before,
                "after": rec["betti"],
                "where": control.change_region(current, cfg, keep, conn),
                "applied": not until_topology_change,
            }
            changes.append(change)
            if until_topology_change:
                stop = "topology-change"
                break
        step += 1
        current = new
        records.append(rec)
        if keep_states:
            states.append(new)
        if new.voxels:
            last_nonempty = new.volume
        if progress is not None:
            progress(step, new)
        if not guard and len(history) >= 2 and _same(history[-2], new.volume) and new.voxels:
            stop = "cycle"
        history = (history + [new.volume])[-2:]
    reached = stop in ("vanished", "converged")
    return FlowResult(
        steps=records,
        states=states,
        stop_reason=stop,
        limit=_limit(records, last_nonempty, reached),
        topology_changes=changes,
        connectivity=conn,
        guard=guard,
        reversed_moves=reversed_moves,
        guard_steps=kinds if guard else None,
    )


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and np.array_equal(a, b)
