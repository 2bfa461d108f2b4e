"""The digital curvature flow (section 5 of the paper) and topology control.

One step (Definition 18, eq. 5.15-5.18) maps an object on one lattice to an
object on the other: the new voxels are centred at the old lattice vertices,
and vertex ``w`` becomes a voxel iff its configuration is 255 (interior) or it
is a boundary vertex that *moves outward* (DESIGN section 4):

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
whole-array passes per axis (:func:`segment_end_signs`: run starts by
comparison with the shifted array, a cumulative sum that numbers the runs,
then a look-up per edge or flat vertex); nothing loops over voxels.

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
(below) catches the rest. In 2D the same rule holds for 4 (inward) and 8
(outward).

Lattices
--------
The new object lives on the other lattice: ``parity' = 1 - parity`` and
``offset' = offset - 1`` from parity 0, ``offset' = offset`` from parity 1, so
that new voxel ``w`` (array index = vertex index of the configuration array)
is the cube centred at old vertex ``w`` in world coordinates. The result is
cropped to its bounding box.

Topology control (Theorem 21)
-----------------------------
Refine the grid twice: old voxel ``v`` is a block of ``2^n`` fine cells, and
so is the new voxel centred at vertex ``w``; the fine cell of the new block
in octant ``e`` of ``w`` lies in old voxel ``w - 1 + e``. The old object is
thus the new blocks each holding the octants of its configuration, and a
step fills the blocks of the outward moves and empties those of the inward
moves. :func:`isoflow.guard.realise_moves` does that **one fine cell at a time, a cell only
when it is a simple point** (Bertrand's topological numbers in its 3x3x3
neighbourhood are 1 for the object and for the background, with the
connectivity pair asked; :func:`isoflow.guard.simple_points`). Blocks of one sub-lattice
class (``w`` modulo 2) are two fine cells apart, so a whole class is tested at
once, and a block's ``2^n`` octants go one after the other; sweeps repeat
until nothing changes. A block that cannot reach its move is *stuck*: its
move is reversed (inward <-> outward) once and the sweeps go on. When no
block is left stuck, the new object is reached from the old one by simple
deformations only, so nothing was split, merged, opened or closed -- not even
a split and a merge at once that would leave the Betti numbers equal.

* **Without** ``guard`` :func:`run_flow` compares the Betti numbers of
  consecutive states and reports each change with the step and *where*: the
  world bounding box of the vertices whose plain move is not a simple
  deformation (the stuck blocks, without reversing them); the bounding box of
  the new object when none is found. The last step, to the empty set, is the
  limit of the flow and not reported.
* **With** ``guard=True`` every step is :func:`isoflow.guard.guarded_step`: the plain moves
  carried out by :func:`isoflow.guard.realise_moves`, the stuck ones reversed. If blocks
  stay stuck both ways, three last resorts (the stuck vertices with their
  plain move, all outward, all inward) are tried; the first one whose Betti
  numbers equal the current ones is taken, and if none does the run stops,
  ``guard-blocked``, before that step. Every guarded step is checked with the
  full Betti numbers, so **no guarded step changes them**. Under the guard
  the object never vanishes (that would change b0): when a guarded step gives
  back the same shape (typically one voxel per component, on one corner of
  the last box) the run ends ``converged``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Callable

import numpy as np

from .configurations import configurations
from .errors import IsoflowError
from .indices import (
    CONVEX,
    FLAT,
    NONE,
    NOT_WELL_COMPOSED,
    class_lut,
    code_lut,
    f_lut,
)
from .lattice import DigitalObject
from .topology import check_connectivity

__all__ = [
    "FlowResult",
    "check_output_dir",
    "default_max_steps",
    "export_flow",
    "flow_moves",
    "flow_step",
    "flow_table",
    "is_box",
    "motion_luts",
    "run_flow",
    "segment_end_signs",
]

#: classes (gamma + 4) of eq. 4.6 that always move outward: (+,-,-)+, n=5,
#: concave edge, concave corner
_OUTWARD_CLASSES = (8, 1, 2, 3)
_CONVEX_EDGE = 6
_FLAT = 4


# --------------------------------------------------------------------------
# Connectivity
# --------------------------------------------------------------------------


def flow_connectivity(ndim: int, connectivity: int | None) -> int:
    """The object's connectivity for this dimension. In 2D, 6 and 26 (the 3D
    names of the smaller and the larger adjacency) read as 4 and 8."""
    if ndim not in (2, 3):
        raise IsoflowError(f"the digital curvature flow is defined for 2D and 3D objects, not {ndim}D")
    if connectivity is None:
        connectivity = 6
    if ndim == 2 and connectivity in (6, 26):
        connectivity = {6: 4, 26: 8}[connectivity]
    return check_connectivity(ndim, connectivity)


def _is_min(connectivity: int) -> bool:
    """True for the face connectivity (6 in 3D, 4 in 2D)."""
    return connectivity in (4, 6)


# --------------------------------------------------------------------------
# Lookup tables of the motion (DESIGN section 4)
# --------------------------------------------------------------------------


@lru_cache(maxsize=None)
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
    if not _is_min(connectivity):
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


def _segment_moves(cfg: np.ndarray, keep: np.ndarray, negative: np.ndarray, role: np.ndarray) -> None:
    """Set ``keep`` at the convex edges whose two ends are negative and the
    flat vertices with a negative end on a segment along an in-face axis
    (``role`` as in :func:`motion_luts`: edges 1..n, flats n+1..2n; in 2D
    the flats' role is ``1 + segment axis`` and they behave like flats)."""
    nd = cfg.ndim
    r_all = role[cfg]
    points = np.nonzero(r_all)
    if len(points[0]) == 0:
        return
    r = r_all[points]
    del r_all
    if nd == 2:
        edge_axis = np.full(len(r), -1)
        flat_axes = [r == 1 + a for a in range(nd)]
    else:
        edge_axis = np.where(r <= nd, r - 1, -1)
        normal = r - 1 - nd
        flat_axes = [(r > nd) & (normal != a) for a in range(nd)]
    edges_ok = np.ones(len(r), bool)
    flats_ok = np.zeros(len(r), bool)
    for axis in range(nd):
        on_edge = edge_axis == axis
        on_flat = flat_axes[axis]
        sel = np.flatnonzero(on_edge | on_flat)
        if len(sel) == 0:
            continue
        before, after = segment_end_signs(cfg, negative, axis, tuple(p[sel] for p in points))
        e_here = on_edge[sel]
        edges_ok[sel[e_here]] = before[e_here] & after[e_here]
        f_here = on_flat[sel]
        flats_ok[sel[f_here]] |= before[f_here] | after[f_here]
    moved = np.where(edge_axis >= 0, edges_ok, flats_ok)
    keep[tuple(p[moved] for p in points)] = True


def segment_end_signs(
    cfg: np.ndarray, negative: np.ndarray, axis: int, points: tuple[np.ndarray, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Are the two ends of the segment through each of ``points`` negative?

    A segment is the maximal run of equal configurations along ``axis``; its
    ends are the vertices just before and just after the run. ``points`` is a
    tuple of index arrays (as from ``np.nonzero``); returns two boolean arrays
    over them: the end before the run is negative, the end after it is
    negative (``negative`` is a table over configurations). Vertices past the
    array are background (config 0, not negative).

    Run-length work on the lines along ``axis`` laid out contiguously: one
    comparison with the shifted array marks the run starts, one
    ``flatnonzero`` lists them and one cumulative sum numbers the runs; a
    point's run number gives its run's first vertex, the next run's start
    one past its last. A constant number of passes, then work proportional
    to the number of points.
    """
    lines = np.ascontiguousarray(np.moveaxis(cfg, axis, -1))
    n = lines.shape[-1]
    flat = lines.reshape(-1, n)
    total = flat.size
    change = np.empty(flat.shape, bool)
    change[:, 0] = True
    np.not_equal(flat[:, 1:], flat[:, :-1], out=change[:, 1:])
    starts = np.flatnonzero(change)
    itype = np.int32 if total < 2**31 else np.int64
    run_of = np.cumsum(change.ravel(), dtype=itype)  # 1 + run number of every vertex
    del change
    others = [points[d] for d in range(cfg.ndim) if d != axis]
    q = np.ravel_multi_index((*others, points[axis]), lines.shape)
    run = run_of[q] - 1
    del run_of
    first = starts[run]
    nxt = np.append(starts, total)[run + 1]  # start of the next run: one past the end
    values = flat.ravel()
    before = (first % n != 0) & negative[values[first - 1]]
    after_ok = nxt % n != 0  # the run ends inside the line (nxt == total gives 0 too)
    after = after_ok & negative[values[np.minimum(nxt, total - 1)]]
    return before, after


def _shifted_object(obj: DigitalObject, volume: np.ndarray) -> DigitalObject:
    """Put a vertex-indexed array on the other lattice (see module doc)."""
    offset = tuple(o - 1 for o in obj.offset) if obj.parity == 0 else obj.offset
    return replace(obj, volume=volume, offset=offset, parity=1 - obj.parity)


def flow_moves(obj: DigitalObject, connectivity: int | None = 6) -> tuple[np.ndarray, np.ndarray]:
    """Configurations and outward moves of every lattice vertex (3D or 2D).

    Returns ``(cfg, keep)``, both shaped ``volume.shape + 1``: ``keep`` is
    True at the vertices that become voxels of the next object (interior or
    moving outward). ``cfg != 0 and cfg != full`` are the boundary vertices.
    """
    conn = flow_connectivity(obj.ndim, connectivity)
    if obj.ndim == 2:
        from .planar import planar_moves

        return planar_moves(obj.volume, conn)
    cfg = configurations(obj.volume)
    keep_lut, negative, role = motion_luts(conn)
    keep = keep_lut[cfg]
    _segment_moves(cfg, keep, negative, role)
    return cfg, keep


def flow_step(obj: DigitalObject, connectivity: int | None = 6) -> DigitalObject:
    """One step of the digital curvature flow (Definition 18, eq. 5.15).

    3D objects follow the table of the module docstring; 2D objects the
    planar flow of eq. 5.8 (:func:`isoflow.planar.planar_flow_step`). The
    result sits on the other lattice and is cropped to its bounding box.
    ``obj`` may also be a bare binary array.
    """
    obj = DigitalObject.of(obj)
    cfg, keep = flow_moves(obj, connectivity)
    return _shifted_object(obj, keep).cropped()


# --------------------------------------------------------------------------
# Running the flow
# --------------------------------------------------------------------------


def _bbox_list(obj: DigitalObject):
    box = obj.bbox()
    return None if box is None else [box[0].tolist(), box[1].tolist()]


def _record(obj: DigitalObject, step: int, conn: int) -> dict:
    """Per-step figures: voxels, parity, Betti numbers, chi, energy, bbox."""
    from .analysis import analyze

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
    before the step that would change the Betti numbers), ``guard-blocked``
    (no repair restores them), ``converged`` (guarded: the step would give
    back the same shape), ``cycle`` (the shape repeats with period 2) or
    ``max-steps`` (safety cap). ``limit``: ``center`` (world coordinates of
    the centre of the last non-empty state's bbox) and ``last_shape``
    (``cuboid`` when that state is a full box, ``other`` otherwise,
    ``not-reached`` when the run stopped before vanishing or converging).
    ``topology_changes``: one dict per change of the Betti numbers (step,
    before, after, where = world bbox, applied).
    """

    steps: list[dict]
    states: list[DigitalObject]
    stop_reason: str
    limit: dict
    topology_changes: list[dict]
    connectivity: int
    guard: bool
    reversed_moves: int = 0

    def to_dict(self) -> dict:
        return {
            "connectivity": self.connectivity,
            "guard": self.guard,
            "stop_reason": self.stop_reason,
            "steps": self.steps,
            "limit": self.limit,
            "topology_changes": self.topology_changes,
            "reversed_moves": self.reversed_moves,
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
    from . import guard as control  # it builds on flow_moves, so it is imported here

    obj = DigitalObject.of(obj)
    conn = flow_connectivity(obj.ndim, connectivity)
    for name, value in (("steps", steps), ("max_steps", max_steps)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0):
            raise IsoflowError(f"{name} must be an integer >= 0, got {value!r}")
    cap = steps if steps is not None else (default_max_steps(obj) if max_steps is None else max_steps)
    current = obj.cropped()
    records = [_record(current, 0, conn)]
    states = [current] if keep_states else []
    changes: list[dict] = []
    reversed_moves = 0
    history = [current.volume]
    last_nonempty = current.volume if current.voxels else None
    stop = None
    step = 0
    while stop is None:
        if current.voxels == 0:
            stop = "vanished"
            break
        if step >= cap:
            stop = "steps" if steps is not None else "max-steps"
            break
        before = records[-1]["betti"]
        if guard:
            got = control.guarded_step(current, conn, before)
            if got is None:
                stop = "guard-blocked"
                break
            new, n_reversed = got
            reversed_moves += n_reversed
            if _same(new.volume, current.volume):
                stop = "converged"
                break
        else:
            cfg, keep = flow_moves(current, conn)
            new = _shifted_object(current, keep).cropped()
        rec = _record(new, step + 1, conn)
        if rec["betti"] != before and not guard and new.voxels:
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
        if len(history) >= 2 and _same(history[-2], new.volume) and new.voxels:
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
    )


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and np.array_equal(a, b)


# --------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------


def flow_table(result: FlowResult) -> tuple[list[str], list[list]]:
    """The per-step figures as CSV columns and rows (bbox as min/max per axis)."""
    nd = len(result.steps[0]["betti"])
    ndim = 3 if nd == 3 else 2
    axes = "xyz"[:ndim]
    header = ["step", "voxels", "parity"] + [f"b{i}" for i in range(nd)]
    header += ["euler_characteristic", "energy"]
    header += [f"bbox_min_{a}" for a in axes] + [f"bbox_max_{a}" for a in axes]
    rows = []
    for s in result.steps:
        box = s["bbox"] or [[""] * ndim, [""] * ndim]
        rows.append([s["step"], s["voxels"], s["parity"], *s["betti"], s["euler_characteristic"], s["energy"], *box[0], *box[1]])
    return header, rows


def check_output_dir(directory, force: bool = False):
    """The output directory as a Path; refuses a file, or a directory that
    already holds files unless ``force``."""
    from pathlib import Path

    out = Path(directory)
    if out.exists() and not out.is_dir():
        raise IsoflowError(f"{out}: exists and is not a directory")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise IsoflowError(f"{out}: directory is not empty; pass --force to overwrite its files")
    return out


def export_flow(result: FlowResult, directory, force: bool = False, plot: bool = True) -> list:
    """Write a flow's files into ``directory``: ``step_NNN.ply`` (the boundary
    surface of every non-empty 3D state, world coordinates, per-vertex
    curvature data), ``flow.csv`` (one row per step), ``flow.png`` (voxels,
    energy and Betti numbers against the step) and, in 3D, ``shapes.png``
    (the object at a few steps).

    Refuses a directory that already holds files unless ``force``. Needs a
    result run with ``keep_states=True``; :class:`FlowWriter` writes the same
    files while the flow runs, without keeping the states.
    """
    if not result.states and result.steps:
        raise IsoflowError("export_flow needs the states: run the flow with keep_states=True")
    writer = FlowWriter(directory, result.connectivity, force, last_step=len(result.steps) - 1)
    for rec, state in zip(result.steps, result.states):
        writer.add(rec["step"], state)
    return writer.finish(result, plot=plot)


class FlowWriter:
    """Writes a flow's files step by step (see :func:`export_flow`).

    Pass :meth:`add` as (part of) ``run_flow``'s ``progress`` callback, after
    adding the input as step 0, and run with ``keep_states=False``: memory
    then stays that of one state plus the few kept for ``shapes.png``, where
    keeping every state of a shrinking box of side s costs about s^4/4 bytes.
    ``force`` also removes the files a previous flow left (``step_*.ply``, the
    CSV and pictures), so that no stale step survives beside the new ones.
    """

    #: states kept for shapes.png: at most twice the panels, evenly spaced
    PANELS = 6

    def __init__(self, directory, connectivity: int, force: bool = False, last_step: int = 999):
        out = check_output_dir(directory, force)
        out.mkdir(parents=True, exist_ok=True)
        if force:
            for old in [*out.glob("step_*.ply"), *(out / n for n in ("flow.csv", "flow.png", "shapes.png"))]:
                if old.is_file():
                    old.unlink()
        self.out, self.connectivity = out, connectivity
        self.width = max(3, len(str(last_step)))
        self.written: list = []
        self.frames: list = []  # (step, state), every `stride`-th step
        self.stride = 1
        self.last = None  # the last non-empty (step, state)

    def add(self, step: int, state: DigitalObject) -> None:
        from . import io
        from .surface import boundary_mesh

        if not state.voxels:
            return
        self.last = (step, state)
        if step % self.stride == 0:
            self.frames.append((step, state))
            if len(self.frames) > 2 * self.PANELS:
                self.frames = self.frames[::2]
                self.stride *= 2
        if state.ndim != 3:
            return
        mesh = boundary_mesh(state.volume, self.connectivity)
        path = self.out / f"step_{step:0{self.width}d}.ply"
        comments = (f"isoflow flow step {step}, parity {state.parity}, {self.connectivity}-connectivity",)
        io.write_ply(path, io.mesh_vertex_table(mesh, state), mesh.polygons(), force=True, comments=comments)
        self.written.append(path)

    def finish(self, result: FlowResult, plot: bool = True) -> list:
        """Write flow.csv and the pictures; returns every path written."""
        import csv

        header, rows = flow_table(result)
        csv_path = self.out / "flow.csv"
        with open(csv_path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(header)
            w.writerows(rows)
        self.written.append(csv_path)
        if plot:
            from .render import render_flow, render_flow_shapes

            self.written.append(render_flow(result, self.out / "flow.png"))
            # the last non-empty state closes the row unless it is sampled already
            frames = list(self.frames)
            if self.last is not None and (not frames or frames[-1][0] != self.last[0]):
                frames.append(self.last)
            if frames and frames[0][1].ndim == 3:
                records = {rec["step"]: rec for rec in result.steps}
                shown = [(state, records[step]) for step, state in frames]
                self.written.append(
                    render_flow_shapes(shown, self.out / "shapes.png", result.connectivity, self.PANELS)
                )
        return self.written
