"""The genus of a mesh, as the mesh, manifold3d, pymeshlab and the voxelised
solid each see it.

:func:`mesh_topology` says what the mesh itself says (components, Euler
number, genus per component, defects); :func:`verify_genus` puts it beside
manifold3d's, pymeshlab's and the digital topology of the voxelised solid
at each resolution, with one verdict.

What "genus" means differs between tools (see PEERS.md): trimesh's Euler
number is ``V - E + F`` of the whole mesh, manifold3d's ``genus()`` is
``1 - chi/2`` of the whole mesh (negative for several components), pymeshlab
sums genera over components. Here ``genus`` always means the total number of
handles: the sum over closed components of ``(2 - chi_c) / 2``; for a solid
this is its number of tunnels b1.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..digital.topology import LABEL_BYTES_PER_VOXEL, betti_numbers
from ..errors import IsoflowError
from ..scale.memory import default_budget, gib
from .load import load_mesh, mesh_defects
from .fills import Fill
from .voxelize import voxelize

# --------------------------------------------------------------------------
# the mesh's own topology
# --------------------------------------------------------------------------


def mesh_topology(vertices, faces, return_components: bool = False):
    """Components, Euler number and genus of a triangle mesh, with its defects.

    Components are edge-connected face sets. A component's genus is
    ``(2 - chi_c) / 2`` when it is closed (no boundary edge), every edge has
    two faces, and every vertex has one fan of faces in it; otherwise None.
    ``nonmanifold_vertices`` counts vertices with more than one fan (two
    closed surfaces touching at a point, like ``hourglass_ico.obj``).
    With ``return_components``, also each face's component number.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

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
    graph = coo_matrix((np.ones(len(order)), (face_of[order], first_face)), shape=(nf, nf))
    ncomp, comp = connected_components(graph, directed=False)

    # per component: V (vertices used), E (edges), F, and whether closed
    comp_of_edge = comp[face_of[order][edge_start]]
    E = np.bincount(comp_of_edge, minlength=ncomp)
    F = np.bincount(comp, minlength=ncomp)
    vc = np.unique(np.stack([np.repeat(comp, 3), f.ravel()], axis=1), axis=0)
    V = np.bincount(vc[:, 0], minlength=ncomp)
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
    cgraph = coo_matrix((np.ones(len(src)), (src, dst)), shape=(3 * nf, 3 * nf))
    _, fan = connected_components(cgraph, directed=False)
    vf = np.unique(np.stack([f.ravel(), fan], axis=1), axis=0)
    fans_per_vertex = np.bincount(vf[:, 0], minlength=len(v))
    vcomp = np.unique(np.stack([f.ravel(), np.repeat(comp, 3)], axis=1), axis=0)
    comps_per_vertex = np.bincount(vcomp[:, 0], minlength=len(v))
    pinched_in_comp = np.zeros(ncomp, dtype=bool)
    inner_pinch = np.flatnonzero(fans_per_vertex > np.maximum(comps_per_vertex, 1))
    if len(inner_pinch):
        hit = np.isin(f, inner_pinch).any(axis=1)
        pinched_in_comp[np.unique(comp[hit])] = True

    chi = V - E + F
    closed = ~bad_edge & ~pinched_in_comp
    genus_c = [int((2 - c) // 2) if ok and c % 2 == 0 else None for c, ok in zip(chi.tolist(), closed)]
    used = np.unique(f)
    euler = int(len(used) - len(edge_start) + nf)
    total = sum(genus_c) if genus_c and all(g is not None for g in genus_c) and defects["inconsistent_edges"] == 0 else None
    report = {
        "watertight": bool(defects["watertight"]),
        "components": int(ncomp),
        "euler_number": euler,
        "genus": total,
        "genus_per_component": genus_c,
        "boundary_edges": int(defects["boundary_edges"]),
        "nonmanifold_edges": int(defects["nonmanifold_edges"]),
        "inconsistent_edges": int(defects["inconsistent_edges"]),
        "nonmanifold_vertices": int(np.count_nonzero(fans_per_vertex > 1)),
        "vertices": len(used),
        "faces": int(nf),
        # vertices on faces of more than one component: components touching
        "shared_vertices": int(np.count_nonzero(comps_per_vertex > 1)),
    }
    return (report, comp) if return_components else report


def manifold3d_report(vertices, faces) -> dict:
    import manifold3d as m3

    v, e = normalized(vertices)  # manifold3d takes float32
    try:
        mf = m3.Manifold(
            m3.Mesh(vert_properties=np.asarray(v, np.float32), tri_verts=np.asarray(faces, np.uint32))
        )
    except Exception as exc:  # the binding raises for malformed input
        return {"error": f"{type(exc).__name__}: {exc}"}
    status = mf.status()
    if status != m3.Error.NoError:
        return {"error": status.name}
    parts = mf.decompose()
    with np.errstate(over="ignore", under="ignore"):
        volume = float(np.ldexp(mf.volume(), 3 * e))
    return {
        "genus": int(sum(p.genus() for p in parts)),
        "genus_whole_mesh": int(mf.genus()),
        "components": len(parts),
        "volume": volume,
    }


def pymeshlab_report(vertices, faces) -> dict:
    try:
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(normalized(vertices)[0], np.asarray(faces, np.int32)))
        t = ms.get_topological_measures()
    except Exception as exc:
        return {"error": f"{type(exc).__name__}: {exc}"}
    out = {k: (int(t[k]) if not isinstance(t[k], bool) else bool(t[k])) for k in (
        "genus", "connected_components_number", "boundary_edges", "non_two_manifold_edges",
        "non_two_manifold_vertices", "is_mesh_two_manifold") if k in t}
    if out.get("genus", 0) < 0:
        out["error"] = "pymeshlab reports genus -1: the mesh is not a two-manifold"
    return out


def self_intersections(vertices, faces, component) -> dict:
    """Faces that cross other faces (pymeshlab's
    ``compute_selection_by_self_intersections_per_face``), split into those
    crossing a face of their own component (``self_intersecting_faces``: the
    component is no embedded surface) and those crossing only other
    components (``faces_crossing_other_components``: components overlap).

    The whole mesh is tested once; only components with a selected face are
    tested again on their own. The vertices are normalised first: the test's
    tolerances are absolute, so tiny or huge units, or a mesh far from the
    origin, gave false crossings or missed real ones.
    """
    try:
        import pymeshlab

        v = normalized(vertices)[0]
        f = np.asarray(faces, np.int32)
        hit = _intersecting_faces(pymeshlab, v, f)
        own = np.zeros(len(f), dtype=bool)
        for c in np.unique(component[hit]):
            rows = np.flatnonzero(component == c)
            used, local = np.unique(f[rows], return_inverse=True)
            own[rows] = _intersecting_faces(pymeshlab, v[used], local.reshape(-1, 3).astype(np.int32))
    except Exception as exc:  # pymeshlab raises its own types for degenerate input
        return {"error": f"{type(exc).__name__}: {exc}"}
    return {
        "self_intersecting_faces": int(np.count_nonzero(own)),
        "faces_crossing_other_components": int(np.count_nonzero(hit & ~own)),
    }


def _intersecting_faces(pymeshlab, v, f) -> np.ndarray:
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(v, f))
    ms.compute_selection_by_self_intersections_per_face()
    return np.asarray(ms.current_mesh().face_selection_array(), dtype=bool)


def normalized(vertices) -> tuple[np.ndarray, int]:
    """``(vertices, e)``: the vertices centred on their bounding box and
    scaled by ``2**-e`` to a size near 1 (exact in binary), for the tools
    that take float32 or absolute tolerances (manifold3d, pymeshlab's
    intersection test): a mesh in units of 1e-35 or 1e36, or placed at 1e7,
    then reads as it does at 1. Topology does not change; lengths scale by
    ``2**e``."""
    v = np.asarray(vertices, np.float64)
    if not len(v):
        return v, 0
    lo, hi = v.min(axis=0), v.max(axis=0)
    size = float(np.max(hi - lo))
    e = int(np.frexp(size)[1]) if size > 0 and np.isfinite(size) else 0
    return np.ldexp(v - (lo + hi) / 2, -e), e


def solid_report(vertices, faces) -> dict:
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
    the digital genus measures); ``boundary`` says whether the mesh is the
    solid's boundary (every surface between a region of winding 0 and one
    of winding not 0), so that the mesh's own genus is the one to compare.
    ``{"error": ...}`` where manifold3d refuses the mesh.
    """
    import manifold3d as m3

    v, e = normalized(vertices)
    try:
        whole = m3.Manifold(
            m3.Mesh(vert_properties=np.asarray(v, np.float32), tri_verts=np.asarray(faces, np.uint32))
        )
        if whole.status() != m3.Error.NoError:
            return {"error": whole.status().name}
        parts = whole.decompose()
        signs = [1 if p.volume() >= 0 else -1 for p in parts]
        solids = [p if s > 0 else _inside_out(m3, p) for p, s in zip(parts, signs)]
        solid, boundary, approximate = _nonzero_solid(m3, solids, signs)
        pieces = solid.decompose()
    except Exception as exc:  # the binding raises for malformed input (its first line says what)
        detail = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        return {"error": f"{type(exc).__name__}: {detail}"}
    with np.errstate(over="ignore", under="ignore"):
        volume = float(np.ldexp(solid.volume(), 3 * e))
    return {"genus": int(sum(p.genus() for p in pieces)), "surfaces": len(pieces), "volume": volume,
            "boundary": boundary, "approximate": approximate}


#: relative volume below which two solids are taken not to overlap (float32 booleans)
_OVERLAP_RTOL = 1e-6
#: pairs of components whose boxes meet, beyond which the nesting is not
#: worked out (a boolean each): the outward ones are united and the
#: inside-out ones subtracted, ``approximate``
MAX_PAIRS = 5000


def _nonzero_solid(m3, solids: list, signs: list) -> tuple:
    """``(solid, boundary, approximate)`` of :func:`solid_report` from the
    components as solids and their windings (+1 / -1)."""
    n = len(solids)
    if n == 0:
        return m3.Manifold(), True, False
    vols = [s.volume() for s in solids]
    boxes = np.array([np.asarray(s.bounding_box(), np.float64).reshape(2, 3) for s in solids])
    lo, hi = boxes[:, 0], boxes[:, 1]
    meet = np.all((lo[:, None] <= hi[None]) & (lo[None] <= hi[:, None]), axis=2)
    if n > 1 and (np.count_nonzero(meet) - n) // 2 > MAX_PAIRS:
        return _outward_less_inside_out(m3, solids, signs), False, True
    group = list(range(n))  # union-find of crossing components

    def root(i):
        while group[i] != i:
            group[i] = group[group[i]]
            i = group[i]
        return i

    inside = {}  # i -> components j whose solid holds solid i
    for i in range(n):
        for j in range(i + 1, n):
            if not meet[i, j]:
                continue
            common = (solids[i] ^ solids[j]).volume()
            small = min(vols[i], vols[j])
            if common <= _OVERLAP_RTOL * small:
                continue  # apart (or touching)
            if common >= (1 - _OVERLAP_RTOL) * small:  # the smaller one inside the larger
                a, b = (i, j) if vols[i] <= vols[j] else (j, i)
                inside.setdefault(a, []).append(b)
                continue
            if signs[i] != signs[j]:  # crossing, facing opposite ways: no nesting to follow
                return _outward_less_inside_out(m3, solids, signs), False, True
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
        around = wind(parent[k]) if parent[k] is not None else 0
        boundary &= (wind(k) != 0) != (around != 0)
        if wind(k) != 0:
            region = body[k]
            if children.get(k):
                region = region - m3.Manifold.batch_boolean([body[c] for c in children[k]], m3.OpType.Add)
            regions.append(region)
    solid = m3.Manifold.batch_boolean(regions, m3.OpType.Add) if regions else m3.Manifold()
    return solid, boundary, False


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
#: peak bytes per grid voxel of one resolution: the volume, the voxeliser's
#: difference array (int32) and the labelling of the Betti numbers
DIGITAL_BYTES_PER_VOXEL = 1 + 4 + LABEL_BYTES_PER_VOXEL


def digital_steps(vertices, faces, resolutions=DEFAULT_RESOLUTIONS, connectivity: int = 6, *,
                  step: bool = True, max_resolution: int = MAX_RESOLUTION, time_limit: float = TIME_LIMIT,
                  target: int | None = None, progress=None, on_resolution=None,
                  strict: bool = False, fill: Fill = "winding") -> tuple[list, str | None]:
    """Digital topology of the voxelised solid at ``resolutions`` and then,
    while ``step`` and the Betti numbers of the last two differ (or agree on
    a genus other than ``target``: two coarse grids can both close the
    same thin hole), at twice the last, within ``max_resolution``,
    ``time_limit`` seconds and the memory budget.

    Returns the entries (resolution, pitch, shape, voxels, Betti numbers,
    genus, seconds) and why the stepping stopped early (None when it ended
    with stable Betti numbers and the target genus).
    ``progress(done, total)`` follows the voxelisations as one count that
    only grows: each resolution tried weighs ``resolution**3`` (what its grid
    costs), and ``total`` grows by that weight when the stepping adds a
    resolution. ``on_resolution(entry)`` is called after each. ``fill``
    is the voxels compared (:mod:`isoflow.mesh.fills`).
    """
    import time

    todo = sorted({int(r) for r in resolutions})
    out: list = []
    finished = 0  # weight of the resolutions done
    start = time.monotonic()
    while True:
        if todo:
            res = todo.pop(0)
        else:
            stable = len(out) >= 2 and out[-1]["betti"] == out[-2]["betti"]
            if stable and (target is None or out[-1]["genus"] == target):
                return out, None
            if not step:
                return out, "the resolutions asked"
            last = out[-1]
            res = 2 * last["resolution"]
            grow = (res / last["resolution"]) ** 3
            if res > max_resolution:
                return out, f"the largest resolution allowed ({max_resolution}, --max-resolution)"
            if time.monotonic() - start + last["seconds"] * grow > time_limit:
                return out, f"the time limit ({time_limit:g} s, --time-limit): {res} would take about {last['seconds'] * grow:.0f} s"
            need = int(np.prod(last["shape"]) * grow * DIGITAL_BYTES_PER_VOXEL)
            if need > default_budget():
                return out, f"the memory budget: {res} would need about {gib(need)}"
        t = time.monotonic()
        weight = res**3
        ahead = finished + weight + sum(r**3 for r in todo)  # the resolutions known now

        def rung(done, total, finished=finished, weight=weight, ahead=ahead):
            progress(finished + round(weight * (done / total if total else 1.0)), ahead)

        vol = voxelize(vertices, faces, resolution=res, strict=strict, fill=fill,
                       progress=None if progress is None else rung, details=True)
        vol, pitch = vol.volume, vol.pitch
        finished += weight
        betti = betti_numbers(vol, connectivity)
        entry = {"resolution": int(res), "pitch": pitch, "shape": list(vol.shape), "voxels": int(vol.sum()),
                 "connectivity": connectivity, "betti": betti, "genus": betti[1],
                 "seconds": round(time.monotonic() - t, 3)}
        out.append(entry)
        if on_resolution is not None:
            on_resolution(entry)


# --------------------------------------------------------------------------
# genus verification
# --------------------------------------------------------------------------


def verify_genus(path, resolutions=DEFAULT_RESOLUTIONS, connectivity: int = 6, progress=None, *,
                 step: bool = True, max_resolution: int = MAX_RESOLUTION, time_limit: float = TIME_LIMIT,
                 on_resolution=None, strict: bool = False, fill: Fill = "winding") -> dict:
    """The mesh's topology, manifold3d's and pymeshlab's, its self-
    intersections, the genus of the solid it bounds, and the digital
    topology of that solid voxelised at growing resolutions, with a verdict.

    The verdict compares the digital genus (b1 of the voxelised solid) with
    the solid's genus (manifold3d's union) where components overlap or
    touch, and with the mesh's own genus otherwise. It is ``agree`` only
    when the digital Betti numbers are the same at the last two resolutions
    tried (:func:`digital_steps` doubles the resolution until they are, or
    says "not converged at R"), and never for a self-intersecting mesh: its
    surface bounds no well-defined solid, and no grid settles that.

    An open or inconsistently oriented mesh has no genus of its own; its
    solid is read by the generalised winding number (|w| > 1/2) and its
    digital topology reported; ``strict`` refuses it (IsoflowError).
    ``fill`` chooses the voxels compared (:mod:`isoflow.mesh.fills`; the
    report's ``fill``).
    """
    path = Path(path)
    resolutions = list(resolutions)
    if not resolutions:
        raise IsoflowError("verify_genus needs at least one resolution")
    stats: dict = {}
    v, f = load_mesh(path, stats=stats)
    mesh, comp = mesh_topology(v, f, return_components=True)
    crossings = self_intersections(v, f, comp)
    out = {
        "input": str(path),
        "mesh": mesh,
        "manifold3d": manifold3d_report(v, f),
        "pymeshlab": pymeshlab_report(v, f),
        "self_intersecting_faces": crossings.get("self_intersecting_faces"),
        "faces_crossing_other_components": crossings.get("faces_crossing_other_components"),
        "solid_genus": None,
        "fill": fill,
        "digital": [],
    }
    notes = []
    welded = stats["welded"]
    if stats["dropped_faces"]:
        n = stats["dropped_faces"]
        notes.append(f"{n} degenerate face{'s' if n > 1 else ''} (two corners at one position) dropped")
    if welded:
        notes.append(
            f"{welded} vertices that differ only by rounding noise were welded before counting "
            "(tools that merge exact duplicates only see a different, open or higher-genus mesh)"
        )
    if "error" in crossings:
        notes.append(f"pymeshlab could not test for self-intersections ({crossings['error']})")
    crossing_self = bool(out["self_intersecting_faces"])
    overlap = bool(out["faces_crossing_other_components"] or mesh["shared_vertices"])
    balanced = mesh["boundary_edges"] == 0 and mesh["inconsistent_edges"] == 0
    if not balanced:
        notes.append(
            f"the mesh is open ({mesh['boundary_edges']} boundary edges"
            + (f", {mesh['inconsistent_edges']} inconsistently oriented" if mesh["inconsistent_edges"] else "")
            + "): it bounds no solid, so it has no genus as a closed surface; its solid is read by the "
            "generalised winding number (|w| > 1/2)"
        )
    solid = solid_report(v, f) if balanced and not crossing_self else {"error": "not computed"}
    out["solid"] = solid
    if "genus" in solid:
        out["solid_genus"] = solid["genus"]
    # shells nested facing the same way: the solid swallows the inner ones,
    # so the mesh is not its boundary and the solid's genus is the reference
    nested = solid.get("boundary") is False and not overlap
    overlap = overlap or nested
    g = mesh["genus"]
    reference, ref_name = (out["solid_genus"], "solid genus") if overlap else (g, "mesh genus")
    stop = None
    try:  # with strict, a mesh that is not watertight is refused here
        out["digital"], stop = digital_steps(
            v, f, resolutions, connectivity, step=step and not crossing_self, max_resolution=max_resolution,
            time_limit=time_limit, target=reference, progress=progress, on_resolution=on_resolution,
            strict=strict, fill=fill)
    except IsoflowError as exc:
        raise IsoflowError(f"{path}: {exc}") from None
    digital = out["digital"]
    stable = len(digital) >= 2 and digital[-1]["betti"] == digital[-2]["betti"]
    out["converged"] = stable

    if mesh["nonmanifold_edges"]:
        notes.append(f"{mesh['nonmanifold_edges']} non-manifold edges (more than two faces): not a 2-manifold, genus undefined")
    if mesh["nonmanifold_vertices"]:
        notes.append(
            f"{mesh['nonmanifold_vertices']} non-manifold vertices where separate sheets touch at a point; "
            "genus counted per edge-connected component"
        )
    if nested:
        notes.append(
            f"the mesh's {mesh['components']} components nest with shells facing the same way (a winding "
            "number of 2 or more inside): the solid they bound by the nonzero rule swallows the inner ones, "
            f"genus {out['solid_genus']} (manifold3d)"
        )
    elif overlap:
        notes.append(
            f"the mesh's {mesh['components']} components overlap or touch "
            f"({out['faces_crossing_other_components'] or 0} faces cross other components, "
            f"{mesh['shared_vertices']} vertices shared): the solid they bound is their union, "
            + (f"genus {out['solid_genus']} (manifold3d)" if out["solid_genus"] is not None
               else f"which manifold3d could not build ({solid.get('error')})")
        )
    if digital:
        last = digital[-1]
        if last["betti"][2]:
            notes.append(f"the solid has {last['betti'][2]} cavities (nested shells) at resolution {last['resolution']}")
        if reference is not None and stable:
            for d in digital[:-2]:
                if d["genus"] != reference:
                    notes.append(
                        f"at resolution {d['resolution']} the grid is too coarse: digital genus {d['genus']} "
                        f"(pitch {d['pitch']:.4g}; handles thinner than a voxel close or open)"
                    )
    m3 = out["manifold3d"]
    if "error" in m3:
        notes.append(f"manifold3d refused the mesh ({m3['error']})")
    if g is None and balanced and not mesh["nonmanifold_edges"]:
        notes.append("the mesh is not a closed oriented manifold, so it has no genus")

    agree = False
    if crossing_self:
        head = (f"self-intersecting: {out['self_intersecting_faces']} faces cross faces of their own component, "
                "so the surface bounds no well-defined solid and no finer grid settles its genus")
    elif digital and digital[-1]["betti"][0] == 0:
        # a flat or zero-volume mesh: an empty grid has genus 0 and would
        # "agree" with the surface's genus 0 for nothing
        volume = solid.get("volume")
        head = (f"no solid: the mesh encloses no voxel at resolution {digital[-1]['resolution']}"
                + (f" (its enclosed volume is {volume:.3g})" if volume is not None else "")
                + ", so there is no solid genus to check")
    elif not digital or reference is None:
        head = f"no {ref_name} to compare" if digital else "no mesh genus to compare"
    elif not stable:
        trail = ", ".join(f"{d['resolution']}: {tuple(d['betti'])}" for d in digital[-3:])
        why = ("the digital Betti numbers still change" if len(digital) > 1 else
               "one resolution cannot show that the digital Betti numbers have settled")
        head = (f"not converged at {digital[-1]['resolution']}: {why} ({trail})"
                + (f"; stopped by {stop}" if stop else ""))
    elif digital[-1]["genus"] == reference:
        agree = True
        head = f"agree: {'solid genus' if overlap else 'genus'} {reference}"
    else:
        head = (f"disagree: {ref_name} {reference}, digital genus {digital[-1]['genus']} "
                f"(the same at {digital[-2]['resolution']} and {digital[-1]['resolution']})"
                + (f"; stopped by {stop}" if stop else ""))
    out["agree"] = agree
    out["verdict"] = head + ("; " + "; ".join(notes) if notes else "")
    return out
