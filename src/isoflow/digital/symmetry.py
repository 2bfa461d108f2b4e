"""The symmetries of the n-cube, on octant bits, on configurations and on images.

The ``2^n n!`` symmetries (every axis permutation with every set of
reflections: 2, 8, 48, 384 for n = 1..4) act on the window of a vertex by
permuting its cells, so on its configurations; the paper's classes are
their orbits (section 4: nine well-composed boundary classes in 3D).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, given_text, whole_given
from .configurations import check_dimension, octants, read_only


@dataclass(frozen=True)
class CubeGroup:
    """The ``2^n n!`` symmetries of the n-cube (all arrays read-only).

    Element ``g`` is the axis permutation ``axis_permutations[g]`` (``p``)
    and the reflections ``flips[g]`` (``f``); it maps image ``X`` to
    ``np.transpose(np.flip(X, axes where f), p)`` (:func:`apply_symmetry`).
    On window offsets it sends ``d`` to ``e`` with ``e_j = d_{p_j} xor
    f_{p_j}``, i.e. octant bit ``b`` to ``bit_permutations[g, b]``, and the
    configuration ``c`` of a vertex of ``X`` to the configuration
    ``configuration_permutations[g, c]`` of the corresponding vertex of the
    transformed image. Element 0 is the identity.
    """

    n: int
    axis_permutations: np.ndarray  # (G, n) int8
    flips: np.ndarray  # (G, n) bool
    bit_permutations: np.ndarray  # (G, 2^n) int16
    configuration_permutations: np.ndarray  # (G, 2^(2^n)) uint8 / uint16

    def __len__(self) -> int:
        return len(self.axis_permutations)


@cache
def hyperoctahedral_group(n: int) -> CubeGroup:
    """The symmetries of the n-cube on octant bits and on configurations.

    Generated as every axis permutation (``n!``) combined with every set of
    reflections (``2^n``): 2, 8, 48, 384 elements for n = 1..4. The induced
    action on the ``2^(2^n)`` configurations is vectorised: a configuration
    is split into bytes and each byte's image is looked up in a (G, 256)
    table, so the (384, 65536) table of 4D costs two gathers.
    """
    n = check_dimension(n)
    d = octants(n).astype(np.int64)
    weights = 1 << np.arange(n)
    perms, flips, bitperms = [], [], []
    for p in itertools.permutations(range(n)):
        p = np.array(p)
        for f in itertools.product((0, 1), repeat=n):
            f = np.array(f)
            e = d[:, p] ^ f[p]  # e_j = d_{p_j} xor f_{p_j}
            perms.append(p)
            flips.append(f.astype(bool))
            bitperms.append(e @ weights)
    bitperms = np.array(bitperms, dtype=np.int64)  # (G, 2^n)
    nbits = 1 << n
    nconf = 1 << nbits
    dtype = np.uint8 if n <= 3 else np.uint16
    conf = np.arange(nconf, dtype=np.int64)
    out = np.zeros((len(bitperms), nconf), dtype=dtype)
    for lo in range(0, nbits, 8):
        width = min(8, nbits - lo)
        byte = np.arange(1 << width)
        # image of every value of this byte under every g: (G, 2^width)
        table = np.zeros((len(bitperms), 1 << width), dtype=np.int64)
        for j in range(width):
            table |= ((byte[None, :] >> j) & 1) << bitperms[:, lo + j : lo + j + 1]
        out |= table.astype(dtype)[:, (conf >> lo) & ((1 << width) - 1)]
    return CubeGroup(
        n=n,
        axis_permutations=read_only(np.array(perms, dtype=np.int8)),
        flips=read_only(np.array(flips, dtype=bool)),
        bit_permutations=read_only(bitperms.astype(np.int16)),
        configuration_permutations=read_only(out),
    )


def apply_symmetry(volume: ArrayLike, g: int) -> np.ndarray:
    """Image of ``volume`` under element ``g`` of :func:`hyperoctahedral_group`.

    Flips the axes with ``flips[g]``, then transposes with
    ``axis_permutations[g]`` (output axis ``j`` is input axis ``p_j``).

    Parameters
    ----------
    volume : array_like
        An image of dimension 1 to 4.
    g : int
        The element, ``0 .. 2^n n! - 1``.

    Returns
    -------
    numpy.ndarray
        The transformed image (a view of ``volume`` where NumPy gives one).

    Raises
    ------
    IsoflowError
        A ``g`` that is no integer of that range, an image not 1D to 4D.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.array([[1, 2, 3], [4, 5, 6]])
    >>> [apply_symmetry(image, g).tolist() for g in (0, 1, 4)]  # none, axis 1 flipped, transposed
    [[[1, 2, 3], [4, 5, 6]], [[3, 2, 1], [6, 5, 4]], [[1, 4], [2, 5], [3, 6]]]
    """
    x = np.asarray(volume)
    group = hyperoctahedral_group(x.ndim)
    # an index that is no integer (2.5, True, "3") would be cut or read as
    # another element, or fail in NumPy's indexing
    index = whole_given(g)
    if index is None or not 0 <= index < len(group):
        raise IsoflowError(f"symmetry index must be an integer 0..{len(group) - 1}, got {given_text(g)}")
    g = index
    flip_axes = tuple(int(i) for i in np.flatnonzero(group.flips[g]))
    y = np.flip(x, axis=flip_axes) if flip_axes else x
    return np.transpose(y, tuple(int(i) for i in group.axis_permutations[g]))


@cache
def configuration_orbits(n: int) -> np.ndarray:
    """Canonical representative (least image under the group) of every configuration."""
    n = check_dimension(n)
    perms = hyperoctahedral_group(n).configuration_permutations
    return read_only(perms.min(axis=0).astype(np.int64))
