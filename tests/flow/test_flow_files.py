"""A flow's step files open in trimesh and pymeshlab as the surfaces isoflow
counts, and flow.csv records trimesh's reading of each (issue 15, item 3)."""

import contextlib
import csv
import io
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pymeshlab
import pytest
import trimesh
from skimage.measure import euler_number

import isoflow
from isoflow import boundary_mesh
from isoflow.cli import main


def run(*args):
    o, e = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(e):
        rc = main([str(a) for a in args])
    return rc, o.getvalue(), e.getvalue()


def noisy_block(seed=0, n=10):
    """Random voxels on a slab: edge and vertex contacts (doubled edges at
    26-connectivity) in the first steps of a 26-connected flow."""
    rng = np.random.default_rng(seed)
    v = rng.random((n, n, n)) < 0.45
    v[n // 2 - 1 : n // 2 + 2, :, :] = True  # keeps the flow going for a few steps
    return v


def test_26_connected_flow_step_files_and_their_check_columns(tmp_path):
    v = noisy_block()
    np.save(tmp_path / "v.npy", v)
    out = tmp_path / "run"
    rc, stdout, err = run("flow", tmp_path / "v.npy", "--connectivity", 26, "--out", out)
    assert rc == 0, err
    with open(out / "flow.csv") as fh:
        rows = {int(r["step"]): r for r in csv.DictReader(fh)}
    plys = sorted(out.glob("step_*.ply"))
    assert len(plys) == sum(int(r["voxels"]) > 0 for r in rows.values()) >= 3
    seen_doubled = 0
    for ply in plys:
        step = int(ply.stem.split("_")[1])
        row = rows[step]
        # the object of this step, read back from its surface: voxel count and chi
        tm = trimesh.load(ply, process=False)
        assert tm.is_watertight and tm.is_winding_consistent, ply
        assert tm.volume == pytest.approx(int(row["voxels"]))
        header = ply.read_bytes()[:600].decode("ascii", "replace")
        n_faces = int(header.split("element face ")[1].split()[0])
        triangles = "comment faces: triangles" in header  # where an edge is doubled (docs/formats.md)
        assert len(tm.faces) == (n_faces if triangles else 2 * n_faces)
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(ply))
        t = ms.get_topological_measures()
        assert t["is_mesh_two_manifold"] and t["boundary_edges"] == 0, ply
        euler = t["vertices_number"] - t["edges_number"] + t["faces_number"]
        assert euler == tm.euler_number == int(row["mesh_euler"])
        # the CSV's check columns: trimesh's reading next to isoflow's
        assert row["trimesh_watertight"] == "True"
        assert row["trimesh_euler"] == row["mesh_euler"] and row["trimesh_genus"] == row["mesh_genus"]
        assert int(row["euler_characteristic"]) == int(row["b0"]) - int(row["b1"]) + int(row["b2"])
        seen_doubled += triangles
    assert seen_doubled  # some steps had doubled edges (triangles in the binary PLY)
    # Euler number as documented, V - E + F = 2 chi + 2 p, on the first step
    first = boundary_mesh(v, 26)
    assert int(rows[0]["mesh_euler"]) == 2 * euler_number(np.pad(v, 1), 3) + 2 * first.pinched
    assert f"{len(plys)} of {len(plys)} step surfaces read back by trimesh" in stdout


def test_a_step_file_names_its_vertex_columns_as_a_surface_file_does(tmp_path):
    """A step's PLY carried per-vertex columns (config, class, gamma, a, f)
    that no comment named, where ``isoflow surface``'s PLY names them. The
    columns its comment names are the ones trimesh reads beside the
    position and colour, in the header's order."""
    v = np.zeros((5, 5, 5), bool)
    v[1:4, 1:4, 1:4] = True
    np.save(tmp_path / "v.npy", v)
    assert run("flow", tmp_path / "v.npy", "--steps", "1", "--out", tmp_path / "run", "--no-check")[0] == 0
    ply = tmp_path / "run" / "step_000.ply"
    header = ply.read_bytes().split(b"end_header")[0].decode("ascii").splitlines()
    named = [line.split(":", 1)[1] for line in header if line.startswith("comment per-vertex:")]
    assert len(named) == 1, header
    # "config byte, class (gamma+4; ...), gamma (...), ...": each column's name, its notes left out
    columns = [part.split()[0] for part in re.sub(r"\([^)]*\)", "", named[0]).split(",")]
    vertex = header.index(next(line for line in header if line.startswith("element vertex")))
    element = header[vertex + 1:]
    element = element[: next((i for i, line in enumerate(element) if line.startswith("element")), len(element))]
    in_header = [line.split()[-1] for line in element if line.startswith("property ")]
    read = trimesh.load(ply, process=False).metadata["_ply_raw"]["vertex"]["data"].dtype.names
    assert list(read) == in_header
    assert columns == [name for name in in_header if name not in ("x", "y", "z", "red", "green", "blue")]
    assert columns == ["config", "class", "gamma", "a", "f"]  # as docs/formats.md lists them


def test_flow_step_file_that_reads_differently_exits_1(tmp_path, monkeypatch):
    from isoflow.mesh import export

    real = export.surface_faces

    def lossy(mesh, suffix, **kw):  # a writer that loses a face
        kind, faces = real(mesh, suffix, **kw)
        return kind, faces[1:]

    monkeypatch.setattr(export, "surface_faces", lossy)
    np.save(tmp_path / "b.npy", np.ones((3, 3, 3), bool))
    rc, _, err = run("flow", tmp_path / "b.npy", "--out", tmp_path / "run")
    assert rc == 1
    lines = err.strip().splitlines()
    assert len(lines) == 3 and f"{tmp_path / 'run' / 'step_000.ply'}: trimesh reads watertight False" in lines[0]
    with open(tmp_path / "run" / "flow.csv") as fh:
        assert {r["trimesh_watertight"] for r in csv.DictReader(fh) if r["mesh_euler"]} == {"False"}


def test_flow_out_in_a_missing_directory_is_refused(tmp_path, capsys):
    """--out is checked as -o is: a missing parent is a mistyped path, not
    one to make, parents and all."""
    from isoflow.cli import main

    np.save(tmp_path / "b.npy", np.ones((3, 3, 3), bool))
    assert main(["flow", str(tmp_path / "b.npy"), "--out", str(tmp_path / "nodir" / "sub")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nodir: no such directory" in err[0]
    assert not (tmp_path / "nodir").exists()
    assert main(["flow", str(tmp_path / "b.npy"), "--out", str(tmp_path / "new")]) == 0  # one level is made
    assert (tmp_path / "new" / "flow.csv").exists()


def test_an_interrupt_while_writing_names_the_directory(tmp_path, capsys, monkeypatch):
    """Ctrl-C while a step file is written: one line naming the run's
    directory (it was ': ; the previous run's ...'), exit 130, the earlier
    run's files unchanged."""
    from isoflow.cli import main
    from isoflow.mesh import export

    np.save(tmp_path / "b.npy", np.ones((4, 4, 4), bool))
    assert main(["flow", str(tmp_path / "b.npy"), "--out", str(tmp_path / "o")]) == 0
    before = {p.name: p.read_bytes() for p in (tmp_path / "o").iterdir()}
    capsys.readouterr()

    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(export, "write_mesh_file", stop)
    assert main(["flow", str(tmp_path / "b.npy"), "--out", str(tmp_path / "o"), "--force"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"isoflow: interrupted: {tmp_path / 'o'}: stopped while writing the flow's files; the previous "
                   "run's files in the directory are unchanged"], err
    assert {p.name: p.read_bytes() for p in (tmp_path / "o").iterdir()} == before


@pytest.mark.parametrize("name,extra", [
    ("step_007.npy", []),  # an earlier run's step file: removed once the run is in place
    ("step_000.npy", ["--volumes", ".npy"]),  # replaced by the new step 0 (cropped, its place lost)
])
def test_flow_out_force_never_replaces_its_own_input(tmp_path, name, extra):
    v = np.zeros((6, 7, 8), bool)
    v[1:5, 2:6, 2:7] = True
    out = tmp_path / "run"
    out.mkdir()
    np.save(out / name, v)
    before = (out / name).read_bytes()
    rc, stdout, err = run("flow", out / name, "--out", out, "--force", *extra)
    assert rc == 2 and stdout == ""
    assert err.strip().splitlines() == [
        f"isoflow flow: error: {out / name}: is the input, and flow --out {out} replaces the step files, flow.csv "
        "and pictures there; give --out another directory (--force replaces an output, never the input)"]
    assert sorted(p.name for p in out.iterdir()) == [name] and (out / name).read_bytes() == before
    # another file in the directory is no step file: the run goes ahead beside it
    np.save(out / "v.npy", v)
    rc, stdout, err = run("flow", out / "v.npy", "--out", out, "--force", "--no-check")
    assert rc == 0, err
    assert (out / "v.npy").exists() and (out / "step_000.ply").exists()


@pytest.mark.parametrize("name,extra", [
    ("step_002.npy", []),  # an earlier run's step file: removed once the run is in place
    ("step_001.zarr", ["--volumes", ".zarr"]),  # a step store, replaced by the new step 1 (flowed block by block)
])
def test_flow_out_force_never_replaces_its_input_through_a_link(tmp_path, name, extra):
    """``flow LINK --out DIR --force``, LINK a symbolic link to a step file
    of DIR: the refusal looked at the link's own directory, so the run
    went ahead and removed (or replaced with another state) the file the
    link names, the user's input. The link is followed now, as the shell
    user sees the file: refused in one line, the file kept."""
    zarr = pytest.importorskip("zarr")
    v = np.zeros((6, 7, 8), bool)
    v[1:5, 2:6, 2:7] = True
    out = tmp_path / "run"
    out.mkdir()
    if name.endswith(".zarr"):
        zarr.open_array(str(out / name), mode="w", shape=v.shape, chunks=(3, 7, 8), dtype="u1")[...] = v
    else:
        np.save(out / name, v)
    link = tmp_path / f"link{Path(name).suffix}"
    link.symlink_to(out / name)
    before = {str(f.relative_to(out)): f.read_bytes() for f in sorted(out.rglob("*")) if f.is_file()}
    p = subprocess.run([sys.executable, "-m", "isoflow", "flow", str(link), "--out", str(out), "--force", *extra],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and p.stdout == "", p.stderr
    assert p.stderr.strip().splitlines() == [
        f"isoflow flow: error: {link}: is the input, and flow --out {out} replaces the step files, flow.csv "
        "and pictures there; give --out another directory (--force replaces an output, never the input)"]
    assert {str(f.relative_to(out)): f.read_bytes() for f in sorted(out.rglob("*")) if f.is_file()} == before
    assert np.array_equal(isoflow.read_volume(link).volume, v)


def test_flow_out_force_replaces_links_of_an_earlier_run_not_what_they_name(tmp_path):
    """A run directory whose step files are symbolic links (to a store and
    a file of the user's, elsewhere): ``--force`` put the new run's files
    in place, then failed on the links ("Cannot call rmtree on a symbolic
    link", exit 2) saying the previous run was unchanged. The links are
    step names of the directory and go as step files do (the one the new
    run writes is replaced by its store); what they name is kept."""
    zarr = pytest.importorskip("zarr")
    v = np.zeros((6, 7, 8), bool)
    v[1:5, 2:6, 2:7] = True
    mine = tmp_path / "mine.zarr"
    zarr.open_array(str(mine), mode="w", shape=v.shape, chunks=(3, 7, 8), dtype="u1")[...] = v
    np.save(tmp_path / "mine.npy", v)
    kept = {str(f.relative_to(tmp_path)): f.read_bytes() for f in sorted(tmp_path.rglob("*")) if f.is_file()}
    out = tmp_path / "run"
    out.mkdir()
    (out / "step_000.zarr").symlink_to(mine)
    (out / "step_009.zarr").symlink_to(mine)
    (out / "step_010.npy").symlink_to(tmp_path / "mine.npy")
    np.save(tmp_path / "cube.npy", np.ones((3, 3, 3), bool))
    p = subprocess.run([sys.executable, "-m", "isoflow", "flow", str(tmp_path / "cube.npy"), "--out", str(out),
                        "--force", "--volumes", ".zarr", "-q"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert sorted(f.name for f in out.iterdir()) == ["flow.csv", "flow.png", "shapes.png", "step_000.ply",
                                                     "step_000.zarr", "step_001.ply", "step_001.zarr",
                                                     "step_002.ply", "step_002.zarr"]
    assert not (out / "step_000.zarr").is_symlink()
    assert np.count_nonzero(zarr.open_group(str(out / "step_000.zarr"), mode="r")["0"][...]) == 27
    assert {str(f.relative_to(tmp_path)): f.read_bytes() for f in sorted(tmp_path.rglob("*"))
            if f.is_file() and out not in f.parents and f.name != "cube.npy"} == kept


def test_a_step_named_link_to_a_folder_of_the_user_s_does_not_block_the_run(tmp_path):
    """A link named step_005.zarr to a directory that is no zarr store:
    told from a real directory by its name only, it made --force refuse
    the whole run. It is the run's to remove: unlinked, what it leads to
    kept byte for byte."""
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    out = tmp_path / "run"
    out.mkdir()
    (out / "step_005.zarr").symlink_to(mine, target_is_directory=True)
    np.save(tmp_path / "cube.npy", np.ones((3, 3, 3), bool))
    p = subprocess.run([sys.executable, "-m", "isoflow", "flow", str(tmp_path / "cube.npy"), "--out", str(out),
                        "--force", "-q"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert not (out / "step_005.zarr").is_symlink() and not (out / "step_005.zarr").exists()
    assert [f.name for f in mine.iterdir()] == ["notes.txt"] and (mine / "notes.txt").read_text() == "mine"
    # a 3x3x3 cube: 6 faces of 9 squares, 2 triangles each
    assert len(trimesh.load(out / "step_000.ply", process=False).faces) == 6 * 9 * 2


def test_step_volumes_a_format_cannot_hold_are_refused_before_the_flow(tmp_path):
    # binvox holds 3D voxels of one size: a 2D image or a pitch per axis
    # was refused when step 0 was written, after the input was read and
    # the flow begun; now before the output directory is made
    np.save(tmp_path / "img.npy", np.ones((4, 5), bool))
    isoflow.write_volume(isoflow.DigitalObject(np.ones((3, 3, 3), bool), pitch=(1.0, 1.0, 2.0)), tmp_path / "a.npz")
    for name, why in (("img.npy", "binvox holds 3D voxels, this object is 2D"),
                      ("a.npz", "binvox holds one voxel size and this object's pitch is [1, 1, 2]")):
        rc, stdout, err = run("flow", tmp_path / name, "--out", tmp_path / "new", "--volumes", ".binvox")
        assert rc == 2 and stdout == ""
        assert err.strip().splitlines() == [f"isoflow flow: error: {tmp_path / 'new' / 'step_000.binvox'}: {why}"
                                            + ("; write .nii.gz, .nrrd or .h5 to keep it" if name == "a.npz" else "")]
        assert not (tmp_path / "new").exists()


def test_a_failed_first_run_does_not_speak_of_a_previous_run(tmp_path, monkeypatch):
    # a step volume that fails to be written (here: the disk), into a new
    # directory and an empty one: there is no previous run to keep (it said
    # "the previous run's files in the directory are unchanged"); over an
    # earlier run it is kept
    import isoflow.mesh.volumes as volumes

    def full(obj, path, force=False, unit=None):
        raise isoflow.IsoflowError(f"{path}: no space left on the device")

    np.save(tmp_path / "img.npy", np.ones((4, 5), bool))
    (tmp_path / "empty").mkdir()
    with monkeypatch.context() as m:
        m.setattr(volumes, "write_volume", full)
        for out in (tmp_path / "new", tmp_path / "empty"):
            rc, stdout, err = run("flow", tmp_path / "img.npy", "--out", out, "--volumes", ".npz")
            assert rc == 2
            assert err.strip().splitlines() == [
                f"isoflow flow: error: {out / 'step_000.npz'}: no space left on the device; nothing was written"]
    assert not (tmp_path / "new").exists() and not any((tmp_path / "empty").iterdir())
    assert run("flow", tmp_path / "img.npy", "--out", tmp_path / "empty")[0] == 0
    before = {p.name: p.read_bytes() for p in (tmp_path / "empty").iterdir()}
    with monkeypatch.context() as m:
        m.setattr(volumes, "write_volume", full)
        rc, stdout, err = run("flow", tmp_path / "img.npy", "--out", tmp_path / "empty", "--volumes", ".npz", "--force")
    assert rc == 2 and err.strip().endswith("; the previous run's files in the directory are unchanged")
    assert {p.name: p.read_bytes() for p in (tmp_path / "empty").iterdir()} == before


@pytest.mark.parametrize("fails", [1, 2])
def test_a_rename_that_fails_part_way_says_what_it_replaced(tmp_path, monkeypatch, fails):
    """The final renames into --out: the second failing (an I/O error)
    said "the previous run is unchanged" with the first new file in place.
    The line now counts what was put in place; the files that differ from
    the previous run's are exactly that many."""
    import os

    np.save(tmp_path / "a.npy", np.pad(np.ones((6, 6, 6), bool), 2))
    np.save(tmp_path / "b.npy", np.pad(np.ones((4, 5, 6), bool), 2))
    out = tmp_path / "run"
    assert run("flow", tmp_path / "a.npy", "--steps", "2", "--out", out)[0] == 0
    before = {f.name: f.read_bytes() for f in out.iterdir()}
    real, calls = os.replace, []

    def failing(src, dst, *a, **k):
        if Path(dst).parent == out:  # the renames into the run's directory, not those inside the staging one
            calls.append(dst)
            if len(calls) == fails:
                raise OSError(5, "Input/output error", str(dst))
        return real(src, dst, *a, **k)

    monkeypatch.setattr(os, "replace", failing)
    rc, _, err = run("flow", tmp_path / "b.npy", "--steps", "2", "--out", out, "--force")
    monkeypatch.setattr(os, "replace", real)
    after = {f.name: f.read_bytes() for f in out.iterdir()}
    changed = sorted(n for n in after if before.get(n) != after[n])
    assert rc == 2 and len(changed) == fails - 1 and sorted(after) == sorted(before)
    assert len(err.strip().splitlines()) == 1 and "Input/output error" in err
    if fails == 1:
        assert err.strip().endswith("the previous run's files in the directory are unchanged")
    else:
        assert "unchanged" not in err and "1 of this run's" in err and "files of both runs" in err
    assert not [f for f in out.iterdir() if f.name.startswith(".")]  # the staging directory is gone


def _entries(path: Path) -> dict:
    """What a step entry holds, file by file (a link: where it leads; a
    store: each file's bytes by its path inside)."""
    if path.is_symlink():
        return {"link": str(path.readlink())}
    if path.is_dir():
        return {str(f.relative_to(path)): f.read_bytes() for f in sorted(path.rglob("*")) if f.is_file()}
    return {"": path.read_bytes()}


@pytest.mark.parametrize("fails", ["rename", "rename and back", "removal", "interrupt"])
@pytest.mark.parametrize("kind,name", [("link", "step_000.ply"), ("store", "step_001.zarr")])
def test_a_step_entry_replaced_part_way_is_kept_and_said(tmp_path, monkeypatch, kind, name, fails):
    """A link or a step store at a step's name was removed before the
    rename that puts this run's entry there; that rename failing (an I/O
    error) lost the previous run's entry ("no NAME is there now"). It is
    moved aside now, and back where this run's is not put in its place:
    the previous entry is as it was, whole (a link leading to the user's
    file, a store's every file), and the line says so; where the move back
    fails too, the line names the hidden name that holds it; where the
    moved-aside entry cannot be removed, this run's is in place and the
    line names what is left."""
    import os

    from isoflow.flow import files

    v = np.zeros((8, 8, 8), bool)
    v[2:6, 2:6, 2:6] = True
    np.save(tmp_path / "v.npy", v)
    v[2:6, 2:6, 6] = True  # this run's: other step files than the previous run's
    np.save(tmp_path / "w.npy", v)
    out = tmp_path / "run"
    extra = ["--volumes", ".zarr"] if kind == "store" else []
    assert run("flow", tmp_path / "v.npy", "--steps", "1", "--out", out, "--no-check", *extra)[0] == 0
    mine = tmp_path / "mine.ply"
    if kind == "link":  # the user's own file, linked under a step's name
        (out / name).rename(mine)
        (out / name).symlink_to(mine)
    assert (out / name).is_symlink() or (out / name).is_dir()
    previous, theirs = _entries(out / name), mine.read_bytes() if kind == "link" else None
    real_replace, real_remove = os.replace, files.remove_entry

    def failing(src, dst, *a, **k):
        staged = Path(src).name == name and Path(src).parent != out  # this run's entry, from the staging directory
        if Path(dst) == out / name and staged and fails == "interrupt":  # Ctrl-C with the previous entry aside
            raise KeyboardInterrupt
        if Path(dst) == out / name and (staged or fails == "rename and back"):
            raise OSError(5, "Input/output error", str(dst))
        return real_replace(src, dst, *a, **k)

    def unremovable(path):
        if path.parent == out and path.name.startswith(f".{name.split('.')[0]}"):  # the moved-aside entry
            raise OSError(13, "Permission denied", str(path))
        return real_remove(path)

    with monkeypatch.context() as m:
        m.setattr(os, "replace", failing) if fails != "removal" else m.setattr(files, "remove_entry", unremovable)
        rc, _, err = run("flow", tmp_path / "w.npy", "--steps", "1", "--out", out, "--force", "--no-check", *extra)
    assert rc == (130 if fails == "interrupt" else 2) and len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err
    hidden = [p for p in out.iterdir() if p.name.startswith(".")]
    if kind == "link":
        assert mine.read_bytes() == theirs  # what the link led to is the user's, whatever came
    if fails in ("rename", "interrupt"):
        assert _entries(out / name) == previous and not hidden
        if name == "step_000.ply":  # the first rename: the whole previous run is as it was
            assert err.strip().endswith("the previous run's files in the directory are unchanged"), err
        else:  # step_000's store and surface went in first
            assert "2 of this run's" in err and f"the previous run's {name} is as it was" in err, err
        said = "interrupted while putting the run's files in place" if fails == "interrupt" else \
            "could not put it in place (Input/output error)"
        assert said in err and "moved aside" not in err, err
    elif fails == "rename and back":  # the previous entry whole at the hidden name the line gives
        assert not os.path.lexists(out / name) and len(hidden) == 1 and _entries(hidden[0]) == previous
        assert f"the previous run's {name} (a {'link' if kind == 'link' else 'step store'}" in err, err
        assert f"was moved aside as {hidden[0].name} to make room and could not be moved back" in err, err
    else:  # this run's entry in place, the previous one left beside it
        assert len(hidden) == 1 and _entries(hidden[0]) == previous and _entries(out / name) != previous
        assert f"could not remove the previous run's {'link' if kind == 'link' else 'step store'} (Permission " \
               f"denied); the previous run's {name} is left beside it as {hidden[0].name}" in err, err
    assert not [p for p in hidden if "run" in p.name]  # the staging directory is gone


def test_a_second_interrupt_while_the_previous_run_goes_names_what_is_left(tmp_path, capsys, monkeypatch):
    """Ctrl-C while the previous run's files that the new run does not
    replace were removed, and again (past the second within which a
    repeat is ignored) as the staging directory went: the second, bare,
    interrupt was worded "stopped after the run was complete", with files
    of the previous run left beside the new one's. The line now names
    the ones removed and the ones left, as the directory holds them."""
    import shutil

    from isoflow.flow import files
    from isoflow.mesh.outputs import TEMP_MARK

    big, small = np.zeros((8, 8, 8), bool), np.zeros((8, 8, 8), bool)
    big[1:7, 1:7, 1:7] = True  # the previous run: more steps than the new one
    small[2:5, 2:5, 2:5] = True
    np.save(tmp_path / "big.npy", big)
    np.save(tmp_path / "small.npy", small)
    out, fresh = tmp_path / "o", tmp_path / "fresh"
    assert main(["flow", str(tmp_path / "big.npy"), "--out", str(out), "--no-check"]) == 0
    assert main(["flow", str(tmp_path / "small.npy"), "--out", str(fresh), "--no-check"]) == 0
    before, written = {p.name for p in out.iterdir()}, {p.name for p in fresh.iterdir()}
    real_remove, real_rmtree, removals, stops = files.remove_entry, shutil.rmtree, [], []

    def remove(path):
        removals.append(path)
        if len(removals) == 2:  # the first interrupt, one file of the previous run removed
            raise KeyboardInterrupt
        real_remove(path)

    def rmtree(path, *args, **kwargs):
        if Path(path).name.startswith(f".{files.STAGE}{TEMP_MARK}") and not stops:  # the second, as the stage goes
            stops.append(path)
            raise KeyboardInterrupt
        return real_rmtree(path, *args, **kwargs)

    monkeypatch.setattr(files, "remove_entry", remove)
    monkeypatch.setattr(shutil, "rmtree", rmtree)
    capsys.readouterr()
    assert main(["flow", str(tmp_path / "small.npy"), "--out", str(out), "--force", "--no-check"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    monkeypatch.setattr(shutil, "rmtree", real_rmtree)
    after = {p.name for p in out.iterdir()}
    gone, left = sorted(before - written - after), sorted(before - written & after)
    assert stops and len(gone) == 1 and len(left) >= 2 and written <= after
    assert len(err) == 1 and "complete" not in err[0], err
    assert f"1 of them was removed ({gone[0]})" in err[0], err
    assert f"{len(left)} are left beside them ({', '.join(left[:3])}" in err[0], err

@pytest.mark.parametrize("at", ["progress_bar", "bar_total"])
@pytest.mark.parametrize("store", [False, True])
def test_an_interrupt_as_the_run_begins_leaves_no_staging_directory(tmp_path, monkeypatch, store, at):
    """Between the staging directory's making and the flow's first step (the
    progress bar's start, the bar's size, an import), an interrupt left the
    directory behind (and, over an earlier run, a hidden directory beside
    its files): it is removed wherever the interrupt comes, and an earlier
    run stays."""
    import isoflow.cli.flow as cli_flow

    v = np.zeros((6, 6, 6), bool)
    v[1:5, 1:5, 1:5] = True
    name = "in.zarr" if store else "in.npy"
    isoflow.write_volume(isoflow.DigitalObject(v), tmp_path / name)
    extra = ["--volumes", ".zarr"] if store else []
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "flow.csv").write_text("the previous run\n")

    @contextlib.contextmanager
    def interrupted_bar(*args, **kwargs):
        raise KeyboardInterrupt
        yield

    def interrupted_size(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_flow, at, interrupted_bar if at == "progress_bar" else interrupted_size)
    for out in (tmp_path / "new", tmp_path / "run"):
        rc, _, err = run("flow", tmp_path / name, "--out", out, "--force", *extra)
        assert rc == 130 and err.strip().splitlines()[-1].startswith("isoflow: interrupted"), err
    assert not (tmp_path / "new").exists()
    assert [p.name for p in (tmp_path / "run").iterdir()] == ["flow.csv"]
    assert (tmp_path / "run" / "flow.csv").read_text() == "the previous run\n"


def test_a_state_grown_past_magicavoxel_names_the_step(tmp_path, monkeypatch):
    # a flow's states can grow past their input by a few voxels: MagicaVoxel's
    # limit then failed at a later step with a voxelize hint ("voxelise it
    # coarser (--resolution 256)"); now the step and the formats that hold any size
    from isoflow.mesh.formats import magicavoxel

    np.save(tmp_path / "v.npy", np.random.default_rng(0).random((8, 8, 8)) < 0.5)  # 8 across, 10 at step 2 (26-connected)
    out = tmp_path / "out"
    args = ("flow", tmp_path / "v.npy", "--out", out, "--steps", "3", "--connectivity", "26", "--no-check")
    assert run(*args)[0] == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(magicavoxel, "MAX_SIDE", 9)
    rc, stdout, err = run(*args, "--force", "--volumes", ".vox")
    assert rc == 2 and "Traceback" not in err
    errors = [line for line in err.strip().splitlines() if not line.startswith("isoflow flow: warning:")]
    assert errors == [
        f"isoflow flow: error: {out / 'step_002.vox'}: MagicaVoxel models are at most 9 voxels a side, this object "
        "is 9x10x9 (step 2's state); write the steps in another --volumes format (.npz or .zarr holds any size); "
        "the previous run's files in the directory are unchanged"]
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # too large at step 0: refused before the flow, naming step 0
    monkeypatch.setattr(magicavoxel, "MAX_SIDE", 7)
    rc, stdout, err = run(*args, "--force", "--volumes", ".vox")
    assert rc == 2 and err.strip().splitlines() == [
        f"isoflow flow: error: {out / 'step_000.vox'}: MagicaVoxel models are at most 7 voxels a side, this object "
        "is 8x8x8 (step 0's state); write the steps in another --volumes format (.npz or .zarr holds any size)"]
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.parametrize("extra, remedy", [
    (["--volumes", ".ome.zarr"], "flow it block by block (--out DIR --volumes .zarr"),
    ([], "flow it block by block (--out DIR --volumes .zarr"),
    (["--volumes", ".npz", "--label", "1"], "write label 1's voxels as a store of their own"),
    (["--guard"], "crop it: --guard is not done block by block"),
])
def test_a_store_too_large_to_flow_in_memory_names_the_block_wise_flow(tmp_path, extra, remedy):
    """``--volumes .ome.zarr`` (OME-Zarr, as ``.zarr``) flows in memory and
    writes each state from there: the state is in memory already. A store
    that would not fit there was refused as any read is, "use a .zarr store
    with 'isoflow info'": the line, up front, from the shell, now names the
    flow that reads it block by block (``--volumes .zarr``), or why none
    does. The store holds 2^60 uint8 voxels (only its metadata is written):
    three bytes a voxel, 3 * 2^30 GiB."""
    import subprocess
    import sys

    zarr = pytest.importorskip("zarr")
    zarr.open_array(str(tmp_path / "huge.zarr"), mode="w", shape=(1 << 20,) * 3, chunks=(256,) * 3, dtype="u1",
                    zarr_format=2, fill_value=0)
    p = subprocess.run([sys.executable, "-m", "isoflow", "flow", "huge.zarr", "--steps", "1", "--out", "run", *extra],
                       capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert p.returncode == 2 and p.stderr.count("\n") == 1, p.stderr
    assert p.stderr.startswith("isoflow flow: error: huge.zarr: a 1048576x1048576x1048576 volume of uint8 needs about "
                               f"{3 << 30:.1f} GiB of memory"), p.stderr
    assert remedy in p.stderr and not (tmp_path / "run").exists()


def test_a_guarded_run_s_csv_has_the_move_of_every_step_as_its_json(tmp_path):
    """flow.csv holds the columns of --json's step records: a guarded run's
    ``move`` too (empty for step 0, the input)."""
    import json

    np.save(tmp_path / "t.npy", np.pad(np.ones((3, 4, 5), bool), 1))
    rc, stdout, err = run("flow", tmp_path / "t.npy", "--guard", "--out", tmp_path / "run", "--json")
    assert rc == 0, err
    moves = [s.get("move", "") for s in json.loads(stdout)["steps"]]
    with open(tmp_path / "run" / "flow.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["move"] for r in rows] == moves == ["", "flow", "flow", "flow"]
    assert [int(r["voxels"]) for r in rows] == [60, 24, 6, 1]  # docs/flow.md: the 3x4x5 box, to one voxel


def test_2d_out_writes_shapes_png_and_counts_pixels(tmp_path, monkeypatch):
    """A 2D run's --out writes shapes.png as the help says, and its table
    and flow.png count pixels, as ``isoflow info`` does for a 2D image."""
    from PIL import Image

    from isoflow.flow import pictures

    labels = {}
    save = pictures.save_figure

    def keep_labels(fig, path):
        labels[path.name] = [ax.get_ylabel() for ax in fig.axes] + [ax.get_title() for ax in fig.axes]
        return save(fig, path)

    monkeypatch.setattr(pictures, "save_figure", keep_labels)
    img = np.zeros((9, 8), bool)
    img[1:7, 2:7] = True
    img[3:5, 4] = False  # a hole, closed at step 1
    np.save(tmp_path / "img.npy", img)
    out = tmp_path / "run"
    rc, stdout, err = run("flow", tmp_path / "img.npy", "--out", out)
    assert rc == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["flow.csv", "flow.png", "shapes.png"]
    assert "shapes.png" in stdout
    header = stdout.splitlines()[1].split()
    assert header[:2] == ["step", "pixels"] and "voxels" not in stdout
    assert labels["flow.png"][0] == "pixels"
    assert "step 0: 28 pixels, betti (1, 1)" in labels["shapes.png"]
    with Image.open(out / "shapes.png") as picture:  # a picture, with the object drawn in it
        grey = np.asarray(picture.convert("L"))
    assert grey.shape[0] > 200 and (grey < 200).mean() > 0.05


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_huge_steps_name_files_by_the_reachable_step_and_count_without_a_bar(tmp_path, monkeypatch):
    """--steps far past what the object lasts: the names are padded for the
    steps a run of it can reach (docs/flow.md), not for --steps, and a
    terminal gets a counter, not a bar at 0 % with an estimate of hours."""
    box = np.ones((3, 4, 5), bool)
    np.save(tmp_path / "box.npy", box)
    out = tmp_path / "run"
    err = _Terminal()
    o = io.StringIO()
    with contextlib.redirect_stdout(o), contextlib.redirect_stderr(err):
        rc = main(["flow", str(tmp_path / "box.npy"), "--steps", "1000000000000", "--out", str(out), "--volumes", ".npz"])
    assert rc == 0, err.getvalue()
    assert sorted(p.name for p in out.glob("step_*")) == [
        "step_000.npz", "step_000.ply", "step_001.npz", "step_001.ply", "step_002.npz", "step_002.ply"]
    assert isoflow.read_volume(out / "step_002.npz").voxels == 6
    assert "%|" not in err.getvalue() and "flow: " in err.getvalue()  # a counter was shown
    assert "stopped: vanished" in o.getvalue()


def test_steps_the_run_can_reach_get_a_bar(tmp_path):
    np.save(tmp_path / "box.npy", np.ones((3, 4, 5), bool))
    err = _Terminal()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        assert main(["flow", str(tmp_path / "box.npy"), "--steps", "2"]) == 0
    assert "%|" in err.getvalue()


def test_a_run_past_its_expected_last_step_widens_every_name(tmp_path):
    """The writer pads for the step it expects; a run that goes on past it
    has all its names widened before they are moved into place."""
    from isoflow.flow.files import FlowWriter

    result = isoflow.run_flow(np.ones((2, 2, 2), bool))  # steps 0 and 1
    writer = FlowWriter(tmp_path / "run", 6, last_step=5, check=False)
    writer.add(0, result.states[0])
    writer.add(1000, result.states[0])  # (as a step 1000 would)
    writer.finish(result, plot=False)
    assert sorted(p.name for p in (tmp_path / "run").glob("step_*")) == ["step_0000.ply", "step_1000.ply"]


#: a fresh interpreter's ``isoflow flow --guard --out`` of Example 19, which
#: prints the modules a thread other than the main one imports first
FIRST_IMPORTS = """
import builtins, importlib.util, json, sys, threading
first, real = [], builtins.__import__
def watch(name, globals=None, locals=None, fromlist=(), level=0):
    if threading.current_thread() is not threading.main_thread():
        full = importlib.util.resolve_name("." * level + name, (globals or {}).get("__package__")) if level else name
        if full not in sys.modules:
            first.append(full)
    return real(name, globals, locals, fromlist, level)
builtins.__import__ = watch
from isoflow import data
from isoflow.cli import main
print(json.dumps([main(["flow", str(data.example19()), "--guard", "--out", sys.argv[1], "-q"]), first]))
"""


def test_the_step_files_check_imports_nothing_on_its_thread(tmp_path):
    """``isoflow flow meshes/example19.txt --guard --out run/`` (a README
    command) failed once with ``KeyError: 'scipy'``: the read-back thread
    imported trimesh (and with it scipy) for the first time while the flow
    imported scipy.ndimage for step 1's components. The first check runs
    on the flow's thread, so the thread imports nothing of its own."""
    import json
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", FIRST_IMPORTS, str(tmp_path / "run")], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    rc, first = json.loads(done.stdout.splitlines()[-1])
    assert rc == 0 and first == []
    with open(tmp_path / "run" / "flow.csv") as fh:  # the checks are made: trimesh's reading of both steps
        rows = list(csv.DictReader(fh))
    assert [r["trimesh_euler"] for r in rows] == ["2", "2"]


def test_until_topology_change_stops_before_the_step_that_merges(tmp_path):
    """``isoflow flow --until-topology-change`` (run_flow's
    until_topology_change, which the command had no option for) stops
    before the step that would change the Betti numbers: every state
    written has scipy's two 6-components of the input, and the plain run's
    next state, the step not taken, has one."""
    from scipy import ndimage

    v = np.zeros((12, 8, 8), bool)
    v[1:5, 1:5, 1:5] = True
    v[5:9, 5:7, 1:5] = True  # shares an edge with the first box
    np.save(tmp_path / "two.npy", v)
    assert ndimage.label(v)[1] == 2
    rc, out, _ = run("flow", tmp_path / "two.npy", "--until-topology-change", "--out", tmp_path / "run",
                     "--volumes", ".npz", "--json", "-q")
    assert rc == 0
    got = json.loads(out)
    assert got["stop_reason"] == "topology-change"
    files = sorted((tmp_path / "run").glob("step_*.npz"))
    assert len(files) == len(got["steps"])
    assert [ndimage.label(np.load(f)["volume"])[1] for f in files] == [2] * len(files)
    rc, _, _ = run("flow", tmp_path / "two.npy", "--out", tmp_path / "plain", "--volumes", ".npz", "-q")
    taken = np.load(tmp_path / "plain" / f"step_{len(files):03d}.npz")["volume"]
    assert rc == 0 and ndimage.label(taken)[1] == 1
    rc, out, _ = run("flow", tmp_path / "two.npy", "--until-topology-change", "-q")
    rows = [line.split()[0] for line in out.splitlines() if line.strip()[:1].isdigit()]
    change = [line for line in out.splitlines() if "topology change at step" in line]
    assert rc == 0 and rows == [str(s) for s in range(len(files))] and len(change) == 1
    assert change[0].endswith("(the step is not taken: the run stopped before it)")


def test_the_text_places_the_limit_and_a_change_of_a_far_origin_to_a_fraction_of_a_voxel(tmp_path):
    """At an origin far from 0 in fine voxels the table's limit and the box
    of a topology change were printed to 6 digits: a box's limit at
    [123456, -654321, 1e+06], voxels away from its centre, and a change in
    the box [123456, ...] to [123456, ...], of no size. The centre is
    pynrrd's reading of the file: a box flows to its centre."""
    nrrd = pytest.importorskip("nrrd")
    import re

    pitch, origin = np.array([0.01, 0.02, 0.04]), np.array([123456.0, -654321.0, 1.0e6])
    header = {"space directions": np.diag(pitch), "space origin": origin, "space": "left-posterior-superior"}
    box = np.zeros((8, 9, 10), np.uint8)
    box[2:5, 2:6, 2:7] = 1  # 3 x 4 x 5
    nrrd.write(str(tmp_path / "box.nrrd"), box, header)
    back, head = nrrd.read(str(tmp_path / "box.nrrd"))
    idx = np.argwhere(back)
    # the space origin is the centre of voxel 0: the box's centre is the mean of its voxels' centres
    centre = np.asarray(head["space origin"]) + np.diag(head["space directions"]) * idx.mean(0)
    rc, out, _ = run("flow", tmp_path / "box.nrrd", "-q")
    limit = re.search(r"limit: \[([^\]]*)\]", out).group(1)
    assert rc == 0 and np.allclose([float(x) for x in limit.split(",")], centre, rtol=0, atol=pitch / 200)

    two = np.zeros((12, 8, 8), np.uint8)
    two[1:5, 1:5, 1:5] = 1
    two[5:9, 5:7, 1:5] = 1  # shares an edge: the third step merges the two pieces
    nrrd.write(str(tmp_path / "two.nrrd"), two, header)
    rc, out, _ = run("flow", tmp_path / "two.nrrd", "-q")
    lo, hi = re.search(r"in the box \[([^\]]*)\] to \[([^\]]*)\]", out).groups()
    lo, hi = (np.array([float(x) for x in c.split(",")]) for c in (lo, hi))
    assert rc == 0 and (hi - lo > pitch / 2).all()


def test_the_report_names_the_length_unit_of_its_coordinates(tmp_path):
    """The limit and the boxes of topology changes are world coordinates
    in the input's length unit, which neither the text nor --json said:
    the unit nibabel reads from the NIfTI header, where it names one."""
    nib = pytest.importorskip("nibabel")

    two = np.zeros((12, 8, 8), np.uint8)
    two[1:5, 1:5, 1:5] = 1
    two[5:9, 5:7, 1:5] = 1  # shares an edge: the third step merges the two pieces
    image = nib.Nifti1Image(two, np.diag([0.5, 0.7, 1.2, 1.0]))
    image.header.set_xyzt_units("mm")
    nib.save(image, tmp_path / "two.nii.gz")
    unit = nib.load(tmp_path / "two.nii.gz").header.get_xyzt_units()[0]
    rc, out, _ = run("flow", tmp_path / "two.nii.gz", "--json", "-q")
    assert rc == 0 and json.loads(out)["unit"] == unit == "mm"
    rc, out, _ = run("flow", tmp_path / "two.nii.gz", "-q")
    placed = [line for line in out.splitlines() if line.lstrip().startswith(("limit:", "topology change"))]
    assert rc == 0 and len(placed) == 2
    assert "] mm, the centre" in placed[0] and placed[1].endswith("] mm")

    nib.save(nib.Nifti1Image(two, np.eye(4)), tmp_path / "plain.nii.gz")  # no unit in the header
    assert nib.load(tmp_path / "plain.nii.gz").header.get_xyzt_units()[0] == "unknown"
    rc, out, _ = run("flow", tmp_path / "plain.nii.gz", "--json", "-q")
    assert rc == 0 and json.loads(out)["unit"] is None


def test_export_flow_names_force_in_python_words(tmp_path):
    """``export_flow`` into a directory that holds files told a Python
    caller to "pass --force", an option of the command line; it names its
    own ``force=True``, and the command still says --force."""
    from isoflow.errors import IsoflowError
    from isoflow.flow.files import export_flow

    result = isoflow.run_flow(isoflow.DigitalObject(np.ones((3, 4, 5), bool)))
    export_flow(result, tmp_path / "run", plot=False)
    with pytest.raises(IsoflowError, match="force=True") as refused:
        export_flow(result, tmp_path / "run", plot=False)
    assert "--force" not in str(refused.value)
    np.save(tmp_path / "box.npy", np.ones((3, 4, 5), bool))
    rc, _, err = run("flow", tmp_path / "box.npy", "--out", tmp_path / "run")
    assert rc == 2 and "pass --force" in err and "force=True" not in err


def test_flow_png_shows_the_betti_numbers_of_a_run_of_one_state(tmp_path):
    """``flow --steps 0 --out`` (or a run stopped before its first step)
    drew an empty Betti panel: a step line of one point draws nothing.
    Read back by Pillow, the panel (less the legend, at its right) now
    holds pixels of b0's colour, matplotlib's tab:blue."""
    from PIL import Image

    np.save(tmp_path / "box.npy", np.ones((3, 4, 5), bool))
    rc, _, _ = run("flow", tmp_path / "box.npy", "--steps", "0", "--out", tmp_path / "run", "-q")
    assert rc == 0
    picture = np.asarray(Image.open(tmp_path / "run" / "flow.png").convert("RGB")).astype(int)
    height, width = picture.shape[:2]
    betti_panel = picture[height * 63 // 100 : height * 93 // 100, width // 8 : width * 3 // 4]
    blue = np.abs(betti_panel - np.array([31, 119, 180])).sum(-1) < 60  # tab:blue, #1f77b4
    assert blue.sum() > 4


def test_flow_png_of_one_state_ticks_whole_steps(tmp_path, monkeypatch):
    """The step axis of a run of one state was ticked -0.045, -0.03, ...:
    the steps shown are whole numbers."""
    from isoflow.flow import pictures

    drawn = []
    monkeypatch.setattr(pictures, "save_figure", lambda fig, path: drawn.append(fig) or path)
    result = isoflow.run_flow(isoflow.DigitalObject(np.ones((3, 4, 5), bool)), steps=0)
    pictures.render_flow(result, tmp_path / "flow.png")
    axis = drawn[0].axes[2]
    low, high = axis.get_xlim()
    ticks = [t for t in axis.get_xticks() if low <= t <= high]
    assert ticks and all(float(t).is_integer() for t in ticks)


def pinched_vertices(v: np.ndarray, conn: int) -> int:
    """Lattice vertices whose eight cells are two opposite cells of one
    kind and six of the other, of the kind the connectivity joins and the
    surface splits: background under 6, object under 26 (counted here on
    the padded array, without isoflow)."""
    p = np.pad(v, 1)
    cells = np.stack([p[a:p.shape[0] - 1 + a, b:p.shape[1] - 1 + b, c:p.shape[2] - 1 + c]
                      for a in (0, 1) for b in (0, 1) for c in (0, 1)])  # octant k = 4a + 2b + c
    pair = ~cells if conn == 6 else cells
    count = pair.sum(0) == 2
    opposite = np.zeros(count.shape, bool)
    for k in range(4):
        opposite |= pair[k] & pair[7 - k]
    return int((count & opposite).sum())


@pytest.mark.parametrize("conn", [6, 26])
def test_flow_csv_mesh_euler_is_twice_chi_and_twice_the_pinched_vertices(tmp_path, conn):
    """docs/flow.md: ``mesh_euler`` is ``2 chi + 2 p``, with chi
    scikit-image's Euler number of each written state and p its pinched
    vertices counted on the array."""
    rng = np.random.default_rng(3)
    v = rng.random((9, 9, 9)) < 0.5
    np.save(tmp_path / "noise.npy", v)
    rc, _, _ = run("flow", tmp_path / "noise.npy", "--connectivity", conn, "--out", tmp_path / "run",
                   "--volumes", ".npz", "-q")
    assert rc == 0
    rows = list(csv.DictReader(open(tmp_path / "run" / "flow.csv")))
    pinched = 0
    for row in rows[:-1]:  # the last state is empty: no surface
        state = np.load(tmp_path / "run" / f"step_{int(row['step']):03d}.npz")["volume"]
        chi = euler_number(np.pad(state, 1), connectivity=1 if conn == 6 else 3)
        p = pinched_vertices(state, conn)
        pinched += p
        assert int(row["mesh_euler"]) == 2 * chi + 2 * p
    assert pinched  # the noise has pinched vertices: the two numbers differ


@pytest.mark.parametrize("store", [False, True])
def test_an_interrupt_while_the_flow_computes_names_the_directory(tmp_path, capsys, monkeypatch, store):
    """Ctrl-C while a step is computed (no file being written) said only
    "isoflow: interrupted", where one while a file is written says the
    previous run's files are unchanged. Both now say it, in memory and
    block by block, and the earlier run's files are byte for byte as
    they were."""
    from isoflow.flow import engines
    from isoflow.flow.chunked import ChunkedFlow

    v = np.zeros((8, 8, 8), bool)
    v[1:7, 1:7, 1:7] = True
    source = tmp_path / ("b.zarr" if store else "b.npy")
    isoflow.write_volume(isoflow.DigitalObject(v), source) if store else np.save(source, v)
    extra = ["--volumes", ".zarr"] if store else ["--no-check"]
    assert main(["flow", str(source), "--out", str(tmp_path / "o"), *extra]) == 0
    before = {p.name: p.read_bytes() for p in (tmp_path / "o").iterdir() if p.is_file()}
    capsys.readouterr()

    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(ChunkedFlow if store else engines.ArrayFlow, "step", stop)
    monkeypatch.setattr(engines.BitFlow, "step", stop)
    assert main(["flow", str(source), "--out", str(tmp_path / "o"), "--force", *extra]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"isoflow: interrupted: {tmp_path / 'o'}: stopped while the flow ran; the previous run's files "
                   "in the directory are unchanged"], err
    assert {p.name: p.read_bytes() for p in (tmp_path / "o").iterdir() if p.is_file()} == before


# (block by block the command's own handler differs; the writer's renames are the same)
@pytest.mark.parametrize("store,where", [(False, "after finish"), (False, "as the stage goes"),
                                         (False, "at the directory's sync"), (True, "after finish")])
def test_an_interrupt_once_the_run_is_in_place_says_so(tmp_path, capsys, monkeypatch, store, where):
    """Ctrl-C arriving once every file of the run was renamed into --out
    (after the writer's finish returned, or as the emptied staging
    directory was removed) was worded "stopped while the flow ran; the
    previous run's files in the directory are unchanged", with the new
    run's files in place and the previous run's gone. It now says that
    the run is complete and its files are in place; stopped before the
    previous run's other files were removed, it says they may be left.
    (Into a new directory it said "nothing was written".)"""
    import shutil

    from isoflow.flow import files
    from isoflow.mesh.outputs import TEMP_MARK

    big, small = np.zeros((8, 8, 8), bool), np.zeros((8, 8, 8), bool)
    big[1:7, 1:7, 1:7] = True  # the previous run: more steps than the new one
    small[2:5, 2:5, 2:5] = True
    suffix = ".zarr" if store else ".npy"
    for name, v in (("big", big), ("small", small)):
        isoflow.write_volume(isoflow.DigitalObject(v), tmp_path / f"{name}{suffix}") if store else \
            np.save(tmp_path / f"{name}.npy", v)
    extra = ["--volumes", ".zarr"] if store else ["--no-check"]
    out, fresh = tmp_path / "o", tmp_path / "fresh"
    if not store:  # (block by block, the one case there, into a directory of no previous run: a run less)
        assert main(["flow", str(tmp_path / f"big{suffix}"), "--out", str(out), *extra]) == 0
    assert main(["flow", str(tmp_path / f"small{suffix}"), "--out", str(fresh), *extra]) == 0
    before = {p.name for p in out.iterdir()} if out.exists() else set()
    written = {p.name for p in fresh.iterdir()}
    assert store or before - written  # the previous run's files that the new run does not replace
    capsys.readouterr()
    if where == "after finish":
        real_finish = files.FlowWriter.finish

        def finish(self, *args, **kwargs):
            real_finish(self, *args, **kwargs)  # every file in place
            raise KeyboardInterrupt

        monkeypatch.setattr(files.FlowWriter, "finish", finish)
    elif where == "as the stage goes":
        real_rmtree, stops = shutil.rmtree, []

        def rmtree(path, *args, **kwargs):
            if Path(path).name.startswith(f".{files.STAGE}{TEMP_MARK}") and not stops:  # the staging directory, once
                stops.append(path)
                raise KeyboardInterrupt
            return real_rmtree(path, *args, **kwargs)

        monkeypatch.setattr(shutil, "rmtree", rmtree)
    else:
        def sync(path):
            raise KeyboardInterrupt

        monkeypatch.setattr(files, "sync_directory", sync)
    assert main(["flow", str(tmp_path / f"small{suffix}"), "--out", str(out), "--force", *extra]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    after = {p.name for p in out.iterdir()}
    if where == "at the directory's sync":  # before the previous run's other files were removed
        assert after == before | written
        left = sorted(before - written)
        assert err == [f"isoflow: interrupted: {out}: interrupted after the run's files were put in place; this "
                       f"run's {len(written)} files are in place; of the previous run's {len(left)} files that it "
                       f"does not replace, none of them was removed, {len(left)} are left beside them "
                       f"({', '.join(left[:3])}{f', and {len(left) - 3} more' if len(left) > 3 else ''})"], err
    else:
        assert after == written
        assert err == [f"isoflow: interrupted: {out}: stopped after the run was complete; its {len(written)} files "
                       "are in place"], err
    # step 0 is the new input: its voxels as numpy counts them
    first = zarr_count(out / "step_000.zarr") if store else trimesh.load(out / "step_000.ply", process=False).volume
    assert first == pytest.approx(np.count_nonzero(small))


def zarr_count(path: Path) -> int:
    """The voxels of an OME-Zarr step store, as zarr reads its first level."""
    import zarr

    return int(np.count_nonzero(zarr.open_group(str(path), mode="r")["0"][...]))


def test_a_terminal_sees_the_bar_while_step_0_is_written_and_a_line_while_the_files_are_finished(tmp_path, monkeypatch):
    """A large object's ``flow --out`` was silent on a terminal while step
    0's surface was written (as long as a step) and while the last step
    files were read back and the pictures drawn (seconds at 300^3): the
    bar appeared only after step 1 and was gone during the finish."""
    from isoflow.flow.files import FlowWriter

    np.save(tmp_path / "box.npy", np.ones((3, 4, 5), bool))
    err = _Terminal()
    seen = {}
    add, finish = FlowWriter.add, FlowWriter.finish

    def spy_add(self, step, state):
        seen.setdefault(step, err.getvalue())
        return add(self, step, state)

    def spy_finish(self, result, plot=True):
        seen["finish"] = err.getvalue()
        return finish(self, result, plot)

    monkeypatch.setattr(FlowWriter, "add", spy_add)
    monkeypatch.setattr(FlowWriter, "finish", spy_finish)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        assert main(["flow", str(tmp_path / "box.npy"), "--steps", "2", "--out", str(tmp_path / "run")]) == 0
    assert "flow:   0%|" in seen[0]  # the bar, before step 0's surface is written
    last = seen["finish"].rsplit("\r", 1)[-1]
    assert last == f"flow: writing {tmp_path / 'run'}", seen["finish"][-200:]


def test_a_store_flowed_block_by_block_shows_the_bar_from_step_0(tmp_path, monkeypatch):
    """``flow STORE.zarr --volumes .zarr`` said nothing on a terminal while
    step 0 (the store read block by block) was analysed."""
    from isoflow.flow import chunked

    isoflow.write_volume(np.ones((3, 4, 5), bool), tmp_path / "box.zarr")
    err = _Terminal()
    seen = []
    start = chunked.ChunkedFlow.start

    def spy_start(self, source):
        seen.append(err.getvalue())
        return start(self, source)

    monkeypatch.setattr(chunked.ChunkedFlow, "start", spy_start)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        assert main(["flow", str(tmp_path / "box.zarr"), "--steps", "2", "--volumes", ".zarr",
                     "--out", str(tmp_path / "run")]) == 0
    assert "flow:   0%|" in seen[0]


def test_2d_shapes_png_draws_a_png_mask_as_pillow_reads_it(tmp_path):
    """shapes.png of a PNG mask shows the mask the right way up: the object
    in its one panel (--steps 0), sampled at the pixel centres, is the
    mask as Pillow reads the file (rows down, columns across), not that
    mask upside down."""
    from PIL import Image
    from scipy import ndimage

    mask = np.zeros((20, 30), np.uint8)  # an F: not symmetric top to bottom
    mask[2:16, 3:7] = 255
    mask[2:6, 3:20] = 255
    mask[8:11, 3:14] = 255
    Image.fromarray(mask).save(tmp_path / "f.png")
    with Image.open(tmp_path / "f.png") as png:
        read = np.asarray(png) > 0
    rows, cols = np.nonzero(read)
    expected = read[rows.min() : rows.max() + 1, cols.min() : cols.max() + 1]
    rc, _, err = run("flow", tmp_path / "f.png", "--steps", 0, "--out", tmp_path / "run")
    assert rc == 0, err
    with Image.open(tmp_path / "run" / "shapes.png") as picture:
        rgb = np.asarray(picture.convert("RGB")).astype(int)
    # the pixels' fill: one mid grey (the text and the axes are black, the background white)
    grey = (np.ptp(rgb, axis=2) == 0) & (np.abs(rgb[..., 0] - 115) < 15)
    parts, count = ndimage.label(grey)
    drawn = parts == 1 + np.argmax(ndimage.sum(grey, parts, range(1, count + 1)))
    y, x = np.nonzero(drawn)
    h, w = expected.shape
    centres_y = (y.min() + (np.arange(h) + 0.5) * (y.max() + 1 - y.min()) / h).astype(int)
    centres_x = (x.min() + (np.arange(w) + 0.5) * (x.max() + 1 - x.min()) / w).astype(int)
    np.testing.assert_array_equal(drawn[np.ix_(centres_y, centres_x)], expected)


def test_2d_flow_text_names_its_last_state_a_rectangle_or_not(tmp_path):
    """In the plane the text's limit line says rectangle, not cuboid: the
    last non-empty state of a 5x7 rectangle's flow, read back from its
    step file by NumPy, fills its box (scikit-image's extent 1), and a
    checkerboard, whose 18 pixels vanish in one step, does not."""
    from skimage.measure import regionprops

    np.save(tmp_path / "box.npy", np.ones((5, 7), bool))
    rc, out, err = run("flow", tmp_path / "box.npy", "--out", tmp_path / "run", "--volumes", ".npy")
    assert rc == 0, err
    last = int(re.search(r"\(step (\d+): ", out).group(1))
    state = np.load(tmp_path / "run" / f"step_{last:03d}.npy")
    assert regionprops(state.astype(np.uint8))[0].extent == 1
    assert f"(step {last}: a rectangle)" in out and "cuboid" not in out
    checker = np.indices((6, 6)).sum(axis=0) % 2 == 0
    assert regionprops(checker.astype(np.uint8))[0].extent < 1
    np.save(tmp_path / "checker.npy", checker)
    rc, out, err = run("flow", tmp_path / "checker.npy")
    assert rc == 0, err
    assert "(step 0: not a rectangle)" in out and "cuboid" not in out


@pytest.mark.parametrize(("steps", "last"), [(["--steps", "5"], "flow: 100%|"), (["--steps", "3"], "flow: 100%|"),
                                             ([], "flow: 3 steps [")])
def test_a_short_run_shows_its_full_count_before_the_bar_is_cleared(tmp_path, steps, last):
    """On a terminal the bar of a short run was cleared at the count its
    first step showed (33 %: tqdm draws at most every 0.1 s), and that of
    a run that vanished before --steps at its share of --steps (20 %): the
    last state drawn before the clearing is the whole run. The 3x4x5 box
    vanishes at step 3 (60, 24, 6, 0 voxels: docs/flow.md)."""
    np.save(tmp_path / "box.npy", np.ones((3, 4, 5), bool))
    err = _Terminal()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        assert main(["flow", str(tmp_path / "box.npy"), *steps]) == 0
    shown = [part for part in err.getvalue().split("\r") if part.strip()]
    assert shown and shown[-1].startswith(last), shown


def test_flow_png_ticks_its_counts_in_whole_numbers(tmp_path, monkeypatch):
    """flow.png's voxel axis of a run of one voxel (1 voxel, then none)
    was ticked 0.2, 0.4, ...: voxel counts, energies (sums of whole
    weights over vertex classes, eq. 5.22), Betti numbers and steps are
    whole numbers, and so is every tick of every axis of the picture."""
    from isoflow.flow import pictures

    drawn = []
    monkeypatch.setattr(pictures, "save_figure", lambda fig, path: drawn.append(fig) or path)
    result = isoflow.run_flow(isoflow.DigitalObject(np.ones((1, 1, 1), bool)))
    assert [s["voxels"] for s in result.steps] == [1, 0]
    pictures.render_flow(result, tmp_path / "flow.png")
    drawn[0].canvas.draw()
    for axis in drawn[0].axes:
        for ticks, (low, high) in ((axis.get_xticks(), axis.get_xlim()), (axis.get_yticks(), axis.get_ylim())):
            shown = [t for t in ticks if low <= t <= high]
            assert shown and all(float(t).is_integer() for t in shown), (axis.get_ylabel(), shown)
        labels = [t.get_text().replace("\N{MINUS SIGN}", "-") for t in axis.get_yticklabels() if t.get_text()]
        assert labels and all(re.fullmatch(r"-?\d+", text) for text in labels), (axis.get_ylabel(), labels)


def test_a_2d_flow_writes_its_steps_as_png_masks_read_back_as_written(tmp_path):
    """A 2D flow could not write its steps as PNG (``--volumes .png``: PNG
    was read only). Each step is a lossless 8-bit grey PNG of 0 and 255,
    rows its y as isoflow reads a PNG: Pillow reads every step file as
    the state's pixels transposed, and isoflow reads it back as the state,
    pixel for pixel (its place, which PNG does not keep, said once)."""
    from PIL import Image

    mask = np.zeros((12, 20), np.uint8)  # rows y, columns x; an L, not symmetric
    mask[2:9, 3:15] = 255
    mask[5:9, 3:6] = 0
    Image.fromarray(mask).save(tmp_path / "l.png")
    result = isoflow.run_flow(isoflow.read_volume(tmp_path / "l.png"), connectivity=4)
    out = tmp_path / "run"
    rc, _, err = run("flow", tmp_path / "l.png", "--out", out, "--volumes", ".png")
    assert rc == 0, err
    states = [s for s in result.states if s.voxels]
    assert sorted(p.name for p in out.glob("step_*")) == [f"step_{k:03d}.png" for k in range(len(states))]
    with Image.open(out / "step_000.png") as png:  # the input as Pillow reads it, cropped to the L: same way up
        assert np.array_equal(np.asarray(png), mask[2:9, 3:15])
    for k, state in enumerate(states):
        with Image.open(out / f"step_{k:03d}.png") as png:
            assert png.mode == "L" and png.format == "PNG"
            pixels = np.asarray(png)
        assert set(np.unique(pixels)) <= {0, 255}
        assert np.array_equal(pixels.T > 0, state.volume)
        assert np.array_equal(isoflow.read_volume(out / f"step_{k:03d}.png").volume, state.volume)
    dropped = [line for line in err.splitlines() if "PNG keeps no pixel size, origin or unit" in line]
    assert len(dropped) == 1 and "warning:" in dropped[0], err
    assert "; origin [" in dropped[0] and "pitch" not in dropped[0]  # a pixel size of 1 is read back as it was


def test_2d_shapes_png_ticks_pixel_coordinates_in_whole_pixels(tmp_path, monkeypatch):
    """shapes.png of a small PNG mask (pixel size 1: its coordinates count
    pixels) was ticked -0.5, 0.5, 1.5, ...; every tick label of its
    panels is a whole number, in matplotlib's own axes."""
    from PIL import Image

    from isoflow.flow import pictures

    drawn, save = [], pictures.save_figure
    monkeypatch.setattr(pictures, "save_figure", lambda fig, path: drawn.append((path.name, fig)) or save(fig, path))
    mask = np.zeros((6, 6), np.uint8)
    mask[2:4, 2:4] = 255
    Image.fromarray(mask).save(tmp_path / "dot.png")
    rc, _, err = run("flow", tmp_path / "dot.png", "--out", tmp_path / "run")
    assert rc == 0, err
    fig = dict(drawn)["shapes.png"]
    fig.canvas.draw()
    for axis in fig.axes:
        labels = [t.get_text().replace("\N{MINUS SIGN}", "-") for t in axis.get_xticklabels() + axis.get_yticklabels()]
        labels = [text for text in labels if text]
        assert labels and all(re.fullmatch(r"-?\d+", text) for text in labels), (axis.get_title(), labels)


def test_2d_shapes_png_titles_clear_the_tick_labels_of_the_panels_above(tmp_path, monkeypatch):
    """shapes.png of two rectangles, one with a hole (six panels in two
    rows, pixel size 1): the second row's titles were drawn across the
    first row's x tick labels (laid out by ``tight_layout``), "step 4: 25
    pixels" crossed by "6" and "8". No
    title now meets a tick label that another panel draws, as
    matplotlib places them in the figure."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from isoflow.flow import pictures

    drawn, save = [], pictures.save_figure
    monkeypatch.setattr(pictures, "save_figure", lambda fig, path: drawn.append((path.name, fig)) or save(fig, path))
    img = np.zeros((20, 20), bool)
    img[2:10, 3:15] = True
    img[12:18, 12:18] = True
    img[14:16, 14:16] = False
    np.save(tmp_path / "two.npy", img)
    rc, _, err = run("flow", tmp_path / "two.npy", "--connectivity", "8", "--guard", "--out", tmp_path / "run")
    assert rc == 0, err
    fig = dict(drawn)["shapes.png"]
    assert len(fig.axes) == 6
    canvas = FigureCanvasAgg(fig)  # (save_figure closed it: drawn again as it was saved)
    canvas.draw()
    renderer = canvas.get_renderer()
    ticks = []
    for k, axis in enumerate(fig.axes):
        (x0, x1), (y0, y1) = sorted(axis.get_xlim()), sorted(axis.get_ylim())
        shown = [t for t in axis.get_xticklabels() if t.get_text() and x0 <= t.get_position()[0] <= x1]
        shown += [t for t in axis.get_yticklabels() if t.get_text() and y0 <= t.get_position()[1] <= y1]
        ticks += [(k, t.get_text(), t.get_window_extent(renderer)) for t in shown]
    for k, axis in enumerate(fig.axes):
        title = axis.title.get_window_extent(renderer)
        crossed = [(j, text) for j, text, box in ticks if j != k and title.overlaps(box)]
        assert not crossed, (axis.get_title(), crossed)
