"""The genus of a mesh, as the mesh, manifold3d, pymeshlab and the voxelised
solid each see it.

:func:`mesh_topology` says what the mesh itself says (components, Euler
number, genus per component, defects); :func:`verify_genus` puts it beside
manifold3d's, pymeshlab's and the digital topology of the voxelised solid
at each resolution, with one verdict.

What "genus" means differs between tools (docs/voxelisation.md): trimesh's Euler
number is ``V - E + F`` of the whole mesh, manifold3d's ``genus()`` is
``1 - chi/2`` of the whole mesh (negative for several components), pymeshlab
sums genera over components. Here ``genus`` always means the total number of
handles: the sum over closed components of ``(2 - chi_c) / 2``; for a solid
this is its number of tunnels b1.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any, Literal

import numpy as np

from ..digital.topology import LABEL_BYTES_PER_VOXEL, betti_numbers
from ..errors import IsoflowError, check_callable, check_switch, counted, given_text, scalar_given, whole_given
from ..scale import memory
from .crossings import find_crossings
from .cube_grid import CubeGrid
from .fills import Fill, Voxelization, check_fill, check_strict
from .grid import GridTooLarge, finest_fit, float64_rounding, grid_fits, grid_need, grid_words, near_origin
from .load import MeshInput, check_mesh, mesh_defects, mesh_input, repeated_faces
from .t_junctions import close_t_junctions
from .verdict import GenusVerdict, Note, Stop, VerdictKind, strict_refusal
from .voxel_object import voxel_object, written_connectivity
from .voxelize import Solid, in_memory, plan_voxels, voxelize

# --------------------------------------------------------------------------
# the mesh's own topology
# --------------------------------------------------------------------------


def mesh_topology(vertices, faces, return_components: bool = False):
    """Components, Euler number and genus of a triangle mesh, with its defects.

    Components are edge-connected face sets. A component's genus is
    ``(2 - chi_c) / 2`` when it is closed (no boundary edge), every edge has
    two faces and it is orientable (its faces may be turned inconsistently:
    the genus is the surface's); otherwise None. A vertex with more than
    one fan of faces in it (a pinch: sheets that touch at a point) counts
    once per fan in ``chi_c``: the genus is that of the closed surface
    whose sheets are apart there, as manifold3d counts it (it splits such
    vertices) and as the 6-connected voxels see it.
    ``nonmanifold_vertices`` counts vertices with more than one fan (two
    closed surfaces touching at a point, like ``hourglass_ico.obj``, or
    two parts of one surface, like a chain of voxels whose ends touch at a
    corner), less the ends of non-manifold edges, whose sheets meet along
    the edge (as pymeshlab counts them).
    ``boundary_loops`` counts the chains of open edges (joined through the
    fans at their ends) and ``genus_with_boundary`` sums ``(2 - chi_c -
    b_c) / 2`` over the components, closed or open: None where an edge has
    more than two faces or a component is not orientable.
    With ``return_components``, also each face's component number.

    Examples
    --------
    >>> import numpy as np
    >>> square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> r = mesh_topology(square, np.array([[0, 1, 2], [0, 2, 3]]))
    >>> r["genus"], r["boundary_loops"], r["genus_with_boundary"]
    (None, 1, 0)
    """
    from ..scale.graphs import components
    from .census import distinct_counts  # compiled: loaded with the census, when a mesh is counted

    v = np.asarray(vertices)
    f = np.asarray(faces, dtype=np.int64)
    defects = mesh_defects(v, f)
    nf = len(f)
    # half-edges: (face, corner t) from vertex f[t] to f[t+1]
    a = f.ravel()
    b = np.roll(f, -1, axis=1).ravel()
    face_of = np.repeat(np.arange(nf), 3)
    key = np.minimum(a, b) * (len(v) + 1) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    skey = key[order]
    edge_start = np.flatnonzero(np.r_[True, skey[1:] != skey[:-1]])
    edge_count = np.diff(np.r_[edge_start, len(skey)])
    # faces sharing an edge are in one component (all of them at a
    # non-manifold edge): join each half-edge's face to its edge's first face
    first_face = face_of[order][np.repeat(edge_start, edge_count)]
    ncomp, comp = components(nf, face_of[order], first_face)

    # per component: E (edges), F, and whether closed
    comp_of_edge = comp[face_of[order][edge_start]]
    E = np.bincount(comp_of_edge, minlength=ncomp)
    F = np.bincount(comp, minlength=ncomp)
    bad_edge = np.bincount(comp_of_edge, weights=(edge_count != 2), minlength=ncomp) > 0

    # fans: corners around a vertex joined across the manifold edges
    corner_a = np.arange(3 * nf)  # corner at a of half-edge i is corner i
    corner_b = face_of * 3 + (np.arange(3 * nf) % 3 + 1) % 3
    pairs = edge_count == 2
    h1 = order[edge_start[pairs]]
    h2 = order[edge_start[pairs] + 1]
    same_dir = a[h1] == a[h2]
    src = np.concatenate([corner_a[h1], corner_b[h1]])
    dst = np.concatenate([np.where(same_dir, corner_a[h2], corner_b[h2]), np.where(same_dir, corner_b[h2], corner_a[h2])])
    _, fan = components(3 * nf, src, dst)
    fans_per_vertex = distinct_counts(f.ravel(), len(v), fan, 3 * nf)
    comps_per_vertex = distinct_counts(f.ravel(), len(v), np.repeat(comp, 3), ncomp)
    # the ends of an edge of more than two faces have a fan per sheet along
    # it: sheets that meet along an edge, which its own note names, not at
    # a point (pymeshlab counts no such vertex either)
    on_nonmanifold_edge = np.zeros(len(v), dtype=bool)
    crowded = order[edge_start[edge_count > 2]]
    on_nonmanifold_edge[a[crowded]] = on_nonmanifold_edge[b[crowded]] = True

    # V - E + F with a pinched vertex counted once per fan: the surface with its sheets
    # apart there, the closed surface its faces make (manifold3d splits
    # such vertices; isoflow's own boundary meshes count pinches so)
    chi = distinct_counts(np.repeat(comp, 3), ncomp, fan, 3 * nf) - E + F
    orientable = _orientable(nf, face_of[h1], face_of[h2], same_dir, comp, ncomp)
    closed = ~bad_edge & orientable
    genus_c: list[int | None] = [int((2 - c) // 2) if ok and c % 2 == 0 else None
                                 for c, ok in zip(chi.tolist(), closed)]
    # an open surface has a genus too, with its holes: chi_c = 2 - 2 g - b
    # (b boundary loops), as trimesh and pymeshlab count an open mesh's
    # handles. A loop is a chain of open edges joined through the fans at
    # their ends, so two holes that touch at a vertex (a fan each, as chi
    # counts it) stay two loops
    open_h = order[edge_start[edge_count == 1]]
    _, loop = components(3 * nf, fan[corner_a[open_h]], fan[corner_b[open_h]])
    _, first = np.unique(loop[fan[corner_a[open_h]]], return_index=True)
    loops_c = np.bincount(comp[face_of[open_h[first]]], minlength=ncomp)
    crowded_c = np.bincount(comp_of_edge, weights=edge_count > 2, minlength=ncomp) > 0
    with_boundary = 2 - chi - loops_c
    genus_b: list[int | None] = [int(c // 2) if ok and c % 2 == 0 and c >= 0 else None
                                 for c, ok in zip(with_boundary.tolist(), ~crowded_c & orientable)]
    used = np.count_nonzero(np.bincount(f.ravel(), minlength=len(v)))
    euler = int(used - len(edge_start) + nf)
    known = [g for g in genus_c if g is not None]
    # a closed component with faces turned the wrong way still has a genus: the surface's, as pymeshlab
    # counts it and trimesh's fix_normals leaves it; a non-orientable one (no consistent turning) has none
    total = sum(known) if genus_c and len(known) == len(genus_c) else None
    known_b = [g for g in genus_b if g is not None]
    report = {
        "watertight": bool(defects["watertight"]),
        "components": int(ncomp),
        "euler_number": euler,
        "genus": total,
        "genus_per_component": genus_c,
        "boundary_edges": int(defects["boundary_edges"]),
        "boundary_loops": int(loops_c.sum()),
        # every component a surface, closed or with holes: the handles of all
        # of them (the genus where the mesh is closed)
        "genus_with_boundary": sum(known_b) if genus_b and len(known_b) == len(genus_b) else None,
        "nonmanifold_edges": int(defects["nonmanifold_edges"]),
        "inconsistent_edges": int(defects["inconsistent_edges"]),
        # components that no turning of faces makes consistent (a Moebius band): no surface genus at all
        "non_orientable": int(np.count_nonzero(~orientable)),
        "nonmanifold_vertices": int(np.count_nonzero(fans_per_vertex[~on_nonmanifold_edge] > 1)),
        "vertices": int(used),
        "faces": int(nf),
        # vertices on faces of more than one component: components touching
        "shared_vertices": int(np.count_nonzero(comps_per_vertex > 1)),
    }
    return (report, comp) if return_components else report


def _orientable(nf: int, f1: np.ndarray, f2: np.ndarray, same_dir: np.ndarray, comp: np.ndarray,
                ncomp: int) -> np.ndarray:
    """Whether each component's faces can be turned so that every edge of
    two faces is walked once each way: the faces' orientation double cover
    (a face and its turned copy, joined across each such edge to the copy
    of the other face that agrees with it) keeps the two copies of a face
    apart exactly where they can. ``f1``, ``f2``: the two faces of each
    edge with two faces; ``same_dir``: whether they walk it the same way.

    Examples
    --------
    >>> # two triangles on the edge 0-1, the second walking it the same way: turn one of them
    >>> _orientable(2, np.array([0]), np.array([1]), np.array([True]), np.zeros(2, np.int64), 1).tolist()
    [True]
    """
    from ..scale.graphs import components

    turn = same_dir.astype(np.int64)
    a = np.concatenate([2 * f1, 2 * f1 + 1])
    b = np.concatenate([2 * f2 + turn, 2 * f2 + 1 - turn])
    _, cover = components(2 * nf, a, b)
    apart = cover[0::2] != cover[1::2]
    return np.bincount(comp, weights=~apart, minlength=ncomp) == 0


def whole_manifold(vertices, faces) -> tuple[Any, int]:
    """The mesh as one manifold3d ``Manifold`` (its vertices
    :func:`normalized`, in float32), or the exception its binding raised
    for malformed input, and the exponent ``e`` of the scaling: what
    :func:`manifold3d_report` and :func:`solid_report` both start from, so
    that :func:`witnesses` builds it once (a second on a million faces).

    Parameters
    ----------
    vertices : ndarray, shape (N, 3)
    faces : int ndarray, shape (M, 3)

    Returns
    -------
    tuple
        ``(manifold or exception, e)``.
    """
    import manifold3d as m3

    v, e = normalized(vertices)  # manifold3d takes float32
    try:
        return m3.Manifold(
            m3.Mesh(vert_properties=np.asarray(v, np.float32), tri_verts=np.asarray(faces, np.uint32))
        ), e
    except Exception as exc:  # the binding raises for malformed input
        return exc, e


def manifold_parts(mf) -> list:
    """A manifold3d ``Manifold``'s connected parts, as its ``decompose()``
    gives them (a pinched vertex, which manifold3d splits, parts them too),
    in time linear in its size: ``decompose()`` takes time quadratic in the
    number of parts.

    Parameters
    ----------
    mf : manifold3d.Manifold
        A manifold without error.

    Returns
    -------
    list of manifold3d.Manifold
        One per connected part (none for an empty manifold; ``mf`` itself
        where it is one part).

    Examples
    --------
    >>> import manifold3d as m3
    >>> two = m3.Manifold.cube([1, 1, 1]) + m3.Manifold.cube([1, 1, 1]).translate([3, 0, 0])
    >>> sorted(p.volume() for p in manifold_parts(two)), len(two.decompose())
    ([1.0, 1.0], 2)
    """
    import manifold3d as m3

    from ..scale.graphs import components

    mesh = mf.to_mesh()
    f = np.asarray(mesh.tri_verts, np.int64)
    if not len(f):
        return []
    v = np.asarray(mesh.vert_properties)[:, :3]
    count, label = components(len(v), np.r_[f[:, 0], f[:, 0]], np.r_[f[:, 1], f[:, 2]])
    if count == 1:
        return [mf]
    face_label = label[f[:, 0]]
    order = np.argsort(face_label, kind="stable")
    parts = []
    for chosen in np.split(order, np.searchsorted(face_label[order], np.arange(1, count))):
        used, local = np.unique(f[chosen], return_inverse=True)
        parts.append(m3.Manifold(m3.Mesh(vert_properties=np.ascontiguousarray(v[used], np.float32),
                                         tri_verts=local.reshape(-1, 3).astype(np.uint32))))
    return parts


def manifold3d_report(vertices, faces, whole: tuple[Any, int] | None = None) -> dict:
    """manifold3d's genus of the mesh (the sum over its parts), of the whole
    mesh, its number of parts and volume, or ``{"error": ...}`` where it
    refuses the mesh; ``whole``: :func:`whole_manifold` of the mesh, where
    already built."""
    import manifold3d as m3

    mf, e = whole_manifold(vertices, faces) if whole is None else whole
    if isinstance(mf, Exception):
        return {"error": f"{type(mf).__name__}: {mf}"}
    status = mf.status()
    if status != m3.Error.NoError:
        return {"error": status.name}
    parts = manifold_parts(mf)
    volume = unscaled_volume(mf.volume(), e)
    return {
        "genus": int(sum(p.genus() for p in parts)),
        "genus_whole_mesh": int(mf.genus()),
        "components": len(parts),
        "volume": volume,
    }


def unscaled_volume(scaled: float, e: int) -> float | None:
    """The volume of the mesh as given, from manifold3d's of the copy
    scaled by ``2**-e`` (:func:`normalized`), or None where float64 cannot
    hold it: it overflowed to inf, which the JSON printed as ``Infinity``
    (no JSON parser's number), or underflowed to 0.

    Parameters
    ----------
    scaled : float
        manifold3d's volume of the scaled copy.
    e : int
        The exponent of the scaling.

    Returns
    -------
    float or None
        ``scaled * 2**(3 e)``, or None beyond float64's range.

    Examples
    --------
    >>> unscaled_volume(1.5, 2), unscaled_volume(1.5, 400), unscaled_volume(1.5, -400), unscaled_volume(0.0, 400)
    (96.0, None, None, 0.0)
    """
    with np.errstate(over="ignore", under="ignore"):
        volume = float(np.ldexp(scaled, 3 * e))
    return volume if math.isfinite(volume) and (volume != 0 or scaled == 0) else None


def pymeshlab_report(vertices, faces) -> dict:
    try:
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(normalized(vertices)[0], np.asarray(faces, np.int32)))
        t = ms.get_topological_measures()
    except Exception as exc:
        return {"error": f"{type(exc).__name__}: {exc}"}
    out: dict[str, Any] = {k: (int(t[k]) if not isinstance(t[k], bool) else bool(t[k])) for k in (
        "genus", "connected_components_number", "boundary_edges", "non_two_manifold_edges",
        "non_two_manifold_vertices", "is_mesh_two_manifold") if k in t}
    if out.get("genus", 0) < 0:
        out["error"] = "pymeshlab reports genus -1: the mesh is not a two-manifold"
    return out


def self_intersections(vertices, faces, component) -> dict:
    """Faces that cross other faces (:func:`isoflow.mesh.crossings.crossing_pairs`:
    exact, on the coordinates as given, never a centred or scaled copy), split into those crossing a face of
    their own component (``self_intersecting_faces``: the component is no
    embedded surface), those that only touch faces of their own component
    (``faces_touching_own_component``: :attr:`~isoflow.mesh.crossings.Crossings.touch`,
    solids stacked face to face on shared corners) and those crossing
    other components (``faces_crossing_other_components``: components
    overlap or touch)."""
    found = find_crossings(vertices, faces)
    pairs = found.pairs
    component = np.asarray(component)
    nf = len(np.asarray(faces))
    own, rest, other = (np.zeros(nf, dtype=bool) for _ in range(3))
    same = component[pairs[:, 0]] == component[pairs[:, 1]]
    # faces of one component that only touch (solids stacked face to face
    # on shared corners) do not make it self-intersecting: the solid is
    # their union, as where components touch
    own[pairs[same & ~found.touch].ravel()] = True
    rest[pairs[same & found.touch].ravel()] = True
    other[pairs[~same].ravel()] = True
    return {
        "self_intersecting_faces": int(np.count_nonzero(own)),
        "faces_touching_own_component": int(np.count_nonzero(rest & ~own)),
        "faces_crossing_other_components": int(np.count_nonzero(other & ~own)),
        "zero_area_faces": found.zero_area,
        "pairs_along_slivers": found.along_slivers,
    }


def normalized(vertices) -> tuple[np.ndarray, int]:
    """``(vertices, e)``: the vertices centred on their bounding box and
    scaled by ``2**-e`` to a size near 1 (exact in binary), for the tools
    that take float32 or absolute tolerances (manifold3d, pymeshlab): a mesh in units of 1e-35 or 1e36, or placed at 1e7,
    then reads as it does at 1. Topology does not change; lengths scale by
    ``2**e``."""
    v = np.asarray(vertices, np.float64)
    if not len(v):
        return v, 0
    lo, hi = v.min(axis=0), v.max(axis=0)
    size = float(np.max(hi - lo))
    e = int(np.frexp(size)[1]) if size > 0 and np.isfinite(size) else 0
    return np.ldexp(v - (lo + hi) / 2, -e), e


def solid_report(vertices, faces, whole: tuple[Any, int] | None = None) -> dict:
    """The solid the mesh bounds by the nonzero winding rule (the rule the
    voxeliser reads), built with manifold3d's booleans.

    The components (manifold3d's ``decompose``; inside-out ones, of negative
    volume, turned into solids of winding -1) are grouped where they cross
    (a union, when they face the same way), then nested: a body inside
    another takes the winding number of the one around it plus its own.
    The solid is every body whose winding number is not 0, less the bodies
    inside it: a hollow ball stays hollow, a ship in its bottle stays in it,
    an inverted mesh is solid, a torus inside a sphere facing the same way
    is swallowed. Crossing components that face opposite ways have no
    nesting; there the outward ones are united and the inside-out ones
    subtracted (``approximate``: True).

    ``genus`` is the number of handles of the solid's boundary (its b1, what
    the digital genus measures); ``surfaces`` its closed boundary surfaces,
    ``bodies`` and ``cavities`` those that bound a body from outside and a
    cavity (its b0 and b2); ``filled_genus`` and ``filled_bodies`` the
    genus and bodies of the solid with its cavities filled (what a flood
    fill voxelises: the union of the outer surfaces' solids, which swallows
    the bodies inside cavities); ``boundary`` says whether the mesh is the
    solid's boundary (every surface between a region of winding 0 and one
    of winding not 0), so that the mesh's own genus is the one to compare.
    ``{"error": ...}`` where manifold3d refuses the mesh. ``whole``:
    :func:`whole_manifold` of the mesh, where already built.
    """
    import manifold3d as m3

    made, e = whole_manifold(vertices, faces) if whole is None else whole
    try:
        if isinstance(made, Exception):
            raise made
        if made.status() != m3.Error.NoError:
            return {"error": made.status().name}
        parts = manifold_parts(made)
        signs = [1 if p.volume() >= 0 else -1 for p in parts]
        solids = [p if s > 0 else _inside_out(m3, p) for p, s in zip(parts, signs)]
        solid, boundary, approximate, lens = _nonzero_solid(m3, solids, signs)
        pieces = manifold_parts(solid)
        filled_genus, filled_bodies = _filled(m3, pieces)
    except Exception as exc:  # the binding raises for malformed input (its first line says what)
        detail = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        return {"error": f"{type(exc).__name__}: {detail}"}
    volume = unscaled_volume(solid.volume(), e)
    if lens is not None:  # back to the mesh's own lengths and place
        v = np.asarray(vertices, np.float64)
        middle = (v.min(axis=0) + v.max(axis=0)) / 2
        lens = {"thickness": float(np.ldexp(lens[0], e)), "at": (middle + np.ldexp(lens[1], e)).tolist()}
    # decompose() splits the solid into its shells: a body's outer one
    # (positive volume) and its cavities' (negative)
    bodies = sum(1 for p in pieces if p.volume() > 0)
    return {"genus": int(sum(p.genus() for p in pieces)), "surfaces": len(pieces), "bodies": bodies,
            "cavities": len(pieces) - bodies, "filled_genus": filled_genus, "filled_bodies": filled_bodies,
            "volume": volume, "boundary": boundary, "approximate": approximate, "thinnest_lens": lens}


def _filled(m3, pieces: list) -> tuple[int, int]:
    """``(genus, bodies)`` of the solid whose shells are ``pieces`` with
    its cavities filled: the union of the solids its outer surfaces
    (positive volume) bound, of which a body inside a cavity is part, and
    whose own cavities (outer surfaces closing a space between them) are
    left out in turn."""
    outer = [p for p in pieces if p.volume() > 0]
    if len(outer) == len(pieces):  # no cavity: the solid itself
        return int(sum(p.genus() for p in pieces)), len(pieces)
    filled = manifold_parts(m3.Manifold.batch_boolean(outer, m3.OpType.Add)) if len(outer) > 1 else outer
    shells = [p for p in filled if p.volume() > 0]
    return int(sum(p.genus() for p in shells)), len(shells)


#: relative volume below which two solids are taken not to overlap (float32 booleans)
_OVERLAP_RTOL = 1e-6
#: pairs of components whose boxes meet, beyond which the nesting is not
#: worked out (a boolean each): the outward ones are united and the
#: inside-out ones subtracted, ``approximate``
MAX_PAIRS = 5000


def _nonzero_solid(m3, solids: list, signs: list) -> tuple:
    """``(solid, boundary, approximate, lens)`` of :func:`solid_report`
    from the components as solids and their windings (+1 / -1); ``lens``:
    :func:`lens_of` the thinnest overlap of two crossing components (None
    where none cross)."""
    n = len(solids)
    if n == 0:
        return m3.Manifold(), True, False, None
    vols = [s.volume() for s in solids]
    meeting = _boxes_meeting(solids)
    if len(meeting) > MAX_PAIRS:
        return _outward_less_inside_out(m3, solids, signs), False, True, None
    group = list(range(n))  # union-find of crossing components

    def root(i):
        while group[i] != i:
            group[i] = group[group[i]]
            i = group[i]
        return i

    inside: dict[int, list[int]] = {}  # i -> components j whose solid holds solid i
    lens = None
    for i, j in meeting.tolist():
        overlap = solids[i] ^ solids[j]
        common = overlap.volume()
        small = min(vols[i], vols[j])
        if common <= _OVERLAP_RTOL * small:
            continue  # apart (or touching)
        if common >= (1 - _OVERLAP_RTOL) * small:  # the smaller one inside the larger
            a, b = (i, j) if vols[i] <= vols[j] else (j, i)
            inside.setdefault(a, []).append(b)
            continue
        if signs[i] != signs[j]:  # crossing, facing opposite ways: no nesting to follow
            return _outward_less_inside_out(m3, solids, signs), False, True, None
        this = lens_of(overlap)
        lens = this if lens is None or this[0] < lens[0] else lens
        group[root(i)] = root(j)
    # bodies: crossing components of one way united
    members: dict[int, list[int]] = {}
    for i in range(n):
        members.setdefault(root(i), []).append(i)
    keys = list(members)
    body_of = {i: k for k, ms in members.items() for i in ms}
    body = {k: m3.Manifold.batch_boolean([solids[i] for i in ms], m3.OpType.Add) if len(ms) > 1 else solids[ms[0]]
            for k, ms in members.items()}
    volume = {k: body[k].volume() for k in keys}
    # a body's parent: the smallest other body holding one of its components
    parent = {}
    for k in keys:
        around = {body_of[j] for i in members[k] for j in inside.get(i, ())} - {k}
        parent[k] = min(around, key=lambda b: volume[b]) if around else None
    winding = {}

    def wind(k):
        if k not in winding:
            winding[k] = signs[k] + (wind(parent[k]) if parent[k] is not None else 0)
        return winding[k]

    children: dict = {}
    for k in keys:
        if parent[k] is not None:
            children.setdefault(parent[k], []).append(k)
    regions = []
    boundary = True
    for k in keys:
        outer = wind(parent[k]) if parent[k] is not None else 0
        boundary &= (wind(k) != 0) != (outer != 0)
        if wind(k) != 0:
            region = body[k]
            if children.get(k):
                region = region - m3.Manifold.batch_boolean([body[c] for c in children[k]], m3.OpType.Add)
            regions.append(region)
    solid = m3.Manifold.batch_boolean(regions, m3.OpType.Add) if regions else m3.Manifold()
    return solid, boundary, False, lens


def lens_of(overlap) -> tuple[float, np.ndarray]:
    """``(thickness, centre)`` of the solid two crossing solids share (a
    manifold3d ``Manifold``): its mean thickness, twice its volume over its
    surface area (a sheet of thickness t and area S has volume S t and
    surface area 2 S, its rim aside), and the centre of its bounding box.
    Where two surfaces meet almost tangentially this lens is thin, and the
    crevice around it narrower than a voxel over a wide band.

    Examples
    --------
    >>> import manifold3d as m3
    >>> a = m3.Manifold.cube([1.0, 1.0, 1.0])
    >>> t, centre = lens_of(a ^ a.translate([0.0, 0.0, 0.9]))  # a slab 0.1 thick, 1 x 1
    >>> round(t, 4), centre.round(2).tolist()
    (0.0833, [0.5, 0.5, 0.95])
    """
    box = np.asarray(overlap.bounding_box(), np.float64)
    return 2 * overlap.volume() / overlap.surface_area(), (box[:3] + box[3:]) / 2


def _boxes_meeting(solids: list) -> np.ndarray:
    """Pairs ``(i, j)``, ``i < j``, in order, of the solids whose bounding
    boxes meet: found through a grid of cubes (:class:`~isoflow.mesh.cube_grid.CubeGrid`)
    rather than by testing every pair, whose table grows with the square
    of the components (gigabytes for a mesh of twenty thousand boxes)."""
    if len(solids) < 2:
        return np.zeros((0, 2), np.int64)
    boxes = np.array([np.asarray(s.bounding_box(), np.float64).reshape(2, 3) for s in solids])
    chunks = list(CubeGrid(boxes[:, 0], boxes[:, 1]).pairs())
    pairs = np.concatenate(chunks) if chunks else np.zeros((0, 2), np.int64)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def _outward_less_inside_out(m3, solids: list, signs: list):
    """The outward components united, less the inside-out ones united."""
    pos = [s for s, w in zip(solids, signs) if w > 0]
    neg = [s for s, w in zip(solids, signs) if w < 0]
    solid = m3.Manifold.batch_boolean(pos, m3.OpType.Add) if pos else m3.Manifold()
    if neg:
        solid = solid - m3.Manifold.batch_boolean(neg, m3.OpType.Add)
    return solid


def _inside_out(m3, part):
    """The part with its triangles turned (a cavity's wall as a solid).
    ``to_mesh`` gives read-only arrays and int32 indices, and ``Mesh``
    refuses both (manifold3d 3.5): it takes writable float32 and uint32."""
    mesh = part.to_mesh()
    tris = np.array(np.asarray(mesh.tri_verts)[:, ::-1], np.uint32)
    return m3.Manifold(m3.Mesh(vert_properties=np.array(mesh.vert_properties, np.float32), tri_verts=tris))


# --------------------------------------------------------------------------
# the digital genus, resolution after resolution
# --------------------------------------------------------------------------

#: resolutions ``isoflow genus`` tries first; then it doubles the last
DEFAULT_RESOLUTIONS = (64, 128)
#: the automatic stepping stops before a resolution beyond this ...
MAX_RESOLUTION = 1024
#: ... or one whose predicted time (8x the last: cubic) would end past this
TIME_LIMIT = 60.0


def default_resolutions(max_resolution: int = MAX_RESOLUTION) -> list[int]:
    """The resolutions tried first where none is given: 64 and 128
    (:data:`DEFAULT_RESOLUTIONS`), or, where ``max_resolution`` is below
    128, the cap and its half, so that no grid passes a cap set alone
    (a cap of 32: 16 and 32).

    Parameters
    ----------
    max_resolution : int
        The cap on the resolutions, at least 1.

    Returns
    -------
    list of int

    Examples
    --------
    >>> default_resolutions(), default_resolutions(32), default_resolutions(100), default_resolutions(1)
    ([64, 128], [16, 32], [50, 100], [1])
    """
    if max_resolution >= max(DEFAULT_RESOLUTIONS):
        return list(DEFAULT_RESOLUTIONS)
    return sorted({max(1, max_resolution // 2), max_resolution})


#: peak bytes per grid voxel of one resolution: the volume, the voxeliser's
#: difference array (int32) and the labelling of the Betti numbers
DIGITAL_BYTES_PER_VOXEL = 1 + 4 + LABEL_BYTES_PER_VOXEL


def digital_steps(vertices, faces, resolutions=DEFAULT_RESOLUTIONS, connectivity: int = 6, *,
                  step: bool = True, max_resolution: int = MAX_RESOLUTION, time_limit: float = TIME_LIMIT,
                  target: int | None = None, progress=None, on_resolution=None,
                  strict: bool = False, fill: Fill = "winding", bodies: int | None = None,
                  t_junctions: bool = True, joined: int | None = None,
                  touching: list | None = None) -> tuple[list, Stop | None]:
    """Digital topology of the voxelised solid at ``resolutions`` and then,
    while ``step`` and the Betti numbers of the last two differ (or agree on
    a genus other than ``target``, or on components other than ``bodies``:
    two coarse grids can both close the same thin hole, or join two bodies
    across the same thin gap), at twice the last, within ``max_resolution``,
    ``time_limit`` seconds and the memory budget.

    Returns the entries (resolution, pitch, shape, voxels, Betti numbers,
    genus, seconds) and why the stepping stopped early (a :class:`Stop`;
    None when it ended with stable Betti numbers and the target genus).
    ``progress(done, total)`` follows the voxelisations as one count that
    only grows: each resolution tried weighs ``resolution**3`` (what its grid
    costs), and ``total`` grows by that weight when the stepping adds a
    resolution. ``on_resolution(entry)`` is called after each. ``fill``
    is the voxels compared (:mod:`isoflow.mesh.fills`); ``t_junctions``
    False: the mesh's T-junctions are split already, or none closes
    (:func:`~isoflow.mesh.voxelize.voxelize` looks for none). ``joined``:
    the components the voxels keep at every resolution where they join
    bodies that touch (:func:`touch_joined_bodies`), settled on as
    ``bodies`` is. ``touching``: the Betti numbers of the solids joined
    where they touch (:func:`touch_joined_betti`), which the voxels keep at
    every resolution: two grids that agree on them end the stepping (the
    stop ``"touching"``), whatever the reference says.
    """
    import time

    todo = sorted({int(r) for r in resolutions})
    out: list = []
    finished = 0  # weight of the resolutions done
    start = time.monotonic()
    res: int | None
    while todo or out:
        stepped = not todo  # a resolution the stepping chose, not one asked
        if todo:
            res = todo.pop(0)
        else:
            res, stop = next_resolution(out, target, step=step, max_resolution=max_resolution,
                                        time_limit=time_limit, elapsed=time.monotonic() - start, bodies=bodies,
                                        joined=joined, touching=touching)
            if res is None:
                return out, stop
        weight = res**3
        ahead = finished + weight + sum(r**3 for r in todo)  # the resolutions known now

        def rung(done, total, finished=finished, weight=weight, ahead=ahead):
            progress(finished + round(weight * (done / total if total else 1.0)), ahead)

        try:
            entry = digital_entry(vertices, faces, res, connectivity, strict=strict, fill=fill,
                                  progress=None if progress is None else rung, finest=not stepped,
                                  t_junctions=t_junctions)
        except GridTooLarge as exc:
            if stepped:  # the estimate let it through, the exact count did not: the memory stops the stepping
                return out, Stop("memory", resolution=res, estimate=grid_need(exc.shape, DIGITAL_BYTES_PER_VOXEL))
            raise
        finished += weight
        out.append(entry)
        if on_resolution is not None:
            on_resolution(entry)
    return out, None


def next_resolution(done: list, target: int | None, *, step: bool, max_resolution: int, time_limit: float,
                    elapsed: float, bodies: int | None = None,
                    joined: int | None = None, touching: list | None = None) -> tuple[int | None, Stop | None]:
    """The resolution to try after ``done`` (twice the last), or None with
    why not: the Betti numbers settled on ``target`` and, where given,
    ``bodies`` components, or ``joined``, those no grid parts (no
    :class:`Stop`), or settled on ``touching``, those of the solids joined
    where they touch, which no grid changes (a Stop "touching"), or
    a limit (the time that ``elapsed`` seconds leave, the memory budget).
    ``max_resolution`` caps the doubling only: where the resolutions asked
    already pass it, they are what ended the stepping (a Stop "asked")."""
    stable = len(done) >= 2 and done[-1]["betti"] == done[-2]["betti"]
    if stable and (target is None or done[-1]["genus"] == target) and (bodies is None or
                                                                       done[-1]["betti"][0] in (bodies, joined)):
        return None, None
    if stable and touching is not None and list(done[-1]["betti"]) == list(touching):
        # the voxels join the solids where they touch, and the last two grids
        # are the joined solid: a finer grid joins them there alike
        return None, Stop("touching", resolution=done[-1]["resolution"])
    if not step:
        return None, Stop("asked")
    last = done[-1]
    res = 2 * last["resolution"]
    grow = (res / last["resolution"]) ** 3
    if res > max_resolution:
        if last["resolution"] > max_resolution:
            # asked beyond the cap, which caps only the doubling: the
            # resolutions asked end the stepping, not the cap
            return None, Stop("asked", limit=max_resolution, resolution=last["resolution"], option="max_resolution")
        return None, Stop("max_resolution", limit=max_resolution, resolution=res, option="max_resolution")
    if elapsed + last["seconds"] * grow > time_limit:
        return None, Stop("time_limit", limit=time_limit, resolution=res, estimate=last["seconds"] * grow,
                          option="time_limit")
    need = int(np.prod(last["shape"]) * grow * DIGITAL_BYTES_PER_VOXEL)
    if need > memory.default_budget():
        return None, Stop("memory", resolution=res, estimate=need)
    return res, None


def shell_genus(vertices: np.ndarray, faces: np.ndarray, shell: Voxelization, connectivity: int) -> int:
    """The genus of the solid a shell with cavities shows: b1 of the shell
    with the cavities that lie in the solid filled, those voxels the
    winding rule puts in on the same grid.

    A cavity of the shell holds no point of the surface, so the winding
    number is the same all over it: it is solid or empty as a whole.
    Filling a cavity takes its own tunnels from the shell's b1 (Alexander
    duality): the inside of a closed surface of genus g is a handlebody of
    g tunnels, so a shell that resolves it has b1 = 2g, and halving b1 held
    only there. Walls inside the solid (solids stacked face to face) cut it
    into cells without tunnels, which leave b1 the solid's genus; a shell
    that fills a thin part, with no cavity there, has the part's b1; and an
    empty cavity (a hole inside a hollow ball) keeps the tunnels that go
    around it.

    Parameters
    ----------
    vertices, faces : numpy.ndarray
        The mesh as voxelised.
    shell : Voxelization
        Its shell (``fill="shell"``), with its volume.
    connectivity : int
        6 or 26, as the Betti numbers are counted.

    Returns
    -------
    int

    Examples
    --------
    A torus's shell at 32 across has one cavity, its inside, and two
    tunnels; filled by the winding rule there, one:

    >>> import trimesh
    >>> from isoflow.mesh.voxelize import voxelize
    >>> t = trimesh.creation.torus(1.0, 0.4)
    >>> s = voxelize(t.vertices, t.faces, resolution=32, fill="shell", details=True)
    >>> shell_genus(np.asarray(t.vertices), np.asarray(t.faces), s, 6)
    1
    """
    vol = shell.volume
    assert vol is not None, "an in-memory voxelisation has its volume"
    inside = voxelize(vertices, faces, pitch=shell.pitch, grid=(shell.origin, vol.shape), fill="winding",
                      details=True).volume
    return int(betti_numbers(vol | inside, connectivity)[1])


def digital_entry(vertices, faces, resolution: int, connectivity: int, *, strict: bool = False,
                  fill: Fill = "winding", progress=None, finest: bool = True, t_junctions: bool = True) -> dict:
    """The solid voxelised at ``resolution`` and its Betti numbers: one
    entry of :func:`digital_steps`. A grid whose voxels and labelling do not
    fit in the memory budget is refused (:class:`~isoflow.mesh.grid.GridTooLarge`),
    naming the finest one that does where ``finest``. ``t_junctions``: as
    :func:`~isoflow.mesh.voxelize.voxelize` takes it."""
    import time

    t = time.monotonic()
    budget = memory.default_budget()
    # the Betti numbers do not depend on where the voxels lie: a mesh far
    # from the origin is moved near it (exactly), where a grid finer than
    # the spacing of its coordinates can be laid
    vertices, faces = check_mesh(vertices, faces, where="voxelize")
    vertices = near_origin(vertices, faces)
    vertices, faces, shape, what, _, _, _ = plan_voxels(vertices, faces, resolution=resolution)
    try:
        # the volume and its labelling, as the stepping counts them (the
        # voxeliser checks its own share, the volume and its slabs)
        if not grid_fits(shape, DIGITAL_BYTES_PER_VOXEL, 0, budget):
            need = grid_need(shape, DIGITAL_BYTES_PER_VOXEL)
            raise GridTooLarge(what, f"{grid_words(shape, need)} for its Betti numbers", budget, shape=shape)
        solid = voxelize(vertices, faces, resolution=resolution, strict=strict, fill=fill, progress=progress,
                         details=True, t_junctions=t_junctions)
    except GridTooLarge as exc:
        if not finest:
            raise
        # the finest grid whose Betti numbers fit by both counts; the Betti
        # numbers need the volume in memory: a zarr store is no way out
        made = Solid(vertices, faces, strict=strict, fill=fill, t_junctions=t_junctions)
        fit = finest_fit(vertices, faces, what, shape, lambda s, fr: grid_fits(s, DIGITAL_BYTES_PER_VOXEL, 0, budget)
                         and in_memory(made, fr, s, budget)[0])
        # verify_genus takes no max_bytes: its budget is the memory available
        raise exc.but(fit=fit, sought=True, hints=("", ""), store=False, place="", parameter=None) from None
    vol, pitch = solid.volume, solid.pitch
    assert vol is not None, "an in-memory voxelisation has its volume"
    betti = betti_numbers(vol, connectivity)
    genus = betti[1]
    if fill == "shell" and betti[1] is not None and betti[2]:
        genus = shell_genus(vertices, faces, solid, connectivity)
    return {"resolution": int(resolution), "pitch": pitch, "shape": list(vol.shape), "voxels": int(vol.sum()),
            "connectivity": connectivity, "betti": betti, "genus": genus,
            "seconds": round(time.monotonic() - t, 3)}


# --------------------------------------------------------------------------
# genus verification
# --------------------------------------------------------------------------


def verify_genus(mesh: MeshInput, resolutions: Sequence[int | np.integer] | None = None,
                 connectivity: int | np.integer | None = None, progress: Callable[[int, int | None], object] | None = None, *,
                 step: bool = True, max_resolution: int | np.integer = MAX_RESOLUTION, time_limit: float = TIME_LIMIT,
                 on_resolution: Callable[[dict], object] | None = None, strict: bool = False,
                 fill: Fill = "winding") -> GenusVerdict:
    """The mesh's topology, manifold3d's and pymeshlab's, its self-
    intersections, the genus of the solid it bounds, and the digital
    topology of that solid voxelised at growing resolutions, with a verdict.

    The verdict compares the digital genus (b1 of the voxelised solid) with
    the solid's genus (manifold3d's union) where components overlap, touch
    or nest, and with the mesh's own genus otherwise; a surface isoflow
    wrote (its file says so) that touches itself at its voxels' edge or
    vertex contacts, which those rows read otherwise, is compared with its
    voxels at its own grid (:func:`voxel_contacts`). It is ``agree`` only
    when the digital Betti numbers are the same at the last two resolutions
    tried (:func:`digital_steps` doubles the resolution until they are),
    and never for a self-intersecting mesh: its surface bounds no
    well-defined solid, and no grid settles that.

    A face listed again the same way round (the same three corners) is
    dropped before the mesh, its crossings, manifold3d, pymeshlab and the
    solid count it (it draws no more surface, only non-manifold edges),
    and edges that a vertex of another face splits (T-junctions) are split
    there; the digital rows voxelise the faces as loaded, each copy
    counted, exactly as :func:`~isoflow.mesh.voxelize.voxelize_file` reads
    the file (the generalised winding number adds a copy's winding: a wall
    listed twice parts the solid; the voxeliser splits the T-junctions
    too, with :func:`~isoflow.mesh.t_junctions.close_t_junctions`, and
    reads a mesh closed so by the exact scanline). A note names each
    repair and the rows it was made for.
    An open mesh has no genus of its own; an inconsistently oriented one has
    the genus of its surface where its faces can be turned consistently
    (none where they cannot: a non-orientable surface). The solid of
    either is read by the generalised winding number (``|w| > 1/2``) and
    its digital topology reported; ``strict`` refuses it (IsoflowError).

    Parameters
    ----------
    mesh : str, os.PathLike, (vertices, faces) or object with ``vertices`` and ``faces``
        A mesh file of any format trimesh reads, or a mesh in memory (a
        ``trimesh.Trimesh``; positions welded as a file's are:
        :func:`~isoflow.mesh.load.mesh_input`).
    resolutions : sequence of int, optional
        Voxels along the longest side, tried first. None (the default):
        :func:`default_resolutions` within ``max_resolution``.
    connectivity : {6, 26}, optional
        The digital solid's. None (the default): the one a surface isoflow
        wrote records in its file
        (:func:`~isoflow.mesh.voxel_object.written_connectivity`), which a
        ``written_connectivity`` note names where it is 26, else 6.
    progress : callable, optional
        ``progress(done, total)`` per resolution.
    step : bool
        Double the resolution until the Betti numbers of the last two agree,
        within ``max_resolution``, ``time_limit`` (seconds) and the memory;
        not for a self-intersecting mesh, nor for a non-orientable one with
        nothing to compare (no inside: the stop ``"no_inside"``); where
        the voxels join solids that touch and the last two grids read the
        solid so joined, no further (the stop ``"touching"``).
    max_resolution : int
        The doubling stops before a resolution beyond this (the verdict's
        ``stop`` says so); it caps only the doubling: ``resolutions`` past
        it are tried, and then end the stepping.
    time_limit : float
        Seconds: the doubling stops before a resolution whose predicted time
        (eight times the last one's) would end the run past this.
    on_resolution : callable, optional
        Called with each resolution's entry as it is done.
    strict : bool
        Refuse a mesh that is not watertight as written, as
        ``voxelize(strict=True)`` does: the repairs made before counting
        (repeated faces dropped, edges split at T-junctions) are not made
        for it.
    fill : {"winding", "shell", "flood"}
        The voxels compared (:mod:`isoflow.mesh.fills`; the verdict's ``fill``).

    Returns
    -------
    GenusVerdict
        The witnesses, the verdict's kind and the facts it rests on;
        ``to_dict()`` is the JSON the ``genus`` command prints.

    Raises
    ------
    IsoflowError
        A mesh that cannot be read (or, with ``strict``, is not watertight);
        resolutions that are not a non-empty sequence; a ``max_resolution``
        below 1 or a ``time_limit`` that is not a positive number of seconds.

    Examples
    --------
    >>> from isoflow import data
    >>> v = verify_genus(data.torus(), resolutions=[24, 48], step=False)
    >>> v.kind, v.reference, [d["genus"] for d in v.digital]
    ('agree', 1, [1, 1])
    >>> import trimesh
    >>> verify_genus(trimesh.creation.torus(1.0, 0.3), resolutions=[32, 64], step=False).kind
    'agree'
    """
    # the arguments checked as the command line's are (a negative time
    # limit, a cap below one or a lone int ran, or failed in list(), with
    # no word naming them)
    check_callable(progress, "progress", "progress(done, total)")
    check_callable(on_resolution, "on_resolution", "on_resolution(entry)")
    strict = check_strict(strict, "verify_genus")
    fill = check_fill(fill, "verify_genus")  # before any resolution runs: the verdict compares by it as a string
    # a 0D array is iterable by its type and not by NumPy, which raised TypeError from list()
    if resolutions is None:  # (a cap checked below; one that is not an int keeps the defaults for its refusal)
        cap = whole_given(max_resolution)
        resolutions = default_resolutions(max(1, MAX_RESOLUTION if cap is None else cap))
    resolutions = scalar_given(resolutions)  # type: ignore[assignment]  # refused below as one number
    if isinstance(resolutions, (str, bytes)) or not isinstance(resolutions, Iterable):
        hint = f"; one resolution is [{given_text(resolutions)}]" if whole_given(resolutions) is not None else ""
        raise IsoflowError(f"verify_genus: resolutions must be a sequence of integers, got {given_text(resolutions)}{hint}")
    resolutions = [scalar_given(r) for r in resolutions]  # type: ignore[misc]  # a 0D array of a number is that number
    if not resolutions:
        raise IsoflowError("verify_genus needs at least one resolution")
    wholes = [whole_given(r) for r in resolutions]  # int() took "32" and 32.5 (as 32) in silence
    for r, whole in zip(resolutions, wholes):
        if whole is None or whole < 1:
            raise IsoflowError(f"verify_genus: resolutions must be integers >= 1, got {given_text(r)} in "
                               f"{given_text(resolutions)}")
    resolutions = wholes  # type: ignore[assignment]  # Python ints, as just checked
    # the verdict's rows and its JSON hold Python ints, whatever the caller's type
    whole = whole_given(max_resolution)
    if whole is None or whole < 1:
        raise IsoflowError(f"verify_genus: max_resolution must be an integer >= 1, got {given_text(max_resolution)}")
    max_resolution = whole
    # the connectivity a surface isoflow wrote records in its file, read once
    # for the default connectivity and the voxel-contact reference
    written = written_connectivity(mesh) if isinstance(mesh, (str, os.PathLike)) else None
    connectivity, recorded = _connectivity_of(connectivity, written)
    time_limit = scalar_given(time_limit)  # type: ignore[assignment]  # a 0D array of a number is that number
    if isinstance(time_limit, (bool, np.bool_)) or not isinstance(time_limit, (int, float, np.integer, np.floating)) \
            or not time_limit > 0:
        raise IsoflowError(f"verify_genus: time_limit must be a positive number of seconds, got {given_text(time_limit)}")
    step = check_switch(step, "step", "verify_genus")
    stats: dict = {}
    name, v, f = mesh_input(mesh, stats=stats)
    if strict:
        _refuse_as_voxelize(name, v, f, fill)
    # the digital rows voxelise the faces as loaded, as isoflow voxelize
    # reads the same file: a copy of a face adds its winding (a wall listed
    # twice parts the solid), which the surface counted below has not
    given = voxelised = v, f
    f = _drop_repeated_faces(v, f, stats)
    v, f = _split_t_junctions(v, f, stats)
    if "t_junctions" in stats:
        # the digital rows read the faces as loaded split at the T-junctions
        # as the voxeliser splits them, each copy too: split once here, the
        # voxeliser then finds the cracks closed at every resolution
        if "repeated_faces" in stats:
            vx, fx, split = close_t_junctions(*given)
            voxelised = vx, fx
            # the note says how many faces the voxeliser split, not the mesh rows' count
            stats["t_junctions"] = dict(stats["t_junctions"], digital_faces=0 if split is None else split["faces"])
        else:  # no face dropped: the mesh rows' split is the voxeliser's
            voxelised = v, f
    # the voxeliser would look for T-junctions in an open mesh at each
    # resolution: where the mesh rows' search closed nothing it finds
    # nothing in the same faces, and where that search closed some, one
    # search of the split mesh, here, says whether it finds more (only
    # then is it left to look)
    t_junctions = "t_junctions" in stats and close_t_junctions(*voxelised)[2] is not None
    w = witnesses(v, f)
    # the header says the faces the digital rows read beside the mesh's
    w["mesh"] = dict(w["mesh"], faces_as_loaded=len(given[1]))
    reference = w["solid_genus"] if w["overlap"] else w["walled_genus"] if w["walled"] else w["mesh"]["genus"]
    filled = filled_genus(w, fill)
    target = reference if filled is None else filled
    bodies = reference_bodies(w, fill)
    source: Literal["mesh", "solid", "voxels"] = "solid" if w["overlap"] else "mesh"
    contacts = voxel_contacts(w, v, f, connectivity, fill, written)
    if contacts is not None and (reference, bodies) == (contacts["betti"][1], contacts["betti"][0]):
        contacts = None  # the rows read the contacts as the connectivity does: nothing to say
    if contacts is not None:
        # a voxel surface touching itself at edge or vertex contacts: the
        # mesh's genus and manifold3d's solid read those points as neither
        # connectivity does, the voxels at the surface's own grid do
        reference = target = contacts["betti"][1]
        bodies, source = contacts["betti"][0], "voxels"
    # a non-orientable component has no inside: with nothing else to compare
    # against, no finer grid settles what its winding number reads, and the
    # doubling only multiplies components (a Moebius band: hundreds at 1024)
    no_inside = bool(w["mesh"]["non_orientable"]) and target is None
    joined = None if contacts is not None else touch_joined_bodies(w, f, connectivity, fill, bodies)
    try:  # with strict, a mesh that is not watertight is refused here
        digital, stop = digital_steps(
            *voxelised, resolutions, connectivity, step=step and not w["crossing_self"] and not no_inside,
            max_resolution=max_resolution,
            time_limit=time_limit, target=target, progress=progress, on_resolution=on_resolution,
            strict=strict, fill=fill, bodies=bodies, t_junctions=t_junctions, joined=joined,
            touching=None if joined is None else touch_joined_betti(w, f, joined))
    except IsoflowError as exc:  # a refused grid keeps its command-line words
        raise exc.called("verify_genus", "voxelize").at(name) from None
    if step and no_inside and stop is not None:
        stop = Stop("no_inside")
    stable = len(digital) >= 2 and digital[-1]["betti"] == digital[-2]["betti"]
    kind = verdict_kind(w, digital, target, stable, bodies)
    return GenusVerdict(
        input=name, mesh=w["mesh"], manifold3d=w["manifold3d"], pymeshlab=w["pymeshlab"],
        self_intersecting_faces=w["self_intersecting_faces"],
        faces_crossing_other_components=w["faces_crossing_other_components"],
        solid_genus=w["solid_genus"], fill=fill, digital=digital, solid=w["solid"], converged=stable, agree=kind == "agree",
        kind=kind, reference=reference, reference_source=source,
        stop=stop, bodies=bodies, filled_genus=filled,
        notes=tuple(recorded + load_notes(stats) + shape_notes(w, kind, fill, contacts) + rounding_notes(v, f, w, stats)
                    + digital_notes(w, digital, target, stable, fill, bodies, source)))


def _connectivity_of(connectivity: int | np.integer | None, written: int | None) -> tuple[int, list[Note]]:
    """The digital rows' connectivity, checked: the one asked, else
    ``written``, the one the file records where isoflow wrote it, else 6;
    with the ``written_connectivity`` note where the file's, 26, was taken.
    A surface isoflow wrote splits its voxels' edge and vertex contacts at
    that connectivity, so read at the other one its rows count other
    voxels."""
    from ..digital.connectivity import check_connectivity

    if connectivity is not None:
        return check_connectivity(3, connectivity), []
    if written is None or written == 6:  # (6 is every other file's: nothing to say)
        return 6, []
    return written, [Note("written_connectivity", {"connectivity": written})]


def voxel_contacts(w: dict, v: np.ndarray, f: np.ndarray, connectivity: int, fill: Fill,
                   written: int | None = None) -> dict | None:
    """The facts of the ``voxel_contacts`` note, or None: where a closed,
    oriented mesh that crosses nowhere is a voxel surface
    (:func:`~isoflow.mesh.voxel_object.voxel_lattice`) touching itself
    along edges or at vertices (the edge and vertex contacts of its voxels,
    which ``isoflow surface`` splits and a reader's weld joins) and its
    file records ``written``, the connectivity it was written at
    (:func:`~isoflow.mesh.voxel_object.written_connectivity`; None: no
    record, another program's file or a mesh in memory): the voxels
    it bounds at its own grid, their Betti numbers at ``connectivity``
    (the digital rows') and at the other one, the non-manifold ``edges``
    and ``vertices`` the contacts make, and ``written``, the file's
    connectivity. Only the winding fill's voxels are the solid compared.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from isoflow.mesh.export import write_surface
    >>> vol = np.zeros((4, 4, 3), bool); vol[1, 1, 1] = vol[2, 2, 1] = True   # an edge contact
    >>> path = write_surface(vol, pathlib.Path(tempfile.mkdtemp()) / "s.ply", 6)
    >>> _, v, f = mesh_input(path)
    >>> from isoflow.mesh.voxel_object import written_connectivity
    >>> facts = voxel_contacts(witnesses(v, f), v, f, 6, "winding", written_connectivity(path))
    >>> facts["betti"], facts["other"], facts["edges"], facts["written"]
    ([2, 0, 0], [1, 0, 0], 1, 6)
    """
    m = w["mesh"]
    touch = m["nonmanifold_edges"] or m["nonmanifold_vertices"] or m["shared_vertices"]
    if fill != "winding" or connectivity not in (6, 26) or not touch or not w["balanced"] or w["crossing_self"]:
        return None
    # only a file isoflow wrote says that its faces are voxels' and at which
    # connectivity they touch: boxes a user stacks on a lattice are solids
    # that touch, whose reference stays manifold3d's union
    if written is None:
        return None
    found = voxel_object(v, f, connectivity)
    if found is None:
        return None
    return {**found, "edges": int(m["nonmanifold_edges"]), "vertices": int(m["nonmanifold_vertices"]),
            "solid_genus": w["solid_genus"], "written": written}


def _refuse_as_voxelize(name: str, v: np.ndarray, f: np.ndarray, fill: Fill) -> None:
    """With ``strict``, refuse what ``voxelize(strict=True)`` refuses, on
    the mesh as loaded: the repairs the genus makes before counting
    (repeated faces dropped, edges split at T-junctions) would otherwise
    let through a mesh that the strict voxeliser refuses for the open or
    non-manifold edges it has. The line says what genus does without
    ``strict``: it makes those repairs (voxelize splits the T-junctions
    too, but keeps each repeated face)."""
    found = Solid(v, f, fill=fill).strict_defects()
    if found is None:
        return
    said = f"{name}: mesh is not watertight: {found[0]}"
    unstrict = _without_strict(v, f, found[1])
    raise strict_refusal(said, unstrict)


def _without_strict(v: np.ndarray, f: np.ndarray, rule: str) -> str:
    """What :func:`verify_genus` does without ``strict`` with a mesh that
    ``strict`` refuses: the repairs it makes (repeated faces dropped, edges
    split at T-junctions), and whether they close the mesh, or else the
    ``rule`` that reads the mesh as it stands (:meth:`Solid.strict_defects`)."""
    facts: dict = {}
    v2, f2 = _split_t_junctions(v, _drop_repeated_faces(v, f, facts), facts)
    repairs = []
    if "repeated_faces" in facts:
        repairs.append(f"drops {counted(facts['repeated_faces']['copies'], 'repeated face')}")
    if "t_junctions" in facts:
        repairs.append(f"splits the edges at {counted(facts['t_junctions']['points'], 'T-junction')}")
    done = " and ".join(repairs)
    # the copies are dropped for the mesh rows alone: the digital rows read the faces as loaded
    copies = "; its digital rows count every copy of a face" if "repeated_faces" in facts else ""
    if repairs and Solid(v2, f2).strict_defects() is None:
        return f"genus {done}, which closes the mesh, and counts its genus{copies}"
    return f"genus {done + ', then ' if repairs else ''}gives its verdict on the mesh as it stands: {rule}{copies}"


def _drop_repeated_faces(v: np.ndarray, f: np.ndarray, stats: dict) -> np.ndarray:
    """The faces less the repeats of earlier ones (the same three corners
    the same way round, :func:`~isoflow.mesh.load.repeated_faces`); where
    there are some, ``stats["repeated_faces"]`` holds the facts of their
    note: ``n`` faces listed more than once, ``copies`` dropped and the
    ``corners`` of the first such face."""
    first = repeated_faces(f)
    repeat = first != np.arange(len(f))
    if not repeat.any():
        return f
    listed = np.unique(first[repeat])
    stats["repeated_faces"] = {"n": len(listed), "copies": int(np.count_nonzero(repeat)),
                               "corners": _corners_of(v, f[listed[0]])}
    return f[~repeat]


def _split_t_junctions(v: np.ndarray, f: np.ndarray, stats: dict) -> tuple[np.ndarray, np.ndarray]:
    """The mesh with the edges that a vertex of another face splits (a
    T-junction: :func:`~isoflow.mesh.t_junctions.close_t_junctions`) split
    there, where that closes them; ``stats["t_junctions"]`` holds the
    facts of their note. The faces were counted as open though the
    surface is closed as drawn."""
    v2, f2, facts = close_t_junctions(v, f)
    if facts is not None:
        stats["t_junctions"] = facts
    return v2, f2


def _corners_of(v: np.ndarray, face: np.ndarray) -> tuple:
    """A face's corners as tuples of floats (a note's facts, where to look)."""
    return tuple(tuple(float(x) for x in v[i]) for i in face)


def _double_sided(v: np.ndarray, f: np.ndarray) -> dict | None:
    """Pairs of faces on the same three corners, once each way round (the
    two sides of a sheet, or a wall between two solids), or None: ``n``
    pairs, the ``corners`` of the first, and the ``genus`` of the mesh with
    the later face of each pair left out (None where that mesh has none),
    what removing the reversed copies would give.  A pair of zero-area
    faces (corners in a line) draws nothing: left to the zero-area note.

    Where pairs form walls between solids (boxes stacked face to face on
    shared corners, a voxel model written cube by cube:
    :func:`~isoflow.mesh.census.one_face_per_pair` drops such a wall whole),
    also ``walls``, the pairs in walls, and ``union_genus``, the genus of
    the mesh without its walls: the surface of the solids' union, which is
    what the voxels are (both left out where that mesh is no closed
    manifold: a face of a closed surface drawn twice is no wall)."""
    from .census import one_face_per_pair, opposite_pairs  # compiled: loaded with the census

    mate = opposite_pairs(f, len(v))
    later = (mate >= 0) & (mate < np.arange(len(f)))
    if later.any():
        p = v[f[later]]
        later[later] = np.any(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    if not later.any():
        return None
    first = int(mate[np.argmax(later)])
    out = {"n": int(np.count_nonzero(later)), "corners": _corners_of(v, f[first]),
           "genus": mesh_topology(v, f[~later])["genus"]}
    read, one = one_face_per_pair(v, f, mate)
    walls = (len(f) - len(read) - one) // 2  # a wall's pairs are dropped both faces; the others one face each
    union_genus = mesh_topology(v, read)["genus"] if walls else None
    if union_genus is not None:  # walls that part solids: without them the surface closes (not a face drawn twice)
        out.update(walls=walls, union_genus=union_genus)
    return out


def witnesses(v: np.ndarray, f: np.ndarray) -> dict:
    """What the mesh, the exact crossing test, manifold3d and pymeshlab say
    of a loaded mesh, and the flags the verdict reads: ``crossing_self``
    (faces cross faces of their own component), ``balanced`` (closed and
    consistently oriented), ``nested`` (shells nest facing the same way, so
    the mesh is not the solid's boundary), ``overlap`` (the solid's genus
    is the reference: components overlap, touch or nest, or faces of one
    component touch, or ``edge_joined``: closed oriented sheets meet along
    non-manifold edges, solids touching along an edge) and
    ``double_sided`` (faces listed once each way round, or None), and
    ``walled`` with ``walled_genus``: every such pair lies in a wall
    between solids, and the genus of the mesh without the walls, the
    reference where no solid genus is (the solids on either side of a wall
    share its faces: their union is what the voxels are, and which side a
    lone pair means is not known, so a mesh with other pairs has none)."""
    mesh, comp = mesh_topology(v, f, return_components=True)
    whole = whole_manifold(v, f)
    out = {"mesh": mesh, "manifold3d": manifold3d_report(v, f, whole), "pymeshlab": pymeshlab_report(v, f)}
    out.update(self_intersections(v, f, comp))
    crossing_self = bool(out["self_intersecting_faces"])
    balanced = mesh["boundary_edges"] == 0 and mesh["inconsistent_edges"] == 0
    solid = solid_report(v, f, whole) if balanced and not crossing_self else {"error": "not computed"}
    touching = bool(out["faces_crossing_other_components"] or mesh["shared_vertices"]
                    or out["faces_touching_own_component"])
    nested = solid.get("boundary") is False and not touching
    double_sided = _double_sided(v, f)
    # closed, oriented, and no wall drawn from both sides: sheets that meet
    # along a non-manifold edge are solids touching along it (two boxes on
    # a common edge), whose union manifold3d builds as it splits the edge
    edge_joined = bool(balanced and mesh["nonmanifold_edges"] and not double_sided and not touching and not nested)
    # each component's longest side: one shorter than a voxel holds at most
    # one voxel centre, so a grid may miss it rather than merge it
    ends = v[f].reshape(len(f), -1)
    n = int(comp.max()) + 1 if len(comp) else 0
    low = np.full((n, 3), np.inf)
    high = np.full((n, 3), -np.inf)
    for k in range(3):
        np.minimum.at(low[:, k], comp, ends[:, k::3].min(axis=1))
        np.maximum.at(high[:, k], comp, ends[:, k::3].max(axis=1))
    out["component_sizes"] = (high - low).max(axis=1) if n else np.zeros(0)
    out.update(solid=solid, solid_genus=solid.get("genus"), crossing_self=crossing_self, balanced=balanced,
               nested=nested, overlap=touching or nested or edge_joined, edge_joined=edge_joined,
               double_sided=double_sided)
    sided = out["double_sided"] or {}
    out.update(walled=sided.get("walls", 0) == sided.get("n", -1), walled_genus=sided.get("union_genus"))
    return out


def filled_genus(w: dict, fill: Fill) -> int | None:
    """The genus the digital genus of a flood fill is compared with where
    the solid has cavities: that of the solid with its cavities filled
    (:func:`solid_report`'s ``filled_genus``), which the flood fill is, and
    which has none of the handles inside the cavities (a torus inside a
    hollow ball: 0, where the mesh's genus is 1); None for the other fills,
    a solid without cavities (the reference is its genus) or no solid.

    Examples
    --------
    >>> w = {"solid": {"genus": 1, "bodies": 2, "cavities": 1, "filled_genus": 0, "filled_bodies": 1}}
    >>> filled_genus(w, "flood"), filled_genus(w, "winding")
    (0, None)
    """
    solid = w["solid"]
    if fill != "flood" or not solid.get("cavities") or "filled_genus" not in solid:
        return None
    return int(solid["filled_genus"])


def reference_bodies(w: dict, fill: Fill) -> int | None:
    """The bodies the digital components (b0) are compared with: those of
    the solid manifold3d builds (edge-connected, so two balls touching at
    a point are two), for a flood fill of a solid with cavities those of
    the solid with its cavities filled (which swallows the bodies inside
    them), or None where there is no such solid or the voxels are not it:
    a shell (whose components are surfaces), or faces drawn from both
    sides other than walls between solids (manifold3d counts both faces of
    each pair, which cancel: a closed surface drawn double-sided bounds no
    body for it, where the voxeliser reads one face of each pair and fills
    the solid it draws).

    Examples
    --------
    >>> w = {"solid": {"bodies": 0, "cavities": 0}, "double_sided": {"n": 320}, "walled": False}
    >>> reference_bodies(w, "winding"), reference_bodies(dict(w, double_sided=None), "winding")
    (None, 0)
    """
    solid = w["solid"]
    if "bodies" not in solid or fill == "shell" or (w.get("double_sided") and not w.get("walled")):
        return None
    if fill == "flood" and solid["cavities"]:
        return int(solid["filled_bodies"]) if "filled_bodies" in solid else None
    return int(solid["bodies"])


def verdict_kind(w: dict, digital: list, reference: int | None, stable: bool,
                 bodies: int | None = None) -> VerdictKind:
    """What the verdict says first (see :data:`~isoflow.mesh.verdict.VerdictKind`);
    ``reference`` is the genus the digital genus should reach (a flood
    fill's: :func:`filled_genus`).
    An empty grid comes first: it has genus 0 and would "agree" with a
    surface's genus 0 for nothing (a flat or zero-volume mesh, whose faces
    may also lie on each other). The digital components are compared with
    ``bodies`` as the digital genus is with ``reference``: a mesh of two
    bodies whose voxels are one component disagrees."""
    if digital and digital[-1]["betti"][0] == 0:
        return "no_solid"
    if w["crossing_self"]:
        return "self_intersecting"
    if not digital or reference is None:
        return "no_reference"
    if not stable:
        return "not_converged"
    same_bodies = bodies is None or digital[-1]["betti"][0] == bodies
    return "agree" if digital[-1]["genus"] == reference and same_bodies else "disagree"


def load_notes(stats: dict) -> list[Note]:
    """What the loading did: faces dropped, positions merged, repeated
    faces dropped, edges split at T-junctions."""
    notes = []
    if stats.get("dropped_faces"):
        notes.append(Note("dropped_faces", {"n": stats["dropped_faces"]}))
    if stats.get("welded"):
        notes.append(Note("welded", {"n": stats["welded"]}))
    if stats.get("repeated_faces"):
        notes.append(Note("repeated_faces", stats["repeated_faces"]))
    if stats.get("t_junctions"):
        notes.append(Note("t_junctions", stats["t_junctions"]))
    return notes


def shape_notes(w: dict, kind: VerdictKind, fill: Fill = "winding", contacts: dict | None = None) -> list[Note]:
    """What the mesh is: double-sided, open or inconsistently oriented
    (with the ``fill`` whose voxels were compared instead),
    non-manifold, nested or overlapping, and,
    where the verdict does not start with it, self-intersecting. A voxel
    surface touching itself (``contacts``: :func:`voxel_contacts`) has one
    note for its non-manifold edges and vertices, which says how each row
    reads them."""
    if contacts is not None:
        return [Note("voxel_contacts", contacts)]
    mesh = w["mesh"]
    notes = []
    # components no turning of their faces makes consistent: said in the note on their edges
    odd = {"non_orientable": mesh["non_orientable"]} if mesh["non_orientable"] else {}
    if w["double_sided"]:
        notes.append(Note("double_sided", w["double_sided"]))
    if mesh["boundary_edges"]:
        notes.append(Note("open", {"boundary_edges": mesh["boundary_edges"],
                                   "inconsistent_edges": mesh["inconsistent_edges"], "fill": fill, **odd}))
    elif not w["balanced"]:  # every edge has two faces or more: not open, but not oriented as a solid's boundary
        notes.append(Note("inconsistent", {"edges": mesh["inconsistent_edges"], "fill": fill, **odd,
                                           **({"genus": mesh["genus"]} if mesh["genus"] is not None else {})}))
    if mesh["nonmanifold_edges"]:
        joined = {"solid_genus": w["solid_genus"], "error": w["solid"].get("error")} if w["edge_joined"] else {}
        notes.append(Note("nonmanifold_edges", {"n": mesh["nonmanifold_edges"], **joined}))
    if mesh["nonmanifold_vertices"]:
        notes.append(Note("nonmanifold_vertices", {"n": mesh["nonmanifold_vertices"]}))
    if w["nested"]:
        notes.append(Note("nested", {"components": mesh["components"], "solid_genus": w["solid_genus"]}))
    elif w["overlap"] and not w["edge_joined"]:  # (the non-manifold edges' note says where they touch)
        notes.append(Note("overlap", {
            "components": mesh["components"], "crossing": w["faces_crossing_other_components"] or 0,
            "shared": mesh["shared_vertices"], "solid_genus": w["solid_genus"], "error": w["solid"].get("error"),
            **({"touching": w["faces_touching_own_component"]} if w["faces_touching_own_component"] else {}),
            **({"approximate": True} if w["solid"].get("approximate") else {})}))
    if w["crossing_self"] and kind != "self_intersecting":
        notes.append(Note("self_intersecting", {"n": w["self_intersecting_faces"]}))
    if w["zero_area_faces"]:
        notes.append(Note("zero_area_faces", {"n": w["zero_area_faces"], "along": w["pairs_along_slivers"]}))
    return notes


def rounding_notes(v: np.ndarray, f: np.ndarray, w: dict, stats: dict) -> list[Note]:
    """Coordinates that float64 holds coarsely against the mesh's edges
    (:func:`~isoflow.mesh.grid.float64_rounding`), with the defects found
    that the rounding may have made."""
    facts = float64_rounding(v, f)
    if facts is None:
        return []
    mesh = w["mesh"]
    found = {"crossings": w["self_intersecting_faces"] or w["faces_crossing_other_components"],
             "degenerate faces": stats.get("dropped_faces"), "welds": stats.get("welded"),
             "non-manifold edges": mesh["nonmanifold_edges"], "non-manifold vertices": mesh["nonmanifold_vertices"],
             "zero-area faces": w["zero_area_faces"]}
    return [Note("float64_rounding", {**facts, "defects": [k for k, n in found.items() if n]})]


def touch_joined_bodies(w: dict, faces: np.ndarray, connectivity: int, fill: Fill, bodies: int | None) -> int | None:
    """The components the voxels keep at every resolution where they join
    solids that touch at a point or along an edge (26-connected, or a
    flood fill's shared shell voxels: :func:`_corner_joined`), fewer than
    the solid's ``bodies``; None where that count is not known, or not
    fewer.

    It is known where the bodies touch only at vertices they share: no
    face crosses or touches another component, no shell nests in another
    and the solid has no cavity, so each group of faces joined through
    shared vertices (trimesh's ``body_count``) is one component at any
    grid fine enough to part what does not touch.

    Parameters
    ----------
    w : dict
        The witnesses (:func:`witnesses`).
    faces : numpy.ndarray
        The mesh's faces (M, 3), as counted there.
    connectivity : int
        The digital rows' connectivity.
    fill : str
        The voxels compared.
    bodies : int or None
        The solid's bodies (:func:`reference_bodies`).

    Returns
    -------
    int or None

    Examples
    --------
    Two tetrahedra on a common corner (vertex 0), one body each:

    >>> f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3],
    ...               [0, 4, 5], [0, 5, 6], [0, 6, 4], [4, 6, 5]])
    >>> w = {"mesh": {"shared_vertices": 1, "nonmanifold_vertices": 0, "nonmanifold_edges": 0},
    ...      "faces_crossing_other_components": 0, "nested": False, "solid": {"cavities": 0}}
    >>> touch_joined_bodies(w, f, 26, "winding", 2), touch_joined_bodies(w, f, 6, "winding", 2)
    (1, None)
    """
    from ..scale.graphs import components

    mesh = w["mesh"]
    touch = mesh["shared_vertices"] or mesh["nonmanifold_vertices"] or mesh["nonmanifold_edges"]
    if bodies is None or not touch or not (connectivity == 26 or fill == "flood"):
        return None
    if w["faces_crossing_other_components"] or w["nested"] or w["solid"].get("cavities") != 0:
        return None  # bodies joined otherwise than at shared vertices, or shells that are no body
    used, index = np.unique(faces, return_inverse=True)
    index = index.reshape(faces.shape)
    groups = components(len(used), np.r_[index[:, 0], index[:, 1]], np.r_[index[:, 1], index[:, 2]])[0]
    return groups if groups < bodies else None


def touch_joined_betti(w: dict, faces: np.ndarray, joined: int) -> list[int] | None:
    """The Betti numbers of the solid whose bodies are joined where they
    touch (what 26-connected voxels, or a flood fill's shell, read at every
    resolution fine enough to part what does not touch), ``joined``
    components (:func:`touch_joined_bodies`); None where the mesh does not
    say them.

    The sheets are the faces joined across edges of two faces; where they
    are the solid's bodies (manifold3d's, without cavities), the union of
    the closed bodies glued where they touch has the Euler characteristic
    of the bodies apart (bodies less genus), less ``k - 1`` for each vertex
    of ``k`` sheets and plus ``k - 1`` for each edge of ``k`` sheets. No
    cavity is assumed: a joined solid that encloses one reads otherwise,
    and the stepping goes on.

    Parameters
    ----------
    w : dict
        The witnesses (:func:`witnesses`), whose ``solid`` is read.
    faces : numpy.ndarray
        The faces (M, 3) the witnesses counted.
    joined : int
        The components (:func:`touch_joined_bodies`).

    Returns
    -------
    list of int or None
        ``[b0, b1, b2]``.

    Examples
    --------
    Two tetrahedra on a common edge (vertices 0 and 1), one body each:

    >>> f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3],
    ...               [0, 1, 4], [0, 5, 1], [0, 4, 5], [1, 5, 4]])
    >>> touch_joined_betti({"solid": {"bodies": 2, "genus": 0, "cavities": 0}}, f, 1)
    [1, 0, 0]
    """
    from ..scale.graphs import components

    solid = w["solid"]
    if "bodies" not in solid or solid.get("cavities") != 0 or len(faces) == 0:
        return None
    f = np.asarray(faces, dtype=np.int64)
    sides = np.sort(np.stack([f, np.roll(f, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    edges, edge_of, uses = np.unique(sides, axis=0, return_inverse=True, return_counts=True)
    edge_of = edge_of.ravel()  # the edge of each side (face * 3 + side)
    order = np.argsort(edge_of, kind="stable")
    two = order[uses[edge_of[order]] == 2].reshape(-1, 2) // 3  # the two faces of each edge of two faces
    sheets, sheet = components(len(f), two[:, 0], two[:, 1])
    if sheets != solid["bodies"]:
        return None  # sheets that are not the bodies (a face between non-manifold edges only)
    face_of = np.repeat(np.arange(len(f)), 3)
    at_vertices = len(np.unique(np.c_[f.ravel(), sheet[face_of]], axis=0)) - len(np.unique(f))
    at_edges = len(np.unique(np.c_[edge_of, sheet[face_of]], axis=0)) - len(edges)
    chi = int(solid["bodies"]) - int(solid["genus"]) - at_vertices + at_edges
    return [int(joined), int(joined) - chi, 0]


def _corner_joined(w: dict, last: dict, bodies: int | None, fill: Fill) -> bool:
    """Whether the last grid is fewer components than the solid's bodies
    where solids touch at a point or along an edge (a shared or pinched
    vertex, a non-manifold edge) and its voxels join them at any
    resolution: 26-connected ones meeting at a corner or an edge, or a
    flood fill's shell, whose voxels the touching surfaces share; manifold3d
    splits the vertex or edge, and 6-connected winding voxels part the
    bodies on a fine enough grid."""
    mesh = w["mesh"]
    touch = mesh["shared_vertices"] or mesh["nonmanifold_vertices"] or mesh["nonmanifold_edges"]
    joins = last["connectivity"] == 26 or fill == "flood"
    return bool(joins and bodies is not None and touch and last["betti"][0] < bodies)


#: a lens (:func:`lens_of`) thinner than this many voxels of the finest
#: grid is named where the digital Betti numbers do not settle
THIN_LENS_VOXELS = 2


def digital_notes(w: dict, digital: list, reference: int | None, stable: bool, fill: Fill = "winding",
                  bodies: int | None = None, source: str = "mesh") -> list[Note]:
    """What the grids showed (cavities, resolutions too coarse, 26-connected
    voxels joining solids that touch, fewer components than ``bodies``,
    other components than ``bodies`` where the solid's are compared:
    ``source`` not ``"voxels"``) and what the peers could not say; where
    the Betti numbers do not settle, the thinnest overlap of crossing
    components, if the finest grid does not resolve it."""
    notes = []
    if digital:
        last = digital[-1]
        if _corner_joined(w, last, bodies, fill):
            notes.append(Note("corner_joins", {"bodies": bodies, "components": last["betti"][0],
                                               "by": "flood" if fill == "flood" else "connectivity"}))
        elif bodies is not None and last["betti"][0] not in (0, bodies) and source != "voxels":
            # a grid joins bodies closer than a voxel and breaks parts thinner
            # than one: the count alone (a disagree's words, or none where the
            # tunnels have not settled) does not say that a finer grid may mend it
            # (an empty grid joined or broke nothing: the no_solid verdict says why)
            # fewer components may also be bodies smaller than a voxel, which a grid misses
            # (counted where each component is a body: none overlaps, touches or nests in another)
            sizes = () if w.get("overlap") else w.get("component_sizes", ())
            small = int(np.count_nonzero(np.asarray(sizes) < last["pitch"]))
            notes.append(Note("body_count", {"bodies": bodies, "components": last["betti"][0],
                                             "resolution": last["resolution"], "pitch": last["pitch"],
                                             **({"small": small} if small and last["betti"][0] < bodies else {})}))
        if last["betti"][2] and fill != "shell":  # (a shell encloses the inside of each closed surface)
            notes.append(Note("cavities", {"n": last["betti"][2], "resolution": last["resolution"],
                                           "solid": w["solid"].get("cavities")}))
        lens = w["solid"].get("thinnest_lens")
        if not stable and lens is not None and lens["thickness"] < THIN_LENS_VOXELS * last["pitch"]:
            notes.append(Note("thin_overlap", {**lens, "voxels": lens["thickness"] / last["pitch"],
                                               "resolution": last["resolution"]}))
        if reference is not None and stable:
            # too coarse: a grid whose genus the finer, settled ones do not
            # repeat; one that gives the settled genus is not, even where
            # that genus is not the reference
            notes += [Note("coarse", {"resolution": d["resolution"], "genus": d["genus"], "pitch": d["pitch"]})
                      for d in digital[:-2] if d["genus"] != last["genus"]]
    if fill == "flood" and w["solid"].get("cavities"):
        # the flood fill is the solid with its cavities filled: a torus inside a hollow ball is lost to it,
        # which is why its target is not the mesh's genus
        solid = w["solid"]
        # what the filling loses: bodies nested in the cavities (their surfaces swallowed), and handles
        # (of those bodies, or of a cavity's own surface: a torus-shaped hole)
        notes.append(Note("flood_cavities", {"n": solid["cavities"],
                                             "inside": max(0, solid["bodies"] - solid["filled_bodies"]),
                                             "handles": max(0, solid["genus"] - solid["filled_genus"])}))
    if "error" in w["manifold3d"]:
        notes.append(Note("manifold3d_refused", {"error": w["manifold3d"]["error"]}))
    mesh = w["mesh"]
    if mesh["genus"] is None and w["balanced"] and not mesh["nonmanifold_edges"]:
        notes.append(Note("no_mesh_genus"))
    return notes
