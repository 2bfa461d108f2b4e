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

trimesh parses the file (an OBJ of plain ``v`` and ``f`` lines, as
isoflow writes it, is read on its bytes into the arrays trimesh's parser
gives: :func:`obj_as_trimesh_reads`; a GLB's trimesh reader is given
the accessors the figures use: :func:`scene_nodes`); the figures are
counted by their trimesh definitions in one compiled pass over its arrays
(:mod:`isoflow.mesh.node_topology`), which sorts no edge. The read-back
needs about 100 bytes per triangle of a binary PLY, 70 of a GLB, 225 of
an STL whose positions are welded, and per line of a text file 280 of an
OBJ and 470 of an ASCII PLY (trimesh's parse holds a string and an array
a line), measured on the 11.5 million triangles of a 256^3 porous field
(docs/surface.md); a file whose read-back would not fit in the memory
budget is not read back, and the caller says so.
"""

from __future__ import annotations

import contextlib
import gc
import os
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .float32 import float32_effect, float64_corners, float64_moved
from .outputs import staged

#: relative tolerance on the volume: coordinates may be stored as float32
VOLUME_RTOL = 1e-4


def volume_unit(obj) -> float:
    """The length unit the volumes of ``obj``'s surface are compared in
    (:func:`unit_of` its voxel size)."""
    return unit_of(obj.spacing)


def unit_of(spacing) -> float:
    """The length unit the volumes are compared in: the power of two
    nearest the largest voxel size, so that a mesh in units of 1e-200 or
    1e200 neither underflows nor overflows (its volume in world units
    may: 1e600 is no float).

    Examples
    --------
    >>> unit_of((0.3, 0.3, 1.2)), unit_of(1e-200) == 2.0 ** -664
    (1.0, True)
    """
    return float(2.0 ** np.round(np.log2(np.max(spacing))))


def volume_words(units: float, unit: float, digits: int = 6) -> str:
    """A volume of ``units`` cubes of side ``unit`` (:func:`volume_unit`, a
    power of two) in world units, to ``digits`` significant digits. Where
    float64 cannot hold it (a voxel size of 1e150 makes a volume of 1e450, which
    float64 makes inf, and inf equals inf whatever the file holds) it is
    written from exact decimal arithmetic and says that it was compared in
    that unit.

    Parameters
    ----------
    units : float
        The volume in ``unit`` cubed, what the read-back compares.
    unit : float
        The length unit, a power of two.
    digits : int
        Significant digits.

    Returns
    -------
    str
        The volume as a message says it.

    Examples
    --------
    >>> volume_words(64.0, 0.5)
    '8'
    >>> volume_words(64.0, 2.0 ** 500)
    '2.24478e+453 (beyond float64: compared in voxel units, 64 cubes of 2^500)'
    >>> volume_words(1.0, 2.0 ** -400)
    '5.80771e-362 (beyond float64: compared in voxel units, 1 cube of 2^-400)'
    """
    from decimal import Decimal, localcontext

    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        world = units * np.float64(unit) ** 3
    if units == 0.0 or np.isfinite(world) and world != 0.0:
        return f"{world if units else 0.0:.{digits}g}"
    exponent = int(np.log2(unit))
    with localcontext() as ctx:
        ctx.prec = 40
        exact = Decimal(units) * Decimal(2) ** (3 * exponent)
        ctx.prec = digits
        exact = (+exact).normalize()  # rounded to the digits, without the trailing zeros "g" drops for a float
    return (f"{exact:g} (beyond float64: compared in voxel units, {units:.{digits}g} "
            f"{'cube' if units == 1 else 'cubes'} of 2^{exponent})")


def agreed_volume_words(read_units: float, voxels: int, spacing) -> str:
    """The volume of a read-back that agrees with isoflow's count, in a
    message: the count of ``voxels`` voxels of size ``spacing``, to the
    six digits ``isoflow info`` prints it to. The reader's own figure
    holds fewer where the corners moved (float64 far from the origin,
    an STL's float32), and the read-back agrees within that move: its
    digits there are the move's, not the object's, so where it differs
    from the count at six digits the words say it was read within the
    move, and no figure of the move's digits.

    Parameters
    ----------
    read_units : float
        The volume the reader found, in :func:`volume_unit` cubed.
    voxels : int
        The object's voxels.
    spacing : array_like
        The voxel size per axis.

    Returns
    -------
    str
        The volume as the read-back line says it.

    Examples
    --------
    >>> agreed_volume_words(8.0, 8, (1.0, 1.0, 1.0))
    '8'
    >>> agreed_volume_words(7.99999, 8, (1.0, 1.0, 1.0))  # an STL's float32 corners
    '8 (read within the move of the corners)'
    """
    unit = unit_of(np.asarray(spacing, np.float64))
    counted = volume_words(float(voxels) * float(np.prod(np.asarray(spacing, np.float64) / unit)), unit)
    read = volume_words(read_units, unit)
    return counted if read == counted else f"{counted} (read within the move of the corners)"


#: peak bytes of the read-back (each measured, with about 10 % to spare:
#: docs/surface.md, "Memory: the check before meshing"): a fixed part, by
#: what this process has not loaded yet, as imports done once cost nothing
#: more: trimesh's and its readers' imports, numba's start where no
#: compiled pass has run yet (``surface --labels`` of small labels meshes
#: without one), and the read-back's own compiled passes, loaded from
#: numba's cache
READBACK_BYTES_TRIMESH = 88 << 20
READBACK_BYTES_NUMBA = 125 << 20
READBACK_BYTES_LOADED = 8 << 20
#: all three: a process that has loaded neither
READBACK_BYTES_FIXED = READBACK_BYTES_TRIMESH + READBACK_BYTES_NUMBA + READBACK_BYTES_LOADED
#: and per triangle of a binary file, by suffix: an STL's positions are
#: welded and its area summed, the weld hashing its corners in a table of
#: a power of two entries, 2 to 4 a corner, so its figure is taken where
#: the table is 4 a corner, the most it holds
READBACK_BYTES_PER_TRIANGLE = {".ply": 150, ".stl": 250, ".glb": 100}
READBACK_BYTES_OTHER = 400
#: and per line of a text file (a vertex or a face): an OBJ, read as
#: arrays of its bytes, and an ASCII PLY, which trimesh's parse holds as a
#: string and an array a line; the lines are the file's, so an OBJ or a
#: PLY of triangles is asked for its own
READBACK_BYTES_PER_LINE = {".obj": 380, ".ply": 520}


def readback_memory(mesh, suffix: str = "", lines: int | None = None) -> int:
    """Estimated peak bytes of reading the mesh's file back with trimesh.

    Parameters
    ----------
    mesh : QuadMesh
        The mesh the file holds.
    suffix : str
        The file's suffix.
    lines : int, optional
        The lines of the file where it is text (an OBJ, an ASCII PLY:
        :func:`text_lines`), whose read-back is counted per line; None:
        binary (an OBJ's then counted as its vertices and triangles, the
        most lines it may hold).

    Returns
    -------
    int
        The imports (:func:`readback_fixed`), and per triangle (two per
        quad and one more per edge midpoint of a face) or per line of text.

    Examples
    --------
    >>> from isoflow.digital.surface import boundary_mesh
    >>> mesh = boundary_mesh(np.ones((2, 2, 2), bool))
    >>> readback_memory(mesh, ".stl") - readback_fixed()  # 24 squares, 48 triangles
    12000
    >>> readback_memory(mesh, ".ply", lines=26 + 24) - readback_fixed()  # ASCII: a line a vertex, a face
    26000
    """
    suffix = suffix.lower()
    triangles = 2 * len(mesh.faces) + int(np.count_nonzero(mesh.edge_midpoint >= 0))
    if suffix == ".obj" and lines is None:
        lines = len(mesh.vertices) + triangles
    return readback_bytes(triangles, suffix, lines)


def readback_bytes(triangles: int, suffix: str = "", lines: int | None = None) -> int:
    """:func:`readback_memory` of a file of ``triangles`` triangles (a
    scene's, all its nodes together), or of ``lines`` lines where it is
    text.

    Examples
    --------
    >>> readback_bytes(48, ".stl") - readback_fixed(), readback_bytes(1000, ".glb") - readback_fixed()
    (12000, 100000)
    """
    suffix = suffix.lower()
    if lines is not None and suffix in READBACK_BYTES_PER_LINE:
        return readback_fixed() + lines * READBACK_BYTES_PER_LINE[suffix]
    return readback_fixed() + int(triangles) * READBACK_BYTES_PER_TRIANGLE.get(suffix, READBACK_BYTES_OTHER)


def readback_fixed() -> int:
    """The read-back's fixed part: :data:`READBACK_BYTES_LOADED`, and
    :data:`READBACK_BYTES_TRIMESH` where trimesh is not loaded yet and
    :data:`READBACK_BYTES_NUMBA` where numba has not started (no compiled
    pass has run: its first call imports ``numba.np.arraymath`` among
    the rest), whose imports cost nothing more once done.

    Examples
    --------
    >>> import trimesh
    >>> from isoflow.mesh.equal_rows import first_equal
    >>> _ = first_equal(np.zeros((1, 3)))  # a compiled pass: numba started
    >>> readback_fixed() == READBACK_BYTES_LOADED
    True
    """
    return (READBACK_BYTES_LOADED + (0 if "trimesh" in sys.modules else READBACK_BYTES_TRIMESH)
            + (0 if "numba.np.arraymath" in sys.modules else READBACK_BYTES_NUMBA))


def readback_skipped(need: int) -> str | None:
    """Why a read-back of ``need`` bytes is skipped (it would not fit in
    the memory budget), in the words of the note; None where it fits.

    Examples
    --------
    >>> readback_skipped(1) is None, readback_skipped(1 << 60).startswith("trimesh would need about ")
    (True, True)
    """
    from ..scale.memory import default_budget, sized

    budget = default_budget()
    return f"trimesh would need about {sized(need)}, more than the budget of {sized(budget)}" if need > budget else None


def text_lines(path: str | os.PathLike) -> int | None:
    """The lines of a text mesh file (an OBJ, an ASCII PLY), counted in
    chunks of 16 MiB; None for a binary one (any other file).

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> (out / "a.obj").write_bytes(b"v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n")
    32
    >>> text_lines(out / "a.obj"), text_lines(out / "a.stl")
    (4, None)
    """
    path = Path(path)
    with contextlib.suppress(OSError), open(path, "rb") as fh:
        head = fh.read(1 << 12)
        if path.suffix.lower() != ".obj" and not (path.suffix.lower() == ".ply" and b"\nformat ascii " in head):
            return None
        count = head.count(b"\n")
        while chunk := fh.read(16 << 20):
            count += chunk.count(b"\n")
        return count
    return None


def isoflow_figures(mesh, obj, components: list | None = None) -> dict:
    """What the file must read as: isoflow's own counts of the boundary mesh
    (``components``: ``mesh.components()`` when the caller has them)."""
    comps = mesh.components() if components is None else components
    return expected_figures(int(mesh.euler_characteristic), int(sum(c["genus"] for c in comps)), int(obj.voxels),
                            obj.spacing)


def expected_figures(euler: int, genus: int, voxels: int, spacing, slack: float = 0.0) -> dict:
    """What the boundary surface of an object of ``voxels`` voxels of size
    ``spacing``, of Euler characteristic ``euler`` and total genus ``genus``,
    must read as (watertight; the volume in world units and in
    :func:`volume_unit` cubed; ``slack``, in world units cubed, how far
    the volume may differ, as ``slack_units`` in the unit cubed: where
    float64 moves the corners, :func:`~isoflow.mesh.float32.float64_moved`).

    Examples
    --------
    >>> expected_figures(2, 0, 8, (0.5, 0.5, 2.0))["volume"]
    4.0
    """
    return expected_figures_each([euler], [genus], [voxels], spacing, [slack])[0]


def expected_figures_each(euler: list[int], genus: list[int], voxels: list[int], spacing,
                          slack: list[float] | None = None) -> list[dict]:
    """:func:`expected_figures` of many objects of one voxel size (a
    label image's), the voxel's volume and unit found once for all of
    them: found per object, NumPy's calls for them outweigh the rest of
    each object's figures.

    Parameters
    ----------
    euler, genus, voxels : list of int
        Per object: its surface's Euler characteristic, its total genus,
        its voxels.
    spacing : array_like
        The voxel size per axis, the same for every object.
    slack : list of float, optional
        Per object, how far its volume may differ, in world units cubed;
        none by default.

    Returns
    -------
    list of dict
        Per object, what :func:`expected_figures` gives.

    Examples
    --------
    >>> [f["volume"] for f in expected_figures_each([2, 0], [0, 1], [8, 20], (0.5, 0.5, 2.0))]
    [4.0, 10.0]
    """
    spacing = np.asarray(spacing, np.float64)
    unit = unit_of(spacing)
    with np.errstate(over="ignore", under="ignore"):
        voxel, voxel_units = float(np.prod(spacing)), float(np.prod(spacing / unit))
    slack = [0.0] * len(voxels) if slack is None else slack
    return [{"watertight": True, "euler_number": int(e), "genus": int(g), "volume": float(n) * voxel,
             "volume_units": float(n) * voxel_units, "slack_units": float(s / unit ** 3) if s else 0.0}
            for e, g, n, s in zip(euler, genus, voxels, slack)]


def trimesh_figures(path, weld: bool = False, unit: float = 1.0, area: bool = False) -> dict:
    """Watertightness (every edge in two faces, consistently wound), Euler
    number, genus and volume (``volume_units``: in ``unit`` cubed, about
    the vertices' mean: far from the origin, the triple products in world
    coordinates cancel to a few digits) of a mesh file as trimesh reads it: with
    ``process=False`` (no vertex merge, the file's own vertices), and when
    ``weld`` (STL stores no shared vertices) with equal positions welded
    into one vertex (trimesh's own merge rounds positions to 1e-8 in any
    units, which joins distinct corners of a surface in units of 1e-6).
    ``area_units``: the surface's area in ``unit`` squared (an STL's, and
    with ``area``: the volume's tolerance for float32's or float64's move;
    None otherwise).

    A PLY or an STL is parsed by trimesh's reader of the format and the
    mesh built from its arrays alone (a PLY's colours cost a third of the
    read, measured on flow steps, and do not touch the topology); a GLB's
    nodes are those of trimesh's glTF reader placed by their transforms
    (:func:`scene_nodes`), joined as ``trimesh.load(force="mesh")`` joins
    them, without the colours. The volume is the signed volume of the
    triangles trimesh read (``trimesh.volume`` also integrates the inertia:
    another third).
    """
    import trimesh

    path = Path(path)
    if path.suffix.lower() == ".stl" and weld:
        tm = trimesh.Trimesh(*welded_stl(path), process=False)
        return mesh_figures(tm, unit, area=True)
    if path.suffix.lower() in (".ply", ".stl"):
        # the format's own reader, whose arrays make the mesh as they are
        # (trimesh.load of an STL copies the mesh twice through a scene)
        from trimesh.exchange.ply import load_ply
        from trimesh.exchange.stl import load_stl

        with open(path, "rb") as fh:
            kw = (load_ply if path.suffix.lower() == ".ply" else load_stl)(fh)
        tm = trimesh.Trimesh(kw["vertices"], kw["faces"], process=False)
    elif (read := obj_as_trimesh_reads(path)) is not None:
        tm = trimesh.Trimesh(*read, process=False)
    elif path.suffix.lower() == ".glb":
        # the nodes as trimesh's glTF reader places them, which
        # trimesh.load(force="mesh") joins into one mesh: it copies the mesh
        # twice, deriving face colours from the vertex colours at each copy
        # (most of the read-back), which do not touch the topology
        nodes = list(scene_nodes(path).values())
        if len(nodes) == 1:
            tm = trimesh.Trimesh(*nodes[0], process=False)
        else:
            first = np.cumsum([0] + [len(v) for v, _ in nodes])
            tm = trimesh.Trimesh(np.concatenate([v for v, _ in nodes] or [np.zeros((0, 3))]),
                                 np.concatenate([t + k for (_, t), k in zip(nodes, first)] or
                                                [np.zeros((0, 3), np.int64)]), process=False)
    else:
        import warnings

        with warnings.catch_warnings():  # NumPy's, on degenerate triangles: the verdict says what is wrong
            warnings.simplefilter("ignore", RuntimeWarning)
            tm = trimesh.load(path, force="mesh", process=False)
    if weld:
        tm = weld_equal_positions(tm)
    return mesh_figures(tm, unit, area=weld or area)


def obj_as_trimesh_reads(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray] | None:
    """The vertices and triangles ``trimesh.load`` (``process=False``,
    ``force="mesh"``) gives for an OBJ file of plain ``v`` and ``f`` lines,
    as isoflow writes them, read on the file's bytes as arrays
    (:func:`isoflow.mesh.readers.read_obj`, every polygon fanned from its
    first corner as trimesh fans it); None for any other file or suffix,
    and for a face index that names no vertex: trimesh's read says what it
    makes of those.

    trimesh parses a file of faces of one size as one array, but one of
    quads and pentagons (a surface with edge midpoints) line by line in
    Python, most of such a file's read-back.

    Parameters
    ----------
    path : str or os.PathLike
        The surface file written (``.obj``: any other suffix gives None).

    Returns
    -------
    tuple of numpy.ndarray or None
        float64 (N, 3) vertices (those a face uses, in the file's order) and
        int64 (M, 3) triangles.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "p.obj"
    >>> _ = path.write_text("v 0 0 0\\nv 2 0 0\\nv 2 2 0\\nv 0 2 0\\nv 1 0 0\\nv 3 3 3\\nf 5 2 3 4 1\\nf 1 2 6\\n")
    >>> vertices, triangles = obj_as_trimesh_reads(path)
    >>> len(vertices), triangles.tolist()
    (6, [[4, 1, 2], [4, 2, 3], [4, 3, 0], [0, 1, 5]])
    """
    from .readers import BadFaceIndex, read_obj

    path = Path(path)
    if path.suffix.lower() != ".obj":
        return None
    try:
        return read_obj(path.read_bytes(), ears=False)
    except BadFaceIndex:
        return None


def mesh_figures(tm, unit: float = 1.0, area: bool = False) -> dict:
    """The figures of :func:`trimesh_figures` of a trimesh mesh (``area``:
    with its surface area, as an STL's read-back needs)."""
    from .node_topology import node_topology, node_volumes

    faces = np.asarray(tm.faces, np.int64).reshape(-1, 3)
    # trimesh's figures (is_watertight and is_winding_consistent, V - E + F,
    # body_count) by their definitions in one compiled pass over its
    # arrays, where trimesh sorts every edge (most of a large read-back)
    topology = node_topology(faces, [0, len(tm.vertices)], [0, len(faces)])
    euler, bodies = int(topology["euler"][0]), int(topology["bodies"][0])
    if bodies < 0:  # a triangle on a vertex the file does not hold: trimesh's own counts
        euler = int(tm.euler_number)
        bodies = int(tm.body_count) - int(np.count_nonzero(~tm.referenced_vertices))
    v = np.asarray(tm.vertices, np.float64)
    units = float(node_volumes(v, faces, [0, len(v)], [0, len(faces)], unit)[0])
    area_units = None
    if area:
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            local = v / unit  # before the mean: near float64's largest coordinates their world sum is inf
            local = local - (local.mean(axis=0) if len(v) else 0.0)
            # a million triangles at a time: the corners' tables of every
            # triangle at once would be most of an STL's read-back
            step = 1 << 20
            area_units = float(sum(np.linalg.norm(np.cross(local[f[:, 1]] - local[f[:, 0]], local[f[:, 2]] - local[f[:, 0]]),
                                                  axis=1).sum() for f in (faces[i:i + step] for i in range(0, len(faces), step)))
                               / 2)
    return figures(bool(topology["closed"][0]), euler, bodies, units, unit, area_units)


def figures(closed: bool, euler: int, bodies: int, volume_units: float, unit: float,
            area_units: float | None = None) -> dict:
    """The figures of one mesh as :func:`mesh_figures` gives them, from its
    counts: the genus where it is closed and its Euler number even, the
    volume in world units from ``volume_units`` (in ``unit`` cubed)."""
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        volume = float(volume_units * np.float64(unit) ** 3)
    return {"watertight": closed, "euler_number": int(euler),
            "genus": int(bodies - euler // 2) if closed and euler % 2 == 0 else None,
            "volume": volume, "volume_units": float(volume_units), "area_units": area_units}


def welded_stl(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """An STL as trimesh's reader parses it, its equal positions welded
    into one vertex (:func:`weld_equal_positions`): the distinct positions
    and the triangles on them. The file's records (positions, normals,
    attributes: 50 bytes a triangle) are let go once the corners are
    welded, and the reader's triangles (the corners in order, 24 bytes a
    triangle) as soon as they are found to be that order; the positions
    are welded as the file's float32 (the weld's float64 copy of them is
    its own).

    Examples
    --------
    >>> import tempfile, trimesh
    >>> path = Path(tempfile.mkdtemp()) / "box.stl"
    >>> _ = trimesh.creation.box().export(path)
    >>> vertices, triangles = welded_stl(path)
    >>> vertices.shape, triangles.shape, vertices.dtype.name
    ((8, 3), (12, 3), 'float32')
    """
    from trimesh.exchange.stl import load_stl

    from .load import distinct_rows

    with open(path, "rb") as fh:
        kw = load_stl(fh)
    corners, triangles = kw.pop("vertices"), kw.pop("faces")
    del kw  # the normals and attributes, views of the records
    if corners_in_order(triangles):
        triangles = None
    points, at = distinct_rows(corners)
    del corners  # the last view of the records
    return points, at.reshape(-1, 3) if triangles is None else at[triangles]


def corners_in_order(triangles: np.ndarray) -> bool:
    """Whether the triangles are ``0 1 2``, ``3 4 5``, ... (as trimesh's
    STL reader makes them), checked a million corners at a time.

    Examples
    --------
    >>> corners_in_order(np.arange(6).reshape(2, 3)), corners_in_order(np.array([[0, 2, 1]]))
    (True, False)
    """
    flat = np.asarray(triangles).reshape(-1)
    step = 1 << 20
    return all(np.array_equal(flat[i:i + step], np.arange(i, min(i + step, len(flat)))) for i in range(0, len(flat), step))


def weld_equal_positions(tm):
    """The mesh with vertices at equal positions made one (a reader's weld
    of an STL, where float32 keeps distinct positions distinct)."""
    import trimesh

    from .load import distinct_rows

    points, at = distinct_rows(np.asarray(tm.vertices))
    return trimesh.Trimesh(points, at.reshape(-1)[np.asarray(tm.faces)], process=False)


def volumes_agree(read: float | np.ndarray | list, counted: float | np.ndarray | list,
                  slack: float | np.ndarray | list = 0.0) -> np.ndarray:
    """Whether the volumes read back agree with isoflow's counts, within
    :data:`VOLUME_RTOL` and ``slack`` (absolute), all in the same unit
    cubed. A volume that is not finite agrees with nothing: ``np.isclose``
    takes inf as close to inf, which would pass a read-back whose arithmetic
    overflowed as a check.

    Parameters
    ----------
    read, counted : float or array_like
        The volumes read back and counted.
    slack : float or array_like
        How far they may differ besides the relative tolerance.

    Returns
    -------
    numpy.ndarray
        Per volume, whether the two agree (0-d for two floats).

    Examples
    --------
    >>> bool(volumes_agree(8.0, 8.0)), bool(volumes_agree(float("inf"), float("inf")))
    (True, False)
    """
    read, counted = np.asarray(read, np.float64), np.asarray(counted, np.float64)
    return np.isclose(read, counted, rtol=VOLUME_RTOL, atol=slack) & np.isfinite(read) & np.isfinite(counted)


def check_surface_file(path, mesh, obj, *, topology: bool = True, components: list | None = None) -> dict:
    """Read a written surface file back with trimesh and compare it with
    isoflow's counts. Returns ``{"isoflow": ..., "trimesh": ..., "agree":
    bool, "problem": str or None}``, and ``"skipped"`` (why) with
    ``agree`` None where the read-back would not fit in memory.

    STL is read with its equal positions welded. Where the object has edge
    or vertex contacts the weld joins copies the mesh keeps apart, so
    ``topology=False`` then compares the volume only (the caller says why).
    STL's float32 positions move the surface by up to ``moved``
    (:func:`isoflow.mesh.float32.float32_effect`), which changes the volume
    by at most ``moved`` times the area: the volume is compared within that,
    and within float64's own move of the corners where the object lies far
    from the origin against its voxel size
    (:func:`isoflow.mesh.float32.float64_corners`).
    """
    path = Path(path)
    # a text file's parse is counted per line of it: a file of triangles holds more lines than one of quads
    why = readback_skipped(readback_memory(mesh, path.suffix, text_lines(staged(path))))
    if why is not None:
        return {"isoflow": None, "trimesh": None, "agree": None, "problem": None, "skipped": why}
    ours = isoflow_figures(mesh, obj, components)
    # far from the origin against the voxel size float64 itself moves the
    # corners (float64_move_note): every format's volume moves with them
    moved = float64_moved(float64_corners(obj.origin, obj.spacing, obj.volume.shape))
    try:
        # the new file where its set is not in place yet (its temporary keeps the suffix)
        theirs = trimesh_figures(staged(path), weld=path.suffix.lower() == ".stl", unit=volume_unit(obj),
                                 area=moved > 0)
    except Exception as exc:  # a file trimesh cannot read is the worst disagreement
        return {"isoflow": ours, "trimesh": {k: None for k in ours}, "agree": False,
                "problem": f"{path}: trimesh cannot read it ({type(exc).__name__}: {exc})"}
    keys = ("watertight", "euler_number", "genus") if topology else ()
    problems = [f"{k} {theirs[k]} (isoflow: {ours[k]})" for k in keys if theirs[k] != ours[k]]
    # the signed volume needs no manifold: a welded STL still encloses it
    if path.suffix.lower() == ".stl":
        moved = max(moved, float32_effect(obj.world(mesh.vertices), obj.spacing)["moved"] or 0.0)
    slack = 2 * moved / volume_unit(obj) * theirs["area_units"] if moved else 0.0
    if not volumes_agree(theirs["volume_units"], ours["volume_units"], slack):
        unit = volume_unit(obj)
        problems.append(f"volume {volume_words(theirs['volume_units'], unit, 9)} "
                        f"(isoflow: {volume_words(ours['volume_units'], unit, 9)})")
    problem = f"{path}: trimesh reads " + ", ".join(problems) if problems else None
    return {"isoflow": ours, "trimesh": theirs, "agree": not problems, "problem": problem}


def check_scene_file(path, parts: list, progress=None) -> list[str]:
    """Read a glTF scene written by :func:`isoflow.mesh.export.write_glb_scene`
    back with trimesh and compare every node (its transform applied) with
    isoflow's counts: ``parts`` holds ``(name, mesh, obj, components)``;
    ``progress(done, total)`` hears of the nodes measured. Returns the
    problems, one line each (none: every node agrees)."""
    return check_scene_figures(path, [(name, isoflow_figures(mesh, obj, components), volume_unit(obj))
                                      for name, mesh, obj, components in parts], progress)


def check_scene_figures(path, expected: list, progress=None) -> list[str]:
    """:func:`check_scene_file` of the figures each node must read as:
    ``expected`` holds ``(name, figures, unit)``, the figures as
    :func:`expected_figures` gives them and the unit the volume is compared
    in (:func:`unit_of`)."""
    path = Path(path)
    try:
        nodes = scene_nodes(staged(path), as_read=True)
    except Exception as exc:
        return [f"{path}: trimesh cannot read it ({type(exc).__name__}: {exc})"]
    problems, found, placed = [], [], []
    for name, ours, unit in expected:
        if name not in nodes:
            problems.append(f"{path}: no node {name}")
            continue
        placed.append((*nodes[name], unit))
        found.append((name, ours, unit))
    measured = scene_figures(placed, progress)
    # every node's volume in one comparison: a call per node costs more than measuring the node
    close = volumes_agree([theirs["volume_units"] for theirs in measured],
                          [ours["volume_units"] for _, ours, _ in found],
                          [ours.get("slack_units", 0.0) for _, ours, _ in found]) if found else []
    for (name, ours, unit), theirs, volume_agrees in zip(found, measured, close):
        wrong = [f"{k} {theirs[k]} (isoflow: {ours[k]})" for k in ("watertight", "euler_number", "genus")
                 if theirs[k] != ours[k]]
        if not volume_agrees:
            wrong.append(f"volume {volume_words(theirs['volume_units'], unit, 9)} "
                         f"(isoflow: {volume_words(ours['volume_units'], unit, 9)})")
        if wrong:
            problems.append(f"{path}: node {name}: trimesh reads " + ", ".join(wrong))
    return problems


def scene_nodes(path: str | os.PathLike, as_read: bool = False) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Every node of a binary glTF that holds a mesh, as trimesh's glTF
    reader parses it. The reader's arrays are taken as they are, without
    the mesh object per node that ``trimesh.load`` builds (most of a
    scene's read-back where it has thousands of nodes), and the reader is
    given the positions' and triangles' accessors alone where the others
    are ones it would read without fail
    (:func:`isoflow.mesh.glb_geometry.read_geometry`).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.glb`` file.
    as_read : bool
        Give the arrays in the reader's types (the file's float32
        positions, its 16- or 32-bit indices), for a caller that casts
        many nodes' at once (:func:`union_figures`) rather than paying a
        NumPy call per node for each cast.

    Returns
    -------
    dict
        ``name -> (vertices, triangles)``: float64 vertices placed by the
        node's transform and those of the nodes above it, int64 triangles
        of three columns; with ``as_read``, the vertices of a node that
        no transform moves and the triangles as the reader gives them.

    Examples
    --------
    >>> import tempfile, trimesh
    >>> scene = trimesh.Scene()
    >>> _ = scene.add_geometry(trimesh.creation.box(), node_name="box", geom_name="box",
    ...                        transform=trimesh.transformations.translation_matrix([5.0, 0.0, 0.0]))
    >>> path = Path(tempfile.mkdtemp()) / "s.glb"
    >>> _ = scene.export(path)
    >>> vertices, triangles = scene_nodes(path)["box"]
    >>> vertices.mean(axis=0).tolist(), triangles.shape
    ([5.0, 0.0, 0.0], (12, 3))
    """
    # the parse makes containers by the hundred thousand (the JSON's
    # accessors, trimesh's per node) that live until it is done and are
    # freed by their counts; the collector, run each few hundred new
    # containers, would walk all of them again and again
    with collector_paused():
        return _scene_nodes(path, as_read)


@contextlib.contextmanager
def collector_paused() -> Iterator[None]:
    """Python's cyclic garbage collector paused for the block, and
    resumed after it where it ran before (a caller that had paused it
    keeps it paused): for work that makes many containers that are freed
    by their counts, none in a cycle.

    Examples
    --------
    >>> import gc
    >>> with collector_paused():
    ...     gc.isenabled()
    False
    >>> gc.isenabled()
    True
    """
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _scene_nodes(path: str | os.PathLike, as_read: bool) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """:func:`scene_nodes`, the collector as the caller has it."""
    from .glb_geometry import read_geometry

    with open(path, "rb") as fh:
        # the accessors the figures do not use are checked, not made arrays
        # (most of trimesh's parse of a scene of thousands of nodes)
        read = read_geometry(fh)
    edges = {edge["frame_to"]: edge for edge in read["graph"]}
    moving: dict[int, bool] = {}  # a matrix (by id) -> whether it is other than the identity

    def moves(matrix) -> bool:
        """Whether the matrix is other than the identity: found once for
        each array trimesh gives (one for all the nodes of a file that
        gives them none, rather than a comparison per node)."""
        key = id(matrix)  # (each lives in the graph until the nodes are taken)
        if key not in moving:
            moving[key] = not np.array_equal(np.asarray(matrix, np.float64), np.eye(4))
        return moving[key]

    def placement(frame: str) -> np.ndarray | None:
        """The node's transform and those above it, None where none of
        them moves it (most nodes of isoflow's scenes: no matrix per node
        to make)."""
        edge = edges.get(frame)
        if edge is None:  # the root
            return None
        above = placement(edge["frame_from"])
        if "matrix" not in edge or not moves(edge["matrix"]):
            return above
        return (np.eye(4) if above is None else above) @ np.asarray(edge["matrix"], np.float64)

    nodes = {}
    for frame, edge in edges.items():
        if "geometry" not in edge:
            continue
        geometry = read["geometry"][edge["geometry"]]
        vertices, triangles = geometry["vertices"], geometry["faces"]
        transform = placement(frame)
        if transform is not None and not np.array_equal(transform, np.eye(4)):
            vertices = np.asarray(vertices, np.float64) @ transform[:3, :3].T + transform[:3, 3]
        elif not as_read:
            vertices = np.asarray(vertices, np.float64)
        nodes[frame] = (vertices, triangles if as_read else np.asarray(triangles, np.int64).reshape(-1, 3))
    return nodes


#: triangles of the nodes :func:`scene_figures` measures at once (the
#: volume's temporaries, some 100 bytes a triangle, stay in the caches)
UNION_TRIANGLES = 1 << 17


def scene_figures(placed: list, progress=None) -> list[dict]:
    """:func:`mesh_figures` of every node of a scene (``placed``: its
    vertices in place, its faces and its volume unit), a run of nodes of
    about :data:`UNION_TRIANGLES` triangles at a time (see
    :func:`union_figures`); ``progress(done, total)`` after each run."""
    sizes = np.cumsum([len(f) for _, f, _ in placed])
    out: list[dict] = []
    while len(out) < len(placed):
        end = max(len(out) + 1, int(np.searchsorted(sizes, (sizes[len(out) - 1] if out else 0) + UNION_TRIANGLES)))
        out += union_figures(placed[len(out):end])
        if progress is not None:
            progress(len(out), len(placed))
    return out


def union_figures(placed: list) -> list[dict]:
    """:func:`mesh_figures` of some nodes of a scene, measured together:
    each node's closedness, Euler number and bodies by
    :func:`isoflow.mesh.node_topology.node_topology` (trimesh's
    definitions) and its volume by
    :func:`~isoflow.mesh.node_topology.node_volumes`. A node whose
    triangles name a vertex it does not hold is measured alone, by
    trimesh's own counts."""
    import trimesh

    from .node_topology import node_topology, node_volumes

    # the nodes' arrays cast and renumbered together, in a few numpy calls
    # whatever their number: a scene of thousands of small nodes would
    # otherwise pay a call per node for each
    triangles = [np.reshape(f, (-1, 3)) for _, f, _ in placed]
    counts = np.array([len(v) for v, _, _ in placed], np.int64)
    sizes = np.array([len(f) for f in triangles], np.int64)
    vfirst, ffirst = np.concatenate([[0], np.cumsum(counts)]), np.concatenate([[0], np.cumsum(sizes)])
    faces = np.concatenate(triangles, dtype=np.int64)
    faces += np.repeat(vfirst[:-1], sizes)[:, None]
    topology = node_topology(faces, vfirst, ffirst)
    units = np.array([unit for _, _, unit in placed], np.float64)
    volume_units = node_volumes(np.concatenate([v for v, _, _ in placed], dtype=np.float64), faces, vfirst, ffirst,
                                units)
    closed, euler, bodies = topology["closed"].tolist(), topology["euler"].tolist(), topology["bodies"].tolist()
    volume_units, unit_list = volume_units.tolist(), units.tolist()
    return [figures(closed[t], euler[t], bodies[t], volume_units[t], unit_list[t]) if bodies[t] >= 0
            else mesh_figures(trimesh.Trimesh(v, f, process=False), unit)
            for t, (v, f, unit) in enumerate(placed)]
