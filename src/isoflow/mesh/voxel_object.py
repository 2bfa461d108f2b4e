"""The voxels a voxel surface bounds, read at its own grid.

A boundary mesh of voxels (``isoflow surface``, or any mesh whose faces are
unit squares of one lattice) bounds a set of voxels exactly: every face lies
on a lattice plane and every voxel centre is half a pitch off it, so the
winding number at the centres has no ties. Where the voxels touch only along
an edge or at a corner (edge and vertex contacts), the mesh touches itself
there: the file splits those points, a reader that welds equal positions
joins them, and neither the mesh's genus nor the solid manifold3d builds says
what the connectivity of the voxels says. The voxels' Betti numbers at their
own grid, read with the connectivity the digital rows use, do: that is the
reference :func:`~isoflow.mesh.genus.verify_genus` compares such a mesh with.
"""

from __future__ import annotations

import json
import os
import re
import struct
import warnings

import numpy as np

from ..digital.topology import betti_numbers
from ..errors import MeshNote
from ..scale import memory
from .grid import grid_fits
from .load import used_vertices
from .voxelize import voxelize

#: a lattice coordinate is taken as on the lattice within this share of a pitch
#: (an STL's float32 positions move them by up to half a float32 step)
LATTICE_TOLERANCE = 1e-3

#: bytes a voxel of the native grid takes while it is voxelised and labelled
_BYTES_PER_VOXEL = 16


def voxel_lattice(vertices: np.ndarray, faces: np.ndarray) -> tuple[float, np.ndarray, tuple[int, int, int]] | None:
    """The grid of a mesh whose faces are pieces of unit squares of one
    lattice, or None.

    The pitch is the longest step of a face edge along an axis; every face
    must lie in a plane of the lattice perpendicular to an axis, and every
    vertex on the lattice or on the middle of a lattice edge (the midpoints
    ``isoflow surface`` puts on an edge one sheet passes twice).

    Parameters
    ----------
    vertices : numpy.ndarray
        (N, 3) float64 positions.
    faces : numpy.ndarray
        (M, 3) vertex indices.

    Returns
    -------
    tuple or None
        ``(pitch, origin, shape)``: the grid's pitch, its lower corner
        (the mesh's) and its shape in voxels, or None where the mesh is no
        voxel surface.

    Examples
    --------
    >>> import trimesh
    >>> ball = trimesh.creation.icosphere(1)
    >>> voxel_lattice(ball.vertices, ball.faces) is None  # faces across the axes
    True
    >>> from isoflow import boundary_mesh
    >>> vol = np.zeros((3, 3, 3), bool); vol[1, 1, :2] = True
    >>> m = boundary_mesh(vol, 6)
    >>> tri = np.concatenate([m.faces[:, [0, 1, 2]], m.faces[:, [0, 2, 3]]])
    >>> pitch, origin, shape = voxel_lattice(m.vertices, tri)
    >>> float(pitch), shape
    (1.0, (1, 1, 2))
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces)
    if len(f) == 0 or f.ndim != 2 or f.shape[1] != 3:
        return None
    corners = v[f]
    used = used_vertices(v, f)
    lo, hi = used.min(axis=0), used.max(axis=0)
    steps = np.abs(corners[:, [1, 2, 0]] - corners).max()
    if not np.isfinite(steps) or not steps > 0:
        return None
    extent = hi - lo
    longest = int(np.argmax(extent))
    n = round(float(extent[longest]) / float(steps))
    if n < 1:
        return None
    pitch = float(extent[longest]) / n
    half = (used - lo) / pitch * 2.0
    if not np.all(np.abs(half - np.round(half)) <= 2 * LATTICE_TOLERANCE):
        return None
    # every face flat across one axis, on a lattice plane (not a half one):
    # the voxel centres then lie half a pitch off every face
    flat = np.ptp(corners, axis=1) == 0
    if not flat.any(axis=1).all():
        return None
    axis = np.argmax(flat, axis=1)
    plane = (corners[np.arange(len(f)), 0, axis] - lo[axis]) / pitch
    if not np.all(np.abs(plane - np.round(plane)) <= LATTICE_TOLERANCE):
        return None
    if np.abs(corners[:, [1, 2, 0]] - corners).max(axis=(1, 2)).max() > pitch * (1 + LATTICE_TOLERANCE):
        return None
    shape = tuple(int(x) for x in np.round(extent / pitch))
    if min(shape) < 1:
        return None
    return pitch, lo, shape  # type: ignore[return-value]


def voxel_object(vertices: np.ndarray, faces: np.ndarray, connectivity: int) -> dict | None:
    """The voxels a voxel surface bounds at its own grid
    (:func:`voxel_lattice`) and their Betti numbers at ``connectivity``,
    or None where the mesh is no voxel surface or the grid does not fit
    in the memory budget.

    Parameters
    ----------
    vertices : numpy.ndarray
        (N, 3) float64 positions.
    faces : numpy.ndarray
        (M, 3) vertex indices of a closed, consistently oriented mesh.
    connectivity : {6, 26}
        The voxels' (the background's is the other).

    Returns
    -------
    dict or None
        ``pitch``, ``origin`` (a list), ``shape``, ``voxels``,
        ``connectivity``, ``betti`` (b0, b1, b2) and ``genus`` (b1), and
        ``other``: the Betti numbers at the other connectivity (they differ
        only where the voxels have edge or vertex contacts).

    Examples
    --------
    >>> from isoflow import boundary_mesh
    >>> vol = np.zeros((4, 4, 3), bool); vol[1, 1, 1] = vol[2, 2, 1] = True   # an edge contact
    >>> m = boundary_mesh(vol, 6)
    >>> tri = np.concatenate([m.faces[:, [0, 1, 2]], m.faces[:, [0, 2, 3]]])
    >>> seen = voxel_object(m.vertices, tri, 6)
    >>> seen["betti"], seen["other"]
    ([2, 0, 0], [1, 0, 0])
    """
    grid = voxel_lattice(vertices, faces)
    if grid is None:
        return None
    pitch, origin, shape = grid
    if not grid_fits(shape, _BYTES_PER_VOXEL, 0, memory.default_budget()):
        return None
    with warnings.catch_warnings():
        # the digital rows voxelise the same faces and say what they find
        warnings.simplefilter("ignore", MeshNote)
        vol = voxelize(vertices, faces, pitch=pitch, grid=(origin, shape))[0]
    betti = [int(b) for b in betti_numbers(vol, connectivity)]
    other = [int(b) for b in betti_numbers(vol, 32 - connectivity)]
    return {"pitch": pitch, "origin": [float(x) for x in origin], "shape": list(shape), "voxels": int(vol.sum()),
            "connectivity": int(connectivity), "betti": betti, "genus": betti[1], "other": other}


#: ``isoflow surface of NAME, 6-connectivity`` (the command line) or
#: ``isoflow write_surface, 26-connectivity`` (the library)
_WRITTEN = re.compile(r"isoflow [^\n]*?\b(6|26)-connectivity")


def written_connectivity(path: str | os.PathLike) -> int | None:
    """The connectivity a surface file that ``isoflow surface`` or
    ``write_surface`` wrote records (the PLY's and OBJ's comments, the
    STL's header, the GLB's ``extras``), or None where the file records
    none (another program's file).

    Parameters
    ----------
    path : str or os.PathLike
        The mesh file.

    Returns
    -------
    int or None
        6 or 26.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.ply"
    >>> _ = p.write_bytes(b"ply\\ncomment isoflow surface of v.npy, 26-connectivity\\nend_header\\n")
    >>> written_connectivity(p)
    26
    """
    try:
        with open(path, "rb") as fh:
            head = fh.read(1 << 16)
    except OSError:
        return None
    text = ""
    if head.startswith(b"ply"):
        text = head.split(b"end_header", 1)[0].decode("latin-1")
        text = "\n".join(line for line in text.splitlines() if line.startswith("comment"))
    elif head.startswith(b"isoflow "):  # a binary STL's 80-byte header
        text = head[:80].decode("latin-1")
    elif head.startswith(b"#"):  # an OBJ's leading comments
        text = "\n".join(line for line in head.decode("latin-1").splitlines()[:8] if line.startswith("#"))
    elif head[:4] == b"glTF" and len(head) >= 20:
        size = struct.unpack("<I", head[12:16])[0]
        try:
            doc = json.loads(head[20:20 + size])
        except ValueError:
            return None
        text = " ".join(str((m.get("extras") or {}).get("isoflow", "")) for m in doc.get("meshes", [])
                        if isinstance(m, dict))
    found = _WRITTEN.search(text)
    return int(found.group(1)) if found else None
