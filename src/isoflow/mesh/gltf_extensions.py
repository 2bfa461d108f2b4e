"""glTF extensions that change a model's geometry and that trimesh, the
reader of glTF and GLB files, does not apply.

``EXT_mesh_gpu_instancing`` draws a node's mesh once per row of its
instance transforms; trimesh reads the node's mesh once, so a file of three
instanced boxes would be voxelised and counted as one box.
``EXT_meshopt_compression`` (and its ``KHR_`` successor) stores buffer
views compressed; trimesh reads the compressed bytes as if they were the
data.  A file that uses either is refused in one line naming the node or
extension, rather than read as another model; so is a primitive drawn
as a triangle fan (mode 6), which trimesh's reader skips (a model read
without those faces; :func:`skipped_primitive`), a file whose primitives
are all points or lines, of no face (:func:`faceless_model`), and a
``.gltf`` whose
buffer file is not beside it (:func:`missing_buffer`: trimesh's error is
"FileNotFoundError: model.bin", no more); :func:`gltf_refusal` says
either, the file's JSON read once.  Points and lines beside triangles,
which trimesh leaves out of the mesh, are named in a note
(:func:`faceless_note`, in the words of :func:`read_without`, which
names an OBJ's ``l`` lines and a PLY's edges beside faces too).  The file's JSON is looked at only (a GLB's
first chunk), never its buffers.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path
from urllib.parse import unquote

from ..errors import some_of

#: buffer-view compression that trimesh reads as if it were the data
COMPRESSIONS = ("EXT_meshopt_compression", "KHR_meshopt_compression")
#: the GLB header (magic, version, length) and the first chunk's (length, type)
_GLB_HEAD = struct.Struct("<4sII")
_CHUNK_HEAD = struct.Struct("<I4s")


def gltf_json(path: Path) -> dict | None:
    """The JSON of a ``.gltf`` file or of a ``.glb`` file's first chunk, or
    None where the file is neither (its reader then says what is wrong).

    Parameters
    ----------
    path : pathlib.Path
        A ``.gltf`` or ``.glb`` file.

    Returns
    -------
    dict or None
        The parsed JSON object.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "a.gltf"
    >>> _ = p.write_text('{"asset": {"version": "2.0"}}')
    >>> gltf_json(p)
    {'asset': {'version': '2.0'}}
    """
    try:
        with open(path, "rb") as fh:
            if path.suffix.lower() != ".glb":
                return json_of(fh.read(), glb=False)
            head = fh.read(_GLB_HEAD.size + _CHUNK_HEAD.size)
            if len(head) < _GLB_HEAD.size + _CHUNK_HEAD.size:
                return None
            length, _ = _CHUNK_HEAD.unpack_from(head, _GLB_HEAD.size)
            return json_of(head + fh.read(length), glb=True)
    except OSError:
        return None


def json_of(data: bytes, glb: bool) -> dict | None:
    """The JSON of a glTF file's bytes (a GLB's first chunk where ``glb``),
    or None where they hold none (the reader then says what is wrong).

    Parameters
    ----------
    data : bytes
        The file's bytes (of a GLB, at least its headers and first chunk).
    glb : bool
        Whether they are a GLB file's.

    Returns
    -------
    dict or None
        The parsed JSON object.

    Examples
    --------
    >>> json_of(b'{"asset": {"version": "2.0"}}', glb=False)
    {'asset': {'version': '2.0'}}
    >>> json_of(b"solid cube", glb=True) is None
    True
    """
    try:
        if glb:
            magic, _, _ = _GLB_HEAD.unpack_from(data)
            length, kind = _CHUNK_HEAD.unpack_from(data, _GLB_HEAD.size)
            if magic != b"glTF" or kind != b"JSON":
                return None
            data = data[_GLB_HEAD.size + _CHUNK_HEAD.size:_GLB_HEAD.size + _CHUNK_HEAD.size + length]
        tree = json.loads(data)
    except (struct.error, ValueError):
        return None
    return tree if isinstance(tree, dict) else None


def gltf_refusal(path: Path, tree: dict | None) -> str | None:
    """The one line refusing a glTF or GLB file that trimesh would read as
    another model (:func:`unapplied_in`), or a ``.gltf`` whose buffer file
    is not there (:func:`missing_buffer`), or None; from the file's JSON,
    read once (:func:`gltf_json`) for these and for the note of what
    trimesh leaves out (:func:`faceless_note`).

    Parameters
    ----------
    path : pathlib.Path
        The ``.gltf`` or ``.glb`` file.
    tree : dict or None
        Its JSON (:func:`gltf_json`); None where the file holds none (its
        reader then says what is wrong): no refusal here.

    Returns
    -------
    str or None
        ``PATH: node 0 draws its mesh 3 times by the glTF extension
        EXT_mesh_gpu_instancing, ...``.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "a.gltf"
    >>> node = {"mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 0}}}}
    >>> print(gltf_refusal(p, {"nodes": [node], "accessors": [{"count": 3}]}).replace(str(p), "a.gltf"))
    ... # doctest: +ELLIPSIS
    a.gltf: node 0 draws its mesh 3 times by the glTF extension EXT_mesh_gpu_instancing, which ...
    >>> tree = {"buffers": [{"uri": "a.bin", "byteLength": 4}]}
    >>> print(gltf_refusal(p, tree).replace(str(p.parent), "DIR"))  # doctest: +ELLIPSIS
    DIR/a.gltf: buffer 0 is the file 'a.bin', which is not there (DIR/a.bin); ...
    >>> gltf_refusal(Path("a.glb"), {"meshes": [{"primitives": [{"mode": 1}]}]})[:50]
    'a.glb: no triangles read: its primitives are lines'
    >>> gltf_refusal(Path("a.glb"), None) is None
    True
    """
    if tree is None:
        return None
    return unapplied_in(tree, str(path)) or (missing_buffer(path, tree) if path.suffix.lower() == ".gltf" else None)


def unapplied_in(tree: dict, where: str) -> str | None:
    """:func:`gltf_refusal`'s checks of the extensions, the fans and the
    primitives of no face, on a glTF file's JSON (an archive's member, named ``where``).

    Parameters
    ----------
    tree : dict
        The file's JSON (:func:`json_of`).
    where : str
        The file as the line names it (``ARCHIVE:MEMBER``).

    Returns
    -------
    str or None
        The refusal, or None.

    Examples
    --------
    >>> unapplied_in({"extensionsUsed": ["EXT_meshopt_compression"]}, "m.zip:a.glb")[:67]
    'm.zip:a.glb: its buffers are compressed by the glTF extension EXT_m'
    """
    used = [name for name in COMPRESSIONS if name in _names(tree.get("extensionsUsed"))]
    if used:
        return (f"{where}: its buffers are compressed by the glTF extension {used[0]}, which isoflow's reader "
                "(trimesh) does not decompress: it would read the compressed bytes as the model; export it "
                "without meshopt compression (gltfpack without -c, Blender's glTF exporter)")
    for index, node in enumerate(_list(tree.get("nodes"))):
        instances = _instances(node, tree)
        if instances is not None:
            return (f"{where}: node {index} draws its mesh {instances} times by the glTF extension "
                    "EXT_mesh_gpu_instancing, which isoflow's reader (trimesh) does not apply: it would read "
                    "one copy; export the model with each instance as a node of its own (Blender: "
                    "Realize Instances before the glTF export)")
    return skipped_primitive(where, tree) or faceless_model(where, tree)


#: glTF's primitive mode of triangle fans, which trimesh's reader skips
#: (it reads points, lines, triangles and triangle strips)
TRIANGLE_FAN = 6


def skipped_primitive(where: str | Path, tree: dict) -> str | None:
    """The one line refusing a glTF file with a primitive that holds faces
    trimesh's reader skips (a triangle fan: it reads the other primitives
    and says nothing, so the model lacks those faces), or None.

    Parameters
    ----------
    where : str or pathlib.Path
        The file, as the line names it.
    tree : dict
        Its JSON (:func:`json_of`).

    Returns
    -------
    str or None
        ``PATH: mesh 0 ('fan') primitive 0 is drawn as a triangle fan ...``.

    Examples
    --------
    >>> tree = {"meshes": [{"name": "cap", "primitives": [{"mode": 4}, {"mode": 6}]}]}
    >>> print(skipped_primitive(Path("a.glb"), tree))  # doctest: +ELLIPSIS
    a.glb: mesh 0 ('cap') primitive 1 is drawn as a triangle fan (glTF mode 6), which ...
    >>> skipped_primitive(Path("a.glb"), {"meshes": [{"primitives": [{}]}]}) is None  # mode 4 by default
    True
    """
    fans = [(index, at, name) for index, at, name, mode in _modes(tree) if mode == TRIANGLE_FAN]
    if not fans:
        return None
    named = some_of((f"mesh {index}{_named(name)} primitive {at}" for index, at, name in fans), shown=1)
    drawn = "is drawn as a triangle fan" if len(fans) == 1 else "are drawn as triangle fans"
    return (f"{where}: {named} {drawn} (glTF mode 6), which isoflow's reader (trimesh) skips: the model would be "
            "read without its faces; export it with triangles (mode 4, the default of Blender's and most exporters)")


#: glTF's primitive modes of no face (points, lines, line loops, line
#: strips), which trimesh reads as a point cloud or a path, not as the mesh
FACELESS = {0: "points", 1: "lines", 2: "lines", 3: "lines"}
#: the modes of faces: triangles (the default), strips, fans
_FACES = (4, 5, TRIANGLE_FAN)


def _modes(tree: dict) -> list[tuple[int, int, object, object]]:
    """``(mesh, primitive, name, mode)`` of each primitive of a glTF
    file's meshes, a mode left out being triangles (4)."""
    found = []
    for index, mesh in enumerate(_list(tree.get("meshes"))):
        primitives = _list(mesh.get("primitives")) if isinstance(mesh, dict) else []
        for at, primitive in enumerate(primitives):
            if isinstance(primitive, dict):
                found.append((index, at, mesh.get("name"), primitive.get("mode", 4)))
    return found


def _named(name: object) -> str:
    """`` ('NAME')`` of a mesh's name, as a line names it after its index;
    nothing where the mesh has none."""
    return f" ({name!r})" if isinstance(name, str) and name else ""


def _kinds(modes: list[int]) -> str:
    """The kinds of faceless primitives ``modes`` are, with their modes:
    ``lines (glTF mode 1)``, ``lines (glTF modes 1, 3) and points (glTF
    mode 0)``."""
    said = []
    for kind in ("lines", "points"):
        of = sorted({m for m in modes if FACELESS.get(m) == kind})
        if of:
            said.append(f"{kind} (glTF mode{'s' if len(of) > 1 else ''} {', '.join(map(str, of))})")
    return " and ".join(said)


def faceless_model(where: str | Path, tree: dict) -> str | None:
    """The one line refusing a glTF file whose primitives are lines (and
    points), none of faces: trimesh reads them as a path, and the mesh
    asked for has no triangle.  A file of points alone is None here: the
    reader's point-cloud line says how many it holds.

    Parameters
    ----------
    where : str or pathlib.Path
        The file, as the line names it.
    tree : dict
        Its JSON (:func:`json_of`).

    Returns
    -------
    str or None
        ``PATH: no triangles read: its primitives are lines (glTF mode
        2), not triangles: ...``.

    Examples
    --------
    >>> tree = {"meshes": [{"primitives": [{"mode": 2}, {"mode": 0}]}]}
    >>> print(faceless_model("edges.gltf", tree))  # doctest: +ELLIPSIS
    edges.gltf: no triangles read: its primitives are lines (glTF mode 2) and points (glTF mode 0), not ...
    >>> faceless_model("a.gltf", {"meshes": [{"primitives": [{"mode": 1}, {}]}]}) is None  # triangles too
    True
    """
    modes = [mode for *_, mode in _modes(tree)]
    if not modes or not all(m in FACELESS for m in modes) or all(FACELESS[m] == "points" for m in modes):
        return None
    return (f"{where}: no triangles read: its primitives are {_kinds(modes)}, not triangles: they bound no "
            "solid, and there is nothing to voxelise; export the model's faces (a mesh of triangles), not its "
            "edges or curves")


def faceless_note(where: str | Path, tree: dict) -> str | None:
    """The note naming the primitives of points or lines of a glTF file
    that also has faces: trimesh reads the faces as the mesh and leaves
    those out, without a word; they bound no solid, so the model is read
    whole.  None where there is no such primitive, or no face.

    Parameters
    ----------
    where : str or pathlib.Path
        The file, as the note names it.
    tree : dict
        Its JSON (:func:`json_of`).

    Returns
    -------
    str or None
        ``PATH: read without mesh 0 ('box') primitive 1, drawn as lines
        (glTF mode 1): it holds no face and bounds no solid``.

    Examples
    --------
    >>> tree = {"meshes": [{"name": "box", "primitives": [{}, {"mode": 1}, {"mode": 3}]}]}
    >>> print(faceless_note("a.glb", tree))  # doctest: +ELLIPSIS
    a.glb: read without 2 primitives of lines (glTF modes 1, 3), mesh 0 ('box') primitive 1 the first: they ...
    >>> faceless_note("a.glb", {"meshes": [{"primitives": [{}]}]}) is None
    True
    """
    found = _modes(tree)
    skipped = [(index, at, name, mode) for index, at, name, mode in found if mode in FACELESS]
    if not skipped or not any(mode in _FACES for *_, mode in found):
        return None
    index, at, name, mode = skipped[0]
    named = _named(name)
    if len(skipped) == 1:
        return read_without(where, f"mesh {index}{named} primitive {at}, drawn as {_kinds([mode])}", 1)
    return read_without(where, f"{len(skipped)} primitives of {_kinds([m for *_, m in skipped])}, mesh "
                               f"{index}{named} primitive {at} the first", len(skipped))


def read_without(where: str | Path, what: str, count: int) -> str:
    """The note naming what a mesh file holds beside its faces that its
    reader leaves out without a word: primitives of points or lines of a
    glTF file (:func:`faceless_note`), an OBJ's ``l`` lines, a PLY's
    ``edge`` element. They hold no face and bound no solid, so the model
    is read whole; the note says what was not read.

    Parameters
    ----------
    where : str or pathlib.Path
        The file, as the note names it.
    what : str
        What was left out, in words.
    count : int
        How many things ``what`` names: one is said in the singular.

    Returns
    -------
    str

    Examples
    --------
    >>> read_without("cage.ply", "its 18 edges (the PLY edge element)", 18)
    'cage.ply: read without its 18 edges (the PLY edge element): they hold no face and bound no solid'
    """
    held = "it holds no face and bounds" if count == 1 else "they hold no face and bound"
    return f"{where}: read without {what}: {held} no solid"


def missing_buffer(path: Path, tree: dict) -> str | None:
    """The one line refusing a ``.gltf`` file whose buffer names a file
    that is not there, or None (images are not looked at: a model reads
    without its textures).

    Parameters
    ----------
    path : pathlib.Path
        The ``.gltf`` file, beside which its buffer files are.
    tree : dict
        Its JSON (:func:`gltf_json`).

    Returns
    -------
    str or None
        ``PATH: buffer 0 is the file 'model.bin', which is not there
        (DIR/model.bin); ...``.

    Examples
    --------
    >>> tree = {"buffers": [{"uri": "data:application/octet-stream;base64,AAAA"}]}
    >>> missing_buffer(Path("a.gltf"), tree) is None  # a buffer held in the file itself
    True
    """
    for index, buffer in enumerate(_list(tree.get("buffers"))):
        uri = buffer.get("uri") if isinstance(buffer, dict) else None
        if not isinstance(uri, str) or uri.startswith("data:"):
            continue
        where = path.parent / unquote(uri)
        if not where.is_file():
            return (f"{path}: buffer {index} is the file {uri!r}, which is not there ({where}); a glTF file "
                    "needs its .bin beside it (copy it too, or export a single .glb)")
    return None


def _instances(node: object, tree: dict) -> int | str | None:
    """How many times ``node`` draws its mesh by EXT_mesh_gpu_instancing
    (the count of its first attribute's accessor, or "several" where the
    file does not say), or None where it does not use the extension."""
    ext = node.get("extensions") if isinstance(node, dict) else None
    inst = ext.get("EXT_mesh_gpu_instancing") if isinstance(ext, dict) else None
    if not isinstance(inst, dict):
        return None
    attributes = inst.get("attributes")
    accessors = _list(tree.get("accessors"))
    for index in (attributes.values() if isinstance(attributes, dict) else ()):
        if isinstance(index, int) and 0 <= index < len(accessors) and isinstance(accessors[index], dict):
            count = accessors[index].get("count")
            if isinstance(count, int):
                return count
    return "several"


def _list(value: object) -> list:
    """``value`` where it is a list, else an empty one (a file's JSON is
    not trusted to hold the types the specification names)."""
    return value if isinstance(value, list) else []


def _names(value: object) -> list[str]:
    """The strings of a list of extension names."""
    return [v for v in _list(value) if isinstance(v, str)]
