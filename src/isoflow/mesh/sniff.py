"""What format a mesh file's first bytes say it holds, whatever its suffix.

Mesh readers go by the file's suffix: an OBJ file saved as ``model.stl``
is read as an STL and gives no triangles.  Where a read has failed,
:func:`sniff_mesh_format` looks at the first few kilobytes (and the
file's size, for a binary STL) so that the error can name the format the
content is in and the suffix to give it
(:func:`isoflow.mesh.load.reading_mesh`).  It is only asked after a
failure: reading a good file costs nothing more.
"""

from __future__ import annotations

import re

#: How many bytes from the start of a file :func:`sniff_mesh_format` needs.
SNIFF_BYTES = 4096

#: Each format :func:`sniff_mesh_format` tells apart: what its content
#: looks like, as an error message says it, and the suffix its readers
#: expect.
FORMATS: dict[str, tuple[str, str]] = {
    "obj": ("an OBJ file (lines 'v x y z' and 'f ...')", ".obj"),
    "ply": ("a PLY file (it starts with 'ply')", ".ply"),
    "off": ("an OFF file (its first word is OFF, COFF, NOFF or the like)", ".off"),
    "stl-ascii": ("an ASCII STL file ('solid' then 'facet' lines)", ".stl"),
    "stl-binary": ("a binary STL file (its size is 84 bytes plus 50 per facet its header counts)", ".stl"),
    "glb": ("a binary glTF file (it starts with 'glTF')", ".glb"),
    "gltf": ("a glTF JSON file (an object with \"asset\")", ".gltf"),
}

#: the words that files of these formats start with, by their specifications
#: (the other formats have none)
MAGIC_WORDS: dict[str, bytes] = {"glb": b"glTF", "ply": b"ply"}

_OFF = re.compile(rb"(ST)?C?N?4?n?OFF")  # the header keywords isoflow.mesh.off takes (and the n-D ones)
_OBJ_KEYS = frozenset((b"v", b"vt", b"vn", b"vp", b"f", b"l", b"p", b"o", b"g", b"s", b"usemtl", b"mtllib"))


def sniff_mesh_format(head: bytes, size: int | None = None) -> str:
    """The mesh format a file's first bytes say it holds, or ``""``.

    Cheap, and only as sure as the first bytes are: a binary glTF starts
    with ``glTF``, a PLY file with ``ply``, an OFF file's first word (after
    ``#`` comments) is ``OFF``, ``COFF``, ``NOFF``..., an ASCII STL starts
    with ``solid`` and names a ``facet`` within its first kilobyte, a glTF
    JSON file is an object that names its ``"asset"``, and an OBJ file's
    lines are ``v``, ``f``, ``vn``, ``#``, ``o``, ``g``, ``mtllib``... lines,
    with at least one ``v``.  A binary STL has no magic: it is told by its
    size, 84 bytes plus 50 for each of the facets its bytes 80 to 84 count
    (as readers tell it; a binary STL's header may itself start with
    ``solid``).

    Parameters
    ----------
    head : bytes
        The file's first bytes: :data:`SNIFF_BYTES` of them, or the whole
        file where it is shorter.
    size : int, optional
        The file's size in bytes; without it a binary STL is not told.

    Returns
    -------
    str
        A key of :data:`FORMATS` (``"obj"``, ``"ply"``, ``"off"``,
        ``"stl-ascii"``, ``"stl-binary"``, ``"glb"``, ``"gltf"``), or ``""``
        where the bytes are none of them.

    Examples
    --------
    >>> sniff_mesh_format(b"# a tetrahedron\\nv 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n")
    'obj'
    >>> sniff_mesh_format(b"ply\\nformat binary_little_endian 1.0\\n")
    'ply'
    >>> sniff_mesh_format(bytes(80) + (1).to_bytes(4, "little") + bytes(50), size=134)
    'stl-binary'
    >>> sniff_mesh_format(b"\\x00\\x01 not a mesh")
    ''
    """
    head = bytes(head[:SNIFF_BYTES])
    if head.startswith(MAGIC_WORDS["glb"]):
        return "glb"
    ply = MAGIC_WORDS["ply"]
    if head.startswith(ply) and head[len(ply):len(ply) + 1] in (b"\n", b"\r", b" ", b""):
        return "ply"
    if size is not None and size >= 134 and len(head) >= 84:
        n = int.from_bytes(head[80:84], "little")
        if n and size == 84 + 50 * n:
            return "stl-binary"
    text = head.removeprefix(b"\xef\xbb\xbf").lstrip()
    if text[:1] == b"{":
        return "gltf" if b'"asset"' in text else ""
    low = text[:1024].lower()
    if low.startswith(b"solid") and b"facet" in low:
        return "stl-ascii"
    lines = text.splitlines()
    if len(head) >= SNIFF_BYTES and len(lines) > 1:
        lines = lines[:-1]  # the last line may be cut short
    words = [w for w in (ln.split(b"#", 1)[0].split() for ln in lines) if w]
    if words and _OFF.fullmatch(words[0][0]):
        return "off"
    if words and all(w[0] in _OBJ_KEYS for w in words) and any(w[0] == b"v" for w in words):
        return "obj"
    return ""
