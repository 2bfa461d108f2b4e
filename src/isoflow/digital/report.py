"""The shape report of a digital object as a typed result (``isoflow info``)."""

from __future__ import annotations

import dataclasses
import operator
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any, TypedDict, overload

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError
from ..results import OMIT_NONE, Result, omitted_with, read_only


class ClosedSurface(TypedDict):
    """One closed surface of the boundary mesh (docs/mathematics.md): its Euler
    characteristic ``V - E + F``, its genus ``1 - chi / 2`` and its number
    of quads.

    Examples
    --------
    A ring of eight voxels, two thick, has one closed surface, a torus:

    >>> import numpy as np
    >>> from isoflow import closed_surfaces
    >>> ring = np.ones((3, 3, 2), bool)
    >>> ring[1, 1] = False
    >>> closed_surfaces(ring, 6)["surfaces"]
    [{'euler_characteristic': 0, 'genus': 1, 'faces': 48}]
    """

    euler_characteristic: int
    genus: int
    faces: int


#: a surface's keys, in the order its dict and the JSON give them
SURFACE_KEYS = ("euler_characteristic", "genus", "faces")

#: surfaces turned into dicts at a time while iterating (a noisy object has a
#: million: their dicts all at once were the report's whole memory again)
ITER_CHUNK = 1 << 14


class ClosedSurfaces(Sequence[ClosedSurface]):
    """The closed surfaces of a report, held as two columns of int64: each
    reads as the :class:`ClosedSurface` dict it stands for.

    A noisy object has a million surfaces; a dict apiece held about 230
    bytes each, 13 times the volume's own bytes, where the columns hold 16.
    The sequence reads as the list of dicts did: ``len``, ``s[i]`` (a dict,
    negative ``i`` from the end), iteration (dicts), ``==`` with a list of
    dicts or another ``ClosedSurfaces`` (both ways), ``bool``, ``in``,
    ``repr`` (the list's own), pickling and copying. ``s[a:b]`` is a
    ``ClosedSurfaces`` of the surfaces in the slice; ``+`` joins two into a
    ``ClosedSurfaces`` and one and a list into a list. It is read-only (no
    ``append``): ``list(s)`` or :meth:`tolist` gives a list to change, and
    :meth:`columns` the arrays (a table: ``pandas.DataFrame(s.columns())``).
    ``json.dumps`` takes :meth:`tolist`, as ``Report.to_dict`` gives it.

    Parameters
    ----------
    euler_characteristic : array_like of int
        Each surface's ``V - E + F`` (even: the surfaces are closed and
        orientable).
    faces : array_like of int
        Each surface's quads, as many.

    Examples
    --------
    >>> s = ClosedSurfaces([0, 2], [48, 6])  # a torus, a cube
    >>> s
    [{'euler_characteristic': 0, 'genus': 1, 'faces': 48}, {'euler_characteristic': 2, 'genus': 0, 'faces': 6}]
    >>> len(s), s[-1]["genus"], s[:1] == [{"euler_characteristic": 0, "genus": 1, "faces": 48}]
    (2, 0, True)
    >>> {k: v.tolist() for k, v in s.columns().items()}
    {'euler_characteristic': [0, 2], 'genus': [1, 0], 'faces': [48, 6]}
    """

    __slots__ = ("_chi", "_faces")
    # equal to a list, which has no hash
    __hash__ = None  # type: ignore[assignment]

    def __init__(self, euler_characteristic: ArrayLike = (), faces: ArrayLike = ()) -> None:
        chi, quads = (np.array(a, dtype=np.int64) for a in (euler_characteristic, faces))
        if chi.ndim != 1 or chi.shape != quads.shape:
            raise IsoflowError(f"ClosedSurfaces: euler_characteristic of shape {chi.shape} and faces of shape "
                               f"{quads.shape}: two 1D columns of the same length expected")
        odd = np.flatnonzero(chi % 2)
        if len(odd):
            raise IsoflowError(f"ClosedSurfaces: surface {odd[0]} has euler_characteristic {chi[odd[0]]}, odd: "
                               f"a closed orientable surface's is even")
        self._chi, self._faces = read_only(chi), read_only(quads)

    @classmethod
    def from_list(cls, surfaces: Iterable[Mapping[str, Any]]) -> ClosedSurfaces:
        """The surfaces of a list of :class:`ClosedSurface` dicts (a report's
        JSON read back), in their order.

        Parameters
        ----------
        surfaces : iterable of mapping
            Each with the keys ``euler_characteristic``, ``genus`` and
            ``faces``, integers, the genus ``1 - chi / 2``.

        Returns
        -------
        ClosedSurfaces

        Raises
        ------
        IsoflowError
            Naming the first surface whose keys or values are not those.

        Examples
        --------
        >>> ClosedSurfaces.from_list([{"euler_characteristic": 2, "genus": 0, "faces": 6}]).columns()["faces"]
        array([6])
        """
        if isinstance(surfaces, ClosedSurfaces):
            return surfaces
        rows = list(surfaces)
        for i, s in enumerate(rows):
            if not isinstance(s, Mapping) or set(s) != set(SURFACE_KEYS):
                got = sorted(map(str, s)) if isinstance(s, Mapping) else type(s).__name__
                raise IsoflowError(f"surfaces[{i}]: {got}, where a surface has the keys {list(SURFACE_KEYS)}")
        cols = {}
        for key in SURFACE_KEYS:
            values = [s[key] for s in rows]
            plain = [i for i, v in enumerate(values) if isinstance(v, bool) or not isinstance(v, (int, np.integer))]
            if plain:
                raise IsoflowError(f"surfaces[{plain[0]}]: {key} {values[plain[0]]!r}, not an integer")
            cols[key] = np.array(values, dtype=np.int64)
        made = cls(cols["euler_characteristic"], cols["faces"])
        wrong = np.flatnonzero(cols["genus"] != 1 - made._chi // 2)
        if len(wrong):
            i = int(wrong[0])
            raise IsoflowError(f"surfaces[{i}]: genus {cols['genus'][i]}, where euler_characteristic "
                               f"{made._chi[i]} gives 1 - chi / 2 = {1 - made._chi[i] // 2}")
        return made

    def columns(self) -> dict[str, np.ndarray]:
        """The surfaces as a table: one read-only int64 array per key, in
        the order of :data:`SURFACE_KEYS`.

        Returns
        -------
        dict of str to numpy.ndarray
            ``euler_characteristic``, ``genus`` and ``faces``, one entry per
            surface (what ``pandas.DataFrame`` takes).

        Examples
        --------
        >>> ClosedSurfaces([-2, 2], [64, 6]).columns()["genus"]
        array([2, 0])
        """
        return {"euler_characteristic": self._chi, "genus": read_only(1 - self._chi // 2), "faces": self._faces}

    def _where(self, value: object) -> np.ndarray:
        """The indices of the surfaces equal to ``value`` (a surface's
        dict; nothing else equals one)."""
        if not isinstance(value, Mapping) or set(value) != set(SURFACE_KEYS) or not all(
                isinstance(value[k], (int, np.integer)) and not isinstance(value[k], bool) for k in SURFACE_KEYS):
            return np.zeros(0, np.int64)
        chi, faces, genus = (int(value[k]) for k in ("euler_characteristic", "faces", "genus"))
        if genus != 1 - chi // 2:
            return np.zeros(0, np.int64)
        return np.flatnonzero((self._chi == chi) & (self._faces == faces))

    def count(self, value: object) -> int:
        """How many surfaces equal ``value``, as a list's ``count``.

        Parameters
        ----------
        value : object
            A :class:`ClosedSurface` dict (nothing else equals a surface).

        Returns
        -------
        int

        Examples
        --------
        >>> ClosedSurfaces([2, 2], [6, 6]).count({"euler_characteristic": 2, "genus": 0, "faces": 6})
        2
        """
        return len(self._where(value))

    def index(self, value: object, start: int = 0, stop: int | None = None) -> int:
        """The first index of a surface equal to ``value`` from ``start``
        on (before ``stop``), as a list's ``index``.

        Parameters
        ----------
        value : object
            A :class:`ClosedSurface` dict.
        start, stop : int, optional
            Where to look, as a slice's bounds.

        Returns
        -------
        int

        Raises
        ------
        ValueError
            Where no surface there equals it.

        Examples
        --------
        >>> ClosedSurfaces([0, 2], [48, 6]).index({"euler_characteristic": 2, "genus": 0, "faces": 6})
        1
        """
        lo, hi, _ = slice(start, stop).indices(len(self))
        found = self._where(value)
        found = found[(found >= lo) & (found < hi)]
        if not len(found):
            raise ValueError(f"{value!r} is not among the surfaces")
        return int(found[0])

    def __contains__(self, value: object) -> bool:
        return len(self._where(value)) > 0

    def tolist(self) -> list[ClosedSurface]:
        """The surfaces as a list of new dicts (what ``json.dumps`` takes).

        Returns
        -------
        list of ClosedSurface

        Examples
        --------
        >>> ClosedSurfaces([2], [6]).tolist()
        [{'euler_characteristic': 2, 'genus': 0, 'faces': 6}]
        """
        return self._dicts(self._chi, self._faces)

    @staticmethod
    def _dicts(chi: np.ndarray, faces: np.ndarray) -> list[ClosedSurface]:
        # each column made Python ints at once: three NumPy scalars a
        # surface to read and convert otherwise
        return [{"euler_characteristic": c, "genus": g, "faces": f}
                for c, g, f in zip(chi.tolist(), (1 - chi // 2).tolist(), faces.tolist())]

    def __len__(self) -> int:
        return len(self._chi)

    @overload
    def __getitem__(self, index: int) -> ClosedSurface: ...

    @overload
    def __getitem__(self, index: slice) -> ClosedSurfaces: ...

    def __getitem__(self, index: int | slice) -> ClosedSurface | ClosedSurfaces:
        if isinstance(index, slice):
            return ClosedSurfaces(self._chi[index], self._faces[index])
        i = operator.index(index)
        if not -len(self) <= i < len(self):
            raise IndexError(f"surface index {i} out of range for {len(self)} surfaces")
        c = int(self._chi[i])
        return {"euler_characteristic": c, "genus": 1 - c // 2, "faces": int(self._faces[i])}

    def __iter__(self) -> Iterator[ClosedSurface]:
        for start in range(0, len(self), ITER_CHUNK):
            yield from self._dicts(self._chi[start:start + ITER_CHUNK], self._faces[start:start + ITER_CHUNK])

    def __eq__(self, other: object) -> bool:
        if isinstance(other, ClosedSurfaces):
            return bool(np.array_equal(self._chi, other._chi) and np.array_equal(self._faces, other._faces))
        if isinstance(other, list):  # as a list compares: item by item, and unequal to a tuple
            return len(self) == len(other) and all(a == b for a, b in zip(self, other))
        return NotImplemented

    @overload
    def __add__(self, other: ClosedSurfaces) -> ClosedSurfaces: ...

    @overload
    def __add__(self, other: list[ClosedSurface]) -> list[ClosedSurface]: ...

    def __add__(self, other: object) -> ClosedSurfaces | list[ClosedSurface]:
        if isinstance(other, ClosedSurfaces):
            return ClosedSurfaces(np.concatenate([self._chi, other._chi]), np.concatenate([self._faces, other._faces]))
        if isinstance(other, list):
            return self.tolist() + other
        return NotImplemented

    def __radd__(self, other: object) -> list[ClosedSurface]:
        if isinstance(other, list):
            return other + self.tolist()
        return NotImplemented

    def __repr__(self) -> str:
        return repr(self.tolist())

    def __reduce__(self) -> tuple[type[ClosedSurfaces], tuple[np.ndarray, np.ndarray]]:
        return ClosedSurfaces, (self._chi, self._faces)


def closed_surfaces_of(surfaces: Any) -> Any:
    """``surfaces`` as :class:`ClosedSurfaces` where it is a list of surface
    dicts (a JSON read back), else as given (None, or already columns).

    Examples
    --------
    >>> type(closed_surfaces_of([])).__name__, closed_surfaces_of(None)
    ('ClosedSurfaces', None)
    """
    return ClosedSurfaces.from_list(surfaces) if isinstance(surfaces, (list, tuple)) else surfaces


#: what ``isoflow info --json`` prints beside a report's fields: the input
#: as given, a volume file's type of values, voxel size, origin and
#: anatomical frame, a mesh's voxel grid (docs/cli.md)
INFO_INPUT_KEYS = ("input", "dtype", "pitch", "origin", "space", "voxelised")


# eq=False: the equality is Result's, a mapping's (a generated one would
# find a report unequal to the dict of its own items)
@dataclasses.dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class Report(Result):
    """Everything ``isoflow info --json`` prints about one object.

    Attributes
    ----------
    voxels : int
        Object voxels.
    dimension : int
        2, 3 or 4 (1 for a bare 1D array).
    shape : list of int
        The array's shape.
    connectivity : int
        The object's connectivity (the background takes the complementary one).
    parity : int
        The lattice the object sits on (eq. 5.1): 0 the lattice, 1 the dual.
    euler_characteristic : int
        chi, by the digital Gauss-Bonnet sum (Theorems 10-11).
    betti : list of int or None
        ``[b0, b1, b2]`` in 3D (components, tunnels, cavities), ``[b0, b1]``
        in 2D, ``[b0]`` in 1D (the runs); in 4D the Betti numbers that
        components give (the others None).
    n : list of int
        The class histogram of eq. 4.9: nine counts ``n_-4 .. n_4`` in 3D;
        convex, flat, concave in 2D (in 1D the run ends, convex, and 0, 0);
        the 45 manifold classes in 4D.
    classes : dict
        ``n`` by class label (in 4D by the class's least configuration, the
        classes that occur).
    non_well_composed : int
        Boundary vertices outside the classes of ``n`` (in 4D, outside the
        45 manifold classes: also the face-connected configurations where
        the boundary is not a 3-manifold).
    a_dot_n : int
        ``sum_v a(v)`` over every vertex, equal to ``2^n chi``.
    energy : int
        ``E = k^T n`` (eq. 5.22), ``k = a^2``, over the classes of ``n``
        alone: the ``non_well_composed`` vertices are left out, so in 4D
        this is less than :func:`isoflow.digital.ndim.surface_energy`, the
        sum over every vertex, wherever the boundary is not a manifold (two
        cells sharing one corner: 30, the other corners, against 226 at
        80-connectivity).
    a_dot_n_well_composed : int or None
        The paper's ``a^T n`` over the classes of ``n`` alone: the nine in
        3D, the 45 manifold classes in 4D (None in 1D and 2D).
    surfaces : ClosedSurfaces or None
        Each closed surface of the boundary mesh, largest first (3D, when
        asked; ``[]`` for an empty object): a read-only sequence of
        :class:`ClosedSurface` dicts held as columns (a list of them, as
        from JSON, is made one). None, and no key in the mapping
        or the JSON, where surfaces do not apply: in 2D the boundary is
        closed curves, in 4D a 3-manifold (``info`` says "not applicable").
    pinched_vertices : int or None
        Vertex contacts the mesh splits although the connectivity joins them.
    doubled_edges : int or None
        Lattice edges one sheet of the surface passes twice.
    volume, surface_area : float or None
        3D: the voxels times the volume of one, and the boundary faces
        times their area (per normal axis the product of the two other
        voxel sizes), in ``unit`` cubed and squared; inf past float64
        (``info --json`` writes null). None, and no key, in another
        dimension.
    area, perimeter : float or None
        The same in 2D: the pixels times the area of one, and the boundary
        pixel edges times their length (the pixel size along the edge).
    bbox : list of float or None
        The lowest corner of the voxels, then the highest (x, y, z, then x,
        y, z; 4 numbers in 2D), world coordinates; None (``null``) for an
        empty object. With unit voxels at 0, scikit-image's ``bbox``. A
        coordinate is None along an axis where float64 cannot keep the
        voxel corners apart (a voxel of 1 at an origin of 1e43, said in a
        warning: :mod:`isoflow.digital.float64`).
    centroid : list of float or None
        The mean of the voxels' centres, world coordinates (voxel ``v``
        spans ``[v, v + 1]``: with unit voxels at 0, scikit-image's
        ``centroid + 0.5``); None for an empty object; its coordinates
        None where the box's are.
    unit : str or None
        The length unit of the world measures: the object's (a file's, as
        :func:`isoflow.read_volume` reads it), None where it has none.
        Without a placement the voxels are unit cubes at 0, the measures in
        voxels. The measures are :func:`isoflow.label_table`'s columns of
        one label; they and ``unit`` are keys in 2D and 3D only: a 4D
        object's fourth axis is mostly time, whose step is no length (a
        hypervolume would mix frames and space), and a bare 1D array has
        no placement.

    Examples
    --------
    Fields read as attributes and as keys; ``to_dict()`` is the JSON:

    >>> import numpy as np
    >>> from isoflow import analyze
    >>> r = analyze(np.ones((2, 2, 2), bool))
    >>> r.voxels, r["euler_characteristic"], r.to_dict()["betti"]
    (8, 1, [1, 0, 0])

    Surfaces are a 3D notion: a 2D report has none, rather than an empty list:

    >>> square = analyze(np.ones((2, 2), bool))
    >>> square.surfaces is None, "surfaces" in square, "surfaces" in square.to_dict()
    (True, False, False)

    In 4D two cells sharing one corner: 30 corners of one cell, each
    ``a = 1``, and the shared corner, not a manifold point, left out:

    >>> cells = np.zeros((2, 2, 2, 2), bool)
    >>> cells[0, 0, 0, 0] = cells[1, 1, 1, 1] = True
    >>> r = analyze(cells, 80)
    >>> len(r.n), r.non_well_composed, r.energy, r.a_dot_n_well_composed, r.a_dot_n
    (45, 1, 30, 30, 16)

    World measures in the object's unit, the box and centroid ``null`` where
    it is empty:

    >>> from isoflow import DigitalObject
    >>> r = analyze(DigitalObject(np.ones((2, 2, 1), bool), pitch=(0.5, 0.5, 2.0), unit="mm"))
    >>> r.volume, r.surface_area, r.unit
    (2.0, 10.0, 'mm')
    >>> analyze(np.zeros((2, 2, 2), bool)).to_dict()["bbox"] is None
    True
    """

    voxels: int
    dimension: int
    shape: list[int]
    connectivity: int
    parity: int
    euler_characteristic: int
    betti: list[int | None]
    n: list[int]
    classes: dict
    non_well_composed: int
    a_dot_n: int
    a_dot_n_well_composed: int | None = dataclasses.field(default=None, metadata=OMIT_NONE)
    energy: int
    surfaces: ClosedSurfaces | None = dataclasses.field(default=None, metadata=OMIT_NONE)
    pinched_vertices: int | None = dataclasses.field(default=None, metadata=OMIT_NONE)
    doubled_edges: int | None = dataclasses.field(default=None, metadata=OMIT_NONE)
    volume: float | None = dataclasses.field(default=None, metadata=OMIT_NONE)
    surface_area: float | None = dataclasses.field(default=None, metadata=OMIT_NONE)
    area: float | None = dataclasses.field(default=None, metadata=OMIT_NONE)
    perimeter: float | None = dataclasses.field(default=None, metadata=OMIT_NONE)
    bbox: list[float | None] | None = dataclasses.field(default=None, metadata=omitted_with("volume", "area"))
    centroid: list[float | None] | None = dataclasses.field(default=None, metadata=omitted_with("volume", "area"))
    unit: str | None = dataclasses.field(default=None, metadata=omitted_with("volume", "area"))

    @property
    def genus(self) -> list[int] | None:
        """The genus of each closed surface, as ``surfaces`` holds them;
        None where they were not counted (2D, 4D, ``surfaces=False``), as
        ``surfaces`` is: an empty list would say the boundary has none.

        Examples
        --------
        >>> from isoflow import analyze
        >>> analyze(np.ones((3, 3, 3), bool)).genus, analyze(np.ones((3, 3), bool)).genus
        ([0], None)
        """
        return None if self.surfaces is None else self.surfaces.columns()["genus"].tolist()

    def __post_init__(self) -> None:
        # a list of surface dicts (JSON read back, a caller's own) held as
        # the columns the computed report holds
        object.__setattr__(self, "surfaces", closed_surfaces_of(self.surfaces))
        super().__post_init__()

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> Report:
        """The report with the given fields (a key it does not know is refused); a
        4D report's ``classes``, keyed by configuration, get their integer
        keys back from JSON, whose keys are strings (the report read back
        was not equal to the one written). What ``isoflow info --json``
        prints about its input beside the report (:data:`INFO_INPUT_KEYS`)
        is left out, so that the command's JSON reads back as the report.

        Examples
        --------
        >>> import json
        >>> from isoflow import analyze
        >>> r = analyze(np.ones((2, 2, 2, 2), bool), 80)
        >>> back = Report.from_dict(json.loads(json.dumps(r.to_dict())))
        >>> back == r, sorted(back.classes)
        (True, [1, 3, 15, 255])
        """
        values = {k: v for k, v in values.items() if k not in INFO_INPUT_KEYS}
        if values.get("dimension") == 4 and isinstance(values.get("classes"), Mapping):
            values["classes"] = {int(k): n for k, n in values["classes"].items()}
        return super().from_dict(values)


@dataclasses.dataclass(frozen=True, kw_only=True, eq=False, repr=False)
class SurfaceCensus(Result):
    """The closed surfaces of a 3D object's boundary mesh, counted without
    the mesh (:func:`~isoflow.digital.closed_surfaces.closed_surfaces`), and
    what the same pass gives.

    Attributes
    ----------
    surfaces : ClosedSurfaces
        Largest first: the same multiset as the components of
        ``boundary_mesh(volume, connectivity)``, held as columns (as a
        :class:`Report`'s).
    pinched_vertices : int
        The mesh's ``pinched``.
    doubled_edges : int
        The mesh's ``midpoints // 2``.
    hist : numpy.ndarray
        The 256 configuration counts.
    betti_counts : tuple of int
        b0 and the enclosed background components under the connectivity.
    """

    surfaces: list[ClosedSurface]
    pinched_vertices: int
    doubled_edges: int
    hist: np.ndarray
    betti_counts: tuple[int, int]

    def __post_init__(self) -> None:
        object.__setattr__(self, "surfaces", closed_surfaces_of(self.surfaces))
        super().__post_init__()

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> SurfaceCensus:
        """The census of :meth:`to_dict`'s JSON, its histogram an array and
        its Betti counts a tuple again (JSON makes both lists, and the census
        read back was not equal to the one written).

        Examples
        --------
        >>> import json
        >>> from isoflow import closed_surfaces
        >>> c = closed_surfaces(np.ones((2, 2, 2), bool))
        >>> back = SurfaceCensus.from_dict(json.loads(json.dumps(c.to_dict())))
        >>> back == c, back.betti_counts, back.hist.dtype
        (True, (1, 0), dtype('int64'))
        """
        given = dict(values)
        given["hist"] = np.asarray(given["hist"], dtype=np.int64)
        given["betti_counts"] = tuple(given["betti_counts"])
        return super().from_dict(given)
