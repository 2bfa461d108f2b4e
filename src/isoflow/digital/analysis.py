"""The shape report of a digital object: what ``isoflow info`` prints.

One pass of configurations gives the histogram from which chi (Theorems
10-11), the class vector ``n`` (eq. 4.9), ``a^T n`` (eq. 4.12-4.13) and the
energy ``E = k^T n`` (eq. 5.22) all follow; two labellings give the Betti
numbers, and the labels of the object and background pieces on either side
of every boundary face give the closed surfaces and their genus
(:mod:`isoflow.digital.closed_surfaces`, without building the mesh).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, check_switch
from ..scale import arrays
from ..scale.compiled import Method, using
from .closed_surfaces import closed_surfaces, compiled_census, empty_census, small_census, use_census
from .configurations import configuration_histogram
from .connectivity import resolve_connectivity
from .indices import (
    CLASS_LABELS,
    NOT_WELL_COMPOSED,
    PLANAR_LABELS,
    a_lut,
    class_histogram,
    class_lut,
    euler_lut,
    planar_class_lut,
)
from .lattice import DigitalObject
from .measures import MEASURE_NAMES, Extent, extent_of, faces_per_axis, world_measures
from .report import Report
from .topology import DIMENSIONS, betti_numbers, euler_from_histogram
from .units import unit_given


def analyze(
    obj: DigitalObject | ArrayLike,
    connectivity: int | np.integer | None = None,
    surfaces: bool = True,
    threads: int | np.integer | None = None,
    method: Method = "auto",
    *,
    pitch: float | ArrayLike | None = None,
    origin: ArrayLike | None = None,
    unit: str | None = None,
) -> Report:
    """Everything ``isoflow info`` reports about a 2D, 3D or 4D object (a
    bare 1D array too, as :func:`~isoflow.digital.topology.euler_characteristic`
    and :func:`~isoflow.digital.topology.betti_numbers` take it).

    One pass of configurations gives the histogram from which chi (Theorems
    10-11), the class vector ``n`` (eq. 4.9), ``a^T n`` (eqs. 4.12-4.13) and
    the energy ``E = k^T n`` (eq. 5.22) all follow; labellings of the object
    and of the background give the Betti numbers; and, in 3D, the labels on
    either side of every boundary face give the closed surfaces of the
    boundary mesh and their genus, without building the mesh.

    Parameters
    ----------
    obj : DigitalObject or array_like of bool
        A digital object, or a bare binary volume: a NumPy array, or a CuPy
        (or other array-API) array whose histogram and Betti numbers are
        computed on its device (only the surfaces, when asked, are counted
        from a host copy).
    connectivity : int, optional
        The object's: 6 or 26 in 3D, 4 or 8 in 2D, 8 or 80 in 4D, 2 in 1D
        (default: the paper's 6, 4, 8, 2); the background takes the other.
    surfaces : bool
        Count the closed surfaces and their genus (3D).
    threads : int, optional
        Threads of the compiled passes (default: the ``ISOFLOW_THREADS``
        environment variable, else every CPU).
    method : {"auto", "numpy", "compiled"}
        The NumPy passes, the compiled ones (numba), or ``"auto"``: by the
        volume's size together with the voxels that ``"auto"`` has already
        sent down the NumPy passes in this process (a loop over many small
        volumes takes the compiled passes once they add up to the
        threshold, so numba's start is paid once), and for a 3D volume the
        compiled pass at any size once it is loaded in this process (a
        compiled pass ran here; see
        :func:`~isoflow.digital.closed_surfaces.use_census`). The report
        is the same either way.
    pitch, origin, unit : optional
        The voxel size (one number or one per axis), the world position
        of lattice point 0 (of voxel 0's lowest corner for an array) and
        their length unit, in which the report's world measures are
        given; a :class:`~isoflow.digital.lattice.DigitalObject` brings
        its own, which those given replace (default: unit voxels at 0 and
        no unit).

    Returns
    -------
    Report
        In 2D and 3D with the object's world measures: ``volume`` and
        ``surface_area`` (``area`` and ``perimeter`` in 2D), ``bbox``,
        ``centroid`` and ``unit``, as :func:`~isoflow.digital.label_table.label_table`
        gives a label's.
        ``a_dot_n`` sums the Gauss-Bonnet weight over every vertex, the
        configurations that are not well-composed included, and so equals
        ``2^n chi`` on every object; ``a_dot_n_well_composed`` is the paper's
        ``a^T n`` over the nine classes alone (in 4D the 45 manifold
        classes), and ``energy`` sums ``a^2`` over the classes of ``n``
        alone (the nine, the three planar ones, the 45 manifold ones).

    Raises
    ------
    IsoflowError
        When the volume is not binary, not 1D to 4D, or would not fit in
        memory.

    Examples
    --------
    A solid torus: one component, one tunnel, no cavity, its boundary one
    surface of genus 1, and ``a^T n = 8 chi = 0`` (Theorem 11, one tunnel):

    >>> import numpy as np
    >>> x, y, z = np.indices((12, 12, 5)) - np.array([5.5, 5.5, 2]).reshape(3, 1, 1, 1)
    >>> torus = ((np.hypot(x, y) - 3.5) ** 2 + z**2) <= 2.5**2
    >>> r = analyze(torus)
    >>> r.betti, r.euler_characteristic, r.a_dot_n, r.genus
    ([1, 1, 0], 0, 0, [1])

    A row of two runs: their four ends are its convex vertices.

    >>> r = analyze(np.array([0, 1, 1, 0, 1], bool))
    >>> r.betti, r.euler_characteristic, r.classes, r.energy
    ([2], 2, {'convex': 4, 'flat': 0, 'concave': 0}, 4)

    Two CT voxels of 0.5 x 0.5 x 2 mm, side by side along x:

    >>> r = analyze(np.ones((2, 1, 1), bool), pitch=(0.5, 0.5, 2.0), unit="mm")
    >>> r.volume, r.surface_area, r.bbox, r.centroid, r.unit
    (1.0, 7.0, [0.0, 0.0, 0.0, 1.0, 0.5, 2.0], [0.5, 0.25, 1.0], 'mm')
    """
    surfaces = check_switch(surfaces, "surfaces", "analyze")
    with using(threads):
        return Report.from_dict(_analyze(obj, connectivity, surfaces, method, Place(pitch, origin, unit)))


class Place(NamedTuple):
    """The placement given to :func:`analyze` (None: the object's, else the default).

    Examples
    --------
    >>> Place(pitch=0.5).unit is None
    True
    """

    pitch: Any = None
    origin: Any = None
    unit: str | None = None


def placed(obj, ndim: int, given: Place, function: str = "analyze") -> tuple[np.ndarray, np.ndarray, str | None]:
    """``(spacing, corner, unit)`` of the report's world measures: the
    voxel size, the world position of voxel 0's lowest corner and the
    length unit, of ``obj`` (a DigitalObject) with those ``given`` in
    place of its own, checked as an object's are, a refusal naming
    ``function``, the function called.

    Examples
    --------
    >>> obj = DigitalObject(np.ones((1, 1), bool), offset=(2, 0), pitch=0.5, unit="mm")
    >>> [x.tolist() if hasattr(x, "tolist") else x for x in placed(obj, 2, Place(origin=(10, 0)))]
    [[0.5, 0.5], [11.0, 0.0], 'mm']
    """
    if ndim not in (2, 3, 4):
        if any(v is not None for v in given):
            raise IsoflowError(f"{function}: pitch, origin and unit place 2D to 4D objects, got a {ndim}D array")
        return np.ones(ndim), np.zeros(ndim), None
    own = obj if isinstance(obj, DigitalObject) else DigitalObject.placement(ndim)
    pitch = own.pitch if given.pitch is None else given.pitch
    origin = own.origin if given.origin is None else given.origin
    # as given: the object's check names a string, and a bool among numbers, which an array would make a number
    place = DigitalObject.placement(ndim, pitch=pitch, origin=origin, offset=own.offset,
                                    parity=own.parity, function=function)
    return place.spacing, place.world(np.zeros(ndim)), unit_given(own.unit if given.unit is None else given.unit,
                                                                   function)


def _analyze(obj, connectivity, surfaces: bool, method: Method, given: Place) -> dict:
    if isinstance(obj, DigitalObject):
        vol, parity = obj.volume, obj.parity
    else:
        # a bool array's bytes are made 0/1 only for the NumPy passes: the
        # compiled pass reads any nonzero byte as set
        vol, parity = arrays.as_volume(obj, "analyze: obj", canonical=False, dims=DIMENSIONS)[1], 0
    spacing, corner, unit = placed(obj, vol.ndim, given)
    conn = resolve_connectivity(vol.ndim, connectivity)
    compiled = use_census(vol, surfaces, method, record=True)
    if not compiled and isinstance(vol, np.ndarray):
        vol = arrays.binary(vol)  # the NumPy passes and the extent read 0/1 bytes: checked once, here
        if vol.ndim == 3 and method == "auto":
            method = "numpy"  # chosen (and counted in the tally) once, above
    census: Mapping[str, Any] | None = _census(vol, conn, surfaces, compiled)
    if census is not None:
        hist = census["hist"]
        chi = euler_from_histogram(hist, 3, conn)
        b0, enclosed = census["betti_counts"]
        betti = [b0, b0 + enclosed - chi, enclosed]
    else:
        hist = configuration_histogram(vol, method=method)
        chi = euler_from_histogram(hist, vol.ndim, conn)
        betti = betti_numbers(vol, conn, chi=chi, method=method)
    if vol.ndim in MEASURE_NAMES:
        # the compiled census has it from its bit rows; else one sum per axis
        extent = census["extent"] if compiled and census is not None else extent_of(vol)
    else:
        extent = None
    out = report_from_histogram(hist, vol.ndim, conn, voxels=voxels_from_histogram(hist), shape=vol.shape,
                                betti=betti, parity=parity, extent=extent, place=(spacing, corner, unit))
    if vol.ndim == 3 and surfaces:
        if census is None:  # a device volume: its surfaces from a host copy
            census = closed_surfaces(arrays.to_host(vol), conn)
        out.update(surfaces=census["surfaces"], pinched_vertices=census["pinched_vertices"],
                   doubled_edges=census["doubled_edges"])
        # docs/mathematics.md: the split mesh has V - E + F = 2 chi + 2 p
        assert out["surfaces"].columns()["euler_characteristic"].sum() == 2 * chi + 2 * census["pinched_vertices"]
    return out


def _census(vol, conn: int, surfaces: bool, compiled: bool) -> dict | None:
    """One pass that gives the histogram, the Betti counts and (when asked)
    the surfaces of a 3D host volume: compiled (``compiled``, by
    :func:`~isoflow.digital.closed_surfaces.use_census`), or from one
    configuration array and its labellings (``vol`` then 0/1 bytes); None
    where the passes go one by one."""
    if vol.size == 0 and vol.ndim == 3 and isinstance(vol, np.ndarray):
        return empty_census(vol.shape)
    if compiled:
        return compiled_census(vol, conn, surfaces)
    if vol.ndim == 3 and surfaces and isinstance(vol, np.ndarray):
        return small_census(vol, conn)
    return None


def voxels_from_histogram(hist: np.ndarray) -> int:
    """Object voxels: each is an octant of exactly ``2^n`` vertices, so the
    octant bits set over all configurations count every voxel ``2^n`` times."""
    hist = np.asarray(hist, dtype=np.int64)
    octants = int(len(hist)).bit_length() - 1
    codes = np.arange(len(hist))
    bits = ((codes[:, None] >> np.arange(octants)) & 1).sum(axis=1)
    return int(hist @ bits) // octants


def report_from_histogram(
    hist: np.ndarray,
    ndim: int,
    conn: int,
    voxels: int,
    shape,
    betti: list[int],
    parity: int = 0,
    extent: Extent | None = None,
    place: tuple | None = None,
) -> dict:
    """The report's histogram part, from numbers any pass over the volume gives.

    Split out of :func:`analyze` so that the out-of-core pass
    (:mod:`isoflow.digital.outofcore`), which never holds the volume, builds the very
    same dict from its block-wise histogram and component counts. In 3D
    :func:`analyze` appends the surfaces when asked; in 2D and 4D there are
    none to count (the boundary is curves, a 3-manifold), so the report has
    no ``surfaces`` key. In 2D and 3D the world measures
    (:mod:`isoflow.digital.measures`) from the histogram's faces, the
    voxels' ``extent`` and ``place``, ``(spacing, corner, unit)`` (default
    unit voxels at 0).
    """
    hist = np.asarray(hist)
    chi = euler_from_histogram(hist, ndim, conn)
    out: dict = {
        "voxels": int(voxels),
        "dimension": ndim,
        "shape": [int(s) for s in shape],
        "connectivity": conn,
        "parity": parity,
        "euler_characteristic": chi,
        "betti": [None if b is None else int(b) for b in betti],
    }
    if ndim == 4:
        out.update(_report_4d(hist, conn))
    elif ndim == 3:
        cls = class_lut()
        n = class_histogram(hist)
        a = a_lut(conn)
        k = a.astype(np.int64) ** 2
        on = cls >= 0
        out.update(
            n=n.tolist(),
            classes=dict(zip(CLASS_LABELS, n.tolist())),
            non_well_composed=int(hist[cls == NOT_WELL_COMPOSED].sum()),
            a_dot_n=int(np.dot(hist, a)),
            a_dot_n_well_composed=int(np.dot(hist[on], a[on])),
            energy=int(np.dot(hist[on], k[on])),
        )
    elif ndim == 1:
        # a run's two ends (configurations 1 and 2) are the only boundary vertices, convex, of
        # Euler share 1/2 (a = 1): the planar classes with neither flat nor concave vertices
        ends = int(hist[1] + hist[2])
        out.update(
            n=[ends, 0, 0],
            classes=dict(zip(PLANAR_LABELS, [ends, 0, 0])),
            non_well_composed=0,
            a_dot_n=int(np.dot(hist, euler_lut(1, conn))),
            energy=ends,
        )
    else:
        pcls = planar_class_lut()
        n = np.bincount(pcls[pcls >= 0], weights=hist[pcls >= 0], minlength=3).astype(int)
        out.update(
            n=n.tolist(),
            classes=dict(zip(PLANAR_LABELS, n.tolist())),
            non_well_composed=int(hist[pcls == NOT_WELL_COMPOSED].sum()),
            a_dot_n=int(np.dot(hist, euler_lut(2, conn))),
            energy=int(n[0] + n[2]),
        )
    spacing, corner, unit = (np.ones(ndim), np.zeros(ndim), None) if place is None else place
    out.update(world_measures(ndim, int(voxels), faces_per_axis(hist, ndim) if ndim in MEASURE_NAMES else None,
                              extent, spacing, corner, unit, tuple(int(n) for n in shape)))
    return out


def _report_4d(hist: np.ndarray, conn: int) -> dict:
    """4D (section 6): the histogram over the 45 classes of boundary
    configurations where the boundary is a 3-manifold and both adjacencies give
    the same Euler share (``isoflow.digital.ndim``); everything else on the boundary is
    counted as not well-composed. ``a`` is 16 x the Euler share, so
    ``a_dot_n = 16 chi`` (the form of eq. 6.2 that holds)."""
    from .ndim import manifold_configurations
    from .symmetry import configuration_orbits

    canon = configuration_orbits(4)
    manifold = manifold_configurations(4)
    boundary = np.ones(len(hist), bool)
    boundary[[0, len(hist) - 1]] = False
    classes = np.unique(canon[manifold & boundary])
    counts = np.bincount(np.searchsorted(classes, canon[manifold & boundary]),
                         weights=hist[manifold & boundary], minlength=len(classes)).astype(np.int64)
    a = euler_lut(4, conn)
    return {
        "n": counts.tolist(),
        "classes": {int(c): int(k) for c, k in zip(classes, counts) if k},
        "non_well_composed": int(hist[boundary & ~manifold].sum()),
        "a_dot_n": int(np.dot(hist, a)),
        "a_dot_n_well_composed": int(np.dot(hist[manifold & boundary], a[manifold & boundary])),
        "energy": int(np.dot(hist[manifold & boundary], a[manifold & boundary] ** 2)),
    }
