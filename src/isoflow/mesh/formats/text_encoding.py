"""How a text file written by a Windows tool is encoded, from its head.

Excel's "Unicode Text", Notepad's "Unicode" and PowerShell's ``>`` write
UTF-16, half of whose bytes are NUL, which a reader's test for binary
data takes it for. Behind its byte-order mark it is plainly UTF-16; some
tools write none, and then the NUL bytes in every other place tell the
byte order. The point-list reader (:mod:`isoflow.mesh.volumes`) and the
label-names reader (:mod:`isoflow.mesh.formats.label_names`) ask here,
each then checking what its own text must be.
"""

from __future__ import annotations

import codecs

#: how much of a file's head tells its encoding
HEAD_BYTES = 1024


def utf16_order(head: bytes) -> str | None:
    """The UTF-16 codec a file's first bytes ``head`` suggest, or None.

    ``"utf-16"`` where it opens with a UTF-16 byte-order mark (the codec
    reads the order from the mark and drops it); ``"utf-16-le"`` or
    ``"utf-16-be"`` where, without one, every other byte of the first
    :data:`HEAD_BYTES` is NUL in the high-byte places of that order and
    the other places are not all NUL (a run of NUL bytes is no text).
    A head of odd length is no UTF-16. The caller still checks that the
    text decodes, and is what it expects.

    Parameters
    ----------
    head : bytes
        The first bytes of the file (more than :data:`HEAD_BYTES` are
        not looked at).

    Returns
    -------
    str or None
        The codec's name, None where the head is not UTF-16 as above.

    Examples
    --------
    >>> utf16_order("1 liver\\n".encode("utf-16"))
    'utf-16'
    >>> utf16_order("1 liver\\n".encode("utf-16-le")), utf16_order("1 liver\\n".encode("utf-16-be"))
    ('utf-16-le', 'utf-16-be')
    >>> utf16_order(b"1 liver\\n") is None, utf16_order(bytes(8)) is None
    (True, True)
    """
    if head.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return "utf-16"
    head = head[:HEAD_BYTES]
    if len(head) < 2 or len(head) % 2:
        return None
    for encoding, low, high in (("utf-16-le", head[0::2], head[1::2]), ("utf-16-be", head[1::2], head[0::2])):
        if not high.strip(b"\0") and low.strip(b"\0"):
            return encoding
    return None
