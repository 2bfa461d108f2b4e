"""The digital object: a binary volume placed on the lattice or its dual.

Definition 2 of the paper: a digital object is a finite complex of unit
cubes. Here it is a boolean array plus where that array sits:

* ``offset``: integer lattice position of voxel ``(0, 0, 0)``'s lowest corner;
* ``parity``: 0 on the lattice Z^n, 1 on the dual lattice Z^n + e/2 (eq. 5.1),
  which every step of the digital curvature flow switches;
* ``pitch`` and ``origin``: world coordinates, so that an object voxelised
  from a mesh exports back onto the mesh. ``pitch`` is one number, or one
  per axis for anisotropic voxels (a CT scan's 0.5 x 0.5 x 2 mm); the
  digital topology never looks at it, the exported coordinates do;
* ``unit``: the length unit of ``pitch`` and ``origin`` (``mm``, ``µm``,
  ...; None for none), as the file read said it, kept by every step and
  written with the object;
* ``space``: the anatomical frame of the world axes (``"RAS"``,
  ``"LPS"``, ...: :mod:`isoflow.digital.frames`; None for none), kept and
  written as ``unit`` is.

Array voxel ``v`` is the cube whose lowest corner has lattice coordinates
``offset + v + parity/2`` and world coordinates ``origin + pitch * (that)``
(per axis when ``pitch`` is a vector).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from contextvars import ContextVar
from dataclasses import dataclass, field, replace
from numbers import Real
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, counted, given_text, number_text, whole_given
from ..results import read_only, same_fields, writeable_under
from ..scale.arrays import as_array, binary, is_masked_array, read_anew
from .frames import space_given
from .units import unit_given


@dataclass(frozen=True, eq=False)
class DigitalObject:
    """A binary volume with its place on the lattice or its dual (eq. 5.1).

    Voxel ``i`` of the array is the closed cube ``[i, i+1]`` shifted by
    ``offset``, and by ``(1/2, ..., 1/2)`` on the dual lattice (``parity``
    1): each flow step moves the object from one lattice to the other and
    back. ``pitch`` and ``origin`` put it in world coordinates (those of the
    mesh it came from), so its surfaces and flows export where the mesh is.
    2D and 3D objects take every operation; 4D ones the topology report
    (section 6).

    Parameters
    ----------
    volume : array_like of bool or 0/1
        Held read-only: a writeable array of the caller's is copied (the
        one an object given in its place hands ``np.asarray`` too, an
        xarray DataArray's), so that changing it afterwards leaves the
        object as it was and the caller's array writeable, and so is
        a read-only view of memory that something else can write (a
        writeable array's ``view()`` made read-only, ``np.broadcast_to``
        of it); a read-only array that owns its memory is held as it is.
    offset : tuple of int, optional
        Lattice index of voxel ``(0, ..., 0)`` (default zeros).
    parity : {0, 1}
        The lattice (0) or the dual lattice (1).
    pitch : float or array_like of float
        The voxel size, one number or one per axis.
    origin : array_like of float, optional
        World position of lattice point 0 (default zeros).
    unit : str, optional
        The length unit of ``pitch`` and ``origin``, in any spelling
        :func:`~isoflow.digital.units.length_unit` reads (``"mm"``,
        ``"micron"``, ...), held in isoflow's (``"\u00b5m"``); None (the
        default) for none. :func:`~isoflow.mesh.volumes.read_volume` sets
        it from the file, every step that keeps the object's place keeps
        it, and :func:`~isoflow.mesh.volumes.write_volume` writes it.
    space : str, optional
        The anatomical frame of the world axes: where +x, +y, +z point, as
        three letters (``"RAS"``: to the patient's Right, Anterior,
        Superior, as NIfTI and MGH mean; ``"LPS"``, as a 3D Slicer NRRD
        says), in any case, held in capitals; None (the default) for none.
        Set, kept and written as ``unit`` is: a writer of another frame
        negates the axes that point the other way
        (:mod:`isoflow.digital.frames`).

    Raises
    ------
    IsoflowError
        When the volume is not binary or not 2D to 4D, or a field is not
        what it must be (a ``unit`` that is no length unit, a ``space`` that
        is no anatomical frame among them).

    Examples
    --------
    The paper's Example 19 given by its 20 lattice points (Definitions 1-2):
    a corner cube and its three face neighbours.

    >>> import numpy as np
    >>> corner = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    >>> points = {tuple(np.add(p, d)) for p in corner for d in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]}
    >>> obj = DigitalObject.from_points(sorted(points))
    >>> len(points), obj.voxels, obj.volume.shape
    (20, 4, (2, 2, 2))

    A CT scan's voxels of 0.5 x 0.5 x 2 millimetres, the unit in isoflow's
    spelling:

    >>> scan = DigitalObject(np.ones((4, 4, 2), bool), pitch=(0.5, 0.5, 2.0), unit="millimetre")
    >>> scan.unit, scan.cropped().unit
    ('mm', 'mm')

    ... and in the frame of a 3D Slicer scan:

    >>> DigitalObject(np.ones((4, 4, 2), bool), space="lps").cropped().space
    'LPS'
    """

    volume: np.ndarray
    offset: tuple[int, ...] = None  # type: ignore[assignment]
    parity: int = 0
    pitch: float | np.ndarray = 1.0
    origin: np.ndarray = field(default=None)  # type: ignore[arg-type]
    unit: str | None = None
    space: str | None = None

    # equal when every field is, the volume by its elements: the generated
    # __eq__ compared the arrays with ==, whose truth NumPy refuses; and
    # unhashable, as NumPy arrays are (a read-only one's memory can still
    # change through a writeable view of it)
    __eq__ = same_fields
    __hash__ = None  # type: ignore[assignment]

    if TYPE_CHECKING:
        # what the constructor takes (__post_init__ checks and converts it),
        # beside the fields' types, which say what the object then holds
        def __init__(self, volume: ArrayLike, offset: Sequence[int | np.integer] | np.ndarray | None = None,
                     parity: int | np.integer = 0,
                     pitch: float | ArrayLike = 1.0, origin: ArrayLike | None = None,
                     unit: str | None = None, space: str | None = None) -> None: ...

    def __post_init__(self):
        function, where, remedy, remedy_dims = _CALLED.get()
        # a dask array is computed into memory made for this object, held
        # without the copy that memory numpy.asarray gives would need
        anew = read_anew(self.volume, where)
        vol = binary(self.volume if anew is None else anew, where, remedy=remedy, remedy_dims=remedy_dims)
        if vol.ndim not in (2, 3, 4):
            raise IsoflowError(f"{where}: a digital object is 2D, 3D or 4D, got a {vol.ndim}D array")
        object.__setattr__(self, "volume", read_only(vol) if anew is not None else _held(vol, self.volume))
        try:
            self._place(vol.ndim)
        except IsoflowError as exc:
            raise (exc if function is None else exc.called(function)) from None

    def _place(self, n: int) -> None:
        """The fields that place the volume of ``n`` dimensions, checked
        and held."""
        offset = (0,) * n if self.offset is None else _field(
            self.offset, "offset", n, integral=True, bound=MAX_COORDINATE)
        object.__setattr__(self, "offset", tuple(int(o) for o in offset))
        origin = np.zeros(n) if self.origin is None else _field(self.origin, "origin", n)
        object.__setattr__(self, "origin", read_only(origin))
        # True equals 1: taken as the dual lattice unasked
        bool_given = np.asarray(self.parity).dtype.kind == "b"
        parity = None if bool_given else _field(self.parity, "parity", None, integral=True)
        if parity not in (0, 1):
            # the value as written: _field gives it back as a float
            given = np.asarray(self.parity)
            given = given.item() if given.size == 1 else given.tolist()
            raise IsoflowError(f"'parity' must be 0 (lattice) or 1 (dual lattice), got {given_text(given)}")
        object.__setattr__(self, "parity", int(parity))
        object.__setattr__(self, "pitch", checked_pitch(self.pitch, n))
        object.__setattr__(self, "unit", unit_given(self.unit, "DigitalObject"))
        object.__setattr__(self, "space", space_given(self.space, "DigitalObject"))

    def __setstate__(self, state: dict[str, Any]) -> None:
        # pickle restores the fields without __post_init__, and NumPy
        # unpickles every array writeable
        self.__dict__.update(state)
        for value in (self.volume, self.origin, self.pitch):
            if isinstance(value, np.ndarray):
                read_only(value)

    # ------------------------------------------------------------ builders
    @classmethod
    def of(cls, x: DigitalObject | ArrayLike, function: str | None = None, argument: str = "obj",
           remedy: str | None = None, remedy_dims: tuple[int, ...] = (2, 3)) -> DigitalObject:
        """``x`` itself if it is a DigitalObject, else the object of the
        binary array ``x`` at the origin: the API takes either.

        Parameters
        ----------
        x : DigitalObject or array_like of bool
            An object, or a 0/1 array.
        function : str, optional
            The function called, which a refusal of ``x`` begins with,
            then its ``argument`` (``run_flow: obj``); None: as the
            constructor names it (``DigitalObject volume``).
        argument : str
            The argument ``x`` was given for.
        remedy : str, optional
            What the refusal of a label image offers, the call of one
            label's mask, ``{}`` where it goes (``"write_surface({},
            path)"``); None: ``function`` of the mask alone
            (:func:`~isoflow.scale.arrays.binary`).
        remedy_dims : tuple of int
            The dimensions of a label image offered ``remedy``: those
            ``function`` takes.

        Returns
        -------
        DigitalObject
            ``x`` itself, or a new object of unit voxels at the origin.

        Raises
        ------
        IsoflowError
            An array that is not binary, or not 2D, 3D or 4D.

        Examples
        --------
        >>> obj = DigitalObject(np.ones((2, 2), bool), pitch=0.5)
        >>> DigitalObject.of(obj) is obj, DigitalObject.of([[1, 0], [1, 1]]).voxels
        (True, 3)
        >>> DigitalObject.of(np.ones(3, bool), "run_flow")
        Traceback (most recent call last):
        ...
        isoflow.errors.IsoflowError: run_flow: obj: a digital object is 2D, 3D or 4D, got a 1D array
        >>> DigitalObject.of(np.arange(8).reshape(2, 2, 2), "flow_step")  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        isoflow.scale.arrays.NotBinary: flow_step: obj: not a binary volume (...); threshold it first, e.g. volume > 0, \
or one label at a time, e.g. flow_step(volume == 2)
        """
        if isinstance(x, DigitalObject):
            return x
        if function is None:
            return cls(x)
        remedy = f"{function}({{}})" if remedy is None else remedy
        with _called(_Caller(function, f"{function}: {argument}", remedy, remedy_dims)):
            return cls(x)

    @classmethod
    def from_voxels(cls, indices: ArrayLike, **kw: Any) -> DigitalObject:
        """Object made of the voxels with the given integer indices (N, n).

        Parameters
        ----------
        indices : array_like of int, shape (N, 2) or (N, 3)
            The voxels' lattice indices (repeats are one voxel).
        **kw
            ``pitch``, ``origin``, ``parity``, ``unit``, ``space`` of the object.

        Returns
        -------
        DigitalObject
            In the smallest array that holds the voxels, ``offset`` its
            lowest index; no indices (shape ``(0, n)``) give the empty
            object, as the all-zero volume they come from.

        Examples
        --------
        >>> obj = DigitalObject.from_voxels([[0, 0, 0], [2, 0, 0]], pitch=0.5)
        >>> obj.volume.shape, obj.voxels, [c.tolist() for c in obj.bbox()]
        ((3, 1, 1), 2, [[0.0, 0.0, 0.0], [1.5, 0.5, 0.5]])
        >>> DigitalObject.from_voxels(np.argwhere(np.zeros((4, 4, 4), bool))).voxels
        0
        """
        idx = _integer_points(indices, "voxel index")
        if not len(idx):  # np.argwhere of an all-zero mask, a label that is absent
            return cls(np.zeros((0,) * idx.shape[1], bool), **kw)
        lo = idx.min(axis=0)
        _check_grid(lo, idx.max(axis=0), len(idx), "voxel indices", 1)
        vol = np.zeros(idx.max(axis=0) - lo + 1, dtype=bool)
        vol[tuple((idx - lo).T)] = True
        return cls(vol, offset=tuple(lo), **kw)

    @classmethod
    def from_points(cls, points: ArrayLike, **kw: Any) -> DigitalObject:
        """The paper's point model (Definitions 1-2).

        A set of lattice points defines the object made of every unit cube
        (square in 2D) whose 2^n corners all belong to the set.

        Parameters
        ----------
        points : array_like of int, shape (N, 2) or (N, 3)
            The lattice points.
        **kw
            ``pitch``, ``origin``, ``parity``, ``unit``, ``space`` of the object.

        Returns
        -------
        DigitalObject

        Examples
        --------
        The 12 points of a 3x2x2 block are the corners of two unit cubes:

        >>> points = [[x, y, z] for x in range(3) for y in range(2) for z in range(2)]
        >>> DigitalObject.from_points(points).voxels
        2

        No points (shape ``(0, n)``) are the empty object, as one point is;
        ``[]`` says no dimension, and is refused:

        >>> DigitalObject.from_points(np.empty((0, 3))).voxels
        0
        """
        pts = _integer_points(points, "lattice point")
        if not len(pts):  # np.argwhere of an all-zero mask: no cube has its corners
            return cls(np.zeros((0,) * pts.shape[1], bool), **kw)
        lo = pts.min(axis=0)
        _check_grid(lo, pts.max(axis=0), len(pts), "lattice points", 2)  # the point grid and the cubes
        grid = np.zeros(pts.max(axis=0) - lo + 1, dtype=bool)
        grid[tuple((pts - lo).T)] = True
        n = grid.ndim
        shape = tuple(max(s - 1, 0) for s in grid.shape)
        vol = np.ones(shape, dtype=bool)
        for corner in np.ndindex(*(2,) * n):
            vol &= grid[tuple(slice(c, c + s) for c, s in zip(corner, shape))]
        return cls(vol, offset=tuple(lo), **kw)

    @classmethod
    def placement(cls, ndim: int | np.integer, pitch: ArrayLike | None = None, origin: ArrayLike | None = None,
                  offset: ArrayLike | None = None, parity: int | np.integer | None = None,
                  function: str | None = None) -> DigitalObject:
        """An empty object of one voxel that holds a place only: ``pitch``,
        ``origin``, ``offset`` and ``parity`` (None: the defaults) checked
        as every object's are, so that a table or a file written without a
        DigitalObject names a bad field as the object would: after
        ``function``, the function called, where it is given, else by
        itself (a reader puts its file before it).

        Examples
        --------
        >>> place = DigitalObject.placement(3, pitch=(0.5, 0.5, 2.0), origin=(1, 2, 3))
        >>> place.spacing.tolist(), place.origin.tolist(), place.voxels
        ([0.5, 0.5, 2.0], [1.0, 2.0, 3.0], 0)
        >>> DigitalObject.placement(3, pitch=-1, function="label_table")
        Traceback (most recent call last):
        ...
        isoflow.errors.IsoflowError: label_table: 'pitch' must be positive (one number, or one per axis), got -1
        """
        whole = whole_given(ndim)
        if whole is None:
            # named here, as Python's own error for (1,) * ndim names no argument; another
            # integer than 2, 3, 4 is refused by the constructor, as the array of a file would be
            raise IsoflowError(f"placement: ndim must be 2, 3 or 4, got {given_text(ndim)}")
        given: dict[str, Any] = {"pitch": pitch, "origin": origin, "offset": offset, "parity": parity}
        with _called(_CONSTRUCTOR._replace(function=function)):
            return cls(np.zeros((1,) * whole, bool), **{k: v for k, v in given.items() if v is not None})

    # ------------------------------------------------------------ geometry
    @property
    def ndim(self) -> int:
        """The dimension: 2, 3 or 4."""
        return self.volume.ndim

    @property
    def voxels(self) -> int:
        """How many voxels the object has."""
        return int(np.count_nonzero(self.volume))

    def lattice_coordinates(self, array_points: ArrayLike) -> np.ndarray:
        """Lattice coordinates of points given in array-corner units.

        Parameters
        ----------
        array_points : array_like of float, shape (..., ndim)
            Points in the array's own units: ``(i, j, k)`` is the lowest
            corner of voxel ``[i, j, k]``.

        Returns
        -------
        numpy.ndarray
            The points shifted by ``offset`` (and by 1/2 on the dual
            lattice), float64, of the same shape.

        Raises
        ------
        IsoflowError
            Points that are not numbers, or whose last axis does not hold
            one coordinate per axis of the object.

        Examples
        --------
        >>> obj = DigitalObject(np.ones((2, 2, 2), bool), offset=(5, 0, 0), parity=1)
        >>> obj.lattice_coordinates([[0, 0, 0], [2, 2, 2]]).tolist()
        [[5.5, 0.5, 0.5], [7.5, 2.5, 2.5]]
        """
        return self._points(array_points) + np.array(self.offset) + 0.5 * self.parity

    @property
    def spacing(self) -> np.ndarray:
        """The voxel size along each axis (``pitch`` as a vector)."""
        return np.broadcast_to(np.asarray(self.pitch, np.float64), (self.ndim,)).copy()

    def world(self, array_points: ArrayLike) -> np.ndarray:
        """World coordinates of points given in array-corner units.

        Parameters
        ----------
        array_points : array_like of float, shape (..., ndim)
            As in :meth:`lattice_coordinates`.

        Returns
        -------
        numpy.ndarray
            ``origin + pitch * lattice_coordinates(array_points)``.

        Raises
        ------
        IsoflowError
            As :meth:`lattice_coordinates`.

        Examples
        --------
        Voxel ``[1, 0, 0]`` of a 0.5 mm grid whose lattice point 0 is at
        x = 10 spans x = 10.5 to 11:

        >>> obj = DigitalObject(np.ones((2, 1, 1), bool), pitch=0.5, origin=(10, 0, 0))
        >>> obj.world([[1, 0, 0], [2, 1, 1]]).tolist()
        [[10.5, 0.0, 0.0], [11.0, 0.5, 0.5]]
        """
        return self.origin + self.spacing * self.lattice_coordinates(array_points)

    def _points(self, array_points: ArrayLike) -> np.ndarray:
        # checked here: NumPy's broadcast error named neither the argument
        # nor the object's dimension, and a string gave "could not convert"
        points = as_array(array_points, "array_points")
        if points.dtype.kind not in "biuf":
            raise IsoflowError(f"array_points: coordinates must be numbers, got an array of type {points.dtype}")
        if points.ndim == 0 or points.shape[-1] != self.ndim:
            raise IsoflowError(f"array_points: a {self.ndim}D object's points have {self.ndim} coordinates "
                               f"(the last axis), got shape {points.shape}")
        return np.asarray(points, np.float64)

    def bbox(self) -> tuple[np.ndarray, np.ndarray] | None:
        """World [min corner, max corner] of the object's voxels; None if empty.

        Examples
        --------
        >>> v = np.zeros((4, 4), bool); v[1:3, 2] = True
        >>> [c.tolist() for c in DigitalObject(v, pitch=0.5, origin=(10, 0)).bbox()]
        [[10.5, 1.0], [11.5, 1.5]]
        >>> DigitalObject(np.zeros((2, 2), bool)).bbox() is None
        True
        """
        if not self.volume.any():
            return None
        lo, hi = _nonzero_bounds(self.volume)
        return self.world(lo), self.world(hi)

    def cropped(self) -> DigitalObject:
        """The same object in the smallest array that holds it.

        An empty object is held by an array of no voxels, which has no
        place: its offset is zeros (parity, pitch and origin are kept), so
        that every empty object crops to the same one.

        Examples
        --------
        >>> v = np.zeros((4, 4), bool); v[1:3, 2] = True
        >>> c = DigitalObject(v, offset=(5, 5)).cropped()
        >>> c.volume.shape, c.offset
        ((2, 1), (6, 7))
        >>> DigitalObject(np.zeros((4, 4), bool), offset=(5, 5)).cropped().offset
        (0, 0)
        """
        if not self.volume.any():
            # an object of no voxels has no place: one offset for all, so that empty objects compare equal
            return replace(self, volume=np.zeros((0,) * self.ndim, bool), offset=(0,) * self.ndim)
        lo, hi = _nonzero_bounds(self.volume)
        sl = tuple(slice(a, b) for a, b in zip(lo, hi))
        return replace(
            self,
            volume=self.volume[sl],
            offset=tuple(int(o + a) for o, a in zip(self.offset, lo)),
        )

    def on_dual_lattice(self, vertex_volume: np.ndarray | None = None) -> DigitalObject:
        """A volume indexed by this object's lattice vertices, as an object on
        the other lattice (eq. 5.1): its voxel ``w`` is the cube centred at
        vertex ``w``. ``vertex_volume`` has this volume's shape plus one per
        axis, as :func:`isoflow.digital.configurations.configurations` gives;
        ``parity' = 1 - parity``, and ``offset' = offset - 1`` from parity 0,
        ``offset' = offset`` from parity 1. Not cropped.

        Parameters
        ----------
        vertex_volume : numpy.ndarray of bool, optional
            One per lattice vertex of this object's volume: its shape that
            volume's plus one per axis. Omitted, the result is the
            placement alone, an empty volume (where a step's voxels are
            placed before they are known).

        Returns
        -------
        DigitalObject
            On the other lattice, with this one's pitch and origin.

        Raises
        ------
        IsoflowError
            ``vertex_volume`` of another shape, naming the shape expected
            and the one given.

        Examples
        --------
        >>> from isoflow import configurations
        >>> cube = DigitalObject(np.ones((2, 2, 2), bool))
        >>> touched = cube.on_dual_lattice(configurations(cube.volume) > 0)  # the vertices a voxel touches
        >>> touched.volume.shape, touched.offset, touched.parity, touched.voxels
        ((3, 3, 3), (-1, -1, -1), 1, 27)
        >>> cube.on_dual_lattice().volume.shape, cube.on_dual_lattice().offset
        ((0, 0, 0), (-1, -1, -1))
        """
        if vertex_volume is None:
            vertex_volume = np.zeros((0,) * self.ndim, bool)
        else:
            expected = tuple(n + 1 for n in self.volume.shape)
            if np.shape(vertex_volume) != expected:
                raise IsoflowError(f"on_dual_lattice: vertex_volume has shape {np.shape(vertex_volume)}, not "
                                   f"{expected}: one per lattice vertex of this object's volume of shape "
                                   f"{self.volume.shape}, its shape plus one per axis")
        offset = tuple(o - 1 for o in self.offset) if self.parity == 0 else self.offset
        return replace(self, volume=vertex_volume, offset=offset, parity=1 - self.parity)

    def __repr__(self) -> str:
        return (
            f"DigitalObject(shape={self.volume.shape}, voxels={self.voxels}, "
            f"offset={self.offset}, parity={self.parity}, pitch={_significant(self.pitch)}, "
            f"origin={self.origin.tolist()}" + ("" if self.unit is None else f", unit={self.unit!r}")
            + ("" if self.space is None else f", space={self.space!r}") + ")"
        )


class _Caller(NamedTuple):
    """Who a DigitalObject made now is made for, as its refusals say it:
    the function called (None: no function, where a reader puts its file
    before them), its volume's name (the constructor's, or the function's
    and its argument's), and what a label image is offered
    (:func:`~isoflow.scale.arrays.binary`'s ``remedy`` and
    ``remedy_dims``)."""

    function: str | None
    volume: str
    remedy: str
    remedy_dims: tuple[int, ...]


#: the constructor called by itself
_CONSTRUCTOR = _Caller("DigitalObject", "DigitalObject volume", "DigitalObject({})", (2, 3))
#: whom a DigitalObject made now is made for: the one mechanism that names
#: the function called in a refusal of its volume (DigitalObject.of)
_CALLED: ContextVar[_Caller] = ContextVar("called", default=_CONSTRUCTOR)


@contextlib.contextmanager
def _called(caller: _Caller) -> Iterator[None]:
    """Within it, a DigitalObject made refuses its fields and its volume
    as ``caller`` says."""
    token = _CALLED.set(caller)
    try:
        yield
    finally:
        _CALLED.reset(token)


def _held(vol: np.ndarray, given: Any) -> np.ndarray:
    """The volume an object keeps, read-only: a copy where ``vol`` is the
    caller's writeable array (or the one an object given in its place
    holds) or a view of memory someone else could write (under the
    object, and its answers with it), a read-only view of a writeable
    array included; ``vol`` itself where :func:`binary` made it anew (a
    conversion from 0/1 integers, or from nested lists) or nothing can
    write its memory (a file's, handed over:
    :func:`~isoflow.results.handed_over`)."""
    # np.asarray of an object that is no array or sequence (one with __array__, as an xarray DataArray
    # has, or a memoryview) may give that object's own memory, which read_only would have frozen too
    theirs = vol is given or vol.base is not None or not isinstance(given, (np.ndarray, list, tuple))
    if (vol.flags.writeable and theirs) or writeable_under(vol):
        vol = vol.copy()
    return read_only(vol)


def _significant(pitch: float | np.ndarray) -> float | list[float]:
    """The pitch to 12 significant digits, as the repr shows it: 0.1 where
    arithmetic left 0.10000000000000002, and 8.249e-11 (0.8249 Angstrom in
    metres) whole, which 12 decimals cut to 8.2e-11 (and 1e-13 to 0.0)."""
    shown = [float(f"{p:.12g}") for p in np.atleast_1d(np.asarray(pitch, np.float64))]
    return shown if np.ndim(pitch) else shown[0]


def _nonzero_bounds(volume: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Smallest index and one past the largest index of True voxels, per axis."""
    lo, hi = [], []
    for axis in range(volume.ndim):
        others = tuple(a for a in range(volume.ndim) if a != axis)
        where = np.flatnonzero(volume.any(axis=others))
        lo.append(where[0])
        hi.append(where[-1] + 1)
    return np.array(lo), np.array(hi)


#: Largest |coordinate| of a lattice point, voxel index or offset: exact in
#: float64 and far from int64 overflow when extents are computed.
MAX_COORDINATE = 2**40


def _integer_points(points, what: str) -> np.ndarray:
    arr = as_array(points, f"{what} coordinates")
    if arr.size == 0 and arr.ndim < 2:
        # (0, n): no points, which still says its dimension; [] says none
        raise IsoflowError(f"an empty list of {what} coordinates has no dimension: pass np.empty((0, 3)) for the "
                           "empty 3D object (np.empty((0, 2)) in 2D)")
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise IsoflowError(f"expected a list of 2D or 3D {what} coordinates, got shape {arr.shape}")
    if arr.dtype.kind not in "biuf":
        raise IsoflowError(f"{what} coordinates must be integers, got an array of type {arr.dtype}")
    if arr.dtype.kind == "f" and (not np.all(np.isfinite(arr)) or not np.all(arr == np.round(arr))):
        raise IsoflowError(f"{what} coordinates must be integers")
    # compare before converting: uint64 / huge floats would wrap in int64
    out = (arr > MAX_COORDINATE) | (arr < -MAX_COORDINATE)
    if out.any():
        value = arr[out].flat[0]
        raise IsoflowError(f"{what} coordinate {value} is out of range (beyond +-{MAX_COORDINATE})")
    return arr.astype(np.int64)


def _check_grid(lo, hi, count: int, what: str, bytes_per_voxel: int) -> None:
    """Refuse, before allocating, a grid spanning lo..hi beyond the memory budget."""
    import math

    from ..scale.memory import check_fits

    extents = [int(b) - int(a) + 1 for a, b in zip(lo, hi)]
    check_fits(
        math.prod(extents) * bytes_per_voxel,
        f"a {'x'.join(map(str, extents))} grid for {count} {what} from {tuple(map(int, lo))} to {tuple(map(int, hi))}",
        hint="check for stray or far-apart points",
    )


def checked_pitch(value: ArrayLike, ndim: int, name: str = "pitch") -> float | np.ndarray:
    """A voxel size as a lattice keeps it, or a one-line refusal.

    Parameters
    ----------
    value : array_like
        One number, or one per axis.
    ndim : int
        The axes.
    name : str
        The field as the refusals name it (a file's own word for a voxel
        size, such as an ``.npz``'s ``spacing``).

    Returns
    -------
    float or numpy.ndarray
        A positive float, or a vector of ``ndim`` positive floats (a
        read-only array) when the voxels are anisotropic; a vector whose
        entries are all equal becomes one number, so that isotropic stays a
        scalar.

    Examples
    --------
    >>> checked_pitch([0.5, 0.5, 0.5], 3), checked_pitch([1, 2, 2], 3).tolist()
    (0.5, [1.0, 2.0, 2.0])
    >>> checked_pitch([1, -1, 1], 3, "spacing")
    Traceback (most recent call last):
        ...
    isoflow.errors.IsoflowError: 'spacing' must be positive (one number, or one per axis), got [1, -1, 1]
    """
    _unmasked(value, name)
    arr = as_array(value, f"'{name}'")  # nested lists of uneven lengths named, not NumPy's ValueError
    # in a voxel size's words, before _field's
    _refuse_bools(value, arr, name, "a number (one, or one per axis)")
    arr = _object_numbers(arr)
    if arr.ndim == 0 and arr.dtype.kind not in "biuf":
        # one value, no number: _field's "3 numbers, one per axis" reads as if one number were not taken
        raise IsoflowError(f"'{name}' must be a number (one, or one per axis), got {given_text(arr.item())}")
    if arr.dtype.kind in "iuf" and not np.isfinite(arr).all():
        # named as what a voxel size must be: _field's "3 numbers, one per axis" reads as a count that is wrong
        raise IsoflowError(f"'{name}' must be finite and positive (one number, or one per axis), got {number_text(arr)}")
    if arr.dtype.kind in "biuf" and arr.size == 1 and arr.ndim <= 1:
        pitch = _field(arr.reshape(()), name, None)
    else:
        pitch = _field(value, name, ndim)
    if not np.all(np.asarray(pitch) > 0):
        raise IsoflowError(f"'{name}' must be positive (one number, or one per axis), got {number_text(arr)}")
    if np.ndim(pitch) == 0:
        return float(pitch)
    if np.all(pitch == pitch[0]):
        return float(pitch[0])
    pitch = pitch.copy()
    pitch.flags.writeable = False
    return pitch


def _object_numbers(arr: np.ndarray) -> np.ndarray:
    """``arr`` as float64 where it holds numbers as Python objects (a list
    of ints and floats through ``np.array(..., dtype=object)``, a pandas
    column, a ``Fraction``): numbers all the same; else ``arr`` itself.

    Examples
    --------
    >>> from fractions import Fraction
    >>> _object_numbers(np.array(Fraction(1, 2), dtype=object)).item(), _object_numbers(np.array("1")).dtype.kind
    (0.5, 'U')
    """
    if arr.dtype == object and all(isinstance(v, Real) and not isinstance(v, (bool, np.bool_)) for v in arr.flat):
        return arr.astype(np.float64)
    return arr


def _refuse_bools(value, arr: np.ndarray, name: str, want: str) -> None:
    """Refuse True or False as a field's value or among its elements
    (``arr``: ``value`` as an array): a slip, not the number 1 or 0. A bool
    among numbers, ``(True, 0, 0)``, becomes 1 in ``asarray``, so the
    elements of a small value are looked at as given.

    Examples
    --------
    >>> _refuse_bools((True, 2.0, 1.0), np.asarray((True, 2.0, 1.0)), "pitch", "numbers")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: 'pitch' must be numbers, not True or False, got [True, 2.0, 1.0]
    """
    held = np.asarray(value, dtype=object) if arr.size <= 8 else arr
    if arr.dtype.kind == "b" or any(isinstance(v, (bool, np.bool_)) for v in held.flat):
        items = [v.item() if isinstance(v, np.generic) else v for v in held.flat]
        what = f"an array of shape {arr.shape}" if held is arr else repr(items[0] if arr.ndim == 0 else items)
        raise IsoflowError(f"'{name}' must be {want}, not True or False, got {what}")


def _unmasked(value, name: str) -> None:
    """Refuse a masked array with masked elements as a field's value: NumPy
    reads the number stored under the mask, which is missing data.

    Examples
    --------
    >>> _unmasked(np.ma.masked_array([1.0, 2.0, 3.0], [0, 1, 0]), "pitch")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: 'pitch': a masked array with 1 masked element; pass its numbers (a.data, or a.filled(x))
    """
    if is_masked_array(value) and np.ma.count_masked(value):
        raise IsoflowError(f"'{name}': a masked array with {counted(int(np.ma.count_masked(value)), 'masked element')}; "
                           "pass its numbers (a.data, or a.filled(x))")


def _field(value, name: str, length: int | None, integral: bool = False, bound: float | None = None):
    """A finite number (``length`` None; a one-element array will do) or a
    vector of ``length`` numbers, integers where ``integral``, within
    ``+-bound``; otherwise an error naming the field and the value."""
    _unmasked(value, name)
    arr = given = as_array(value, f"'{name}'")  # nested lists of uneven lengths named, not NumPy's ValueError

    def shown() -> str:
        if given.size > 8:
            return f"an array of shape {given.shape}"
        # numbers as meant: asarray of (1.5, 0) holds 0.0, which is the 0 given
        return number_text(given) if given.dtype.kind in "biuf" else repr(given.tolist())

    def bad() -> IsoflowError:
        want = ("an integer" if integral else "a number") if length is None else (
            f"{length} {'integers' if integral else 'numbers'}, one per axis")
        hint = ""
        if length is not None and given.ndim == 0 and given.dtype.kind in "iuf":
            # the voxel size takes one number for every axis, so one number looks
            # as if it should do for a point too: say what to write instead
            hint = (f" (unlike the voxel size, one number does not stand for every axis): "
                    f"{name}=({', '.join([shown()] * length)})")
        return IsoflowError(f"'{name}' must be {want}, got {shown()}{hint}")

    _refuse_bools(value, arr, name, "integers" if integral else "numbers")
    arr = _object_numbers(arr)
    if arr.dtype.kind not in "biuf":  # strings, complex, other objects
        raise bad()
    if (arr.size != 1) if length is None else (arr.shape != (length,)):
        raise bad()
    f = arr.astype(np.float64)
    if not np.isfinite(f).all():  # the count is right: say what is wrong with the value
        raise IsoflowError(f"'{name}' must be finite, got {shown()}")
    if integral and (f != np.round(f)).any():
        raise bad()
    if bound is not None and (np.abs(f) > bound).any():
        raise IsoflowError(f"'{name}' {shown()} is out of range (beyond +-{bound})")
    return f.item() if length is None else f
