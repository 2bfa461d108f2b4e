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

from ..digital.topology import betti_numbers
from ..errors import IsoflowError
from .load import load_mesh, mesh_defects
from .voxelize import voxelize

#: resolutions ``isoflow genus`` uses when none is asked
DEFAULT_RESOLUTIONS = (64, 128)


# --------------------------------------------------------------------------
# the mesh's own topology
# --------------------------------------------------------------------------


def mesh_topology(vertices, faces) -> dict:
    """Components, Euler number and genus of a triangle mesh, with its defects.

    Components are edge-connected face sets. A component's genus is
    ``(2 - chi_c) / 2`` when it is closed (no boundary edge), every edge has
    two faces, and every vertex has one fan of faces in it; otherwise None.
    ``nonmanifold_vertices`` counts vertices with more than one fan (two
    closed surfaces touching at a point, like ``hourglass_ico.obj``).
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
    return {
        "watertight": bool(defects["watertight"]),
        "components": int(ncomp),
        "euler_number": euler,
        "genus": total,
        "genus_per_component": genus_c,
        "boundary_edges": int(defects["boundary_edges"]),
        "nonmanifold_edges": int(defects["nonmanifold_edges"]),
        "inconsistent_edges": int(defects["inconsistent_edges"]),
        "nonmanifold_vertices": int(np.count_nonzero(fans_per_vertex > 1)),
        "vertices": int(len(used)),
        "faces": int(nf),
    }


def manifold3d_report(vertices, faces) -> dict:
    import manifold3d as m3

    try:
        mf = m3.Manifold(
            m3.Mesh(vert_properties=np.asarray(vertices, np.float32), tri_verts=np.asarray(faces, np.uint32))
        )
    except Exception as exc:  # the binding raises for malformed input
        return {"error": f"{type(exc).__name__}: {exc}"}
    status = mf.status()
    if status != m3.Error.NoError:
        return {"error": status.name}
    parts = mf.decompose()
    return {
        "genus": int(sum(p.genus() for p in parts)),
        "genus_whole_mesh": int(mf.genus()),
        "components": len(parts),
        "volume": float(mf.volume()),
    }


def pymeshlab_report(vertices, faces) -> dict:
    try:
        import pymeshlab

        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(np.asarray(vertices, np.float64), np.asarray(faces, np.int32)))
        t = ms.get_topological_measures()
    except Exception as exc:
        return {"error": f"{type(exc).__name__}: {exc}"}
    out = {k: (int(t[k]) if not isinstance(t[k], bool) else bool(t[k])) for k in (
        "genus", "connected_components_number", "boundary_edges", "non_two_manifold_edges",
        "non_two_manifold_vertices", "is_mesh_two_manifold") if k in t}
    if out.get("genus", 0) < 0:
        out["error"] = "pymeshlab reports genus -1: the mesh is not a two-manifold"
    return out


# --------------------------------------------------------------------------
# genus verification
# --------------------------------------------------------------------------


def verify_genus(path, resolutions=DEFAULT_RESOLUTIONS, connectivity: int = 6, progress=None,
                 strict: bool = False) -> dict:
    """The mesh's topology, manifold3d's and pymeshlab's, and the digital
    topology of its voxelised solid at each resolution, with a verdict.

    ``agree`` is true when the mesh is a closed surface and the digital genus
    (b1 of the solid) at the finest resolution equals the mesh's genus.
    """
    path = Path(path)
    resolutions = list(resolutions)
    if not resolutions:
        raise IsoflowError("verify_genus needs at least one resolution")
    stats: dict = {}
    v, f = load_mesh(path, stats=stats)
    mesh = mesh_topology(v, f)
    out = {
        "input": str(path),
        "mesh": mesh,
        "manifold3d": manifold3d_report(v, f),
        "pymeshlab": pymeshlab_report(v, f),
        "digital": [],
    }
    notes = []
    welded = stats["exact_vertices"] - stats["welded_vertices"]
    if welded:
        notes.append(
            f"{welded} vertices that differ only by rounding noise were welded before counting "
            "(tools that merge exact duplicates only see a different, open or higher-genus mesh)"
        )
    balanced = mesh["boundary_edges"] == 0 and mesh["inconsistent_edges"] == 0
    if not balanced:
        notes.append(
            f"the mesh is open ({mesh['boundary_edges']} boundary edges"
            + (f", {mesh['inconsistent_edges']} inconsistently oriented" if mesh["inconsistent_edges"] else "")
            + "): it bounds no solid, so it has no genus as a closed surface; its solid is read by the "
            "generalised winding number (|w| > 1/2)"
        )
    for res in sorted(resolutions):
        try:
            vol, origin, pitch = voxelize(v, f, resolution=res, strict=strict, progress=progress)
        except IsoflowError as exc:
            raise IsoflowError(f"{path}: {exc}") from None
        betti = betti_numbers(vol, connectivity)
        out["digital"].append(
            {"resolution": int(res), "pitch": pitch, "shape": list(vol.shape), "voxels": int(vol.sum()),
             "connectivity": connectivity, "betti": betti, "genus": betti[1]}
        )
    g = mesh["genus"]
    digital = out["digital"]
    agree = bool(g is not None and digital and digital[-1]["genus"] == g)
    out["agree"] = agree
    if mesh["nonmanifold_edges"]:
        notes.append(f"{mesh['nonmanifold_edges']} non-manifold edges (more than two faces): not a 2-manifold, genus undefined")
    if mesh["nonmanifold_vertices"]:
        notes.append(
            f"{mesh['nonmanifold_vertices']} non-manifold vertices where separate sheets touch at a point; "
            "genus counted per edge-connected component"
        )
    if digital:
        last = digital[-1]
        if mesh["components"] != last["betti"][0] and g is not None:
            notes.append(
                f"the mesh's {mesh['components']} components bound {last['betti'][0]} solid piece(s): "
                "components overlap or touch" if mesh["components"] > last["betti"][0]
                else f"the solid splits into {last['betti'][0]} pieces at resolution {last['resolution']}"
            )
        if last["betti"][2]:
            notes.append(f"the solid has {last['betti'][2]} cavities (nested shells) at resolution {last['resolution']}")
        if g is not None:
            for d in digital[:-1]:
                if d["genus"] != g:
                    notes.append(
                        f"at resolution {d['resolution']} the grid is too coarse: digital genus {d['genus']} "
                        f"(pitch {d['pitch']:.4g}; handles thinner than a voxel close or open)"
                    )
            if last["genus"] != g:
                notes.append(
                    f"at the finest resolution asked ({last['resolution']}) the digital genus is {last['genus']}, "
                    f"the mesh's {g}: try a finer --resolution"
                )
    m3 = out["manifold3d"]
    if "error" in m3:
        notes.append(f"manifold3d refused the mesh ({m3['error']})")
    if g is None and balanced and not mesh["nonmanifold_edges"]:
        notes.append("the mesh is not a closed oriented manifold, so it has no genus")
    if agree:
        head = f"agree: genus {g}"
    elif g is None:
        head = "no mesh genus to compare"
    else:
        head = f"disagree: mesh genus {g}, digital genus {digital[-1]['genus'] if digital else None}"
    out["verdict"] = head + ("; " + "; ".join(notes) if notes else "")
    return out
