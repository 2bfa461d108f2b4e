"""The scripts in examples/ do what they say, and what they print and
write agrees with independently known values: the genus in
meshes/manifest.json (isoflow.data.info), trimesh's V - E + F of the files
written, and scikit-image's Euler number of the volumes written.

Each example runs once per test session: in the documentation's gallery
when Sphinx is installed (the ``example_run`` fixture of
tests/docs_site.py reads the files it wrote and what the gallery shows it
printing), else on its own, as a user runs it. One test runs a script as a
user does, from another directory, with its options."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from docs_site import EXAMPLES, example_names
from skimage.measure import euler_number

import isoflow
from isoflow import data


def genus(name: str) -> int:
    return data.info(name)["genus"]


def test_every_example_is_tested_and_listed():
    scripts = example_names()
    tested = {n for n in globals() if n.startswith("test_")}
    assert {f"test_{s}" for s in scripts} <= tested
    listing = (EXAMPLES / "README.md").read_text()
    assert all(f"`{s}.py`" in listing for s in scripts)
    assert len(scripts) >= 6
    for script in scripts:  # the public API and the installed samples only
        text = (EXAMPLES / f"{script}.py").read_text()
        assert "from isoflow." not in text and "import isoflow." not in text, script
        assert "meshes/" not in text and "parents[" not in text, script


def test_every_example_s_docstring_names_the_files_it_writes():
    """The docstring is the gallery page's text: every file an example
    claims in OUT (the names it refuses to overwrite) is named there as
    ``OUT/NAME``."""
    import ast

    unnamed = []
    for script in example_names():
        tree = ast.parse((EXAMPLES / f"{script}.py").read_text())
        doc = " ".join(ast.get_docstring(tree).split())
        claimed = [a.value for node in ast.walk(tree) if isinstance(node, ast.Call)
                   and getattr(node.func, "id", None) == "outputs" for a in node.args if isinstance(a, ast.Constant)]
        assert claimed, script
        unnamed += [f"{script}: {name}" for name in claimed if f"``OUT/{name}``" not in doc]
    assert not unnamed, unnamed


def test_an_example_run_as_a_user_runs_it(tmp_path):
    """From another directory, with its options; a second run does not
    replace the outputs: one line, exit 2."""
    out = tmp_path / "out"
    # the mesh by its sample name, as -h names the default (a path is taken too: every default is one)
    command = [sys.executable, str(EXAMPLES / "voxelize_topology.py"), str(out), "--mesh", "eight.off",
               "--resolution", "20"]
    env = dict(os.environ, MPLBACKEND="Agg")
    first = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path, env=env)
    assert first.returncode == 0, first.stderr
    assert "1 component, 2 tunnels, 0 cavities" in first.stdout
    with np.load(out / "solid.npz") as z:
        assert euler_number(z["volume"], 1) == 1 - genus("eight.off")
    again = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path, env=env)
    assert again.returncode == 2 and "exists" in again.stderr and "Traceback" not in again.stderr


@pytest.mark.parametrize("script", example_names())
def test_an_example_s_help_gives_every_default(script, tmp_path):
    """The gallery's pages name the examples' defaults ("at the default 24
    voxels across"), and ``isoflow -h`` says its own, but an example's
    ``-h`` said none: ``--mesh MESH  a closed triangle mesh``, not which
    one, nor ``--resolution``'s. Every option that takes a value says its
    default, a sample mesh by a name that isoflow.data has."""
    import re

    run = subprocess.run([sys.executable, str(EXAMPLES / f"{script}.py"), "-h"], capture_output=True, text=True,
                         cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    options = run.stdout[run.stdout.index("options:"):]
    blocks = re.split(r"\n(?=  -)", options)[1:]
    valued = [" ".join(b.split()) for b in blocks if re.match(r"\s*--[\w-]+ [A-Z]", b)]
    assert valued and all("default" in b for b in valued), valued
    for name in re.findall(r"default: isoflow.data's ([\w.]+)\)", " ".join(valued)):
        assert Path(data.path(name)).is_file(), name
    assert not list(tmp_path.iterdir())  # -h writes nothing


#: a script as the examples are written (``_common``), whose one call takes a compiled pass (2 million voxels)
COMPILING = """
import sys
sys.path.insert(0, sys.argv[1])
sys.argv = ["chi.py", sys.argv[2]]
import numpy as np
from _common import parse_args
import isoflow
parse_args("chi of a cube")
volume = np.zeros((128, 128, 128), bool)
volume[10:20, 10:20, 10:20] = True
print(isoflow.euler_characteristic(volume, 6))
"""


def test_an_example_says_that_numba_compiles(tmp_path):
    """On numba's empty cache the examples ran for minutes without a word:
    the library logs its note at level INFO, which Python's default handler
    drops. An example prints it on stderr, once, when numba compiles (its
    cache gains the compiled pass's files), and says nothing when numba
    loads the pass from its cache."""
    env = dict(os.environ, MPLBACKEND="Agg", NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    command = [sys.executable, "-c", COMPILING, str(EXAMPLES), str(tmp_path / "out")]
    runs = [subprocess.run(command, capture_output=True, text=True, env=env) for _ in range(2)]
    assert [r.returncode for r in runs] == [0, 0] and [r.stdout for r in runs] == ["1\n", "1\n"], runs[0].stderr
    assert list((tmp_path / "cache").rglob("*.nbi"))  # numba compiled on the first run and cached the pass
    first = runs[0].stderr.splitlines()
    assert len(first) == 1 and first[0].startswith("chi.py: note: numba is compiling isoflow's passes"), first
    assert runs[1].stderr == ""


#: zarr_cluster.py's cluster, whose two workers each say what the library says when numba starts compiling
WORKERS_COMPILING = """
import logging
import sys

if __name__ == "__main__":  # not in a worker process, where spawn may run the main module again
    sys.path.insert(0, sys.argv[1])
    sys.argv = ["zarr_cluster.py", sys.argv[2]]
    import zarr_cluster
    from _common import parse_args
    from dask.distributed import Client, LocalCluster

    from isoflow.scale.compiled import note_compile

    parse_args("notes")
    came = []  # the records that reach this process, printed or not
    seen = logging.Handler()
    seen.emit = came.append
    logging.getLogger("isoflow").addHandler(seen)
    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0") as cluster, \\
            Client(cluster) as client:
        with zarr_cluster.worker_notes(client):
            client.run(note_compile)
    print(len(came))
"""


def test_zarr_cluster_says_that_its_workers_compile(tmp_path):
    """zarr_cluster.py ran for minutes on numba's empty cache with nothing
    on the screen: its worker processes compile the
    voxeliser, and what they log stays in them. Their note is printed by
    the script, once for both workers."""
    pytest.importorskip("distributed")
    from isoflow.scale.compiled import COMPILE_NOTE

    command = [sys.executable, "-c", WORKERS_COMPILING, str(EXAMPLES), str(tmp_path / "out")]
    done = subprocess.run(command, capture_output=True, text=True, env=dict(os.environ, MPLBACKEND="Agg"))
    # each worker's record (dask's log forwarding, under load, lost them
    # both), and one line for them all
    assert done.returncode == 0 and done.stdout == "2\n", done.stderr
    notes = [line for line in done.stderr.splitlines() if "note:" in line]
    assert notes == [f"zarr_cluster.py: note: {COMPILE_NOTE}"], done.stderr


def test_zarr_cluster_s_failed_note_poll_is_quiet(monkeypatch, capfd):
    """zarr_cluster.py asks its workers for their notes every second: a
    poll that failed (a worker dying mid-run, the client closing) printed
    the polling thread's traceback, and the last poll's failure replaced
    the run's own result or error. A failed poll now says nothing; the
    run's error is the one raised. A client whose every poll fails as a
    lost connection does stands for the cluster (none is started)."""
    import time

    monkeypatch.syspath_prepend(str(EXAMPLES))
    import zarr_cluster

    class Lost:
        polls = 0

        def run(self, function, **kwargs):
            if function is zarr_cluster.keep_notes:  # asked once, before the run
                return {}
            self.polls += 1
            raise OSError("Timed out trying to connect to tcp://127.0.0.1:1 after 30 s")

    client = Lost()
    with zarr_cluster.worker_notes(client, every=0.01):
        time.sleep(0.2)  # polls on the thread, each failing
    assert client.polls >= 3  # the thread's, and the last one's
    with pytest.raises(ValueError, match="the run's own error") as raised:
        with zarr_cluster.worker_notes(client, every=0.01):
            raise ValueError("the run's own error")
    assert raised.value.__context__ is None  # not raised while a poll's error was handled
    assert capfd.readouterr().err == ""


def test_zarr_cluster_s_hung_note_poll_is_given_up(monkeypatch, caplog):
    """A poll of the workers' notes that hangs (a worker that never
    answers: ``client.run`` has no time limit) held zarr_cluster.py for
    ever at the end of its run, which joined the polling thread without a
    limit. The end now waits a few seconds and goes on in silence, as a
    failed poll does, and a note that comes after that is not printed."""
    import logging
    import threading
    import time

    monkeypatch.syspath_prepend(str(EXAMPLES))
    import zarr_cluster

    release = threading.Event()

    class Hung:
        def run(self, function, **kwargs):
            if function is zarr_cluster.keep_notes:  # asked once, before the run
                return {}
            release.wait()  # no answer until the test ends it
            return {"tcp://127.0.0.1:1": ["a late note"]}

    caplog.set_level(logging.INFO, logger="isoflow")
    monkeypatch.setattr(zarr_cluster, "LAST_POLL_SECONDS", 0.1, raising=False)
    ended = []

    def script():
        with zarr_cluster.worker_notes(Hung(), every=0.01):
            time.sleep(0.05)
        ended.append(time.monotonic())

    began = time.monotonic()
    body = threading.Thread(target=script, daemon=True)
    body.start()
    body.join(10)
    release.set()
    time.sleep(0.1)  # the hung polls answer now, after the run gave them up
    assert ended and ended[0] - began < 5
    assert [r for r in caplog.records if r.name == "isoflow"] == []


def test_voxelize_topology(example_run):
    out, printed = example_run("voxelize_topology")
    g = genus("torus.obj")
    report = json.loads((out / "report.json").read_text())
    assert report["betti"] == [1, g, 0]
    assert report["euler_characteristic"] == 1 - g and report["a_dot_n"] == 8 * (1 - g)
    assert [s["genus"] for s in report["surfaces"]] == [g]
    assert f"1 component, {g} tunnel, 0 cavities" in printed
    with np.load(out / "solid.npz") as z:
        volume = z["volume"]
    assert int(volume.sum()) == report["voxels"]
    assert euler_number(volume, 1) == 1 - g
    assert (out / "topology.png").stat().st_size > 0


def test_curvature_surface(example_run):
    out, printed = example_run("curvature_surface")
    g = genus("bob_small.ply")  # genus 1: V - E + F = 0, sum of a = 8 chi = 0
    ply = trimesh.load(out / "surface.ply", process=False)
    assert ply.euler_number == 2 - 2 * g and ply.is_watertight
    columns = ply.metadata["_ply_raw"]["vertex"]["data"]
    assert int(columns["a"].sum()) == 8 * (1 - g)
    assert {"config", "class", "gamma", "a", "f", "red", "green", "blue"} <= set(columns.dtype.names)
    assert ply.visual.kind == "vertex"
    lo, hi = trimesh.load(data.bob()).bounds
    assert np.all(ply.bounds[0] > lo - 0.1 * (hi - lo)) and np.all(ply.bounds[1] < hi + 0.1 * (hi - lo))
    import matplotlib.image

    assert matplotlib.image.imread(out / "surface.png").ndim == 3
    assert f"= {8 * (1 - g)} = 8 chi" in printed and f"genus {g}" in printed
    assert f"surface.ply: {len(ply.vertices)} vertices, {len(ply.faces)} triangles" in printed  # what the file holds


def test_flow_export(example_run):
    out, printed = example_run("flow_export")
    g = genus("torus.obj")
    with open(out / "flow.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [int(rows[0][k]) for k in ("b0", "b1", "b2")] == [1, g, 0]
    assert int(rows[-1]["voxels"]) == 0 and "stopped: vanished" in printed
    assert [int(r["step"]) for r in rows] == list(range(len(rows)))
    assert len(printed.splitlines()) >= len(rows) + 3  # a line per step
    plys = sorted(out.glob("step_*.ply"))
    assert len(plys) == sum(int(r["voxels"]) > 0 for r in rows)
    assert trimesh.load(plys[0], process=False).euler_number == 2 - 2 * g
    for name in ("flow.png", "shapes.png"):
        assert (out / name).stat().st_size > 0
    # the torus is symmetric: the flow ends at its centre (in mesh units)
    centre = trimesh.load(data.torus()).bounds.mean(axis=0)
    limit = [float(c) for c in printed.split("limit point (")[1].split(")")[0].split(",")]
    assert np.allclose(limit, centre, atol=0.1)


def test_flow_export_says_when_the_torus_changes_topology():
    """The docstring's account of the run: at the default resolution the
    torus keeps its tunnel until it vanishes (no change printed), at 16
    across its ring breaks into pieces first."""
    import ast

    doc = " ".join(ast.get_docstring(ast.parse((EXAMPLES / "flow_export.py").read_text())).split())
    assert "keeps its tunnel to its last non-empty step" in doc and "``--resolution 16``" in doc
    g = genus("torus.obj")
    default = isoflow.run_flow(isoflow.voxelize_file(data.torus(), resolution=24), connectivity=6)
    assert default.topology_changes == []
    assert all(s["betti"] == [1, g, 0] for s in default.steps if s["voxels"])
    coarse = isoflow.run_flow(isoflow.voxelize_file(data.torus(), resolution=16), connectivity=6)
    first = coarse.topology_changes[0]
    assert first["before"] == [1, g, 0] and first["after"][0] > 1


def test_flow_export_forced_over_a_longer_run_keeps_only_its_own_steps(tmp_path):
    """Rerun with --force where an earlier, finer run left more steps: the
    step surfaces in OUT are this flow's non-empty steps only (as
    ``isoflow flow --out`` leaves them), each enclosing its step's voxels."""
    out = tmp_path / "out"
    env = dict(os.environ, MPLBACKEND="Agg")
    script = str(EXAMPLES / "flow_export.py")
    for extra in (["--resolution", "16"], ["--resolution", "10", "--force"]):
        done = subprocess.run([sys.executable, script, str(out), *extra], capture_output=True, text=True, env=env)
        assert done.returncode == 0, done.stderr
    solid = isoflow.voxelize_file(data.torus(), resolution=10)
    steps = isoflow.run_flow(solid, connectivity=6).steps
    kept = [s for s in steps if s["voxels"]]
    assert sorted(p.name for p in out.glob("step_*.ply")) == [f"step_{s['step']:03d}.ply" for s in kept]
    for s in kept:
        volume = trimesh.load(out / f"step_{s['step']:03d}.ply", process=False).volume
        assert np.isclose(volume, s["voxels"] * solid.pitch ** 3)


def test_flow_export_draws_equal_betti_numbers_both_visible(tmp_path, monkeypatch):
    """The torus keeps b0 = b1 = 1 to its last non-empty step: in flow.png a
    line drawn over an equal one must be narrower than it, or the one below
    is hidden (as isoflow flow's flow.png draws them), and the Betti numbers,
    whole numbers, are ticked in whole numbers."""
    import runpy

    import matplotlib
    from matplotlib.figure import Figure

    matplotlib.use("Agg")
    drawn = []
    save = Figure.savefig

    def keep(fig, *args, **kwargs):
        drawn.append(fig)
        return save(fig, *args, **kwargs)

    out = tmp_path / "out"
    monkeypatch.setattr(Figure, "savefig", keep)
    monkeypatch.syspath_prepend(str(EXAMPLES))
    monkeypatch.setattr(sys, "argv", ["flow_export.py", str(out)])
    runpy.run_path(str(EXAMPLES / "flow_export.py"), run_name="__main__")
    betti = next(ax for fig in drawn for ax in fig.axes if ax.get_title() == "Betti numbers")
    lines = betti.get_lines()
    assert [line.get_label() for line in lines] == ["b0", "b1", "b2"]
    equal = [(i, j) for i in range(3) for j in range(i + 1, 3)
             if np.array_equal(lines[i].get_ydata(), lines[j].get_ydata())]
    assert (0, 1) in equal  # b0 = b1 at every step of the torus's run
    for i, j in equal:
        assert lines[j].get_linewidth() < lines[i].get_linewidth()
    low, high = betti.get_ylim()
    ticks = [y for y in betti.get_yticks() if low <= y <= high]
    assert ticks and all(float(y).is_integer() for y in ticks)


def test_genus_table(example_run):
    out, _ = example_run("genus_table")
    with open(out / "genus.csv") as fh:
        rows = {r["mesh"]: r for r in csv.DictReader(fh)}
    meshes = {n for n in data.names() if Path(n).suffix.lower() in (".stl", ".obj", ".ply", ".off")}
    assert set(rows) == meshes
    for name in meshes:
        m = data.info(name)
        assert rows[name]["genus"] == ("-" if m["genus"] is None else str(m["genus"])), name
        assert rows[name]["components"] == str(m["components"]), name
        for tool in ("manifold3d", "pymeshlab"):  # a genus counts handles: a tool that gives none is "-", never below 0
            assert rows[name][tool] == "-" or int(rows[name][tool]) >= 0, (name, tool)
    for name in ("bob_small.ply", "torus.obj", "eight.off", "spot.ply"):
        assert rows[name]["digital_64"] == str(genus(name)) and rows[name]["agree"] == "True"
    assert rows["plane_holes.obj"]["agree"] == "False"  # open: no genus to agree with
    assert (out / "genus.png").stat().st_size > 0


def test_zarr_cluster(example_run):
    zarr = pytest.importorskip("zarr")
    pytest.importorskip("distributed")
    out, printed = example_run("zarr_cluster")
    g = genus("eight.off")
    report = json.loads((out / "report.json").read_text())
    assert report["chunked"] == report["in_memory"]
    assert report["chunked"]["betti"] == [1, g, 0]
    level = zarr.open_group(str(out / "solid.zarr"), mode="r")["0"]  # OME-Zarr: its full-resolution level
    assert tuple(level.chunks) == (19, 29, 13) and all(s % c for s, c in zip(level.shape, level.chunks))
    volume = np.asarray(level[:]).astype(bool)
    assert euler_number(volume, 1) == 1 - g == report["chunked"]["euler_characteristic"]
    assert int(volume.sum()) == report["chunked"]["voxels"]
    assert "identical" in printed and "2 worker processes" in printed
    # a solid in one piece without cavities is bounded by b0 + b2 = 1 closed surface, said in the singular
    assert printed.count("energy") == 2 and printed.count(", 1 closed surface\n") == 2



def test_zarr_cluster_without_dask_is_one_line(tmp_path):
    """Without dask (``pip install -e .`` alone) the example stopped with
    a traceback; it names the extra pyproject.toml gives dask.distributed
    in, in one line, exit 2, and writes nothing."""
    import tomllib

    extras = tomllib.loads((EXAMPLES.parent / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    extra = next(name for name, deps in extras.items() if name != "test" and any(d.startswith("distributed") for d in deps))
    shadow = tmp_path / "shadow" / "dask"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text("raise ImportError(\"No module named 'dask'\")\n")  # as if not installed
    path = os.pathsep.join([str(tmp_path / "shadow"), os.environ.get("PYTHONPATH", "")])
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=path)
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, str(EXAMPLES / "zarr_cluster.py"), str(out)], capture_output=True, text=True,
                          env=env)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.splitlines()) == 1 and f"pip install 'isoflow[{extra}]'" in done.stderr
    assert not any(out.iterdir())

def test_four_d(example_run):
    out, _ = example_run("four_d")
    g = genus("eight.off")
    reports = json.loads((out / "report.json").read_text())
    moving = np.load(out / "moving.npy")
    assert moving.ndim == 4 and all(euler_number(frame, 1) == 1 - g for frame in moving)
    for conn in (8, 80):
        m, s = reports[f"moving_{conn}"], reports[f"shell_{conn}"]
        # the moving solid is the solid itself up to homotopy; the shell is S^3
        assert (m["betti"][0], m["betti"][3], m["euler_characteristic"]) == (1, 0, 1 - g)
        assert (s["betti"][0], s["betti"][3], s["euler_characteristic"]) == (1, 1, 0)
        assert m["a_dot_n"] == 16 * m["euler_characteristic"]
    # the picture shows the move: in the moving row's panels (each a frame,
    # its empty cells grey) the solid's black cells go one column in
    # moving.shape[1] to the right from one frame to the next
    import matplotlib.image

    rgb = matplotlib.image.imread(out / "frames.png")[..., :3]
    top = rgb[: len(rgb) // 2]
    grey, black = np.all((top > 0.85) & (top < 0.97), axis=-1), np.all(top < 0.25, axis=-1)
    rows = grey.sum(axis=1) > 100  # across the panels, below their titles
    columns = (grey | black)[rows].sum(axis=0) > 0.9 * rows.sum()
    edges = np.flatnonzero(np.diff(np.r_[0, columns.astype(int), 0]))
    where = [np.nonzero(black[rows][:, a:b])[1].mean() / (b - a) for a, b in zip(edges[::2], edges[1::2])]
    assert len(where) == len(moving) == 6
    assert np.allclose(np.diff(where), 1 / moving.shape[1], atol=0.01)


def table_example_rows(out, stem: str) -> list[tuple[dict, np.ndarray]]:
    """A table example's CSV rows, each with its label's mask in the image
    it wrote: one row per nonzero label, in order, each with scikit-image's
    Euler number (at 2n-connectivity)."""
    with open(out / f"{stem}.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    image = isoflow.read_labels(out / f"{stem}.npz").array
    assert [int(r["label"]) for r in rows] == sorted(set(np.unique(image).tolist()) - {0})
    masks = [image == int(row["label"]) for row in rows]
    assert [int(r["euler_characteristic"]) for r in rows] == [euler_number(m, 1) for m in masks]
    return list(zip(rows, masks))


def holes(mask: np.ndarray) -> int:
    """A cell's holes: the 8-components of its complement that keep off
    the image's edge, by scipy."""
    from scipy import ndimage

    return ndimage.label(np.pad(~mask, 1, constant_values=True), np.ones((3, 3)))[1] - 1


def test_cell_table(example_run):
    out, printed = example_run("cell_table")
    rows = table_example_rows(out, "cells")
    for row, mask in rows:
        assert int(row["b1"]) == holes(mask)
        assert float(row["area"]) == mask.sum() * 0.0625  # pixels of 0.25 units
    total = sum(int(r["b1"]) for r, _ in rows)
    assert rows[0][0]["b1"] == "2" and f"{total} holes in all" in printed and total > 10
    assert (out / "cells.png").stat().st_size > 0


def test_cell_table_says_one_cell_and_one_hole_in_the_singular(tmp_path):
    """Three cells on 32 pixels: one cell holds one hole (scipy's count of
    the components of its complement off the image's edge)."""
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, str(EXAMPLES / "cell_table.py"), str(out), "--cells", "3", "--size", "32"],
                          capture_output=True, text=True, env=dict(os.environ, MPLBACKEND="Agg"))
    assert done.returncode == 0, done.stderr
    assert sorted(holes(mask) for _, mask in table_example_rows(out, "cells")) == [0, 0, 1]
    assert "1 cell with holes, 1 hole in all" in done.stdout


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
@pytest.mark.parametrize("stdout", ["full", "closed"])
def test_an_example_whose_stdout_cannot_be_written_says_so_in_one_line(tmp_path, stdout):
    """Standard output that cannot take what an example prints (a full disk
    under a redirection, ``> /dev/full``; a descriptor closed by ``>&-``)
    ended it in a traceback and exit status 1, where _common promises one
    line and exit status 2, as the isoflow command gives."""
    import errno

    command = [sys.executable, str(EXAMPLES / "cell_table.py"), str(tmp_path / "out"), "--cells", "3", "--size", "32"]
    env = dict(os.environ, MPLBACKEND="Agg")
    if stdout == "full":
        with open("/dev/full", "w") as full:
            done = subprocess.run(command, stdout=full, stderr=subprocess.PIPE, text=True, env=env)
        cause = os.strerror(errno.ENOSPC)
    else:
        done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env,
                              preexec_fn=lambda: os.close(1))
        cause = os.strerror(errno.EBADF)
    assert (done.returncode, done.stderr) == (2, f"cell_table.py: error: standard output: cannot be written ({cause})\n")


def test_four_d_says_one_frame_in_the_singular(tmp_path):
    """One frame: the moving solid is the solid itself, and the line says
    "1 frame"; the frames in moving.npy are the one asked for."""
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, str(EXAMPLES / "four_d.py"), str(out), "--frames", "1"],
                          capture_output=True, text=True, env=dict(os.environ, MPLBACKEND="Agg"))
    assert done.returncode == 0, done.stderr
    assert np.load(out / "moving.npy").shape[0] == 1
    assert "moved over 1 frame keeps" in done.stdout


def test_label_table(example_run):
    out, printed = example_run("label_table")
    rows = table_example_rows(out, "labels")
    for row, mask in rows:
        assert float(row["volume"]) == mask.sum() * 0.125  # voxels of 0.5 units
    # the hollowed grain has its cavity, the drilled one its tunnel
    assert (int(rows[0][0]["b2"]), int(rows[1][0]["b1"])) == (1, 1)
    assert rows[0][0]["genera"] == "0;0" and f"{len(rows)} labels" in printed
    assert (out / "labels.png").stat().st_size > 0


@pytest.mark.parametrize(("name", "stem", "cell"), [("label_table", "labels", 0.5 ** 3), ("cell_table", "cells", 0.25 ** 2)])
def test_a_table_example_s_image_gives_its_table_to_isoflow_info(example_run, capsys, name, stem, cell):
    """The docstring's ``isoflow info OUT/STEM.npz --labels`` gives the table
    the script wrote: each label's volume (2D: area) is its voxels times the
    voxel the script measured in, not in unit voxels, as a .npy would."""
    import ast

    from isoflow.cli.main import main

    doc = " ".join(ast.get_docstring(ast.parse((EXAMPLES / f"{name}.py").read_text())).split())
    assert f"``isoflow info OUT/{stem}.npz --labels`` gives the same table" in doc
    out, _ = example_run(name)
    capsys.readouterr()
    assert main(["info", str(out / f"{stem}.npz"), "--labels", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["labels"]
    key = "volume" if stem == "labels" else "area"
    assert rows and all(r[key] == r["voxels"] * cell for r in rows)
    with open(out / f"{stem}.csv", newline="") as fh:
        written = list(csv.DictReader(fh))
    assert [(int(w["label"]), float(w[key])) for w in written] == [(r["label"], r[key]) for r in rows]


def test_cell_table_draws_the_cells_as_a_viewer_shows_their_png(tmp_path, monkeypatch):
    """The picture's cells are the label image as tifffile reads the TIFF
    that ``write_labels`` makes of it (rows are y, columns x): x across and
    y down, as an image viewer shows it and shapes.png draws a 2D flow,
    not the array's axis 0 down."""
    import runpy

    import matplotlib
    import tifffile
    from matplotlib.figure import Figure

    matplotlib.use("Agg")
    drawn = []
    save = Figure.savefig

    def keep(fig, *args, **kwargs):
        drawn.append(fig.axes[0].images[0].get_array())
        return save(fig, *args, **kwargs)

    out = tmp_path / "out"
    monkeypatch.setattr(Figure, "savefig", keep)
    monkeypatch.syspath_prepend(str(EXAMPLES))
    monkeypatch.setattr(sys, "argv", ["cell_table.py", str(out), "--cells", "5", "--size", "24"])
    runpy.run_path(str(EXAMPLES / "cell_table.py"), run_name="__main__")
    image = isoflow.read_labels(out / "cells.npz").array
    assert image.shape == (24, 24) and not np.array_equal(image, image.T)
    isoflow.write_labels(image, tmp_path / "cells.tif")
    np.testing.assert_array_equal(np.asarray(drawn[0]), tifffile.imread(tmp_path / "cells.tif"))
