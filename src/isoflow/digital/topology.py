"""Euler characteristic, Betti numbers and genus of digital objects.

chi is the digital Gauss-Bonnet sum (Theorems 10-11, in the exact form
``a^T n = 8 chi``, docs/mathematics.md): a histogram of vertex configurations
weighted by :func:`isoflow.digital.indices.euler_lut`. Betti numbers come from
counting connected components of the object (b0) and of the background with
the complementary connectivity (b2 in 3D, b1 in 2D); the remaining Betti
number follows from chi.
"""

from __future__ import annotations

from typing import Any, overload

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, counted, given_text, whole_given
from ..scale import arrays
from ..scale.arrays import is_host
from ..scale.compiled import Method, use_compiled
from ..scale.memory import check_fits
from .configurations import DIMENSIONS, configuration_histogram
from .connectivity import complement, resolve_connectivity
from .indices import euler_lut


def euler_from_histogram(hist: np.ndarray, ndim: int, connectivity: int) -> int:
    """chi from the configuration histogram: ``sum_c hist[c] lut[c] / 2^n``."""
    total = int(np.dot(hist, euler_lut(ndim, connectivity)))
    scale = 1 << ndim
    assert total % scale == 0, "local Euler shares must sum to a multiple of 2^n"
    return total // scale


def euler_characteristic(volume: ArrayLike, connectivity: int | np.integer | None = None) -> int:
    """The Euler characteristic of a 1D to 4D binary volume (eqs. 4.12-4.13).

    chi is the digital Gauss-Bonnet sum ``a^T n / 2^n`` (Theorems 10-11 in
    the exact form that holds on every object): the configuration histogram
    weighted by :func:`~isoflow.digital.indices.euler_lut`.

    Parameters
    ----------
    volume : array_like of bool or 0/1
        A NumPy array, a CuPy array (read on its GPU) or any array-API
        array (see :mod:`isoflow.scale.arrays`).
    connectivity : int, optional
        The object's: ``2n`` (default, the paper's) or ``3^n - 1``.

    Returns
    -------
    int

    Raises
    ------
    IsoflowError
        When the volume is not binary or not 1D to 4D, or the connectivity
        is not valid in its dimension.

    Examples
    --------
    A hollow box (a cavity inside) has chi = 1 - 0 + 1 = 2; scikit-image's
    ``euler_number`` agrees:

    >>> import numpy as np
    >>> box = np.ones((5, 5, 5), bool)
    >>> box[2, 2, 2] = False
    >>> euler_characteristic(box, 6), euler_characteristic(box, 26)
    (2, 2)
    """
    xp, v = arrays.as_volume(volume, "euler_characteristic: volume", dims=DIMENSIONS)
    conn = resolve_connectivity(v.ndim, connectivity)
    return euler_from_histogram(configuration_histogram(v), v.ndim, conn)


def _labeller(xp, v, method: Method = "auto") -> tuple[Any, Any, Any]:
    """``(xp, volume, label)`` for a checked volume (:func:`arrays.as_volume`):
    the volume where its library can label it (host NumPy, a CuPy GPU),
    otherwise copied to the host once."""
    label = arrays.label_function(xp)
    if label is None:
        v = arrays.to_host(v)
        xp, label = np, arrays.label_function(np)
    if is_host(xp) and not use_compiled(v, method=method):
        # an int32 label per voxel, next to the complement
        check_fits(
            LABEL_BYTES_PER_VOXEL * v.size,
            f"labelling a {'x'.join(map(str, v.shape))} volume for its Betti numbers",
            hint="2D/3D volumes can be stored as .zarr and read block by block",
        )
    return xp, v, label


#: peak bytes per voxel of a labelling: int32 labels, the complement and the
#: labeller's own work arrays (about 8 measured with scipy on a 90^4 volume)
LABEL_BYTES_PER_VOXEL = 10


def count_components(volume, connectivity: int) -> int:
    """Number of connected components of the True voxels.

    Large host volumes use the run-based union-find of :mod:`isoflow.scale.kernels`
    (no label volume); small ones :func:`isoflow.scale.labels.label`, CuPy
    volumes ``cupyx.scipy.ndimage.label`` on their GPU.
    """
    xp, v, label = _labeller(*arrays.as_volume(volume))
    return _count_components(xp, v, label, connectivity, _chosen(v))


def _chosen(v, method: Method = "auto") -> Method:
    """The method of every pass over ``v``, chosen once: for a host volume
    ``"auto"`` becomes ``"compiled"`` or ``"numpy"``, the volume counted in
    the tally of :func:`~isoflow.scale.compiled.use_compiled` once (its
    passes then take the same path)."""
    if method == "auto" and isinstance(v, np.ndarray):
        return "compiled" if use_compiled(v, method=method, record=True) else "numpy"
    return method


def _count_components(xp, v, label, connectivity: int, method: Method = "auto") -> int:
    if use_compiled(v, method=method):
        from ..scale.kernels import count_components as compiled

        return compiled(v, connectivity)
    with arrays.on_device(v):
        return int(label(v, connectivity)[1])


def count_enclosed(volume, connectivity: int) -> int:
    """Components of the background (with ``connectivity``) that do not reach
    the array border: cavities in 3D, holes in 2D.

    The region outside the array is background and touches every border
    component, so those merge into one exterior; no padded copy is needed.
    """
    xp, v, label = _labeller(*arrays.as_volume(volume))
    return _count_enclosed(xp, v, label, connectivity, _chosen(v))


def _count_enclosed(xp, v, label, connectivity: int, method: Method = "auto") -> int:
    if v.size == 0:
        return 0
    if use_compiled(v, method=method):
        from ..scale.kernels import count_enclosed as compiled

        return compiled(v, connectivity)
    with arrays.on_device(v):
        labels, n = label(~v, connectivity)
        faces = []
        for axis in range(v.ndim):
            for end in (0, -1):
                index: list[Any] = [slice(None)] * v.ndim
                index[axis] = end
                faces.append(xp.reshape(labels[tuple(index)], (-1,)))
        # unique_values/concatenate/count_nonzero: in both NumPy and CuPy
        border = xp.unique_values(xp.concatenate(faces))
        return int(n) - int(xp.count_nonzero(border))


#: an array whose type says it is 1D to 3D (NumPy types the shape of
#: ``np.zeros((4, 4, 4))``), whose Betti numbers are all known
AtMost3D = np.ndarray[tuple[int], Any] | np.ndarray[tuple[int, int], Any] | np.ndarray[tuple[int, int, int], Any]


# the Betti numbers are typed by the dimension where the array's type says
# it: ints in 1D to 3D, so that ``b0 + b1`` type-checks, b1 and b2 None in
# 4D; a volume whose type does not say (nested lists) Any
@overload
def betti_numbers(volume: AtMost3D, connectivity: int | np.integer | None = None, chi: int | np.integer | None = None,
                  method: Method = "auto") -> list[int]: ...
@overload
def betti_numbers(volume: np.ndarray[tuple[int, int, int, int], Any], connectivity: int | np.integer | None = None,
                  chi: int | np.integer | None = None, method: Method = "auto") -> list[int | None]: ...
@overload
def betti_numbers(volume: ArrayLike, connectivity: int | np.integer | None = None, chi: int | np.integer | None = None,
                  method: Method = "auto") -> list[Any]: ...
def betti_numbers(volume: ArrayLike, connectivity: int | np.integer | None = None, chi: int | np.integer | None = None,
                  method: Method = "auto") -> list[int] | list[int | None]:
    """The Betti numbers of a 1D to 4D binary volume.

    b0 counts the components under ``connectivity``, the last Betti number
    the background components that do not reach the border (cavities in 3D,
    holes in 2D) under the complementary connectivity, and in 3D
    ``b1 = b0 + b2 - chi`` the tunnels. In 1D b0 is the number of runs,
    which is chi (segments have no holes).

    Parameters
    ----------
    volume : array_like of bool or 0/1
        A NumPy array, or a CuPy array labelled on its GPU.
    connectivity : int, optional
        The object's: 6 or 26 in 3D, 4 or 8 in 2D, 8 or 80 in 4D, 2 in 1D
        (default: the paper's 6, 4, 8, 2).
    chi : int, optional
        The Euler characteristic when it is known already (one that cannot
        be the volume's is refused, and so is one that is not an integer).
    method : {"auto", "numpy", "compiled"}
        The labellings (cc3d, scipy, CuPy), the compiled run-based
        union-find, or ``"auto"``: by the volume's size together with the
        voxels that ``"auto"`` has already sent down the NumPy passes in
        this process (:func:`~isoflow.scale.compiled.use_compiled`).

    Returns
    -------
    list of int
        ``[b0, b1, b2]`` in 3D, ``[b0, b1]`` in 2D (``chi = b0 - b1`` is
        checked), ``[b0]`` in 1D (``chi = b0`` is checked); in 4D ``[b0, None, None, b3]``: chi fixes ``b1 - b2`` but
        not each. Typed ``list[int]`` for an array NumPy's types say is 1D
        to 3D (``np.zeros((4, 4, 4))``) or say no dimension of (a slice, a
        comparison: read as the common case), so that ``b0, b1, b2 =
        betti_numbers(v)`` then ``b0 + b1`` type-checks under ``mypy
        --strict``; ``list[int | None]`` for one typed 4D; ``list[Any]``
        for nested lists.

    Raises
    ------
    IsoflowError
        When the volume is not binary or not 1D to 4D, the connectivity is
        not valid in its dimension, or ``chi`` is no integer or cannot be
        the volume's.

    Examples
    --------
    A hollow ring, a cube with a tunnel, and a box with a cavity:

    >>> import numpy as np
    >>> ring = np.ones((3, 3, 1), bool)
    >>> ring[1, 1, 0] = False
    >>> box = np.ones((3, 3, 3), bool)
    >>> box[1, 1, 1] = False
    >>> betti_numbers(ring), betti_numbers(box)
    ([1, 1, 0], [1, 0, 1])

    A row of three runs:

    >>> betti_numbers(np.array([1, 1, 0, 1, 0, 0, 1], bool))
    [3]
    """
    # 1D as euler_characteristic takes it (docs/ndim.md: the same functions serve 1D to 4D)
    xp, v = arrays.as_volume(volume, "betti_numbers: volume", dims=DIMENSIONS)
    conn = resolve_connectivity(v.ndim, connectivity)
    method = _chosen(v, method)  # one choice for the histogram and the labellings
    # b1 = b0 + b2 - chi is a count only for an integer chi
    if chi is not None:
        whole = whole_given(chi)
        if whole is None:
            raise IsoflowError(f"chi must be an integer, got {given_text(chi)}")
        chi = whole  # a Python int gives a list of plain ints, as chi computed here does
    else:
        chi = euler_from_histogram(configuration_histogram(v, method=method), v.ndim, conn)
    if v.ndim == 1:
        # the runs are the vertices where a run starts (configuration 2: the cell after the vertex alone),
        # counted here rather than taken from chi so that a chi given is checked
        runs = int(configuration_histogram(v, method=method)[2])
        if chi != runs:
            raise IsoflowError(f"chi={chi} is not this volume's Euler characteristic ({counted(runs, 'run')}); "
                               "leave chi out to compute it")
        return [runs]
    if v.size == 0:
        # no voxel and no cell of background inside: nothing to label (the
        # labellers pad the volume, which may be long along its other axes)
        b0 = enclosed = 0
    else:
        # the volume is checked once here; one host copy where the library cannot label
        xp, v, label = _labeller(xp, v, method)
        method = _chosen(v, method)  # (a device volume copied to the host)
        if use_compiled(v, method=method):
            from ..scale.kernels import count_object_and_enclosed

            b0, enclosed = count_object_and_enclosed(v, conn, complement(v.ndim, conn))
        else:
            b0 = _count_components(xp, v, label, conn, method)
            enclosed = _count_enclosed(xp, v, label, complement(v.ndim, conn), method)
    if v.ndim == 4:
        return [b0, None, None, enclosed]
    # a ``chi`` given that is not the volume's: in 2D chi = b0 - b1 exactly,
    # in 3D it would give a negative b1; a check, not an assert, as -O
    # removes asserts
    if (v.ndim == 2 and b0 - enclosed != chi) or (v.ndim == 3 and b0 + enclosed - chi < 0):
        raise IsoflowError(f"chi={chi} is not this volume's Euler characteristic ({b0} components and "
                           f"{enclosed} {'holes' if v.ndim == 2 else 'cavities'}); leave chi out to compute it")
    if v.ndim == 2:
        return [b0, enclosed]
    return [b0, b0 + enclosed - chi, enclosed]


def genus_of_closed_surface(euler: int) -> int:
    """Genus of a connected closed orientable surface: ``1 - chi/2``."""
    return 1 - euler // 2
