"""The length unit a mesh file declares, for the volume voxelised from it.

Most mesh formats (STL, OBJ, PLY, OFF) hold bare numbers. Three say what
they are in: a 3MF model's ``unit`` attribute (``micron``, ``millimeter``,
``centimeter``, ``inch``, ``foot``, ``meter``; millimetres where it is left
out, by the 3MF core specification), glTF, whose distances are metres by
its specification, and COLLADA, whose document ``<asset>`` gives its unit
as metres per unit (``<unit meter="0.001" name="millimeter"/>``; metres
where it is left out, by the COLLADA specification's default of 1.0), as
trimesh's reader takes it (trimesh's ``Scene.units`` says the same of all
three: ``0.001 * meters``).
A pitch given for such a mesh is in that unit, and so are the volume's
voxel size and origin: a volume written without it reads back as a
number of no unit, which a NIfTI reader then takes for millimetres.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import IO

from ..digital.units import LENGTH_UNITS, PICOMETRES, length_unit
from ..errors import IsoflowError

# the glTF 2.0 specification, "Coordinate System and Units": "The units
# for all linear distances are meters."
GLTF_UNIT = "m"
# the 3MF core specification: the model's unit attribute, "millimeter" by default
THREEMF_DEFAULT = "millimeter"


def declared_unit(path: str | os.PathLike) -> str | None:
    """The length unit a mesh file declares for its coordinates, or None.

    Parameters
    ----------
    path : str or Path
        A mesh file (any format trimesh reads).

    Returns
    -------
    str or None
        In isoflow's spelling (:func:`~isoflow.digital.units.length_unit`):
        ``"m"`` for a glTF or GLB file (but isoflow's own, which holds its
        volume's numbers: None), a 3MF model's ``unit`` (``"mm"``
        where it gives none), a COLLADA file's (DAE, or the first DAE of a
        ZAE: :func:`collada_unit`); None for a format that holds no unit
        (STL, OBJ, PLY, OFF, ...) and for a 3MF or COLLADA file that cannot
        be read here (the mesh reader then says why).

    Examples
    --------
    >>> import pathlib, tempfile, trimesh
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = trimesh.creation.box().export(folder / "box.3mf")
    >>> declared_unit(folder / "box.3mf"), declared_unit(folder / "box.stl")
    ('mm', None)
    """
    suffix = Path(path).suffix.lower()
    if suffix in (".glb", ".gltf"):
        # isoflow's own glTF holds the volume's numbers as they are (a
        # surface of a volume in mm holds mm), so it declares no unit
        return None if gltf_generator(Path(path)) == "isoflow" else GLTF_UNIT
    if suffix == ".3mf":
        return threemf_unit(Path(path))
    if suffix in (".dae", ".zae"):
        return collada_unit(Path(path))
    return None


def gltf_generator(path: Path) -> str | None:
    """The ``asset.generator`` of a glTF file (binary or text), None where
    it gives none or cannot be read here (the mesh reader then says why).

    Examples
    --------
    >>> import pathlib, tempfile, trimesh
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "box.glb"
    >>> _ = trimesh.creation.box().export(path)
    >>> gltf_generator(path).endswith("github.com/mikedh/trimesh")
    True
    """
    import json

    from .glb_geometry import GLB_HEAD

    try:
        with open(path, "rb") as fh:
            head = fh.read(GLB_HEAD.size)
            if len(head) == GLB_HEAD.size and head[:4] == b"glTF":  # binary: the JSON chunk first
                _, _, _, json_length, kind = GLB_HEAD.unpack(head)
                tree = json.loads(fh.read(json_length)) if kind == b"JSON" else {}
            else:  # a .gltf: the file is the JSON
                tree = json.loads(head + fh.read())
        generator = tree["asset"].get("generator")
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None
    return generator if isinstance(generator, str) else None


def threemf_unit(path: Path) -> str | None:
    """A 3MF package's model unit, read from the root element of its model
    part alone (the mesh itself is trimesh's to read)."""
    try:
        with zipfile.ZipFile(path) as package:
            part = model_part(package)
            if part is None:
                return None
            with package.open(part) as stream:
                for _, element in ET.iterparse(stream, events=("start",)):
                    unit = length_unit(element.get("unit", THREEMF_DEFAULT))
                    # a DigitalObject holds one of isoflow's length units or none
                    return unit if unit in LENGTH_UNITS else None
    except (OSError, zipfile.BadZipFile, ET.ParseError, KeyError):
        return None
    return None


def collada_unit(path: Path) -> str | None:
    """A COLLADA file's unit: the ``meter`` of the ``<unit>`` in the
    document's own ``<asset>`` (metres where it gives none, the COLLADA
    specification's default, as trimesh reads it) as the one of isoflow's
    length units of that many metres, None where it is none of them or the
    file cannot be read here (the mesh reader then says why). A ZAE's is
    its first DAE member's, the one trimesh reads.

    Parameters
    ----------
    path : Path
        A ``.dae`` or ``.zae`` file.

    Returns
    -------
    str or None

    Examples
    --------
    >>> import pathlib, tempfile, trimesh
    >>> data = trimesh.exchange.dae.export_collada(trimesh.creation.box())
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "box.dae"
    >>> _ = path.write_bytes(data.replace(b"<up_axis>", b'<unit meter="0.0254" name="inch"/><up_axis>'))
    >>> collada_unit(path), collada_unit(path.with_name("absent.dae"))
    ('in', None)
    """
    try:
        if path.suffix.lower() == ".zae":
            with zipfile.ZipFile(path) as package:
                member = next((n for n in package.namelist() if n.lower().endswith(".dae")), None)
                if member is None:
                    return None
                with package.open(member) as stream:
                    meter = _collada_meter(stream)
        else:
            with open(path, "rb") as stream:
                meter = _collada_meter(stream)
    except (OSError, zipfile.BadZipFile, ET.ParseError, ValueError):
        return None
    # the unit of that many metres (the names files give, "millimeter", "inch", vary; the number is the unit)
    return next((unit for unit, pm in PICOMETRES.items() if math.isclose(pm * 1e-12, meter, rel_tol=1e-9)), None)


def _collada_meter(stream: IO[bytes]) -> float:
    """Metres per unit of a COLLADA document: its ``<asset>``'s ``<unit
    meter>``, 1.0 where it gives none (only the document's own asset is
    read: a node's or a geometry's may say other things of theirs)."""
    depth, meter = 0, 1.0
    for event, element in ET.iterparse(stream, events=("start", "end")):
        local = element.tag.rsplit("}", 1)[-1]
        depth += 1 if event == "start" else -1
        if event == "start" and depth == 3 and local == "unit":
            meter = float(element.get("meter", "1.0"))
        elif event == "end" and depth == 1 and local == "asset":  # the document's asset is over
            break
        elif event == "start" and depth == 2 and local != "asset":  # no asset first: none (the schema puts it first)
            break
    if not (math.isfinite(meter) and meter > 0):
        raise ValueError(f"unit meter {meter}")
    return meter


def model_part(package: zipfile.ZipFile) -> str | None:
    """The 3MF model part: the one the package's relationships name as the
    3D model, else the only ``.model`` member (as a writer that leaves out
    the relationship still names its part)."""
    names = package.namelist()
    if "_rels/.rels" in names:
        with package.open("_rels/.rels") as stream:
            for _, element in ET.iterparse(stream, events=("start",)):
                if element.tag.endswith("Relationship") and element.get("Type", "").endswith("/3dmodel"):
                    target = element.get("Target", "").lstrip("/")
                    if target in names:
                        return target
    models = [n for n in names if n.lower().endswith(".model")]
    return models[0] if len(models) == 1 else None


def declared_units(meshes) -> list[str | None]:
    """Each mesh's declared unit (:func:`declared_unit`; each file read
    once), None for arrays and trimesh objects.

    Parameters
    ----------
    meshes : sequence
        Mesh files, arrays or trimesh objects.

    Returns
    -------
    list of (str or None)

    Examples
    --------
    >>> declared_units(["car.glb", "part.stl"])
    ['m', None]
    """
    return [declared_unit(m) if isinstance(m, (str, os.PathLike)) else None for m in meshes]


def common_unit(names: list[str], units: list[str | None]) -> str | None:
    """The one unit of meshes laid on one grid (``units``, each mesh's, by
    :func:`declared_units`, or the unit a :class:`~isoflow.mesh.bodies.Body`
    carries): the unit where every mesh has the same, None where any has
    none (an array, an STL); meshes of different units are refused, as one
    grid places them all by their numbers.

    Parameters
    ----------
    names : list of str
        Each mesh's name, for the refusal.
    units : list of (str or None)
        Each mesh's unit.

    Returns
    -------
    str or None

    Raises
    ------
    IsoflowError
        Two meshes have different units, each named with its unit.

    Examples
    --------
    >>> common_unit(["a.3mf", "b.3mf"], ["mm", "mm"]), common_unit(["a.3mf", "b.stl"], ["mm", None])
    ('mm', None)
    """
    known = set(units) - {None}
    if len(known) > 1:
        said = ", ".join(f"{name} in {unit}" for name, unit in zip(names, units) if unit is not None)
        raise IsoflowError(f"the meshes declare different length units ({said}), and one grid places them by their "
                           "numbers; scale them to one unit first")
    return known.pop() if known and None not in units else None
