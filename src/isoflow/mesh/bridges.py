"""Bridges between digital objects and manifold3d solids.

* :func:`from_manifold`: a manifold3d solid built from cubes, boxes and
  booleans, sampled on an integer-aligned grid;
* :func:`to_manifold`: the union of the voxels as a ``manifold3d.Manifold``,
  built from isoflow's own boundary mesh;
* :func:`cube_union`: the same union as manifold3d builds it from cubes (a
  reference, slow and sliver-prone; docs/voxelisation.md, "manifold3d").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..digital.lattice import MAX_COORDINATE, DigitalObject
from ..digital.surface import boundary_mesh
from ..errors import IsoflowError, given_text
from .voxelize import say_note, voxelize

if TYPE_CHECKING:
    from manifold3d import Manifold


def from_manifold(manifold: Manifold, pitch: float = 1.0,
                  origin: ArrayLike = (0.0, 0.0, 0.0)) -> DigitalObject:
    """Digitise a manifold3d solid on the grid ``origin + pitch * Z^3``.

    Voxel ``v`` (the cube ``[origin + pitch v, origin + pitch (v+1)]``) is in
    iff its centre is inside. A solid made of unit cubes and boxes with
    integer corners is reproduced exactly at pitch 1.

    Parameters
    ----------
    manifold : manifold3d.Manifold
    pitch : float
        The voxel size.
    origin : array_like of 3 floats
        A corner of the grid.

    Returns
    -------
    DigitalObject
        Cropped to the solid, its ``offset`` the lattice index of its first voxel.

    Raises
    ------
    IsoflowError
        For something other than a Manifold, a pitch that is not one
        positive number, an origin that is not three numbers, or a pitch
        and origin that put the manifold beyond the voxel indices a
        :class:`DigitalObject` holds (+-2**40).

    Examples
    --------
    A 2x3x4 box less a unit cube at a corner:

    >>> import manifold3d as m3
    >>> solid = m3.Manifold.cube([2.0, 3.0, 4.0]) - m3.Manifold.cube([1.0, 1.0, 1.0])
    >>> obj = from_manifold(solid)
    >>> obj.voxels, obj.volume.shape
    (23, (2, 3, 4))
    """
    # checked before any arithmetic, so that each bad argument is named:
    # the mesh is taken from the manifold, and the pitch divides
    if not callable(getattr(manifold, "to_mesh", None)):
        raise IsoflowError(f"from_manifold takes a manifold3d.Manifold, got {type(manifold).__name__}"
                           "; a mesh: voxelize_mesh, an array: DigitalObject")
    if isinstance(pitch, (list, tuple, np.ndarray)) and getattr(pitch, "ndim", 1) == 1 and len(pitch) not in (1, 3):
        # the object's check would ask for one number per axis, which this takes only when they are equal
        raise IsoflowError(f"from_manifold: 'pitch' must be one number (cubic voxels), got {given_text(list(pitch))}")
    place = DigitalObject.placement(3, pitch=pitch, origin=origin, function="from_manifold")  # as every object's are
    if np.ndim(place.pitch):
        raise IsoflowError(f"from_manifold: 'pitch' must be one number (cubic voxels), got {np.asarray(pitch).tolist()!r}")
    pitch, corner = float(place.pitch), place.origin
    mesh = manifold.to_mesh()
    verts = np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3]
    tris = np.asarray(mesh.tri_verts, dtype=np.int64)
    if len(tris) == 0:
        return DigitalObject(np.zeros((0, 0, 0), bool), pitch=pitch, origin=corner)
    lo, hi = lattice_box(verts, pitch, corner)
    shape = np.maximum(hi - lo, 1)
    found = voxelize(verts, tris, pitch=pitch, grid=(corner + pitch * lo, shape), details=True)
    # a manifold is closed and bounds what it draws (no double-sided or
    # zero-thickness faces), so a solid thin beside its shell is the solid,
    # exact for a union of voxels: the note speaks only for an empty one
    vol = found.volume
    assert vol is not None  # (voxelised in memory: the volume is held)
    if not vol.any():
        say_note(found.note)
    return DigitalObject(vol, offset=tuple(int(v) for v in lo), pitch=pitch, origin=corner).cropped()


def lattice_box(verts: np.ndarray, pitch: float, corner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The voxel indices of the lowest and one past the highest corner of
    the vertices' box; refused beyond the indices a DigitalObject holds,
    where a fine pitch or a far origin made int64 wrap round (and the
    voxeliser divide by a pitch squared to zero)."""
    lo, hi = np.floor((verts.min(axis=0) - corner) / pitch), np.ceil((verts.max(axis=0) - corner) / pitch)
    far = float(np.max(np.abs(np.concatenate([lo, hi]))))
    if not far <= MAX_COORDINATE:
        raise IsoflowError(f"from_manifold: pitch={given_text(pitch)} and origin={corner.tolist()} put the manifold's voxels "
                           f"at index {far:.3g}, beyond the +-{MAX_COORDINATE} a DigitalObject holds; "
                           "give a coarser pitch, or an origin nearer the manifold")
    return lo.astype(np.int64), hi.astype(np.int64)


def cube_union(voxels):
    """The union of unit cubes at integer voxel indices, as manifold3d builds
    it with ``batch_boolean`` (slow and sliver-prone for many cubes, see
    docs/voxelisation.md; :func:`to_manifold` is the fast, exact route)."""
    import manifold3d as m3

    cubes = [m3.Manifold.cube([1.0, 1.0, 1.0]).translate([float(c) for c in v]) for v in np.asarray(voxels)]
    return m3.Manifold.batch_boolean(cubes, m3.OpType.Add)


# --------------------------------------------------------------------------
# objects -> meshes
# --------------------------------------------------------------------------


def to_manifold(obj: DigitalObject | ArrayLike, connectivity: int | np.integer | None = 6) -> Manifold:
    """The union of the object's voxels as a ``manifold3d.Manifold`` in world
    coordinates.

    It is built from isoflow's boundary mesh rather than by a boolean union
    of cubes: manifold3d's own union of cubes that touch only along an edge or
    at a corner follows no digital connectivity (a 3x3x3 checkerboard of 14
    cubes comes out as 8 components) and leaves zero-volume slivers. From the
    boundary mesh, manifold3d sees exactly the surface of the connectivity
    asked, and ``volume()`` is the voxel volume. Its ``decompose()`` gives
    the closed surfaces of that mesh (the ``surfaces`` of
    :func:`isoflow.analyze`), not the object's components: edge contacts
    are joined under 26 and split under 6, but vertex contacts are split in
    the mesh under either (docs/mathematics.md, "The boundary mesh"), so two
    voxels that meet at a corner are one component at 26 and two pieces; a
    cavity's surface is a piece of its own too.

    Parameters
    ----------
    obj : DigitalObject or array_like of bool, 3D
    connectivity : {6, 26} or None
        The object's (None: the paper's 6, as for :func:`isoflow.analyze`).

    Returns
    -------
    manifold3d.Manifold
        Empty for an empty object.

    Raises
    ------
    IsoflowError
        When the object is not 3D, or manifold3d refuses the mesh.

    Examples
    --------
    Two voxels sharing an edge: two solids under 6-connectivity, one under 26.

    >>> import numpy as np
    >>> v = np.zeros((2, 2, 1), bool)
    >>> v[0, 0, 0] = v[1, 1, 0] = True
    >>> len(to_manifold(v, 6).decompose()), len(to_manifold(v, 26).decompose()), to_manifold(v).volume()
    (2, 1, 2.0)

    Two voxels sharing a corner: one 26-component, two pieces.

    >>> import isoflow
    >>> w = np.zeros((2, 2, 2), bool)
    >>> w[0, 0, 0] = w[1, 1, 1] = True
    >>> len(to_manifold(w, 26).decompose()), isoflow.betti_numbers(w, 26)[0]
    (2, 1)
    """
    import manifold3d as m3

    # the dimension before the values: "threshold it" is no remedy for a 2D label image
    if getattr(obj, "ndim", 3) == 3:
        obj = DigitalObject.of(obj, "to_manifold", remedy_dims=(3,))  # a label table is no solid
    if not isinstance(obj, DigitalObject) or obj.ndim != 3:
        raise IsoflowError(f"to_manifold needs a 3D object, got {getattr(obj, 'ndim', 0)}D")
    mesh = boundary_mesh(obj.volume, connectivity)
    if len(mesh.faces) == 0:
        return m3.Manifold()
    verts = obj.world(mesh.vertices).astype(np.float32)
    result = m3.Manifold(m3.Mesh(vert_properties=verts, tri_verts=mesh.triangles().astype(np.uint32)))
    status = result.status()
    if status != m3.Error.NoError:
        raise IsoflowError(f"manifold3d refused the boundary mesh: {status.name}")
    return result
