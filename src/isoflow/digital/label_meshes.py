"""The boundary mesh of every label of a label image, many labels per call
of :func:`~isoflow.digital.surface.boundary_mesh`.

A label's mesh depends on its own voxels only (everything else is its
complement), so the boxes of many labels, each the label's mask, are laid
side by side along the first axis with one empty voxel layer between
them, and meshed at once: a lattice vertex of one box sees no voxel of
another, so each box's part of the mesh is the mesh of that box alone.
The parts are cut apart by the lattice layer of each vertex. Boxes of
like cross-section share a batch (sorted by area), so that the batch's
padding stays small; a box larger than a batch is meshed alone.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from ..scale.arrays import index_dtype
from ..scale.compiled import Method
from .surface import QuadMesh, boundary_mesh, pinch_lut

#: voxels of one batch of boxes (its mask, and the mesh's passes over it)
BATCH_VOXELS = 1 << 22


@dataclass
class Batch:
    """The meshes of some labels' boxes, meshed at once: per-vertex and
    per-face arrays of all the parts, part after part (part ``s`` holds
    vertices ``vfirst[s]:vfirst[s + 1]`` and faces ``ffirst[s]:ffirst[s +
    1]``), vertices in their own box's array-corner units, faces and
    midpoints numbered within their part."""

    rows: list[int]  # the labels' indices, part by part
    masks: list[np.ndarray]  # each box's mask (a view into the batch's volume)
    vertices: np.ndarray
    config: np.ndarray
    sheet: np.ndarray
    faces: np.ndarray
    edge_midpoint: np.ndarray
    face_normals: np.ndarray
    vfirst: np.ndarray
    ffirst: np.ndarray
    pinched: np.ndarray  # per part
    connectivity: int

    def part(self, s: int) -> QuadMesh:
        """Part s as a mesh of its own (views of the batch's arrays)."""
        v0, v1, f0, f1 = self.vfirst[s], self.vfirst[s + 1], self.ffirst[s], self.ffirst[s + 1]
        return QuadMesh(vertices=self.vertices[v0:v1], faces=self.faces[f0:f1],
                        edge_midpoint=self.edge_midpoint[f0:f1], face_normals=self.face_normals[f0:f1],
                        config=self.config[v0:v1], sheet=self.sheet[v0:v1], connectivity=self.connectivity,
                        pinched=int(self.pinched[s]))

    def joined(self) -> QuadMesh:
        """Every part in one mesh object for its per-vertex columns (its
        faces keep their parts' numbering: not a mesh to walk)."""
        return QuadMesh(vertices=self.vertices, faces=self.faces, edge_midpoint=self.edge_midpoint,
                        face_normals=self.face_normals, config=self.config, sheet=self.sheet,
                        connectivity=self.connectivity, pinched=int(self.pinched.sum()))


def label_meshes(image: np.ndarray, labels: np.ndarray, lo: np.ndarray, hi: np.ndarray, connectivity: int = 6,
                 method: Method = "auto") -> list[tuple[QuadMesh, np.ndarray]]:
    """Per label, its boundary mesh in its box and the box's mask.

    Parameters
    ----------
    image : numpy.ndarray
        A 3D label image.
    labels : numpy.ndarray
        The labels, one per box.
    lo, hi : numpy.ndarray
        (n, 3) voxel indices: label i's box is ``image[lo[i, 0]:hi[i, 0],
        ...]`` (it holds every voxel of the label).
    connectivity : {6, 26}
        The labels' connectivity.
    method : {"auto", "numpy", "compiled"}
        How each batch is meshed (:func:`boundary_mesh`).

    Returns
    -------
    list of (QuadMesh, numpy.ndarray)
        Per label, the mesh :func:`boundary_mesh` gives for
        ``image[box] == label`` (vertices in the box's array-corner units;
        the same vertices and faces, in another order) and that mask (a
        view into its batch).

    Examples
    --------
    >>> image = np.zeros((4, 3, 3), np.uint8)
    >>> image[0, 0, 0], image[2:4, 1:3, 1:3] = 1, 2
    >>> found = label_meshes(image, np.array([1, 2]), np.array([[0, 0, 0], [2, 1, 1]]),
    ...                      np.array([[1, 1, 1], [4, 3, 3]]))
    >>> [(len(m.faces), m.euler_characteristic, int(box.sum())) for m, box in found]
    [(6, 2, 1), (24, 2, 8)]
    """
    out: list = [None] * len(labels)
    for batch in label_batches(image, labels, lo, hi, connectivity, method):
        for s, t in enumerate(batch.rows):
            out[t] = (batch.part(s), batch.masks[s])
    return out


def label_batches(image: np.ndarray, labels: np.ndarray, lo: np.ndarray, hi: np.ndarray, connectivity: int = 6,
                  method: Method = "auto") -> Iterator[Batch]:
    """The batches of :func:`label_meshes` (same arguments), one at a time.

    Examples
    --------
    >>> image = np.zeros((4, 3, 3), np.uint8)
    >>> image[0, 0, 0], image[2:4, 1:3, 1:3] = 1, 2
    >>> [(b.rows, b.vfirst.tolist()) for b in label_batches(image, np.array([1, 2]),
    ...  np.array([[0, 0, 0], [2, 1, 1]]), np.array([[1, 1, 1], [4, 3, 3]]))]
    [([1, 0], [0, 26, 34])]
    """
    lo, hi = np.asarray(lo, np.int64).reshape(-1, 3), np.asarray(hi, np.int64).reshape(-1, 3)
    extent = hi - lo
    method = batches_method(extent, method, record=True)
    order = np.argsort(-(extent[:, 1] * extent[:, 2]), kind="stable")
    at = 0
    while at < len(order):
        # the boxes of a batch: while their layers, one empty between, fit
        rows = [int(order[at])]
        ny, nz, nx = int(extent[order[at], 1]), int(extent[order[at], 2]), int(extent[order[at], 0]) + 1
        at += 1
        while at < len(order):
            t = int(order[at])
            wide, deep = max(ny, int(extent[t, 1])), max(nz, int(extent[t, 2]))
            if (nx + int(extent[t, 0]) + 1) * wide * deep > BATCH_VOXELS:
                break
            rows.append(t)
            ny, nz, nx = wide, deep, nx + int(extent[t, 0]) + 1
            at += 1
        yield _batch(image, labels, lo, extent, rows, (nx, ny, nz), connectivity, method)


def batches_method(extent: np.ndarray, method: Method = "auto", record: bool = False) -> Method:
    """How every batch of boxes of ``extent`` (one row per box) is meshed:
    ``"auto"`` decides once for all of them, on their voxels together (each
    box and its empty layer), as :func:`~isoflow.digital.surface.mesh_method`
    decides for one volume: numba's start is paid once for every batch, so
    many batches each below the compiled passes' threshold take them
    together (and with them the voxels that ``"auto"`` has already sent
    down the NumPy passes in this process,
    :func:`~isoflow.scale.compiled.weigh`; ``record``: the batches are
    meshed now, and are counted in that tally).

    Examples
    --------
    >>> few = np.array([[4, 4, 4]] * 10)
    >>> batches_method(few, "numpy"), batches_method(few, "compiled")
    ('numpy', 'compiled')
    """
    from ..scale.compiled import have_numba, weigh

    if method != "auto":
        return method
    voxels = int(((extent[:, 0] + 1) * extent[:, 1] * extent[:, 2]).sum()) if len(extent) else 0
    return "compiled" if have_numba() and weigh(voxels, surfaces=True, record=record) else "numpy"


def _batch(image, labels, lo, extent, rows: list[int], shape: tuple[int, int, int], connectivity: int,
           method: Method) -> Batch:
    """The boxes of ``rows`` laid along axis 0 in a volume of ``shape``
    (each box, then an empty layer), meshed once and cut apart."""
    vol = np.zeros(shape, bool)
    starts = np.concatenate([[0], np.cumsum(extent[rows, 0] + 1)])
    if method == "compiled" and image.dtype.kind in "iu":  # one pass for every box
        from ..scale.box_masks import as_unsigned, box_masks

        box_masks(as_unsigned(image), as_unsigned(np.asarray(labels[rows], image.dtype)), lo[rows], extent[rows],
                  starts, vol)
    else:
        for s, t in enumerate(rows):
            a, e, x = lo[t], extent[t], starts[s]
            vol[x:x + e[0], :e[1], :e[2]] = image[a[0]:a[0] + e[0], a[1]:a[1] + e[1], a[2]:a[2] + e[2]] == labels[t]
    masks = [vol[x:x + e[0], :e[1], :e[2]] for x, e in zip(starts.tolist(), extent[rows].tolist())]
    mesh = boundary_mesh(vol, connectivity, method)
    # a vertex's box: that of its lattice layer (a box's last layer is its
    # own, the empty layer after it has no vertex; a midpoint lies within)
    slot_of_layer = np.repeat(np.arange(len(rows)), np.diff(starts))
    slot = slot_of_layer[mesh.vertices[:, 0].astype(np.int64)]  # (coordinates >= 0: truncation is the floor)
    in_order = not len(slot) or bool((slot[1:] >= slot[:-1]).all())
    # the compiled passes give the vertices layer by layer, so part by part
    # already (and the mesh is this call's own: its vertices are moved in place)
    vorder = None if in_order else np.argsort(slot, kind="stable")
    vertices, config, sheet = (mesh.vertices if mesh.vertices.flags.writeable else mesh.vertices.copy(),
                               mesh.config, mesh.sheet) if in_order else \
        (mesh.vertices[vorder], mesh.config[vorder], mesh.sheet[vorder])
    vslot = slot if in_order else slot[vorder]  # each new vertex's part
    vfirst = np.searchsorted(vslot, np.arange(len(rows) + 1))
    face_slot = slot[mesh.faces[:, 0]]
    faces, midpoint, normals = mesh.faces, mesh.edge_midpoint, mesh.face_normals
    if len(face_slot) and not (face_slot[1:] >= face_slot[:-1]).all():
        forder = np.argsort(face_slot, kind="stable")
        faces, midpoint, normals, face_slot = faces[forder], midpoint[forder], normals[forder], face_slot[forder]
    ffirst = np.searchsorted(face_slot, np.arange(len(rows) + 1))
    # every part's arrays at once, in its box's units and numbering
    vertices[:, 0] -= starts[vslot]
    idx = index_dtype(int(np.diff(vfirst).max(initial=0)))
    if in_order:
        # a face's vertices and midpoints all lie in its own part, so its
        # numbers within the part are the batch's less the part's first
        first = vfirst[face_slot].astype(faces.dtype)[:, None]
        faces = (faces - first).astype(idx, copy=False)
        midpoint = np.where(midpoint >= 0, midpoint - first, -1).astype(idx, copy=False)
    else:
        new_index = np.empty(len(vorder), np.int64)
        new_index[vorder] = np.arange(len(vorder))
        local = new_index - vfirst[slot]  # each vertex's number within its part
        faces = local[faces].astype(idx)
        midpoint = np.where(midpoint >= 0, local[np.maximum(midpoint, 0)], -1).astype(idx)
    # vertex contacts the split mesh separates (few): counted per part
    lone = np.flatnonzero(pinch_lut(connectivity)[config] & (sheet == 0))
    return Batch(rows=rows, masks=masks, vertices=vertices, config=config, sheet=sheet, faces=faces,
                 edge_midpoint=midpoint, face_normals=normals, vfirst=vfirst, ffirst=ffirst,
                 pinched=np.bincount(vslot[lone], minlength=len(rows)),
                 connectivity=connectivity)
