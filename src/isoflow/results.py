"""What isoflow's entry points return: frozen dataclasses that read as mappings.

A result's fields are typed attributes (``report.euler_characteristic``) and
also keys (``report["euler_characteristic"]``), as scikit-image's region
properties are; :meth:`Result.to_dict` gives exactly the JSON object the
command line prints. Fields whose metadata says ``omit_none`` and whose
value is None are left out of the keys and of the JSON (a report without
surfaces has no ``surfaces`` key), so that a key is present iff it was
computed; a field of :func:`omitted_with` is left out with the fields it
names.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np

#: field metadata of a field that is absent (not a key, not in the JSON) when None
OMIT_NONE = {"omit_none": True}


def omitted_with(*names: str) -> dict[str, tuple[str, ...]]:
    """Field metadata of a field that is a key exactly where one of the
    fields ``names`` is (None among its values is then an answer, as an
    empty object's box: ``null`` in the JSON, not a key left out).

    Examples
    --------
    >>> omitted_with("volume", "area")
    {'omit_with': ('volume', 'area')}
    """
    return {"omit_with": names}


def json_ready(value: Any) -> Any:
    """``value`` with results, tuples and NumPy scalars and arrays turned into
    the dicts, lists and Python numbers that :func:`json.dumps` takes; a
    sequence held as columns (a report's surfaces) by its own ``tolist``,
    which gives plain dicts and numbers as an array's gives numbers.

    Examples
    --------
    >>> json_ready((np.int64(3), [np.float32(0.5)]))
    [3, [0.5]]
    """
    if isinstance(value, Result):
        return value.to_dict()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):  # a result's part (a verdict's stop)
        return {f.name: json_ready(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {str(k): json_ready(v) for k, v in value.items()}
    tolist = getattr(value, "tolist", None) if isinstance(value, Sequence) else None
    if callable(tolist):
        return tolist()
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def read_only(a: np.ndarray) -> np.ndarray:
    """``a``, made read-only in place and returned: an array that is shared
    (a cached table) or held by a frozen result, which no holder may change.

    Parameters
    ----------
    a : numpy.ndarray
        The array.

    Returns
    -------
    numpy.ndarray
        ``a`` itself.

    Examples
    --------
    >>> read_only(np.zeros(2)).flags.writeable
    False
    """
    a.flags.writeable = False
    return a


def writeable_under(a: np.ndarray) -> bool:
    """Whether the memory that ``a`` views can still be written through
    something else: an array it views, however deep, that is writeable,
    or a writeable buffer under them (a ``bytearray``, an ``mmap`` opened
    for writing). A read-only view of such memory changes when its owner
    writes.

    Parameters
    ----------
    a : numpy.ndarray
        A view, or an array that owns its memory.

    Returns
    -------
    bool
        False where ``a`` owns its memory, or every array and buffer under
        it is read-only (a file mapped for reading, ``bytes``).

    Examples
    --------
    >>> owner = np.zeros(3)
    >>> writeable_under(read_only(owner.view())), writeable_under(read_only(np.zeros(3)))
    (True, False)
    """
    base: Any = a.base
    while base is not None:
        if isinstance(base, np.ndarray):
            if base.flags.writeable:
                return True
        else:
            try:
                with memoryview(base) as buffer:
                    if not buffer.readonly:
                        return True
            except (TypeError, ValueError):  # no buffer (as_strided's holder of the array), or a closed mmap
                pass
        base = getattr(base, "base", None)
    return False


def handed_over(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only in place with every array it views, and
    returned: a volume that its maker gives to a holder that copies memory
    others could still write (a :class:`~isoflow.digital.lattice.DigitalObject`)
    and keeps no writeable handle on, so that it is held without a copy.

    Parameters
    ----------
    a : numpy.ndarray
        The array; the arrays it views are the maker's own.

    Returns
    -------
    numpy.ndarray
        ``a``, now read-only, as the arrays under it are.

    Examples
    --------
    >>> owner = np.zeros((2, 3))
    >>> view = handed_over(owner.T)
    >>> view.flags.writeable, owner.flags.writeable, writeable_under(view)
    (False, False, False)
    """
    base: Any = a
    while isinstance(base, np.ndarray):
        base.flags.writeable = False
        base = base.base
    return a


def read_only_fields(obj: Any) -> None:
    """Make the array fields of the dataclass instance ``obj`` read-only,
    each as a read-only view where it is writeable, so that an array the
    caller passed keeps its own flags.

    Parameters
    ----------
    obj : dataclass instance
        A frozen result; its fields are set with ``object.__setattr__``.

    Examples
    --------
    >>> @dataclasses.dataclass(frozen=True)
    ... class Box:
    ...     corner: np.ndarray
    >>> given = np.zeros(3)
    >>> box = Box(given)
    >>> read_only_fields(box)
    >>> box.corner.flags.writeable, given.flags.writeable
    (False, True)
    """
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if isinstance(value, np.ndarray) and value.flags.writeable:
            object.__setattr__(obj, f.name, read_only(value.view()))


def same_values(a: Any, b: Any) -> bool:
    """Whether two values are equal, NumPy arrays among them (and in the
    lists, tuples and mappings that hold them) by shape and elements: ``==``
    on an array gives an array, whose truth NumPy refuses (``ValueError``).

    Parameters
    ----------
    a, b : Any
        The values.

    Returns
    -------
    bool

    Examples
    --------
    >>> same_values({"n": np.arange(3), "b": [1, 0]}, {"n": np.arange(3), "b": [1, 0]})
    True
    >>> same_values(np.zeros(2), np.zeros(3)), same_values((1, np.ones(2)), (1, np.zeros(2)))
    (False, False)
    """
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.shape(a) == np.shape(b) and bool(np.array_equal(a, b))
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(map(same_values, a, b))
    if isinstance(a, Mapping) and isinstance(b, Mapping) and not (isinstance(a, Result) or isinstance(b, Result)):
        return a.keys() == b.keys() and all(same_values(a[k], b[k]) for k in a)
    return bool(a == b)


def same_fields(a: Any, b: object) -> bool:
    """The ``__eq__`` of a dataclass with array fields: the same type and
    every field :func:`same_values` (the ``__eq__`` a dataclass generates
    compares the fields as tuples, and so fails on the arrays).

    Parameters
    ----------
    a : dataclass instance
        The instance compared.
    b : object
        What it is compared with.

    Returns
    -------
    bool
        ``NotImplemented`` for another type, so that Python tries ``b``'s
        own comparison, and then identity.

    Examples
    --------
    >>> @dataclasses.dataclass(eq=False)
    ... class Box:
    ...     corner: np.ndarray
    ...     __eq__ = same_fields
    >>> Box(np.zeros(3)) == Box(np.zeros(3)), Box(np.zeros(3)) == Box(np.ones(3))
    (True, False)
    """
    names = [f.name for f in dataclasses.fields(a)]  # before the test below narrows ``a`` to ``b``'s type
    if type(a) is not type(b):
        return NotImplemented
    return all(same_values(getattr(a, name), getattr(b, name)) for name in names)


#: items of a list and entries of a dict that a result's repr shows (a 3D
#: report's nine classes in full): a noisy scan has thousands of surfaces
#: and a long flow thousands of steps, which made the repr megabytes long
SHOWN_ITEMS = 10
#: elements of an array shown at each end of an axis, as NumPy cuts them
ARRAY_EDGE = 3


def brief(value: Any) -> str:
    """The repr of ``value`` with its long lists, dicts and arrays cut to
    their first :data:`SHOWN_ITEMS` items and a count of the rest.

    Parameters
    ----------
    value : Any
        A result's field.

    Returns
    -------
    str

    Examples
    --------
    >>> brief([{"genus": 0}] * 12)  # doctest: +ELLIPSIS
    "[{'genus': 0}, {'genus': 0}, ..., {'genus': 0}, ... 2 more]"
    >>> brief(np.arange(256))  # doctest: +ELLIPSIS
    'array([  0,   1,   2, ..., 253, 254, 255]...)'
    >>> brief(np.zeros((98, 3)))
    'array(..., shape=(98, 3), dtype=float64)'
    >>> brief((1, 2))
    '(1, 2)'
    """
    if isinstance(value, np.ndarray) and value.ndim > 1:
        # NumPy prints a row a line, every row up to 1000 numbers: a small
        # mesh's vertices took hundreds of lines
        return f"array(..., shape={value.shape}, dtype={value.dtype})"
    if isinstance(value, np.ndarray):
        with np.printoptions(threshold=2 * ARRAY_EDGE, edgeitems=ARRAY_EDGE):
            return repr(value)
    # (a sequence of another type, as a report's surfaces held as columns,
    # reprs as a list)
    if isinstance(value, Sequence) and not isinstance(value, (str, bytes, bytearray, range)) \
            and not hasattr(value, "_fields"):  # a named tuple reprs its names
        items = [brief(v) for v in value[:SHOWN_ITEMS]] + more(len(value))
        return ("[{}]" if not isinstance(value, tuple) else "({},)" if len(value) == 1 else "({})").format(", ".join(items))
    if isinstance(value, dict):
        items = [f"{k!r}: {brief(v)}" for k, v in list(value.items())[:SHOWN_ITEMS]] + more(len(value))
        return "{" + ", ".join(items) + "}"
    return repr(value)


def fields_repr(obj: Any) -> str:
    """The repr of a dataclass instance with each field that its repr shows
    cut short by :func:`brief`: what a result, a mesh and a label image
    print in a notebook.

    Parameters
    ----------
    obj : dataclass instance

    Returns
    -------
    str

    Examples
    --------
    >>> @dataclasses.dataclass(repr=False)
    ... class Mesh:
    ...     vertices: np.ndarray
    ...     connectivity: int
    ...     __repr__ = fields_repr
    >>> Mesh(np.zeros((98, 3)), 6)
    Mesh(vertices=array(..., shape=(98, 3), dtype=float64), connectivity=6)
    """
    shown = [f.name for f in dataclasses.fields(obj) if f.repr]
    return f"{type(obj).__name__}({', '.join(f'{k}={brief(getattr(obj, k))}' for k in shown)})"


def more(count: int) -> list[str]:
    """What :func:`brief` says of the items past the first shown."""
    return [f"... {count - SHOWN_ITEMS} more"] if count > SHOWN_ITEMS else []


class Result(Mapping[str, Any]):
    """Base of isoflow's result dataclasses: fields read as attributes and
    as keys, and :meth:`to_dict` is the command line's JSON.

    Subclasses are ``@dataclasses.dataclass(frozen=True, repr=False)``,
    taking this class's short repr; a field with ``metadata=OMIT_NONE`` is
    not a key while it is None. Array fields are read-only, when made and
    when unpickled alike.
    """

    def __repr__(self) -> str:
        # the whole of a big result stays in to_dict and the attributes
        return fields_repr(self)

    def __post_init__(self) -> None:
        # frozen fields hold arrays that could still be written in place
        read_only_fields(self)

    def __setstate__(self, state: dict[str, Any]) -> None:
        # pickle restores the fields without __init__, and NumPy unpickles
        # every array writeable
        self.__dict__.update(state)
        read_only_fields(self)

    def _keys(self) -> list[str]:
        fields = dataclasses.fields(self)  # type: ignore[arg-type]
        absent = {f.name for f in fields if f.metadata.get("omit_none") and getattr(self, f.name) is None}
        return [
            f.name
            for f in fields
            if f.name not in absent and not ("omit_with" in f.metadata and absent.issuperset(f.metadata["omit_with"]))
        ]

    def __getitem__(self, key: str) -> Any:
        if key in self._keys():
            return getattr(self, key)
        raise KeyError(key)

    def __iter__(self) -> Iterator[str]:
        return iter(self._keys())

    def __len__(self) -> int:
        return len(self._keys())

    def __eq__(self, other: object) -> bool:
        # a mapping's equality (the items), with the arrays among the values
        # compared by their elements: Mapping's own raised NumPy's ValueError
        if not isinstance(other, Mapping):
            return NotImplemented
        return len(self) == len(other) and all(k in other and same_values(self[k], other[k]) for k in self)

    def to_dict(self) -> dict[str, Any]:
        """The result as plain dicts, lists and numbers (what ``--json`` prints).

        Returns
        -------
        dict
            The fields that are keys, in their order, with tuples as lists
            and NumPy scalars and arrays as Python numbers and lists, so
            that ``json.dumps`` takes it.

        Examples
        --------
        >>> import json
        >>> from isoflow import analyze
        >>> report = analyze(np.ones((2, 2, 2), bool))
        >>> json.loads(json.dumps(report.to_dict()))["betti"]
        [1, 0, 0]
        """
        return {k: json_ready(getattr(self, k)) for k in self._keys()}

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]):  # noqa: ANN206 (the subclass)
        """The result with the given fields; keys it does not know are refused."""
        names = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        unknown = set(values) - names
        if unknown:
            raise TypeError(f"{cls.__name__} has no fields {sorted(unknown)}")
        return cls(**values)
