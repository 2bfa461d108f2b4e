"""A flow's files: the surface of every step, a CSV of the figures, pictures.

:class:`FlowWriter` writes them while the flow runs (``isoflow flow --out``),
so that no state is kept in memory; :func:`export_flow` writes them from a
finished :class:`~isoflow.flow.run.FlowResult` that kept its states.
"""

from __future__ import annotations

from pathlib import Path

from ..digital.lattice import DigitalObject
from ..digital.surface import boundary_mesh
from ..errors import IsoflowError
from ..mesh import export
from .run import FlowResult


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
        self.out, self.connectivity, self.force = out, connectivity, force
        self.volume_suffix = None  # set by write_volumes
        self.width = max(3, len(str(last_step)))
        self.written: list = []
        self.frames: list = []  # (step, state), every `stride`-th step
        self.stride = 1
        self.last = None  # the last non-empty (step, state)

    def add(self, step: int, state: DigitalObject) -> None:
        if not state.voxels:
            return
        self.last = (step, state)
        if step % self.stride == 0:
            self.frames.append((step, state))
            if len(self.frames) > 2 * self.PANELS:
                self.frames = self.frames[::2]
                self.stride *= 2
        if self.volume_suffix:
            self.add_volume(step, state)
        if state.ndim != 3:
            return
        mesh = boundary_mesh(state.volume, self.connectivity)
        path = self.out / f"step_{step:0{self.width}d}.ply"
        comments = (f"isoflow flow step {step}, parity {state.parity}, {self.connectivity}-connectivity",)
        export.write_ply(path, export.mesh_vertex_table(mesh, state), mesh.polygons(), force=True, comments=comments)
        self.written.append(path)

    # ------------------------------------------------ per-step volumes (--volumes)
    def write_volumes(self, suffix: str) -> None:
        """Also write every non-empty step's volume as ``step_NNN{suffix}``
        (any format :func:`isoflow.mesh.volumes.write_volume` writes, with
        voxel size and origin; ``.npz`` keeps the lattice parity too).
        Checked now, before the flow runs; with ``force`` the volumes an
        earlier run left with that suffix are removed."""
        import shutil

        from ..mesh.volumes import check_volume_output

        suffix = suffix if suffix.startswith(".") else "." + suffix
        check_volume_output(self.out / f"step_{0:0{self.width}d}{suffix}", force=True)
        if self.force:
            for old in self.out.glob(f"step_*{suffix}"):
                shutil.rmtree(old) if old.is_dir() else old.unlink()
        self.volume_suffix = suffix

    def add_volume(self, step: int, state: DigitalObject) -> None:
        from ..mesh.volumes import write_volume

        path = self.out / f"step_{step:0{self.width}d}{self.volume_suffix}"
        self.written.append(write_volume(state, path, force=True))

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
            from .pictures import render_flow, render_flow_shapes

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
