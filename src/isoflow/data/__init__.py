"""Sample meshes and point lists that ship with isoflow (like ``skimage.data``).

Each function returns the path of a file installed with the package, ready
for :func:`isoflow.voxelize_file`, :func:`isoflow.verify_genus`,
:func:`isoflow.read_object` or the ``isoflow`` command. The files are
byte-identical copies of public files; :func:`info` gives each one's source,
licence and topology (``manifest.json``), and ``README.md`` beside them says
the same as a table.

In a source checkout the files are the repository's ``meshes/`` folder; a
wheel installs that folder as ``isoflow/data/meshes``.

Examples
--------
>>> from isoflow import data
>>> data.bob().name
'bob_small.ply'
>>> data.info("bob_small.ply")["genus"]
1
>>> "torus.obj" in data.names()
True
"""

from __future__ import annotations

import copy
import functools
import json
from pathlib import Path
from typing import Any

from ..errors import IsoflowError, value_kind

__all__ = ["bob", "eight", "example19", "folder", "info", "names", "path", "spot", "torus"]


def _named(name: object) -> str:
    """A sample's name as a message says it: a str by its repr, anything
    else as no name, by its type (and shape: an array's repr is many lines)."""
    return repr(name) if isinstance(name, str) else f"name must be a str, got {value_kind(name)}"


@functools.cache
def folder() -> Path:
    """The folder that holds the sample files.

    Returns
    -------
    pathlib.Path
        ``isoflow/data/meshes`` in an installed package, the repository's
        ``meshes/`` in a source checkout.

    Raises
    ------
    IsoflowError
        If neither holds the samples' ``manifest.json`` (a package built
        without its data).

    Examples
    --------
    >>> from isoflow import data
    >>> (data.folder() / "manifest.json").is_file()
    True
    """
    here = Path(__file__).resolve().parent
    # a wheel puts the files beside this module; a checkout keeps them at
    # the repository's top (src/isoflow/data -> three levels up)
    for candidate in (here / "meshes", here.parents[2] / "meshes"):
        if (candidate / "manifest.json").is_file():
            return candidate
    raise IsoflowError(f"{here / 'meshes'}: the sample files are missing (reinstall isoflow)")


def names() -> tuple[str, ...]:
    """Every sample file's name, sorted.

    Returns
    -------
    tuple of str
        The meshes of :func:`info` and the point list ``example19.txt``.

    Examples
    --------
    >>> from isoflow import data
    >>> data.names()[:3]
    ('bob_small.ply', 'cube_no_bottom.obj', 'eight.off')
    """
    return tuple(sorted((*_manifest(), "example19.txt"), key=str.lower))


def path(name: str) -> Path:
    """The path of one sample file.

    Parameters
    ----------
    name : str
        A name from :func:`names`, such as ``"bob_small.ply"``.

    Returns
    -------
    pathlib.Path
        The installed file.

    Raises
    ------
    IsoflowError
        If ``name`` is not a sample's name (the message lists them).

    Examples
    --------
    >>> from isoflow import data
    >>> data.path("eight.off").suffix
    '.off'
    """
    if not isinstance(name, str) or name not in names():  # (an array's ``in`` raised NumPy's ambiguous truth value)
        raise IsoflowError(f"{_named(name)}: no such sample file; the samples are {', '.join(names())}")
    return folder() / name


def info(name: str) -> dict[str, Any]:
    """What is known of a sample mesh: source, licence and topology.

    Parameters
    ----------
    name : str
        A mesh's name from :func:`names` (``example19.txt`` is a point list,
        described in the samples' README).

    Returns
    -------
    dict
        The mesh's entry in ``manifest.json``: ``source_url``,
        ``model_license``, ``sha256``, ``components``, ``genus`` (``None``
        for an open mesh), ``watertight``, ``boundary_edges`` and what
        trimesh, manifold3d, pymeshlab and scikit-image measured of it;
        each call's own copy.

    Raises
    ------
    IsoflowError
        If ``name`` is not a sample mesh.

    Examples
    --------
    >>> from isoflow import data
    >>> entry = data.info("eight.off")
    >>> entry["genus"], entry["components"], entry["watertight"]
    (2, 1, True)
    """
    meshes = _manifest()
    if not isinstance(name, str) or name not in meshes:  # (an array or a list is no key: TypeError)
        raise IsoflowError(f"{_named(name)}: no such sample mesh; the meshes are {', '.join(sorted(meshes))}")
    # a deep copy: the entry's dicts and lists are the cached manifest's,
    # which a caller's edit would change for every later call
    return copy.deepcopy(meshes[name])


@functools.cache
def _manifest() -> dict[str, dict[str, Any]]:
    entries = json.loads((folder() / "manifest.json").read_text())["meshes"]
    return {e["filename"]: e for e in entries}


def bob() -> Path:
    """Keenan Crane's "Bob", a closed genus-1 triangle mesh (PLY, 10 kB; CC0).

    Returns
    -------
    pathlib.Path
        ``bob_small.ply``.

    Examples
    --------
    >>> import isoflow
    >>> from isoflow import data
    >>> solid = isoflow.voxelize_file(data.bob(), resolution=24)
    >>> isoflow.betti_numbers(solid.volume, 6)
    [1, 1, 0]
    """
    return path("bob_small.ply")


def spot() -> Path:
    """Keenan Crane's cow "Spot", a closed genus-0 triangle mesh (PLY; CC0).

    Returns
    -------
    pathlib.Path
        ``spot.ply``.

    Examples
    --------
    >>> from isoflow import data
    >>> data.spot().name, data.info("spot.ply")["genus"]
    ('spot.ply', 0)
    """
    return path("spot.ply")


def torus() -> Path:
    """A closed torus, genus 1 (OBJ; Oded Stein's meshes, CC BY 4.0).

    Returns
    -------
    pathlib.Path
        ``torus.obj``.

    Examples
    --------
    >>> from isoflow import data
    >>> data.torus().name, data.info("torus.obj")["genus"]
    ('torus.obj', 1)
    """
    return path("torus.obj")


def eight() -> Path:
    """The classic "eight", a closed genus-2 surface (OFF; MIT).

    Returns
    -------
    pathlib.Path
        ``eight.off``.

    Examples
    --------
    >>> from isoflow import data
    >>> data.eight().name, data.info("eight.off")["genus"]
    ('eight.off', 2)
    """
    return path("eight.off")


def example19() -> Path:
    """The paper's Example 19 (eq. 5.19): 20 lattice points, four unit cubes.

    Read with the point model (Definitions 1-2), the points are the corners
    of a corner cube and its three face neighbours; the digital curvature
    flow takes them to the cube centred at (1, 1, 1), then to that point.

    Returns
    -------
    pathlib.Path
        ``example19.txt``, a text point list (``x y z`` per line).

    Examples
    --------
    >>> import isoflow
    >>> from isoflow import data
    >>> int(isoflow.read_object(data.example19()).volume.sum())
    4
    """
    return path("example19.txt")
