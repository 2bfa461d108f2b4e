"""A surface file larger than memory, read back in chunks and compared with
isoflow's counts (binary PLY and STL, as :mod:`isoflow.mesh.surface_blocks`
writes them).

trimesh reads a whole file at once (:mod:`isoflow.mesh.readback`); this
check streams it, a chunk of faces at a time, the vertices they name read
through a map of the file that is dropped after each chunk, so memory stays
at a chunk's worth whatever the file's size. Every face record is read.
It checks, from the file alone:

* the header's counts, each face's corner count, every index in range;
* **closed and consistently wound**: every directed edge ``(a, b)`` is
  matched by one ``(b, a)``. The sum over all directed edges of
  ``h1(a) h2(b) - h1(b) h2(a)`` (two 64-bit hashes, arithmetic modulo
  2^64) is zero when they are; an unmatched edge leaves it nonzero except
  with probability about 2^-64. In an STL the ends are lattice positions
  (a reader's weld), in a PLY vertex indices;
* the **Euler number** ``V - E + F`` with ``E`` half the face corners;
* the **volume** the faces enclose (divergence theorem), against the
  voxels' volume;
* in a PLY, **Gauss-Bonnet** on the vertex records: the ``a`` column adds
  up to ``8 chi`` (eq. 4.10) with ``2 chi = V - E + F - 2 pinched``
  (docs/mathematics.md, the boundary mesh);
* in an STL, each triangle's normal along its corners' orientation.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .readback import VOLUME_RTOL, volume_unit

#: faces read at a time
CHUNK_FACES = 1 << 18

_PLY_NUMPY = {"char": "i1", "uchar": "u1", "short": "<i2", "ushort": "<u2", "int": "<i4", "uint": "<u4",
              "float": "<f4", "double": "<f8", "int8": "i1", "uint8": "u1", "int32": "<i4", "float32": "<f4",
              "float64": "<f8"}


def _mix(x: np.ndarray, salt: int) -> np.ndarray:
    """A 64-bit hash of each integer (splitmix64's finaliser, salted)."""
    z = x.astype(np.uint64) + np.uint64(salt)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


def edge_fingerprint(rows: np.ndarray) -> int:
    """``sum h1(a) h2(b) - h1(b) h2(a)`` over the directed edges of
    polygons, modulo 2^64: zero when every directed edge has its reverse.

    Parameters
    ----------
    rows : numpy.ndarray
        (F, k) integer keys of each polygon's corners, in cyclic order.

    Returns
    -------
    int
        The sum; add those of several chunks modulo 2^64.

    Examples
    --------
    >>> tetra = np.array([[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]])
    >>> edge_fingerprint(tetra), edge_fingerprint(tetra[:3]) != 0
    (0, True)
    """
    a, b = rows, np.roll(rows, -1, axis=1)
    with np.errstate(over="ignore"):
        terms = _mix(a, 1) * _mix(b, 2) - _mix(b, 1) * _mix(a, 2)
        return int(terms.sum(dtype=np.uint64))


def read_ply_header(path) -> tuple[int, np.dtype, int, int]:
    """The layout of a binary PLY of vertex columns and a face list.

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    tuple
        ``(header bytes, vertex record type, vertices, faces)``.

    Raises
    ------
    ValueError
        Not a binary little-endian PLY.
    """
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    end = head.find(b"end_header\n")
    if not head.startswith(b"ply\n") or end < 0:
        raise ValueError("not a PLY file")
    lines = head[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in lines:
        raise ValueError("not a binary little-endian PLY")
    counts = {m.group(1): int(m.group(2)) for m in map(re.compile(r"element (\w+) (\d+)").match, lines) if m}
    props = [ln.split()[1:] for ln in lines if ln.startswith("property ") and "list" not in ln]
    vdt = np.dtype([(name, _PLY_NUMPY[kind]) for kind, name in props])
    return end + len(b"end_header\n"), vdt, counts.get("vertex", 0), counts.get("face", 0)


def check_ply(path, expected: dict, frame) -> dict:
    """Stream a binary PLY of :mod:`isoflow.mesh.surface_blocks` and
    compare it with isoflow's counts (see :func:`check_streamed`)."""
    head, vdt, nv, nf = read_ply_header(path)
    k = 4 if expected["kind"] == "quads" else 3
    fdt = np.dtype([("n", "u1"), ("i", "<i4", (k,))])
    problems = []
    if (nv, nf) != (expected["vertices"], expected["faces"]):
        problems.append(f"{nv} vertices and {nf} faces (isoflow: {expected['vertices']} and {expected['faces']})")
        return _verdict(path, problems, {})
    fingerprint, units, area = 0, 0.0, 0.0
    centre, unit = _centre(frame, expected), volume_unit(frame)
    for start in range(0, nf, CHUNK_FACES):
        count = min(CHUNK_FACES, nf - start)
        rec = np.fromfile(path, fdt, count, offset=head + nv * vdt.itemsize + start * fdt.itemsize)
        idx = rec["i"].astype(np.int64)
        bad = int(np.count_nonzero(rec["n"] != k)) + int(np.count_nonzero((idx < 0) | (idx >= nv)))
        if bad:
            problems.append(f"{bad} faces with another corner count than {k} or an index out of range")
            return _verdict(path, problems, {})
        fingerprint = (fingerprint + edge_fingerprint(idx)) % 2**64
        verts = np.memmap(path, vdt, "r", offset=head, shape=(nv,))
        xyz = np.stack([verts[c][idx].astype(np.float64) for c in ("x", "y", "z")], axis=-1)
        del verts  # drops the mapped pages from this process's memory
        units += _volume_units(xyz, centre, unit)
        area += _area_units(xyz, unit) if expected.get("moved") else 0.0
    a_sum = sum(int(np.fromfile(path, vdt, min(CHUNK_FACES, nv - s), offset=head + s * vdt.itemsize)["a"]
                    .astype(np.int64).sum()) for s in range(0, nv, CHUNK_FACES))
    euler = nv - nf * k // 2 + nf
    figures = {"fingerprint": fingerprint, "euler_number": euler, "volume_units": units, "a_sum": a_sum,
               "area_units": area}
    problems += _compare(figures, expected, frame, gauss_bonnet=True)
    return _verdict(path, problems, figures)


def check_stl(path, expected: dict, frame) -> dict:
    """Stream a binary STL of :mod:`isoflow.mesh.surface_blocks` and
    compare it with isoflow's counts (see :func:`check_streamed`)."""
    from .surface_blocks import STL_DTYPE, STL_HEADER

    nf = int(np.fromfile(path, "<u4", 1, offset=80)[0])
    problems = []
    if nf != expected["faces"] or Path(path).stat().st_size != STL_HEADER + nf * STL_DTYPE.itemsize:
        problems.append(f"{nf} triangles in {Path(path).stat().st_size} bytes (isoflow: {expected['faces']})")
        return _verdict(path, problems, {})
    fingerprint, units, flipped, area = 0, 0.0, 0, 0.0
    centre, unit = _centre(frame, expected), volume_unit(frame)
    origin, spacing = frame.world(np.zeros((1, 3)))[0], frame.spacing
    for start in range(0, nf, CHUNK_FACES):
        rec = np.fromfile(path, STL_DTYPE, min(CHUNK_FACES, nf - start), offset=STL_HEADER + start * STL_DTYPE.itemsize)
        xyz = rec["v"].astype(np.float64)
        # corners on the half-voxel grid: integer keys, as a reader's weld joins them
        grid = np.round(2 * (xyz - origin) / spacing).astype(np.int64)
        keys = (grid[..., 0] * (1 << 21) + grid[..., 1]) * (1 << 21) + grid[..., 2]
        fingerprint = (fingerprint + edge_fingerprint(keys)) % 2**64
        cross = np.cross(xyz[:, 1] - xyz[:, 0], xyz[:, 2] - xyz[:, 0])
        flipped += int(np.count_nonzero((cross * rec["normal"]).sum(axis=1) <= 0))
        units += _volume_units(xyz, centre, unit)
        area += _area_units(xyz, unit) if expected.get("moved") else 0.0
    figures = {"fingerprint": fingerprint, "volume_units": units, "flipped": flipped, "area_units": area}
    if flipped:
        problems.append(f"{flipped} triangles whose normal is not along their corners' order")
    problems += _compare(figures, expected, frame, gauss_bonnet=False)
    return _verdict(path, problems, figures)


def check_streamed(path, expected: dict, frame) -> dict:
    """Read a surface file back in chunks and compare it with isoflow's
    counts (see the module docs for what is checked).

    Parameters
    ----------
    path : str or os.PathLike
        A binary PLY or STL written by
        :func:`isoflow.mesh.surface_blocks.write_surface_blocks`.
    expected : dict
        That function's result (``vertices``, ``faces``, ``kind``,
        ``euler_characteristic``, ``pinched``, ``voxels``), and ``centre``:
        a point near the surface in array-corner units (the volume's
        centre), about which the volume is summed; ``moved``, optional:
        how far float64 moves the corners
        (:func:`isoflow.mesh.float32.float64_moved`), within which times
        twice the area the volume is compared.
    frame : DigitalObject
        The voxel size and origin of the positions.

    Returns
    -------
    dict
        ``agree`` (bool), ``problem`` (one line, or None), ``figures`` (what
        the file reads as), ``mode``: ``"streamed"``. A file that cannot be
        read is a disagreement.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from isoflow import DigitalObject
    >>> from isoflow.mesh.surface_blocks import write_surface_blocks
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "cube.stl"
    >>> written = write_surface_blocks(np.ones((2, 2, 2), bool), out, scheduler="sync")
    >>> check_streamed(out, dict(written, centre=(1, 1, 1)), DigitalObject(np.ones((2, 2, 2), bool)))["agree"]
    True
    """
    try:
        return (check_stl if Path(path).suffix.lower() == ".stl" else check_ply)(path, expected, frame)
    except (OSError, ValueError, KeyError) as exc:
        return _verdict(path, [f"cannot be read ({type(exc).__name__}: {exc})"], {})


def _centre(frame, expected: dict) -> np.ndarray:
    """A point near the surface, so that the triple products of the volume
    do not cancel far from the origin."""
    return frame.world(np.asarray(expected.get("centre", np.zeros(3)), np.float64)[None])[0]


def _volume_units(xyz: np.ndarray, centre: np.ndarray, unit: float) -> float:
    """The signed volume of polygons (fans from their first corner, rows of
    corner positions) in ``unit`` cubed."""
    p = (xyz - centre) / unit
    total = 0.0
    for t in range(1, p.shape[1] - 1):
        a, b, c = p[:, 0], p[:, t], p[:, t + 1]
        total += float(np.einsum("ij,ij->", a, np.cross(b, c))) / 6
    return total


def _area_units(xyz: np.ndarray, unit: float) -> float:
    """The area of polygons (fans from their first corner, rows of corner
    positions) in ``unit`` squared: the volume's slack where float64
    moves the corners (``expected["moved"]``)."""
    p = xyz / unit
    total = 0.0
    for t in range(1, p.shape[1] - 1):
        total += float(np.linalg.norm(np.cross(p[:, t] - p[:, 0], p[:, t + 1] - p[:, 0]), axis=1).sum()) / 2
    return total


def _compare(figures: dict, expected: dict, frame, gauss_bonnet: bool) -> list[str]:
    problems = []
    if figures["fingerprint"] != 0:
        problems.append("edges without their reverse (not closed, or not consistently wound)")
    if "euler_number" in figures and figures["euler_number"] != expected["euler_characteristic"]:
        problems.append(f"V-E+F {figures['euler_number']} (isoflow: {expected['euler_characteristic']})")
    want = float(expected["voxels"]) * float(np.prod(frame.spacing / volume_unit(frame)))
    # float64's own move of the corners far from the origin moves the volume by up to twice it times the area
    slack = 2 * expected.get("moved", 0.0) / volume_unit(frame) * figures.get("area_units", 0.0)
    if not np.isclose(figures["volume_units"], want, rtol=VOLUME_RTOL, atol=slack):
        problems.append(f"volume {figures['volume_units']:.9g} (isoflow: {want:.9g}, in units of "
                        f"{volume_unit(frame):g}^3)")
    if gauss_bonnet:
        eight_chi = 4 * (expected["euler_characteristic"] - 2 * expected["pinched"])
        if figures["a_sum"] != eight_chi:
            problems.append(f"the a column adds up to {figures['a_sum']} (isoflow: 8 chi = {eight_chi})")
    return problems


def _verdict(path, problems: list[str], figures: dict) -> dict:
    problem = f"{path}: read back in chunks: " + ", ".join(problems) if problems else None
    return {"agree": not problems, "problem": problem, "figures": figures, "mode": "streamed"}
