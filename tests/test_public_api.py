"""The public API as a user and a type checker see it: ``isoflow.__all__``,
the lazy loader, the stub ``__init__.pyi`` and ``py.typed``; mypy reads
concrete types off a user's script."""

from __future__ import annotations

import ast
import importlib
import inspect
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import isoflow

PACKAGE = Path(isoflow.__file__).parent


def stub_names() -> dict[str, str]:
    """name -> module, as the stub declares them (``from .m import x as x``)."""
    tree = ast.parse((PACKAGE / "__init__.pyi").read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            for alias in node.names:
                assert alias.asname == alias.name, f"the stub re-exports {alias.name} as itself"
                out[alias.name] = "." * node.level + (node.module or alias.name)
    return out


def test_all_is_what_the_stub_declares_and_every_name_loads():
    names = stub_names()
    assert sorted(isoflow.__all__) == sorted(names) == isoflow.__all__
    for name in isoflow.__all__:
        value = getattr(isoflow, name)
        home = importlib.import_module(names[name].replace(".", "isoflow.", 1) if names[name] != "." else "isoflow")
        if inspect.ismodule(value):
            assert value is importlib.import_module(f"isoflow.{name}")
        else:
            assert getattr(home, name) is value, name


def test_nothing_but_the_api_is_public():
    # no stray names (an imported helper such as import_module) in the namespace
    # (a subpackage that has been imported is an attribute of its parent:
    # Python's import system puts it there)
    public = {n for n in dir(isoflow) if not n.startswith("_") and not inspect.ismodule(getattr(isoflow, n))}
    assert public == {n for n in isoflow.__all__ if not inspect.ismodule(getattr(isoflow, n))}
    with pytest.raises(AttributeError, match="no attribute 'import_module'"):
        isoflow.import_module  # noqa: B018


def test_the_package_says_it_is_typed():
    assert (PACKAGE / "py.typed").is_file() and (PACKAGE / "__init__.pyi").is_file()
    import tomllib

    data = tomllib.loads((PACKAGE.parents[1] / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    assert {"py.typed", "*.pyi"} <= set(data["isoflow"])


USER_SCRIPT = '''
import numpy as np
import isoflow

vol = np.zeros((4, 4, 4), dtype=bool)
obj = isoflow.DigitalObject(vol)
reveal_type(isoflow.analyze(vol))
reveal_type(isoflow.analyze(vol).betti)
reveal_type(isoflow.analyze_chunked(vol))
reveal_type(isoflow.analyze_zarr("v.zarr"))
reveal_type(isoflow.closed_surfaces(vol, 6))
reveal_type(isoflow.configurations(vol))
reveal_type(isoflow.configuration_histogram(vol))
reveal_type(isoflow.euler_characteristic(vol, 6))
reveal_type(isoflow.betti_numbers(vol, 6))
reveal_type(isoflow.euler_lut(3, 6))
reveal_type(isoflow.a_lut(6))
reveal_type(isoflow.class_histogram(isoflow.configuration_histogram(vol)))
reveal_type(isoflow.class_lut())
reveal_type(isoflow.code_lut())
reveal_type(isoflow.f_lut())
reveal_type(isoflow.gamma_lut())
reveal_type(isoflow.normal_lut())
reveal_type(isoflow.planar_index(np.ones((3, 3), bool)))
reveal_type(isoflow.CLASS_LABELS)
reveal_type(isoflow.boundary_mesh(vol, 6))
reveal_type(isoflow.boundary_mesh(vol, 6).euler_characteristic)
reveal_type(isoflow.flow_step(obj, 6))
reveal_type(isoflow.run_flow(obj, steps=1))
reveal_type(isoflow.voxelize_mesh(np.zeros((3, 3)), np.zeros((1, 3), int), resolution=4))
reveal_type(isoflow.voxelize_file("m.stl", resolution=4))
reveal_type(isoflow.voxelize_meshes(["a.stl", "b.obj"], resolution=4))
reveal_type(isoflow.voxelize_meshes(["a.stl", "b.obj"], resolution=4).overlaps)
reveal_type(isoflow.verify_genus("m.stl"))
reveal_type(isoflow.voxelize_to_zarr("m.stl", "v.zarr", resolution=4))
reveal_type(isoflow.voxelize_to_zarr("m.stl", "v.zarr", resolution=4, details=True))
reveal_type(isoflow.read_volume("v.npy"))
reveal_type(isoflow.read_object("v.npy"))
reveal_type(isoflow.read_points("p.txt"))
reveal_type(isoflow.read_label_names("lut.txt"))
reveal_type(isoflow.write_volume(obj, "v.npz"))
reveal_type(isoflow.write_labels(np.zeros((2, 2, 2), np.uint8), "l.npz", pitch=0.5))
reveal_type(isoflow.write_surface(obj, "s.ply", 6, mesh=isoflow.boundary_mesh(vol, 6), ascii=True))
reveal_type(isoflow.from_manifold(isoflow.to_manifold(obj)))  # (manifold3d has no py.typed: Manifold is Any)
reveal_type(isoflow.data.bob())
'''

@pytest.fixture(scope="module")
def mypy_cache(tmp_path_factory) -> Path:
    """One mypy cache for this module's runs: each run then reads NumPy's
    and isoflow's types from it rather than analysing them again."""
    return tmp_path_factory.mktemp("mypy-cache")


def mypy(tmp_path: Path, script: str, cache: Path, *options: str) -> subprocess.CompletedProcess:
    """mypy run on ``script`` as a user's ``user.py``, isoflow found by its stub."""
    path = tmp_path / "user.py"
    path.write_text(script)
    env = {"MYPYPATH": str(PACKAGE.parent), "PATH": "/usr/bin:/bin"}
    return subprocess.run([sys.executable, "-m", "mypy", *options, "--follow-imports=silent", "--ignore-missing-imports",
                           "--cache-dir", str(cache), str(path)],
                          capture_output=True, text=True, cwd=tmp_path, env=env)


@pytest.mark.skipif(shutil.which("mypy") is None and importlib.util.find_spec("mypy") is None,
                    reason="mypy not installed (pip install -e '.[test]')")
def test_mypy_sees_concrete_types_in_a_user_script(tmp_path, mypy_cache):
    p = mypy(tmp_path, USER_SCRIPT, mypy_cache)
    revealed = re.findall(r"user\.py:(\d+): note: Revealed type is \"(.*)\"", p.stdout)
    calls = [line for line in USER_SCRIPT.splitlines() if line.startswith("reveal_type")]
    assert len(revealed) == len(calls), p.stdout + p.stderr
    vague = [calls[i] + " -> " + t for i, (_, t) in enumerate(revealed)
             if t == "Any" or t.startswith("builtins.dict[Any") or t == "builtins.dict[builtins.str, Any]"]
    assert not vague, "\n".join(vague)
    # the results are isoflow's own types, not dicts
    assert "isoflow.digital.report.Report" in revealed[0][1]
    assert "isoflow.mesh.verdict.GenusVerdict" in revealed[calls.index('reveal_type(isoflow.verify_genus("m.stl"))')][1]
    labels = calls.index('reveal_type(isoflow.voxelize_meshes(["a.stl", "b.obj"], resolution=4))')
    assert "isoflow.mesh.label_voxels.LabelVoxelization" in revealed[labels][1]
    store = calls.index('reveal_type(isoflow.voxelize_to_zarr("m.stl", "v.zarr", resolution=4))')
    assert revealed[store][1] == "isoflow.mesh.slabs.ZarrStore"
    assert revealed[store + 1][1] == "tuple[isoflow.mesh.slabs.ZarrStore, isoflow.mesh.fills.Voxelization]"


# calls the functions take at run time (as their docstrings say), which the
# annotations refused: a bare array for write_volume, a tuple or list pitch
# and nested lists for write_labels (its own example) and DigitalObject,
# array_like volumes and origins, connectivity=None (the paper's default,
# as for analyze), a progress callback that returns a value (a progress
# bar's update; run_flow's alone wanted one returning None)
TAKEN_SCRIPT = """
import numpy as np
import isoflow

seen: list[int] = []


def tell(step: int, state: isoflow.DigitalObject) -> int:
    seen.append(state.voxels)
    return step


vol = np.zeros((4, 4, 4), dtype=bool)
vol[1:3, 1:3, 1:3] = True
isoflow.write_volume(vol, "v.npz")
isoflow.write_labels(np.ones((2, 2), np.uint16), "l.nii.gz", pitch=(0.5, 0.25))
isoflow.write_labels([[1, 2], [0, 1]], "m.nii.gz", pitch=[0.5, 0.25], origin=(1, 2))
isoflow.boundary_mesh(vol.tolist(), None)
isoflow.closed_surfaces(vol, None)
isoflow.to_manifold(vol, connectivity=None)
isoflow.write_surface(vol.tolist(), "s.ply", None)
isoflow.planar_index([[1, 0], [0, 1]])
isoflow.class_histogram(isoflow.configuration_histogram(vol).tolist())
obj = isoflow.DigitalObject(vol.tolist(), pitch=(0.5, 0.5, 1.0), origin=[1, 2, 3])
isoflow.from_manifold(isoflow.to_manifold(obj), pitch=0.5, origin=[1, 2, 3])
isoflow.label_table(vol.astype(np.uint8), pitch=np.array([0.5, 0.5, 1.0]), origin=np.zeros(3))
isoflow.run_flow(vol.tolist(), steps=1)
isoflow.run_flow(vol, steps=2, progress=tell)
isoflow.a_lut(None)
"""


@pytest.mark.skipif(shutil.which("mypy") is None and importlib.util.find_spec("mypy") is None,
                    reason="mypy not installed (pip install -e '.[test]')")
def test_mypy_takes_the_arguments_the_functions_take(tmp_path, mypy_cache):
    p = mypy(tmp_path, TAKEN_SCRIPT, mypy_cache)
    assert p.returncode == 0 and "error" not in p.stdout, p.stdout + p.stderr


# a closed set of words (a Literal): a misspelt one is a type error, and
# still refused at run time, before any file is read
MISSPELT = [
    'isoflow.read_object("p.txt", points_are="voxel")',
    'isoflow.voxelize_mesh(np.zeros((3, 3)), np.zeros((1, 3), int), resolution=4, fill="windings")',
    'isoflow.voxelize_meshes(["a.stl"], resolution=4, overlap="earlier")',
    'isoflow.analyze(vol, method="fast")',
]


@pytest.mark.skipif(shutil.which("mypy") is None and importlib.util.find_spec("mypy") is None,
                    reason="mypy not installed (pip install -e '.[test]')")
def test_mypy_refuses_a_word_outside_a_closed_set(tmp_path, mypy_cache):
    head = "import numpy as np\nimport isoflow\n\nvol = np.zeros((4, 4, 4), dtype=bool)\n"
    p = mypy(tmp_path, head + "\n".join(MISSPELT) + "\n", mypy_cache)
    first = head.count("\n") + 1
    lines = {int(n) for n in re.findall(r"user\.py:(\d+): error:", p.stdout)}
    assert lines == set(range(first, first + len(MISSPELT))), p.stdout + p.stderr


@pytest.mark.parametrize("call", MISSPELT)
def test_a_word_outside_a_closed_set_is_refused_at_run_time(call, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises((isoflow.IsoflowError, ValueError)):
        eval(call, {"np": np, "isoflow": isoflow, "vol": np.zeros((4, 4, 4), dtype=bool)})


def test_the_script_s_calls_run(tmp_path, monkeypatch):
    import trimesh

    monkeypatch.chdir(tmp_path)
    names: dict = {}
    exec(compile(TAKEN_SCRIPT, "user.py", "exec"), names)
    # the callback was told of every state after the first, as the states kept say them
    assert names["seen"] == [s.voxels for s in isoflow.run_flow(names["vol"], steps=2).states[1:]]
    assert trimesh.load(tmp_path / "s.ply", process=False).euler_number == 2  # one cube's sphere
    assert isoflow.read_labels(tmp_path / "l.nii.gz").spacing.tolist() == [0.5, 0.25]
    vol = np.load(tmp_path / "v.npz")["volume"]
    assert isoflow.boundary_mesh(vol, None) == isoflow.boundary_mesh(vol, 6)
    assert isoflow.closed_surfaces(vol, None)["surfaces"] == isoflow.closed_surfaces(vol, 6)["surfaces"]
    assert isoflow.to_manifold(vol, None).volume() == 8.0
    obj = isoflow.DigitalObject(vol.tolist(), pitch=(0.5, 0.5, 1.0), origin=[1, 2, 3])
    assert obj.spacing.tolist() == [0.5, 0.5, 1.0] and obj.world(np.zeros((1, 3))).tolist() == [[1.0, 2.0, 3.0]]

# counts, labels and connectivities as NumPy integers, as a user takes them
# from np.unique or an array: each call beside the same call with Python
# ints (``same``), which mypy refused though the functions take them
NUMPY_INT_SCRIPT = """
import json

import nibabel
import numpy as np
import trimesh

import isoflow


def same(a: object, b: object) -> None:
    assert a == b or json.dumps(a) == json.dumps(b), (a, b)


vol = np.zeros((6, 6, 6), dtype=bool)
vol[1:4, 1:4, 1:4] = True
labels = vol.astype(np.uint8)
labels[0, 0, 0] = 3
np.save("v.npy", labels)
nibabel.save(nibabel.Nifti1Image(np.stack([labels, labels], axis=-1), np.eye(4)), "t.nii.gz")  # two time points
trimesh.creation.box().export("box.stl")
c, k = np.unique(np.array([6, 26]))[1], np.int64(3)
same(isoflow.euler_characteristic(vol, np.int64(26)), isoflow.euler_characteristic(vol, 26))
same(isoflow.analyze(vol, c, threads=np.int64(1)), isoflow.analyze(vol, 26, threads=1))
same(isoflow.betti_numbers(vol, c, chi=np.int64(1)), isoflow.betti_numbers(vol, 26, chi=1))
same(isoflow.boundary_mesh(vol, c), isoflow.boundary_mesh(vol, 26))
same(isoflow.closed_surfaces(vol, c)["surfaces"], isoflow.closed_surfaces(vol, 26)["surfaces"])
same(isoflow.a_lut(c).tolist(), isoflow.a_lut(26).tolist())
same(isoflow.euler_lut(k, c).tolist(), isoflow.euler_lut(3, 26).tolist())
same(isoflow.configuration_histogram(vol, slab=np.int64(2)).tolist(), isoflow.configuration_histogram(vol, slab=2).tolist())
same(isoflow.flow_step(vol, c).voxels, isoflow.flow_step(vol, 26).voxels)
same(isoflow.run_flow(vol, steps=np.int64(2), connectivity=c)["steps"], isoflow.run_flow(vol, steps=2, connectivity=26)["steps"])
same(isoflow.run_flow(vol, max_steps=np.int64(1))["steps"], isoflow.run_flow(vol, max_steps=1)["steps"])
same(isoflow.to_manifold(vol, c).volume(), isoflow.to_manifold(vol, 26).volume())
same(isoflow.write_surface(vol, "a.ply", c).read_bytes(), isoflow.write_surface(vol, "b.ply", 26).read_bytes())
same(isoflow.label_table(labels, c, labels=np.unique(labels)[1:], threads=np.int64(1))["voxels"].tolist(),
     isoflow.label_table(labels, 26, labels=[1, 3], threads=1)["voxels"].tolist())
same(isoflow.label_table(labels, labels=[np.int64(3)])["voxels"].tolist(),
     isoflow.label_table(labels, labels=[3])["voxels"].tolist())
same(isoflow.read_volume("v.npy", label=k).voxels, isoflow.read_volume("v.npy", label=3).voxels)
same(isoflow.read_object("v.npy", label=k).voxels, isoflow.read_object("v.npy", label=3).voxels)
same(isoflow.read_volume("t.nii.gz", label=k, time=np.int64(1)).voxels, isoflow.read_volume("t.nii.gz", label=3, time=1).voxels)
same(isoflow.read_labels("t.nii.gz", time=np.int64(1)).array.tolist(), isoflow.read_labels("t.nii.gz", time=1).array.tolist())
same(isoflow.voxelize_file("box.stl", resolution=np.int64(8)).voxels, isoflow.voxelize_file("box.stl", resolution=8).voxels)
same(isoflow.voxelize_meshes(["box.stl"], resolution=np.int64(8), max_bytes=np.int64(1 << 30)).voxels,
     isoflow.voxelize_meshes(["box.stl"], resolution=8, max_bytes=1 << 30).voxels)
isoflow.voxelize_to_zarr("box.stl", "a.zarr", resolution=np.int64(8), chunks=(np.int64(4), 4, 4),
                         max_bytes=np.int64(1 << 30))
same(isoflow.analyze_zarr("a.zarr", c, block_shape=(np.int64(4), 4, 4), threads=np.int64(1)).voxels,
     isoflow.voxelize_file("box.stl", resolution=8).voxels)
same(isoflow.DigitalObject(vol, offset=(np.int64(1), 0, 0), parity=np.int64(1)),
     isoflow.DigitalObject(vol, offset=(1, 0, 0), parity=1))
same(isoflow.DigitalObject.placement(k, parity=np.int64(1)), isoflow.DigitalObject.placement(3, parity=1))
verdict = isoflow.verify_genus("box.stl", resolutions=[np.int64(8)], connectivity=c, max_resolution=np.int64(16))
same(verdict.digital[0]["connectivity"], 26)
json.dumps(verdict.digital)
"""


@pytest.mark.skipif(shutil.which("mypy") is None and importlib.util.find_spec("mypy") is None,
                    reason="mypy not installed (pip install -e '.[test]')")
def test_mypy_takes_numpy_integers_for_counts_labels_and_connectivities(tmp_path, mypy_cache):
    p = mypy(tmp_path, NUMPY_INT_SCRIPT, mypy_cache)
    assert p.returncode == 0 and "error" not in p.stdout, p.stdout + p.stderr


def test_numpy_integers_give_what_python_ints_give(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    exec(compile(NUMPY_INT_SCRIPT, "user.py", "exec"), {})


def public_functions() -> list[tuple[str, object]]:
    """Every public function: the names of ``__all__`` and of the public
    subpackages' ``__all__``."""
    out = []
    for name in isoflow.__all__:
        value = getattr(isoflow, name)
        if inspect.ismodule(value):
            out += [(f"{name}.{n}", getattr(value, n)) for n in value.__all__]
        else:
            out.append((name, value))
    return [(n, f) for n, f in out if inspect.isfunction(f)]


def test_every_public_function_is_typed():
    untyped = []
    for name, f in public_functions():
        sig = inspect.signature(f)
        untyped += [f"{name}({p})" for p, v in sig.parameters.items() if v.annotation is inspect.Parameter.empty]
        if sig.return_annotation is inspect.Signature.empty:
            untyped.append(f"{name} -> ?")
    assert not untyped, untyped


def test_every_public_function_has_a_numpydoc_docstring_with_an_example():
    # (the examples run with the suite: --doctest-modules over src/isoflow)
    lacking = []
    for name, f in public_functions():
        doc = inspect.getdoc(f) or ""
        sections = ["Returns", "Examples"] + (["Parameters"] if inspect.signature(f).parameters else [])
        lacking += [f"{name}: {s}" for s in sections if f"{s}\n{'-' * len(s)}" not in doc]
        if ">>>" not in doc:
            lacking.append(f"{name}: an example")
    assert not lacking, lacking
    classes = [n for n in isoflow.__all__ if inspect.isclass(getattr(isoflow, n))]
    assert all(inspect.getdoc(getattr(isoflow, n)) for n in classes)


def test_every_parameter_of_a_public_function_is_documented_and_only_those():
    """numpydoc's own check of the Parameters section against the
    signature (PR01: a parameter not documented, PR02: one documented that
    the function has not): verify_genus's page said nothing of
    ``max_resolution`` and ``time_limit``, which bound its doubling."""
    validate = pytest.importorskip("numpydoc.validate").validate
    wrong = []
    for name, f in public_functions():
        found = validate(f"{f.__module__}.{f.__qualname__}")["errors"]
        wrong += [f"{name}: {message}" for code, message in found if code in ("PR01", "PR02")]
    assert not wrong, wrong


def test_every_public_method_of_a_public_class_is_typed_with_an_example():
    """The methods of the public classes are on their API pages beside the
    functions, and are held to the same: ``DigitalObject.of(x)``, the
    constructor every entry point calls on the object or array it is
    given, took an unannotated ``x`` and showed no example."""
    lacking = []
    for name in isoflow.__all__:
        cls = getattr(isoflow, name)
        if not inspect.isclass(cls) or not cls.__module__.startswith("isoflow"):
            continue
        for method, raw in vars(cls).items():
            f = raw.__func__ if isinstance(raw, (classmethod, staticmethod)) else raw
            if method.startswith("_") or not inspect.isfunction(f):
                continue  # properties are read as fields, documented in a line
            sig = inspect.signature(f)
            lacking += [f"{name}.{method}({p})" for p, v in sig.parameters.items()
                        if v.annotation is inspect.Parameter.empty and p not in ("self", "cls")]
            if sig.return_annotation is inspect.Signature.empty:
                lacking.append(f"{name}.{method} -> ?")
            if ">>>" not in (inspect.getdoc(f) or ""):
                lacking.append(f"{name}.{method}: an example")
    assert not lacking, lacking


def test_every_public_class_s_page_has_an_example():
    """The API pages of IsoflowWarning and ClosedSurface showed no example,
    where every function's does: each public class's docstring (its page)
    has one, which the suite runs."""
    classes = [n for n in isoflow.__all__ if inspect.isclass(getattr(isoflow, n))]
    assert "IsoflowWarning" in classes and "ClosedSurface" in classes
    lacking = [n for n in classes if ">>>" not in (getattr(isoflow, n).__doc__ or "")]
    assert not lacking, lacking


BETTI_SCRIPT = """
import numpy as np
import isoflow

v = np.zeros((4, 4, 4), dtype=bool)
v[1:3, 1:3, 1:3] = True
b0, b1, b2 = isoflow.betti_numbers(v)
tunnels: int = b0 + b1 - b2
mask = np.ones((3, 5)) > 0
c0, c1 = isoflow.betti_numbers(mask)
holes: int = c0 - c1
reveal_type(isoflow.betti_numbers(np.zeros((2, 2, 2, 2), dtype=bool)))
"""


@pytest.mark.skipif(shutil.which("mypy") is None and importlib.util.find_spec("mypy") is None,
                    reason="mypy not installed (pip install -e '.[test]')")
def test_the_betti_numbers_of_a_3d_or_2d_array_add_up_under_mypy_strict(tmp_path, mypy_cache):
    """``b0, b1, b2 = isoflow.betti_numbers(v)`` then ``b0 + b1`` was an
    error under ``mypy --strict`` (the return was ``list[int | None]``, None
    only in 4D): mypy finds no error in 2D and 3D, and still types a 4D
    array's result with its None; at run time a 4D volume keeps b1 and b2
    None."""
    p = mypy(tmp_path, BETTI_SCRIPT, mypy_cache, "--strict")
    assert "error" not in p.stdout and 'Revealed type is "list[int | None]"' in p.stdout, p.stdout + p.stderr
    four = np.zeros((3, 3, 3, 3), bool)
    four[1, 1, 1, 1] = True
    assert isoflow.betti_numbers(four) == [1, None, None, 0]
