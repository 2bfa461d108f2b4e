"""Every isoflow exception crosses a process as it was raised: its class,
its message and every attribute given to it.

A worker process hands its error back pickled: dask's processes scheduler
with cloudpickle, dask.distributed after installing tblib's picklers on
it (``tblib.pickling_support.install``, in ``distributed.core.error_message``),
which rebuild an exception whose class has a custom ``__init__`` through
``cls.__new__``. Where the copy does not load, distributed sends
``Exception(repr(exc))`` in its place."""

import copyreg
import pickle

import numpy as np
import pytest

from isoflow.errors import DoesNotFit, IsoflowError, NoSuchFile, NotAPath, missing
from isoflow.mesh.formats.magicavoxel import ModelTooLarge
from isoflow.mesh.grid import GridTooLarge
from isoflow.mesh.surface_blocks import EmptySurface
from isoflow.scale.arrays import NotBinary


def examples() -> list[tuple[BaseException, dict]]:
    """One error of each class, beside the attributes it was given."""
    cases: list[tuple[BaseException, dict]] = [
        (IsoflowError("a.npy: empty"), {}),
        (IsoflowError.worded("pass force=True", "pass --force"), {"command_line": "pass --force"}),
        (NotAPath("read_volume: path must be a str or os.PathLike, got NoneType None"), {}),
        (missing("gone.npy"), {}),
        (NoSuchFile.worded("gone.npy: no such file", "gone.npy: no such file (--out)"),
         {"command_line": "gone.npy: no such file (--out)"}),
        (EmptySurface("v.npy: no voxel of the object"), {}),
        (ModelTooLarge("big.vox: at most 256 voxels a side"), {}),
        (DoesNotFit("the table needs about 2.0 GiB of memory, more than the budget of 1.0 GiB"), {}),
    ]
    given = {"bare": "m.zarr: not a binary volume", "every": None, "ndim": 3, "kind": "labels", "value": np.uint8(255)}
    cases.append((NotBinary("m.zarr: not a binary volume; --label 255", **given), given))
    facts = {"what": "resolution=5000", "budget": 1 << 30, "shape": (5000, 5000, 5000), "fit": 1290, "store": True}
    cases.append((GridTooLarge(facts["what"], "116 GiB", facts["budget"], shape=facts["shape"], fit=facts["fit"],
                               sought=True, store=True), facts))
    return cases


def subclasses(cls: type) -> set[type]:
    return {cls} | {s for sub in cls.__subclasses__() for s in subclasses(sub)}


def same(got: BaseException, exc: BaseException, attributes: dict) -> None:
    assert type(got) is type(exc)
    assert str(got) == str(exc) and got.args == exc.args
    assert getattr(got, "command_line", None) == getattr(exc, "command_line", None)
    for name, value in attributes.items():
        assert getattr(got, name) == value, name
        assert type(getattr(got, name)) is type(value), name


def test_each_error_comes_back_from_a_worker_as_raised():
    tried = {type(exc) for exc, _ in examples()}
    missed = {c for c in subclasses(IsoflowError) if c.__module__.startswith("isoflow.")} - tried
    assert not missed, f"add an example of {sorted(c.__name__ for c in missed)}"
    for exc, attributes in examples():  # dask's processes scheduler
        same(pickle.loads(pickle.dumps(exc)), exc, attributes)
    # dask.distributed: tblib's picklers build an error of a custom __init__
    # through cls.__new__, unsafe for NoSuchFile (a ValueError and a
    # FileNotFoundError) unless its class says how it pickles
    pickling_support = pytest.importorskip("tblib.pickling_support")
    before = dict(copyreg.dispatch_table)
    try:
        for exc, attributes in examples():
            pickling_support.install(exc)
            same(pickle.loads(pickle.dumps(exc)), exc, attributes)
    finally:  # the picklers stay registered for the classes: the other tests pickle as before
        copyreg.dispatch_table.clear()
        copyreg.dispatch_table.update(before)
