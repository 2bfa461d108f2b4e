"""Output paths, checked before any work is done.

Every command checks each file it will write (``-o``, ``--png``, ``--out``)
up front: a bad picture path must not be found after minutes of meshing,
and an existing file is never replaced without ``force``.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import IsoflowError


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
