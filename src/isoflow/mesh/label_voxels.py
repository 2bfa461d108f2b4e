"""Several meshes into one label image: label i for the i-th mesh.

The grid is the one :mod:`isoflow.mesh.grid` lays over a single mesh, laid
over the union of the meshes' bounding boxes (so one mesh gives the grid it
gives alone). Each mesh is voxelised alone by
:func:`~isoflow.mesh.voxelize.voxelize`, with the same ``fill``, on the block
of that grid its bounding box covers (one voxel of margin: every voxel its
surface touches), whose voxel centres and planes are the grid's bit for bit,
and written into the label array as label i (1-based; 0 is background).

Overlaps
--------
Where meshes overlap, ``overlap="later"`` (default) gives the voxel the
label of the later mesh: the order of the meshes is their priority, as
painting them one over the other would. ``overlap="error"`` refuses, naming
the pairs and their meshes. Either way the result counts the voxels inside two or more
meshes (each once) and, per pair of labels ``(i, j)``, ``i < j``, the
voxels of mesh j that held label i when mesh j was placed: the voxels label
i lost to label j. Where no voxel lies in three or more meshes, that is
the voxels the two meshes share.

Memory
------
The label array (the smallest unsigned type that holds the labels), a bit
per voxel for the overlaps and one mesh's block at a time (one byte per
voxel) must fit in the budget; the largest block is known from the bounding
boxes, so what would not fit is refused before any mesh is voxelised.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..errors import IsoflowError, check_callable, check_switch, choice_of, given_text, some_of
from ..results import Result
from ..scale import memory
from .bodies import Body, mesh_bodies
from .fills import Fill, check_fill, check_strict
from .grid import (
    GridTooLarge,
    check_grid_request,
    check_placement,
    finest_fit,
    grid_fits,
    grid_need,
    grid_words,
    voxel_grid,
)
from .load import mesh_bbox
from .mesh_units import common_unit
from .voxelize import PROGRESS_UNITS, check_write_bytes, tell_rule, voxelize

#: how the voxels inside two or more meshes are labelled
Overlap = Literal["later", "error"]
OVERLAPS: tuple[str, ...] = ("later", "error")
#: pairs named in a note or an error; the rest are counted
NAMED_PAIRS = 8
#: :func:`place` writes a mesh's block into the label array about this many voxels at a time
PLACE_VOXELS = 1 << 21


@dataclass(frozen=True, eq=False, repr=False)
class LabelVoxelization(Result):
    """Several meshes voxelised into one label image.

    Reads as a mapping too (``r["names"]``); :meth:`to_dict` is every field
    but the array.

    Attributes
    ----------
    labels : unsigned integer ndarray (nx, ny, nz) or None
        Label i (1-based) where mesh i fills the voxel, 0 elsewhere; the
        smallest unsigned type that holds the labels. None when read back
        from :meth:`to_dict`'s JSON, which leaves the array out.
    origin : float64 ndarray (3,)
        Lower corner of voxel (0, 0, 0).
    pitch : float
    names : tuple of str
        Label i's mesh is ``names[i - 1]``: its file, ``FILE:NODE`` for a
        scene's node, ``FILE:SOLID`` for a named solid of an ASCII STL,
        ``FILE:K`` for a connected body, ``mesh K`` for arrays.
    voxels : tuple of int
        Label i's voxels, ``voxels[i - 1]``, after overlaps are resolved.
    fill : {"winding", "shell", "flood"}
    overlap : {"later", "error"}
    overlap_voxels : int
        Voxels inside two or more meshes, each counted once.
    overlaps : tuple of (int, int, int)
        ``(i, j, n)``, ``i < j``: n voxels of label i were taken by the later
        label j (see the module docstring), by ``(i, j)``.
    notes : tuple of (str or None)
        Each mesh's own note (:class:`~isoflow.mesh.fills.Voxelization`).
    note : str or None
        One line on the overlaps and on labels left without a voxel.
    unit : str or None
        The length unit of the origin and pitch: the one every mesh file
        declares (:func:`~isoflow.mesh.mesh_units.declared_unit`: a 3MF
        model's, a glTF's metres), as a single mesh's ``DigitalObject.unit``
        is; None where any mesh holds bare numbers.
    """

    labels: np.ndarray | None = field(repr=False)
    origin: np.ndarray
    pitch: float
    names: tuple[str, ...]
    voxels: tuple[int, ...]
    fill: Fill
    overlap: Overlap
    overlap_voxels: int
    overlaps: tuple[tuple[int, int, int], ...]
    notes: tuple[str | None, ...]
    note: str | None = None
    unit: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """Every field but the label array, as JSON takes it."""
        out = super().to_dict()
        del out["labels"]
        return out

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> LabelVoxelization:
        """The label voxelisation of :meth:`to_dict`'s JSON: the label array
        is not in it, so there is none (``labels`` given is taken), the
        origin is an array and the sequences tuples again. It was refused,
        the array being a field without a default.

        Examples
        --------
        >>> import json, trimesh
        >>> r = voxelize_meshes([trimesh.creation.box()], resolution=4)
        >>> back = LabelVoxelization.from_dict(json.loads(json.dumps(r.to_dict())))
        >>> back.to_dict() == r.to_dict(), back.labels, back.origin.tolist(), back.voxels
        (True, None, [-0.5, -0.5, -0.5], (64,))
        """
        given = {"labels": None, **values}
        # JSON makes the origin and every tuple a list: back to the fields' types, so that the
        # result equals the one written (a field left out is left to the dataclass to name)
        if "origin" in given:
            given["origin"] = np.asarray(given["origin"], dtype=np.float64)
        for name in ("names", "voxels", "notes"):
            if name in given:
                given[name] = tuple(given[name])
        if "overlaps" in given:
            given["overlaps"] = tuple(tuple(o) for o in given["overlaps"])
        return super().from_dict(given)


def check_overlap(overlap: object) -> Overlap:
    """``overlap`` if it names a rule, else an IsoflowError naming them."""
    chosen = choice_of(overlap, OVERLAPS)  # the plain string, which the result keeps
    if chosen is None:
        raise IsoflowError(f"voxelize_meshes: overlap must be one of {', '.join(OVERLAPS)}, got {given_text(overlap)}")
    return chosen  # type: ignore[return-value]


def label_dtype(count: int) -> np.dtype:
    """The smallest unsigned integer type that holds labels 0 .. count.

    Examples
    --------
    >>> [str(label_dtype(n)) for n in (1, 255, 256, 70000)]
    ['uint8', 'uint8', 'uint16', 'uint32']
    """
    return np.dtype(np.min_scalar_type(max(1, int(count))))


def union_corners(bodies: list[Body]) -> tuple[np.ndarray, np.ndarray]:
    """The corners of the bodies' bounding boxes, two a body, as a mesh
    whose faces use every corner: :func:`voxel_grid` lays on it the grid of
    their union (it depends on the box alone)."""
    corners = np.vstack([mesh_bbox(b.vertices, b.faces, b.name)[:2] for b in bodies])
    return corners, np.repeat(np.arange(len(corners)), 3).reshape(-1, 3)


def union_grid(bodies: list[Body], pitch, resolution):
    """``(pitch, origin, shape, what)`` of the grid :func:`voxel_grid` lays
    over the union of the bodies' bounding boxes (:func:`union_corners`)."""
    corners, used = union_corners(bodies)
    pitch, origin, shape, what, _ = voxel_grid(corners, used, pitch, resolution)
    check_placement(corners.min(axis=0), corners.max(axis=0), pitch, what)
    return pitch, origin, shape, what


def body_window(body: Body, origin: np.ndarray, pitch: float, shape) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """``(start, stop)``: the block of the grid holding every voxel whose
    closed cube meets the body's bounding box, one voxel of margin against
    rounding (for ``flood``, a border free of the shell)."""
    lo, hi, _ = mesh_bbox(body.vertices, body.faces, body.name)
    with np.errstate(over="ignore", invalid="ignore"):
        a = np.floor((lo - origin) / pitch) - 1
        b = np.floor((hi - origin) / pitch) + 2
    n = np.asarray(shape, dtype=np.float64)
    a = np.clip(np.nan_to_num(a, nan=0.0), 0, n - 1)
    b = np.clip(np.where(np.isnan(b), n, b), a + 1, n)
    return tuple(int(x) for x in a), tuple(int(x) for x in b)


def packed_span(start: int, size: int) -> tuple[int, int]:
    """The bytes ``[a, b)`` of a bit-packed axis that hold the bits
    ``[start, start + size)``.

    Examples
    --------
    >>> packed_span(5, 4), packed_span(8, 8)
    ((0, 2), (1, 2))
    """
    return start >> 3, -(-(start + size) // 8)


def place_rows(ny: int, nbytes: int, voxels: int = PLACE_VOXELS) -> int:
    """Rows (first axis) of a block :func:`place` takes at a time: about
    ``voxels`` voxels of its ``ny`` x ``8 * nbytes`` rows of packed
    overlap bits, at least one row.

    Examples
    --------
    >>> place_rows(100, 25, voxels=1_000_000), place_rows(2000, 250, voxels=1_000_000)
    (50, 1)
    """
    return max(1, voxels // max(1, ny * 8 * nbytes))


def place_bytes(window, itemsize: int, voxels: int = PLACE_VOXELS) -> int:
    """Temporaries of :func:`place` for the block ``window`` (``(start,
    stop)``) of labels of ``itemsize`` bytes, at most: per voxel of the rows
    it takes at a time, the block's labels compared with 0 and its overlap
    (a byte each), the overlap on whole bytes of bits (a byte) and packed
    (an eighth), and the labels it took (``itemsize``, and 8 bytes as
    ``np.bincount`` casts them to its index type).

    Examples
    --------
    >>> place_bytes(((0, 0, 0), (10, 10, 16)), 1)
    19400
    """
    (_, sy, sz), (nx, ey, ez) = window
    ny = ey - sy
    za, zb = packed_span(sz, ez - sz)
    rows = min(place_rows(ny, zb - za, voxels), nx - window[0][0])
    # 11.125 bytes as 89 eighths: whole numbers, as a grid past float64 (a pitch of 1e-300) has blocks past it too
    return -(-rows * ny * 8 * (zb - za) * (89 + 8 * itemsize) // 8)


def place(labels: np.ndarray, shared: np.ndarray, vol: np.ndarray, start, label: int, taken: np.ndarray,
          voxels: int = PLACE_VOXELS) -> int:
    """Write ``label`` where the block ``vol`` (at ``start``) is in, the
    later mesh winning; count into ``taken[i]`` the voxels taken from each
    earlier label i and mark them in ``shared`` (a bit per voxel, packed
    along the last axis). Returns the block's voxels. A few rows of the
    block at a time (about ``voxels`` voxels, at least one row), so that
    the temporaries stay :func:`place_bytes` whatever the overlap: the
    overlap's bits are packed row by row, never listed by index.

    Examples
    --------
    >>> labels, shared, taken = np.zeros((1, 1, 10), np.uint8), np.zeros((1, 1, 2), np.uint8), np.zeros(2, np.int64)
    >>> labels[0, 0, 3:6] = 1
    >>> place(labels, shared, np.ones((1, 1, 4), bool), (0, 0, 4), 2, taken), labels[0, 0].tolist(), taken.tolist()
    (4, [0, 0, 0, 1, 2, 2, 2, 2, 0, 0], [0, 2])
    >>> np.unpackbits(shared[0, 0])[:10].tolist()
    [0, 0, 0, 0, 1, 1, 0, 0, 0, 0]
    """
    sx, sy, sz = start
    nx, ny, nz = vol.shape
    block = labels[sx:sx + nx, sy:sy + ny, sz:sz + nz]
    za, zb = packed_span(sz, nz)
    at = sz - 8 * za  # the block's first z in the bytes of ``shared`` it covers
    rows = place_rows(ny, zb - za, voxels)
    filled = 0
    for a in range(0, nx, rows):
        m, lab = vol[a:a + rows], block[a:a + rows]
        filled += int(np.count_nonzero(m))
        hit = m & (lab != 0)
        if hit.any():
            taken += np.bincount(lab[hit], minlength=len(taken))[:len(taken)]
            wide = np.zeros((len(hit), ny, 8 * (zb - za)), dtype=bool)
            wide[:, :, at:at + nz] = hit
            shared[sx + a:sx + a + len(hit), sy:sy + ny, za:zb] |= np.packbits(wide, axis=-1)
        lab[m] = label
    return filled


def label_extra(shape, windows, itemsize: int, write_bytes: float = 0) -> int:
    """Bytes beyond the label array and its overlap bits that voxelising
    into the label image of ``shape`` holds at most: the largest mesh's
    block (a byte a voxel) with :func:`place`'s temporaries, or, once the
    blocks are gone, ``write_bytes`` per byte of the labels (a writer's).

    Examples
    --------
    >>> label_extra((10, 10, 16), [((0, 0, 0), (10, 10, 16))], 1), label_extra((10, 10, 16), [], 1, write_bytes=2)
    (21000, 3200)
    """
    largest = max((math.prod(b - a for a, b in zip(*w)) + place_bytes(w, itemsize) for w in windows), default=0)
    return max(largest, grid_need(shape, write_bytes * itemsize))


def refuse_labels(bodies: list[Body], shape, what: str, itemsize: int, write_bytes: float, budget: int,
                  extra: int) -> GridTooLarge:
    """The refusal of a label image of ``shape`` (grid ``what``, needing
    ``extra`` bytes beyond its labels and bits) beyond ``budget``, naming
    the finest grid over the same bodies that fits
    (:func:`~isoflow.mesh.grid.finest_fit`, with each body's block in each
    grid it tries)."""
    corners, used = union_corners(bodies)
    per_voxel = itemsize + 0.125

    def fits(grid, frame) -> bool:
        shift, e, origin_s, pitch_s = frame  # the grid's origin and pitch, as voxel_grid gives them
        origin, pitch = np.ldexp(origin_s, e) + shift, math.ldexp(pitch_s, e)
        windows = [body_window(b, origin, pitch, grid) for b in bodies]
        return grid_fits(grid, per_voxel, label_extra(grid, windows, itemsize, write_bytes), budget)

    need = grid_need(shape, per_voxel, extra)
    return GridTooLarge(what, grid_words(shape, need), budget, shape=tuple(shape),
                        fit=finest_fit(corners, used, what, shape, fits), sought=True,
                        beyond="" if need > budget else "more than one array can index")


def voxelize_meshes(meshes: Sequence[object], *, pitch: float | None = None, resolution: int | np.integer | None = None,
                    fill: Fill = "winding",
                    overlap: Overlap = "later", split: bool = False, strict: bool = False,
                    max_bytes: int | np.integer | None = None, write_bytes: float = 0,
                    progress: Callable[[int, int], object] | None = None) -> LabelVoxelization:
    """Several meshes voxelised into one label image on one grid.

    Parameters
    ----------
    meshes : sequence
        Mesh files (any format trimesh reads), ``(vertices, faces)`` pairs
        or ``trimesh.Trimesh`` objects; mesh i gets label i (1-based).
    pitch, resolution
        At most one, for the grid over all of them (the rule of
        :mod:`isoflow.mesh.grid` on the union of their bounding boxes);
        neither: ``resolution=64``.
    fill : {"winding", "shell", "flood"}
        Every mesh's fill (:mod:`isoflow.mesh.fills`).
    overlap : {"later", "error"}
        A voxel inside several meshes gets the later one's label, or the
        overlap is refused (IsoflowError naming the pairs and counts, and
        the mesh of each label it names).
    split
        One label per body instead of per file: a scene's nodes, an ASCII
        STL's named solids, any other mesh's connected bodies
        (:mod:`isoflow.mesh.bodies`).
    strict
        As :func:`~isoflow.mesh.voxelize.voxelize`, for every mesh.
    max_bytes
        Memory budget (default: :func:`isoflow.scale.memory.default_budget`):
        the label array, a bit per voxel and the largest mesh's block are
        refused up front when they exceed it, naming the finest grid that
        fits (``GridTooLarge.fit``).
    write_bytes
        Bytes per byte of the label array that the caller needs beside it
        once it is made (a file writer's copies,
        :func:`~isoflow.mesh.volumes.write_bytes_per_voxel`), counted in
        the same check.
    progress
        Optional ``callable(done, total)`` as the meshes are voxelised; one
        with a ``rule`` method too
        (:class:`~isoflow.mesh.voxelize.RuleProgress`) is told, before each
        mesh is filled, whether the winding rule sums its solid angles.

    Returns
    -------
    LabelVoxelization
        The label array with its origin and pitch (in ``unit``, the one
        the mesh files declare), the labels' names and voxels, the
        overlaps, each mesh's note and one note of its own.

    Raises
    ------
    IsoflowError
        A bad mesh or option (naming the mesh), a grid beyond the budget,
        overlaps with ``overlap="error"``.

    Notes
    -----
    Each label's voxels, where no later mesh overlaps them, are exactly
    what :func:`~isoflow.mesh.voxelize.voxelize` gives for that mesh alone
    with ``pitch=r.pitch, grid=(r.origin, r.labels.shape)``.

    Examples
    --------
    >>> import trimesh
    >>> a = trimesh.creation.box((2, 2, 2))
    >>> b = trimesh.creation.box((2, 2, 2)); _ = b.apply_translation((1, 0, 0))
    >>> r = voxelize_meshes([a, b], pitch=0.5)
    >>> r.labels.shape, r.labels.dtype.name, r.voxels, r.overlaps
    ((6, 4, 4), 'uint8', (32, 64), ((1, 2, 32),))
    """
    fill, overlap = check_fill(fill, "voxelize_meshes"), check_overlap(overlap)
    strict = check_strict(strict, "voxelize_meshes")
    split = check_switch(split, "split", "voxelize_meshes")
    check_callable(progress, "progress", "progress(done, total)")  # wrapped per mesh below, so checked here
    if pitch is None and resolution is None:
        resolution = 64
    check_grid_request(pitch, resolution, "voxelize_meshes")  # before the meshes are read
    try:
        return _voxelized_meshes(meshes, pitch, resolution, fill, overlap, split, strict, max_bytes, write_bytes,
                                 progress)
    except IsoflowError as exc:  # the voxeliser's refusals, which the command shares, name the function called
        raise exc.called("voxelize_meshes", "voxelize") from None


def _voxelized_meshes(meshes, pitch, resolution, fill, overlap, split, strict, max_bytes, write_bytes,
                      progress) -> LabelVoxelization:
    """:func:`voxelize_meshes` of checked switches and grid request."""
    bodies = mesh_bodies(meshes, split)
    pitch, origin, shape, what = union_grid(bodies, pitch, resolution)
    dtype = label_dtype(len(bodies))
    windows = [body_window(b, origin, pitch, shape) for b in bodies]
    budget = memory.budget_of(max_bytes)
    write_bytes = check_write_bytes(write_bytes)
    extra = label_extra(shape, windows, dtype.itemsize, write_bytes)
    if not grid_fits(shape, dtype.itemsize + 0.125, extra, budget):
        raise refuse_labels(bodies, shape, what, dtype.itemsize, write_bytes, budget, extra)
    fixed = math.prod(shape) * dtype.itemsize + shape[0] * shape[1] * (-(-shape[2] // 8))
    labels = np.zeros(shape, dtype)
    shared = np.zeros((shape[0], shape[1], -(-shape[2] // 8)), np.uint8)
    voxels = np.zeros(len(bodies) + 1, dtype=np.int64)
    pairs: dict[tuple[int, int], int] = {}
    notes = []
    for n, (body, window) in enumerate(zip(bodies, windows), 1):
        step = None if progress is None else _Share(progress, n - 1, len(bodies))
        try:
            r = voxelize(body.vertices, body.faces, pitch=pitch, grid=(origin, shape), window=window, fill=fill,
                         strict=strict, max_bytes=max(budget - fixed, 1), progress=step, details=True)
        except IsoflowError as exc:
            raise exc.at(body.name) from None  # a refused grid keeps its command-line words
        assert r.volume is not None  # voxelize keeps the voxels in memory unless given a store
        taken = np.zeros(n, dtype=np.int64)
        voxels[n] = place(labels, shared, r.volume, window[0], n, taken)
        voxels[:n] -= taken
        pairs.update({(i, n): int(c) for i, c in enumerate(taken) if c})
        notes.append(r.note)
    names = tuple(b.name for b in bodies)
    result = LabelVoxelization(
        labels=labels, origin=np.asarray(origin, dtype=np.float64), pitch=float(pitch), names=names,
        voxels=tuple(int(c) for c in voxels[1:]), fill=fill, overlap=overlap,
        overlap_voxels=int(np.bitwise_count(shared).sum(dtype=np.int64)),
        overlaps=tuple((i, j, c) for (i, j), c in sorted(pairs.items())), notes=tuple(notes),
        unit=common_unit([b.name for b in bodies], [b.unit for b in bodies]))
    if overlap == "error" and result.overlaps:
        # nothing is written or listed: the line says which mesh each label it names is
        shown = sorted({k for i, j, _ in result.overlaps[:NAMED_PAIRS] for k in (i, j)})
        which = ", ".join(f"{k} {names[k - 1]}" for k in shown)
        things, thing = _things(split)
        said = f"the {things} overlap: {overlap_text(result, things)}, label {which}; "
        raise IsoflowError.worded(f"voxelize: {said}overlap='later' gives a shared voxel the later {thing}'s label",
                                  f"{said}--overlap later gives a shared voxel the later {thing}'s label")
    return _with_note(result, split)


class _Share:
    """Mesh n's progress (from 0) as a share of the whole, and what
    :func:`voxelize` tells of its rule, passed on
    (:class:`~isoflow.mesh.voxelize.RuleProgress`)."""

    def __init__(self, progress: Callable[[int, int], object], n: int, count: int):
        self.progress, self.n, self.count = progress, n, count

    def __call__(self, done: int, total: int) -> None:
        self.progress(self.n * PROGRESS_UNITS + done * PROGRESS_UNITS // max(1, total), self.count * PROGRESS_UNITS)

    def rule(self, solid_angles: bool) -> None:
        tell_rule(self.progress, solid_angles)


def overlap_text(r: LabelVoxelization, things: str = "meshes") -> str:
    """The overlaps in words: how many voxels, the first pairs and counts;
    ``things``: what the labels are (``"bodies"`` of files split)."""
    said = some_of((f"{i} and {j}: {c}" for i, j, c in r.overlaps), NAMED_PAIRS, noun="pair")
    voxels = "voxel lies" if r.overlap_voxels == 1 else "voxels lie"
    return f"{r.overlap_voxels} {voxels} inside two or more {things} (labels {said})"


def _things(split: bool) -> tuple[str, str]:
    """What the labels are, in the plural and the singular: the meshes
    given, or with ``split`` the bodies of each."""
    return ("bodies", "body") if split else ("meshes", "mesh")


def _with_note(r: LabelVoxelization, split: bool = False) -> LabelVoxelization:
    """The result with its one line on overlaps and empty labels (of the
    bodies of files, with ``split``)."""
    import dataclasses

    parts = []
    things, thing = _things(split)
    if r.overlaps:
        parts.append(overlap_text(r, things) + f"; the later {thing}'s label wins (--overlap error / "
                                               "overlap='error' refuses)")
    empty = [i for i, c in enumerate(r.voxels, 1) if c == 0]
    if empty:
        which = ", ".join(f"{i} ({r.names[i - 1]})" for i in empty[:NAMED_PAIRS])
        parts.append(f"label{'s' if len(empty) > 1 else ''} {which} got no voxel (smaller than a voxel, no "
                     f"solid, or covered by later {things})")
    return dataclasses.replace(r, note="; ".join(parts) or None)
