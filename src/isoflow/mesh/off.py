"""Object File Format (``.off``), read here rather than by trimesh.

trimesh 4-5's OFF reader keeps face indices as strings and fails on any
face of five or more corners under NumPy 2 (its fan triangulation
multiplies strings), and it reads a file that lists fewer faces or vertices
than its header says without a word. This reader takes the ASCII variants
people write (``OFF``, ``COFF``, ``NOFF``, ``CNOFF``, ``STOFF``..., the
counts on the header line or the next, ``#`` comments, colours or normals
after the coordinates and after a face's corners), and Geomview's ``4OFF``
(homogeneous coordinates ``x y z w``, the point ``(x/w, y/w, z/w)``) and
``nOFF`` of space dimension 3, and refuses the rest in one line: binary
OFF, points of another dimension or at infinity (``w = 0``), counts that
do not match the lines, a corner that is not a vertex.

Polygons are cut as :func:`isoflow.mesh.readers.triangulate` cuts them:
into fans from their first corner, as trimesh does, except a concave
polygon whose fan would leave it, which is cut by ears; a polygon that
runs along one of its edges twice (``4 1 2 3 2``: a spike) gives two
triangles that cancel in the winding number.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import IsoflowError
from .readers import triangulate

#: the header keyword: ST (texture), C (colour), N (normal) prefixes
_HEADER = re.compile(r"^(ST)?C?N?(4?)(n?)OFF$")


def read_off(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices float64 (N, 3), triangles int64 (M, 3))`` of an ASCII OFF file."""
    try:
        text = path.read_bytes().decode("utf-8", errors="replace")
    except OSError as exc:
        raise IsoflowError(f"{path}: cannot read ({exc})") from None
    numbered = [(i, ln.split("#", 1)[0].split()) for i, ln in enumerate(text.splitlines(), 1)]
    numbered = [(i, words) for i, words in numbered if words]  # the line numbers name a bad face
    lines = [words for _, words in numbered]
    if not lines:
        raise IsoflowError(f"{path}: empty OFF file")
    head = lines[0]
    m = _HEADER.match(head[0])
    if m is None:
        raise IsoflowError(f"{path}: not an OFF file (its first word is not OFF, COFF, NOFF or the like)")
    if "BINARY" in (w.upper() for w in head[1:]):
        raise IsoflowError(f"{path}: binary OFF is not read; save it as ASCII OFF, PLY or OBJ")
    rest, body = head[1:], lines[1:]
    if m.group(3):  # nOFF: the space dimension comes first, on the header line or the next
        if not rest:
            rest, body = (body[0], body[1:]) if body else ([], [])
        if not rest or rest[0] != "3":
            said = f"of dimension {rest[0]}" if rest else "of no dimension given"
            raise IsoflowError(f"{path}: {head[0]} holds points {said}; isoflow reads 3D OFF (nOFF with 3)")
        rest = rest[1:]
    counts, body = (rest, body) if rest else (body[0] if body else [], body[1:])
    try:
        nv, nf = int(counts[0]), int(counts[1])
    except (IndexError, ValueError):
        raise IsoflowError(f"{path}: OFF counts line {' '.join(counts)!r} is not 'vertices faces edges'") from None
    if nv < 0 or nf < 0 or nv + nf > len(body):
        raise IsoflowError(f"{path}: the OFF header says {nv} vertices and {nf} faces, "
                           f"the file holds {len(body)} lines after it")
    width = 4 if m.group(2) else 3  # 4OFF: homogeneous x y z w
    try:
        vertices = np.array([ln[:width] for ln in body[:nv]], dtype=np.float64).reshape(nv, width)
    except ValueError:
        bad = next(i for i, ln in enumerate(body[:nv]) if len(ln) < width or not _numbers(ln[:width]))
        raise IsoflowError(f"{path}: OFF vertex {bad} is {' '.join(body[bad])!r}, not {width} numbers") from None
    if width == 4:
        vertices = homogeneous_points(vertices, path)
    polygons = []
    for i, ln in enumerate(body[nv:nv + nf]):
        try:
            k = int(ln[0])
            corners = [int(c) for c in ln[1:1 + k]]
        except ValueError:
            corners, k = [], -1
        if k < 3 or len(corners) != k:
            raise IsoflowError(f"{path}: OFF face {i} is {' '.join(ln)!r}, not a corner count and that many indices")
        if not all(0 <= c < nv for c in corners):  # (else a Python IndexError, or -1 read as the last)
            bad = next(c for c in corners if not 0 <= c < nv)
            lineno = numbered[len(lines) - len(body) + nv + i][0]
            raise IsoflowError(f"{path}:{lineno}: OFF face {i} {' '.join(ln)!r} uses vertex {bad}, "
                               f"not one of the {nv} vertices (numbered from 0 to {nv - 1})")
        polygons.append(corners)
    if not polygons:
        return vertices, np.zeros((0, 3), dtype=np.int64)
    sizes = np.array([len(c) for c in polygons], dtype=np.int64)
    flat = np.fromiter((c for corners in polygons for c in corners), dtype=np.int64, count=int(sizes.sum()))
    return vertices, triangulate(flat, sizes, vertices)


def homogeneous_points(xyzw: np.ndarray, path: Path) -> np.ndarray:
    """The 3D points ``(x/w, y/w, z/w)`` of 4OFF's homogeneous coordinates;
    a point at infinity (``w = 0``) is no corner of a surface in space.

    Examples
    --------
    >>> homogeneous_points(np.array([[2.0, 4.0, 6.0, 2.0]]), Path("m.off"))
    array([[1., 2., 3.]])
    """
    w = xyzw[:, 3]
    if not np.all(np.isfinite(w) & (w != 0)):
        bad = int(np.flatnonzero(~(np.isfinite(w) & (w != 0)))[0])
        raise IsoflowError(f"{path}: 4OFF vertex {bad} has w = {w[bad]:g}: a point at infinity, not one of the "
                           "surface's corners (4OFF gives x y z w, the point x/w, y/w, z/w)")
    return xyzw[:, :3] / w[:, None]


def _numbers(fields) -> bool:
    try:
        [float(x) for x in fields]
    except ValueError:
        return False
    return True
