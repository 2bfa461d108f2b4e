"""A flow's files: the surface of every step, a CSV of the figures, pictures.

:class:`FlowWriter` writes them while the flow runs (``isoflow flow --out``),
so that no state is kept in memory; :func:`export_flow` writes them from a
finished :class:`~isoflow.flow.run.FlowResult` that kept its states.

Every step file is read back with trimesh as soon as it is written
(:func:`isoflow.mesh.readback.check_surface_file`), on a worker thread while
the flow computes the next step (numpy, numba and trimesh's sorts release
the GIL: on a machine with a free core the check costs little wall time);
the CSV records trimesh's watertightness, Euler number and genus next to
isoflow's own.

A run is written into a hidden staging directory inside the output
directory and moved into place only when complete: an error or an
interruption leaves the previous run's files as they were, and the old
run's step files are removed only after the new run has finished writing.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import warnings
from pathlib import Path

from ..digital.lattice import DigitalObject
from ..digital.surface import boundary_mesh
from ..errors import IsoflowError, some_of, warn
from ..mesh import export
from ..mesh.outputs import (
    abandoned_asides,
    aside_name,
    atomic_write,
    check_writable_dir,
    file_suffix,
    interrupted_by_signal,
    make_output_dir,
    remove_abandoned,
    remove_entry,
    sync_directory,
    sync_file,
    temp_sibling,
    write_error,
)
from ..mesh.readback import check_surface_file
from .run import FlowResult

#: the CSV's per-step columns on the step's surface file (3D flows)
CHECK_COLUMNS = ["mesh_euler", "mesh_genus", "trimesh_watertight", "trimesh_euler", "trimesh_genus"]

#: names a run writes besides its step files; --force replaces them
RUN_FILES = ("flow.csv", "flow.png", "shapes.png")


def _step_file_pattern() -> re.Pattern:
    """The names of step files a run writes: ``step_NNN`` and ``.ply`` or
    any volume suffix (so that a run replaces what an earlier one wrote
    with another ``--volumes`` suffix, or with none)."""
    from ..mesh.formats.registry import volume_suffixes

    suffixes = sorted({".ply", *volume_suffixes(writable=True)}, key=len, reverse=True)
    return re.compile(r"step_\d+(" + "|".join(re.escape(s) for s in suffixes) + r")", re.IGNORECASE)


def step_width(last_step: int) -> int:
    """Digits of the step numbers in file names (``step_007.ply``), enough
    for the last step and at least three, so that names sort as steps do.

    Examples
    --------
    >>> step_width(96), step_width(1500)
    (3, 4)
    """
    return max(3, len(str(last_step)))


def check_step_volume(path, step: int, state: DigitalObject) -> None:
    """Refuse what the format of ``path`` cannot hold of the state of
    ``step`` (:func:`~isoflow.mesh.volumes.check_volume_holds`), and where
    that is its size, name the step and the flow's remedy: a flow's states
    can grow past their input by a few voxels, past MagicaVoxel's
    :data:`~isoflow.mesh.formats.magicavoxel.MAX_SIDE` a side at a later
    step, and no coarser grid helps a run under way.

    Parameters
    ----------
    path : str or os.PathLike
        The step's volume file.
    step : int
        The step whose state it holds.
    state : DigitalObject
        That state.

    Raises
    ------
    IsoflowError
        One line, naming the file (and the step where the state is too
        large).
    """
    from ..mesh.formats.magicavoxel import ModelTooLarge
    from ..mesh.volumes import check_volume_holds

    try:
        check_volume_holds(path, state)
    except ModelTooLarge as exc:
        raise IsoflowError(f"{exc} (step {step}'s state); write the steps in another --volumes format "
                           "(.npz or .zarr holds any size)") from None


def _run_names(out: Path) -> list[Path]:
    """What a run into ``out`` replaces or removes there: the step files of
    any suffix, flow.csv and the pictures."""
    steps = _step_file_pattern()
    return [p for p in out.glob("step_*") if steps.fullmatch(p.name)] + [out / n for n in RUN_FILES]


def _is_zarr_store(path: Path) -> bool:
    """Whether the directory ``path`` is a zarr store (version 2 or 3)."""
    return any((path / mark).exists() for mark in (".zgroup", ".zarray", "zarr.json"))


def refuse_foreign_step(taken: Path) -> None:
    """Refuse ``taken``, a path a run replaces (``step_001.zarr``), where it
    is a directory of the user's: ``force`` replaces a run's files (a step
    store, a file, a link, unlinked and what it leads to kept), never a
    directory that is not a ``.zarr`` store.

    Parameters
    ----------
    taken : Path
        A path bearing a step's or a run file's name in the output directory.

    Raises
    ------
    IsoflowError
        Where ``taken`` is a directory, not a link, and not a zarr store.

    Examples
    --------
    >>> import tempfile
    >>> mine = Path(tempfile.mkdtemp()) / "step_000.zarr"
    >>> mine.mkdir()
    >>> refuse_foreign_step(mine)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: ...step_000.zarr: a directory that is not a step store of a run; force=True ...
    >>> (mine / "zarr.json").write_text("{}"); refuse_foreign_step(mine)
    2
    """
    if taken.is_dir() and not taken.is_symlink() and not (taken.suffix.lower() == ".zarr" and _is_zarr_store(taken)):
        raise IsoflowError.worded(
            f"{taken}: a directory that is not a step store of a run; force=True replaces a run's files, not it: "
            "move it, or give another directory",
            f"{taken}: a directory that is not a step store of a run; flow --force replaces a run's files, not it: "
            "move it, or give --out another directory")


def replaced_by_run(directory, path) -> bool:
    """Whether a run into ``directory`` (with ``force``) replaces or removes
    the file ``path``: a step file of any suffix, flow.csv or a picture
    there, named by ``path`` itself or by the file a symbolic link
    ``path`` leads to. The command refuses such a file as its input.

    Examples
    --------
    >>> import tempfile
    >>> base = Path(tempfile.mkdtemp())
    >>> run = base / "run"
    >>> run.mkdir()
    >>> (run / "step_002.npy").write_bytes(b"")
    0
    >>> (base / "input.npy").symlink_to(run / "step_002.npy")
    >>> replaced_by_run(run, run / "step_002.npy"), replaced_by_run(run, base / "input.npy")
    (True, True)
    """
    out, path = Path(directory), Path(path)
    if not (out.is_dir() and path.exists()):
        return False
    # the link itself (a step file's name in the directory) or the file it leads to, which the run removes
    return any(os.path.samefile(out, named.parent) and (
        named.name in RUN_FILES or _step_file_pattern().fullmatch(named.name) is not None)
        for named in (path, Path(os.path.realpath(path))))


def flow_table(result: FlowResult, checks: dict | None = None) -> tuple[list[str], list[list]]:
    """The per-step figures as CSV columns and rows (bbox as min/max per
    axis), the columns of the ``steps`` records of ``isoflow flow --json``:
    a guarded run's ``move`` too (empty for step 0, the input); with
    ``checks`` (step -> :func:`check_surface_file` result, 3D), isoflow's
    and trimesh's reading of each step's surface file."""
    nd = len(result.steps[0]["betti"])
    ndim = 3 if nd == 3 else 2
    axes = "xyz"[:ndim]
    header = ["step", "voxels", "parity"] + [f"b{i}" for i in range(nd)]
    header += ["euler_characteristic", "energy"]
    header += [f"bbox_min_{a}" for a in axes] + [f"bbox_max_{a}" for a in axes]
    if result.guard:
        header.append("move")
    if checks is not None:
        header += CHECK_COLUMNS
    rows = []
    for s in result.steps:
        box = s["bbox"] or [""] * (2 * ndim)
        row = [s["step"], s["voxels"], s["parity"], *s["betti"], s["euler_characteristic"], s["energy"], *box]
        if result.guard:
            row.append(s.get("move", ""))
        if checks is not None:
            c = checks.get(s["step"])
            row += [""] * len(CHECK_COLUMNS) if c is None or c.get("skipped") else [
                c["isoflow"]["euler_number"], c["isoflow"]["genus"],
                c["trimesh"]["watertight"], c["trimesh"]["euler_number"], c["trimesh"]["genus"],
            ]
        rows.append(row)
    return header, rows


#: a run's staging directory: :func:`~isoflow.mesh.outputs.temp_sibling`
#: of this name in the output directory
STAGE = "run"


#: the suffixes of the run's own outputs other than its step files: the
#: table ``--out`` writes and the object ``--json`` prints, each with what
#: gives that file
RUN_FILE_SUFFIXES = {".csv": ("table", "--out {dir} writes {dir}/flow.csv"),
                     ".json": ("JSON", "--json prints the run's JSON: > {dir}.json")}


def refuse_file_suffix(out: Path) -> None:
    """Refuse a directory to be made whose name ends in a mesh, volume,
    table or JSON suffix: ``flow --out X.ply`` or ``--out flow.csv`` meant
    a file, and a directory of that name is not what the user asked for
    (:func:`check_output_dir` calls it only where the directory is not
    there: an existing one is the user's own).

    Parameters
    ----------
    out : pathlib.Path
        The output directory as given.

    Raises
    ------
    IsoflowError
        One line naming ``out`` and the name without the suffix.

    Examples
    --------
    >>> refuse_file_suffix(Path("run"))
    >>> refuse_file_suffix(Path("steps.nii.gz"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    isoflow.errors.IsoflowError: steps.nii.gz: the flow's files (...) go into a directory, and .nii.gz is a volume ...
    """
    from ..mesh.formats.registry import volume_suffixes
    from ..mesh.load import MESH_SUFFIXES

    suffix = file_suffix(out.name, others=RUN_FILE_SUFFIXES)
    if suffix is None:
        return
    # the check runs before the input is read: a 2D run writes no surfaces
    files = "step_NNN.ply in 3D, flow.csv, flow.png, shapes.png"
    kind = "mesh" if suffix in MESH_SUFFIXES else RUN_FILE_SUFFIXES.get(suffix, ("volume",))[0]
    given, other = out.name[-len(suffix):], out.with_name(out.name[: -len(suffix)])
    # a volume per step is what --volumes writes: the likelier wish behind --out steps.nii.gz
    hint = f" (--volumes {suffix} adds every step's volume)" if suffix in volume_suffixes(writable=True) else ""
    if suffix in RUN_FILE_SUFFIXES:
        hint = " (" + RUN_FILE_SUFFIXES[suffix][1].format(dir=other) + ")"
    raise IsoflowError.worded(
        f"{out}: the flow's files ({files}) go into a directory, and {given} is a {kind} suffix; "
        f"give a directory such as {other}",
        f"{out}: --out names the directory for the run's files ({files}), and {given} is a {kind} suffix; "
        f"give --out {other}{hint}")


def check_output_dir(directory, force: bool = False):
    """The output directory as a Path; refuses a file, a directory that
    already holds files unless ``force``, one that cannot be written, or one
    whose parent is missing (as ``-o`` refuses a file there: a mistyped
    path is not made, parents and all)."""
    out = Path(directory)
    if out.exists() and not out.is_dir():
        raise IsoflowError(f"{out}: exists and is not a directory")
    if not out.is_dir():
        refuse_file_suffix(out)
    if not out.exists() and out.parent.exists() and not out.parent.is_dir():  # the OS's own word, as mkdir would say it
        raise IsoflowError(f"{out.parent}: not a directory, a file (for the output directory {out.name})")
    if not out.exists() and not out.parent.is_dir():
        raise IsoflowError(f"{out.parent}: no such directory (for the output directory {out.name})")
    if out.is_dir():  # a killed run's staging directory does not make it taken
        remove_abandoned(out / STAGE)
        # a run killed while it put its files in place left the previous run's entries it moved aside:
        # each is put back where its name is empty, else removed, before the directory's files are counted
        steps = _step_file_pattern()
        for entry in abandoned_asides(out):
            if steps.fullmatch(entry.name) or entry.name in RUN_FILES:
                remove_abandoned(entry)
    if out.is_dir() and any(out.iterdir()) and not force:
        raise IsoflowError.worded(f"{out}: directory is not empty; pass force=True to overwrite its files",
                                  f"{out}: directory is not empty; pass --force to overwrite its files")
    if out.is_dir():
        for taken in _run_names(out):
            refuse_foreign_step(taken)
    parent = out if out.is_dir() else next((p for p in out.parents if p.exists()), Path("."))
    check_writable_dir(parent, f"the flow's files ({out})")
    return out


def export_flow(result: FlowResult, directory, force: bool = False, plot: bool = True) -> list:
    """Write a flow's files into ``directory``: ``step_NNN.ply`` (the boundary
    surface of every non-empty 3D state, world coordinates, per-vertex
    curvature data), ``flow.csv`` (one row per step), ``flow.png`` (voxels,
    energy and Betti numbers against the step) and ``shapes.png`` (the
    object at a few steps: its surface in 3D, its pixels in 2D).

    Refuses a directory that already holds files unless ``force``. Needs a
    result run with ``keep_states=True``; :class:`FlowWriter` writes the same
    files while the flow runs, without keeping the states. Raises
    :class:`IsoflowError` when trimesh reads a step file differently from
    isoflow's counts (the files are written all the same).
    """
    if not result.states and result.steps:
        raise IsoflowError("export_flow needs the states: run the flow with keep_states=True")
    writer = FlowWriter(directory, result.connectivity, force, last_step=len(result.steps) - 1)
    try:
        for rec, state in zip(result.steps, result.states):
            writer.add(rec["step"], state)
        written = writer.finish(result, plot=plot)
    except BaseException:
        writer.abort()
        raise
    if writer.problems:
        raise IsoflowError(f"{writer.problems[0]} ({len(writer.problems)} step file(s) disagree)")
    return written


class FlowWriter:
    """Writes a flow's files step by step (see :func:`export_flow`).

    Pass :meth:`add` as (part of) ``run_flow``'s ``progress`` callback, after
    adding the input as step 0, and run with ``keep_states=False``: memory
    then stays that of one state plus the few kept for ``shapes.png``, where
    keeping every state of a shrinking box of side s costs about s^4/4 bytes.

    Files go to a staging directory inside the output directory;
    :meth:`finish` moves them into place and only then removes what a
    previous run left (``step_*.ply``, the CSV and pictures) when ``force``;
    :meth:`abort` (on an error or interruption) removes the staging
    directory and leaves the previous run untouched. Step files are flushed
    to the disk (``fsync``) on the worker thread that reads them back, before
    they are moved into place. ``checks`` holds
    trimesh's reading of every step file, ``problems`` one line per file
    that reads differently from isoflow's counts.
    """

    #: states kept for shapes.png: at most twice the panels, evenly spaced
    PANELS = 6
    #: step files waiting for their check: bounds the meshes kept in memory
    PENDING = 2

    def __init__(self, directory, connectivity: int, force: bool = False, last_step: int = 999, check: bool = True):
        out = check_output_dir(directory, force)
        self.created = not out.exists()
        self.had_files = not self.created and any(out.iterdir())  # (a killed run's staging is gone: check_output_dir)
        self.out, self.connectivity = out, connectivity
        self.volume_suffix = None  # set by write_volumes
        self._said: set[str] = set()  # warnings said already (see _named)
        self.width = step_width(last_step)
        self.staged: list[str] = []  # names written into the staging directory
        self.in_place = False  # every staged file is moved into the directory (_commit)
        # the previous run's files that this run does not replace, once _commit has listed them: those still
        # there when an interrupt or an error stops their removal are named as left
        self.earlier: list[Path] | None = None
        self.checks: dict[int, dict] = {}
        self.problems: list[str] = []
        self.check = check  # read every step file back with trimesh
        self._pool = None  # the checking thread, started with the first step file
        self._pending: list = []  # (step, name, future), oldest first
        self.frames: list = []  # (step, state), every `stride`-th step
        self.stride = 1
        self.last = None  # the last non-empty (step, state)
        # the staging directory made last: until the constructor returns the
        # caller holds no writer whose abort() would remove it
        try:
            make_output_dir(out)
            self.stage = temp_sibling(out / STAGE, directory=True)
        except OSError as exc:
            raise write_error(out, exc, existed=not self.created) from None

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
        name = f"step_{step:0{self.width}d}.ply"
        # the columns named as in `isoflow surface`'s PLY: a step file is read on its own, away from this run
        comments = (f"isoflow flow step {step}, parity {state.parity}, {self.connectivity}-connectivity",
                    export.VERTEX_COMMENT)
        with self._named():  # flushed to the disk on the worker thread
            written = export.write_mesh_file(self.stage / name, mesh, state, force=True, comments=comments, sync=False)
        self.staged.append(name)
        if self._pool is None:
            # the first check on this thread: it imports trimesh, scipy and numba, and a first import of a package
            # on two threads at once can fail (KeyError: 'scipy' as this thread imports scipy.ndimage)
            from concurrent.futures import Future, ThreadPoolExecutor

            first: Future = Future()
            with self._named():
                first.set_result(self._sync_and_check(written["path"], mesh, state))
            self._pending.append((step, name, first))
            self._pool = ThreadPoolExecutor(1, thread_name_prefix="isoflow-readback")
            return
        self._pending.append((step, name, self._pool.submit(self._sync_and_check, written["path"], mesh, state)))
        while len(self._pending) > self.PENDING:
            self._collect()

    def _sync_and_check(self, path, mesh, state):
        sync_file(path)  # before the file is moved into place
        return check_surface_file(path, mesh, state) if self.check else None

    def _collect(self) -> None:
        """Wait for the oldest worker task and record its check."""
        step, name, future = self._pending.pop(0)
        with self._named():
            check = future.result()
        if check is None:
            return
        self.checks[step] = check
        if check["agree"] is False:
            self.problems.append(check["problem"].replace(str(self.stage / name), str(self.out / name)))

    # ------------------------------------------------ per-step volumes (--volumes)
    def write_volumes(self, suffix: str) -> None:
        """Also write every non-empty step's volume as ``step_NNN{suffix}``
        (any format :func:`isoflow.mesh.volumes.write_volume` writes, with
        voxel size and origin, and their length unit, the input's (each
        state keeps the object's ``unit``), where the format keeps one;
        ``.npz`` keeps the lattice parity too).
        Checked now, before the flow runs; like the step surfaces they are
        staged, and the volumes an earlier run left with that suffix are
        removed only when this run is complete (:meth:`finish`)."""
        from ..mesh.volumes import check_volume_suffix

        self.volume_suffix = check_volume_suffix(suffix)

    def add_volume(self, step: int, state: DigitalObject) -> None:
        """Write ``state`` as ``step_NNN{suffix}`` into the staging
        directory (:meth:`write_volumes`), after the format's check of what
        it can hold (:func:`check_step_volume`).

        Written from memory, a ``.zarr`` or ``.ome.zarr`` store as any
        other format: the in-memory flow holds the state whole already, and
        the write adds its stored 0/1 copy (a byte a voxel); an input store
        too large for that is refused before the flow (``isoflow flow``
        names ``--volumes .zarr``, which flows it block by block).

        Parameters
        ----------
        step : int
            The step whose state it is.
        state : DigitalObject
            That state, non-empty.
        """
        from ..mesh.volumes import write_volume

        name = f"step_{step:0{self.width}d}{self.volume_suffix}"
        with self._named():
            check_step_volume(self.stage / name, step, state)
            write_volume(state, self.stage / name, force=True)
        self.staged.append(name)

    def finish(self, result: FlowResult, plot: bool = True) -> list:
        """Write flow.csv and the pictures, move the run into place and
        remove what a previous run left; returns every path written."""
        import csv

        while self._pending:
            self._collect()
        self._stop_checks()
        self._widen()
        three_d = result.steps and len(result.steps[0]["betti"]) == 3
        header, rows = flow_table(result, self.checks if three_d and self.check else None)
        with self._named(), atomic_write(self.stage / "flow.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(header)
            w.writerows(rows)
        self.staged.append("flow.csv")
        if plot:
            from .pictures import render_flow, render_flow_shapes

            with self._named():
                render_flow(result, self.stage / "flow.png")
            self.staged.append("flow.png")
            # the last non-empty state closes the row unless it is sampled already
            frames = list(self.frames)
            if self.last is not None and (not frames or frames[-1][0] != self.last[0]):
                frames.append(self.last)
            if frames:
                records = {rec["step"]: rec for rec in result.steps}
                shown = [(state, records[step]) for step, state in frames]
                with self._named():
                    render_flow_shapes(shown, self.stage / "shapes.png", result.connectivity, self.PANELS)
                self.staged.append("shapes.png")
        return self._commit()

    def _widen(self) -> None:
        """Rename the staged step files to the width of the last step
        written where the run went past the step it was expected to reach
        (``last_step``: a guarded run can), so that every name of the run
        has the same width and names sort as steps do."""
        numbered = [(name, re.fullmatch(r"step_(\d+)(.*)", name)) for name in self.staged]
        steps = [int(m[1]) for _, m in numbered if m]
        width = step_width(max(steps, default=0))
        if width <= self.width:
            return
        renamed = {name: f"step_{int(m[1]):0{width}d}{m[2]}" for name, m in numbered if m}
        try:
            for old, new in renamed.items():
                os.replace(self.stage / old, self.stage / new)
        except OSError as exc:
            raise write_error(self.out, exc, existed=self.had_files) from None
        self.staged = [renamed.get(name, name) for name in self.staged]
        for old, new in renamed.items():
            self.problems = [line.replace(str(self.out / old), str(self.out / new)) for line in self.problems]
        self.width = width

    @contextlib.contextmanager
    def _named(self):
        """A failed write names the file it was for, not its staging copy,
        and says that the previous run is kept; a warning names it too, and
        what every step's file would repeat (``MagicaVoxel keeps no voxel
        size or origin``) is said once per run, of the first step's file."""
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                yield
            for w in caught:
                text = str(w.message).replace(str(self.stage), str(self.out))
                # the same warning for another step: other file, other numbers
                key = re.sub(r"step_\d+|\[[^]]*\]", "*", text.replace(str(self.out), ""))
                if key not in self._said:
                    self._said.add(key)
                    warn(text, w.category)
        except (OSError, IsoflowError, KeyboardInterrupt) as exc:
            if isinstance(exc, OSError):
                exc = write_error(Path(exc.filename or self.stage), exc, existed=False)
            msg = str(exc).replace(str(self.stage), str(self.out)).replace("nothing was written", "")
            if not msg.strip():  # an interrupt between two writes: name the run's directory
                msg = f"{self.out}: stopped while writing the flow's files"
            raise (KeyboardInterrupt if isinstance(exc, KeyboardInterrupt) else IsoflowError)(self.kept(msg)) from None

    def kept(self, msg: str) -> str:
        """``msg`` followed by what an interrupted or failed run leaves in
        the output directory: a directory without files before this run
        holds no previous run to keep, and there nothing of it is left
        (:meth:`abort`)."""
        return msg.rstrip("; ") + ("; the previous run's files in the directory are unchanged" if self.had_files
                                   else "; nothing was written")

    def interrupted(self, exc: KeyboardInterrupt) -> KeyboardInterrupt:
        """The interrupt of a run, named: one raised while the flow computes
        a step (not while a file is written) says nothing, and the command
        then did not say that the previous run's files are unchanged. One
        raised once every file of this run is in place (as the staging
        directory goes, or after :meth:`finish` returned) says so, and
        which of the previous run's files it does not replace are gone and
        which are left (a second interrupt may stop their removal part
        way, and "complete" would hide the files still there)."""
        if str(exc).strip():
            return exc
        if self.in_place:
            left = self._earlier_left()
            if not left:
                return KeyboardInterrupt(f"{self.out}: stopped after the run was complete; its {len(self.staged)} "
                                         "files are in place")
            return KeyboardInterrupt(f"{self.out}: stopped while the previous run's files were removed; this run's "
                                     f"{len(self.staged)} files are in place{left}")
        return KeyboardInterrupt(self.kept(f"{self.out}: stopped while the flow ran"))

    def _commit(self) -> list:
        """Move the staged files over the output directory's, then remove the
        previous run's files that this run did not replace. A failure (or an
        interrupt) part way says what it left: the previous run unchanged
        only where none of this run's files was put in place yet and none of
        the previous run's was removed."""
        new = set(self.staged)
        with self._named():  # a signal a library swallowed: the previous run stays
            interrupted_by_signal()
        target, previous, aside = self.out, None, None
        try:
            for name in self.staged:
                target = self.out / name
                # a rename takes neither a link of a step store's name, nor a zarr step volume (a directory),
                # nor a file where a store is staged: each is moved aside first (a rename, at once), and back
                # where this run's is not put in its place: a failed rename leaves the previous run's entry whole
                if target.is_symlink() or target.is_dir() or target.exists() and (self.stage / name).is_dir():
                    previous = "link" if target.is_symlink() else "step store" if target.is_dir() else "file"
                    aside = aside_name(target)
                    os.replace(target, aside)
                os.replace(self.stage / name, target)
                if aside is not None:
                    remove_entry(aside)  # what a link led to is kept: it is the user's
                previous, aside = None, None
            self.in_place = True
            target = self.out
            self.earlier = [old for old in _run_names(self.out)
                            if old.name not in new and (old.exists() or old.is_symlink())]
            sync_directory(self.out)
            for old in self.earlier:
                target = old
                # a step name that is a link goes as the step file it stands for; what it names is the user's
                remove_entry(old)
        except (OSError, KeyboardInterrupt) as exc:
            line = self._commit_left(target, exc, previous, aside, self._put_back(target, aside))
            raise (KeyboardInterrupt if isinstance(exc, KeyboardInterrupt) else IsoflowError)(line) from None
        finally:
            shutil.rmtree(self.stage, ignore_errors=True)
        return [self.out / name for name in self.staged]

    def _put_back(self, target: Path, aside: Path | None) -> bool | OSError:
        """Rename the previous run's entry moved ``aside`` back to ``target``
        where this run's was not put there: True where it was, False where
        there was none to move back (not moved yet, or this run's entry is
        in its place), the error of the rename where it failed (the entry
        is then at ``aside``)."""
        if aside is None or not os.path.lexists(aside) or os.path.lexists(target):
            return False
        try:
            os.replace(aside, target)
        except OSError as exc:
            return exc
        return True

    def _earlier_left(self) -> str:
        """What is left of the previous run's files that this run does not
        replace, once this run's are in place: ``""`` where none is (or
        there was no previous run), else which of them were removed and
        which are still there, as found in the directory now."""
        if self.earlier is None:  # stopped before they were listed
            return "; some of the previous run's files may be left beside them" if self.had_files else ""
        left = [old for old in self.earlier if old.exists() or old.is_symlink()]
        if not left:
            return ""
        gone = [old for old in self.earlier if old not in left]
        was = "was" if len(gone) == 1 else "were"
        removed = f"{len(gone)} of them {was} removed ({some_of(sorted(p.name for p in gone))}), " if gone \
            else "none of them was removed, "
        return (f"; of the previous run's {len(self.earlier)} files that it does not replace, {removed}"
                f"{len(left)} {'is' if len(left) == 1 else 'are'} left beside them "
                f"({some_of(sorted(p.name for p in left))})")

    def _commit_left(self, target: Path, exc: BaseException, previous: str | None, aside: Path | None,
                     back: bool | OSError) -> str:
        """The line of a failure (or an interrupt) while :meth:`_commit` put
        the staged files in place, at ``target`` (``previous``: the kind of
        the previous run's entry there, a link, a step store or a file, to be
        moved ``aside`` to make room for this run's; ``back``: whether it was
        moved back, or the error that kept it at ``aside``)."""
        total = len(self.staged)
        # in place: the staged entries renamed out of the staging directory (an interrupt may come between a
        # rename and its count)
        done = sum(not os.path.lexists(self.stage / name) for name in self.staged)
        placed = previous is not None and not os.path.lexists(self.stage / target.name)
        left = aside is not None and os.path.lexists(aside)  # the previous entry at its hidden name, whole or not
        cause = (exc.strerror or str(exc) or type(exc).__name__) if isinstance(exc, OSError) else ""
        if isinstance(exc, KeyboardInterrupt):
            what = "interrupted after the run's files were put in place" if done == total else \
                "interrupted while putting the run's files in place"
        elif placed and left:
            what = f"could not remove the previous run's {previous} ({cause})"
        elif previous is not None and not placed and back is False:  # the previous entry did not move
            what = f"could not move the previous run's {previous} aside to make room ({cause})"
        else:
            what = f"could not put it in place ({cause})" if done < total else f"could not finish the run ({cause})"
        note = ""
        if back is True and done:  # moved back: said outright, as the directory holds files of both runs
            note = f"; the previous run's {target.name} is as it was"
        elif placed and left:  # this run's entry is in place; the previous one's removal did not finish
            some = ", whole or in part" if previous == "step store" else ""
            note = f"; the previous run's {target.name} is left beside it as {aside.name}{some}: remove it"
        elif left:  # moved aside, and the rename back failed: the previous run's entry is whole, at its hidden name
            kept = "; what it led to is kept" if previous == "link" else ""
            why = f" ({back.strerror or back})" if isinstance(back, OSError) else ""
            note = (f"; the previous run's {target.name} (a {previous}{kept}) was moved aside as {aside.name} to make "
                    f"room and could not be moved back{why}: rename it {target.name} to have it back")
        if done == total:  # stopped as the previous run's files that this one did not replace were removed
            return f"{target}: {what}; this run's {total} files are in place{note}{self._earlier_left()}"
        if done == 0 and not note:  # the previous entry is in its place: never moved aside, or moved back
            return self.kept(f"{target}: {what}")
        if done == 0:
            other = "; the previous run's other files are unchanged: run the flow again" if self.had_files else ""
            return f"{target}: {what}{note}{other}"
        said = f"{done} of this run's {total} files {'was' if done == 1 else 'were'} put in place, the rest were not"
        if self.had_files:
            said += "; the directory holds files of both runs: run the flow again"
        return f"{target}: {what}{note}; {said}"

    def _stop_checks(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool, self._pending = None, []

    def abort(self) -> None:
        """Remove the staging directory (and the output directory when this
        writer made it and nothing else is in it): the previous run stays."""
        from ..scale.chunks import settle_zarr_io

        self._stop_checks()
        settle_zarr_io()  # a step store's write that the interrupt did not end would recreate the stage
        shutil.rmtree(self.stage, ignore_errors=True)
        if self.created:
            try:
                self.out.rmdir()
            except OSError:
                pass
