"""Reading volumes and point lists; writing volumes, PLY and OBJ.

Every reader raises :class:`~isoflow.errors.IsoflowError` with the file name
and what is wrong; every writer refuses to replace an existing file unless
``force=True``.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from .arrays import binary
from .errors import IsoflowError
from .lattice import DigitalObject

VOLUME_SUFFIXES = (".npy", ".npz")
POINT_SUFFIXES = (".txt", ".xyz", ".pts", ".csv")


def _check_readable(path: Path) -> None:
    if not path.exists():
        raise IsoflowError(f"{path}: no such file")
    if path.is_dir():
        if path.suffix != ".zarr":
            raise IsoflowError(f"{path}: is a directory, not a volume or point list")
    elif not path.is_file():
        # a device or FIFO would be read until memory runs out (/dev/zero)
        raise IsoflowError(f"{path}: not a regular file (a device, pipe or socket)")


def read_volume(path: str | os.PathLike) -> DigitalObject:
    """A 2D or 3D volume from ``.npy`` or ``.npz``.

    An ``.npz`` written by :func:`write_volume` carries ``volume`` plus its
    ``offset``, ``parity``, ``pitch`` and ``origin``; any other ``.npz`` must
    hold exactly one array (or one named ``volume``).
    """
    path = Path(path)
    _check_readable(path)
    meta: dict = {}
    try:
        loaded = np.load(path, allow_pickle=False)
        # trust the content, not the name: an .npz may be called .npy or .NPZ
        if isinstance(loaded, np.lib.npyio.NpzFile):
            with loaded as z:
                names = list(z.files)
                if "volume" in names:
                    arr = z["volume"]
                    for key in ("offset", "parity", "pitch", "origin"):
                        if key in names:
                            meta[key] = z[key]
                elif len(names) == 1:
                    arr = z[names[0]]
                else:
                    raise IsoflowError(
                        f"{path}: holds arrays {names}; name the volume 'volume'"
                    )
        elif isinstance(loaded, np.ndarray):
            arr = loaded
        else:
            raise IsoflowError(f"{path}: not a numpy array or archive ({type(loaded).__name__})")
    except IsoflowError:
        raise
    except Exception as exc:  # numpy raises several types for a bad file
        raise IsoflowError(f"{path}: not a readable numpy file ({exc.__class__.__name__}: {exc})") from None
    if arr.ndim not in (2, 3, 4):
        raise IsoflowError(f"{path}: a volume must be 2D, 3D or 4D, this array is {arr.ndim}D with shape {arr.shape}")
    vol = binary(arr, str(path))
    try:  # DigitalObject checks the metadata fields; its errors get the file's name
        return DigitalObject(vol, **meta)
    except IsoflowError as exc:
        raise IsoflowError(f"{path}: {exc}") from None


_SPLIT = re.compile(r"[,\s]+")


def read_points(path: str | os.PathLike) -> np.ndarray:
    """Integer lattice points from a text file: ``x y z`` (or ``x y``) per
    line, ``#`` starts a comment, commas or blanks separate the numbers."""
    from .lattice import MAX_COORDINATE

    path = Path(path)
    _check_readable(path)
    try:
        # look at the head first: any file of unknown type lands here, and
        # a big binary one should not be read whole before being refused
        with open(path, "rb") as fh:
            head = fh.read(1024)
        if b"\0" in head:
            raise IsoflowError(
                f"{path}: binary data, not a text point list (x y z per line); "
                f"volumes are .npy/.npz"
            )
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise IsoflowError(f"{path}: cannot read as text ({exc})") from None
    rows, width = [], None
    for lineno, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        fields = [f for f in _SPLIT.split(line) if f]
        if width is None:
            width = len(fields)
            if width not in (2, 3):
                raise IsoflowError(f"{path}:{lineno}: expected 2 or 3 coordinates, got {len(fields)}")
        elif len(fields) != width:
            raise IsoflowError(f"{path}:{lineno}: expected {width} coordinates, got {len(fields)}")
        try:
            values = [float(f) for f in fields]
        except ValueError:
            raise IsoflowError(f"{path}:{lineno}: not a number in {line!r}") from None
        for f, v in zip(fields, values):
            if not np.isfinite(v) or v != round(v):
                raise IsoflowError(f"{path}:{lineno}: coordinate {f} is not an integer")
            if abs(v) > MAX_COORDINATE:  # 1e300 or int64 extremes overflow later
                raise IsoflowError(f"{path}:{lineno}: coordinate {f} is out of range (beyond +-{MAX_COORDINATE})")
        rows.append([int(round(v)) for v in values])
    if not rows:
        raise IsoflowError(f"{path}: no points")
    return np.array(rows, dtype=np.int64)


def read_object(path: str | os.PathLike, points_are: str = "corners") -> DigitalObject:
    """A digital object from a volume file or a point list.

    ``points_are='corners'`` reads a point list with the paper's point model
    (Definitions 1-2); ``'voxels'`` takes each point as a voxel index.
    """
    path = Path(path)
    if points_are not in ("corners", "voxels"):
        raise IsoflowError(f"points_are must be 'corners' or 'voxels', got {points_are!r}")
    if path.suffix.lower() in VOLUME_SUFFIXES:
        return read_volume(path)
    pts = read_points(path)
    try:
        if points_are == "voxels":
            return DigitalObject.from_voxels(pts)
        return DigitalObject.from_points(pts)
    except IsoflowError as exc:  # e.g. the grid beyond the memory budget: say which file
        raise IsoflowError(f"{path}: {exc}") from None


def check_output_path(
    path: str | os.PathLike, force: bool = False, suffixes: tuple[str, ...] = (), what: str = "output"
) -> Path:
    """The output file as a Path, checked before any work is done: it ends in
    one of ``suffixes`` (any case; none: any name), is not a directory, does
    not exist unless ``force``, and its directory exists."""
    path = Path(path)
    if suffixes and path.suffix.lower() not in suffixes:
        raise IsoflowError(f"{path}: {what} must end in {' or '.join(suffixes)}")
    if path.is_dir():  # --force must not mean "replace a directory"
        raise IsoflowError(f"{path}: is a directory; give a file name for the {what}")
    if path.exists() and not force:
        raise IsoflowError(f"{path}: exists; pass --force (force=True) to overwrite")
    if not path.parent.is_dir():
        raise IsoflowError(f"{path.parent}: no such directory (for the {what} {path.name})")
    return path


def check_picture_path(path: str | os.PathLike, force: bool = False) -> Path:
    """A picture file (``--png``, matplotlib output) checked as
    :func:`check_output_path`; call it before the work that the picture shows."""
    return check_output_path(path, force, suffixes=(".png",), what="picture")


def _refuse_overwrite(path: Path, force: bool) -> None:
    check_output_path(path, force)


def write_volume(obj: DigitalObject, path: str | os.PathLike, force: bool = False) -> Path:
    """Save an object as ``.npz`` with its offset, parity, pitch and origin."""
    path = Path(path)
    _refuse_overwrite(path, force)
    with open(path, "wb") as fh:
        np.savez_compressed(
            fh,
            volume=obj.volume,
            offset=np.array(obj.offset, np.int64),
            parity=np.int64(obj.parity),
            pitch=np.float64(obj.pitch),
            origin=obj.origin,
        )
    return path


# --------------------------------------------------------------------------
# Meshes
# --------------------------------------------------------------------------

def gamma_colours(gamma: np.ndarray, vertex_class: np.ndarray) -> np.ndarray:
    """RGB (uint8) of the vertex angle gamma (-4..4 eighths): blue for concave,
    white for flat, red for convex, linear in between; green marks vertices
    that are not well-composed, grey the midpoints of doubled edges."""
    palette = _gamma_palette()
    rgb = palette[np.clip(np.asarray(gamma, np.int64), -4, 4) + 4]  # a gather, not float math per vertex
    rgb[vertex_class == -1] = (20, 170, 60)
    rgb[vertex_class == -2] = (150, 150, 150)
    return rgb


def _gamma_palette() -> np.ndarray:
    """Colour of gamma = -4 .. 4: blue - white - red, linear in between."""
    t = np.arange(-4, 5) / 4.0
    white = np.array([255.0, 255.0, 255.0])
    red = np.array([200.0, 30.0, 30.0])
    blue = np.array([30.0, 60.0, 200.0])
    pos = np.clip(t, 0, 1)[:, None]
    neg = np.clip(-t, 0, 1)[:, None]
    return np.round(white * (1 - pos - neg) + red * pos + blue * neg).astype(np.uint8)


def mesh_vertex_table(mesh, obj: DigitalObject) -> dict[str, np.ndarray]:
    """Per-vertex columns written to PLY: position (world), curvature data."""
    xyz = obj.world(mesh.vertices)
    cls = mesh.vertex_class
    rgb = gamma_colours(mesh.gamma, cls)
    return {
        "x": xyz[:, 0].astype(np.float32),
        "y": xyz[:, 1].astype(np.float32),
        "z": xyz[:, 2].astype(np.float32),
        "config": mesh.config.astype(np.uint8),
        "class": cls.astype(np.int8),
        "gamma": mesh.gamma.astype(np.int8),
        "a": mesh.a.astype(np.int8),
        "f": mesh.f.astype(np.int8),
        "red": rgb[:, 0],
        "green": rgb[:, 1],
        "blue": rgb[:, 2],
    }


_PLY_TYPES = {"f4": "float", "u1": "uchar", "i1": "char", "i4": "int", "f8": "double"}


def _size_groups(faces: np.ndarray):
    """Faces padded with -1, grouped by their number of vertices."""
    faces = np.asarray(faces, dtype=np.int64)
    sizes = (faces >= 0).sum(axis=1) if faces.size else np.zeros(0, np.int64)
    for size in np.unique(sizes):
        rows = faces[sizes == size]
        # -1 slots can sit between vertices (a missing midpoint): drop them
        # keeping the cyclic order. A boolean mask reads row by row, and
        # every row of the group keeps exactly `size` slots.
        yield int(size), rows[rows >= 0].reshape(len(rows), size)


def write_ply(
    path: str | os.PathLike,
    columns: dict[str, np.ndarray],
    faces: np.ndarray,
    *,
    ascii: bool = False,
    force: bool = False,
    comments: tuple[str, ...] = (),
) -> Path:
    """Write a PLY with per-vertex scalar columns and polygon faces.

    ``faces`` is (F, K) with -1 padding for faces with fewer than K vertices.
    Binary little-endian by default. Quads stay quads (MeshLab and trimesh
    read them); faces are written grouped by size.
    """
    path = Path(path)
    _refuse_overwrite(path, force)
    names = list(columns)
    n = len(columns[names[0]])
    groups = list(_size_groups(faces))
    header = ["ply", f"format {'ascii' if ascii else 'binary_little_endian'} 1.0"]
    header += [f"comment {c}" for c in comments]
    header.append(f"element vertex {n}")
    for k in names:
        header.append(f"property {_PLY_TYPES[columns[k].dtype.str[1:]]} {k}")
    header.append(f"element face {sum(len(g) for _, g in groups)}")
    header.append("property list uchar int vertex_indices")
    header.append("end_header")
    with open(path, "wb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        if ascii:
            fmt = " ".join("%.9g" if columns[k].dtype.kind == "f" else "%d" for k in names)
            if n:
                table = np.column_stack([columns[k].astype(np.float64) for k in names])
                np.savetxt(fh, table, fmt=fmt)
            for size, rows in groups:
                np.savetxt(fh, np.column_stack([np.full(len(rows), size), rows]), fmt="%d")
        else:
            vrec = np.empty(n, dtype=[(k, columns[k].dtype.newbyteorder("<")) for k in names])
            for k in names:
                vrec[k] = columns[k]
            fh.write(vrec.tobytes())
            for size, rows in groups:
                rec = np.empty(len(rows), dtype=[("n", "u1"), ("i", "<i4", (size,))])
                rec["n"] = size
                rec["i"] = rows
                fh.write(rec.tobytes())
    return path


def write_obj(
    path: str | os.PathLike,
    vertices: np.ndarray,
    faces: np.ndarray,
    *,
    force: bool = False,
    comments: tuple[str, ...] = (),
) -> Path:
    """Write an OBJ with polygon faces (quads stay quads); ``faces`` as in
    :func:`write_ply`."""
    path = Path(path)
    _refuse_overwrite(path, force)
    with open(path, "w") as fh:
        for c in comments:
            fh.write(f"# {c}\n")
        if len(vertices):
            np.savetxt(fh, vertices, fmt="v %.9g %.9g %.9g")
        for size, rows in _size_groups(faces):
            np.savetxt(fh, rows + 1, fmt="f" + " %d" * size)
    return path
