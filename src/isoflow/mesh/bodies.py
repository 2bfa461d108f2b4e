"""The meshes of a label image: one per file, or one per body with ``split``.

:func:`voxelize_meshes <isoflow.mesh.label_voxels.voxelize_meshes>` gives
each :class:`Body` a label. Without ``split`` a file is one body (a scene's
meshes joined, as every command reads it). With ``split``:

* a **scene** (glTF/GLB, 3MF, DAE/ZAE, 3DXML, XAML, and archives) gives one
  body per node that holds a triangle mesh, in world coordinates (the
  node's transform applied; a geometry placed by two nodes is two bodies),
  named ``FILE:NODE`` and taken in the file's order: a glTF/GLB file's
  ``nodes`` (trimesh's scene graph holds them in another order, its
  traversal's; a node of several primitives is one body), any other
  scene's in the natural order of the node names
  (``part2`` before ``part10``);
  an archive's nodes are named by its files, ``FILE:MEMBER``
  (:func:`archive_bodies`);
* an ASCII STL of several solids that name themselves (``solid bracket``
  ... ``endsolid bracket``) gives one body per solid, named
  ``FILE:bracket``, in the file's order (:func:`solid_bodies`): a solid of
  several bodies is one;
* any other mesh (a binary STL, an STL of one solid or of solids none of
  which is named, OBJ, PLY, OFF, or
  arrays) gives one body per **connected body**, named ``FILE:1``,
  ``FILE:2``, ... in the order of their first face. Faces are joined
  across the edges of the mesh after the weld, corners within the
  T-junction split's tolerance counting as one (:func:`near_roots`: a
  soup whose copies of a corner were rounded apart is one body per solid,
  its faces kept as written): across an edge of one or
  two faces always, and across a non-manifold edge only where they bound
  one wedge of solid around it (:func:`radial_pairs`: the faces in the
  order of their angle around the edge, their orientation saying which
  side is solid). So closed bodies that touch along an edge or share a
  face (written once per body, coincident faces) are parted, each whole
  and closed, where trimesh's split (which joins only across edges of two
  faces) cuts the second into open pieces. Where the faces around a
  non-manifold edge do not alternate in orientation (three fins, a
  double-sided sheet on a solid, a degenerate face), they are all joined;
  a solid written double-sided (each face also the other way round) stays
  one body; and where a piece would come out open (an edge of it not used
  as often each way), all that shares edges with it stays one body: an
  open mesh or a soup is parted only where no edge joins it, as before. A
  closed shell oriented inwards (negative volume: the wall of a cavity)
  stays with the body whose solid holds it, so a hollow part is one body
  with its cavity empty, not a solid and a second solid filling the
  cavity.
"""

from __future__ import annotations

import dataclasses
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import IsoflowError
from .load import (
    ARCHIVE_TYPES,
    check_mesh,
    check_mesh_file,
    is_scene,
    load_mesh,
    mesh_arrays,
    mesh_bbox,
    mesh_members,
    point_cloud_line,
    reading_mesh,
    trimesh_load,
    weld,
)
from .mesh_units import common_unit, declared_units

#: suffixes whose files are scenes of named nodes (split per node)
SCENE_SUFFIXES = (".glb", ".gltf", ".3mf", ".dae", ".zae", ".3dxml", ".xaml", ".zip", ".tar.gz", ".tar.bz2", ".bz2")


@dataclass(frozen=True)
class Body:
    """One mesh of a label image: its name (file, file:node, file:solid,
    file:k, or mesh k for arrays), its triangles (welded when read from
    a file) and the length unit its file declares
    (:func:`~isoflow.mesh.mesh_units.declared_unit`; None for arrays and
    formats that hold none)."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    unit: str | None = None


def is_scene_path(path) -> bool:
    """Whether a file name ends in one of :data:`SCENE_SUFFIXES` (any case)."""
    name = Path(os.fspath(path)).name.lower()
    return any(name.endswith(s) for s in SCENE_SUFFIXES)


def mesh_bodies(meshes, split: bool = False) -> list[Body]:
    """The bodies of ``meshes`` in order: each a file path, a
    ``(vertices, faces)`` pair or an object with ``vertices`` and ``faces``
    (a ``trimesh.Trimesh``); with ``split``, each one's bodies (see the
    module docstring). Files are welded as :func:`load_mesh` welds them;
    arrays and a :class:`Body` are taken as they are. A file's bodies carry
    the unit it declares (the grid's is
    :func:`~isoflow.mesh.mesh_units.common_unit` of theirs). IsoflowError
    for an empty list, a bad mesh, or files declaring different units."""
    if isinstance(meshes, (str, os.PathLike)) or hasattr(meshes, "faces") or is_scene(meshes):
        meshes = [meshes]  # one file or one mesh given alone
    if is_bare_pair(meshes):  # read as two meshes its vertices and its faces would be refused as neither
        raise IsoflowError("voxelize: meshes is one (vertices, faces) pair, not a list of meshes: "
                           "pass [(vertices, faces)]")
    # each file's unit read once, and carried by its bodies (a body read already carries its own): one grid
    # places them by their numbers, so meshes declaring different units are refused before any is read
    units = [m.unit if isinstance(m, Body) else u for m, u in zip(meshes, declared_units(meshes))]
    common_unit([m.name if isinstance(m, Body) else os.fspath(m) if isinstance(m, (str, os.PathLike)) else ""
                 for m in meshes], units)
    bodies: list[Body] = []
    for n, (mesh, unit) in enumerate(zip(meshes, units), 1):
        if isinstance(mesh, Body):  # read already
            bodies.append(mesh)
        elif isinstance(mesh, (str, os.PathLike)):
            bodies += [dataclasses.replace(b, unit=unit) for b in file_bodies(mesh, split)]
        elif split and is_scene(mesh):
            bodies += scene_bodies(mesh, f"mesh {n}")
        else:
            where = f"mesh {n}"  # arrays are taken as they are, not welded (as voxelize_mesh takes them)
            v, f = check_mesh(*mesh_arrays(mesh, where), where)
            bodies += connected_bodies(v, f, where) if split else [Body(where, v, f)]
    if not bodies:
        raise IsoflowError("voxelize: no meshes given")
    return bodies


def is_rows(values: object) -> bool:
    """Whether ``values`` is a table of numbers (a 2D numeric array, or a
    non-empty list of lists of numbers), as a mesh's vertices or faces are
    and no mesh is.

    Parameters
    ----------
    values : object
        One item of what was given as the list of meshes.

    Returns
    -------
    bool
        True for a table of numbers.

    Examples
    --------
    >>> is_rows(np.zeros((3, 3))), is_rows([[0, 1, 2]]), is_rows("part.stl")
    (True, True, False)
    """
    if isinstance(values, np.ndarray):
        return values.ndim == 2 and values.dtype.kind in "iuf"
    return (isinstance(values, (list, tuple)) and len(values) > 0
            and all(isinstance(row, (list, tuple)) and all(isinstance(x, (int, float, np.number)) for x in row)
                    for row in values))


def is_bare_pair(meshes: object) -> bool:
    """Whether ``meshes`` is a single ``(vertices, faces)`` pair rather than
    a list of meshes.

    Parameters
    ----------
    meshes : object
        What was given as the list of meshes.

    Returns
    -------
    bool
        True where both of its two items are tables of numbers.

    Examples
    --------
    >>> v, f = [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]
    >>> is_bare_pair((v, f)), is_bare_pair([(v, f)])
    (True, False)
    """
    return isinstance(meshes, (tuple, list)) and len(meshes) == 2 and all(is_rows(m) for m in meshes)


def file_bodies(path, split: bool) -> list[Body]:
    """A file's bodies: itself, or with ``split`` its nodes (a scene), its
    named solids (an ASCII STL: :func:`solid_bodies`) or its connected
    bodies."""
    name = os.fspath(path)
    if not split:
        return [Body(str(name), *load_mesh(path))]
    if is_scene_path(path):
        return node_bodies(Path(name))
    solids = solid_bodies(Path(name))
    return solids if solids is not None else connected_bodies(*load_mesh(path), str(name))


#: the suffixes of STL files, whose named solids :func:`solid_bodies` reads
STL_SUFFIXES = (".stl", ".stl_ascii")


def solid_bodies(path: Path) -> list[Body] | None:
    """One body per solid of an ASCII STL file of several solids some of
    which are named (``solid bracket`` ... ``endsolid bracket``), named
    ``FILE:NAME`` in the file's order, each solid welded alone as a scene's
    node is (a solid of several bodies stays one); None for any other file
    (a binary STL, one solid, solids none of which is named: their
    connected bodies are the labels).

    An unnamed solid among named ones is named by its number among the
    file's solids (``FILE:2``); a name given before is made unique as
    trimesh names the solids of such a file (``bolt``, ``bolt_1``). A
    solid without a facet gives no body, as a scene's empty node.

    Parameters
    ----------
    path : Path
        The mesh file.

    Returns
    -------
    list of Body or None

    Examples
    --------
    >>> import tempfile
    >>> facet = "facet normal 0 0 1\\nouter loop\\nvertex 0 0 0\\nvertex 1 0 0\\nvertex 0 1 0\\nendloop\\nendfacet\\n"
    >>> p = Path(tempfile.mkdtemp()) / "parts.stl"
    >>> _ = p.write_text("".join(f"solid {n}\\n{facet}endsolid {n}\\n" for n in ("bolt", "", "bolt")))
    >>> [b.name[len(str(p)):] for b in solid_bodies(p)]
    [':bolt', ':2', ':bolt_1']
    """
    from .sniff import sniff_mesh_format

    if not path.name.lower().endswith(STL_SUFFIXES):
        return None
    try:
        with open(path, "rb") as fh:
            head = fh.read(84)
            if sniff_mesh_format(head, path.stat().st_size) == "stl-binary":
                return None  # a binary STL (no solid names), not read twice
            data = head + fh.read()
    except OSError:
        return None  # load_mesh says what is wrong with the file
    return stl_solid_bodies(data, str(path))


def stl_solid_bodies(data: bytes, name: str) -> list[Body] | None:
    """:func:`solid_bodies` of an STL file's bytes (an archive's member),
    each body named ``name:SOLID``, in the file's order; None where the
    file is no ASCII STL of several solids some of which are named.

    Parameters
    ----------
    data : bytes
        The file's content.
    name : str
        The file, as the bodies' names start.

    Returns
    -------
    list of Body or None

    Examples
    --------
    >>> facet = b"facet normal 0 0 1\\nouter loop\\nvertex 0 0 0\\nvertex 1 0 0\\nvertex 0 1 0\\nendloop\\nendfacet\\n"
    >>> [b.name for b in stl_solid_bodies(b"solid zeta\\n" + facet + b"endsolid\\nsolid alpha\\n" + facet + b"endsolid\\n",
    ...                                   "parts.zip:a.stl")]
    ['parts.zip:a.stl:zeta', 'parts.zip:a.stl:alpha']
    """
    from .readers import stl_solids

    solids = stl_solids(data)
    if solids is None or len(solids) < 2 or not any(solid for solid, _ in solids):
        return None
    from trimesh.util import unique_name

    taken: dict[str, None] = {}
    bodies = []
    for k, (solid, (v, f)) in enumerate(solids, 1):
        solid = unique_name(solid or str(k), taken)
        taken[solid] = None
        where = f"{name}:{solid}"
        v, f = weld(*check_mesh(v, f, where), where=where)
        if len(f):  # (every face degenerate: nothing to fill)
            bodies.append(Body(where, v, f))
    return bodies


def node_bodies(path: Path) -> list[Body]:
    """One body per node of a scene file that holds a triangle mesh, in
    world coordinates, in the file's order (:func:`scene_bodies`)."""
    kind = next((t for suffix, t in ARCHIVE_TYPES.items() if path.name.lower().endswith(suffix)), None)
    if kind is not None:
        return archive_bodies(path, kind)
    scene = trimesh_load(path, "scene")
    order, owners = file_order(path.read_bytes(), path.suffix.lower().lstrip("."))
    return scene_bodies(scene, str(path), order, owners)


def archive_bodies(path: Path, kind: str) -> list[Body]:
    """One body per node of each mesh file in an archive, named
    ``FILE:MEMBER`` (``FILE:MEMBER:NODE`` where the member is a scene of
    several, ``FILE:MEMBER:SOLID`` for the named solids of an ASCII STL),
    in the natural order of the member names, then in each member's own
    order (an STL's solids as the file lists them, as
    :func:`solid_bodies` takes a file's). trimesh's scene of a whole
    archive names the nodes of its members at random
    (``geometry_0f7d...``), so that order, the labels', would change from
    one run to the next; the order of the names is the one the files have
    unpacked, whichever archiver stored them."""
    import trimesh

    check_mesh_file(path)
    bodies: list[Body] = []
    with reading_mesh(path):
        for member, member_kind, data, scene in mesh_members(path, kind, key=natural_key):
            # trimesh's scene holds an STL's solids by name: the file's order is read from its text
            solids = stl_solid_bodies(data, f"{path}:{member}") if member_kind == "stl" else None
            if solids is not None:
                bodies += solids
                continue
            order, owners = file_order(data, member_kind)
            # the file's nodes that hold a mesh (a glTF node of several primitives is one, as is a
            # COLLADA geometry of several placed once)
            meshes = {_body_of(scene, n, mesh, order, owners) for n in scene.graph.nodes_geometry
                      if isinstance(mesh := scene.geometry.get(scene.graph[n][1]), trimesh.Trimesh)}
            named = scene_bodies(scene, f"{path}:{member}", order, owners)
            bodies += [Body(f"{path}:{member}", b.vertices, b.faces) for b in named] if len(meshes) == 1 else named
    if not bodies:
        raise IsoflowError(f"{path}: no file of the archive holds a triangle mesh")
    return bodies


def scene_bodies(scene, name: str, order: dict[str, int] | None = None,
                 owners: dict[str, str] | None = None) -> list[Body]:
    """One body per node of a ``trimesh.Scene`` (named ``name:node``) that
    holds a triangle mesh, as :func:`node_bodies` reads a file's: in the
    order of the file's nodes where ``order`` gives each node's index by
    its name (:func:`gltf_node_order`), else in the natural order of the
    node names. A node trimesh adds under a node of ``order`` (one per
    primitive of a glTF mesh of several, such as a mesh of two materials,
    named with a random suffix) is that node's: the primitives are joined
    and welded as one body, as the pieces of one closed mesh. ``owners``
    names the body each node of trimesh's graph is a piece of, where the
    graph keeps no node of the file (a COLLADA file's: trimesh makes a
    node of each primitive, :func:`collada_placements`).

    Examples
    --------
    >>> import trimesh
    >>> scene, box = trimesh.Scene(), trimesh.creation.box()
    >>> scene.graph.update(frame_to="cube", frame_from=scene.graph.base_frame)
    >>> for node, faces in (("cube_1a2b3c", box.faces[2:]), ("cube_4d5e6f", box.faces[:2])):
    ...     _ = scene.add_geometry(trimesh.Trimesh(box.vertices, faces), node_name=node, parent_node_name="cube")
    >>> [(b.name, len(b.faces)) for b in scene_bodies(scene, "f.glb", {"cube": 0})]
    [('f.glb:cube', 12)]
    """
    import trimesh

    groups: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for node in _scene_order(scene.graph, order):
        transform, geometry = scene.graph[node]
        mesh = scene.geometry.get(geometry)
        if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
            continue  # a point cloud, a path, an empty mesh: nothing to fill
        v = trimesh.transform_points(np.asarray(mesh.vertices, dtype=np.float64), transform)
        groups.setdefault(_body_of(scene, node, mesh, order, owners), []).append((v, np.asarray(mesh.faces)))
    bodies = []
    for node, parts in groups.items():
        where = f"{name}:{node}"
        starts = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
        v = np.concatenate([v for v, _ in parts])
        f = np.concatenate([f + s for (_, f), s in zip(parts, starts)])
        v, f = weld(*check_mesh(v, f, where), where=where)
        if len(f):  # (every face degenerate: nothing to fill)
            bodies.append(Body(where, v, f))
    if not bodies:
        points = sum(len(g.vertices) for g in scene.geometry.values() if isinstance(g, trimesh.PointCloud))
        # a scene of points alone is a scan's point cloud, refused as the merged read refuses it
        raise IsoflowError(point_cloud_line(name, points) if points and all(
            isinstance(g, trimesh.PointCloud) for g in scene.geometry.values())
            else f"{name}: no node of the scene holds a triangle mesh")
    return bodies


#: the suffixes of glTF files, whose node order :func:`gltf_node_order` reads
GLTF_SUFFIXES = (".glb", ".gltf")


def gltf_node_order(data: bytes) -> dict[str, int]:
    """Each node's index in a glTF file's ``nodes``, by the name trimesh's
    scene graph gives it (the file's name made unique as trimesh makes
    it, the index where it has none); empty where the JSON cannot be read.

    Examples
    --------
    >>> gltf_node_order(b'{"nodes": [{"name": "b"}, {"name": "a"}, {"name": "b"}, {}]}')
    {'b': 0, 'a': 1, 'b_1': 2, '3': 3}
    """
    from trimesh.util import unique_name

    from .gltf_extensions import json_of

    tree = json_of(data, glb=data[:4] == b"glTF")  # (trimesh reads it or says why; no order to follow then)
    nodes = tree.get("nodes") if tree is not None else None
    nodes = nodes if isinstance(nodes, list) else []
    names: dict[str, int] = {}
    counts: dict = {}
    for i, node in enumerate(nodes):
        names[unique_name(str(node.get("name", i)) if isinstance(node, dict) else str(i), names, counts=counts)] = i
    return names


def file_order(data: bytes, kind: str) -> tuple[dict[str, int] | None, dict[str, str] | None]:
    """The order of a scene file's nodes and the body each node of
    trimesh's graph is a piece of (:func:`scene_bodies`), by its format as
    trimesh names it (``glb``, ``dae``): a glTF's nodes
    (:func:`gltf_node_order`), a COLLADA file's placed geometries
    (:func:`collada_placements`); None, None for another format.

    Parameters
    ----------
    data : bytes
        The file's bytes.
    kind : str
        Its format, as its suffix without the dot.

    Returns
    -------
    tuple
        ``(order, owners)``, each a dict or None.

    Examples
    --------
    >>> file_order(b'{"nodes": [{"name": "lid"}]}', "gltf")
    ({'lid': 0}, None)
    >>> file_order(b"solid", "stl")
    (None, None)
    """
    if f".{kind}" in GLTF_SUFFIXES:
        return gltf_node_order(data), None
    if kind in ("dae", "zae"):
        placed = collada_placements(data, zae=kind == "zae")
        return {node: index for node, (index, _) in placed.items()}, {node: body for node, (_, body) in placed.items()}
    return None, None


def collada_placements(data: bytes, zae: bool = False) -> dict[str, tuple[int, str]]:
    """Each node of trimesh's scene of a COLLADA file (DAE, or a ZAE: a zip
    of one) by its name there, as the placed geometry it is a piece of:
    ``(index, name)``, the placement's index in the file's order and the
    name of the node that places it (the geometry's id where no node has
    a name), made unique as trimesh makes names.  trimesh makes a node of
    each primitive of a placed geometry, named by the geometry's id made
    unique (``cubegeo``, ``cubegeo_1``), and keeps no node of the file: a
    geometry of two materials, placed once, would be two open pieces.  The
    file is walked as trimesh's reader walks it (pycollada), to give each
    primitive the name trimesh gives it; empty where pycollada cannot read
    the file (trimesh then says why).

    Parameters
    ----------
    data : bytes
        The file's bytes.
    zae : bool, optional
        Whether they are a ZAE's (its first ``.dae`` member is read, as
        trimesh reads it).

    Returns
    -------
    dict
        ``{trimesh node: (index, name)}``.

    Examples
    --------
    >>> import trimesh
    >>> data = trimesh.exchange.dae.export_collada(trimesh.creation.box())
    >>> list(collada_placements(data).values())  # the geometry placed by trimesh's node0
    [(0, 'node0')]
    """
    try:
        import collada
        from trimesh.util import decompress, unique_name, wrap_as_stream

        stream = wrap_as_stream(data)
        if zae:
            archive = decompress(stream, file_type="zip")
            stream = archive[next(name for name in archive if name.lower().endswith(".dae"))]
        # the errors trimesh's reader lets pass (ignore_broken)
        ignore = [collada.common.DaeError, collada.common.DaeIncompleteError, collada.common.DaeMalformedError,
                  collada.common.DaeBrokenRefError, collada.common.DaeUnsupportedError]
        scene = collada.Collada(stream, ignore=ignore).scene
        walk = _Walk(collada, unique_name)
        for top in (scene.nodes if scene is not None else []):
            walk.place(top, None)
        return walk.placed
    except Exception:  # (trimesh reads it or says why; no placement to follow then)
        return {}


class _Walk:
    """:func:`collada_placements`' walk of a COLLADA scene, in the order of
    trimesh's ``_parse_node``: the names trimesh gives the primitives, and
    the bodies' names, each made unique as trimesh makes them."""

    def __init__(self, collada, unique_name) -> None:
        self.collada, self.unique_name = collada, unique_name
        self.placed: dict[str, tuple[int, str]] = {}
        self.pieces: set[str] = set()
        self.piece_counts: dict = {}
        self.bodies: list[str] = []
        self.body_counts: dict = {}

    def place(self, node, holder: str | None) -> None:
        """``node`` and the nodes below it, ``holder`` the name of the
        nearest named node above (or None)."""
        collada = self.collada
        if isinstance(node, collada.scene.GeometryNode):
            geometry, kept = node.geometry, []
            for primitive in geometry.primitives:
                if isinstance(primitive, collada.polylist.Polylist):
                    primitive = primitive.triangleset()
                if isinstance(primitive, collada.triangleset.TriangleSet) and primitive.vertex is not None:
                    kept.append(self.unique_name(geometry.id, contains=self.pieces, counts=self.piece_counts))
                    self.pieces.add(kept[-1])
            if kept:
                body = self.unique_name(holder or geometry.id, contains=set(self.bodies), counts=self.body_counts)
                self.bodies.append(body)
                self.placed.update((piece, (len(self.bodies) - 1, body)) for piece in kept)
        elif isinstance(node, collada.scene.Node) and node.children is not None:
            name = getattr(node, "name", None) or getattr(node, "id", None)
            for child in node.children:
                self.place(child, name if isinstance(name, str) and name else holder)


def _scene_order(graph, order: dict[str, int] | None) -> list:
    """The scene's mesh nodes in the file's order: by the index of the
    node, or of the nearest node above it that ``order`` names, then in
    trimesh's order; by the natural order of their names without
    ``order``."""
    nodes = list(graph.nodes_geometry)
    if not order:
        return sorted(nodes, key=natural_key)
    index = [order.get(_file_node(graph, n, order), len(order)) for n in nodes]
    return [n for _, _, n in sorted(zip(index, range(len(nodes)), nodes))]


def _body_of(scene, node, mesh, order: dict[str, int] | None, owners: dict[str, str] | None):
    """The body (:func:`scene_bodies`) that ``node`` of trimesh's graph,
    holding ``mesh``, is a piece of: its placed geometry's where
    ``owners`` names them (COLLADA), else its node of the file where
    ``order`` names those (glTF: :func:`_file_node`), else the node whose
    primitive it is (:func:`_primitive_owner`)."""
    if owners:
        return owners.get(node, node)
    return _file_node(scene.graph, node, order) if order else _primitive_owner(scene, node, mesh)


def _file_node(graph, node, order: dict[str, int] | None):
    """The node of the file that ``node`` of trimesh's graph is: the
    nearest of it and the nodes above it that ``order`` names (a node
    trimesh added for a primitive is its glTF node's), else itself."""
    if not order:
        return node
    parents, at = graph.transforms.parents, node
    while at not in order and at in parents:
        at = parents[at]
    return at if at in order else node


def _primitive_owner(scene, node, mesh) -> object:
    """The glTF node a node of trimesh's graph is a primitive of, for a
    scene without its file's order (one given in Python): trimesh marks
    the geometry it reads from a glTF primitive (``from_gltf_primitive``)
    and hangs a node of a mesh of several primitives under the glTF node,
    which holds no geometry itself; else the node itself."""
    parent = scene.graph.transforms.parents.get(node)
    if (not getattr(mesh, "metadata", {}).get("from_gltf_primitive") or parent is None
            or parent == scene.graph.base_frame or parent in scene.graph.nodes_geometry):
        return node
    return parent


def natural_key(name) -> list:
    """Sort key that orders the numbers in a name by value (``part2``
    before ``part10``)."""
    return [(0, int(t), "") if t.isdigit() else (1, 0, t) for t in re.split(r"(\d+)", str(name)) if t]


def connected_bodies(v: np.ndarray, f: np.ndarray, name: str) -> list[Body]:
    """The connected bodies of a welded mesh (faces joined as
    :func:`body_roots` joins them, corners within the T-junction split's
    tolerance counting as one: :func:`near_roots`), each cavity's inward
    shell kept with the body that holds it, in the order of their first
    face. Each body keeps its faces and corners as given."""
    root = near_roots(v, f, name)  # each face's component: its smallest face
    _, comp = np.unique(root, return_inverse=True)  # numbered by first face
    parts = [np.nonzero(comp == c)[0] for c in range(int(comp.max()) + 1)]
    if len(parts) == 1:
        return [Body(name, v, f)]
    owner = cavity_owners(v, f, parts)
    groups: dict[int, list[int]] = {}
    for c in range(len(parts)):
        groups.setdefault(owner[c], []).append(c)
    if len(groups) == 1:  # shells that are one body (a cavity's wall with its solid) keep the mesh's name
        return [Body(name, v, f)]
    bodies = []
    for k, members in enumerate(groups.values(), 1):
        faces = f[np.concatenate([parts[c] for c in members])]
        used, faces = np.unique(faces, return_inverse=True)
        bodies.append(Body(f"{name}:{k}", v[used], faces.reshape(-1, 3)))
    return bodies


def near_roots(v: np.ndarray, f: np.ndarray, where: str = "mesh") -> np.ndarray:
    """Each face's body as :func:`body_roots` finds it, corners closer than
    the T-junction split's tolerance
    (:data:`~isoflow.mesh.t_junctions.T_JUNCTION_RTOL` of the diagonal)
    counting as one corner.

    A soup whose copies of a corner were rounded apart (an exporter's
    float32, a mesh written face by face) shares no corner at the weld's
    1e-10, so each triangle would be a body; at the tolerance the split of
    T-junctions already trusts, the copies meet and a solid is one body.
    Only the corners of open edges (used by one face) are looked at, as
    that split looks, and only the count merges them: the faces are not
    moved. A face that the merge collapses (a sliver narrower than the
    tolerance) goes with a face that shares one of its corners.

    Parameters
    ----------
    v : numpy.ndarray
        ``(n, 3)`` vertex positions.
    f : numpy.ndarray
        ``(m, 3)`` triangles.
    where : str
        The mesh's name in an error.

    Returns
    -------
    numpy.ndarray
        ``(m,)`` each face's body, as its smallest face index.

    Examples
    --------
    Two triangles of a square whose shared corners are 1e-9 apart are one
    body; 0.1 apart, two.

    >>> v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [1e-9, 0, 0], [1, 1 + 1e-9, 0], [0, 1, 0]])
    >>> near_roots(v, np.array([[0, 1, 2], [3, 4, 5]])).tolist()
    [0, 0]
    >>> near_roots(v + np.repeat([[0, 0, 0], [0, 0, 0.1]], 3, axis=0), np.array([[0, 1, 2], [3, 4, 5]])).tolist()
    [0, 1]
    """
    from .census import edge_table
    from .load import weld_groups
    from .t_junctions import T_JUNCTION_RTOL

    f = np.asarray(f, dtype=np.int64).reshape(-1, 3)
    lo, hi, fwd, bwd, _, _ = edge_table(f, len(v))
    # copies rounded apart leave open edges, as the T-junction split looks only at those:
    # a mesh with none (a closed one) is counted as welded, at no cost
    edge_open = fwd + bwd == 1
    if not edge_open.any():
        return body_roots(v, f)
    group = weld_groups(v, f, T_JUNCTION_RTOL, where, among=np.r_[lo[edge_open], hi[edge_open]])
    g = group[f]
    used = np.zeros(len(v), dtype=bool)
    used[f] = True
    merged = np.zeros(int(group.max()) + 1, dtype=bool)
    merged[group[used]] = True
    if np.count_nonzero(merged) == np.count_nonzero(used):  # no corners merged: the mesh as welded
        return body_roots(v, f)
    first = np.full(int(group.max()) + 1, len(v), dtype=np.int64)
    np.minimum.at(first, group, np.arange(len(v)))
    flat = (g[:, 0] == g[:, 1]) | (g[:, 1] == g[:, 2]) | (g[:, 2] == g[:, 0])
    kept = np.flatnonzero(~flat)
    root = np.arange(len(f), dtype=np.int64)
    if len(kept):
        root[kept] = kept[body_roots(v[first], g[kept])]
    # a collapsed face: with the body of a face sharing one of its corners, else its own
    body_of = np.full(len(first), -1, dtype=np.int64)
    body_of[g[kept].ravel()] = np.repeat(root[kept], 3)
    owners = body_of[g[flat]]
    owners = np.where(owners >= 0, owners, len(f)).min(axis=1, initial=len(f))
    root[flat] = np.where(owners < len(f), owners, root[flat])
    return _smallest(root)


def _smallest(root: np.ndarray) -> np.ndarray:
    """Component labels as each component's smallest face index (its first
    occurrence, as :func:`components_roots` numbers them)."""
    _, first, label = np.unique(root, return_index=True, return_inverse=True)
    return first[label]


#: faces around an edge whose angles differ by less than this (radians)
#: are coincident: one half-plane, ordered by orientation
RADIAL_TIE = 1e-8


def body_roots(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Each face's body as its smallest face index: faces joined across an
    edge of one or two faces, and across a non-manifold edge only where
    they bound one wedge of solid (:func:`radial_pairs`). A piece whose
    every face has a twin of opposite orientation (a double-sided solid)
    is joined to its twins' pieces, and a component of the edge table
    (faces joined across every shared edge) whose pieces are not all
    closed is kept whole: nothing that is not closed is parted from what
    it touches."""
    from .census import edge_table, opposite_pairs

    _, _, fwd, bwd, _, root = edge_table(f, len(v))
    if not np.any(fwd + bwd > 2):  # every edge manifold (or open): the edge table's components
        return root
    f = np.asarray(f, dtype=np.int64).reshape(-1, 3)
    m = len(f)
    a, b, c = f.reshape(-1), f[:, [1, 2, 0]].reshape(-1), f[:, [2, 0, 1]].reshape(-1)
    face = np.repeat(np.arange(m), 3)
    keep = a != b
    a, b, c, face = a[keep], b[keep], c[keep], face[keep]
    key = np.minimum(a, b) * np.int64(max(len(v), 1)) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    a, b, c, face, key = a[order], b[order], c[order], face[order], key[order]
    start = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    size = np.diff(np.r_[start, len(key)])
    group = np.repeat(np.arange(len(start)), size)
    forward = a < b
    ups = np.bincount(group, weights=forward, minlength=len(start)).astype(np.int64)
    radial = (size > 2) & (2 * ups == size)
    paired = np.zeros(len(start), dtype=bool)
    pairs = [np.empty((0, 2), dtype=np.int64)]
    if np.any(radial):
        h = radial[group]
        ok, pa = radial_pairs(v, a[h], b[h], c[h], forward[h], group[h], face[h])
        paired[np.flatnonzero(radial)[ok]] = True
        pairs.append(pa)
    join = ~paired[group]  # every other edge joins all its faces (to its first)
    pairs.append(np.stack([face[join], face[start[group[join]]]], axis=1))
    fine = components_roots(m, np.concatenate(pairs))
    if np.array_equal(fine, root):
        return fine
    # a piece all of whose faces are written both ways (a double-sided solid) joins its twins' pieces
    mate = opposite_pairs(f, len(v))
    whole = np.ones(m, dtype=bool)
    np.logical_and.at(whole, fine, mate >= 0)
    twin = whole[fine]
    if np.any(twin):
        pairs.append(np.stack([np.flatnonzero(twin), mate[twin]], axis=1))
        fine = components_roots(m, np.concatenate(pairs))
    closed = pieces_closed(fine, group, face, forward)
    for r in np.unique(root[~closed[fine]]):  # an open piece: its whole component stays one body
        fine[root == r] = r
    return fine


def radial_pairs(v: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray, forward: np.ndarray,
                 group: np.ndarray, face: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The faces a non-manifold edge joins: the half-edges ``a -> b`` (third
    vertex ``c``) of some edges, grouped by edge (``group`` ascending), each
    edge used equally often each way. Around each edge the faces are taken
    in the order of their angle (the third vertex projected on the plane
    normal to the edge); a face using the edge upwards (lo -> hi) has its
    normal towards increasing angle, so its solid lies behind it, and one
    using it downwards opens a wedge of solid that the next face closes. At
    one angle (coincident faces) the faces that close come first: two
    solids touch there, a solid of no thickness is none. Where the order
    alternates down, up, down, up, ... each downward face is joined to the
    next face round; any other order (a fin, a sheet on a solid, a
    degenerate face) leaves the edge unpaired. Returns (which of the
    groups, in order, were paired; (K, 2) face pairs)."""
    v = np.asarray(v, dtype=np.float64)
    lo, hi = np.where(forward, a, b), np.where(forward, b, a)
    p = v[lo]
    _, first, inverse = np.unique(group, return_index=True, return_inverse=True)
    with np.errstate(invalid="ignore", divide="ignore"):  # a zero-length edge or face: nan, unpaired
        d = v[hi] - p
        d /= np.linalg.norm(d, axis=1)[:, None]
        w = v[c] - p
        w -= np.einsum("ij,ij->i", w, d)[:, None] * d
        length = np.linalg.norm(w, axis=1)
        e1 = w[first][inverse] / length[first][inverse][:, None]  # the first face of each edge: angle 0
        e2 = np.cross(d, e1)
        angle = np.arctan2(np.einsum("ij,ij->i", w, e2), np.einsum("ij,ij->i", w, e1))
        angle = np.where(angle < -RADIAL_TIE, angle + 2 * np.pi, angle)
        bad = ~np.isfinite(angle) | ~(length > RADIAL_TIE * np.linalg.norm(v[hi] - p, axis=1))
    n = len(first)
    bad_group = np.zeros(n, dtype=bool)
    bad_group[inverse[bad]] = True
    angle[bad] = 0.0
    o = np.lexsort((angle, inverse))
    g, t = inverse[o], angle[o]
    tie = np.r_[False, (g[1:] == g[:-1]) & (np.diff(t) < RADIAL_TIE)]
    cluster = np.cumsum(~tie)
    o = o[np.lexsort((~forward[o], cluster))]  # in a cluster: the faces that close a wedge first
    g, up = inverse[o], forward[o]
    bad_group[g[1:][(g[1:] == g[:-1]) & (up[1:] == up[:-1])]] = True  # not alternating
    begin = np.r_[0, np.flatnonzero(g[1:] != g[:-1]) + 1]
    after = np.arange(1, len(o) + 1)
    after[np.r_[begin[1:], len(o)] - 1] = begin  # the next face round, cyclically
    down = ~up & ~bad_group[g]
    pairs = np.stack([face[o][down], face[o][after[down]]], axis=1)
    return ~bad_group, pairs


def components_roots(m: int, pairs: np.ndarray) -> np.ndarray:
    """Each of ``m`` faces' component, joined by ``pairs`` (K, 2), as its
    smallest face index."""
    from ..scale.graphs import components

    _, label = components(m, pairs[:, 0], pairs[:, 1])  # numbered in the order of their smallest face
    return np.unique(label, return_index=True)[1][label]


def pieces_closed(root: np.ndarray, edge: np.ndarray, face: np.ndarray, forward: np.ndarray) -> np.ndarray:
    """Whether each piece (the faces of one ``root``; indexed by root) uses
    each of its edges as often each way, from the half-edges: their edge,
    face and way (``forward``)."""
    piece = root[face]
    o = np.lexsort((piece, edge))
    piece, edge = piece[o], edge[o]
    begin = np.flatnonzero(np.r_[True, (edge[1:] != edge[:-1]) | (piece[1:] != piece[:-1])])
    net = np.add.reduceat(np.where(forward[o], 1, -1), begin)
    closed = np.ones(len(root), dtype=bool)
    closed[piece[begin[net != 0]]] = False
    return closed


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
