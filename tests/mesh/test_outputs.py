"""No file is ever lost or left half-written (issue 15, item 5).

A full disk is a tiny tmpfs where the test can mount one (root in a
sandbox), else skipped; the same failure half-way through a write is also
simulated everywhere by a write that raises ENOSPC. A read-only directory is
a tmpfs remounted read-only (root ignores permission bits), or a directory
without write permission when not root. After every failure: exit 2, one
line naming the file and the cause, the old file byte for byte, no
temporary file.
"""

import contextlib
import errno
import io
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import torus

from isoflow.cli import main
from isoflow.errors import IsoflowError
from isoflow.mesh import outputs
from isoflow.mesh.formats import npy as npy_format

MESHES = Path(__file__).resolve().parents[2] / "meshes"


def run(*args):
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = main([str(a) for a in args])
    return rc, o.getvalue(), e.getvalue()


def listing(directory: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(directory.iterdir()) if p.is_file()}


@contextlib.contextmanager
def tmpfs(path: Path, size: str):
    path.mkdir()
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    p = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)], capture_output=True)
    if p.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {p.stderr.decode().strip()}")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


def fill(directory: Path, leave: int) -> None:
    """Fill a file system but ``leave`` bytes."""
    free = os.statvfs(directory).f_bavail * os.statvfs(directory).f_frsize
    with open(directory / "filler", "wb") as fh:
        fh.write(b"\0" * max(0, free - leave))


class HalfWayFull:
    """A file whose writes stop at ``limit`` bytes with ENOSPC, as a full disk does."""

    def __init__(self, fh, limit):
        self.fh, self.left = fh, limit

    def write(self, data):
        if len(data) > self.left:
            self.fh.write(data[: self.left])
            self.left = 0
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self.left -= len(data)
        return self.fh.write(data)

    def __getattr__(self, name):
        return getattr(self.fh, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.fh.close()


def full_after(monkeypatch, limit: int, exc=None):
    real = open

    def fake_open(path, mode="r", *a, **kw):
        fh = real(path, mode, *a, **kw)
        return HalfWayFull(fh, limit) if "w" in mode else fh

    # every writer that opens its file by name: the atomic writes' own, and
    # the volume formats' (an .npz goes through isoflow.mesh.formats.npy)
    for module in (outputs, npy_format):
        monkeypatch.setattr(module, "open", fake_open, raising=False)


def assert_failed_cleanly(rc, err, target: Path, before: dict, cause: str, code: int = 2):
    assert rc == code, err
    line, = err.strip().splitlines()
    assert str(target) in line and cause in line and "Traceback" not in err, line
    assert listing(target.parent) == before  # the old file byte for byte, nothing added
    assert not [p for p in target.parent.iterdir() if outputs.TEMP_MARK in p.name]


def interrupted_as_made(monkeypatch, module):
    """A signal handled in the instant a temporary is made, as the making
    returns: before its writer's ``try`` (which removes it) begins."""
    real = outputs.temp_sibling

    def made_then_interrupted(*args, **kwargs):
        real(*args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(module, "temp_sibling", made_then_interrupted)


def test_an_interrupt_as_a_temporary_is_made_leaves_nothing(tmp_path, monkeypatch):
    np.save(tmp_path / "t.npy", torus(6, 2))
    out = tmp_path / "out.ply"
    out.write_bytes(b"old")
    before = listing(tmp_path)
    interrupted_as_made(monkeypatch, outputs)
    rc, _, err = run("surface", tmp_path / "t.npy", "-o", out, "--force")
    assert rc == 130, err
    assert listing(tmp_path) == before  # the old file byte for byte, no temporary beside it
    assert not [p for p in tmp_path.iterdir() if outputs.TEMP_MARK in p.name]


def test_an_interrupt_as_the_flows_staging_directory_is_made_leaves_nothing(tmp_path, monkeypatch):
    import isoflow.flow.files

    np.save(tmp_path / "t.npy", torus(6, 2))
    out = tmp_path / "run"
    out.mkdir()
    (out / "flow.csv").write_text("the previous run")
    interrupted_as_made(monkeypatch, isoflow.flow.files)
    rc, _, err = run("flow", tmp_path / "t.npy", "--out", out, "--force", "--steps", 2)
    assert rc == 130, err
    assert sorted(p.name for p in out.iterdir()) == ["flow.csv"]
    assert (out / "flow.csv").read_text() == "the previous run"


# ------------------------------------------------------------ a full disk


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".stl", ".glb"])
def test_surface_write_fails_half_way_old_file_kept(tmp_path, monkeypatch, suffix):
    np.save(tmp_path / "t.npy", torus(6, 2))
    out = tmp_path / f"out{suffix}"
    out.write_bytes(b"the user's previous file")
    before = listing(tmp_path)
    full_after(monkeypatch, 1000)
    rc, _, err = run("surface", tmp_path / "t.npy", "-o", out, "--force")
    assert_failed_cleanly(rc, err, out, before, "No space left on device")
    assert "previous out" in err and "unchanged" in err


def test_voxelize_write_fails_half_way_leaves_no_file(tmp_path, monkeypatch):
    full_after(monkeypatch, 100)
    rc, _, err = run("voxelize", MESHES / "torus.obj", "--resolution", 24, "-o", tmp_path / "v.npz")
    assert_failed_cleanly(rc, err, tmp_path / "v.npz", {}, "No space left on device")
    assert "nothing was written" in err


def test_interrupted_write_keeps_the_old_file(tmp_path, monkeypatch):
    np.save(tmp_path / "t.npy", torus(6, 2))
    out = tmp_path / "out.ply"
    out.write_bytes(b"old")
    before = listing(tmp_path)
    real = open

    class Interrupted(HalfWayFull):
        def write(self, data):
            raise KeyboardInterrupt

    monkeypatch.setattr(outputs, "open", lambda p, m="r", *a, **k: Interrupted(real(p, m, *a, **k), 0), raising=False)
    rc, _, err = run("surface", tmp_path / "t.npy", "-o", out, "--force")
    # an interrupt keeps its usual exit status (130), and names the file
    assert_failed_cleanly(rc, err, out, before, "interrupted while writing", code=130)


def test_surface_on_a_full_tmpfs(tmp_path):
    np.save(tmp_path / "t.npy", torus(8, 3))
    with tmpfs(tmp_path / "disk", "256k") as disk:
        out = disk / "out.ply"
        assert run("surface", tmp_path / "t.npy", "-o", out)[0] == 0  # it fits on an empty disk
        np.save(tmp_path / "small.npy", np.ones((1, 1, 1), bool))
        assert run("surface", tmp_path / "small.npy", "-o", out, "--force")[0] == 0
        fill(disk, 8192)
        before = listing(disk)
        rc, _, err = run("surface", tmp_path / "t.npy", "-o", out, "--force")
        assert_failed_cleanly(rc, err, out, before, "No space left on device")


def test_voxelize_on_a_full_tmpfs(tmp_path):
    with tmpfs(tmp_path / "disk", "64k") as disk:
        fill(disk, 1024)
        before = listing(disk)
        rc, _, err = run("voxelize", MESHES / "torus.obj", "--resolution", 48, "-o", disk / "v.npz")
        assert_failed_cleanly(rc, err, disk / "v.npz", before, "No space left on device")


# ------------------------------------------------------------ a read-only directory


def test_read_only_directory_refused_up_front(tmp_path):
    """A read-only tmpfs as root, a directory without write permission otherwise."""
    np.save(tmp_path / "t.npy", torus(6, 2))
    if os.geteuid() == 0:
        ctx = tmpfs(tmp_path / "ro", "64k")
    else:
        (tmp_path / "ro").mkdir()
        ctx = contextlib.nullcontext(tmp_path / "ro")
    with ctx as ro:
        (ro / "out.ply").write_bytes(b"old")
        if os.geteuid() == 0:
            subprocess.run(["mount", "-o", "remount,ro", str(ro)], check=True)
            cause = "read-only file system"
        else:
            ro.chmod(0o500)
            cause = "permission denied"
        try:
            before = listing(ro)
            rc, _, err = run("surface", tmp_path / "t.npy", "-o", ro / "out.ply", "--force")
            assert rc == 2 and cause in err and str(ro) in err and len(err.strip().splitlines()) == 1
            assert listing(ro) == before
            rc, _, err = run("flow", tmp_path / "t.npy", "--steps", 1, "--out", ro / "run")
            assert rc == 2 and cause in err and not (ro / "run").exists()
        finally:
            if os.geteuid() != 0:
                ro.chmod(0o700)


def test_write_denied_while_writing(tmp_path, monkeypatch):
    """The directory passes the up-front check but the write is refused
    (permissions changed meanwhile, an ACL, a read-only bind mount)."""
    np.save(tmp_path / "t.npy", torus(6, 2))
    out = tmp_path / "out.obj"
    out.write_bytes(b"old")
    before = listing(tmp_path)

    def denied(*a, **k):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))

    monkeypatch.setattr(outputs.os, "replace", denied)
    rc, _, err = run("surface", tmp_path / "t.npy", "-o", out, "--force")
    assert_failed_cleanly(rc, err, out, before, "Permission denied")


def test_vanished_directory(tmp_path):
    d = tmp_path / "gone"
    d.mkdir()
    with pytest.raises(IsoflowError, match=r"gone/x.csv: could not write \(No such file or directory\)"):
        with outputs.atomic_write(d / "x.csv", "w") as fh:
            fh.write("a,b\n")
            for p in d.iterdir():
                p.unlink()
            d.rmdir()
    assert not d.exists()


def test_atomic_path_for_directories(tmp_path):
    """A store written as a directory (zarr) replaces the old one whole."""
    store = tmp_path / "v.zarr"
    store.mkdir()
    (store / "old").write_text("old")
    with outputs.atomic_path(store, directory=True) as tmp:
        (tmp / "new").write_text("new")
    assert [p.name for p in store.iterdir()] == ["new"]
    assert [p.name for p in tmp_path.iterdir()] == ["v.zarr"]
    with pytest.raises(RuntimeError):
        with outputs.atomic_path(store, directory=True) as tmp:
            (tmp / "half").write_text("x")
            raise RuntimeError("writer failed")
    assert [p.name for p in store.iterdir()] == ["new"] and len(list(tmp_path.iterdir())) == 1


def test_new_files_get_the_usual_permissions(tmp_path):
    np.save(tmp_path / "t.npy", np.ones((2, 2, 2), bool))
    umask = os.umask(0o022)
    os.umask(umask)
    assert run("surface", tmp_path / "t.npy", "-o", tmp_path / "o.ply")[0] == 0
    assert (tmp_path / "o.ply").stat().st_mode & 0o777 == 0o666 & ~umask


# ------------------------------------------------------------ flow --out


def test_flow_force_keeps_the_old_run_until_the_new_one_is_written(tmp_path, monkeypatch):
    np.save(tmp_path / "b6.npy", np.ones((6, 6, 6), bool))
    np.save(tmp_path / "b3.npy", np.ones((3, 3, 3), bool))
    out = tmp_path / "run"
    assert run("flow", tmp_path / "b6.npy", "--out", out)[0] == 0
    before = listing(out)
    assert len([n for n in before if n.startswith("step_")]) == 6
    # the new run fails while writing its second step file
    from isoflow.flow import files

    real = files.export.write_mesh_file
    calls = []

    def failing(path, *a, **k):
        calls.append(path)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return real(path, *a, **k)

    monkeypatch.setattr(files.export, "write_mesh_file", failing)
    rc, _, err = run("flow", tmp_path / "b3.npy", "--out", out, "--force")
    line, = err.strip().splitlines()
    assert rc == 2 and "No space left on device" in line and f"{out}/step_001.ply" in line, line
    assert listing(out) == before and sorted(p.name for p in out.iterdir()) == sorted(before)
    monkeypatch.undo()
    # finished: the new run's three steps, none of the old six
    assert run("flow", tmp_path / "b3.npy", "--out", out, "--force")[0] == 0
    assert sorted(n for n in listing(out) if n.startswith("step_")) == ["step_000.ply", "step_001.ply", "step_002.ply"]
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


def test_flow_into_a_new_directory_leaves_nothing_on_failure(tmp_path, monkeypatch):
    np.save(tmp_path / "b3.npy", np.ones((3, 3, 3), bool))
    full_after(monkeypatch, 10)
    rc, _, err = run("flow", tmp_path / "b3.npy", "--out", tmp_path / "new")
    assert rc == 2 and "No space left on device" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "new").exists()


# ------------------------------------------------- what killed writers left

def test_a_killed_writers_temporaries_are_removed_by_the_next_write(tmp_path):
    """A process killed outright (SIGKILL) while writing leaves its
    temporary file or directory; the next write of that file removes it,
    and only it: not a running process's, another host's, or a stranger's
    file of another form."""
    import hashlib
    import socket
    import sys

    np.save(tmp_path / "t.npy", torus(6, 2))
    out = tmp_path / "out.ply"
    host = hashlib.sha1(socket.gethostname().encode()).hexdigest()[:8]
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()  # its pid is free now (until reused)
    dead_file = tmp_path / f".out{outputs.TEMP_MARK}{host}-{ended.pid}-0123abcd.ply"
    dead_file.write_bytes(b"half a mesh")
    dead_dir = tmp_path / f".out{outputs.TEMP_MARK}{host}-{ended.pid}-4567abcd.ply"
    dead_dir.mkdir()  # (a zarr store is a directory)
    (dead_dir / "chunk").write_bytes(b"x")
    kept = [
        tmp_path / f".out{outputs.TEMP_MARK}{host}-{os.getpid()}-89abcdef.ply",  # a running writer's
        tmp_path / f".out{outputs.TEMP_MARK}0000ffff-{ended.pid}-01234567.ply",  # another host's
        tmp_path / f".out{outputs.TEMP_MARK}12345678.ply",  # no owner in its name
        tmp_path / f".other{outputs.TEMP_MARK}{host}-{ended.pid}-0123abcd.ply",  # another file's
    ]
    for k in kept:
        k.write_bytes(b"keep")
    rc, _, err = run("surface", tmp_path / "t.npy", "-o", out)
    assert rc == 0, err
    assert not dead_file.exists() and not dead_dir.exists()
    assert all(k.read_bytes() == b"keep" for k in kept)
    # and the surface itself is whole
    import trimesh

    assert trimesh.load(out, process=False).is_watertight


def ended_pid() -> int:
    """The pid of a process that has ended (free until reused)."""
    import sys

    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    return ended.pid


def old_store(directory: Path, pid: int, random: str = "0123abcd", content: bytes = b"the previous store",
              suffix: str = ".zarr") -> Path:
    """A store (a file, for another ``suffix``) moved aside by a command
    (of ``pid``) that was to replace ``store.zarr``: named as
    ``isoflow.mesh.outputs.aside_name`` names it."""
    import hashlib
    import socket

    host = hashlib.sha1(socket.gethostname().encode()).hexdigest()[:8]
    aside = directory / f".store.isoflow-old-{host}-{pid}-{random}{suffix}"  # as docs/cli.md names it
    if not suffix.endswith(".zarr"):  # a file
        aside.write_bytes(content)
        return aside
    (aside / "0").mkdir(parents=True)
    (aside / ".zgroup").write_text('{"zarr_format": 2}')
    (aside / "0" / "0.0.0").write_bytes(content)
    return aside


def tree(directory: Path) -> dict:
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def voxelize_store(tmp_path: Path, *extra: str) -> subprocess.CompletedProcess:
    import sys

    import trimesh

    trimesh.creation.box(extents=(1, 1, 1)).export(tmp_path / "box.stl")
    return subprocess.run([sys.executable, "-m", "isoflow", "voxelize", str(tmp_path / "box.stl"), "--pitch", "0.25",
                           "-o", str(tmp_path / "store.zarr"), *extra], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("command", ["store", "labels", "surface"])
def test_an_output_moved_aside_by_a_killed_command_is_put_back_not_deleted(tmp_path, command):
    """Killed outright between moving the old output aside and renaming
    the new one in, a command left ``store.zarr`` missing and the previous
    store at its aside name only: the next command that writes it puts it
    back, whole, says so in one line, and then refuses to overwrite it
    without --force, as it would have before the kill. So for a store
    written slab by slab, a label image's store, and a file (a flow's
    step file moved aside where a store was staged in its place)."""
    import sys

    import trimesh

    if command == "surface":
        np.save(tmp_path / "t.npy", torus(6, 2))
        aside = old_store(tmp_path, ended_pid(), content=b"the previous surface", suffix=".ply")
        before = {"": b"the previous surface"}
        argv = ["surface", str(tmp_path / "t.npy"), "-o", str(tmp_path / "store.ply")]
    else:
        aside = old_store(tmp_path, ended_pid())
        before = tree(aside)
        meshes = [tmp_path / "box.stl"] + ([tmp_path / "box2.stl"] if command == "labels" else [])
        trimesh.creation.box(extents=(1, 1, 1)).export(meshes[0])
        trimesh.creation.box(extents=(1, 1, 1), transform=trimesh.transformations.translation_matrix((2, 0, 0))).export(
            tmp_path / "box2.stl")
        argv = ["voxelize", *map(str, meshes), "--pitch", "0.25", "-o", str(tmp_path / "store.zarr")]
    out = tmp_path / ("store.ply" if command == "surface" else "store.zarr")
    r = subprocess.run([sys.executable, "-m", "isoflow", *argv], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    warned = [line for line in r.stderr.splitlines() if "warning" in line]
    assert len(warned) == 1 and out.name in warned[0] and aside.name in warned[0], r.stderr
    assert f"{out.name}: exists; pass --force to overwrite" in r.stderr
    assert not aside.exists()
    assert (tree(out) if out.is_dir() else {"": out.read_bytes()}) == before
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".store.")]


def test_an_aside_left_beside_its_new_store_is_removed(tmp_path):
    """Killed after the new store was in place, before the old one's
    removal: the aside is removed and the store in place left alone."""
    aside = old_store(tmp_path, ended_pid())
    new = tmp_path / "store.zarr"
    new.mkdir()
    (new / ".zgroup").write_text('{"zarr_format": 2, "the": "new one"}')
    r = voxelize_store(tmp_path)
    assert r.returncode == 2 and "store.zarr: exists; pass --force to overwrite" in r.stderr, r.stderr
    assert "warning" not in r.stderr
    assert not aside.exists()
    assert tree(new) == {".zgroup": b'{"zarr_format": 2, "the": "new one"}'}


def test_only_the_newest_of_the_dead_asides_is_put_back_and_a_running_ones_is_left(tmp_path):
    """A running command's aside is its own, whatever the state of the
    path: left alone, and so is another store's (``store.b.zarr``'s aside
    ends in ``RANDOM.b.zarr``). Of two left by killed commands for the
    missing store, the newer is put back and the older, an output replaced
    since, removed."""
    dead = ended_pid()
    running = old_store(tmp_path, os.getpid(), "89abcdef", b"a running command's")
    other = old_store(tmp_path, dead, "76543210", b"store.b.zarr's", suffix=".b.zarr")
    os.utime(other, (1_800_000_000, 1_800_000_000))
    older = old_store(tmp_path, dead, "01234567", b"replaced since")
    newer = old_store(tmp_path, dead, "fedcba98", b"the last store")
    os.utime(older, (1_000_000_000, 1_000_000_000))
    os.utime(newer, (1_500_000_000, 1_500_000_000))
    os.utime(running, (1_700_000_000, 1_700_000_000))  # the newest of all, and not this command's to take
    r = voxelize_store(tmp_path)
    assert r.returncode == 2 and "store.zarr: exists; pass --force to overwrite" in r.stderr, r.stderr
    assert (tmp_path / "store.zarr" / "0" / "0.0.0").read_bytes() == b"the last store"
    assert not older.exists() and not newer.exists()
    assert (running / "0" / "0.0.0").read_bytes() == b"a running command's"
    assert (other / "0" / "0.0.0").read_bytes() == b"store.b.zarr's"


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="names an fsync's directory by /proc/self/fd")
@pytest.mark.parametrize("command", ["labels", "flow"])
def test_a_new_output_directory_is_flushed_into_its_parent(tmp_path, monkeypatch, command):
    # the files renamed into a directory are durable once the directory is flushed, but the directory's own
    # entry is in its parent: unflushed, a crash could lose the new directory, files and all
    synced = []
    real_fsync = os.fsync

    def fsync(fd):
        with contextlib.suppress(OSError):
            synced.append(os.readlink(f"/proc/self/fd/{fd}"))
        real_fsync(fd)

    image = np.zeros((8, 8, 8), np.uint8)
    image[1:3, 1:3, 1:3], image[4:7, 4:7, 4:7] = 1, 2
    np.save(tmp_path / "in.npy", image if command == "labels" else image > 0)
    parent = tmp_path / "parent"
    parent.mkdir()
    monkeypatch.setattr(os, "fsync", fsync)
    if command == "labels":
        rc, _, err = run("surface", tmp_path / "in.npy", "--labels", "-o", f"{parent / 'out'}/", "--suffix", ".ply")
        made = {"label_1.ply", "label_2.ply"}
    else:
        rc, _, err = run("flow", tmp_path / "in.npy", "--out", parent / "out")
        made = {"flow.csv"}
    assert rc == 0, err
    assert made <= {p.name for p in (parent / "out").iterdir()}
    assert str(parent / "out") in synced and str(parent) in synced
    synced.clear()
    rc, _, err = run(*(["surface", tmp_path / "in.npy", "--labels", "-o", f"{parent / 'out'}/", "--suffix", ".ply"]
                       if command == "labels" else ["flow", tmp_path / "in.npy", "--out", parent / "out"]), "--force")
    assert rc == 0, err
    assert str(parent) not in synced  # an existing directory's entry is there already
