"""Writing the boundary mesh: PLY with per-vertex curvature data, and OBJ.

The writers take plain arrays (vertex columns, faces padded with -1) so that
any polygon mesh can be written; :func:`mesh_vertex_table` makes the columns
of a boundary quad mesh (:class:`isoflow.digital.surface.QuadMesh`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..digital.lattice import DigitalObject
from .outputs import check_output_path


def gamma_colours(gamma: np.ndarray, vertex_class: np.ndarray) -> np.ndarray:
    """RGB (uint8) of the vertex angle gamma (-4..4 eighths): blue for concave,
    white for flat, red for convex, linear in between; green marks vertices
    that are not well-composed, grey the midpoints of doubled edges."""
    palette = _gamma_palette()
    rgb = palette[np.clip(np.asarray(gamma, np.int64), -4, 4) + 4]  # a gather, not float math per vertex
    rgb[vertex_class == -1] = (20, 170, 60)
    rgb[vertex_class == -2] = (150, 150, 150)
    return rgb


def _gamma_palette() -> np.ndarray:
    """Colour of gamma = -4 .. 4: blue - white - red, linear in between."""
    t = np.arange(-4, 5) / 4.0
    white = np.array([255.0, 255.0, 255.0])
    red = np.array([200.0, 30.0, 30.0])
    blue = np.array([30.0, 60.0, 200.0])
    pos = np.clip(t, 0, 1)[:, None]
    neg = np.clip(-t, 0, 1)[:, None]
    return np.round(white * (1 - pos - neg) + red * pos + blue * neg).astype(np.uint8)


def mesh_vertex_table(mesh, obj: DigitalObject) -> dict[str, np.ndarray]:
    """Per-vertex columns written to PLY: position (world), curvature data."""
    xyz = obj.world(mesh.vertices)
    cls = mesh.vertex_class
    rgb = gamma_colours(mesh.gamma, cls)
    return {
        "x": xyz[:, 0].astype(np.float32),
        "y": xyz[:, 1].astype(np.float32),
        "z": xyz[:, 2].astype(np.float32),
        "config": mesh.config.astype(np.uint8),
        "class": cls.astype(np.int8),
        "gamma": mesh.gamma.astype(np.int8),
        "a": mesh.a.astype(np.int8),
        "f": mesh.f.astype(np.int8),
        "red": rgb[:, 0],
        "green": rgb[:, 1],
        "blue": rgb[:, 2],
    }


_PLY_TYPES = {"f4": "float", "u1": "uchar", "i1": "char", "i4": "int", "f8": "double"}


def _size_groups(faces: np.ndarray):
    """Faces padded with -1, grouped by their number of vertices."""
    faces = np.asarray(faces, dtype=np.int64)
    sizes = (faces >= 0).sum(axis=1) if faces.size else np.zeros(0, np.int64)
    for size in np.unique(sizes):
        rows = faces[sizes == size]
        # -1 slots can sit between vertices (a missing midpoint): drop them
        # keeping the cyclic order. A boolean mask reads row by row, and
        # every row of the group keeps exactly `size` slots.
        yield int(size), rows[rows >= 0].reshape(len(rows), size)


def write_ply(
    path: str | os.PathLike,
    columns: dict[str, np.ndarray],
    faces: np.ndarray,
    *,
    ascii: bool = False,
    force: bool = False,
    comments: tuple[str, ...] = (),
) -> Path:
    """Write a PLY with per-vertex scalar columns and polygon faces.

    ``faces`` is (F, K) with -1 padding for faces with fewer than K vertices.
    Binary little-endian by default. Quads stay quads (MeshLab and trimesh
    read them); faces are written grouped by size.
    """
    path = Path(path)
    check_output_path(path, force)
    names = list(columns)
    n = len(columns[names[0]])
    groups = list(_size_groups(faces))
    header = ["ply", f"format {'ascii' if ascii else 'binary_little_endian'} 1.0"]
    header += [f"comment {c}" for c in comments]
    header.append(f"element vertex {n}")
    for k in names:
        header.append(f"property {_PLY_TYPES[columns[k].dtype.str[1:]]} {k}")
    header.append(f"element face {sum(len(g) for _, g in groups)}")
    header.append("property list uchar int vertex_indices")
    header.append("end_header")
    with open(path, "wb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        if ascii:
            fmt = " ".join("%.9g" if columns[k].dtype.kind == "f" else "%d" for k in names)
            if n:
                table = np.column_stack([columns[k].astype(np.float64) for k in names])
                np.savetxt(fh, table, fmt=fmt)
            for size, rows in groups:
                np.savetxt(fh, np.column_stack([np.full(len(rows), size), rows]), fmt="%d")
        else:
            vrec = np.empty(n, dtype=[(k, columns[k].dtype.newbyteorder("<")) for k in names])
            for k in names:
                vrec[k] = columns[k]
            fh.write(vrec.tobytes())
            for size, rows in groups:
                rec = np.empty(len(rows), dtype=[("n", "u1"), ("i", "<i4", (size,))])
                rec["n"] = size
                rec["i"] = rows
                fh.write(rec.tobytes())
    return path


def write_obj(
    path: str | os.PathLike,
    vertices: np.ndarray,
    faces: np.ndarray,
    *,
    force: bool = False,
    comments: tuple[str, ...] = (),
) -> Path:
    """Write an OBJ with polygon faces (quads stay quads); ``faces`` as in
    :func:`write_ply`."""
    path = Path(path)
    check_output_path(path, force)
    with open(path, "w") as fh:
        for c in comments:
            fh.write(f"# {c}\n")
        if len(vertices):
            np.savetxt(fh, vertices, fmt="v %.9g %.9g %.9g")
        for size, rows in _size_groups(faces):
            np.savetxt(fh, rows + 1, fmt="f" + " %d" * size)
    return path
