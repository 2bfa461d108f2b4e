"""The check the project promises: every surface file, read back by trimesh.

After writing, ``surface`` and ``flow --out`` load each file with trimesh,
as a user would, and compare what trimesh reads (watertight and
consistently wound, Euler number, genus, volume) with what isoflow counted
on the mesh in memory. A file that reads differently is an error (exit 1),
not a note: it would mean the file does not hold the surface isoflow
describes.

Genus from trimesh's figures: every closed surface component ``c`` has
genus ``(2 - chi_c) / 2``, so the total is ``bodies - euler / 2`` with
``bodies`` trimesh's vertex-connected groups (``body_count``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: relative tolerance on the volume: coordinates are stored as float32
VOLUME_RTOL = 1e-4


def isoflow_figures(mesh, obj) -> dict:
    """What the file must read as: isoflow's own counts of the boundary mesh."""
    comps = mesh.components()
    return {
        "watertight": True,
        "euler_number": int(mesh.euler_characteristic),
        "genus": int(sum(c["genus"] for c in comps)),
        "volume": float(obj.voxels) * float(obj.pitch) ** 3,
    }


def trimesh_figures(path, weld: bool = False) -> dict:
    """Watertightness (every edge in two faces, consistently wound), Euler
    number, genus and volume of a mesh file as trimesh reads it: with
    ``process=False`` (no vertex merge, the file's own vertices), or with
    trimesh's default merge when ``weld`` (STL stores no shared vertices).

    A PLY is parsed by trimesh's PLY reader and the mesh built without its
    colours, which cost a third of the read (measured on flow steps) and do
    not touch the topology. The volume is the signed volume of the
    triangles trimesh read (``trimesh.volume`` also integrates the inertia:
    another third).
    """
    import trimesh

    path = Path(path)
    if path.suffix.lower() == ".ply" and not weld:
        from trimesh.exchange.ply import load_ply

        with open(path, "rb") as fh:
            kw = load_ply(fh)
        tm = trimesh.Trimesh(kw["vertices"], kw["faces"], process=False)
    else:
        tm = trimesh.load(path, force="mesh", process=weld)
    closed = bool(len(tm.faces) and tm.is_watertight and tm.is_winding_consistent)
    euler = int(tm.euler_number)
    bodies = int(tm.body_count) - int(np.count_nonzero(~tm.referenced_vertices))
    genus = bodies - euler // 2 if closed and euler % 2 == 0 else None
    return {"watertight": closed, "euler_number": euler, "genus": genus, "volume": signed_volume(tm.vertices, tm.faces)}


def signed_volume(vertices, triangles) -> float:
    """The volume a closed, outward-oriented triangle mesh encloses (the
    divergence theorem: a sixth of the sum of ``v0 . (v1 x v2)``)."""
    v = np.asarray(vertices, np.float64)[np.asarray(triangles)]
    if not len(v):
        return 0.0
    return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6)


def check_surface_file(path, mesh, obj, *, topology: bool = True) -> dict:
    """Read a written surface file back with trimesh and compare it with
    isoflow's counts. Returns ``{"isoflow": ..., "trimesh": ..., "agree":
    bool, "problem": str or None}``.

    STL is read with trimesh's usual vertex merge. Where the object has edge
    or vertex contacts the merge joins copies the mesh keeps apart, so
    ``topology=False`` then compares the volume only (the caller says why).
    """
    path = Path(path)
    ours = isoflow_figures(mesh, obj)
    theirs = trimesh_figures(path, weld=path.suffix.lower() == ".stl")
    keys = ("watertight", "euler_number", "genus") if topology else ()
    problems = [f"{k} {theirs[k]} (isoflow: {ours[k]})" for k in keys if theirs[k] != ours[k]]
    # the signed volume needs no manifold: a welded STL still encloses it
    if not np.isclose(theirs["volume"], ours["volume"], rtol=VOLUME_RTOL, atol=0):
        problems.append(f"volume {theirs['volume']:.9g} (isoflow: {ours['volume']:.9g})")
    problem = f"{path}: trimesh reads " + ", ".join(problems) if problems else None
    return {"isoflow": ours, "trimesh": theirs, "agree": not problems, "problem": problem}
