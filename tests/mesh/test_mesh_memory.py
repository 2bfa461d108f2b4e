"""The memory that ``isoflow surface`` estimates before meshing, against
the peak the command itself reaches, run as a user runs it."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import trimesh
from conftest import ball, torus
from scipy.ndimage import gaussian_filter

from isoflow.digital.configurations import configuration_histogram
from isoflow.digital.surface import boundary_mesh, mesh_memory, mesh_method
from isoflow.mesh.readback import readback_memory

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ru_maxrss is in KiB on Linux")

# the peak of one child, measured by a parent that runs nothing else
_PEAK = ("import resource, subprocess, sys; r = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
         "print(r.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss); print(r.stderr)")


def peak_bytes(tmp_path, volume: np.ndarray, *options: str) -> int:
    """Peak resident bytes of ``isoflow surface`` on ``volume``, with its read-back."""
    np.save(tmp_path / "v.npy", volume)
    run = subprocess.run([sys.executable, "-c", _PEAK, sys.executable, "-m", "isoflow", "surface", str(tmp_path / "v.npy"),
                          "-o", str(tmp_path / "v.ply"), "--force", *options], capture_output=True, text=True)
    code, kib = run.stdout.split("\n", 1)[0].split()
    assert code == "0", run.stdout
    return int(kib) * 1024


def porous(n: int) -> np.ndarray:
    # the worst case per voxel: a boundary face at almost every other voxel
    return gaussian_filter(np.random.default_rng(7).standard_normal((n, n, n)), 2.0) > 0


@pytest.mark.parametrize("shape", ["porous", "ball", "torus"])
def test_estimate_covers_the_commands_peak(tmp_path, shape):
    # what the budget is checked against is the memory available with the
    # volume loaded: the estimate must cover the rest of the command's
    # peak, meshing, writing and reading back with trimesh, with room. The
    # memory in use at the check is that of the same command on one voxel
    # of the same shape (same input, numba loaded), without its read-back.
    n = 192
    volume = {"porous": porous(n), "ball": ball(64, n), "torus": torus(48, 20, n)}[shape]
    assert mesh_method(volume) == "compiled"
    one = np.zeros_like(volume)
    one[n // 2, n // 2, n // 2] = True
    grown = peak_bytes(tmp_path, volume) - peak_bytes(tmp_path, one, "--no-check")
    # the mesh's estimate and the read-back's (its imports among them), each checked when its work comes
    # (the command loads trimesh for the read-back of its PLY: the imports are asked in full there)
    from isoflow.mesh.readback import READBACK_BYTES_FIXED, readback_fixed

    estimate = mesh_memory(configuration_histogram(volume), "compiled")
    readback = readback_memory(boundary_mesh(volume), ".ply") - readback_fixed() + READBACK_BYTES_FIXED
    assert estimate + readback >= 1.1 * grown, (estimate, grown)
    # the NumPy passes hold arrays the size of the lattice: theirs is larger
    assert mesh_memory(configuration_histogram(volume), "numpy") > estimate


def test_estimate_of_a_ball_is_near_its_peak(tmp_path, monkeypatch):
    # a 600^3 ball was estimated at 3.4 GiB for a peak of 673 MB (16 bytes
    # per lattice vertex, the NumPy passes' arrays, that the bit rows do
    # not make): a job with 2 GB was refused work that fits. The estimate
    # is the one the command checks against the budget.
    from isoflow.cli.surface import checked_mesh
    from isoflow.digital.lattice import DigitalObject
    from isoflow.scale import memory

    volume = ball(128, 384)
    needs: list[int] = []
    monkeypatch.setattr(memory, "check_fits", lambda need, *args, **kwargs: needs.append(need))
    checked_mesh("ball.npy", DigitalObject(volume), 6)
    assert needs and needs[0] <= 1.5 * peak_bytes(tmp_path, volume)


def test_refusal_under_the_budget(tmp_path, capsys, monkeypatch):
    # a budget between the two paths' estimates: the bit rows go ahead, and
    # the refusal is the one line it was, with nothing written
    from isoflow.cli import main
    from isoflow.scale import memory

    volume = ball(64, 192)
    hist = configuration_histogram(volume)
    np.save(tmp_path / "v.npy", volume)
    monkeypatch.setattr(memory, "default_budget", lambda: (mesh_memory(hist, "compiled") + mesh_memory(hist, "numpy")) // 2)
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "a.ply"), "--no-check"]) == 0
    monkeypatch.setattr(memory, "default_budget", lambda: mesh_memory(hist, "compiled") - 1)
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "b.ply")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    faces = len(trimesh.load(tmp_path / "a.ply", process=False).faces) // 2  # two triangles a square
    assert len(err) == 1 and f"the boundary mesh ({faces:,} faces) needs about" in err[0], err
    assert "more than the budget of" in err[0] and err[0].endswith("; crop or coarsen the volume")
    assert not (tmp_path / "b.ply").exists()


def test_numpy_estimate_from_int64_numbering():
    # from 2^28 voxels on the NumPy passes number the lattice in int64: a
    # 660^3 ball meshed with them peaked 6.07 GB above the check, 20 bytes
    # per lattice vertex beside its 912,528 faces (docs/surface.md), where
    # 16 bytes a vertex gave 5.03 GB
    hist = np.zeros(256, np.int64)
    hist[0] = 661**3
    assert mesh_memory(hist, "numpy") >= 1.1 * 20 * 661**3
    assert mesh_memory(hist, "compiled") < mesh_memory(hist, "numpy")


# a budget of ``available`` bytes (MemAvailable, no control group) for
# ``python -m isoflow ARGS``, run as a user runs it
_BUDGETED = ("import runpy, sys; from pathlib import Path; from isoflow.scale import memory\n"
             "d, available = Path(sys.argv[1]), int(sys.argv[2]); (d / 'proc').mkdir(exist_ok=True)\n"
             "(d / 'proc' / 'cgroup').write_text(''); (d / 'meminfo').write_text(f'MemAvailable: {available // 1024} kB')\n"
             "memory.PROC_SELF, memory.MEMINFO = d / 'proc', d / 'meminfo'\n"
             "sys.argv = ['isoflow', *sys.argv[3:]]; runpy.run_module('isoflow', run_name='__main__')")


def surface_within(tmp_path, available: int, *args: str) -> tuple[int, list[str]]:
    """``isoflow surface`` with a budget of 90 % of ``available``: its exit
    code and its stderr lines (less numba's note of a first compile)."""
    run = subprocess.run([sys.executable, "-c", _BUDGETED, str(tmp_path), str(available), "surface", *args],
                         capture_output=True, text=True)
    return run.returncode, [line for line in run.stderr.splitlines() if "numba is compiling" not in line]


def test_a_budget_for_the_mesh_but_not_the_read_back_writes_the_mesh(tmp_path):
    # the read-back's imports (128 MiB) were charged to the mesh: a budget
    # of 57.6 MiB refused a mesh of 1.0 MiB outright, --no-check too. The
    # mesh is written, and the check alone skipped, said in one note; a
    # budget for neither refuses the command in one line, writing nothing
    volume = ball(10, 30)
    np.save(tmp_path / "v.npy", volume)
    for options in ((), ("--no-check",)):
        out = tmp_path / "v.ply"
        code, err = surface_within(tmp_path, 64 << 20, str(tmp_path / "v.npy"), "-o", str(out), "--force", *options)
        assert code == 0, err
        read = trimesh.load(out, process=False)
        assert read.is_watertight and read.volume == pytest.approx(volume.sum())
        if options:
            assert err == []
        else:
            assert len(err) == 1 and err[0].startswith(f"isoflow surface: note: {out}: not read back"), err
            assert "more than the budget of 57.6 MiB" in err[0]
    code, err = surface_within(tmp_path, 64 << 10, str(tmp_path / "v.npy"), "-o", str(tmp_path / "w.ply"))
    assert code == 2 and len(err) == 1 and "the boundary mesh" in err[0] and "more than the budget" in err[0], err
    assert not (tmp_path / "w.ply").exists()


# (suffix, options): every file `isoflow surface` writes and reads back, each
# asked its own read-back estimate
FORMATS = [(".ply", ()), (".ply", ("--triangulate",)), (".ply", ("--ascii",)), (".ply", ("--ascii", "--triangulate")),
           (".stl", ()), (".obj", ()), (".obj", ("--triangulate",)), (".glb", ())]


@pytest.mark.parametrize("suffix, options", FORMATS, ids=[s + "".join(o) for s, o in FORMATS])
def test_readback_estimate_covers_what_the_readers_allocate(tmp_path, suffix, options):
    # a 256^3 porous field's STL was estimated at 2.89 GB beside its mesh
    # (250 bytes a triangle) where its read-back grew by 4.28 GB, an ASCII
    # PLY's at 1.86 GB (150 a triangle, as a binary PLY) where it grew by
    # 5.5 GB: a run passes the check and is killed. What the read-back
    # allocates through NumPy and Python (tracemalloc: the readers' arrays,
    # an ASCII parse's string and array a line; not the compiled passes' own,
    # so a floor of the peak), its imports done before, is within the
    # estimate less its fixed part (the imports)
    import tracemalloc

    from isoflow.digital.lattice import DigitalObject
    from isoflow.mesh import readback
    from isoflow.mesh.export import write_surface

    volume = porous(40)
    obj, mesh = DigitalObject(volume), boundary_mesh(volume)
    comps = mesh.components()
    path = tmp_path / f"p{suffix}"
    write_surface(obj, path, 6, mesh=mesh, ascii="--ascii" in options, triangulate="--triangulate" in options,
                  check=False)
    assert readback.check_surface_file(path, mesh, obj, topology=False, components=comps)["agree"]  # imports done
    tracemalloc.start()
    try:
        readback.check_surface_file(path, mesh, obj, topology=False, components=comps)
        traced = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    lines = len(path.read_bytes().splitlines()) if "--ascii" in options or suffix == ".obj" else None
    asked = readback_memory(mesh, suffix, lines) - readback.readback_fixed()
    assert asked >= traced, (asked, traced)


@pytest.mark.parametrize("suffix, options, former", [(".ply", ("--ascii",), 150)], ids=["ascii"])
def test_a_budget_below_the_read_back_skips_it(tmp_path, suffix, options, former):
    # a budget between the former estimate (per triangle of every file of
    # the suffix) and what the read-back takes ran it, to be killed for
    # memory on a large mesh: the mesh is written and the check is skipped,
    # said in one note. (An STL's writer loads trimesh, and what is left of
    # the read-back's fixed part, with 250 bytes a triangle, is under what
    # its writer asks of a mesh this small: the STL's 250 are held by
    # test_readback_estimate_covers_what_the_readers_allocate)
    from isoflow.mesh.readback import READBACK_BYTES_LOADED, READBACK_BYTES_TRIMESH, readback_fixed, text_lines

    # the command's process has started numba (the meshing's compiled passes), not loaded trimesh
    fixed = READBACK_BYTES_TRIMESH + READBACK_BYTES_LOADED
    volume = ball(10, 30)
    np.save(tmp_path / "v.npy", volume)
    mesh = boundary_mesh(volume)
    triangles = 2 * len(mesh.faces)
    probe = tmp_path / f"probe{suffix}"
    code, err = surface_within(tmp_path, 1 << 40, str(tmp_path / "v.npy"), "-o", str(probe), *options)
    assert code == 0, err
    now = readback_memory(mesh, suffix, text_lines(probe)) - readback_fixed() + fixed  # as the command's process asks
    assert now > fixed + former * triangles
    out = tmp_path / f"v{suffix}"
    budget = fixed + former * triangles + 1000
    code, err = surface_within(tmp_path, budget * 10 // 9 + 1024, str(tmp_path / "v.npy"), "-o", str(out), *options)
    assert code == 0, err
    read = trimesh.load(out, process=False)
    assert read.volume == pytest.approx(volume.sum())
    assert len(err) == 1 and err[0].startswith(f"isoflow surface: note: {out}: not read back"), err


def test_a_picture_beyond_the_budget_is_refused_up_front(tmp_path):
    # --png draws the picture holding the mesh, with matplotlib's imports
    # (a 256^3 ball's peak grew by 94 MB): a budget for the mesh alone drew
    # it past the budget. Refused before any work in one line, nothing
    # written; without --png the same budget writes the mesh
    volume = ball(10, 30)
    np.save(tmp_path / "v.npy", volume)
    code, err = surface_within(tmp_path, 64 << 20, str(tmp_path / "v.npy"), "-o", str(tmp_path / "a.ply"),
                               "--png", str(tmp_path / "a.png"))
    assert code == 2 and len(err) == 1, err
    assert "the boundary mesh" in err[0] and "and its picture needs about" in err[0] and "more than the budget" in err[0]
    assert not (tmp_path / "a.ply").exists() and not (tmp_path / "a.png").exists()
    code, err = surface_within(tmp_path, 64 << 20, str(tmp_path / "v.npy"), "-o", str(tmp_path / "a.ply"), "--no-check")
    assert code == 0 and err == [] and trimesh.load(tmp_path / "a.ply").is_watertight


def test_the_check_counts_an_ascii_write(tmp_path):
    # an ASCII PLY's rows are written from float64 tables: a 256^3 porous
    # field peaked 2.03 GB above the check where 1.76 GB (the binary PLY's
    # estimate) was asked. A budget for the binary PLY alone writes it and
    # refuses --ascii in one line, writing nothing
    from isoflow.mesh.export import write_memory

    volume = ball(10, 30)
    np.save(tmp_path / "v.npy", volume)
    hist = configuration_histogram(volume)
    faces = len(boundary_mesh(volume).faces)
    assert write_memory(faces, ".ply", ascii=True) >= 80 * faces  # the float64 table of a vertex a face, at the least
    budget = mesh_memory(hist, mesh_method(volume)) + write_memory(faces, ".ply", ascii=True) // 2
    available = budget * 10 // 9 + 1024
    code, err = surface_within(tmp_path, available, str(tmp_path / "v.npy"), "-o", str(tmp_path / "a.ply"), "--no-check")
    assert code == 0 and err == [], err
    code, err = surface_within(tmp_path, available, str(tmp_path / "v.npy"), "-o", str(tmp_path / "b.ply"), "--ascii",
                               "--no-check")
    assert code == 2 and len(err) == 1 and "the boundary mesh" in err[0] and "more than the budget" in err[0], err
    assert not (tmp_path / "b.ply").exists()


def test_a_budget_for_the_read_back_once_trimesh_is_loaded_runs_it(tmp_path):
    # an STL's writer loads trimesh, whose imports the read-back was
    # charged again (128 MiB, where 1.4 MB is what it grows by): a budget
    # of 100 MB, the mesh's estimate and a 3,792-triangle read-back's
    # several times over, skipped the check. It reads the file back now
    # and says so
    volume = ball(10, 30)
    np.save(tmp_path / "v.npy", volume)
    triangles = 2 * len(boundary_mesh(volume).faces)
    budget = (128 << 20) + 400 * triangles - 1000  # the former estimate, less a little
    out = tmp_path / "v.stl"
    code, err = surface_within(tmp_path, budget * 10 // 9 + 1024, str(tmp_path / "v.npy"), "-o", str(out))
    assert code == 0 and err == [], err
    read = trimesh.load(out)
    assert read.is_watertight and read.volume == pytest.approx(volume.sum())
    # the command's own line: the check ran (a skipped one is a note on stderr)
    run = subprocess.run([sys.executable, "-c", _BUDGETED, str(tmp_path), str(budget * 10 // 9 + 1024), "surface",
                          str(tmp_path / "v.npy"), "-o", str(out), "--force"], capture_output=True, text=True)
    assert run.returncode == 0 and f"{out}: trimesh reads it back watertight" in run.stdout, run.stdout + run.stderr


#: the read-back's fixed part, set in the command's process
_FIXED = 64 << 20
_FIXED_SET = f"from isoflow.mesh import readback; readback.readback_fixed = lambda: {_FIXED}\n"


def label_image() -> np.ndarray:
    """Two balls of 1,896 voxel faces each, labels 1 and 2."""
    labels = np.zeros((30, 60, 30), np.uint8)
    labels[:, :30][ball(10, 30)] = 1
    labels[:, 30:][ball(10, 30)] = 2
    return labels


@pytest.mark.parametrize("target", ["dir", "glb"])
def test_labels_say_a_read_back_skipped_for_memory(tmp_path, target):
    # surface --labels asked each file the read-back's estimate (for an
    # ASCII PLY its lines) but dropped the answer: where it would not fit,
    # the check was skipped without a word and the line said "each read
    # back by trimesh as isoflow counts it". A GLB scene was read back with
    # no estimate at all. Each is now asked what surface asks of one file
    # (its fixed part set here: what is loaded before is not this test's),
    # and a budget just under that skips the read-back, said in one note,
    # the files written
    from isoflow.mesh.readback import READBACK_BYTES_PER_LINE, READBACK_BYTES_PER_TRIANGLE

    np.save(tmp_path / "lab.npy", label_image())
    if target == "dir":
        out, options = tmp_path / "out", ("--suffix", ".ply", "--ascii")
        code, err = surface_within(tmp_path, 1 << 40, str(tmp_path / "lab.npy"), "--labels", "-o", f"{out}/", *options)
        assert code == 0, err
        lines = len((out / "label_1.ply").read_bytes().splitlines())  # the larger file's need is the one asked
        need = _FIXED + READBACK_BYTES_PER_LINE[".ply"] * lines
    else:
        out, options = tmp_path / "s.glb", ()
        code, err = surface_within(tmp_path, 1 << 40, str(tmp_path / "lab.npy"), "--labels", "-o", str(out), *options)
        assert code == 0, err
        need = _FIXED + READBACK_BYTES_PER_TRIANGLE[".glb"] * len(trimesh.load(out, force="mesh").faces)
    budget = need - 1000
    run = subprocess.run([sys.executable, "-c", _FIXED_SET + _BUDGETED, str(tmp_path), str(budget * 10 // 9 + 1024), "surface",
                          str(tmp_path / "lab.npy"), "--labels", "-o", f"{out}/" if target == "dir" else str(out),
                          "--force", *options], capture_output=True, text=True)
    err = [line for line in run.stderr.splitlines() if "numba is compiling" not in line]
    assert run.returncode == 0 and len(err) == 1 and "not read back" in err[0] and "more than the budget" in err[0], err
    assert "read back by trimesh" not in run.stdout, run.stdout
    files = sorted(out.glob("label_*.ply")) if target == "dir" else [out]
    assert all(trimesh.load(f, force="mesh").is_watertight for f in files) and len(files) in (1, 2)
    # and a budget just over it reads every file back
    available = (need + 4096) * 10 // 9 + 1024
    run = subprocess.run([sys.executable, "-c", _FIXED_SET + _BUDGETED, str(tmp_path), str(available), "surface",
                          str(tmp_path / "lab.npy"), "--labels", "-o", f"{out}/" if target == "dir" else str(out),
                          "--force", *options], capture_output=True, text=True)
    assert run.returncode == 0 and "each read back by trimesh as isoflow counts it" in run.stdout, run.stdout + run.stderr


# the read-back of a small file in a process that has loaded trimesh, or
# started numba, before it or not: its growth against what it was asked
_LOADED = ("import sys, numpy as np; from pathlib import Path\n"
           "from isoflow.digital.lattice import DigitalObject; from isoflow.digital.surface import boundary_mesh\n"
           "from isoflow.mesh import readback\n"
           "def status():\n"
           "    f = dict(line.split(':', 1) for line in open('/proc/self/status'))\n"
           "    return int(f['VmRSS'].split()[0]) * 1024, int(f['VmHWM'].split()[0]) * 1024\n"
           "path, before = Path(sys.argv[1]), sys.argv[2:]\n"
           "v = np.load(path.with_suffix('.npy')); obj, mesh = DigitalObject(v), boundary_mesh(v)\n"
           "if 'trimesh' in before: import trimesh\n"
           "if 'numba' in before:\n"
           "    from isoflow.mesh.equal_rows import first_equal; first_equal(np.zeros((3, 3)))\n"
           "need = readback.readback_memory(mesh, path.suffix, readback.text_lines(path))\n"
           "rss = status()[0]; Path('/proc/self/clear_refs').write_text('5')\n"
           "assert readback.check_surface_file(path, mesh, obj, components=[{'genus': 0}])['agree']\n"
           "print(need, status()[1] - rss)")


@pytest.mark.parametrize("before", [(), ("trimesh",), ("numba",), ("trimesh", "numba")], ids=["none", "trimesh", "numba", "both"])
@pytest.mark.parametrize("suffix", [".ply", ".stl"])
def test_the_fixed_part_covers_what_is_not_loaded_yet(tmp_path, suffix, before):
    # trimesh's imports (128 MiB) were charged whatever the process had
    # loaded, and numba's start not at all: a process that had neither
    # grew by 181 MB reading a small file back, one with trimesh alone (as
    # surface --labels of small labels has it) by 102 MB, one with both
    # by 1 to 2 MB. The estimate covers each, and asks little of the last
    from isoflow.digital.lattice import DigitalObject
    from isoflow.mesh.export import write_surface

    volume = ball(10, 30)
    np.save(tmp_path / "v.npy", volume)
    write_surface(DigitalObject(volume), tmp_path / f"v{suffix}", 6, check=False)
    run = subprocess.run([sys.executable, "-c", _LOADED, str(tmp_path / f"v{suffix}"), *before], capture_output=True,
                         text=True)
    assert run.returncode == 0, run.stderr
    need, grew = map(int, run.stdout.split())
    assert need >= grew, (need, grew)
    if len(before) == 2:
        assert need < (32 << 20), need
