"""Output paths as a user gives them, run as the user runs the command (a
subprocess): a suffix in any case, an existing output replaced with
--force, outputs that collide; the file is read back by its own library.
The runs before and beside the one tested run in this process."""

import os
import resource
import shutil
import signal
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from in_process import isoflow_here as run_here

ROOT = Path(__file__).resolve().parents[1]
TORUS = ROOT / "meshes" / "torus.obj"


def run(*args) -> subprocess.CompletedProcess:
    """The command line in a subprocess, as a user runs it."""
    return subprocess.run([sys.executable, "-m", "isoflow", *map(str, args)], capture_output=True, text=True)



def run_on_a_small_disk(limit: int, *args) -> subprocess.CompletedProcess:
    """The command line with files limited to ``limit`` bytes (RLIMIT_FSIZE, SIGXFSZ ignored): a write
    past it fails midway with EFBIG, as on a full disk, without root to mount one."""
    def small_disk() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return subprocess.run([sys.executable, "-m", "isoflow", *map(str, args)], capture_output=True, text=True,
                          preexec_fn=small_disk)


@pytest.mark.parametrize("suffix", [".Nii", ".Nii.gz"])
def test_a_nifti_suffix_in_mixed_case_is_the_file_written(tmp_path, suffix):
    # nib.save wrote "torus.nii(.gz)" beside the named file and left the named one empty, over the old one
    nib = pytest.importorskip("nibabel")
    out = tmp_path / f"torus{suffix}"
    out.write_bytes(b"old")
    p = run_here("voxelize", TORUS, "--resolution", 16, "-o", out, "--force", "-q")
    assert p.returncode == 0, p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == [out.name]  # no stray or temporary file
    img = nib.Nifti1Image.from_file_map(nib.Nifti1Image.make_file_map({"image": str(out)}))
    assert int(np.asarray(img.dataobj).sum()) > 0
    back = run_here("info", out, "--json")  # and isoflow reads the file it wrote
    assert back.returncode == 0, back.stderr


def test_an_hdf5_write_that_fails_midway_is_one_line_and_keeps_the_old_file(tmp_path):
    # HDF5 wrote on the disk itself: a message of several lines, h5py's tracebacks, a crash (exit -11)
    pytest.importorskip("h5py")
    out = tmp_path / "torus.h5"
    args = ("voxelize", TORUS, "--resolution", 48, "-o", out, "-q")
    first = run_here(*args)  # a full run first: the compiled passes' cache is written before the limit is set
    assert first.returncode == 0, first.stderr
    assert out.stat().st_size > 3000
    out.write_bytes(b"old")
    p = run_on_a_small_disk(3000, *args, "--force")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and str(out) in p.stderr and "File too large" in p.stderr, p.stderr
    assert out.read_bytes() == b"old"
    assert sorted(f.name for f in tmp_path.iterdir()) == [out.name]


@pytest.mark.parametrize("command", [("voxelize", TORUS, "--resolution", 16), ("surface", TORUS, "--resolution", 16),
                                     ("info", "LABELS", "--labels", "--csv")])
def test_a_pipe_or_device_as_the_output_is_refused_and_kept(tmp_path, command):
    # renamed over with --force: "-o /dev/null --force" as root put a regular file in place of /dev/null
    labels = np.zeros((6, 6, 6), np.uint8)
    labels[1:3, 1:3, 1:3] = 1
    np.save(tmp_path / "labels.npy", labels)
    suffix = {"voxelize": ".npz", "surface": ".ply", "info": ".csv"}[command[0]]
    out = tmp_path / f"pipe{suffix}"
    os.mkfifo(out)
    args = [tmp_path / "labels.npy" if a == "LABELS" else a for a in command]
    if command[0] != "info":
        args.append("-o")
    p = run(*args, out, "--force", "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and str(out) in p.stderr, p.stderr
    assert stat.S_ISFIFO(os.lstat(out).st_mode)  # still the pipe


def test_a_pipe_as_the_flow_directory_asks_for_a_directory(tmp_path):
    """``flow --out PIPE`` was refused with "give a file name", where
    --out names the directory of the run's files: the line asks for a
    directory, and the pipe is kept."""
    np.save(tmp_path / "cube.npy", np.ones((3, 3, 3), bool))
    out = tmp_path / "pipe"
    os.mkfifo(out)
    p = run("flow", tmp_path / "cube.npy", "--out", out, "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr == f"isoflow flow: error: {out}: is a device, pipe or socket, not a directory; give a directory\n", \
        p.stderr
    assert stat.S_ISFIFO(os.lstat(out).st_mode)


def files_under(directory: Path) -> dict[str, bytes]:
    """Every file under ``directory`` with its bytes."""
    return {str(f.relative_to(directory)): f.read_bytes() for f in sorted(directory.rglob("*")) if f.is_file()}


@pytest.fixture(scope="module")
def torus_store(tmp_path_factory) -> Path:
    """The torus voxelized into a zarr store, once for the tests that copy it."""
    pytest.importorskip("zarr")
    store = tmp_path_factory.mktemp("store") / "torus.zarr"
    made = run_here("voxelize", TORUS, "--resolution", 16, "-o", store, "-q")
    assert made.returncode == 0, made.stderr
    return store


@pytest.mark.parametrize("outputs", [("flow", "--out", "STORE", "--force"), ("flow", "--out", "STORE/run"),
                                     ("surface", "-o", "STORE/surface.ply"),
                                     ("surface", "--labels", "-o", "STORE/", "--suffix", ".ply")])
def test_an_output_inside_the_input_zarr_store_is_refused(tmp_path, torus_store, outputs):
    # a zarr store is a directory: flow --out STORE --force wrote its step files and pictures into the input
    store = tmp_path / "torus.zarr"
    shutil.copytree(torus_store, store)
    before = files_under(store)
    command, *rest = outputs
    p = run(command, store, *[str(store) + a[5:] if a.startswith("STORE") else a for a in rest], "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and str(store) in p.stderr, p.stderr
    assert files_under(store) == before


def test_voxelize_into_an_existing_directory_says_it_is_a_directory(tmp_path):
    # the refusal listed the volume suffixes only, as for a mistyped suffix
    p = run("voxelize", TORUS, "--resolution", 16, "-o", tmp_path, "--force", "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and f"{tmp_path}: is a directory" in p.stderr, p.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_file_per_label_failing_midway_on_a_full_disk_keeps_the_earlier_set(tmp_path):
    # the files of the labels before the one that failed were replaced, those after it kept: a mixed set
    labels = np.zeros((30, 12, 12), np.uint8)
    labels[1:3, 1:3, 1:3], labels[5:7, 5:7, 5:7] = 1, 2
    labels[10:29, 1:11, 1:11] = 3  # the largest file, written last
    np.save(tmp_path / "labels.npy", labels)
    args = ("surface", tmp_path / "labels.npy", "--labels", "-o", f"{tmp_path / 'out'}/", "--suffix", ".ply", "-q")
    first = run_here(*args)  # a full run first: the compiled passes' cache is written before the limit is set
    assert first.returncode == 0, first.stderr
    before = files_under(tmp_path / "out")
    assert max(len(before["label_1.ply"]), len(before["label_2.ply"])) < 4000 < len(before["label_3.ply"])
    labels[1:4, 1:4, 1:4], labels[5:8, 5:8, 5:8] = 1, 2  # new files for the first two labels, which fit
    np.save(tmp_path / "labels.npy", labels)
    p = run_on_a_small_disk(4000, *args, "--force")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and "label_3.ply" in p.stderr, p.stderr
    assert p.stderr.rstrip().endswith("File too large); nothing was replaced"), p.stderr
    assert files_under(tmp_path / "out") == before


def test_a_long_output_name_that_fits_is_written(tmp_path):
    # a 240-byte name fits (255), but its temporary name beside it did not: "File name too long", exit 2
    out = tmp_path / ("a" * 236 + ".npz")
    p = run_here("voxelize", TORUS, "--resolution", 16, "-o", out, "-q")
    assert p.returncode == 0, p.stderr
    with np.load(out) as back:
        assert back["volume"].sum() > 0
    assert sorted(f.name for f in tmp_path.iterdir()) == [out.name]


@pytest.mark.parametrize("command", [("voxelize", TORUS, "--resolution", 16, "-o"), ("flow", TORUS, "--resolution", 16,
                                                                                     "--out")])
def test_an_output_name_too_long_for_the_file_system_is_one_line(tmp_path, command):
    # Path.exists raised the bare OSError: a traceback, exit 1
    out = tmp_path / ("b" * 300 + ".npz")
    p = run(*command, out, "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and "File name too long" in p.stderr, p.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("ascii_ply", [False, True])
def test_a_ply_of_an_input_named_beyond_ascii_is_written(tmp_path, ascii_ply):
    # the input's name goes into the PLY header's comment, which was encoded as ASCII: a traceback, exit 1
    trimesh = pytest.importorskip("trimesh")
    cube = np.zeros((5, 5, 5), bool)
    cube[1:4, 1:4, 1:4] = True
    np.save(tmp_path / "grün.npy", cube)
    out = tmp_path / "grün.ply"
    p = run("surface", tmp_path / "grün.npy", "-o", out, *(["--ascii"] if ascii_ply else []), "-q")
    assert p.returncode == 0, p.stderr
    mesh = trimesh.load(out, process=False)
    assert len(mesh.faces) == 2 * 6 * 9 and mesh.is_watertight  # 54 quads, as triangles
    assert b"comment isoflow surface of gr\\xfcn.npy" in out.read_bytes()[:300]


def test_an_output_path_with_a_line_break_is_refused_in_one_line(tmp_path):
    # the path was printed as it is: the error took two lines
    out = tmp_path / "no\nsuch" / "x.npz"
    p = run("voxelize", TORUS, "--resolution", 16, "-o", out, "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and "no\\nsuch: no such directory" in p.stderr, p.stderr


def test_flow_force_keeps_a_directory_named_like_a_step_file(tmp_path):
    # --force replaced the run's files and removed a directory of such a name with everything in it
    run_dir = tmp_path / "run"
    (run_dir / "step_001.ply").mkdir(parents=True)
    (run_dir / "step_001.ply" / "notes.txt").write_text("mine")
    p = run("flow", TORUS, "--resolution", 12, "--out", run_dir, "--force", "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and "step_001.ply" in p.stderr, p.stderr
    assert (run_dir / "step_001.ply" / "notes.txt").read_text() == "mine"



@pytest.mark.parametrize("name", ["X.ply", "steps.nii.gz", "run.STL", "out.zarr", "flow.csv", "run.JSON"])
def test_flow_out_with_a_file_suffix_is_refused_not_made_a_directory(tmp_path, name):
    # --out X.ply made a directory named X.ply and filled it with the run's files, exit 0
    box = np.zeros((5, 6, 7), bool)
    box[1:4, 1:5, 1:6] = True
    np.save(tmp_path / "box.npy", box)
    p = run("flow", tmp_path / "box.npy", "--out", tmp_path / name, "-q")
    assert p.returncode == 2 and p.stdout == "", p.stderr
    assert p.stderr.count("\n") == 1 and str(tmp_path / name) in p.stderr, p.stderr
    assert sorted(os.listdir(tmp_path)) == ["box.npy"]  # nothing made
    # a directory of that name that the user made is theirs, taken as a directory is
    (tmp_path / name).mkdir()
    p = run_here("flow", tmp_path / "box.npy", "--out", tmp_path / name, "-q")
    assert p.returncode == 0, p.stderr
    assert "flow.csv" in os.listdir(tmp_path / name)


def test_flow_out_empty_is_refused_not_ignored(tmp_path):
    # --out "" (an unset shell variable) ran the flow, wrote nothing and exited 0
    box = np.zeros((5, 6, 7), bool)
    box[1:4, 1:5, 1:6] = True
    np.save(tmp_path / "box.npy", box)
    p = subprocess.run([sys.executable, "-m", "isoflow", "flow", "box.npy", "--out", ""], capture_output=True,
                       text=True, cwd=tmp_path)
    assert p.returncode == 2 and p.stdout == "", p.stderr
    assert p.stderr == "isoflow flow: error: --out '': an empty directory name; give --out DIR for the run's files\n"
    assert sorted(os.listdir(tmp_path)) == ["box.npy"]  # nothing written into the working directory
    p = subprocess.run([sys.executable, "-m", "isoflow", "flow", "box.npy", "--volumes", ""], capture_output=True,
                       text=True, cwd=tmp_path)
    assert p.returncode == 2 and "--volumes '' writes into the --out directory" in p.stderr, p.stderr

@pytest.mark.parametrize("command", [("voxelize", TORUS, "--resolution", 16, "-o", "out.npz/"),
                                     ("voxelize", TORUS, "--resolution", 16, "-o", "out.h5/"),
                                     ("surface", "LABELS", "-o", "out.ply/"),
                                     ("info", "LABELS", "--labels", "--csv", "out.csv/")])
def test_a_file_output_given_as_a_directory_is_refused(tmp_path, command):
    # Path() dropped the trailing slash: -o out.npz/ (a directory meant) wrote, or with --force replaced, a file out.npz
    labels = np.zeros((6, 6, 6), np.uint8)
    labels[1:3, 1:3, 1:3] = 1
    np.save(tmp_path / "labels.npy", labels)
    given = f"{tmp_path}/{command[-1]}"
    old = tmp_path / command[-1].rstrip("/")
    old.write_bytes(b"old")
    args = [tmp_path / "labels.npy" if a == "LABELS" else a for a in command[:-1]]
    p = run(*args, given, "--force", "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and f"{given}: a trailing slash names a directory" in p.stderr, p.stderr
    assert old.read_bytes() == b"old"
    assert sorted(f.name for f in tmp_path.iterdir()) == sorted(["labels.npy", old.name])


def test_a_zarr_store_given_as_a_directory_is_written(tmp_path):
    # a store is a directory: -o out.zarr/ names it, unlike a file's name with a slash
    pytest.importorskip("zarr")
    p = run_here("voxelize", TORUS, "--resolution", 16, "-o", f"{tmp_path / 'out.zarr'}/", "-q")
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "out.zarr").is_dir()


@pytest.mark.parametrize("suffix", [".npy", ".tif"])
def test_a_short_write_says_why_not_only_numpys_byte_counts(tmp_path, suffix):
    # numpy's tofile reports a short write as "23040 requested and 2872 written": the cause was not said
    if suffix == ".tif":
        pytest.importorskip("tifffile")
    out = tmp_path / f"torus{suffix}"
    args = ("voxelize", TORUS, "--resolution", 48, "-o", out, "-q")
    first = run_here(*args)  # a full run first: the compiled passes' cache is written before the limit is set
    assert first.returncode == 0, first.stderr
    out.write_bytes(b"old")
    p = run_on_a_small_disk(3000, *args, "--force")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and str(out) in p.stderr, p.stderr
    assert "File too large: the file size limit (ulimit -f) is 3000 bytes" in p.stderr and "requested" not in p.stderr
    assert out.read_bytes() == b"old"
    assert sorted(f.name for f in tmp_path.iterdir()) == [out.name]


@pytest.fixture
def full_disk(tmp_path):
    """A directory on a tmpfs of 8 KiB, mounted for the test (root only)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None or shutil.which("umount") is None:
        pytest.skip("mounting a small tmpfs needs root and mount(8)")
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=8k", "tmpfs", str(disk)], capture_output=True)
    if mounted.returncode != 0:
        pytest.skip(f"no tmpfs could be mounted: {mounted.stderr!r}")
    try:
        yield disk
    finally:
        subprocess.run(["umount", str(disk)], check=True)


@pytest.mark.parametrize("suffix", [".npy", ".tif"])
def test_a_short_write_on_a_full_disk_says_no_space_left(full_disk, suffix):
    # numpy's tofile reports a short write as "23040 requested and 8064 written": the full disk was not said
    if suffix == ".tif":
        pytest.importorskip("tifffile")
    out = full_disk / f"torus{suffix}"
    out.write_bytes(b"old")
    p = run("voxelize", TORUS, "--resolution", 48, "-o", out, "--force", "-q")
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and str(out) in p.stderr, p.stderr
    assert "No space left on device: " in p.stderr and "requested" not in p.stderr, p.stderr
    assert out.read_bytes() == b"old"
    assert sorted(f.name for f in full_disk.iterdir()) == [out.name]


@pytest.mark.parametrize("name", ["x.npz", "x.h5", "x.zarr"])
def test_an_output_under_a_file_is_said_to_be_under_a_file(tmp_path, name):
    """``-o mesh.stl/x.npz`` names a file where a directory must be: the
    line says so, as the OS does (ENOTDIR), not that no such directory is
    there (the user can see it is)."""
    import errno

    stl = tmp_path / "box.stl"
    stl.write_bytes(TORUS.read_bytes())
    with pytest.raises(NotADirectoryError):  # the OS's own reading of the path
        open(stl / name, "w")
    got = run("voxelize", TORUS, "--resolution", 8, "-o", stl / name)
    lines = got.stderr.strip().splitlines()
    assert got.returncode == 2 and len(lines) == 1, got.stderr
    assert os.strerror(errno.ENOTDIR).lower() in lines[0].lower() and str(stl) in lines[0], lines[0]


def test_a_flow_directory_under_a_file_is_said_to_be_under_a_file(tmp_path):
    """``flow --out mesh.stl/run`` names a file where a directory must be,
    as the OS does (ENOTDIR), not that no such directory is there."""
    import errno

    stl = tmp_path / "box.stl"
    stl.write_bytes(TORUS.read_bytes())
    with pytest.raises(NotADirectoryError):  # the OS's own reading of the path
        os.mkdir(stl / "run")
    vol = tmp_path / "v.npy"
    np.save(vol, np.ones((3, 3, 3), bool))
    got = run("flow", vol, "--out", stl / "run")
    lines = got.stderr.strip().splitlines()
    assert got.returncode == 2 and len(lines) == 1, got.stderr
    assert os.strerror(errno.ENOTDIR).lower() in lines[0].lower() and str(stl) in lines[0], lines[0]


def test_a_gltf_output_names_the_glb_that_holds_the_same_scene(tmp_path):
    # the refusal listed the suffixes only: nothing said that .glb is glTF
    trimesh = pytest.importorskip("trimesh")
    vol = np.zeros((5, 5, 5), bool)
    vol[1:4, 1:4, 1:4] = True
    np.save(tmp_path / "cube.npy", vol)
    refused = run("surface", tmp_path / "cube.npy", "-o", tmp_path / "cube.gltf")
    line = refused.stderr.strip()
    assert refused.returncode == 2 and "\n" not in line and "Traceback" not in line
    assert sorted(f.name for f in tmp_path.iterdir()) == ["cube.npy"]
    assert line.endswith("; write cube.glb (binary glTF, the same scene in one file)")
    # the file named is glTF as trimesh reads it: the cube's closed surface
    done = run_here("surface", tmp_path / "cube.npy", "-o", tmp_path / "cube.glb", "-q")
    assert done.returncode == 0, done.stderr
    mesh = trimesh.load(tmp_path / "cube.glb", force="mesh")
    assert mesh.is_watertight and mesh.volume == pytest.approx(27.0)


@pytest.mark.parametrize("name", ["out.ply", "OUT.STL", "seg.nii.gz"])
def test_a_file_per_label_into_a_name_with_a_file_suffix_is_refused_not_made_a_directory(tmp_path, name):
    # -o out.ply/ --suffix .obj made a directory named out.ply of .obj files, exit 0
    labels = np.zeros((6, 6, 6), np.uint8)
    labels[1:3, 1:3, 1:3] = 1
    np.save(tmp_path / "labels.npy", labels)
    given = f"{tmp_path / name}/"
    p = run("surface", tmp_path / "labels.npy", "--labels", "-o", given, "--suffix", ".obj", "-q")
    assert p.returncode == 2 and p.stdout == "", p.stderr
    assert p.stderr.count("\n") == 1 and f"{given}: the slash asks for a directory" in p.stderr, p.stderr
    assert sorted(os.listdir(tmp_path)) == ["labels.npy"]  # nothing made
    # a directory of that name that the user made is theirs, written into as any directory is
    (tmp_path / name).mkdir()
    p = run("surface", tmp_path / "labels.npy", "--labels", "-o", given, "--suffix", ".obj", "-q")
    assert p.returncode == 0, p.stderr
    assert os.listdir(tmp_path / name) == ["label_1.obj"]


@pytest.mark.parametrize("name", ["cells", "cells.ply", "cells.STL", "cells.gltf", "cells.nii.gz"])
def test_a_surface_per_label_into_a_name_that_is_no_glb_says_both_ways_that_work(tmp_path, name):
    # -o cells was told to end in .ply or .obj or .stl or .glb, and -o cells.ply (there from an earlier
    # run) to pass --force: following either line was refused again, as only .glb holds a surface per label
    labels = np.zeros((6, 6, 6), np.uint8)
    labels[1:3, 1:3, 1:3] = 1
    labels[3:5, 3:5, 3:5] = 2
    np.save(tmp_path / "labels.npy", labels)
    if name == "cells.ply":
        (tmp_path / name).write_bytes(b"an earlier run's")
    p = run("surface", tmp_path / "labels.npy", "--labels", "-o", tmp_path / name, "-q")
    assert p.returncode == 2 and p.stdout == "", p.stderr
    assert p.stderr.count("\n") == 1, p.stderr
    ways = p.stderr.rstrip("\n").split("; give ")[-1].split(" or ")
    assert len(ways) == 2, p.stderr
    for way in ways:  # each way out the line gives is a command that writes every label's surface
        done = run_here("surface", tmp_path / "labels.npy", "--labels", *way.split(), "-q")
        assert done.returncode == 0, (way, done.stderr)
    import trimesh

    assert sorted(trimesh.load(tmp_path / "cells.glb").graph.nodes_geometry) == ["label_1", "label_2"]
    files = sorted((tmp_path / "cells").iterdir())
    assert [f.stem for f in files] == ["label_1", "label_2"]
    assert all(trimesh.load(f).is_watertight for f in files)


def test_a_suffix_that_is_no_format_of_a_file_per_label_is_named(tmp_path):
    # -o out/ --suffix .gltf was told the suffixes taken, not that .gltf (as given) is not one of them
    labels = np.zeros((6, 6, 6), np.uint8)
    labels[1:3, 1:3, 1:3] = 1
    np.save(tmp_path / "labels.npy", labels)
    p = run("surface", tmp_path / "labels.npy", "--labels", "-o", f"{tmp_path / 'out'}/", "--suffix", ".gltf", "-q")
    assert p.returncode == 2 and p.stderr.count("\n") == 1, p.stderr
    assert p.stderr.rstrip().endswith("not .gltf"), p.stderr
    assert sorted(os.listdir(tmp_path)) == ["labels.npy"]


def test_flow_out_named_as_its_table_names_the_directory_that_writes_it(tmp_path):
    # --out flow.csv made a directory flow.csv holding flow.csv/flow.csv, exit 0
    from PIL import Image

    disc = np.zeros((12, 12), np.uint8)
    disc[3:9, 2:10] = 255
    Image.fromarray(disc).save(tmp_path / "disc.png")  # a 2D image: no step_NNN.ply is written for it
    p = run("flow", tmp_path / "disc.png", "--out", tmp_path / "flow.csv", "-q")
    assert p.returncode == 2 and p.stdout == "", p.stderr
    assert f"give --out {tmp_path / 'flow'} (--out {tmp_path / 'flow'} writes {tmp_path / 'flow'}/flow.csv)" in p.stderr
    assert "step_NNN.ply in 3D" in p.stderr, p.stderr
    assert sorted(os.listdir(tmp_path)) == ["disc.png"]


@pytest.mark.parametrize(("output", "words"), [
    (("-o", "out"), "out: is a directory; give a file name for the surface"),
    (("-o", ".ply"), ".ply: is a suffix alone, with no name before it; give the file's name, e.g. surface.ply"),
    (("-o", "-"), "-: a surface is written to a file, not to stdout; give its name, e.g. surface.ply"),
    (("-o", "s.ply", "--png", ".png"), ".png: is a suffix alone, with no name before it; give the file's name, "
                                       "e.g. picture.png"),
])
def test_a_surface_into_a_directory_or_a_bare_suffix_says_which(tmp_path, monkeypatch, output, words):
    # each was "surface must end in .ply or .obj or .stl or .glb", which the name ".ply" does
    monkeypatch.chdir(tmp_path)
    np.save("v.npy", np.ones((2, 2, 2), bool))
    (tmp_path / "out").mkdir()
    p = run_here("surface", "v.npy", *output, "--force", "-q")
    assert p.returncode == 2 and p.stderr == f"isoflow surface: error: {words}\n", p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == ["out", "v.npy"]


@pytest.mark.parametrize(("output", "words"), [
    (".nii.gz", ".nii.gz: is a suffix alone, with no name before it; give the file's name, e.g. volume.nii.gz"),
    (".NPY", ".NPY: is a suffix alone, with no name before it; give the file's name, e.g. volume.NPY"),
    (".tif", ".tif: is a suffix alone, with no name before it; give the file's name, e.g. volume.tif"),
    (".zarr", ".zarr: is a suffix alone, with no name before it; give the file's name, e.g. volume.zarr"),
    (".ome.zarr", ".ome.zarr: is a suffix alone, with no name before it; give the file's name, e.g. volume.ome.zarr"),
    ("-", "-: a volume is written to a file, not to stdout; give its name, e.g. volume.nii.gz"),
])
def test_a_volume_named_by_a_bare_suffix_or_dash_is_refused_as_a_surface_is(tmp_path, monkeypatch, output, words):
    # voxelize -o .nii.gz wrote a hidden file named ".nii.gz" (and .zarr a hidden store), exit 0
    monkeypatch.chdir(tmp_path)
    shutil.copy(TORUS, "torus.obj")
    p = run_here("voxelize", "torus.obj", "--resolution", "8", "-o", output, "-q")
    assert p.returncode == 2 and p.stderr == f"isoflow voxelize: error: {words}\n", p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == ["torus.obj"]


def test_write_volume_write_labels_and_info_csv_refuse_a_bare_suffix(tmp_path, monkeypatch):
    import isoflow
    from isoflow.errors import IsoflowError

    monkeypatch.chdir(tmp_path)
    labels = np.ones((3, 3, 3), np.uint8)
    with pytest.raises(IsoflowError, match=r"^\.tif: is a suffix alone"):
        isoflow.write_labels(labels, ".tif")
    with pytest.raises(IsoflowError, match=r"^-: a volume is written to a file, not to stdout"):
        isoflow.write_volume(labels.astype(bool), "-")
    np.save("seg.npy", labels)
    p = run_here("info", "seg.npy", "--labels", "--csv", ".csv", "-q")
    assert p.returncode == 2 and p.stderr.endswith(": .csv: is a suffix alone, with no name before it; give the file's "
                                                   "name, e.g. table.csv\n"), p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == ["seg.npy"]
