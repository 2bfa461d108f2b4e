"""The cap's tree and its bounds, soups and meshes with many boundaries,
and work that ends at once when a signal comes.

References from outside the code under test: libigl's exact
``igl.winding_number`` (every voxel whose |w| is not within 1e-8 of 1/2,
so centres near the 1/2 level set count too), scipy's adaptive quadrature
for the integrals over edges, and the exit statuses of the README (128 +
the signal's number) on a real process.
"""

from __future__ import annotations

import math
import shutil
import signal
import subprocess
import sys
import time
from concurrent.futures import wait
from pathlib import Path

import numpy as np
import pytest

from isoflow.cli import main
from isoflow.mesh.captree import MAX_NEAR, CapTree, edge_terms, evaluate, far_field, near_sum
from isoflow.mesh.load import mesh_defects
from isoflow.mesh.outputs import TEMP_MARK
from isoflow.mesh.voxelize import Solid, voxelize
from isoflow.mesh.winding import TIE_STEP, close_mesh
from isoflow.scale.cancel import STOP, Stopped, clear_stop, request_stop, run_pieces

igl = pytest.importorskip("igl")
ROOT = Path(__file__).resolve().parents[2]


def soup(rng, n, scale=1.0):
    v = rng.random((3 * n, 3)) * scale
    return v, np.arange(3 * n).reshape(n, 3)


def tet_quads(n, seed=0):
    """benchmarks/generated.py's tetrahedra written as quads (libigl's
    cube_40k.obj in kind) on an n^3 grid: boundary and non-manifold edges
    run everywhere."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("generated", ROOT / "benchmarks" / "generated.py")
    generated = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generated)
    return generated.tet_quads(n, seed)


def assert_exact(v, f, vol, origin, pitch):
    """Every voxel equals libigl's |w| > 1/2 on the faces as the voxeliser
    reads them (oriented where trimesh could), except where |w| is within
    1e-8 of 1/2; a centre on the mesh is compared at the tie rule's point.
    Returns the margins ||w| - 1/2| of the voxels compared and how many
    centres lay on the mesh."""
    faces = Solid(v, f).faces
    c = origin + (np.argwhere(np.ones(vol.shape, bool)) + 0.5) * pitch
    on = igl.point_mesh_squared_distance(c, v, faces)[0] <= (1e-6 * pitch) ** 2
    c[on] += TIE_STEP * pitch
    w = igl.winding_number(np.asarray(v, np.float64), np.asarray(faces, np.int64), c)
    margin = np.abs(np.abs(w) - 0.5)
    sure = margin > 1e-8
    got = vol.reshape(-1)
    bad = sure & (got != (np.abs(w) > 0.5))
    assert not bad.any(), (int(bad.sum()), w[bad][:5], got[bad][:5])
    return margin[sure], int(on.sum())


# ---------------------------------------------------------------------------
# the bounds, one by one
# ---------------------------------------------------------------------------

def test_far_field_remainder_bound_holds(rng):
    """Barill et al.'s order-1 expansion of a cluster's winding number is
    within the proven remainder of libigl's exact value, and the bound is
    not vacuous (it shrinks with x = rho / R as x^2)."""
    for _ in range(20):
        centre = rng.normal(size=3)
        T = centre + rng.normal(scale=0.3, size=(int(rng.integers(1, 12)), 3, 3))
        tree = CapTree(T, np.zeros((0, 2, 3)), np.zeros(0, np.int64))
        c, rho = tree.centre[0], tree.rho[0]
        v, f = T.reshape(-1, 3), np.arange(3 * len(T)).reshape(-1, 3)
        for x in (0.9, 0.5, 0.2, 0.05):
            d = rng.normal(size=3)
            p = c + d / np.linalg.norm(d) * rho / x
            val, bound = far_field(tree.centre, tree.A, tree.Mo, tree.S, tree.rho, 0, *p)
            exact = 4 * math.pi * igl.winding_number(v, f, p[None])[0]
            assert abs(exact - val) <= bound, (x, exact, val, bound)
        assert bound < 0.01 * tree.S[0] / np.sum((p - c) ** 2)


def test_edge_integrals_match_quadrature(rng):
    """The Biot-Savart integral of an edge and the integral of |x|^-3 along
    it (closed forms) against scipy's quadrature, with edges far along
    their own line, where the textbook formula cancels."""
    from scipy.integrate import quad

    cases = [rng.normal(size=(2, 3)) for _ in range(8)]
    cases += [np.array([[5.0, 1e-7, 0.0], [7.0, 1e-7, 0.0]]), np.array([[-7.0, 0.0, 3e-6], [-5.0, 0.0, 3e-6]])]
    for a, b in cases:
        e = b - a
        length = np.linalg.norm(e)
        integral = quad(lambda t, a=a, e=e, length=length: length / np.linalg.norm(a + t * e) ** 3, 0, 1,
                        epsabs=0, epsrel=1e-12)[0]
        field = [quad(lambda t, a=a, e=e, k=k: np.cross(e, a + t * e)[k] / np.linalg.norm(a + t * e) ** 3, 0, 1,
                      epsabs=0, epsrel=1e-12)[0] for k in range(3)]
        gx, gy, gz, bound = edge_terms(*a, *b, 0.0)
        assert bound == pytest.approx(2 * integral, rel=1e-9)
        assert np.allclose([gx, gy, gz], field, rtol=1e-8, atol=1e-12 * np.abs(field).max())


def test_block_model_bounds_the_cap_everywhere_on_the_block(rng):
    """On random blocks near random soups and sheets: at every point of the
    block, the cap's exact winding number (libigl) is the model at the
    centre plus the near triangles and crossings summed there, within the
    bound ``err + var + hess h^2 / 2``."""
    checked = 0
    for trial in range(12):
        if trial % 2:
            v, f = soup(rng, int(rng.integers(3, 40)))
        else:  # a bumpy open sheet: internal edges, one boundary piece
            g = np.stack(np.meshgrid(np.linspace(0, 1, 9), np.linspace(0, 1, 9), indexing="ij"), -1).reshape(-1, 2)
            v = np.column_stack([g, 0.5 + 0.1 * rng.normal(size=len(g))])
            q = np.arange(81).reshape(9, 9)[:-1, :-1].reshape(-1)
            f = np.concatenate([np.stack([q, q + 9, q + 10], 1), np.stack([q, q + 10, q + 1], 1)])
        from isoflow.mesh.load import boundary_chain

        cap = close_mesh(v, f, *boundary_chain(f, len(v)))
        tree = CapTree(cap.T, cap.E, cap.owner)
        cv, cf = cap.T.reshape(-1, 3), np.arange(3 * len(cap.T)).reshape(-1, 3)
        stack, near, cross = np.empty(64, np.int64), np.empty(MAX_NEAR, np.int64), np.empty(MAX_NEAR, np.int64)
        edges, grad = np.empty((6 * MAX_NEAR, 2, 3)), np.empty(4)
        for _ in range(25):
            q = rng.random(3)
            h = rng.choice([0.01, 0.03, 0.08])
            reach = h + 2 * h
            w, err, var, hess, status, nn, nc = evaluate(*q, h, reach, 0.3, 1e-12, *tree.arrays(), stack, near, cross,
                                                         edges, grad)
            if status:
                continue
            d = rng.normal(size=(40, 3))
            pts = q + d / np.linalg.norm(d, axis=1)[:, None] * h * rng.random((40, 1)) ** (1 / 3)
            exact = igl.winding_number(cv, cf, pts)
            bound = err + var + 0.5 * h * h * hess
            for p, x in zip(pts, exact):
                wn, tie = near_sum(tree.T, tree.nlen, near, nn, cross, nc, *q, *p, 1e-12)
                assert not tie
                assert abs(x - (w + grad[:3] @ (p - q) + wn)) <= bound + 1e-9, (x, w, bound)
            checked += 1
    assert checked > 100


# ---------------------------------------------------------------------------
# voxels against libigl
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("n,res", [(1, 29), (7, 40), (30, 33), (100, 48)])
def test_random_soups_are_exact_everywhere(rng, n, res):
    v, f = soup(rng, n)
    out = voxelize(v, f, resolution=res, details=True)
    vol, origin, pitch = out.volume, out.origin, out.pitch
    assert out.chain_edges == 3 * n
    assert vol.any() == (n > 1)  # a lone triangle has |w| < 1/2 everywhere
    margin, _ = assert_exact(v, f, vol, origin, pitch)
    if n >= 30:  # the comparison reaches the 1/2 level set
        assert (margin < 1e-3).sum() > 10


def test_many_boundary_and_non_manifold_edges_are_exact():
    """Tetrahedra written as quads (libigl's cube_40k.obj in kind, smaller):
    boundary edges, non-manifold ones and inconsistent ones everywhere, and
    at resolution 16 voxel centres on its faces (ties, decided at the tie
    rule's point: the cap is these faces reversed)."""
    v, f = tet_quads(4)
    d = mesh_defects(v, f)
    assert d["boundary_edges"] > 50 and d["nonmanifold_edges"] > 200 and d["inconsistent_edges"] > 200
    for res in (16, 17, 40):
        vol, origin, pitch = voxelize(v, f, resolution=res)
        margin, on = assert_exact(v, f, vol, origin, pitch)
        assert 0 < vol.sum() < vol.size and len(margin) > 0.99 * vol.size
        assert on > 100 or res != 16


def test_thin_slivers_are_exact(rng):
    """Needles (two corners a millionth apart), caps (three corners nearly on
    a line) and flat slivers through planes of voxel centres, among big
    triangles."""
    tris = []
    for _ in range(15):
        a, b = rng.random(3), rng.random(3)
        tris.append([a, b, b + rng.normal(scale=1e-6, size=3)])  # needle
        tris.append([a, b, 0.5 * (a + b) + rng.normal(scale=1e-5, size=3)])  # cap
        z = (int(rng.integers(2, 20)) + 0.5) / 24  # the plane of a layer of centres at resolution 24
        tris.append([[a[0], a[1], z], [b[0], b[1], z], [a[0] + 0.01, b[1], z]])
    tris += list(rng.random((8, 3, 3)))
    T = np.array(tris)
    v, f = T.reshape(-1, 3), np.arange(3 * len(T)).reshape(-1, 3)
    vol, origin, pitch = voxelize(v, f, pitch=1 / 24, grid=([0.0, 0.0, 0.0], (24, 24, 24)))
    assert_exact(v, f, vol, origin, pitch)


def test_centres_a_hair_off_a_sheet_near_the_half_level_set():
    """An open square with layers of centres 1e-3 to 1e-9 pitches off its
    plane, where |w| -> 1/2, and a small bowl above it that moves |w| by
    less than 1e-3 (over 1/2 above the sheet, under it below); libigl
    decides each."""
    import trimesh

    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    bowl = trimesh.creation.icosphere(2, radius=0.03)
    keep = bowl.triangles_center[:, 2] < 0.015
    v = np.concatenate([square, bowl.vertices + [0.5, 0.5, 0.6]])
    f = np.concatenate([[[0, 1, 2], [0, 2, 3]], bowl.faces[keep] + 4])
    n = 16
    pitch = 1 / n
    margins = []
    for off in (1e-3, 1e-6, 1e-9, -1e-7):
        grid = ([-2 * pitch, -2 * pitch, (off - 2.5) * pitch], (n + 4, n + 4, 5))
        vol, origin, _ = voxelize(v, f, pitch=pitch, grid=grid)
        margins.append(assert_exact(v, f, vol, origin, pitch)[0])
    assert (np.concatenate(margins) < 1e-3).sum() > 100


def test_caps_by_area_cones_or_the_faces_themselves():
    """A soup is capped by itself reversed (its faces leave the scanline); a
    box with one face missing by a cone; both at once in one mesh."""
    import trimesh

    from isoflow.mesh.load import boundary_chain

    rng = np.random.default_rng(5)
    sv, sf = soup(rng, 4)
    cap = close_mesh(sv, sf, *boundary_chain(sf, len(sv)))
    assert cap.reversed_faces.all() and len(cap.cones()) == 0
    assert np.array_equal(cap.T, sv[sf[:, ::-1]])
    box = trimesh.creation.box()
    bf = box.faces[box.triangles_center[:, 2] > -0.49]  # open at the bottom
    cap = close_mesh(box.vertices, bf, *boundary_chain(bf, len(box.vertices)))
    assert not cap.reversed_faces.any() and len(cap.cones()) == 4
    v = np.concatenate([box.vertices, sv + 2])
    f = np.concatenate([bf, sf + len(box.vertices)])
    cap = close_mesh(v, f, *boundary_chain(f, len(v)))
    assert cap.reversed_faces.sum() == 4 and len(cap.cones()) == 4
    vol, origin, pitch = voxelize(v, f, resolution=40)
    assert_exact(v, f, vol, origin, pitch)


# ---------------------------------------------------------------------------
# stopping
# ---------------------------------------------------------------------------

def test_pieces_stop_when_asked_and_leave_nothing_running():
    done, running = [], []

    def work(i, stop_at=5):
        running.append(i)
        if i == stop_at:
            request_stop()
        time.sleep(0.01)
        done.append(i)

    try:
        with pytest.raises(Stopped):
            run_pieces(work, 1000, threads=2)
        assert len(done) < 20 and sorted(done) == sorted(running)  # every piece begun has ended
    finally:
        clear_stop()
    # an interrupt in the waiting thread (here from the progress callback)
    done.clear()
    running.clear()

    def progress(d, n):
        if d >= 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_pieces(lambda i: work(i, stop_at=-1), 1000, threads=2, progress=progress)
    assert not STOP[0] and len(done) < 1000 and sorted(done) == sorted(running)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_second_interrupt_while_the_workers_stop_still_waits_for_them():
    """``timeout`` sends its signal to the command and again to its process
    group, and people press Ctrl-C twice: the second KeyboardInterrupt
    comes while :func:`run_pieces` waits for its workers to stop. It must
    go on waiting: a worker left running would go on once the command
    clears the flag (seen: ``timeout 20 isoflow voxelize`` of the
    tetrahedral quads said ``terminated`` and ran on until killed)."""
    import threading

    begun, ended = [], []
    main_thread = threading.main_thread().ident

    def work(i):
        begun.append(i)
        if i == 0:
            signal.pthread_kill(main_thread, signal.SIGINT)  # the first signal
        while not STOP[0]:
            time.sleep(0.001)
        if i == 0:
            signal.pthread_kill(main_thread, signal.SIGINT)  # the second, while the main thread waits for the workers
        time.sleep(0.3)  # a block of work that ends at its next poll
        ended.append(i)

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            run_pieces(work, 100, threads=2)
        assert begun and sorted(ended) == sorted(begun)  # nothing left running
        assert not STOP[0]  # and the next work may run
    finally:
        signal.signal(signal.SIGINT, before)
        time.sleep(0.5)  # what a failing run left running ends before the next test
        clear_stop()


def test_pieces_report_progress_to_the_end():
    seen = []
    run_pieces(lambda i: time.sleep(0.002), 200, threads=2, progress=lambda d, n: seen.append((d, n)))
    assert seen[-1] == (200, 200) and all(n == 200 for _, n in seen)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_signal_ends_a_long_voxelisation_at_once(tmp_path):
    """``isoflow voxelize`` on a mesh whose boundary runs everywhere, at a
    size that takes minutes, signalled mid-work (SIGTERM, SIGINT and SIGHUP,
    one command each, side by side; SIGTERM from ``timeout``, which sends
    it twice, to the command and to its process group): each exits within
    2 s with the README's status (128 + the signal), says so in one line,
    and leaves neither the output nor a temporary file."""
    v, f = tet_quads(12)
    mesh = tmp_path / "tets.obj"
    mesh.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in v.tolist())
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f.tolist()))
    voxelize(v[:9], np.array([[0, 1, 2], [3, 4, 5]]), resolution=8)  # compiled passes in numba's cache
    wait = 8  # reading, orienting, the cap, and into the voxels
    timeout = shutil.which("timeout")
    runs = {}
    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        out = tmp_path / f"out{int(sig)}.npz"
        command = [sys.executable, "-m", "isoflow", "voxelize", str(mesh), "--resolution", "160", "-o", str(out)]
        if sig == signal.SIGTERM and timeout:
            command = [timeout, "--preserve-status", str(wait)] + command
        runs[sig] = out, subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    started = time.monotonic()
    time.sleep(wait)
    for sig, (out, proc) in runs.items():
        if sig == signal.SIGTERM and timeout:
            sent = started + wait
        else:
            assert proc.poll() is None, proc.stderr.read()
            sent = time.monotonic()
            proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
        took = time.monotonic() - sent
        assert proc.returncode == 128 + sig, err
        lines = err.strip().splitlines()
        assert lines[-1] == ("isoflow: interrupted" if sig == signal.SIGINT else "isoflow: terminated"), err
        assert "Traceback" not in err
        assert took < 2.0, (sig, took)
        assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if TEMP_MARK in p.name]


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_signal_taken_as_a_compiled_pass_returns_still_ends_as_terminated(tmp_path, capsys, monkeypatch):
    """A signal whose KeyboardInterrupt is raised while numba boxes a
    compiled pass's result (in a finaliser that runs then) comes out as
    ``SystemError: ... returned a result with an exception set``: the
    command still ends as terminated, with 128 + the signal and one line,
    and writes nothing (seen with SIGHUP on a busy machine, as the cap's
    tree was built)."""
    import os

    from isoflow.mesh import captree

    build = captree._build

    def signalled(g, leaf):
        out = build(g, leaf)
        try:
            os.kill(os.getpid(), signal.SIGHUP)
            time.sleep(1)  # the handler runs here
        except KeyboardInterrupt as exc:
            raise SystemError("CPUDispatcher(<function _build>) returned a result with an exception set") from exc
        return out

    monkeypatch.setattr(captree, "_build", signalled)
    v, f = soup(np.random.default_rng(5), 20)
    mesh = tmp_path / "soup.obj"
    mesh.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in v.tolist())
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f.tolist()))
    out = tmp_path / "out.npz"
    assert main(["voxelize", str(mesh), "--resolution", "16", "-o", str(out)]) == 128 + signal.SIGHUP
    assert capsys.readouterr().err.strip().splitlines()[-1] == "isoflow: terminated"
    assert not out.exists() and not [p for p in tmp_path.iterdir() if TEMP_MARK in p.name]


def test_a_pipe_hears_once_how_long_the_voxelisation_will_take(tmp_path, capsys, monkeypatch):
    from isoflow.cli import progress as bar

    v, f = soup(np.random.default_rng(2), 40)
    mesh = tmp_path / "soup.obj"
    mesh.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in v.tolist())
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f.tolist()))
    assert main(["voxelize", str(mesh), "--resolution", "48", "-o", str(tmp_path / "a.npz")]) == 0
    assert "will take" not in capsys.readouterr().err  # quick: no word
    monkeypatch.setattr(bar, "NOTE_AFTER", 0.0)
    monkeypatch.setattr(bar, "NOTE_LONG", 0.0)
    assert main(["voxelize", str(mesh), "--resolution", "48", "-o", str(tmp_path / "b.npz")]) == 0
    err = capsys.readouterr().err
    notes = [line for line in err.splitlines() if "will take about" in line]
    assert len(notes) == 1 and notes[0].startswith("isoflow voxelize: note: voxelize will take about"), err
    assert notes[0].endswith("; --fill flood (the shell and what it encloses) or --fill shell sum no solid angles "
                             "and take far less"), err
    assert main(["voxelize", str(mesh), "--resolution", "48", "-o", str(tmp_path / "c.npz"), "-q"]) == 0
    assert capsys.readouterr().err == ""
    assert bar.duration(45.2) == "45 s" and bar.duration(200) == "3 min 20 s" and bar.duration(7500) == "2 h 5 min"


def test_the_time_note_takes_the_pace_after_the_first_share(capsys, monkeypatch):
    """The reading and numba's compiling (40 s here) come before the first
    share is done and do not recur: the estimate is what has run plus the
    pace since the first share (1 s a share) times the shares left, not
    the time so far over the share done (which said 23 min 20 s for a
    job of 2 min 19 s)."""
    import argparse
    import time

    from isoflow.cli import progress as bar

    clock = [0.0]
    monkeypatch.setattr(time, "monotonic", lambda: clock[0])
    show = bar.TimeNote(argparse.Namespace(command="voxelize", quiet=False), "voxelize")
    for t, done in ((30.0, 0), (40.0, 1), (41.0, 2), (42.0, 3), (50.0, 11), (60.0, 21)):
        clock[0] = t
        show(done, 100)
    assert capsys.readouterr().err == (
        "isoflow voxelize: note: voxelize will take about 2 min 19 s in all (11 % done in 50 s)\n")


def test_the_time_note_takes_the_pace_over_a_whole_piece(capsys, monkeypatch):
    """The two threads begin their pieces together and end them in bursts
    (the tetrahedral quads at 256 across: 70 s a piece, two ending at 76
    and 77 s, the next two at 146 and 151 s; a share of 1,000 reported
    every 0.1 s): the pace taken over the first burst alone said 18
    minutes for a job of about five hours, and taken just before the
    second burst it says ten. Taken as a share ends, over at least as long
    as the first share took, it says about five hours."""
    import argparse
    import time

    from isoflow.cli import progress as bar

    clock = [0.0]
    monkeypatch.setattr(time, "monotonic", lambda: clock[0])
    show = bar.TimeNote(argparse.Namespace(command="voxelize", quiet=False), "voxelize")
    reports = [(6.0, 0), (40.0, 0), (76.2, 1), (77.0, 3), (78.3, 3), (100.0, 3), (146.4, 3), (146.5, 5), (151.3, 7)]
    for t, done in reports:
        clock[0] = t
        show(done, 1000)
    said = capsys.readouterr().err
    assert said == "isoflow voxelize: note: voxelize will take about 4 h 53 min in all (0 % done in 2 min 26 s)\n", said
    assert 4 * 3600 < 146.5 + (146.5 - 76.2) / 4 * 995 < 5 * 3600  # the estimate, by hand


def test_block_models_bound_the_cap_at_each_point_s_distance(rng):
    """The remainder taken at a point's own distance r from the block's
    centre, ``err + var + hess r^2 / 2`` (how the blocks are painted),
    bounds libigl's exact winding number of the cap at points near the
    centre and at the ball's edge, for the tree's model and for the model
    over all of a small cap's triangles at once (cap_lanes), which agree
    with each other where the tree sums every node exactly."""
    from isoflow.mesh.cap_lanes import evaluate_lanes, lanes_arrays
    from isoflow.mesh.load import boundary_chain

    checked = 0
    for _ in range(8):
        v, f = soup(rng, int(rng.integers(3, 40)))
        cap = close_mesh(v, f, *boundary_chain(f, len(v)))
        tree = CapTree(cap.T, cap.E, cap.owner)
        C, D, eo = lanes_arrays(tree)
        K = C.shape[1]
        cv, cf = cap.T.reshape(-1, 3), np.arange(3 * len(cap.T)).reshape(-1, 3)
        stack, near, cross = np.empty(64, np.int64), np.empty(MAX_NEAR, np.int64), np.empty(MAX_NEAR, np.int64)
        near2, cross2 = np.empty(MAX_NEAR, np.int64), np.empty(MAX_NEAR, np.int64)
        edges, grad, grad2 = np.empty((6 * MAX_NEAR, 2, 3)), np.empty(4), np.empty(4)
        scratch = (np.empty(K), np.empty(K), np.empty(K, dtype=np.bool_), np.empty(K), np.empty(K))
        for _ in range(25):
            q = rng.random(3)
            h = rng.choice([0.01, 0.03, 0.08])
            reach = h + 4 * h
            model = evaluate(*q, h, reach, 0.0, 1e-12, *tree.arrays(), stack, near, cross, edges, grad)
            lanes = evaluate_lanes(*q, h, reach, 1e-12, tree.T, tree.nlen, tree.E, tree.owner, C, D, eo, near2,
                                   cross2, edges, grad2, *scratch)
            if model[4] or lanes[4]:
                continue
            w, err, var, hess, _, nn, nc = model
            assert (lanes[5], lanes[6]) == (nn, nc)
            assert sorted(near2[:nn]) == sorted(near[:nn]) and sorted(cross2[:nc]) == sorted(cross[:nc])
            assert abs(lanes[0] - w) < 1e-12 and np.allclose(grad2[:3], grad[:3], rtol=1e-9, atol=1e-12)
            assert lanes[3] <= hess * (1 + 1e-9) + 1e-12 and lanes[1] == lanes[2] == 0
            d = rng.normal(size=(40, 3))
            r = h * np.concatenate([rng.random(20) * 0.3, 1 - rng.random(20) * 1e-3])  # near q, at the edge
            pts = q + d / np.linalg.norm(d, axis=1)[:, None] * r[:, None]
            exact = igl.winding_number(cv, cf, pts)
            for p, x in zip(pts, exact):
                wn, tie = near_sum(tree.T, tree.nlen, near, nn, cross, nc, *q, *p, 1e-12)
                assert not tie
                rr = float((p - q) @ (p - q))
                for ww, g, hh in ((w, grad, hess), (lanes[0], grad2, lanes[3])):
                    assert abs(x - (ww + g[:3] @ (p - q) + wn)) <= err + var + 0.5 * rr * hh + 1e-9
            checked += 1
    assert checked > 50


def test_an_interrupt_inside_submit_still_waits_for_that_worker(monkeypatch):
    """The signal lands while :func:`run_pieces` submits its second
    worker: the work is queued, its future never comes back. That worker
    must still be waited for, and must not go on once the flag is cleared
    (seen in the test above under load: the command hung at exit on it)."""
    from isoflow.scale import cancel

    real, submitted = cancel.pool(), []

    class LosesTheSecondFuture:
        def submit(self, fn):
            submitted.append(real.submit(fn))
            if len(submitted) == 2:
                raise KeyboardInterrupt
            return submitted[-1]

    begun, ended = [], []

    def work(i):
        begun.append(i)
        while not STOP[0]:
            time.sleep(0.001)
        time.sleep(0.05)  # a block of work that ends at its next poll
        ended.append(i)

    monkeypatch.setattr(cancel, "pool", LosesTheSecondFuture)
    try:
        with pytest.raises(KeyboardInterrupt):
            run_pieces(work, 10, threads=2)
        assert sorted(ended) == sorted(begun)  # nothing left running
        assert not STOP[0]
    finally:  # a worker left running would spin until the flag is set again
        STOP[0] = 1
        wait(submitted)
        STOP[0] = 0
