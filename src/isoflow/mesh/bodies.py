"""The meshes of a label image: one per file, or one per body with ``split``.

:func:`voxelize_meshes <isoflow.mesh.label_voxels.voxelize_meshes>` gives
each :class:`Body` a label. Without ``split`` a file is one body (a scene's
meshes joined, as every command reads it). With ``split``:

* a **scene** (glTF/GLB, 3MF, DAE/ZAE, 3DXML, XAML, and archives) gives one
  body per node that holds a triangle mesh, in world coordinates (the
  node's transform applied; a geometry placed by two nodes is two bodies),
  named ``FILE:NODE`` and taken in the natural order of the node names
  (``part2`` before ``part10``: trimesh does not keep the file's order);
* any other mesh (STL with one or several solids, OBJ, PLY, OFF, or arrays)
  gives one body per **connected body**: faces joined across every shared
  edge after the weld, in the order of their first face, named ``FILE:1``,
  ``FILE:2``, ... Bodies that touch along an edge or share a face are one
  body: telling them apart needs the faces' order around each non-manifold
  edge, which the weld's edge table does not hold (trimesh's split joins
  only across edges of two faces, so it parts the first and cuts the second
  into open pieces). A
  closed shell oriented inwards (negative volume: the wall of a cavity)
  stays with the body whose solid holds it, so a hollow part is one body
  with its cavity empty, not a solid and a second solid filling the cavity.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import IsoflowError
from .load import check_mesh, is_scene, load_mesh, mesh_arrays, mesh_bbox, trimesh_load, weld

#: suffixes whose files are scenes of named nodes (split per node)
SCENE_SUFFIXES = (".glb", ".gltf", ".3mf", ".dae", ".zae", ".3dxml", ".xaml", ".zip", ".tar.gz", ".tar.bz2", ".bz2")


@dataclass(frozen=True)
class Body:
    """One mesh of a label image: its name (file, file:node, file:k, or
    mesh k for arrays) and its triangles (welded when read from a file)."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray


def is_scene_path(path) -> bool:
    """Whether a file name ends in one of :data:`SCENE_SUFFIXES` (any case)."""
    name = Path(os.fspath(path)).name.lower()
    return any(name.endswith(s) for s in SCENE_SUFFIXES)


def mesh_bodies(meshes, split: bool = False) -> list[Body]:
    """The bodies of ``meshes`` in order: each a file path, a
    ``(vertices, faces)`` pair or an object with ``vertices`` and ``faces``
    (a ``trimesh.Trimesh``); with ``split``, each one's bodies (see the
    module docstring). Files are welded as :func:`load_mesh` welds them;
    arrays and a :class:`Body` are taken as they are. IsoflowError for an
    empty list or a bad mesh."""
    if isinstance(meshes, (str, os.PathLike)) or hasattr(meshes, "faces") or is_scene(meshes):
        meshes = [meshes]  # one file or one mesh given alone
    bodies: list[Body] = []
    for n, mesh in enumerate(meshes, 1):
        if isinstance(mesh, Body):  # read already
            bodies.append(mesh)
        elif isinstance(mesh, (str, os.PathLike)):
            bodies += file_bodies(mesh, split)
        elif split and is_scene(mesh):
            bodies += scene_bodies(mesh, f"mesh {n}")
        else:
            where = f"mesh {n}"  # arrays are taken as they are, not welded (as voxelize_mesh takes them)
            v, f = check_mesh(*mesh_arrays(mesh, where), where)
            bodies += connected_bodies(v, f, where) if split else [Body(where, v, f)]
    if not bodies:
        raise IsoflowError("voxelize: no meshes given")
    return bodies


def file_bodies(path, split: bool) -> list[Body]:
    """A file's bodies: itself, or with ``split`` its nodes (a scene) or
    its connected bodies."""
    name = os.fspath(path)
    if not split:
        return [Body(str(name), *load_mesh(path))]
    if is_scene_path(path):
        return node_bodies(Path(name))
    return connected_bodies(*load_mesh(path), str(name))


def node_bodies(path: Path) -> list[Body]:
    """One body per node of a scene file that holds a triangle mesh, in
    world coordinates, in the natural order of the node names."""
    return scene_bodies(trimesh_load(path, "scene"), str(path))


def scene_bodies(scene, name: str) -> list[Body]:
    """One body per node of a ``trimesh.Scene`` (named ``name:node``) that
    holds a triangle mesh, as :func:`node_bodies` reads a file's."""
    import trimesh

    bodies = []
    for node in sorted(scene.graph.nodes_geometry, key=natural_key):
        transform, geometry = scene.graph[node]
        mesh = scene.geometry.get(geometry)
        if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
            continue  # a point cloud, a path, an empty mesh: nothing to fill
        where = f"{name}:{node}"
        v = trimesh.transform_points(np.asarray(mesh.vertices, dtype=np.float64), transform)
        v, f = weld(*check_mesh(v, mesh.faces, where), where=where)
        if len(f):  # (every face degenerate: nothing to fill)
            bodies.append(Body(where, v, f))
    if not bodies:
        raise IsoflowError(f"{name}: no node of the scene holds a triangle mesh")
    return bodies


def natural_key(name) -> list:
    """Sort key that orders the numbers in a name by value (``part2``
    before ``part10``)."""
    return [(0, int(t), "") if t.isdigit() else (1, 0, t) for t in re.split(r"(\d+)", str(name)) if t]


def connected_bodies(v: np.ndarray, f: np.ndarray, name: str) -> list[Body]:
    """The connected bodies of a welded mesh (faces joined across shared
    edges), each cavity's inward shell kept with the body that holds it,
    in the order of their first face."""
    from .census import edge_table

    root = edge_table(f, len(v))[5]  # each face's component: its smallest face
    _, comp = np.unique(root, return_inverse=True)  # numbered by first face
    parts = [np.nonzero(comp == c)[0] for c in range(int(comp.max()) + 1)]
    if len(parts) == 1:
        return [Body(name, v, f)]
    owner = cavity_owners(v, f, parts)
    groups: dict[int, list[int]] = {}
    for c in range(len(parts)):
        groups.setdefault(owner[c], []).append(c)
    bodies = []
    for k, members in enumerate(groups.values(), 1):
        faces = f[np.concatenate([parts[c] for c in members])]
        used, faces = np.unique(faces, return_inverse=True)
        bodies.append(Body(f"{name}:{k}", v[used], faces.reshape(-1, 3)))
    return bodies


def cavity_owners(v: np.ndarray, f: np.ndarray, parts: list[np.ndarray]) -> list[int]:
    """For each component, the component it belongs to: itself, or for a
    closed shell of negative volume (a cavity's wall) the smallest
    component of positive volume whose winding number is 1 at a corner of
    it (none found: itself, an inverted solid)."""
    from .census import census

    volume = np.array([signed_volume(v[f[p]]) for p in parts])
    closed = []
    for p in parts:
        lo, hi, fwd, bwd, _ = census(f[p], len(v))
        closed.append(bool(np.all(fwd == bwd)))
    boxes = [mesh_bbox(v, f[p], "split")[:2] for p in parts]
    owner = list(range(len(parts)))
    solids = sorted((c for c in range(len(parts)) if volume[c] > 0), key=lambda c: volume[c])
    for c in range(len(parts)):
        if not (closed[c] and volume[c] < 0):
            continue
        point = v[f[parts[c][0], 0]]
        for s in solids:  # the smallest that holds the cavity is its body
            if np.all(boxes[s][0] <= boxes[c][0]) and np.all(boxes[c][1] <= boxes[s][1]) \
                    and abs(winding_number(v[f[parts[s]]], point)) > 0.5:
                owner[c] = s
                break
    return owner


def signed_volume(T: np.ndarray) -> float:
    """The signed volume the triangles ``T`` (M, 3, 3) bound (positive for
    an outward-oriented closed shell): the sum of their tetrahedra with the
    first corner of the first triangle (the divergence theorem)."""
    c = T[0, 0]
    a, b, d = T[:, 0] - c, T[:, 1] - c, T[:, 2] - c
    return float(np.einsum("ij,ij->i", a, np.cross(b, d)).sum() / 6)


def winding_number(T: np.ndarray, p: np.ndarray) -> float:
    """The winding number of the triangles ``T`` (M, 3, 3) at ``p``: their
    solid angles (Van Oosterom and Strackee 1983) over 4 pi."""
    a, b, c = T[:, 0] - p, T[:, 1] - p, T[:, 2] - p
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb \
        + np.einsum("ij,ij->i", b, c) * la
    return float(2 * np.arctan2(det, den).sum() / (4 * np.pi))
