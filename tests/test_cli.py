"""The command line: JSON contract, outputs, and one-line errors (exit 2)."""

import itertools
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import torus
from skimage.measure import euler_number

from isoflow.cli import main

ROOT = Path(__file__).resolve().parents[1]
MESHES = ROOT / "meshes"


def run(*args, cwd=None):
    """Run the real console entry point in a subprocess."""
    return subprocess.run(
        [sys.executable, "-m", "isoflow.cli", *map(str, args)],
        capture_output=True, text=True, cwd=cwd,
    )


def info_json(capsys, *args):
    assert main(["info", *map(str, args), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_info_json_contract(tmp_path, capsys):
    v = torus(6, 2)
    np.save(tmp_path / "t.npy", v)
    r = info_json(capsys, tmp_path / "t.npy")
    for key in ("voxels", "dimension", "connectivity", "euler_characteristic", "betti", "n",
                "non_well_composed", "a_dot_n", "energy", "surfaces"):
        assert key in r
    assert r["voxels"] == int(v.sum())
    assert r["dimension"] == 3 and r["connectivity"] == 6
    assert r["euler_characteristic"] == euler_number(v, 1) == 0
    assert r["betti"] == [1, 1, 0]
    assert len(r["n"]) == 9 and sum(r["n"]) + r["non_well_composed"] > 0
    assert r["a_dot_n"] == 8 * r["euler_characteristic"]
    assert r["surfaces"] == [{"euler_characteristic": 0, "genus": 1, "faces": r["surfaces"][0]["faces"]}]


@pytest.mark.parametrize("fill, voxels", [("winding", 6 * 11 * 16), ("shell", 6 * 11 * 16 - 4 * 9 * 14)])
def test_info_of_a_mesh_says_its_fill_and_grid(fill, voxels, tmp_path, capsys):
    """A 1 x 2 x 3 box at 16 across: pitch 3/16, 6 x 11 x 16 voxels centred
    on the box, all in its solid, only the outer layer in its shell. The
    report did not say which fill or grid its counts were of."""
    box = tmp_path / "box.stl"
    trimesh.creation.box((1, 2, 3)).export(box)
    r = info_json(capsys, box, "--resolution", 16, "--fill", fill)
    assert r["voxels"] == voxels
    assert r["voxelised"] == {"fill": fill, "pitch": 0.1875, "origin": [-0.5625, -1.03125, -1.5]}
    assert main(["info", str(box), "--resolution", "16", "--fill", fill]) == 0
    assert f"voxelised              --fill {fill}, pitch 0.1875, origin [-0.5625, -1.03125, -1.5]" \
        in capsys.readouterr().out.splitlines()[1]
    np.save(tmp_path / "v.npy", np.ones((2, 2, 2), np.uint8))
    assert "voxelised" not in info_json(capsys, tmp_path / "v.npy")


def test_info_26_connectivity_and_2d(tmp_path, capsys):
    rng = np.random.default_rng(3)
    v = rng.random((9, 9, 9)) < 0.4
    np.save(tmp_path / "r.npy", v.astype(np.uint8))
    r = info_json(capsys, tmp_path / "r.npy", "--connectivity", "26")
    assert r["euler_characteristic"] == euler_number(v, 3)
    img = rng.random((20, 20)) < 0.5
    np.savez(tmp_path / "p.npz", img)
    r2 = info_json(capsys, tmp_path / "p.npz", "--connectivity", "8")
    assert r2["dimension"] == 2 and len(r2["betti"]) == 2 and len(r2["n"]) == 3
    assert r2["euler_characteristic"] == euler_number(img, 2) == r2["betti"][0] - r2["betti"][1]


def test_info_of_empty_object_reports_zeros(tmp_path, capsys):
    np.save(tmp_path / "e.npy", np.zeros((4, 4, 4), bool))
    r = info_json(capsys, tmp_path / "e.npy")
    assert r["voxels"] == 0 and r["euler_characteristic"] == 0
    assert r["betti"] == [0, 0, 0] and r["n"] == [0] * 9 and r["surfaces"] == []


def test_info_table_is_readable(capsys):
    assert main(["info", str(ROOT / "meshes" / "example19.txt")]) == 0
    out = capsys.readouterr().out
    assert "Euler characteristic   1" in out and "(+,-,-)+" in out


@pytest.mark.parametrize("counts, nwc, end", [
    ([3, 40, 7], 2, 27),  # the table as it always read: every count ends at column 27
    ([3, 10**5, 7], 123456, 28),
    ([10**12, 10**6, 7], 10**12, 35),  # 13 digits
])
def test_info_table_counts_share_one_column_whatever_their_size(counts, nwc, end):
    import dataclasses

    from isoflow import analyze
    from isoflow.cli.info import format_info

    v = np.zeros((6, 6, 6), bool)
    v[1:5, 1:5, 1:5] = True
    r = analyze(v)
    labels = list(r["classes"])[:3]
    r = dataclasses.replace(r, classes=dict(zip(labels, counts)), non_well_composed=nwc)
    lines = format_info(r, "big").splitlines()
    start = lines.index("  vertex classes (eq. 4.9):") + 1
    rows = lines[start:start + len(labels) + 1]
    assert [int(row.split()[-1]) for row in rows] == counts + [nwc]
    assert [len(row) for row in rows] == [end] * len(rows)
    assert [row[4:4 + len(str(name))] for row, name in zip(rows, labels + ["not well-composed"])] == [
        str(name) for name in labels + ["not well-composed"]]


def test_surface_writes_ply_and_obj(tmp_path, capsys):
    v = torus(5, 2)
    np.save(tmp_path / "t.npy", v)
    assert main(["surface", str(tmp_path / "t.npy"), "-o", str(tmp_path / "t.ply")]) == 0
    assert main(["surface", str(tmp_path / "t.npy"), "-o", str(tmp_path / "t.obj"), "--triangulate"]) == 0
    for name in ("t.ply", "t.obj"):
        m = trimesh.load(tmp_path / name, process=False)
        assert m.is_watertight and m.euler_number == 0
        assert m.volume == pytest.approx(v.sum())


def test_surface_says_how_trimesh_reads_split_contacts_back(tmp_path, capsys):
    """Two cubes touching along an edge: the mesh keeps two copies of the
    edge's vertices, so trimesh reads the file back watertight only with
    process=False; the line says so, with the number of positions its
    default merge joins (the vertices it drops)."""
    vol = np.zeros((6, 6, 4), bool)
    vol[1:3, 1:3, 1:3] = vol[3:5, 3:5, 1:3] = True  # an edge contact: 3 lattice points, 2 edge midpoints
    np.save(tmp_path / "e.npy", vol)
    assert main(["surface", str(tmp_path / "e.npy"), "-o", str(tmp_path / "e.ply"), "--connectivity", "26"]) == 0
    said = capsys.readouterr().out.splitlines()[-1]
    kept, merged = trimesh.load(tmp_path / "e.ply", process=False), trimesh.load(tmp_path / "e.ply")
    assert kept.is_watertight and not merged.is_watertight
    assert f"with process=False (its default merge joins the split copies at {len(kept.vertices) - len(merged.vertices)} " in said
    np.save(tmp_path / "one.npy", vol[:3])  # one cube: nothing to merge, nothing to say
    assert main(["surface", str(tmp_path / "one.npy"), "-o", str(tmp_path / "one.ply")]) == 0
    assert "reads it back watertight, V-E+F = 2" in capsys.readouterr().out


def test_surface_png(tmp_path, capsys):
    np.save(tmp_path / "t.npy", torus(5, 2))
    assert main(["surface", str(tmp_path / "t.npy"), "-o", str(tmp_path / "t.ply"),
                 "--png", str(tmp_path / "t.png")]) == 0
    assert (tmp_path / "t.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the mesh's lines, held until both files are in place, are printed then, before the picture's
    lines = capsys.readouterr().out.splitlines()
    mesh = trimesh.load(tmp_path / "t.ply", process=False)
    assert lines[0].startswith(f"{tmp_path / 't.ply'}: {len(mesh.vertices)} vertices, ")
    assert lines[1].startswith(f"{tmp_path / 't.ply'}: trimesh reads it back watertight")
    assert lines[2:] == [f"{tmp_path / 't.png'}: picture of the surface coloured by vertex angle"]


def surface_with_picture(tmp_path, volume, *more) -> int:
    """``surface -o out/t.ply --png out/t.png`` of ``volume``."""
    np.save(tmp_path / "v.npy", volume)
    (tmp_path / "out").mkdir(exist_ok=True)
    return main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "out" / "t.ply"), "--png",
                 str(tmp_path / "out" / "t.png"), *more])


@pytest.mark.parametrize("how, status", [("disk full", 2), ("SIGTERM", 128 + 15)])
def test_surface_png_failing_keeps_the_earlier_mesh_too(tmp_path, capsys, monkeypatch, how, status):
    # the new mesh was in place beside the old picture when the picture's write failed; then, with the earlier
    # pair kept, stdout still said the new mesh was written and read back
    from test_labels_cli import fail_at, files_in

    assert surface_with_picture(tmp_path, torus(5, 2)) == 0
    before = files_in(tmp_path / "out")
    capsys.readouterr()
    fail_at(monkeypatch, "t.png", how)
    code = surface_with_picture(tmp_path, torus(6, 2), "--force")
    out, err = capsys.readouterr()
    assert code == status, err
    assert err.count("\n") == 1 and err.rstrip().endswith("nothing was replaced"), err
    assert files_in(tmp_path / "out") == before  # byte for byte, and no temporary left
    assert out == ""  # no line describes a file that is not there


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
@pytest.mark.parametrize("earlier", [False, True], ids=["new", "--force"])
def test_surface_png_interrupted_while_drawn_names_both_files(tmp_path, capsys, monkeypatch, earlier):
    """Ctrl-C while the picture is drawn, after the mesh is written and
    read back: exit 130, no picture, mesh or temporary left (the earlier
    pair byte for byte), and the line names the set, the mesh and its
    picture (it named the mesh alone: "t.ply: nothing was replaced");
    stdout says nothing of the mesh that is not there."""
    import signal

    from test_labels_cli import files_in

    from isoflow.mesh import render

    if earlier:
        assert surface_with_picture(tmp_path, torus(5, 2)) == 0
    else:
        (tmp_path / "out").mkdir()
    before = files_in(tmp_path / "out")
    capsys.readouterr()
    draw = render.render_surface

    def interrupted(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        return draw(*args, **kwargs)

    monkeypatch.setattr(render, "render_surface", interrupted)
    assert surface_with_picture(tmp_path, torus(6, 2), *(["--force"] if earlier else [])) == 130
    out = tmp_path / "out"
    said = capsys.readouterr()
    assert said.err.strip().splitlines() == [
        f"isoflow: interrupted: {out / 't.ply'} and {out / 't.png'}: nothing was replaced"]
    assert said.out == ""
    assert files_in(out) == before


def test_surface_png_force_replaces_the_picture_also_where_the_mesh_reads_back_otherwise(tmp_path, capsys, monkeypatch):
    # the new mesh was put in place and the picture not drawn: the old picture stayed beside it
    from isoflow.mesh import readback

    assert surface_with_picture(tmp_path, torus(5, 2)) == 0
    old_png = (tmp_path / "out" / "t.png").read_bytes()
    capsys.readouterr()
    monkeypatch.setattr(readback, "check_surface_file", lambda path, *a, **k: {"agree": False, "problem": f"{path}: odd"})
    assert surface_with_picture(tmp_path, torus(7, 2), "--force") == 1
    assert capsys.readouterr().err.endswith("t.ply: odd\n")
    mesh = trimesh.load(tmp_path / "out" / "t.ply", process=False)
    assert mesh.is_watertight and mesh.volume == pytest.approx(int(torus(7, 2).sum()))
    new_png = (tmp_path / "out" / "t.png").read_bytes()
    assert new_png[:8] == b"\x89PNG\r\n\x1a\n" and new_png != old_png
    assert sorted(f.name for f in (tmp_path / "out").iterdir()) == ["t.ply", "t.png"]


def _bad(tmp_path):
    np.save(tmp_path / "nonbinary.npy", np.arange(27).reshape(3, 3, 3))
    np.save(tmp_path / "line.npy", np.ones(5, bool))
    np.save(tmp_path / "empty.npy", np.zeros((3, 3, 3), bool))
    (tmp_path / "garbage.npy").write_bytes(b"not numpy at all")
    (tmp_path / "frac.txt").write_text("0 0 0\n1 0.5 0\n")
    (tmp_path / "exists.ply").write_text("keep me")
    np.save(tmp_path / "ok.npy", np.ones((2, 2, 2), bool))
    return [
        (["info", tmp_path / "missing.npy"], "no such file"),
        (["info", tmp_path / "garbage.npy"], "not a numpy file: it starts with b'not nump'"),
        (["info", tmp_path / "nonbinary.npy"], "not a binary volume"),
        (["info", tmp_path / "line.npy"], "1D"),
        (["info", tmp_path / "frac.txt"], "0.5 is not an integer"),
        (["surface", tmp_path / "empty.npy", "-o", tmp_path / "e.ply"], "empty"),
        (["surface", tmp_path / "ok.npy", "-o", tmp_path / "exists.ply"], "--force"),
        (["info", tmp_path / "ok.npy", "--connectivity", "8"], "connectivity 8"),
    ]


def test_bad_input_gives_one_line_and_exit_2(tmp_path):
    for args, words in _bad(tmp_path):
        p = run(*args)
        assert p.returncode == 2, (args, p.stderr)
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
        assert words in lines[0]
        files = [Path(str(a)).name for a in args if isinstance(a, Path)]
        assert any(f in lines[0] for f in files) or "connectivity" in words
    assert (tmp_path / "exists.ply").read_text() == "keep me"
    assert not (tmp_path / "e.ply").exists()


def test_boundary_face_count_from_the_histogram(rng):
    # faces counted from 256 configuration counts alone, against an
    # independent count of object/background neighbour pairs on each axis
    from isoflow.digital.configurations import configuration_histogram
    from isoflow.digital.surface import boundary_faces

    for _ in range(100):
        v = rng.random(tuple(rng.integers(1, 10, 3))) < rng.random()
        p = np.pad(v, 1)
        pairs = sum(int(np.count_nonzero(np.diff(p, axis=a))) for a in range(3))
        assert boundary_faces(configuration_histogram(v)) == pairs


def test_surface_refuses_a_mesh_beyond_the_memory_budget(tmp_path, capsys, monkeypatch):
    from isoflow.scale import memory

    np.save(tmp_path / "t.npy", torus(6, 2))
    monkeypatch.setattr(memory, "default_budget", lambda: 100_000)
    out = tmp_path / "t.ply"
    assert main(["surface", str(tmp_path / "t.npy"), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "t.npy" in err and "faces" in err and "budget" in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_info_counts_surfaces_without_the_mesh_memory(tmp_path, capsys, monkeypatch):
    # the per-surface genus no longer builds the mesh: with a budget far
    # below the mesh's estimate, info still reports every surface, and they
    # are the mesh's own components
    from isoflow import boundary_mesh
    from isoflow.digital.configurations import configuration_histogram
    from isoflow.digital.surface import mesh_memory
    from isoflow.scale import memory

    v = torus(6, 2)
    v[0:3, 0:3, 0:3] = True  # a second surface, a cube in the corner
    want = sorted((c["euler_characteristic"], c["genus"], c["faces"]) for c in boundary_mesh(v).components())
    np.save(tmp_path / "t.npy", v)
    monkeypatch.setattr(memory, "default_budget", lambda: 300_000)
    assert 300_000 < mesh_memory(configuration_histogram(v))
    r = info_json(capsys, tmp_path / "t.npy")
    assert r["betti"] == [2, 1, 0] and r["euler_characteristic"] == euler_number(v, connectivity=1)
    assert sorted((s["euler_characteristic"], s["genus"], s["faces"]) for s in r["surfaces"]) == want
    assert [s["genus"] for s in r["surfaces"]] == [1, 0]  # largest first


def test_info_threads_option_and_environment(tmp_path):
    # a volume above the compiled passes' threshold, as the user runs it:
    # a subprocess, with --threads and ISOFLOW_THREADS; same report on 1 and
    # 3 threads, and the surfaces the mesh has
    import os

    from conftest import ball, compiled_side

    from isoflow import boundary_mesh
    from isoflow.scale.compiled import least_voxels

    v = np.zeros((compiled_side(),) * 3, bool)
    v[:60, :60, :60] = torus(20, 8, size=60)
    v[70:130, 70:130, 70:130] = ball(25, size=60) & ~ball(12, size=60)  # a shell: two spheres
    v[5, 100, 100] = v[6, 101, 101] = True  # a vertex contact
    assert v.size >= least_voxels(surfaces=True)
    np.save(tmp_path / "v.npy", v)
    out = {}
    for threads in (1, 3):
        p = run("info", tmp_path / "v.npy", "--json", "--connectivity", "26", "--threads", threads)
        assert p.returncode == 0, p.stderr
        out[threads] = json.loads(p.stdout)
    env = dict(os.environ, ISOFLOW_THREADS="2")
    p = subprocess.run([sys.executable, "-m", "isoflow.cli", "info", str(tmp_path / "v.npy"), "--json",
                        "--connectivity", "26"], capture_output=True, text=True, env=env)
    assert json.loads(p.stdout) == out[1] == out[3]
    mesh = boundary_mesh(v, 26)
    want = sorted((c["euler_characteristic"], c["genus"], c["faces"]) for c in mesh.components())
    assert sorted((s["euler_characteristic"], s["genus"], s["faces"]) for s in out[1]["surfaces"]) == want
    assert out[1]["pinched_vertices"] == mesh.pinched == 1
    # 26: the two voxels of the vertex contact are one component, which the
    # mesh splits into two cubes (the pinch)
    assert len(want) == 5 and out[1]["betti"] == [3, 1, 1] and out[1]["euler_characteristic"] == euler_number(v, connectivity=3)
    bad = run("info", tmp_path / "v.npy", "--threads", "0")
    assert bad.returncode == 2 and "--threads" in bad.stderr


def test_open_meshes_by_default_strict_refuses_on_every_mesh_command(tmp_path, capsys):
    # plane_holes.obj is open (manifest: 27 boundary loops, 341 boundary
    # edges): read by default with one note line on stderr; --strict refuses
    # it on every command
    mesh = ROOT / "meshes" / "plane_holes.obj"
    r = info_json(capsys, mesh, "--resolution", "12")
    err = capsys.readouterr().err
    assert r["voxels"] > 0
    assert main(["info", str(mesh), "--resolution", "12"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "note" in err[0] and "341 boundary edges" in err[0] and "|w| > 1/2" in err[0]
    out = tmp_path / "o"
    out.mkdir()
    for cmd in (["info", str(mesh), "--resolution", "12"],
                ["surface", str(mesh), "--resolution", "12", "-o", str(out / "s.ply")],
                ["flow", str(mesh), "--resolution", "12", "--steps", "1"],
                ["voxelize", str(mesh), "--resolution", "12", "-o", str(out / "v.npz")],
                ["genus", str(mesh), "--resolution", "12"]):
        assert main(cmd + ["--strict"]) == 2, cmd
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "not watertight: 341 boundary edges" in err[0], (cmd, err)
    assert not any(out.iterdir())
    assert main(["voxelize", str(mesh), "--resolution", "12", "-o", str(tmp_path / "p.npz")]) == 0
    capsys.readouterr()
    assert info_json(capsys, tmp_path / "p.npz")["voxels"] == r["voxels"]
    np.save(tmp_path / "v.npy", np.ones((2, 2, 2), bool))
    assert main(["info", str(tmp_path / "v.npy"), "--strict"]) == 2
    assert "apply to meshes" in capsys.readouterr().err
    # the option that changed nothing is gone: argparse refuses it
    with pytest.raises(SystemExit) as exit:
        main(["info", str(tmp_path / "v.npy"), "--allow-open"])
    assert exit.value.code == 2


def test_memory_budget_is_most_of_what_the_kernel_says_is_available():
    from isoflow.scale.memory import default_budget

    if not Path("/proc/meminfo").exists():
        pytest.skip("no /proc/meminfo (not Linux)")
    fields = dict(line.split(":", 1) for line in open("/proc/meminfo"))
    total = int(fields["MemTotal"].split()[0]) * 1024
    assert 0 < default_budget() <= 0.9 * total


def test_info_on_a_small_volume_never_loads_numba(tmp_path):
    # importing numba and loading its kernels costs about half a second per
    # process: below MIN_VOXELS the command must answer without it (the
    # whole command's time is measured in benchmarks/run.py, not here)
    v = np.random.default_rng(5).random((30, 31, 29)) < 0.5
    np.save(tmp_path / "v.npy", v)
    code = ("import sys, json, io, contextlib; from isoflow.cli import main; out = io.StringIO()\n"
            "with contextlib.redirect_stdout(out): rc = main(['info', sys.argv[1], '--json'])\n"
            "r = json.loads(out.getvalue()); print(rc, 'numba' in sys.modules, len(r['surfaces']))")
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path / "v.npy")], capture_output=True, text=True)
    rc, loaded, surfaces = p.stdout.split()
    assert (rc, loaded) == ("0", "False"), p.stderr
    from isoflow import boundary_mesh

    assert int(surfaces) == len(boundary_mesh(v, 6).components()) > 1


def _imported(args, cwd=None):
    """The modules an ``isoflow`` command imports (``python -X importtime``),
    and its result."""
    p = subprocess.run([sys.executable, "-X", "importtime", "-m", "isoflow.cli", *map(str, args)],
                       capture_output=True, text=True, cwd=cwd)
    modules = {line.split("|")[-1].strip() for line in p.stderr.splitlines() if line.startswith("import time:")}
    return p, modules


@pytest.mark.parametrize("conn", [6, 26])
def test_info_on_a_small_npy_answers_without_numba(tmp_path, conn):
    # a volume below the compiled passes' threshold answers in the NumPy
    # passes without numba's half-second start; one above it loads numba;
    # one between the thresholds with and without the surfaces loads it
    # only for --no-surfaces. Every report equals the in-process one and
    # scikit-image's chi
    from conftest import compiled_side

    from isoflow.digital.analysis import analyze
    from isoflow.scale.compiled import have_numba, least_voxels

    rng = np.random.default_rng(conn)
    # more than a bit per voxel would make the threshold, fewer voxels
    small = rng.random((80, 77, 83)) < 0.3  # edge and vertex contacts everywhere
    big = np.zeros((compiled_side(),) * 3, bool)
    big[:80, :77, :83] = small
    mid = big[:141, :141, :141]
    least = least_voxels(surfaces=True)  # (info's default)
    assert least // 8 < small.size < least <= big.size
    assert least_voxels(surfaces=False) <= mid.size < least
    for name, vol, flags, numba_loaded in (("small", small, [], False), ("big", big, [], have_numba()),
                                           ("mid", mid, [], False), ("mid", mid, ["--no-surfaces"], have_numba())):
        np.save(tmp_path / f"{name}.npy", vol)
        p, modules = _imported(["info", tmp_path / f"{name}.npy", "--json", "--connectivity", conn, *flags])
        assert p.returncode == 0, p.stderr
        assert ("numba" in modules) == numba_loaded, name
        report = json.loads(p.stdout)
        assert report["euler_characteristic"] == euler_number(vol, connectivity=1 if conn == 6 else 3)
        want = analyze(vol, conn, surfaces=not flags)
        assert {k: report[k] for k in want} == json.loads(json.dumps(want.to_dict()))
        assert ("surfaces" in report) == (not flags)


def test_the_compile_note_is_said_once_and_logged_without_a_listener(monkeypatch, caplog):
    import logging

    from isoflow.scale import compiled

    said = []
    monkeypatch.setattr(compiled, "_compile_noted", False)
    monkeypatch.setattr(compiled, "on_first_compile", said.append)
    compiled.note_compile()
    compiled.note_compile()
    assert said == [compiled.COMPILE_NOTE]
    monkeypatch.setattr(compiled, "_compile_noted", False)
    monkeypatch.setattr(compiled, "on_first_compile", None)
    with caplog.at_level(logging.INFO, logger="isoflow"):
        compiled.note_compile()
        compiled.note_compile()
    assert [r.getMessage() for r in caplog.records] == [compiled.COMPILE_NOTE]


def test_method_chooses_the_passes_not_the_report():
    # method= picks the NumPy or the compiled passes explicitly; "auto"
    # decides by the input's size, and for a 3D census also takes the
    # compiled one at any size once it is loaded in the process (a large
    # volume analysed before: numba's start is paid; the fresh process's
    # choice is tested in tests/digital/test_closed_surfaces.py); the
    # report is the same every way, at both connectivities, with edge and
    # vertex contacts and empty volumes (a flow shrinks to nothing)
    from isoflow.digital import closed_surfaces
    from isoflow.digital.analysis import analyze
    from isoflow.scale.compiled import have_numba, least_voxels

    if not have_numba():
        pytest.skip("numba not installed")
    rng = np.random.default_rng(5)
    vols = [rng.random((9, 11, 7)) < 0.4, np.zeros((3, 3, 3), bool), np.ones((1, 1, 1), bool),
            np.zeros((0, 0, 0), bool), np.zeros((4, 0, 2), bool), rng.random((13, 17)) < 0.5]
    for v in vols:
        for c in ((6, 26) if v.ndim == 3 else (4, 8)):
            want = analyze(v, c, method="numpy")
            assert analyze(v, c, method="compiled") == want == analyze(v, c)
    big = np.zeros((least_voxels(surfaces=True) // 10_000 + 1, 100, 100), bool)
    assert closed_surfaces.use_census(big)
    analyze(big)
    assert closed_surfaces.census_loaded() and closed_surfaces.use_census(vols[0])  # loaded: at any size
    assert not closed_surfaces.use_census(vols[0], method="numpy")
    assert closed_surfaces.use_census(vols[0], method="compiled")
    assert not closed_surfaces.use_census(big, method="numpy")


def test_method_refuses_what_it_cannot_do():
    from isoflow import IsoflowError
    from isoflow.digital.analysis import analyze

    with pytest.raises(IsoflowError, match="method must be one of auto, numpy, compiled, got 'fast'"):
        analyze(np.ones((2, 2, 2), bool), method="fast")
    with pytest.raises(IsoflowError, match="method='compiled' takes 2D and 3D NumPy volumes"):
        analyze(np.ones((2, 2, 2, 2), bool), method="compiled")


def test_surfaces_do_not_apply_in_2d_and_4d(tmp_path):
    """A 2D report printed ``"surfaces": []`` and the library's Report held
    ``[]``, which reads as "no closed surface found": a ring has one boundary
    curve and no surface. Surfaces are 3D only: absent from the JSON and the
    mapping in 2D (as in 4D), and the text says they do not apply; a 3D
    empty object keeps its ``[]``."""
    from isoflow import analyze

    ring = np.ones((5, 5), bool)
    ring[2, 2] = False
    np.save(tmp_path / "ring.npy", ring)
    p = run("info", str(tmp_path / "ring.npy"), "--json")
    assert p.returncode == 0, p.stderr
    r = json.loads(p.stdout)
    assert r["betti"] == [1, 1] and "surfaces" not in r
    p = run("info", str(tmp_path / "ring.npy"))
    assert "closed surfaces        not applicable in 2D (the boundary is closed curves)" in p.stdout
    report = analyze(ring)
    # not counted in 2D: None, as surfaces, not an empty list (a boundary of no closed surface)
    assert report.surfaces is None and "surfaces" not in report and report.genus is None
    np.save(tmp_path / "h.npy", np.ones((2, 2, 2, 2), bool))
    p = run("info", str(tmp_path / "h.npy"))
    assert "closed surfaces        not applicable in 4D (the boundary is a 3-manifold)" in p.stdout
    assert "surfaces" not in json.loads(run("info", str(tmp_path / "h.npy"), "--json").stdout)
    assert analyze(np.zeros((3, 3, 3), bool)).surfaces == []


def test_the_flow_s_summary_says_topology_control_is_guard_s(tmp_path, capsys):
    # the command list said "the digital curvature flow (section 5) with topology control", which
    # only --guard gives: a plain run changes the Betti numbers, as scipy counts them
    from scipy import ndimage

    two = np.zeros((12, 12, 12), bool)
    two[1:4, 1:4, 1:4] = two[6:10, 6:10, 6:10] = True  # a 3^3 and a 4^3 box
    np.save(tmp_path / "two.npy", two)
    assert main(["flow", str(tmp_path / "two.npy"), "--json"]) == 0
    steps = json.loads(capsys.readouterr().out)["steps"]
    assert ndimage.label(two)[1] == steps[0]["betti"][0] == 2 and steps[3]["betti"][0] == 1  # the small box went first
    assert main([]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.split()[:1] == ["flow"])
    assert "--guard" in line and not line.endswith("with topology control"), line


def test_a_slice_saved_as_3d_gets_a_note_with_the_line_that_saves_it_2d(tmp_path, capsys):
    """A segmentation of one slice saved as (X, Y, 1) is read as a plate one
    voxel thick, as before, with a note that gives the line saving the 2D
    image; that image analyses as scikit-image counts the slice."""
    import shlex

    import nibabel as nib

    img = np.zeros((9, 8), np.uint8)
    img[1:7, 2:7] = 1
    img[3:5, 4] = 0  # a hole
    img[8, 0] = 1  # and a second piece: b = (2, 1)
    nib.save(nib.Nifti1Image(img[:, :, None], np.diag([0.5, 0.7, 2.0, 1])), tmp_path / "slice.nii.gz")
    np.save(tmp_path / "plate.npy", img[None, :, :].astype(bool))  # one voxel along x
    np.save(tmp_path / "thick.npy", np.repeat(img[:, :, None], 3, axis=2).astype(bool))
    slice_path = str(tmp_path / "slice.nii.gz")

    assert main(["info", slice_path, "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["dimension"] == 3  # read as it was: a 3D plate
    [note] = err.splitlines()
    assert note.startswith(f"isoflow info: note: {slice_path}: shape 9x8x1, one voxel along z: read as a 3D plate")
    code = shlex.split(note.split("give it: ", 1)[1])
    assert code[:2] == ["python", "-c"]
    p = subprocess.run([sys.executable, "-c", code[2]], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    r = info_json(capsys, tmp_path / "slice_2d.npz")
    assert r["dimension"] == 2 and r["betti"] == [2, 1]
    assert r["euler_characteristic"] == euler_number(img, connectivity=1)

    assert main(["flow", slice_path, "--json"]) == 0
    assert "isoflow flow: note: " in capsys.readouterr().err
    assert main(["info", str(tmp_path / "plate.npy")]) == 0
    assert "shape 1x9x8, one voxel along x" in capsys.readouterr().err
    for quiet in (["info", slice_path, "--quiet"], ["flow", slice_path, "--quiet"], ["info", str(tmp_path / "thick.npy")]):
        assert main(quiet) == 0
        assert capsys.readouterr().err == "", quiet


def test_the_line_that_saves_a_slice_2d_keeps_its_length_unit(tmp_path, capsys):
    """The note's line for a mask keeps the file's length unit, as the one
    for a label image does: the 2D image it saves is in the millimetres
    nibabel reads from the NIfTI header, not "the file says no unit"."""
    import shlex

    import nibabel as nib

    img = nib.Nifti1Image(np.pad(np.ones((3, 4, 1), np.uint8), ((1, 1), (1, 1), (0, 0))), np.diag([0.5, 0.7, 2.0, 1]))
    img.header.set_xyzt_units("mm")
    nib.save(img, tmp_path / "slice.nii.gz")
    unit = nib.load(tmp_path / "slice.nii.gz").header.get_xyzt_units()[0]
    assert main(["info", str(tmp_path / "slice.nii.gz"), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["unit"] == unit == "mm"
    code = shlex.split(err.split("give it: ", 1)[1])[2]
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    r = info_json(capsys, tmp_path / "slice_2d.npz")
    assert r["dimension"] == 2 and r["unit"] == unit and r["pitch"] == pytest.approx([0.5, 0.7])


def test_a_4d_volume_one_voxel_thick_says_how_to_read_it_as_3d(tmp_path, capsys):
    """A 3D mask saved with a channel axis (ilastik's HDF5 (z, y, x, 1)) is
    read as stored, 4D, where b1, b2 and the surfaces are not counted; the
    note gives the line that saves the 3D volume, whose numbers are the
    mask's (scikit-image)."""
    import shlex

    h5py = pytest.importorskip("h5py")
    measure = pytest.importorskip("skimage.measure")
    vol = np.zeros((7, 6, 5), np.uint8)
    vol[1:6, 1:5, 1:4] = 1
    vol[3, 2:4, 1:4] = 0  # a tunnel through the block
    vol[2:5, 2:4, 2] = 0
    with h5py.File(tmp_path / "seg.h5", "w") as f:
        f["exported_data"] = vol[..., None]
    seg = str(tmp_path / "seg.h5")
    assert main(["info", seg, "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["dimension"] == 4
    [note] = err.splitlines()
    assert note.startswith(f"isoflow info: note: {seg}: shape 7x6x5x1, one voxel along axis 3: read as a 4D volume")
    code = shlex.split(note.split("give it: ", 1)[1])
    p = subprocess.run([sys.executable, "-c", code[2]], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    r = info_json(capsys, tmp_path / "volume_3d.npz")
    chi = measure.euler_number(np.pad(vol, 1), connectivity=1)
    cavities = measure.label(np.pad(vol == 0, 1, constant_values=True), connectivity=3).max() - 1
    assert r["shape"] == [7, 6, 5] and r["euler_characteristic"] == chi
    assert r["betti"] == [1, 1 + cavities - chi, cavities]
    assert main(["info", seg, "--quiet"]) == 0
    assert capsys.readouterr().err == ""
    assert main(["flow", seg]) == 2  # refused in one line, with no note before it
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.parametrize("command", ["info", "flow"])
@pytest.mark.parametrize("shape, connectivity, words", [
    ((4, 5, 6), 8, "connectivity 8 is not valid in 3D (use 6 or 26)"),
    ((4, 5), 26, "connectivity 26 is not valid in 2D (use 4 or 8)"),
    ((3, 4, 5, 2), 6, "connectivity 6 is not valid in 4D (use 8 or 80)"),
])
def test_a_connectivity_that_does_not_fit_the_file_names_the_file(tmp_path, capsys, command, shape, connectivity, words):
    """The dimension is the file's: the line names the file, as info
    --labels's does (flow refuses a 4D file for its dimension first)."""
    np.save(tmp_path / "v.npy", np.ones(shape, bool))
    assert main([command, str(tmp_path / "v.npy"), "--connectivity", str(connectivity)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    expected = "is 4D" if command == "flow" and len(shape) == 4 else words
    assert lines[0].startswith(f"isoflow {command}: error: {tmp_path / 'v.npy'}: ") and expected in lines[0], lines


def test_flow_refuses_a_3d_connectivity_for_a_2d_object(tmp_path, capsys):
    """``flow --connectivity 6`` of a 2D image ran at 4 (and 26 at 8) with
    exit status 0, where ``info`` refuses it and the help says 4 or 8 in
    2D: one line, exit 2, before any work. Unasked, 2D flows at 4."""
    square = np.zeros((6, 6), bool)
    square[1:5, 1:5] = True
    np.save(tmp_path / "square.npy", square)
    for conn in ("6", "26"):
        capsys.readouterr()
        assert main(["flow", str(tmp_path / "square.npy"), "--connectivity", conn, "--out", str(tmp_path / "run")]) == 2
        assert f"connectivity {conn} is not valid in 2D (use 4 or 8)" in capsys.readouterr().err
        assert not (tmp_path / "run").exists()
    capsys.readouterr()
    assert main(["flow", str(tmp_path / "square.npy"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["connectivity"] == 4
    assert main(["flow", str(tmp_path / "square.npy"), "--connectivity", "8", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["connectivity"] == 8
    said = " ".join((ROOT / "docs" / "flow.md").read_text().split())
    assert "`isoflow flow --connectivity` takes 4 or 8 for a 2D image, as `info` does, and refuses 6 and 26" in said


def test_info_takes_the_compiled_pass_once_numba_is_loaded_for_the_file(tmp_path, capsys, monkeypatch):
    """info loads numba while it reads a file that may hold a large volume
    (by its size: a bit per voxel at the least), and docs/large-volumes.md
    says the compiled pass then takes the volume whatever its size. An
    uncompressed NIfTI of 0.5 M voxels (a byte each) loaded numba and then
    went the NumPy way, below the size "auto" weighs numba's start against:
    the command paid that start for nothing."""
    nib = pytest.importorskip("nibabel")
    from isoflow.digital import analysis
    from isoflow.scale.compiled import have_numba, least_voxels

    if not have_numba():
        pytest.skip("numba not installed: no warm-up")
    side = int((least_voxels(surfaces=True) // 8) ** (1 / 3)) + 1  # the file is large enough, the volume is not
    assert side**3 < least_voxels(surfaces=True)
    v = np.zeros((side,) * 3, np.uint8)
    v[2:-2, 2:-2, 2:-2] = np.random.default_rng(5).random((side - 4,) * 3) < 0.3
    nib.save(nib.Nifti1Image(v, np.eye(4)), tmp_path / "scan.nii")
    swept = []
    census = analysis.compiled_census
    monkeypatch.setattr(analysis, "compiled_census", lambda *a, **k: swept.append(1) or census(*a, **k))
    r = info_json(capsys, tmp_path / "scan.nii")
    assert swept  # the compiled pass, numba being loaded
    assert r["voxels"] == int(v.sum()) and r["euler_characteristic"] == euler_number(v, 1)


@pytest.mark.parametrize("shape", [(9, 8), (6, 5, 7), (4, 4, 4, 3)])
def test_info_json_classes_are_what_docs_cli_md_says(tmp_path, shape):
    """docs/cli.md's `classes`: in 2D and 3D every class, 0 included; in 4D
    only the classes that occur, each keyed by the least configuration of
    its orbit under the cube's symmetries; in every dimension the counts
    add up to the sum of `n`, and with `non_well_composed` to the vertices
    whose cells are neither all in the object nor all out (counted here
    with numpy)."""
    import itertools

    rng = np.random.default_rng(7)
    volume = rng.random(shape) < 0.5
    np.save(tmp_path / "v.npy", volume)
    p = subprocess.run([sys.executable, "-m", "isoflow", "info", str(tmp_path / "v.npy"), "--json"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    report = json.loads(p.stdout)
    d, classes = volume.ndim, report["classes"]
    padded = np.pad(volume, 1).astype(int)
    window = [s - 1 for s in padded.shape]
    cells = sum(padded[tuple(slice(o, o + s) for o, s in zip(offset, window))]
                for offset in itertools.product((0, 1), repeat=d))
    boundary = int(np.count_nonzero((cells > 0) & (cells < 2 ** d)))
    assert sum(classes.values()) == sum(report["n"])
    assert sum(classes.values()) + report["non_well_composed"] == boundary
    if d < 4:
        assert len(classes) == len(report["n"]) and list(classes.values()) == report["n"]
        return
    assert 0 not in classes.values() and list(classes.values()) == [k for k in report["n"] if k]

    def image(config, axes, flips):
        # cell d (bit d0 + 2 d1 + 4 d2 + 8 d3) goes to the cell of the permuted, flipped axes
        out = 0
        for bit in range(16):
            if config >> bit & 1:
                cell = [bit >> a & 1 for a in range(4)]
                moved = [cell[axes[a]] ^ flips[a] for a in range(4)]
                out |= 1 << sum(c << a for a, c in enumerate(moved))
        return out

    group = [(axes, flips) for axes in itertools.permutations(range(4))
             for flips in itertools.product((0, 1), repeat=4)]
    keys = [int(k) for k in classes]
    assert keys == sorted(keys)
    for key in keys:
        assert key == min(image(key, axes, flips) for axes, flips in group), key


@pytest.mark.parametrize("extra", [[], ["--labels"], ["--json"]])
def test_info_force_without_csv_is_refused_not_ignored(tmp_path, capsys, extra):
    """``info x --force`` printed the report as if --force were not there:
    it overwrites an existing --csv file and nothing else, so the --csv
    it was meant for was left out. Refused in one line, as --points-are
    with a volume is; with --csv it replaces the file (the csv module
    reads the new table back)."""
    import csv

    from test_input_errors import fails

    v = torus(6, 2)
    np.save(tmp_path / "t.npy", v)
    fails(capsys, "info", tmp_path / "t.npy", *extra, "--force", words=("t.npy", "--force", "--csv"))
    (tmp_path / "t.csv").write_text("old\n")
    assert main(["info", str(tmp_path / "t.npy"), "--labels", "--csv", str(tmp_path / "t.csv"), "--force"]) == 0
    with open(tmp_path / "t.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [(int(r["label"]), int(r["voxels"]), int(r["euler_characteristic"])) for r in rows] == [
        (1, int(v.sum()), euler_number(v, 1))]


@pytest.mark.parametrize("argv", [["info"], ["info", "--labels"], ["flow", "--steps", "1"]])
def test_an_input_name_the_file_system_does_not_decode_is_text_in_json(tmp_path, capsys, argv):
    """A name with a byte that is not UTF-8 (Latin-1 ``café`` as
    ``caf\\xe9``) was written ``"caf\\udce9.npy"``, a lone surrogate that
    no string holds: Perl's JSON::PP refused the line, jq read U+FFFD.
    Its ``input`` is the byte as Python's ``backslashreplace`` writes it,
    as the text report's first line says it."""
    name = os.fsdecode(b"caf\xe9.npy")
    try:
        np.save(tmp_path / name, np.ones((2, 2, 2), bool))
    except (OSError, UnicodeEncodeError):
        pytest.skip("the file system takes only names that decode")
    path = str(tmp_path / name)
    assert main([argv[0], path, *argv[1:], "--json"]) == 0
    given = json.loads(capsys.readouterr().out)["input"]
    assert given.encode("utf-8") == os.fsencode(path).decode("utf-8", "backslashreplace").encode("utf-8")
    assert given.endswith("caf\\xe9.npy")
    if argv == ["info"]:
        assert main(["info", path]) == 0
        assert capsys.readouterr().out.startswith(f"{given}: 3D, shape 2x2x2, 8 voxels")


@pytest.mark.parametrize("shape", ["empty", "ball", "shell", "two balls"])
def test_info_text_says_how_many_closed_surfaces_even_none(tmp_path, capsys, shape):
    """An empty volume's report had no "closed surfaces" line at all, as
    one run with --no-surfaces, while --json said ``"surfaces": []``.
    The count is the boundary's components: for these well-composed
    objects the components of the object and of its bounded complement
    (scipy.ndimage.label)."""
    from scipy import ndimage

    v = np.zeros((12, 12, 12), bool)
    if shape != "empty":
        v[1:7, 1:7, 1:7] = True
    if shape == "shell":
        v[3:5, 3:5, 3:5] = False
    if shape == "two balls":
        v[8:11, 8:11, 8:11] = True
    np.save(tmp_path / "v.npy", v)
    expected = ndimage.label(v)[1] + ndimage.label(np.pad(~v, 1, constant_values=True),
                                                   np.ones((3, 3, 3)))[1] - 1
    assert main(["info", str(tmp_path / "v.npy")]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("  closed surfaces ")]
    assert lines == [f"  closed surfaces        {expected}"]
    assert main(["info", str(tmp_path / "v.npy"), "--no-surfaces"]) == 0
    assert "closed surfaces" not in capsys.readouterr().out


def test_an_error_line_writes_a_name_s_undecodable_byte_as_the_reports_do(tmp_path, capsys):
    """The reports write a name's byte that is not UTF-8 as ``\\xe9``; an
    error line about the same file wrote ``\\udce9``, Python's lone
    surrogate for it, so one file had two names. The error line's name is
    the reports' (Python's ``backslashreplace`` of the file's bytes)."""
    name = os.fsdecode(b"caf\xe9.npy")
    try:
        np.save(tmp_path / name, np.arange(8).reshape(2, 2, 2))  # not binary: refused
    except (OSError, UnicodeEncodeError):
        pytest.skip("the file system takes only names that decode")
    assert main(["info", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert os.fsencode(str(tmp_path / name)).decode("utf-8", "backslashreplace") in err
    assert "\\udce9" not in err and "\udce9" not in err


@pytest.mark.parametrize("flag", ["--force", "--no-check"])
def test_flow_options_for_the_out_files_without_out_are_refused_not_ignored(tmp_path, capsys, flag):
    """``flow x --force`` and ``flow x --no-check`` ran as if the option
    were not there: both are about the files of --out, so the --out they
    were meant for was left out. One line naming the option and --out, as
    --volumes without --out; with --out both are taken (the step surfaces
    are written and, without --no-check, read back by trimesh)."""
    from test_input_errors import fails

    np.save(tmp_path / "b.npy", np.ones((3, 4, 5), bool))
    fails(capsys, "flow", tmp_path / "b.npy", "--steps", "1", flag, words=(flag, "--out"))
    out = tmp_path / "run"
    assert main(["flow", str(tmp_path / "b.npy"), "--steps", "1", flag, "--out", str(out)]) == 0
    surface = trimesh.load(out / "step_000.ply")
    assert surface.is_watertight and surface.euler_number == 2  # a box's surface: one sphere


def test_info_json_of_voxels_of_1e150_is_json_and_prints_no_numpy_warning(tmp_path, capfd):
    """The single object's volume of voxels of 1e150 is past float64
    (27 x 1e450): ``info --json`` wrote ``Infinity``, which no JSON parser
    in strict mode takes, after NumPy's "overflow encountered in reduce"
    on the terminal. It is null; the surface area (54 x 1e300) and the box
    (3e150) are numbers float64 holds, as Python computes them."""
    import warnings

    from isoflow import DigitalObject, write_volume

    write_volume(DigitalObject(np.ones((3, 3, 3), bool), pitch=1e150), tmp_path / "huge.npz")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        assert main(["info", str(tmp_path / "huge.npz"), "--json"]) == 0
    out, err = capfd.readouterr()
    assert err == ""
    report = json.loads(out, parse_constant=lambda name: pytest.fail(f"{name} is no JSON"))
    with np.errstate(over="ignore"):
        assert np.isinf(np.float64(27) * np.float64(1e150) ** 3)  # beyond float64 ...
    assert report["volume"] is None  # ... so null
    assert report["surface_area"] == 54 * (1e150 * 1e150)
    assert report["bbox"] == [0.0, 0.0, 0.0] + [3 * 1e150] * 3


def test_info_and_surface_say_the_same_volume_beyond_float64(tmp_path, capsys):
    """Voxels of 1e200: info printed "volume inf, surface area inf" where
    surface's read-back says "volume 2.7e+601". info prints the figure
    (27 voxels of 1e200 cubed, as exact fractions give it) and words for
    an area beyond float64, never a bare inf; trimesh's read-back, which
    surface compares, says the same figure."""
    from decimal import Decimal
    from fractions import Fraction

    from isoflow import DigitalObject, write_volume

    write_volume(DigitalObject(np.ones((3, 3, 3), bool), pitch=1e200), tmp_path / "huge.npz")
    exact = 27 * Fraction(1e200) ** 3
    figure = f"{Decimal(exact.numerator // exact.denominator):.5e}"  # an int, beyond float: Decimal formats it
    mantissa, exponent = figure.split("e")
    figure = f"{mantissa.rstrip('0').rstrip('.')}e+{int(exponent)}"
    assert figure == "2.7e+601"
    assert main(["info", str(tmp_path / "huge.npz")]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.strip().startswith("volume"))
    assert line.split() == ["volume", figure, "(beyond", "float64),", "surface", "area", "beyond", "float64's", "range"]
    assert "inf" not in line
    assert main(["surface", str(tmp_path / "huge.npz"), "-o", str(tmp_path / "s.ply")]) == 0
    assert f"volume {figure} (beyond float64" in capsys.readouterr().out


def test_quiet_before_the_command_means_what_it_means_after_it(tmp_path, capsys):
    """`isoflow -q info x.npy` was refused as an unrecognized argument:
    -q/--quiet, which every command takes, is taken before the command's
    name too, with the same effect (the plate's note dropped, the same
    report), and `isoflow --help` lists it."""
    np.save(tmp_path / "plate.npy", np.ones((1, 9, 8), bool))  # one voxel along x: a note on stderr
    plate = str(tmp_path / "plate.npy")
    assert main(["info", plate, "--json"]) == 0
    loud = capsys.readouterr()
    assert "one voxel along x" in loud.err  # what --quiet drops
    for argv in (["info", plate, "--json", "-q"], ["-q", "info", plate, "--json"], ["--quiet", "info", plate, "--json"]):
        assert main(argv) == 0, argv
        out, err = capsys.readouterr()
        assert (out, err) == (loud.out, ""), argv
    p = run("--help")
    assert p.returncode == 0 and "-q, --quiet" in p.stdout, p.stdout


def test_quiet_keeps_the_reason_a_result_is_empty(tmp_path, capsys):
    """-q silences progress and notes, not the reason a result came out
    empty for an input that is not: a lone triangle (bounding no volume, as
    trimesh says) voxelises to no voxel, and -q dropped the note saying why from
    voxelize (to a file, a store, a label image), info and surface; a point
    list in which no unit cube has its 8 corners likewise from info. The
    note of a result that is not empty is still dropped."""
    tri = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    assert not tri.is_watertight and not tri.is_volume
    mesh = str(tmp_path / "tri.obj")
    tri.export(mesh)

    def said(*argv, status=0):
        assert main(["-q", *map(str, argv)]) == status, argv
        out, err = capsys.readouterr()
        return err

    for out in ("q.npz", "q.zarr"):
        err = said("voxelize", mesh, "--resolution", 8, "-o", tmp_path / out)
        assert "note:" in err and "leaves no voxel in" in err, out
    assert int(np.load(tmp_path / "q.npz")["volume"].sum()) == 0  # the file as written: empty indeed
    err = said("voxelize", mesh, MESHES / "cube_no_bottom.obj", "--resolution", 8, "-o", tmp_path / "l.npz")
    assert "leaves no voxel in" in err and f"label 1 ({mesh}) got no voxel" in err
    assert "leaves no voxel in" in said("info", mesh, "--resolution", 8)
    assert "leaves no voxel in" in said("surface", mesh, "--resolution", 8, "-o", tmp_path / "t.ply", status=2)
    (tmp_path / "p.txt").write_text("0 0 0\n1 0 0\n5 5 5\n")  # 3 points: no cube has 8 corners among them
    assert "no unit cube has all 8 of its corners" in said("info", tmp_path / "p.txt")
    assert main(["voxelize", str(MESHES / "cube_no_bottom.obj"), "--resolution", "8", "-o", str(tmp_path / "b.npz")]) == 0
    assert "note:" in capsys.readouterr().err  # an open box: a note, and voxels
    assert said("voxelize", MESHES / "cube_no_bottom.obj", "--resolution", 8, "-o", tmp_path / "c.npz") == ""
    assert int(np.load(tmp_path / "c.npz")["volume"].sum()) > 0


@pytest.mark.parametrize("odd", ["\t", "\x1b[31m"])
def test_a_file_name_with_a_control_character_is_printed_escaped_by_every_command(tmp_path, capsys, odd):
    """surface, flow, voxelize and genus printed file names raw on stdout,
    and the error line escaped only line breaks: a tab or an escape
    sequence in a name reached the terminal, which acts on it. Each is
    written as Python escapes it (as info writes names), so that every
    line is the plain name's line with the name escaped; --json keeps
    the name as it is."""
    escaped = odd.encode("unicode_escape").decode("ascii")
    cube = np.zeros((6, 6, 6), np.uint8)
    cube[1:5, 1:5, 1:5] = 1

    def lines(*argv):
        assert main([*map(str, argv)]) == 0
        out, err = capsys.readouterr()
        return out.splitlines(), err

    said = {}
    for tag in ("plain", odd):
        np.save(tmp_path / f"a{tag}.npy", cube)
        said[tag] = [
            lines("surface", tmp_path / f"a{tag}.npy", "-o", tmp_path / f"s{tag}.ply", "--force"),
            lines("flow", tmp_path / f"a{tag}.npy", "--steps", "1", "--out", tmp_path / f"f{tag}", "--force"),
            lines("voxelize", tmp_path / f"s{tag}.ply", "-o", tmp_path / f"v{tag}.npz", "--pitch", "1", "--force"),
            lines("genus", tmp_path / f"s{tag}.ply", "--resolution", "8", "--no-step"),
        ]
    for (plain, _), (odd_lines, odd_err) in zip(said["plain"], said[odd]):
        assert odd_lines == [line.replace("plain", escaped) for line in plain]
        assert "\x1b" not in "".join(odd_lines) + odd_err and "\t" not in "".join(odd_lines) + odd_err
    assert main(["flow", str(tmp_path / f"a{odd}.npy"), "--steps", "1", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["input"] == str(tmp_path / f"a{odd}.npy")  # JSON: the name itself
    assert main(["info", str(tmp_path / f"gone{odd}.npy")]) == 2
    assert capsys.readouterr().err == f"isoflow info: error: {tmp_path}/gone{escaped}.npy: no such file or directory\n"


@pytest.mark.parametrize("corner", [(10**12, 0, 0), (10**12, -10**12)])
def test_info_of_a_far_point_list_prints_its_box_to_the_voxel(tmp_path, corner):
    """A point list has no voxel size to print its coordinates against, and
    the box of a unit cube at x = 1e12 came out as ``[1e+12, 0, 0] to
    [1e+12, 1, 1]``: both sides of the box as one number, the centroid
    half a voxel off. Its coordinates are lattice units, a voxel 1 wide:
    the box is the points' own least and greatest corner, as written."""
    corners = np.array(list(itertools.product((0, 1), repeat=len(corner)))) + corner
    (tmp_path / "far.txt").write_text("".join(" ".join(map(str, p)) + "\n" for p in corners))
    r = run("info", tmp_path / "far.txt")
    assert r.returncode == 0, r.stderr
    box = next(line for line in r.stdout.splitlines() if "bounding box" in line)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    centre = (lo + hi) / 2
    assert f"[{', '.join(map(str, lo))}] to [{', '.join(map(str, hi))}]" in box, box
    assert f"centroid [{', '.join(f'{c:.1f}' for c in centre)}]" in box, box


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-be"])
def test_info_reads_a_utf16_point_list(tmp_path, encoding):
    """Windows PowerShell's ``>`` and Notepad's "Unicode" save text as
    UTF-16 with a byte-order mark; such a point list was refused as
    "binary data, not a text point list", and the line listed volume
    suffixes. It is text: read as UTF-8 text is, header and line ends as
    written. The 27 points of a 3x3x3 grid are the corners of 8 unit
    cubes, the box [0, 2]^3."""
    text = "x,y,z\r\n" + "".join(f"{x},{y},{z}\r\n" for x, y, z in itertools.product(range(3), repeat=3))
    # "utf-16-be" writes no mark of its own: one is added, as Windows' big-endian "Unicode" has
    data = ("\ufeff" + text).encode(encoding) if encoding.endswith("be") else text.encode(encoding)
    (tmp_path / "points.csv").write_bytes(data)
    r = run("info", tmp_path / "points.csv", "--json")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert report["voxels"] == 8 and report["bbox"] == [0, 0, 0, 2, 2, 2]
    assert report["euler_characteristic"] == 1


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be"])
def test_info_reads_a_utf16_point_list_without_a_byte_order_mark(tmp_path, encoding):
    """Some Windows tools save UTF-16 with no byte-order mark
    (``open(p, "w", encoding="utf-16-le")``); such a point list was
    refused as "binary data, not a text point list". Every other byte is
    NUL beside ASCII digits, blanks and line ends: it is that text, read as
    its UTF-8 is. Each point a voxel (``--points-are voxels``, the cube
    [p, p + 1]): the count, box and centroid are numpy's of ``np.loadtxt``
    of the same text in UTF-8."""
    rng = np.random.default_rng(7)
    points = np.unique(rng.integers(-20, 40, size=(60, 3)), axis=0)
    text = "# x y z\r\n" + "".join(f"{x} {y}\t{z}\r\n" for x, y, z in points)
    with open(tmp_path / "points.txt", "w", encoding=encoding, newline="") as fh:
        fh.write(text)
    assert b"\0" in (tmp_path / "points.txt").read_bytes()[:2] and not text.startswith("\ufeff")
    (tmp_path / "utf8.txt").write_text(text, encoding="utf-8", newline="")
    want = np.loadtxt(tmp_path / "utf8.txt", comments="#", dtype=np.int64, encoding="utf-8")
    r = run("info", tmp_path / "points.txt", "--points-are", "voxels", "--json")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert report["voxels"] == len(np.unique(want, axis=0))
    assert report["bbox"] == [*want.min(axis=0).tolist(), *(want.max(axis=0) + 1).tolist()]
    assert np.allclose(report["centroid"], np.unique(want, axis=0).mean(axis=0) + 0.5)


@pytest.mark.parametrize("data", [np.arange(1, 400, dtype="<u2").tobytes(),  # 16-bit data: high bytes not all NUL
                                  np.array([0, 1, 1, 0, 10, 13] * 20, dtype="<u2").tobytes(),  # no ASCII digit
                                  "# \u00b5m\n1 2 3\n".encode("utf-16-le")])  # not ASCII: not unambiguous
def test_nul_bytes_that_are_not_ascii_utf16_stay_binary(tmp_path, data):
    """Reading UTF-16 without its mark takes only text that cannot be
    anything else: 16-bit data, or UTF-16 beyond ASCII, is refused as the
    binary it may be, in one line, exit 2."""
    (tmp_path / "p.txt").write_bytes(data)
    r = run("info", tmp_path / "p.txt")
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
    assert "binary data, not a text point list" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.parametrize("index", ["", "index"])
def test_info_reads_the_csv_pandas_writes_of_an_array_of_points(tmp_path, index):
    """``pd.DataFrame(points).to_csv("p.csv")`` names the columns 0, 1, 2
    and writes the index first: a header ``,0,1,2`` (``index,0,1,2`` after
    ``reset_index``). Its numbered names kept it from being read as a
    header, and the file was refused at line 1 ("empty coordinate"). A
    line that opens with an index's name is no point: it is skipped, and
    the index column with it. The 8 corners of the unit cube at (10, 10,
    10) are one voxel, the box [10, 11]^3."""
    corners = [(10 + x, 10 + y, 10 + z) for x, y, z in itertools.product((0, 1), repeat=3)]
    text = f"{index},0,1,2\n" + "".join(f"{i},{x},{y},{z}\n" for i, (x, y, z) in enumerate(corners))
    (tmp_path / "p.csv").write_text(text)
    r = run("info", tmp_path / "p.csv", "--json")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert report["voxels"] == 1 and report["bbox"] == [10, 10, 10, 11, 11, 11]


def test_a_2d_label_image_names_the_pixel_that_holds_no_label(tmp_path):
    """A 2D image is pixels everywhere else in isoflow's lines ("1 pixel
    holds values other than 0 and 1"), but a value that is no label was
    named at "voxel (3, 4)". The pixel placed is named, as a pixel, by
    ``info --labels`` and by ``write_labels``."""
    image = np.zeros((6, 7))
    image[3, 4] = 0.5
    np.save(tmp_path / "f.npy", image)
    r = run("info", tmp_path / "f.npy", "--labels")
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "pixel (3, 4) holds 0.5" in r.stderr and "voxel" not in r.stderr, r.stderr
    code = "import isoflow, numpy as np; isoflow.write_labels(np.array([[0, 0], [0, -3]]), 'w.npz')"
    w = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert w.returncode != 0 and "holds -3 at pixel (1, 1)" in w.stderr, w.stderr
    assert not (tmp_path / "w.npz").exists()
