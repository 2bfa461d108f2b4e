"""What isoflow's entry points return: frozen dataclasses that read as mappings.

A result's fields are typed attributes (``report.euler_characteristic``) and
also keys (``report["euler_characteristic"]``), as scikit-image's region
properties are; :meth:`Result.to_dict` gives exactly the JSON object the
command line prints. Fields whose metadata says ``omit_none`` and whose
value is None are left out of the keys and of the JSON (a report without
surfaces has no ``surfaces`` key), so that a key is present iff it was
computed.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

#: field metadata of a field that is absent (not a key, not in the JSON) when None
OMIT_NONE = {"omit_none": True}


def json_ready(value: Any) -> Any:
    """``value`` with results, tuples and NumPy scalars and arrays turned into
    the dicts, lists and Python numbers that :func:`json.dumps` takes.

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
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


class Result(Mapping[str, Any]):
    """Base of isoflow's result dataclasses: fields read as attributes and
    as keys, and :meth:`to_dict` is the command line's JSON.

    Subclasses are ``@dataclasses.dataclass(frozen=True)``; a field with
    ``metadata=OMIT_NONE`` is not a key while it is None.
    """

    def _keys(self) -> list[str]:
        return [
            f.name
            for f in dataclasses.fields(self)  # type: ignore[arg-type]
            if not (f.metadata.get("omit_none") and getattr(self, f.name) is None)
        ]

    def __getitem__(self, key: str) -> Any:
        if key in self._keys():
            return getattr(self, key)
        raise KeyError(key)

    def __iter__(self) -> Iterator[str]:
        return iter(self._keys())

    def __len__(self) -> int:
        return len(self._keys())

    def to_dict(self) -> dict[str, Any]:
        """The result as plain dicts, lists and numbers (what ``--json`` prints)."""
        return {k: json_ready(getattr(self, k)) for k in self._keys()}

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]):  # noqa: ANN206 (the subclass)
        """The result with the given fields; keys it does not know are refused."""
        names = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        unknown = set(values) - names
        if unknown:
            raise TypeError(f"{cls.__name__} has no fields {sorted(unknown)}")
        return cls(**values)
