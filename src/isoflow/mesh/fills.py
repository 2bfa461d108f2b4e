"""Which voxels a mesh fills, and what a voxelisation tells its caller.

Three fills (``fill=`` of :func:`~isoflow.mesh.voxelize.voxelize`,
``--fill`` of every command that voxelises):

``winding``
    The solid the mesh bounds: a voxel is in iff the generalised winding
    number of its centre exceeds 1/2 in absolute value (the nonzero rule on
    closed meshes).  A surface that bounds nothing (a zero-thickness panel,
    a sheet) gives no voxel.
``shell``
    The surface itself: every voxel whose closed cube the surface meets
    (:mod:`isoflow.mesh.shell`).
``flood``
    The shell and everything it encloses: the shell plus every voxel that
    no 6-path of voxels outside the shell joins to the outside of the grid
    (as binvox's and trimesh's fills; scipy's ``binary_fill_holes``).

The details of a voxelisation are a :class:`Voxelization`; where the
winding rule leaves a mesh with area a tiny or empty solid,
:func:`thin_solid` says so and why, and :data:`NO_AREA` where the mesh
has no area at all.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..errors import IsoflowError, check_switch, choice_of, counted, given_text
from ..results import Result

#: the rule that decides which voxels a mesh fills
Fill = Literal["winding", "shell", "flood"]
FILLS: tuple[str, ...] = ("winding", "shell", "flood")

#: The winding rule's solid counts as thin when it has fewer voxels than
#: this share of the surface's shell (measured on 30 public and generated
#: meshes at 64, 128 and 256 across, benchmarks/bench_fills.py
#: --thresholds: the least share of a model that bounds a solid is 0.77,
#: platonic_shelf.obj at 64; a zero-thickness panel gives 0).
THIN_SHARE = 0.5
#: ... or when at least this share of the area bounds no voxel on either
#: side (the same sweep: at most 0.07 on the public meshes, plane_holes.obj
#: at 64; a panel gives 1, the double-sided chair 0.46 at 128).
UNBOUNDED_SHARE = 0.25
#: faces sampled to estimate the share of the area that bounds nothing
SAMPLED_FACES = 8192
#: the shell is counted only where the solid has fewer voxels than this
#: many times the area in voxel faces (a shell has 1.5 to 3 of them).
THIN_TRIGGER = 2.0
#: A mesh whose winding number is 0 or 1 (or 0 or -1) at every voxel
#: centre is judged against its own volume instead of its shell: its solid
#: counts as thin when its voxels lie outside this band of its volume in
#: voxels.  A small solid has a shell about its own size however it lies on
#: the grid, but its voxels stay near its volume: of the boxes, cubes,
#: spheres and cylinders 1 to 7 voxels across at random sub-voxel offsets
#: that the shell's share calls thin, 98 % have 0.5 to 2 times it (0.17 to
#: 1.68 in all), and the fills would add their shell to them
#: (benchmarks/bench_fills.py --thresholds, its small solids; its closed
#: models give 0.94 to 1.56).  A plate thinner than half a voxel has no
#: voxel or a layer over twice its volume, whichever way it lies, so it
#: keeps the note (the sweep's 10 x 10 x 0.05 box at 64 across, a third of
#: a voxel thick, has 3.1 times its volume).
VOLUME_BAND = (0.5, 2.0)


@dataclass(frozen=True, eq=False, repr=False)
class Voxelization(Result):
    """What a voxelisation gave, and what it found in the mesh.

    Reads as a mapping too (``v["note"]``, ``dict(v)``), as the results of
    isoflow's other functions do.

    Attributes
    ----------
    volume : bool ndarray (nx, ny, nz) or None
        The voxels (None where they were written to a store).
    origin : float64 ndarray (3,)
        Lower corner of voxel (0, 0, 0).
    pitch : float
    fill : {"winding", "shell", "flood"}
    voxels : int
        Voxels in.
    defects : dict
        The edge census of the faces as given
        (:func:`~isoflow.mesh.load.mesh_defects`).
    flipped_faces : int
        Faces turned over to orient the mesh consistently.
    double_sided_faces : int
        Pairs of coincident faces of opposite orientation, each read as one.
    chain_edges : int
        Boundary edges the winding number's cap closes (0: the exact
        scanline alone decided).
    overlap_voxels : int
        Voxels inside two or more layers (overlapping shells).
    shell_voxels : int or None
        Voxels of the surface's shell, where they were counted (to tell a
        thin or empty solid).
    note : str or None
        One line for the user on what is unusual, or None.
    """

    volume: np.ndarray | None = field(repr=False)
    origin: np.ndarray
    pitch: float
    fill: Fill
    voxels: int
    defects: dict
    flipped_faces: int = 0
    double_sided_faces: int = 0
    chain_edges: int = 0
    overlap_voxels: int = 0
    shell_voxels: int | None = None
    note: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """Every field but the volume, as JSON takes it (origin a list)."""
        out = super().to_dict()
        del out["volume"]
        return out

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> Voxelization:
        """The voxelisation of :meth:`to_dict`'s JSON: the volume is not in
        it, so there is none, as where the voxels went to a store
        (``volume`` given is taken), and the origin is an array again. It
        was refused, the volume being a field without a default.

        Examples
        --------
        >>> import json, trimesh
        >>> from isoflow import voxelize_mesh
        >>> v = voxelize_mesh(trimesh.creation.box(), resolution=4, details=True)[1]
        >>> back = Voxelization.from_dict(json.loads(json.dumps(v.to_dict())))
        >>> back.to_dict() == v.to_dict(), back.volume, back.origin.tolist()
        (True, None, [-0.5, -0.5, -0.5])
        """
        given = {"volume": None, **values}
        given["origin"] = np.asarray(given["origin"], dtype=np.float64)
        return super().from_dict(given)


def check_fill(fill: object, caller: str = "voxelize") -> Fill:
    """``fill`` if it names a fill, else an IsoflowError naming the three.

    Parameters
    ----------
    fill : object
        What was given as ``fill``.
    caller : str, optional
        The function the message names (``verify_genus`` checks the same
        words).

    Returns
    -------
    Fill
        ``fill``, one of :data:`FILLS`.

    Examples
    --------
    >>> check_fill("shell")
    'shell'
    """
    chosen = choice_of(fill, FILLS)  # the plain string, which the result keeps
    if chosen is None:
        raise IsoflowError(f"{caller}: fill must be one of {', '.join(FILLS)}, got {given_text(fill)}")
    return chosen  # type: ignore[return-value]


def check_strict(strict: object, where: str = "voxelize") -> bool:
    """``strict`` as a bool if it is one, else an IsoflowError naming it:
    ``strict="no"`` turned strict mode on (any non-empty string is true).

    Parameters
    ----------
    strict : object
        What was given as ``strict``: True or False (NumPy's bools too).
    where : str
        The function, for the message.

    Returns
    -------
    bool
        ``strict``.

    Examples
    --------
    >>> check_strict(False)
    False
    >>> check_strict("no")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: voxelize: strict must be True or False, got 'no'
    """
    return check_switch(strict, "strict", where)


def sampled_points(T: np.ndarray, origin, pitch: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The points :func:`unbounded_area` looks up, of the triangles' corners
    ``T`` (M, 3, 3) in the grid's frame: ``(idx, area)`` with ``idx`` (3, K,
    3) the voxels (they may lie outside the grid) of each sampled face's
    centroid and of the points three quarters of a voxel either side of it
    along the normal, and ``area`` (K,) the faces' areas; None where no
    sampled face has area. Every k-th face, at most about
    :data:`SAMPLED_FACES` of them."""
    T = T[:: max(1, len(T) // SAMPLED_FACES)]  # an estimate: every k-th face
    n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    area = np.linalg.norm(n, axis=1)
    keep = area > 0
    if not keep.any():
        return None
    n, area = n[keep] / area[keep, None], area[keep]
    c = T[keep].mean(axis=1)
    idx = np.stack([np.floor((c + step * pitch * n - origin) / pitch).astype(np.int64) for step in (0.0, 0.75, -0.75)])
    return idx, area


def look_up(volume: np.ndarray, idx: np.ndarray, start=(0, 0, 0)) -> np.ndarray:
    """Whether each voxel ``idx`` (..., 3) of the grid is in, of
    ``volume`` the grid's part from voxel ``start`` on (False outside it)."""
    local = idx.reshape(-1, 3) - np.asarray(start, dtype=np.int64)
    inside = np.all((local >= 0) & (local < np.array(volume.shape)), axis=1)
    found = np.zeros(len(local), dtype=bool)
    found[inside] = volume[tuple(local[inside].T)]
    return found.reshape(idx.shape[:-1])


def unbounded_share(area: np.ndarray, found: np.ndarray) -> float:
    """The share of ``area`` (K,) of the sampled faces none of whose three
    points (``found`` (3, K), :func:`sampled_points`) is in."""
    return float(area[~found.any(axis=0)].sum() / area.sum())


def unbounded_area(T: np.ndarray, volume: np.ndarray, origin, pitch: float) -> float:
    """The share of the triangles' area (corners ``T`` (M, 3, 3) in the
    grid's frame) that bounds no voxel of ``volume``: faces with no voxel in
    at their centroid or on either side of it (three quarters of a voxel
    along the normal), as zero-thickness parts, double-sided faces and parts
    thinner than a voxel leave them; estimated on every k-th face, at most
    about :data:`SAMPLED_FACES` of them (:func:`sampled_points`; a grid
    written slab by slab looks its points up slab by slab).

    Examples
    --------
    A square panel in an empty grid bounds nothing:

    >>> T = np.array([[[0, 0, 1.5], [2, 0, 1.5], [0, 2, 1.5]]], dtype=float)
    >>> unbounded_area(T, np.zeros((2, 2, 3), dtype=bool), np.zeros(3), 1.0)
    1.0
    """
    points = sampled_points(T, origin, pitch)
    if points is None:
        return 0.0
    idx, area = points
    return unbounded_share(area, look_up(volume, idx))


def thin_solid(voxels: int, shell_voxels: int | None, share: float, double_sided: int,
               volume: float | None = None) -> str | None:
    """One line where the winding rule's solid is thin or empty, or leaves
    much of the area bounding nothing, with the reasons found and the fills
    that give the model; None otherwise.

    Parameters
    ----------
    voxels : int
        The winding rule's voxels.
    shell_voxels : int or None
        The surface's shell, where it was counted; the solid is thin
        against it when it has fewer than :data:`THIN_SHARE` of them (not
        thin where it was not counted).
    share : float
        The share of the area that bounds no voxel (:func:`unbounded_area`).
    double_sided : int
        Double-sided faces read as one.
    volume : float or None
        The mesh's own volume in voxels where it is known (a closed mesh
        whose winding number is 0 or 1 at every voxel centre, on a grid
        that holds all of it): then the solid is thin when its voxels lie
        outside :data:`VOLUME_BAND` of it, whatever the shell.

    Returns
    -------
    str or None
        The line, or None.

    Examples
    --------
    >>> thin_solid(0, 120, 1.0, 0)[:40]
    'the winding rule leaves no voxel in (the'
    >>> thin_solid(1, 120, 1.0, 0)[:39]
    'the winding rule leaves 1 voxel in (the'

    A cube 3 voxels across, half a voxel off the planes, has 27 voxels
    against a shell of 56, and a volume of 27 voxels:

    >>> thin_solid(27, 56, 0.0, 0) is None, thin_solid(27, 56, 0.0, 0, volume=27.0) is None
    (False, True)
    >>> thin_solid(100, 100, 0.0, 0, volume=30.0)[72:]
    'its voxels are over 2 times its volume, parts thinner than a voxel taken whole or not at all as they lie \
on the grid; a finer grid follows them (--pitch / --resolution, pitch= / resolution=)'
    """
    if volume is not None:
        thin = not VOLUME_BAND[0] * volume <= voxels <= VOLUME_BAND[1] * volume
    else:
        thin = shell_voxels is not None and voxels < THIN_SHARE * shell_voxels
    if not thin and share < UNBOUNDED_SHARE:
        return None
    what = "no voxel" if voxels == 0 else counted(voxels, "voxel")
    if volume is not None:
        held = f"{volume:.0f}" if volume >= 9.5 else f"{volume:.2g}"  # a whole number, as the count, past ten
        against = f" (the mesh's volume is {held} voxels)"
    else:
        against = f" (the surface's shell has {shell_voxels})" if shell_voxels is not None else ""
    why = []
    if double_sided:
        why.append(f"{counted(double_sided, 'double-sided face')} read as one")
    if share > 0:
        why.append(f"{100 * share:.0f} % of the area bounds no voxel on either side "
                   "(zero-thickness parts, or parts thinner than a voxel)")
    if why:
        reason = "; ".join(why)
    elif volume is not None and voxels > VOLUME_BAND[1] * volume:
        # a layer of voxels where the part is thinner than one: the fills would give that layer
        # too, so the line offers the finer grid that follows the part instead
        return (f"the winding rule leaves {what} in{against}: its voxels are over {VOLUME_BAND[1]:g} times its "
                "volume, parts thinner than a voxel taken whole or not at all as they lie on the grid; a finer "
                "grid follows them (--pitch / --resolution, pitch= / resolution=)")
    else:
        reason = "the surface bounds little volume at this resolution"
    return (f"the winding rule leaves {what} in{against}: {reason}; "
            "--fill flood gives the shell and what it encloses, --fill shell the surface's voxels "
            "(fill='flood' / 'shell')")


#: :func:`thin_solid`'s line where every face has zero area: there is no
#: area to share out, and no reason would be given for the empty solid
NO_AREA = ("every face has zero area (its corners in a line or at one point), so the mesh bounds nothing and "
           "the winding rule leaves no voxel in; --fill shell gives the voxels its edges pass through (fill='shell')")


def flood_adds_nothing(voxels: int, shell_voxels: int | None, boundary_edges: int, grid_voxels: int) -> str | None:
    """One line where the flood fill (``voxels``) is only the shell
    (``shell_voxels``, its voxels before the flood): the outside reached
    every other voxel of the grid (``grid_voxels``), through the gaps of an
    open surface (its ``boundary_edges``) or past parts thinner than a
    voxel; None where it enclosed some voxel, or there is no shell or no
    other voxel.

    Examples
    --------
    >>> flood_adds_nothing(1156, 1156, 8, 4096)[:63]
    'the flood fill encloses no voxel beyond the shell (1156 voxels)'
    >>> flood_adds_nothing(4096, 1156, 8, 4096) is None
    True
    """
    if not voxels or voxels != shell_voxels or voxels == grid_voxels:
        return None
    how = (f"through the gaps of the open surface ({counted(boundary_edges, 'boundary edge')})" if boundary_edges
           else "past it (parts thinner than a voxel enclose nothing)")
    return (f"the flood fill encloses no voxel beyond the shell ({counted(voxels, 'voxel')}): the outside reaches every "
            f"other voxel {how}; --fill winding closes holes as a soap film would (fill='winding')")
