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

import numpy as np

from ..scale.arrays import index_dtype
from ..scale.compiled import Method
from .surface import QuadMesh, boundary_mesh, pinch_lut

#: voxels of one batch of boxes (its mask, and the mesh's passes over it)
BATCH_VOXELS = 1 << 22


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
    lo, hi = np.asarray(lo, np.int64).reshape(-1, 3), np.asarray(hi, np.int64).reshape(-1, 3)
    extent = hi - lo
    out: list[tuple[QuadMesh, np.ndarray] | None] = [None] * len(labels)
    order = np.argsort(-(extent[:, 1] * extent[:, 2]), kind="stable")
    at = 0
    while at < len(order):
        # the boxes of a batch: while their layers, one empty between, fit
        batch = [int(order[at])]
        ny, nz, nx = int(extent[order[at], 1]), int(extent[order[at], 2]), int(extent[order[at], 0]) + 1
        at += 1
        while at < len(order):
            t = int(order[at])
            wide, deep = max(ny, int(extent[t, 1])), max(nz, int(extent[t, 2]))
            if (nx + int(extent[t, 0]) + 1) * wide * deep > BATCH_VOXELS:
                break
            batch.append(t)
            ny, nz, nx = wide, deep, nx + int(extent[t, 0]) + 1
            at += 1
        shape = (nx, ny, nz)
        for t, found in zip(batch, _batch_meshes(image, labels, lo, extent, batch, shape, connectivity, method)):
            out[t] = found
    return out  # type: ignore[return-value]


def _batch_meshes(image, labels, lo, extent, batch: list[int], shape: tuple[int, int, int], connectivity: int,
                  method: Method) -> list[tuple[QuadMesh, np.ndarray]]:
    """The boxes of ``batch`` laid along axis 0 in a volume of ``shape``
    (each box, then an empty layer), meshed once and cut apart."""
    vol = np.zeros(shape, bool)
    starts = np.zeros(len(batch) + 1, np.int64)
    masks = []
    for s, t in enumerate(batch):
        a, e = lo[t], extent[t]
        x = int(starts[s])
        vol[x:x + e[0], :e[1], :e[2]] = image[a[0]:a[0] + e[0], a[1]:a[1] + e[1], a[2]:a[2] + e[2]] == labels[t]
        masks.append(vol[x:x + e[0], :e[1], :e[2]])
        starts[s + 1] = x + e[0] + 1
    mesh = boundary_mesh(vol, connectivity, method)
    # a vertex's box: that of its lattice layer (a box's last layer is its
    # own, the empty layer after it has no vertex; a midpoint lies within)
    slot_of_layer = np.repeat(np.arange(len(batch)), np.diff(starts))
    slot = slot_of_layer[np.floor(mesh.vertices[:, 0]).astype(np.int64)]
    vorder = np.argsort(slot, kind="stable")
    new_index = np.empty(len(vorder), np.int64)
    new_index[vorder] = np.arange(len(vorder))
    vfirst = np.searchsorted(slot[vorder], np.arange(len(batch) + 1))
    face_slot = slot[mesh.faces[:, 0]]
    forder = np.argsort(face_slot, kind="stable")
    ffirst = np.searchsorted(face_slot[forder], np.arange(len(batch) + 1))
    # every part's arrays at once, in its box's units and numbering; the
    # parts are then slices
    vertices, config, sheet = mesh.vertices[vorder], mesh.config[vorder], mesh.sheet[vorder]
    vertices[:, 0] -= starts[slot[vorder]]
    idx = index_dtype(int(np.diff(vfirst).max(initial=0)))
    local = new_index - vfirst[slot]  # each vertex's number within its part
    faces = local[mesh.faces[forder]].astype(idx)
    midpoint = mesh.edge_midpoint[forder]
    midpoint = np.where(midpoint >= 0, local[np.maximum(midpoint, 0)], -1).astype(idx)
    normals = mesh.face_normals[forder]
    lone = (pinch_lut(connectivity)[config].astype(bool) & (sheet == 0)).astype(np.int64)
    pinched = np.add.reduceat(lone, vfirst[:-1]) if len(lone) else np.zeros(len(batch), np.int64)
    out = []
    for s in range(len(batch)):
        v0, v1, f0, f1 = vfirst[s], vfirst[s + 1], ffirst[s], ffirst[s + 1]
        part = QuadMesh(vertices=vertices[v0:v1], faces=faces[f0:f1], edge_midpoint=midpoint[f0:f1],
                        face_normals=normals[f0:f1], config=config[v0:v1], sheet=sheet[v0:v1],
                        connectivity=connectivity, pinched=int(pinched[s]))
        out.append((part, masks[s]))
    return out
