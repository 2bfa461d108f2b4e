"""The closed surfaces of an object's boundary and their genus, without
building the boundary mesh.

:func:`isoflow.digital.surface.boundary_mesh` splits the boundary into
closed surfaces by its local rules (DESIGN section 3): edge contacts are
paired inside the object voxel under 6-connectivity and across the edge
under 26, and every vertex contact is split. Those rules make the mesh the
boundary of a solid ``M`` whose pieces are the object's components under an
adjacency of its own, and the complement's pieces the background's:

========  =================  =====================
object    ``M``'s object     ``M``'s background
========  =================  =====================
6         6 (faces)          18 (faces and edges)
26        18                 6
========  =================  =====================

(the vertex contacts that the split mesh separates although the
connectivity joins them are the *pinches*; they are why 18 appears). Every
boundary face separates an object voxel from a background voxel, so it
carries the pair of their labels under those adjacencies, and the faces of
one surface all carry the same pair (two faces meeting at a mesh edge share
an object voxel, or a background cell, or touch along the edge where the
adjacency joins them). Conversely one pair is one surface: in the 3-sphere
(unicoherent), a component ``D`` of the complement of a connected solid
``A`` has a connected boundary, so the surface between ``A`` and the part of
``D`` next to it is a single one. The closed surfaces are therefore the
label pairs that occur, and each one's

    chi(S) = V(S) - E(S) + F(S) = V(S) - F(S)      (E = 2F, every edge in two faces)

follows from counting, per pair, its mesh vertices (the sheets through a
lattice vertex, from :func:`~isoflow.digital.surface.sheet_lut`) and its
faces (a quarter at each of their four corners). The midpoints that the mesh
puts on doubled edges add one vertex and one edge each, which cancel.
``genus = 1 - chi / 2`` since every surface is a closed orientable manifold.

Large host volumes go through the compiled pass of :mod:`isoflow.scale.sweep`
on the runs of the volume (about 1.5 bytes per voxel on a porous field, no
label volume); small ones through scipy labels and the configuration array.
Both equal ``boundary_mesh(volume, connectivity).components()`` exactly
(the tests check it on thousands of random volumes).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..scale.compiled import have_numba, use_compiled
from .configurations import configurations
from .surface import doubled_spoke_lut, pinch_lut, sheet_lut, slot_octants
from .topology import check_connectivity

#: connectivity -> (object adjacency, background adjacency) of the mesh's solid
MESH_ADJACENCY = {6: (6, 18), 26: (18, 6)}


@lru_cache(maxsize=None)
def sweep_tables(connectivity: int = 6) -> tuple[np.ndarray, ...]:
    """Per-configuration tables of the sheets, for the passes here.

    Returns ``(nsheet, sheet_obj, sheet_bg, sheet_quarters, spokes, pinch)``:
    the number of sheets (256,); per sheet (256, 4) the octant of the object
    voxel and of the background voxel that one of its faces separates, and
    its number of faces; ``spokes`` (256,) with bit ``2 axis + side`` set
    where :func:`~isoflow.digital.surface.doubled_spoke_lut` is; ``pinch``
    (256, 2), the two opposite octants of a pinch (object ones under 26,
    background ones under 6), -1 elsewhere.
    """
    check_connectivity(3, connectivity)
    sheets = sheet_lut(connectivity)
    nsheet = (sheets.max(axis=1) + 1).astype(np.int8)
    sheet_obj = np.full((256, 4), -1, np.int8)
    sheet_bg = np.full((256, 4), -1, np.int8)
    quarters = np.zeros((256, 4), np.int8)
    for c in range(256):
        for slot in range(12):
            s = sheets[c, slot]
            if s < 0:
                continue
            quarters[c, s] += 1
            lo, hi = slot_octants(slot)
            obj, bg = (lo, hi) if (c >> lo) & 1 else (hi, lo)
            sheet_obj[c, s], sheet_bg[c, s] = obj, bg
    doubled = doubled_spoke_lut(connectivity)
    spokes = np.zeros(256, np.uint8)
    for axis in range(3):
        for side in (0, 1):
            spokes |= doubled[:, axis, side].astype(np.uint8) << (2 * axis + side)
    pinch = np.full((256, 2), -1, np.int8)
    for c in np.flatnonzero(pinch_lut(connectivity)):
        pair = c if connectivity == 26 else 255 ^ c
        octs = [o for o in range(8) if (pair >> o) & 1]
        pinch[c] = octs
    # The sweep counts a run of equal "layer" configurations (the same four
    # voxels on both sides of the vertex) in one step: it relies on their
    # sheets having four faces each and no doubled spoke.
    layers = [n | (n << 4) for n in range(1, 15)]
    assert (spokes[layers] == 0).all()
    assert all((quarters[c, : nsheet[c]] == 4).all() for c in layers)
    return nsheet, sheet_obj, sheet_bg, quarters, spokes, pinch


def _structure(adjacency: int) -> np.ndarray:
    from scipy.ndimage import generate_binary_structure

    return generate_binary_structure(3, {6: 1, 18: 2, 26: 3}[adjacency])


def surfaces_from_counts(vertices: np.ndarray, quarters: np.ndarray) -> list[dict]:
    """The report's surfaces from each pair's mesh vertices and quarter
    faces, largest first."""
    vertices = np.asarray(vertices, np.int64)
    quarters = np.asarray(quarters, np.int64)
    assert (quarters % 4 == 0).all(), "every face has four corners"
    faces = quarters // 4
    chi = vertices - faces
    order = np.lexsort((chi, -faces))
    return [
        {"euler_characteristic": int(chi[c]), "genus": int(1 - chi[c] // 2), "faces": int(faces[c])}
        for c in order
    ]


def closed_surfaces(volume, connectivity: int = 6) -> dict:
    """The closed surfaces of the boundary of a 3D host volume.

    Returns ``surfaces`` (each with ``euler_characteristic``, ``genus`` and
    ``faces``, largest first: the same multiset as
    ``boundary_mesh(volume, connectivity).components()``), ``pinched_vertices``
    and ``doubled_edges`` (the mesh's ``pinched`` and ``midpoints // 2``).
    Large volumes also give ``hist`` and ``betti_counts`` (b0 and the
    enclosed background components), which come with the same pass.
    """
    vol = np.asarray(volume, dtype=bool)
    if vol.ndim != 3:
        raise ValueError("closed_surfaces needs a 3D volume")
    check_connectivity(3, connectivity)
    if use_compiled(vol):
        return _compiled(vol, connectivity)
    return _small(vol, connectivity)


def _small(vol: np.ndarray, conn: int) -> dict:
    """numpy and scipy: labels of the volume and of its background padded by
    one layer (the outside is one background component), and the
    configuration of every vertex."""
    from scipy.ndimage import label

    obj_adj, bg_adj = MESH_ADJACENCY[conn]
    obj_labels = label(vol, _structure(obj_adj))[0]
    bg_padded = label(np.pad(~vol, 1, constant_values=True), _structure(bg_adj))[0]
    outside = int(bg_padded[0, 0, 0])
    whole = tuple(slice(None) for _ in range(3))
    found = box_sheets(vol, obj_labels, bg_padded[1:-1, 1:-1, 1:-1], whole, conn, outside)
    spokes = sweep_tables(conn)[4]
    cfg = configurations(vol)
    doubled = 0
    for axis in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        doubled += int(np.count_nonzero((spokes[cfg[tuple(lo)]] >> (2 * axis + 1)) & (spokes[cfg[tuple(hi)]] >> (2 * axis)) & 1))
    return {
        "surfaces": surfaces_from_counts(found["vertices"], found["quarters"]),
        "pinched_vertices": int(np.count_nonzero(pinch_lut(conn)[cfg])),
        "doubled_edges": doubled,
    }


def _compiled_box(vox) -> bool:
    """The compiled box pass is worth loading numba for from boxes of 2^12
    voxels (the face tiles of 256^3 blocks have 2^17)."""
    return vox.ndim == 3 and 1 << 12 <= vox.size < 1 << 31 and have_numba()


def _fits_32_bits(labels: np.ndarray, outside) -> bool:
    """Labels that the compiled pass can pack two by two into 64 bits."""
    return labels.dtype in (np.uint16, np.uint32, np.int32) and 0 <= int(outside) < 1 << 32


def _compiled_box_sheets(vox, obj_labels, bg_labels, keep, conn, outside) -> dict:
    """:func:`box_sheets` by the compiled pass. Labels that do not fit in
    32 bits (node keys, in the face tiles out of core) are numbered first
    and the numbers mapped back."""
    from ..scale.sweep import box_sweep

    values = {}
    if not _fits_32_bits(obj_labels, 0):
        values["obj"], obj_labels = np.unique(obj_labels, return_inverse=True)
        obj_labels = obj_labels.reshape(vox.shape).astype(np.uint32)
    if not _fits_32_bits(bg_labels, outside):
        values["bg"], bg_labels = np.unique(np.append(bg_labels.ravel(), outside), return_inverse=True)
        outside = int(bg_labels[-1])
        bg_labels = bg_labels[:-1].reshape(vox.shape).astype(np.uint32)
    bounds = [k.indices(n + 1)[:2] for k, n in zip(keep, vox.shape)]
    found = box_sweep(vox, obj_labels, bg_labels, [a for a, _ in bounds], [b for _, b in bounds],
                      int(outside), sweep_tables(conn))
    if "obj" in values:
        found["obj"] = values["obj"][found["obj"]]
    if "bg" in values:
        found["bg"] = values["bg"][found["bg"]]
    if values:  # pinch pairs: object labels under 26, background ones under 6
        kind = "obj" if conn == 26 else "bg"
        if kind in values:
            found["pairs"] = values[kind][found["pairs"]]
    return found


def box_sheets(vox: np.ndarray, obj_labels: np.ndarray, bg_labels: np.ndarray, keep, conn: int, outside,
               compiled: bool = False) -> dict:
    """Sheets of some vertices of a box of voxels, summed per label pair.

    ``vox``: the box (bool); ``obj_labels``/``bg_labels``: integer labels of
    its object / background voxels (any numbering: local labels, node keys);
    ``keep``: slices of the box's vertex array (shape ``vox.shape + 1``)
    choosing the vertices to count; octants outside the box are background
    labelled ``outside`` (only vertices whose octants outside the box really
    are outside the volume may be kept). Returns the distinct pairs
    (``obj``, ``bg`` label arrays), their mesh ``vertices`` and ``quarters``
    of faces, and the pinch ``pairs`` (labels of the two octants to join for
    the connectivity's components: object labels under 26, background under
    6). Used whole by the small path (numpy: no numba below
    :data:`~isoflow.scale.compiled.MIN_VOXELS`) and block by block out of
    core, where ``compiled`` lets boxes from 2^12 voxels on take the
    compiled pass.
    """
    if compiled and _compiled_box(vox):
        return _compiled_box_sheets(vox, obj_labels, bg_labels, keep, conn, outside)
    nsheet, sheet_obj, sheet_bg, quarters, _, pinch = sweep_tables(conn)
    cfg = configurations(vox)[keep]
    origin = np.array([k.indices(n + 1)[0] for k, n in zip(keep, vox.shape)])
    obj_padded = np.pad(obj_labels, 1)
    bg_padded = np.pad(bg_labels, 1, constant_values=outside)
    # vertex w's octant d is the padded voxel w + d
    strides = np.array(obj_padded.strides) // obj_padded.itemsize
    bg_strides = np.array(bg_padded.strides) // bg_padded.itemsize
    octant = np.array([[o & 1, (o >> 1) & 1, o >> 2] for o in range(8)])
    flat = cfg.ravel()
    on = np.flatnonzero(nsheet[flat])
    corner = np.stack(np.unravel_index(on, cfg.shape), axis=1) + origin
    obj_flat, bg_flat = obj_padded.ravel(), bg_padded.ravel()
    objs, bgs, quarter = [], [], []
    for s in range(int(nsheet.max(initial=0))):
        has = nsheet[flat[on]] > s
        c, at = flat[on[has]], corner[has]
        objs.append(obj_flat[(at + octant[sheet_obj[c, s]]) @ strides])
        bgs.append(bg_flat[(at + octant[sheet_bg[c, s]]) @ bg_strides])
        quarter.append(quarters[c, s].astype(np.int64))
    obj, bg = np.concatenate(objs).astype(np.int64), np.concatenate(bgs).astype(np.int64)
    uo, io = np.unique(obj, return_inverse=True)
    ub, ib = np.unique(bg, return_inverse=True)
    pair, inverse = np.unique(io.astype(np.int64) * len(ub) + ib, return_inverse=True)
    pinched = on[pinch[flat[on], 0] >= 0]
    ends = []
    for e in (0, 1):
        oct_ = pinch[flat[pinched], e]
        at = (np.stack(np.unravel_index(pinched, cfg.shape), axis=1) + origin + octant[oct_])
        side_obj = conn == 26  # the pinch joins two object octants under 26
        ends.append(obj_flat[at @ strides] if side_obj else bg_flat[at @ bg_strides])
    ends = np.stack(ends, axis=1).astype(np.int64).reshape(-1, 2)
    return {
        "obj": uo[pair // len(ub)] if len(ub) else uo[:0],
        "bg": ub[pair % len(ub)] if len(ub) else ub[:0],
        "vertices": np.bincount(inverse, minlength=len(pair)).astype(np.int64),
        "quarters": np.bincount(inverse, weights=np.concatenate(quarter), minlength=len(pair)).astype(np.int64),
        "pairs": ends[ends[:, 0] != ends[:, 1]],  # only those that join two pieces
    }


def _compiled(vol: np.ndarray, conn: int) -> dict:
    """The run-based passes: runs of the object and their gaps, labelled by
    union-find under the mesh's adjacencies, then the vertex sweep; the
    pinches found by the sweep join the labels into the connectivity's own
    components for the Betti numbers."""
    from ..scale import kernels, sweep

    v = kernels.volume_view(vol)
    runs = kernels.object_runs(v)
    gaps = kernels.gap_runs(*runs, v.shape[2])
    obj_adj, bg_adj = MESH_ADJACENCY[conn]
    (pobj, nobj), (pbg, nbg) = kernels.join_runs(
        [(v.shape, *runs), (v.shape, *gaps)], [obj_adj, bg_adj], [False, True]
    )
    goff = gaps[0]
    del gaps  # the sweep needs the gaps' row offsets only
    found = sweep.sweep(v, runs, goff, pobj, pbg, nobj + nbg - 1, sweep_tables(conn))
    # the components of M and of its complement form a tree whose edges
    # are the surfaces (each closed surface splits the 3-sphere in two)
    assert len(found["keys"]) == nobj + nbg - 1
    del runs, goff
    if conn == 26:  # the pinches join object components
        b0 = kernels.join_pairs(pobj, found["pairs"])
        enclosed = nbg - 1
    else:  # they join background components
        b0 = nobj
        enclosed = kernels.join_pairs(pbg, found["pairs"]) - 1
    hist = found["hist"]
    return {
        "surfaces": surfaces_from_counts(found["vertices"], found["quarters"]),
        "pinched_vertices": int(hist[pinch_lut(conn)].sum()),
        "doubled_edges": found["doubled"],
        "hist": hist,
        "betti_counts": (b0, enclosed),
    }
