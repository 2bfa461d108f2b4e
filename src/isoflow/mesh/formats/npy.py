"""NumPy ``.npy`` and ``.npz``: isoflow's own format.

The array's axes are isoflow's (axis 0 is x). An ``.npz`` written by isoflow
carries ``volume`` plus ``offset``, ``parity``, ``pitch`` (one number or one
per axis) and ``origin``, and ``unit``, their length unit (a string, where
one is given), and ``space``, their anatomical frame (``"LPS"``, where one
is known), so that it round-trips exactly, the lattice parity
of a flow's step included, and a label image's names as ``label_names``
(a string: JSON of label value to name). Any other ``.npz`` must hold one
array besides those fields (or one named ``volume``, or the one named as
``ARCHIVE.npz:NAME``), which they describe; ``spacing``, the voxel size's
name in scikit-image, SimpleITK and MONAI, is read as ``pitch``. A ``.npy``
holds the array alone.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...digital.frames import space_given
from ...digital.lattice import DigitalObject, checked_pitch
from ...errors import IsoflowError, coordinates
from .registry import RawVolume, content_hint, names_from_json, names_json, note, unit_field

#: the arrays of an ``.npz`` that describe its volume (isoflow writes them)
FIELDS = ("offset", "parity", "pitch", "origin", "unit", "space", "label_names")

#: the voxel size's name in scikit-image, SimpleITK and MONAI: read as the
#: pitch where the archive holds none (and refused beside one that differs)
SPACING = "spacing"


def read(path: Path, dataset: str | None = None) -> RawVolume:
    meta: dict = {}
    try:
        loaded = np.load(path, allow_pickle=False)
        # trust the content, not the name: an .npz may be called .npy or .NPZ
        if isinstance(loaded, np.lib.npyio.NpzFile):
            with loaded as z:
                names = list(z.files)
                if dataset is not None and dataset not in names:
                    raise IsoflowError(f"{path}: holds no array {dataset!r} (its arrays: {', '.join(names)})")
                volumes = [n for n in names if n not in FIELDS and n != SPACING]
                if dataset is not None:
                    name = dataset
                elif "volume" in names:
                    name = "volume"
                elif len(volumes) == 1 or len(names) == 1:
                    name = (volumes or names)[0]
                else:
                    raise IsoflowError(f"{path}: holds arrays {', '.join(names)}; name one as "
                                       f"{path}:{(volumes or names)[0]}, or save the volume as 'volume'")
                arr = _member(z, name, path)
                if name in volumes:  # a field named as the volume is read alone
                    meta = _fields(z, path, arr.ndim)
                unread = [n for n in volumes if n != name]
                if dataset is None and unread:  # (an affine, a voxel_size: the volume would be placed without it)
                    note(f"{path}: {'its array' if len(unread) == 1 else 'its arrays'} {', '.join(unread)} "
                         f"{'is' if len(unread) == 1 else 'are'} not read: the volume is 'volume', placed by its pitch "
                         f"(or {SPACING}), origin, offset and parity, where given")
        elif isinstance(loaded, np.ndarray):
            if dataset is not None:
                raise IsoflowError(f"{path}: a .npy holds one array; name none (:{dataset})")
            arr = loaded
        else:
            raise IsoflowError(f"{path}: not a numpy array or archive ({type(loaded).__name__})")
    except IsoflowError:
        raise
    except Exception as exc:  # numpy raises several types for a bad file
        head = _head(path)
        if not head.startswith((b"\x93NUMPY", b"PK", b"\x80")):
            # np.load takes any file but an .npy, an .npz or a pickle (b"\x80")
            # for a pickle too, and says to load it "unsafely", which no
            # damaged or foreign file calls for
            raise IsoflowError(f"{path}: not a numpy file: it " + (
                f"starts with {head!r}, not .npy's b'\\x93NUMPY' or an .npz's (zip) b'PK'" if head else "is empty")
                + content_hint(path, "NumPy")) from None
        if _holds_objects(path):
            raise IsoflowError(pickled_objects(path)) from None
        raise IsoflowError(f"{path}: not a readable numpy file ({exc.__class__.__name__}: {exc})") from None
    unit = unit_field(meta["unit"], f"{path}: array 'unit'") if "unit" in meta else None
    names = names_from_json(meta["label_names"], str(path), "array 'label_names'") if "label_names" in meta else None
    space = space_given(str(meta["space"]), f"{path}: array 'space'") if "space" in meta else None
    return RawVolume(arr, meta.get("pitch", 1.0), meta.get("origin"), meta.get("offset"), meta.get("parity", 0),
                     unit=unit, space=space, names=names)


def _fields(archive, path: Path, ndim: int) -> dict:
    """The fields of :data:`FIELDS` an ``.npz`` archive holds, its
    :data:`SPACING` as the pitch (a refusal of its value names it as the
    archive does); a spacing beside a pitch that differs refused."""
    meta = {key: _member(archive, key, path) for key in FIELDS if key in archive.files}
    if SPACING in archive.files:
        spacing = _member(archive, SPACING, path)
        # a 4D volume's (a time series', a channel axis') spacing may give its three axes in space, as its pitch may
        axes = 3 if ndim == 4 and np.size(spacing) == 3 else ndim
        try:
            size = np.broadcast_to(checked_pitch(spacing, axes, SPACING), axes)
            if "pitch" in meta and not np.array_equal(np.broadcast_to(checked_pitch(meta["pitch"], axes), axes), size):
                raise IsoflowError(f"holds both 'pitch' {coordinates(meta['pitch'])} and {SPACING!r} "
                                   f"{coordinates(spacing)}, two voxel sizes: keep one")
        except IsoflowError as exc:
            raise exc.at(path) from None
        meta.setdefault("pitch", spacing)
    return meta


def _member(archive, name: str, path: Path) -> np.ndarray:
    """The array ``name`` of an ``.npz`` archive; one of Python objects
    (``dtype=object``, a pickle inside the archive, which ``np.load``
    reads only with ``allow_pickle``) refused in one line naming it: it
    was numpy's "Object arrays cannot be loaded when allow_pickle=False",
    which names neither the array nor what to do."""
    try:
        return archive[name]
    except ValueError:
        if not _member_holds_objects(archive, name):
            raise
        raise IsoflowError(f"{path}: its array {name!r} holds Python objects (dtype object, a pickle), which isoflow "
                           "does not load; save it as an array of numbers and give that") from None


def _member_holds_objects(archive, name: str) -> bool:
    """Whether the ``.npy`` header of the array ``name`` of an ``.npz``
    says it holds Python objects."""
    try:
        with archive.zip.open(f"{name}.npy") as fh:
            header = _npy_header(fh)
    except (OSError, KeyError):
        return False
    return header is not None and header[2].hasobject


def _holds_objects(path: Path) -> bool:
    """Whether an ``.npy`` file's header says it holds Python objects
    (a pickle, which ``np.load`` reads only with ``allow_pickle``)."""
    header = _header(path)
    return header is not None and header[2].hasobject


def pickled_objects(path: Path) -> str:
    """The refusal of an ``.npy`` of Python objects (Cellpose's
    ``_seg.npy`` is a dict holding its ``masks``), which isoflow does not
    unpickle, with the line that saves its masks as an array in isoflow's
    axis order (x first: NumPy's (y, x) or (z, y, x) reversed).

    Parameters
    ----------
    path : pathlib.Path
        The file as given.

    Returns
    -------
    str
        One line.

    Examples
    --------
    >>> print(pickled_objects(Path("img_seg.npy")))
    img_seg.npy: holds Python objects (a pickle, such as Cellpose's _seg.npy, a dict with its 'masks'), which isoflow \
does not load; for a file you trust, save its masks as an array (x first) and give that: python -c 'import numpy as np; \
np.save("masks.npy", np.load("img_seg.npy", allow_pickle=True).item()["masks"].T)'
    """
    import json
    import shlex

    code = f'import numpy as np; np.save("masks.npy", np.load({json.dumps(str(path))}, allow_pickle=True).item()["masks"].T)'
    return (f"{path}: holds Python objects (a pickle, such as Cellpose's _seg.npy, a dict with its 'masks'), which "
            f"isoflow does not load; for a file you trust, save its masks as an array (x first) and give that: "
            f"python -c {shlex.quote(code)}")


def _head(path: Path) -> bytes:
    """The first bytes of a file (none where it cannot be read)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(8)
    except OSError:
        return b""


def voxel_count(path: Path) -> int | None:
    """The number of voxels of a ``.npy`` file from its header alone (None
    when the file is not a plain ``.npy``), so that a command can choose its
    path before reading the array."""
    header = _header(path)
    return None if header is None else int(np.prod(header[0], dtype=np.int64))


def _header(path: Path) -> tuple | None:
    """An ``.npy`` file's header, ``(shape, fortran_order, dtype)``, read
    alone; None for what is not a plain ``.npy``."""
    try:
        with open(path, "rb") as fh:
            return _npy_header(fh)
    except OSError:  # unreadable: the reader says what
        return None


def _npy_header(fh) -> tuple | None:
    """The header of the ``.npy`` stream open at its start in ``fh``
    (a file, or an array of an ``.npz``), as :func:`_header` gives it."""
    try:
        version = np.lib.format.read_magic(fh)
        header = {(1, 0): np.lib.format.read_array_header_1_0,
                  (2, 0): np.lib.format.read_array_header_2_0}.get(version)
        if header is None:  # (3.0: the same header in UTF-8; rare)
            return None
        return header(fh)
    except Exception:  # not an .npy (an .npz by another name, a bad file): the reader says what
        return None


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    if not path.name.lower().endswith(".npy"):
        return
    # only what this object holds beyond the defaults, with its value: a
    # label image has no lattice offset or parity to lose
    lost = [f"{name} {value}" for name, value, held in (
        ("pitch", coordinates(obj.spacing), np.any(obj.spacing != 1.0)),
        ("origin", coordinates(obj.origin, step=obj.spacing), obj.origin.any()),
        ("lattice offset", coordinates(obj.offset), any(obj.offset)),
        ("parity", str(obj.parity), obj.parity),
        ("unit", str(unit), unit is not None),
        ("anatomical frame", str(space), space is not None)) if held]
    if lost:
        note(f"{path}: a .npy holds the array alone; its {', '.join(lost)} {'is' if len(lost) == 1 else 'are'} "
             "not kept (use .npz to keep them)")


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    with open(path, "wb") as fh:
        if path.name.lower().endswith(".npy"):
            np.save(fh, obj.volume)
            return
        names = getattr(obj, "names", None)  # a label image's
        np.savez_compressed(
            fh,
            volume=obj.volume,
            offset=np.array(obj.offset, np.int64),
            parity=np.int64(obj.parity),
            pitch=np.asarray(obj.pitch, np.float64),
            origin=obj.origin,
            # a string array, which np.load reads without pickle
            **({} if unit is None else {"unit": np.str_(unit)}),
            **({} if space is None else {"space": np.str_(space)}),
            **({"label_names": np.str_(names_json(names))} if names else {}),
        )
