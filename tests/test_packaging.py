"""What a user installs: the package list in pyproject.toml, the sample data
of ``isoflow.data`` (checked against the sha256 sums of meshes/manifest.json),
``python -m isoflow``, and a wheel built and installed in a fresh virtual
environment that runs the README's first command (.ci/check-wheel)."""

from __future__ import annotations

import hashlib
import json
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from isoflow import data
from isoflow.errors import IsoflowError

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
MANIFEST = json.loads((ROOT / "meshes" / "manifest.json").read_text())["meshes"]


def test_every_package_is_listed():
    """setuptools is given the packages by name (the meshes are a mapped
    folder, which packages.find cannot see): a new subpackage must be added."""
    src = ROOT / "src"
    found = {".".join(p.parent.relative_to(src).parts) for p in src.rglob("__init__.py")}
    listed = set(PYPROJECT["tool"]["setuptools"]["packages"])
    assert listed == found | {"isoflow.data.meshes"}
    assert PYPROJECT["tool"]["setuptools"]["package-dir"]["isoflow.data.meshes"] == "meshes"


def test_users_extras_bring_only_what_isoflow_uses():
    """``isoflow[dask]``, ``[formats]`` and ``[gpu]`` are what a user
    installs to run isoflow, not its tests: each of their distributions must
    hold a module that isoflow's code imports, or names to import or look up
    (``"lxml"`` for trimesh's readers, ``"distributed"`` in ``sys.modules``).
    The distribution -> module map is the installed distributions' own
    (importlib.metadata); one not installed here cannot be checked."""
    import ast
    import importlib.metadata
    import re

    used: set[str] = set()
    for path in (ROOT / "src" / "isoflow").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                used |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                used.add(node.module.split(".")[0])
            elif isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.isidentifier():
                used.add(node.value)
    modules: dict[str, set[str]] = {}
    for module, dists in importlib.metadata.packages_distributions().items():
        for dist in dists:
            modules.setdefault(re.sub(r"[-_.]+", "-", dist).lower(), set()).add(module)
    unused = []
    for extra in ("dask", "formats", "gpu"):
        for req in PYPROJECT["project"]["optional-dependencies"][extra]:
            dist = re.sub(r"[-_.]+", "-", re.split(r"[<>=\[ ]", req)[0]).lower()
            if dist in modules and not modules[dist] & used:
                unused.append(f"{extra}: {req}")
    assert not unused, unused


def test_package_data_takes_every_sample_file():
    patterns = PYPROJECT["tool"]["setuptools"]["package-data"]["isoflow.data.meshes"]
    files = [p for p in (ROOT / "meshes").iterdir() if p.is_file()]
    assert all(any(p.match(pattern) for pattern in patterns) for p in files), files


def test_samples_are_the_manifest_files():
    assert set(data.names()) == {m["filename"] for m in MANIFEST} | {"example19.txt"}
    for m in MANIFEST:
        path = data.path(m["filename"])
        assert hashlib.sha256(path.read_bytes()).hexdigest() == m["sha256"], path
        assert data.info(m["filename"])["genus"] == m["genus"]
    assert data.folder().samefile(ROOT / "meshes")  # a checkout reads the repository's own copy


def test_named_samples_and_their_genus():
    import trimesh

    for get, genus in ((data.bob, 1), (data.spot, 0), (data.torus, 1), (data.eight, 2)):
        mesh = trimesh.load(get(), force="mesh")
        assert mesh.is_watertight and mesh.euler_number == 2 - 2 * genus, get.__name__
    points = [line for line in data.example19().read_text().splitlines() if not line.startswith("#")]
    assert len(points) == 20  # the paper's P10, P11 and P12 (eq. 5.19)


def test_a_sample_entry_changed_by_its_caller_is_not_the_next_callers():
    """``data.info`` handed out the nested dicts and lists of one cached
    manifest: a notebook that edited ``entry["tool_results"]`` or
    ``entry["extents"]`` changed what every later call returned. Each call
    is the manifest's entry as json reads the file."""
    name = "eight.off"
    entry = data.info(name)
    entry["extents"].append(99.0)
    next(iter(entry["tool_results"].values()))["changed"] = True
    entry["voxel_euler_64"].clear()
    want = next(m for m in MANIFEST if m["filename"] == name)
    assert data.info(name) == want


def test_unknown_sample_is_one_line():
    with pytest.raises(IsoflowError, match="'nope.ply': no such sample file; the samples are bob_small.ply"):
        data.path("nope.ply")
    with pytest.raises(IsoflowError, match="no such sample mesh"):
        data.info("example19.txt")


def test_python_m_isoflow_is_the_command():
    proc = subprocess.run([sys.executable, "-m", "isoflow", "info", str(data.example19()), "--json"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["voxels"] == 4


def test_wheel_installs_and_runs_the_readme_command(tmp_path):
    """python -m build, a fresh venv, the wheel's isoflow, README line 1
    (its first command twice: numba's compile note on the first run only)."""
    pytest.importorskip("build", reason="the wheel check needs `build` (pip install -e '.[test]')")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    proc = subprocess.run([sys.executable, str(ROOT / ".ci" / "check-wheel"), str(tmp_path)],
                          capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "runs the README's first command" in proc.stdout
    assert "the first run said once that numba compiles, the second loaded its cache" in proc.stdout


def test_readme_is_one_screen_and_its_python_runs(tmp_path, monkeypatch):
    """At most 150 lines; its first commands are what .ci/run runs; its
    Python quick start runs as written and says what it prints, twice, in
    the directory where the first line's ``surface ... -o bob.ply`` ran (it
    refused that ``bob.ply``: "exists; pass force=True"), and writes the
    file the command wrote."""
    from isoflow.cli.main import main

    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 150
    first, second = readme.split("```bash\n")[1].splitlines()[:2]
    assert first.startswith("pip install -e . && isoflow ") and "meshes/bob_small.ply" in first
    assert second == "pip install -e '.[test]' && python -m pytest"
    assert (ROOT / ".ci" / "run").read_text().rstrip().splitlines()[-1] == second
    code = readme.split("```python\n")[1].split("```")[0]
    monkeypatch.chdir(tmp_path)
    assert main(["surface", str(data.bob()), "--resolution", "64", "-o", "bob.ply", "--force", "-q"]) == 0
    command = (tmp_path / "bob.ply").read_bytes().split(b"end_header")[1]
    for _ in range(2):
        namespace: dict = {}
        exec(compile(code, "README.md", "exec"), namespace)
    assert (tmp_path / "bob.ply").read_bytes().split(b"end_header")[1] == command
    report = namespace["report"]
    assert [report["betti"], report["euler_characteristic"]] == [[1, 1, 0], 0]  # as its comment says
    assert list(namespace["table"]["label"]) == [3] and list(namespace["table"]["b1"]) == [1]
    assert (tmp_path / "bob.nii.gz").is_file()


def test_no_path_outside_the_repository():
    """No file of the repository names a folder of the machine it was made on."""
    roots = ("/" + "work/", "/" + "tmp/", "/" + "root/", "../" + "shared")
    places = [ROOT / "README.md", ROOT / "CHANGELOG.md", ROOT / "pyproject.toml"]
    for folder in ("docs", "benchmarks", "tests", "examples", "meshes", "src", ".ci"):
        places += [p for p in (ROOT / folder).rglob("*") if p.is_file() and not any(
            part in ("_build", "generated", "auto_examples", ".cache", "__pycache__") or part.endswith(".egg-info")
            for part in p.relative_to(ROOT).parts)]
    found = []
    for path in places:
        if path.suffix in (".npy", ".npz", ".png", ".ply", ".stl", ".STL", ".pyc"):
            continue
        text = path.read_text(errors="replace")
        found += [f"{path.relative_to(ROOT)}: {root}" for root in roots if root in text]
    assert not found, found


def extra_closure(extra: str, extras: dict[str, list[str]]) -> set[str]:
    """The distributions an extra brings, its ``isoflow[...]`` ones followed."""
    names: set[str] = set()
    for requirement in extras[extra]:
        name = re.split(r"[<>=; ]", requirement)[0]
        if name.startswith("isoflow["):
            names |= {n for inner in name[8:-1].split(",") for n in extra_closure(inner, extras)}
        else:
            names.add(re.sub(r"\[.*\]", "", name).lower().replace("_", "-"))
    return names


def test_the_docs_extra_brings_what_the_gallery_runs():
    """README.md builds the site with ``pip install -e '.[docs]'``; the
    gallery runs every example, and zarr_cluster.py imports dask, which
    that extra did not bring: the build stopped there. Every module an
    example imports is one of the core dependencies or of ``docs``, by
    the installed distributions' own metadata."""
    import ast
    import importlib.metadata

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    allowed = extra_closure("docs", project["optional-dependencies"])
    allowed |= {re.split(r"[<>=\[ ]", d)[0].lower() for d in project["dependencies"]}
    owners = importlib.metadata.packages_distributions()
    missing = []
    for script in sorted((ROOT / "examples").glob("*.py")):
        for node in ast.walk(ast.parse(script.read_text())):
            modules = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module] if isinstance(node, ast.ImportFrom) and node.module and not node.level else []
            for module in modules:
                top = module.split(".")[0]
                if top in sys.stdlib_module_names or top in ("isoflow", "_common"):
                    continue
                distributions = {d.lower().replace("_", "-") for d in owners.get(top, [top])}
                if not distributions & allowed:
                    missing.append(f"{script.name}: {module}")
    assert not missing, missing


def distribution_names(requirements: list[str]) -> set[str]:
    """The normalised distribution names of requirement strings."""
    return {re.sub(r"[-_.]+", "-", re.split(r"[<>=\[ ;]", r)[0]).lower() for r in requirements}


def test_every_module_isoflow_imports_is_declared():
    """src imported llvmlite (two compiled intrinsics) that pyproject.toml
    did not list: it came only as numba's own dependency, at whatever
    release numba picked. Every third-party module that src/isoflow imports
    belongs, by the installed distributions' metadata, to a dependency or an
    extra (a module not installed here, as CuPy without a GPU, cannot be
    checked)."""
    import ast
    import importlib.metadata

    project = PYPROJECT["project"]
    declared = distribution_names(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        declared |= distribution_names([r for r in extra if not r.startswith("isoflow[")])
    owners = importlib.metadata.packages_distributions()
    undeclared = set()
    for path in (ROOT / "src" / "isoflow").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                modules = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                modules = [node.module]
            else:
                continue
            for top in {m.split(".")[0] for m in modules} - set(sys.stdlib_module_names) - {"isoflow"}:
                dists = distribution_names(owners.get(top, []))
                if dists and not dists & declared:
                    undeclared.add(f"{path.relative_to(ROOT)}: {top} ({', '.join(sorted(dists))})")
    assert not undeclared, sorted(undeclared)


def test_no_extra_repeats_a_dependency():
    """``isoflow[bench]`` listed connected-components-3d, which every install
    already has: an extra names only what the plain install lacks."""
    project = PYPROJECT["project"]
    core = distribution_names(project["dependencies"])
    repeated = {f"{name}: {d}" for name, extra in project["optional-dependencies"].items()
                for d in distribution_names(extra) & core}
    assert not repeated, sorted(repeated)


def test_every_extra_the_pages_name_exists():
    """The install lines of README.md and docs/*.md name extras
    (``pip install -e '.[formats]'``, ``isoflow[gpu]``): each is one of
    pyproject.toml's."""
    extras = set(PYPROJECT["project"]["optional-dependencies"])
    named = {}
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "examples").glob("*"))]:
        for extra in re.findall(r"(?:\.|isoflow)\[([a-z0-9_,-]+)\]", page.read_text()):
            named.update({name: page.name for name in extra.split(",")})
    assert set(named) >= {"formats", "dask", "gpu", "test", "docs"}
    assert not set(named) - extras, {name: named[name] for name in set(named) - extras}
