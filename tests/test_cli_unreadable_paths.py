"""Paths the operating system will not let a command look at or read: a
name longer than the file system takes, a file without read permission, a
path through a directory that may not be searched. Each is one line naming
the path and the system's own words for the cause (``os.strerror``), exit
status 2, never a traceback nor another cause ("an empty file")."""

import errno
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import trimesh

from isoflow.cli import main

SRC = str(Path(__file__).resolve().parents[1] / "src")

#: run as root, the command drops to this user (root reads every file), once
#: the modules it needs are imported: the interpreter's own may lie in root's home
NOBODY = 65534
PRELUDE = """
import importlib, os, sys
for name in ("numpy", "trimesh", "isoflow.cli.main", "isoflow.cli.info", "isoflow.cli.surface", "isoflow.cli.flow",
             "isoflow.cli.voxelize", "isoflow.cli.genus", "isoflow.mesh.volumes", "isoflow.mesh.load",
             "isoflow.mesh.outputs", "isoflow.flow.files", "isoflow.mesh.formats.npy", "isoflow.mesh.formats.nifti",
             "isoflow.mesh.formats.tiff", "nibabel", "tifffile", "numpy.lib.format", "zipfile"):
    importlib.import_module(name)
if os.geteuid() == 0:
    os.setgid(NOBODY)
    os.setuid(NOBODY)
from isoflow.cli.main import main
sys.exit(main(sys.argv[1:]))
""".replace("NOBODY", str(NOBODY))


def one_line(capsys, *args) -> str:
    """Run the CLI in this process: exit 2 and one stderr line."""
    assert main([*map(str, args)]) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def unprivileged(cwd: Path, *args) -> subprocess.CompletedProcess:
    """Run the CLI as a user that permission bits bind (not root)."""
    env = {**os.environ, "PYTHONPATH": SRC}
    return subprocess.run([sys.executable, "-c", PRELUDE, *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


@pytest.fixture
def shared_dir():
    """A directory the unprivileged user may enter and write in (pytest's
    tmp_path lies in root's own, closed to others)."""
    with tempfile.TemporaryDirectory(prefix="isoflow-perm-") as name:
        path = Path(name)
        path.chmod(0o777)
        np.save(path / "blob.npy", np.ones((3, 3, 3), bool))
        trimesh.creation.box().export(path / "box.stl")
        yield path
        for p in path.rglob("*"):
            p.chmod(0o755)


@pytest.mark.parametrize("suffix", [".npy", ".nii.gz", ".txt", ".h5"])
def test_an_input_name_too_long_is_one_line(tmp_path, capsys, suffix):
    line = one_line(capsys, "info", tmp_path / ("a" * 300 + suffix))
    assert os.strerror(errno.ENAMETOOLONG) in line, line


@pytest.mark.parametrize("name", ["blob.npy", "blob.nii.gz", "blob.tif", "points.txt", "blob.h5"])
def test_an_input_without_read_permission_says_so(shared_dir, name):
    source = np.load(shared_dir / "blob.npy")
    if name == "points.txt":
        (shared_dir / name).write_text("0 0 0\n")
    elif name != "blob.npy":
        assert main(["voxelize", str(shared_dir / "box.stl"), "--resolution", "4", "-o", str(shared_dir / name),
                     "-q"]) == 0
    assert source.all()
    (shared_dir / name).chmod(0)
    done = unprivileged(shared_dir, "info", name)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert name in lines[0] and os.strerror(errno.EACCES) in lines[0], lines[0]


@pytest.mark.parametrize("argv", [
    ["info", "closed/blob.npy"],
    ["info", "closed/blob.h5"],  # (an HDF5 input is looked at first for its size: read whole, or by blocks)
    ["surface", "closed/blob.h5", "-o", "s.ply"],
    ["flow", "closed/blob.npy", "--out", "run"],
    ["info", "blob.npy", "--labels", "--csv", "closed/t.csv"],
    ["surface", "blob.npy", "-o", "closed/s.ply"],
    ["flow", "blob.npy", "--out", "closed/run"],
    ["voxelize", "box.stl", "--resolution", "4", "-o", "closed/v.npz"],
])
def test_a_path_through_a_closed_directory_is_one_line(shared_dir, argv):
    closed = shared_dir / "closed"
    closed.mkdir()
    np.save(closed / "blob.npy", np.ones((3, 3, 3), bool))
    closed.chmod(0)
    done = unprivileged(shared_dir, *argv)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert "closed" in lines[0] and os.strerror(errno.EACCES) in lines[0], lines[0]


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="needs /proc (Linux)")
@pytest.mark.parametrize("argv", [
    ["info", "{labels}", "--labels", "--csv", "{link}", "--force"],
    ["surface", "{blob}", "-o", "{link}", "--force"],
])
def test_a_link_to_standard_output_is_refused_not_replaced(tmp_path, capsys, argv):
    """``--csv /dev/stdout --force`` with standard output redirected to a
    file: the link's target is a regular file, and the output, written
    beside the link and renamed over it, replaced /dev/stdout (run as
    root) with a regular file. A link of the user's own to the process's
    descriptor stands for /dev/stdout here."""
    link = tmp_path / ("out.ply" if argv[0] == "surface" else "out.csv")
    link.symlink_to("/proc/self/fd/1")
    np.save(tmp_path / "blob.npy", np.ones((3, 3, 3), bool))
    np.save(tmp_path / "labels.npy", np.arange(8, dtype=np.uint8).reshape(2, 2, 2))
    where = {"blob": tmp_path / "blob.npy", "labels": tmp_path / "labels.npy", "link": link}
    line = one_line(capsys, *[a.format(**where) for a in argv])
    assert line.startswith(f"isoflow {argv[0]}: error: {link}: names an open file of this process"), line
    assert link.is_symlink() and os.readlink(link) == "/proc/self/fd/1"
