"""The command line as people expect it: --version, the command list, --quiet
on every command, progress bars only on a terminal, shell completion."""

from __future__ import annotations

import fcntl
import importlib
import importlib.metadata
import io
import os
import shutil
import signal
import struct
import subprocess
import sys
import termios
from pathlib import Path

import numpy as np
import pytest
from conftest import Terminal, stderr_of, torus

import isoflow
from isoflow.cli import main

ROOT = Path(__file__).resolve().parents[1]
TORUS = ROOT / "meshes" / "torus.obj"
COMMANDS = ("info", "surface", "voxelize", "genus", "flow", "completion")


def isoflow_cmd(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "isoflow.cli", *map(str, args)],
                          capture_output=True, text=True, **kwargs)


def test_version_is_the_installed_package_version(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out.strip() == f"isoflow {importlib.metadata.version('isoflow')}"
    assert isoflow.__version__ == importlib.metadata.version("isoflow")  # no second truth drifting


def test_isoflow_alone_lists_the_commands_one_line_each():
    got = isoflow_cmd()  # the real entry point, no arguments at all
    assert got.returncode == 0 and got.stderr == ""
    lines = got.stdout.splitlines()
    for name in COMMANDS:
        listed = [ln for ln in lines if ln.split()[:1] == [name]]
        assert len(listed) == 1 and len(listed[0].split()) > 2, name  # the name and what it does
    assert lines[0].startswith("usage: isoflow")


def test_threads_help_says_what_the_docs_say_it_sets():
    """``--threads`` is the compiled passes' threads (docs/cli.md), for a
    .zarr store read block by block by ``info`` the threads of dask's
    threaded scheduler (docs/outofcore.md), and for ``surface`` of a
    store the blocks meshed at a time (docs/cli.md, docs/surface.md):
    each command's help says what the pages say it sets."""
    import argparse

    from isoflow.cli.main import build_parser

    def page(name):
        return " ".join((ROOT / "docs" / name).read_text().split())

    # the pages' own claims, which the help must repeat
    assert "`--threads N` sets how many threads the compiled passes use" in page("cli.md")
    assert "| `threads` (`--threads`) | threads of dask's threaded scheduler" in page("outofcore.md")
    assert "would fit (`--threads N`)" in page("surface.md") and "how many blocks at a time" in page("surface.md")
    assert ("`surface --threads N` sets the threads of the compiled passes too, and for a 3D `.zarr` store written "
            "block by block the blocks meshed at a time") in page("cli.md")
    assert ("`flow --threads N` sets the threads of the compiled passes too, and for a `.zarr` store flowed block "
            "by block (`--volumes .zarr`) the threads of dask's threaded scheduler, each slab's passes on one "
            "(default `ISOFLOW_THREADS`, else 2, as `flow_chunked(..., workers=2)` in Python)") in page("cli.md")
    claims = {"info": ["threads for the compiled passes", ".zarr store", "threads of dask's threaded scheduler",
                       "each block's passes on one", "$ISOFLOW_THREADS"],
              "surface": ["threads for the compiled passes", "the blocks meshed at a time", "$ISOFLOW_THREADS"],
              "flow": ["threads for the compiled passes", "$ISOFLOW_THREADS", "--volumes .zarr",
                       "threads of dask's threaded scheduler", "each slab's passes on one",
                       "(default: $ISOFLOW_THREADS, else 2)"]}
    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    helps = {name: " ".join(action.help.split()) for name, sub in commands.items() for action in sub._actions
             if "--threads" in action.option_strings}
    assert set(helps) == set(claims)  # a command that takes --threads is checked here
    for name, said in claims.items():
        for claim in said:
            assert claim in helps[name], (name, claim, helps[name])


@pytest.mark.parametrize("command", ["info", "flow", "surface"])
def test_a_bad_isoflow_threads_is_refused_whatever_the_input_size(tmp_path, capsys, monkeypatch, command):
    """ISOFLOW_THREADS is the default of ``--threads`` (docs/cli.md), which
    refuses ``abc``; the variable was read only where a compiled pass ran,
    so ``abc`` passed unseen on a small volume and failed the same command
    on a large one."""
    path = tmp_path / "small.npy"
    np.save(path, np.ones((3, 3, 3), bool))
    extra = ["-o", str(tmp_path / "s.ply")] if command == "surface" else []
    with pytest.raises(SystemExit) as refused:  # the option's own rule
        main(["info", str(path), "--threads", "abc"])
    assert refused.value.code == 2
    capsys.readouterr()
    monkeypatch.setenv("ISOFLOW_THREADS", "abc")
    assert main([command, str(path), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"isoflow {command}: error: the environment variable ISOFLOW_THREADS must be a positive integer, "
                   "got 'abc'"]
    assert not (tmp_path / "s.ply").exists()
    # --threads is what is asked: the variable is not read
    assert main([command, str(path), *extra, "--threads", "2"]) == 0


def test_flow_threads_sets_the_compiled_passes_threads(tmp_path, capsys, monkeypatch):
    """``flow --threads N`` in memory: the run's compiled passes take N
    threads, as ``info`` and ``surface`` do (flow took no --threads);
    block by block it is the flow's dask threads (tests/flow/test_chunked.py)."""
    import inspect

    from isoflow.flow import chunked, run
    from isoflow.scale import compiled

    asked = []
    plain = run.run_flow

    def counted(*args, **kwargs):
        asked.append(compiled.thread_count())
        return plain(*args, **kwargs)

    monkeypatch.setattr(run, "run_flow", counted)
    monkeypatch.delenv("ISOFLOW_THREADS", raising=False)
    np.save(tmp_path / "t.npy", torus(5, 2))
    assert main(["flow", str(tmp_path / "t.npy"), "--steps", "2", "--threads", "7"]) == 0, capsys.readouterr().err
    assert asked == [7]
    # the default the help gives for a store block by block is flow_chunked's
    assert inspect.signature(chunked.flow_chunked).parameters["workers"].default == 2


def test_surface_threads_sets_the_compiled_passes_threads(tmp_path, capsys, monkeypatch):
    """``surface --threads N`` in memory: the compiled passes that mesh the
    volume run on N threads (they ran on every CPU whatever was asked).
    7 is more than the default gives a volume of 5 M voxels (one thread
    per million voxels, at most the CPUs)."""
    pytest.importorskip("numba")
    from isoflow.scale import compiled, kernels

    seen = []

    def counted(voxels=None):
        seen.append(compiled.thread_count(voxels))
        return seen[-1]

    monkeypatch.setattr(kernels, "thread_count", counted)
    monkeypatch.delenv("ISOFLOW_THREADS", raising=False)
    volume = np.zeros((170, 170, 170), bool)  # above least_voxels(surfaces=True): the compiled path
    volume[5:165, 5:165, 5:165] = True
    np.save(tmp_path / "cube.npy", volume)
    assert volume.size >= compiled.least_voxels(surfaces=True)
    assert main(["surface", str(tmp_path / "cube.npy"), "-o", str(tmp_path / "cube.ply"), "--threads", "7",
                 "--no-check"]) == 0, capsys.readouterr().err
    assert seen and set(seen) == {7}


def test_quiet_on_every_command(tmp_path, capsys):
    np.save(tmp_path / "t.npy", torus(5, 2))
    runs = [
        ["info", tmp_path / "t.npy"],
        ["surface", tmp_path / "t.npy", "-o", tmp_path / "t.ply"],
        ["voxelize", TORUS, "--resolution", 16, "-o", tmp_path / "t.npz"],
        ["genus", TORUS, "--resolution", 16],
        ["flow", tmp_path / "t.npy", "--steps", 1],
        ["completion", "bash"],
    ]
    assert sorted(r[0] for r in runs) == sorted(COMMANDS)
    for argv in runs:
        assert main([str(a) for a in argv] + ["--quiet"]) == 0, argv
        assert capsys.readouterr().err == ""
    # errors are never quietened: one line, exit 2
    assert main(["info", str(tmp_path / "missing.npy"), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing.npy" in err


def test_quiet_drops_library_warnings_and_logs(tmp_path):
    """In a process of its own (pytest captures warnings): a library warning
    and a log record during the work reach stderr, not with --quiet, and
    --quiet leaves the filters as they were for whoever calls main() next."""
    np.save(tmp_path / "t.npy", torus(4, 1.5))
    code = """if True:
        import logging, sys, warnings
        import isoflow.digital.analysis as analysis
        from isoflow.cli import main
        real = analysis.analyze
        def chatty(*args, **kwargs):
            warnings.warn("a library warning", UserWarning)
            logging.getLogger("somelib").warning("a library log record")
            return real(*args, **kwargs)
        analysis.analyze = chatty
        assert main(sys.argv[1:] + ["--quiet"]) == 0
        blanket = ("ignore", None, Warning, None, 0)
        assert blanket not in warnings.filters and not logging.root.manager.disable
        print("--- now without --quiet", file=sys.stderr)
        assert main(sys.argv[1:]) == 0
    """
    got = subprocess.run([sys.executable, "-c", code, "info", str(tmp_path / "t.npy")], capture_output=True, text=True)
    assert got.returncode == 0, got.stderr
    assert got.stdout.count("genus 1") == 2
    quiet, loud = got.stderr.split("--- now without --quiet\n")
    assert quiet == ""
    assert "a library warning" in loud and "a library log record" in loud


def test_progress_bars_on_a_terminal_only(tmp_path, monkeypatch):
    zarr = pytest.importorskip("zarr")
    np.save(tmp_path / "t.npy", torus(6, 2))
    z = zarr.open_array(str(tmp_path / "t.zarr"), mode="w", shape=(16, 16, 10), chunks=(5, 16, 10), dtype=bool)
    z[:] = torus(6, 2)[:16, :16, :10]
    runs = {
        "voxelize:": ["voxelize", TORUS, "--resolution", 24, "-o", tmp_path / "v.npz", "--force"],
        "genus:": ["genus", TORUS, "--resolution", 24, 16],
        "flow: ": ["flow", tmp_path / "t.npy"],  # a counter: the length is not known in advance
        "blocks:": ["info", tmp_path / "t.zarr"],  # out of core, per layer of blocks
    }
    for label, argv in runs.items():
        shown = stderr_of(monkeypatch, Terminal(), argv)
        assert label in shown and "\r" in shown, argv
        assert stderr_of(monkeypatch, Terminal(), argv + ["--quiet"]) == "", argv
        assert stderr_of(monkeypatch, io.StringIO(), argv) == "", argv  # a pipe or a log file


def screen_lines(text: str) -> list[str]:
    """The lines a terminal shows for ``text``: a carriage return moves
    back to the line's start, and what follows overwrites it."""
    shown = []
    for line in text.split("\n"):
        cells: list[str] = []
        at = 0
        for ch in line:
            if ch == "\r":
                at = 0
                continue
            cells[at:at + 1] = [ch]
            at += 1
        shown.append("".join(cells).rstrip())
    return shown


def test_genus_resolution_lines_have_a_terminal_line_of_their_own(monkeypatch, capsys):
    """On a terminal each resolution's line was printed after the bar, on
    the bar's own line (``genus:  11%|███ | [00:00<?]genus: resolution
    16: ...``). Each one starts its line, with no bar before it."""
    shown = screen_lines(stderr_of(monkeypatch, Terminal(), ["genus", TORUS, "--resolution", 16, 24, "--no-step"]))
    said = [ln for ln in shown if "resolution" in ln]
    assert len(said) == 2 and all(ln.startswith("genus: resolution ") for ln in said), said
    assert "genus 1" in capsys.readouterr().out


def test_flow_counter_says_its_steps_in_words(tmp_path, monkeypatch):
    """The flow's counter from its first step (docs/flow.md): ``1 step``,
    not tqdm's ``1 steps`` and a rate."""
    np.save(tmp_path / "box.npy", np.ones((3, 3, 3), bool))  # 27, 8, 1, 0 voxels
    shown = stderr_of(monkeypatch, Terminal(), ["flow", tmp_path / "box.npy"])
    assert "\rflow: 1 step [" in shown and "1 steps" not in shown and "/s" not in shown


def test_progress_bar_on_a_pseudo_terminal(tmp_path):
    """The installed command, its stderr a real pseudo-terminal of 80 columns."""
    def run(*extra):
        master, slave = os.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
        proc = subprocess.Popen([sys.executable, "-m", "isoflow.cli", "voxelize", str(TORUS), "--resolution", "32",
                                 "-o", str(tmp_path / "v.npz"), "--force", *extra],
                                stdout=subprocess.PIPE, stderr=slave, stdin=subprocess.DEVNULL)
        os.close(slave)
        out, _ = proc.communicate()
        seen = b""
        while True:
            try:
                chunk = os.read(master, 65536)
            except OSError:  # EIO: the other side is closed
                break
            if not chunk:
                break
            seen += chunk
        os.close(master)
        assert proc.returncode == 0 and b"voxels in a 32x" in out  # the result on stdout
        return seen.decode()

    shown = run()
    assert "voxelize:" in shown and "%|" in shown
    assert run("--quiet") == ""


def test_info_imports_no_progress_or_completion_library(tmp_path):
    np.save(tmp_path / "t.npy", torus(4, 1.5))
    code = ("import sys; from isoflow.cli import main; main(['info', sys.argv[1]]); "
            "print(sorted(m for m in ('tqdm', 'shtab') if m in sys.modules))")
    got = subprocess.run([sys.executable, "-c", code, str(tmp_path / "t.npy")], capture_output=True, text=True)
    assert got.returncode == 0 and got.stdout.splitlines()[-1] == "[]"


def test_info_of_a_small_volume_imports_no_masked_arrays_nor_openssl(tmp_path):
    # numpy.ma (imported on the first use of np.ma) and secrets (whose hmac
    # loads OpenSSL) are a few milliseconds each of a command that sees no
    # masked array and writes no file
    np.save(tmp_path / "t.npy", torus(4, 1.5))
    code = ("import sys; from isoflow.cli import main; main(['info', sys.argv[1]]); "
            "print(sorted(m for m in ('numpy.ma', 'secrets', '_hashlib') if m in sys.modules))")
    got = subprocess.run([sys.executable, "-c", code, str(tmp_path / "t.npy")], capture_output=True, text=True)
    assert got.returncode == 0 and got.stdout.splitlines()[-1] == "[]", got.stderr


def test_the_command_freezes_what_numba_imported(tmp_path):
    # numba's modules live until the command exits: once imported they are
    # frozen, out of what the collector walks (gc.get_objects), so that no
    # collection of the oldest generation walks them again while the
    # command works (looked at when the output is opened, after numba ran)
    pytest.importorskip("numba")
    code = ("import gc, sys\n"
            "seen = []\n"
            "def opened(event, args):\n"
            "    if event == 'open' and str(args[0]).endswith('.npz') and 'numba' in sys.modules:\n"
            "        namespace = sys.modules['numba'].__dict__\n"
            "        seen.append(any(o is namespace for o in gc.get_objects()))\n"
            "sys.addaudithook(opened)\n"
            "from isoflow.cli import console\n"
            "sys.argv = ['isoflow', 'voxelize', sys.argv[1], '--resolution', '16', '-o', sys.argv[2]]\n"
            "try:\n"
            "    console()\n"
            "except SystemExit as exc:\n"
            "    print(exc.code, sorted(set(seen)))\n")
    got = subprocess.run([sys.executable, "-c", code, TORUS, tmp_path / "ring.npz"], capture_output=True, text=True)
    assert got.stdout.splitlines()[-1] == "0 [False]", got.stderr


@pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")
def test_bash_completion_completes(tmp_path):
    script = isoflow_cmd("completion", "bash")
    assert script.returncode == 0
    (tmp_path / "isoflow.bash").write_text(script.stdout)
    (tmp_path / "ring.obj").write_text("")

    def complete(*words):
        line = " ".join(("isoflow",) + words)
        shell = (f"source {tmp_path / 'isoflow.bash'}; COMP_WORDS=({line}); COMP_CWORD={len(words)}; "
                 f"COMP_LINE='{line}'; COMP_POINT=${{#COMP_LINE}}; _shtab_isoflow; echo \"${{COMPREPLY[@]}}\"")
        return subprocess.run(["bash", "-c", shell], capture_output=True, text=True, cwd=tmp_path).stdout.split()

    assert complete("vo") == ["voxelize"]
    assert complete("info", "--conn") == ["--connectivity"]
    assert complete("info", "--connectivity", "2") == ["26"]
    assert complete("genus", "ri") == ["ring.obj"]  # paths complete as files
    assert "--quiet" in complete("flow", "--q")
    assert complete("flow", "--thr") == ["--threads"]  # what the hints of flow block by block name


def test_zsh_and_tcsh_scripts(capsys):
    assert main(["completion", "zsh"]) == 0
    assert capsys.readouterr().out.startswith("#compdef isoflow")
    assert main(["completion", "tcsh"]) == 0
    assert "complete isoflow" in capsys.readouterr().out
    with pytest.raises(SystemExit) as bad:
        main(["completion", "cmd.exe"])
    assert bad.value.code == 2 and "invalid choice" in capsys.readouterr().err


def assert_terminated_while_writing(tmp_path, capsys, before: bytes) -> None:
    """``surface`` of a larger ``v.npy`` over ``s.ply`` (holding ``before``),
    signalled as the caller arranged: exit 143, one line naming the file,
    the previous ``s.ply`` kept and no temporary file left."""
    capsys.readouterr()
    np.save(tmp_path / "v.npy", np.ones((4, 4, 4), bool))
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "s.ply"), "--force"]) == 143
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"isoflow: terminated: {tmp_path / 's.ply'}: interrupted while writing; the previous s.ply "
                   "is unchanged"], err
    assert (tmp_path / "s.ply").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.ply", "v.npy"]  # no temporary file left


def test_a_signal_a_library_swallows_still_stops_the_output(tmp_path, capsys, monkeypatch):
    """The handlers raise KeyboardInterrupt, which trimesh's import guards
    (except BaseException) can swallow: the command then finished, exited 0
    and replaced the output. The signal is kept as well, so nothing is
    renamed into place after it and the command ends as terminated."""
    from isoflow.mesh import export, outputs

    np.save(tmp_path / "v.npy", np.ones((3, 3, 3), bool))
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "s.ply")]) == 0
    before = (tmp_path / "s.ply").read_bytes()
    table = export.mesh_vertex_table

    def swallowed(*args):  # a SIGTERM that arrived and was swallowed while the file was made
        outputs.SIGNALS.append(15)
        return table(*args)

    monkeypatch.setattr(export, "mesh_vertex_table", swallowed)
    assert_terminated_while_writing(tmp_path, capsys, before)
    assert not outputs.SIGNALS  # and the next command starts afresh
    monkeypatch.undo()
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "s.ply"), "--force"]) == 0


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_repeated_signal_does_not_cut_short_the_clean_up(tmp_path, capsys, monkeypatch):
    """``timeout`` sends SIGTERM to the command and again to its process
    group, and people press Ctrl-C twice: a second signal arriving as the
    first one's clean-up begins must not interrupt it (raised again, it
    left the temporary file beside the output and the line without its
    file)."""
    from isoflow.mesh import outputs

    np.save(tmp_path / "v.npy", np.ones((3, 3, 3), bool))
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "s.ply")]) == 0
    before = (tmp_path / "s.ply").read_bytes()
    sync, remove = outputs.sync_file, outputs._remove

    def signalled(path):  # the first signal, as the written file is flushed
        os.kill(os.getpid(), signal.SIGTERM)
        sync(path)

    def removing(tmp):  # the second, as the temporary file is removed
        os.kill(os.getpid(), signal.SIGTERM)
        remove(tmp)

    monkeypatch.setattr(outputs, "sync_file", signalled)
    monkeypatch.setattr(outputs, "_remove", removing)
    # the window, wide enough that a machine too busy to run two lines in a
    # second does not fail the test
    monkeypatch.setattr(importlib.import_module("isoflow.cli.main"), "REPEAT_SECONDS", 60.0)
    assert_terminated_while_writing(tmp_path, capsys, before)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_signal_inside_a_weakref_callback_ends_the_command_without_a_traceback(tmp_path, capsys, monkeypatch):
    """A SIGTERM whose KeyboardInterrupt is raised where Python cannot
    raise it (here a weakref callback, as during garbage collection) is
    dropped by Python with an "Exception ignored" traceback on stderr; the
    command still ends as terminated, in its one line."""
    import weakref

    from isoflow.mesh import export

    np.save(tmp_path / "v.npy", np.ones((3, 3, 3), bool))
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "s.ply")]) == 0
    before = (tmp_path / "s.ply").read_bytes()
    table = export.mesh_vertex_table

    class Dropped:
        pass

    def collected(*args):
        thing = Dropped()
        ref = weakref.ref(thing, lambda _: os.kill(os.getpid(), signal.SIGTERM))
        del thing  # the callback runs now, and the handler inside it
        assert ref() is None
        return table(*args)

    monkeypatch.setattr(export, "mesh_vertex_table", collected)
    monkeypatch.setattr(sys, "unraisablehook", sys.__unraisablehook__)  # Python's, not pytest's
    capsys.readouterr()
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "s.ply"), "--force"]) == 143
    err = capsys.readouterr().err
    assert "Traceback" not in err and "Exception ignored" not in err, err
    assert err.strip().splitlines() == [f"isoflow: terminated: {tmp_path / 's.ply'}: interrupted while writing; "
                                        "the previous s.ply is unchanged"], err
    assert (tmp_path / "s.ply").read_bytes() == before


def quiet_run(capsys, *argv) -> tuple[list[str], list[str]]:
    """A command run with --quiet: its ``warning:`` lines and its other stderr lines."""
    assert main([str(a) for a in argv] + ["--quiet"]) == 0
    lines = capsys.readouterr().err.splitlines()
    return [line for line in lines if ": warning: " in line], [line for line in lines if ": warning: " not in line]


def test_quiet_keeps_each_warning_that_the_result_differs(tmp_path, capsys):
    """--quiet dropped every warning: a .npy that lost the voxel size, a
    NIfTI's rotation left out, an STL's moved or welded corners went unsaid."""
    nib = pytest.importorskip("nibabel")
    trimesh = pytest.importorskip("trimesh")
    # lost: a .npy holds the bare array (numpy's format), the pitch and origin are gone
    warned, other = quiet_run(capsys, "voxelize", TORUS, "--pitch", 0.25, "-o", tmp_path / "t.npy")
    assert type(np.load(tmp_path / "t.npy")) is np.ndarray
    assert len(warned) == 1 and "pitch [0.25, 0.25, 0.25]" in warned[0] and "not kept" in warned[0], warned
    # changed: an affine turned by 30 degrees (nibabel's) is read axis-aligned
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    affine = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    nib.save(nib.Nifti1Image(torus(5, 2).astype(np.uint8), affine), tmp_path / "turned.nii.gz")
    assert not np.allclose(nib.load(tmp_path / "turned.nii.gz").affine[:3, :3], np.diag(np.diag(affine[:3, :3])))
    warned, other = quiet_run(capsys, "info", tmp_path / "turned.nii.gz")
    assert len(warned) == 1 and "rotated or sheared by up to 30 degrees" in warned[0], warned
    assert other == []  # and nothing else: the notes stay dropped
    # rounded: far from the origin float32 moves the corners (by numpy's float32, over a thousandth of a voxel)
    far = isoflow.DigitalObject(torus(5, 2), pitch=0.01, origin=(1e5, 0, 0))
    isoflow.write_volume(far, tmp_path / "far.npz")
    corners = far.world(isoflow.boundary_mesh(far.volume, 6).vertices)
    assert np.abs(corners.astype(np.float32) - corners).max() > 1e-3 * 0.01
    warned, other = quiet_run(capsys, "surface", tmp_path / "far.npz", "-o", tmp_path / "far.stl")
    assert len(warned) == 1 and "STL stores float32 positions, which move the corners" in warned[0], warned
    # changed on reading: readers weld an edge contact's split copies (trimesh: not watertight)
    vol = np.zeros((3, 3, 4), bool)
    vol[1, 1, 1] = vol[2, 2, 1] = True
    np.save(tmp_path / "e.npy", vol)
    warned, other = quiet_run(capsys, "surface", tmp_path / "e.npy", "-o", tmp_path / "e.stl")
    assert not trimesh.load(tmp_path / "e.stl").is_watertight
    assert len(warned) == 1 and "STL keeps no shared vertices" in warned[0], warned


@pytest.mark.parametrize(("dtype", "given", "shown"), [
    (np.int32, "1e300", "1e+300"),  # printed in its 301 digits, the last 285 the float's rounding
    (np.int64, "18446744073709551617", "18446744073709551617"),  # digits typed stay as typed
    (np.int16, "-1e20", "-1e+20"),
    (np.int32, "4e18", "4e+18"),  # within 2**64, printed in 19 digits
    (np.uint8, "300", "300"),
    (np.float32, "1e300", "1e+300"),
])
def test_a_label_beyond_the_array_s_type_names_the_label_as_typed_and_the_type_with_its_article(
        tmp_path, dtype, given, shown):
    """``--label 1e300`` was refused naming label 1000000...160 (301
    digits), and the type read "a int32". From the shell: one line, exit
    2, the label as typed (digits) or in Python's shortest form of the
    float typed, and "an" before a type said with a vowel (int), "a"
    before uint and float."""
    labels = np.zeros((3, 3, 3), dtype)
    labels[1, 1, 1] = 1
    np.save(tmp_path / "l.npy", labels)
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", str(tmp_path / "l.npy"), f"--label={given}"],
                          capture_output=True, text=True)
    name = np.dtype(dtype).name
    article = "an" if name.startswith("int") else "a"
    assert done.returncode == 2 and done.stdout == "", done.stderr
    assert done.stderr.splitlines() == [f"isoflow info: error: {tmp_path / 'l.npy'}: label {shown} is beyond the "
                                        f"values {article} {name} array holds" + (
                                            f" ({np.iinfo(dtype).min} to {np.iinfo(dtype).max})"
                                            if np.dtype(dtype).kind in "iu" else "")]
    assert shown in (given, repr(float(given)))


def test_outputs_and_labels_checked_before_any_work(tmp_path, capsys, monkeypatch):
    """flow --out is checked before the input is read (an open mesh's note
    came first); a label beyond the array's type is one line; a .zarr
    output in a directory that takes no files is one line (a traceback)."""
    (tmp_path / "afile").write_text("x")
    assert main(["flow", str(ROOT / "meshes" / "cube_no_bottom.obj"), "--resolution", "8",
                 "--out", str(tmp_path / "afile")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "afile: exists and is not a directory" in err[0], err
    np.save(tmp_path / "l.npy", np.arange(8, dtype=np.int16).reshape(2, 2, 2))
    for label in ("99999999999999999999999", "1e20", "18446744073709551615"):
        assert main(["info", str(tmp_path / "l.npy"), f"--label={label}"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "beyond the values an int16 array holds" in err[0], err
    from isoflow.mesh import outputs

    monkeypatch.setattr(outputs.os, "access", lambda *a, **k: False)
    assert main(["voxelize", str(TORUS), "--resolution", "8", "-o", str(tmp_path / "t.zarr")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write the zarr store t.zarr here" in err[0], err


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_signal_pending_as_the_handlers_are_put_back_leaves_none_in_place(tmp_path, capsys, monkeypatch):
    """``signal.signal`` runs a pending signal's handler before it changes
    one: a SIGTERM that came as the command ended raised KeyboardInterrupt
    from the first handler put back and left the others raising it after
    the command had returned (a later SIGTERM then ended Python with 130)."""
    np.save(tmp_path / "v.npy", np.ones((3, 3, 3), bool))
    wanted = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
    before = {sig: signal.getsignal(sig) for sig in wanted}
    setting = signal.signal
    pending = [signal.SIGTERM]

    def put_back(sig, handler):
        if handler is before[signal.SIGINT] and pending:  # the first put back, as Python would run the handler
            os.kill(os.getpid(), pending.pop())
        return setting(sig, handler)

    monkeypatch.setattr(signal, "signal", put_back)
    try:
        assert main(["info", str(tmp_path / "v.npy")]) == 143
        assert {sig: signal.getsignal(sig) for sig in wanted} == before
    finally:
        for sig, handler in before.items():
            setting(sig, handler)
    assert capsys.readouterr().err.strip().splitlines()[-1:] == ["isoflow: terminated"]


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_inside_code_run_from_a_string_exits_128_plus_its_number(tmp_path, sig):
    """A signal whose KeyboardInterrupt leaves an ``exec`` of source text
    (scipy's ``exec("from numpy import *")`` while dask.array is imported,
    a namedtuple's ``eval``) is recorded by CPython as unhandled although
    the command handles it; under ``python -m`` the command then ended by
    SIGINT (130) about one SIGTERM in six under ``timeout``, not 143."""
    np.save(tmp_path / "v.npy", np.ones((3, 3, 3), bool))
    (tmp_path / "signal_in_exec.py").write_text(f"""\
import importlib, runpy
cli = importlib.import_module("isoflow.cli.main")
refuse = cli.refuse_output_over_input

def signalled(args):  # while the command runs, as a library's import evaluates a string
    exec("import signal; signal.raise_signal({int(sig)})", {{}})
    refuse(args)

cli.refuse_output_over_input = signalled
runpy.run_module("isoflow", run_name="__main__")
""")
    path = os.pathsep.join([str(tmp_path), str(Path(isoflow.__file__).parents[1]), os.environ.get("PYTHONPATH", "")])
    done = subprocess.run([sys.executable, "-m", "signal_in_exec", "info", str(tmp_path / "v.npy")], cwd=tmp_path,
                          capture_output=True, text=True, env={**os.environ, "PYTHONPATH": path}, timeout=120)
    how = "interrupted" if sig == signal.SIGINT else "terminated"
    assert (done.returncode, done.stderr.strip().splitlines()[-1:]) == (128 + sig, [f"isoflow: {how}"]), done.stderr


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
@pytest.mark.parametrize("labels", [False, True])
def test_a_signal_during_the_read_back_says_the_file_is_written(tmp_path, capsys, monkeypatch, labels):
    """Ctrl-C while trimesh reads the written surface back: exit 130, one
    line saying the file is there and only its check was cut short (it
    said only "interrupted"), and the file is the whole surface; of a file
    per label, that none was replaced."""
    import trimesh

    from isoflow.mesh import readback

    np.save(tmp_path / "v.npy", np.pad(np.ones((3, 3, 3), np.uint8), 1) * 4)
    figures = readback.trimesh_figures

    def interrupted(*args, **kw):
        os.kill(os.getpid(), signal.SIGINT)
        return figures(*args, **kw)

    monkeypatch.setattr(readback, "trimesh_figures", interrupted)
    out = tmp_path / ("d" if labels else "s.ply")
    args = ["--labels", "-o", f"{out}/", "--suffix", ".ply"] if labels else ["-o", str(out)]
    assert main(["surface", str(tmp_path / "v.npy"), *args]) == 130
    if labels:  # the files of a directory are one set, checked before any is put in place
        assert capsys.readouterr().err.strip().splitlines() == [f"isoflow: interrupted: {out}/: nothing was replaced"]
        assert not out.exists()  # the directory this run made, removed with its temporaries
        return
    assert capsys.readouterr().err.strip().splitlines() == [
        f"isoflow: interrupted: {out} is written, not read back (--no-check skips the read-back)"]
    mesh = trimesh.load(out, process=False)
    assert mesh.is_watertight and mesh.volume == pytest.approx(27)


def test_an_output_that_is_the_input_is_refused_even_with_force(tmp_path, capsys):
    """`surface m.obj -o m.obj --force` replaced the user's mesh with the
    voxel surface; every output (-o, --csv, --png) that names the input,
    by another path or a hard link, is refused and the file kept."""
    from test_input_errors import fails

    mesh = Path(__file__).resolve().parents[1] / "meshes" / "torus.obj"
    (tmp_path / "m.obj").write_bytes(mesh.read_bytes())
    os.link(tmp_path / "m.obj", tmp_path / "link.obj")
    labels = np.zeros((4, 4, 4), np.uint8)
    labels[1:3, 1:3, 1:3] = 2
    np.save(tmp_path / "l.npy", labels)
    for argv in (["surface", tmp_path / "m.obj", "-o", tmp_path / "m.obj"],
                 ["surface", tmp_path / "m.obj", "-o", tmp_path / "link.obj"],
                 ["surface", tmp_path / "l.npy", "--label", "2", "-o", tmp_path / "s.ply", "--png", tmp_path / "l.npy"],
                 ["info", tmp_path / "l.npy", "--labels", "--csv", f"{tmp_path}/../{tmp_path.name}/l.npy"]):
        fails(capsys, *argv, "--force", words=("is the input", "--force replaces an output, never the input"))
    assert (tmp_path / "m.obj").read_bytes() == mesh.read_bytes()
    assert np.array_equal(np.load(tmp_path / "l.npy"), labels)


@pytest.mark.parametrize("argv, meant", [
    (["flow", "t.npy", "-o", "f.ply"], "-o: did you mean --out?"),  # flow writes into a directory
    (["info", "t.npy", "--lables"], "--lables: did you mean --labels?"),
    (["info", "t.npy", "extra"], None),
])
def test_an_unknown_argument_shows_its_commands_usage(capsys, argv, meant):
    """argparse's top-level parser reported a command's unknown argument
    with isoflow's usage ("usage: isoflow [-h] [--version] COMMAND"), so
    the user saw no option of the command they typed."""
    with pytest.raises(SystemExit) as done:
        main(argv)
    assert done.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"usage: isoflow {argv[0]} ") and "--connectivity" in err, err
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"isoflow {argv[0]}: error: unrecognized arguments: {' '.join(argv[2:])}"), last
    assert (meant in last) if meant else "did you mean" not in last, last


@pytest.mark.parametrize("value, said", [("-1", "must be 0 or more, got -1"), ("1.5", "not a whole number of steps")])
def test_a_bad_steps_is_refused_before_the_input_is_read(tmp_path, capsys, monkeypatch, value, said):
    from isoflow.cli import flow

    def never(args):
        raise AssertionError(f"{args.input} was read")

    monkeypatch.setattr(flow, "load_input", never)
    blob = tmp_path / "blob.npy"
    np.save(blob, np.ones((3, 3, 3), bool))
    with pytest.raises(SystemExit) as stop:  # as argparse ends on a bad value
        main(["flow", str(blob), "--steps", value])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err == f"isoflow flow: error: argument --steps: {said}" + (f": '{value}'\n" if "whole" in said else "\n")


def shortenings():
    """Each command's long options, each with its shortest beginning that
    no other option of the command shares (what argparse took for it)."""
    from isoflow.cli.main import build_parser

    for name, command in build_parser().commands.items():
        options = [o for action in command._actions for o in action.option_strings if o.startswith("--")]
        for option in options:
            cut = next((option[:n] for n in range(3, len(option))
                        if not any(o.startswith(option[:n]) for o in options if o != option)), None)
            if cut is not None:
                yield name, option, cut


@pytest.mark.parametrize("command, option, cut", list(shortenings()), ids=lambda v: str(v))
def test_a_shortened_option_is_refused_naming_the_option(capsys, command, option, cut):
    """argparse read any unique beginning as the option (``surface --out``
    as --output, ``info --no`` as --no-surfaces): a script's shortening
    would change meaning once another option began the same way."""
    required = {"completion": ["bash"], "surface": ["in.npy", "-o", "out.ply"],
                "voxelize": ["in.stl", "--pitch", "1", "-o", "out.npz"]}
    argv = [command, *required.get(command, ["in.npy"]), cut]
    with pytest.raises(SystemExit) as done:
        main(argv)
    assert done.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"unrecognized arguments: {cut}" in last and f"{cut}: did you mean {option}" in last, last


@pytest.mark.parametrize("argv, named", [
    (["info", ""], "input"),
    (["info", "{labels}", "--labels", "--csv", ""], "--csv"),
    (["surface", "{blob}", "-o", ""], "-o/--output"),
    (["surface", "{blob}", "-o", "{tmp}/s.ply", "--png", ""], "--png"),
    (["voxelize", "", "--pitch", "1", "-o", "{tmp}/v.npz"], "mesh"),
    (["voxelize", "{box}", "--pitch", "1", "-o", ""], "-o/--output"),
    (["genus", ""], "mesh"),
])
def test_an_empty_path_is_refused_naming_its_argument(tmp_path, capsys, argv, named):
    """An unset shell variable (``--csv "$OUT"``): ``--csv ''`` and ``--png
    ''`` were taken as not given (no file, exit status 0), an empty input
    or -o was named as ".", the directory an empty path is."""
    import trimesh

    np.save(tmp_path / "blob.npy", np.ones((3, 3, 3), bool))
    np.save(tmp_path / "labels.npy", np.arange(8, dtype=np.uint8).reshape(2, 2, 2))
    trimesh.creation.box().export(tmp_path / "box.stl")
    where = {"blob": tmp_path / "blob.npy", "labels": tmp_path / "labels.npy", "box": tmp_path / "box.stl", "tmp": tmp_path}
    assert main([a.format(**where) for a in argv]) == 2
    captured = capsys.readouterr()
    assert captured.err == f"isoflow {argv[0]}: error: {named} '': an empty file name; give the file's name\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blob.npy", "box.stl", "labels.npy"]


def test_an_empty_volumes_suffix_is_named_as_given(tmp_path, capsys):
    np.save(tmp_path / "blob.npy", np.ones((3, 3, 3), bool))
    assert main(["flow", str(tmp_path / "blob.npy"), "--out", str(tmp_path / "run"), "--volumes", ""]) == 2
    err = capsys.readouterr().err
    assert err.startswith("isoflow flow: error: --volumes '': volumes are written as .npy, "), err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("suffix", [".npz", ".npy"])
def test_a_terminal_is_told_while_the_volume_is_written(tmp_path, monkeypatch, suffix):
    """Compressing a large volume can take as long as voxelising it, after
    the bar has cleared: while the file is written, the terminal's last
    line names it; then that line is cleared, a warning of the write (.npy
    drops the pitch) on a line of its own, and a pipe gets none of it."""
    from isoflow.mesh.formats.registry import format_for

    module = format_for(tmp_path / f"v{suffix}", writing=True).load()
    write, seen = module.write, []

    def recorded(*args, **kwargs):
        seen.append(sys.stderr.getvalue().rsplit("\r", 1)[-1])  # what the terminal's line shows now
        return write(*args, **kwargs)

    monkeypatch.setattr(module, "write", recorded)
    argv = ["voxelize", TORUS, "--resolution", 16, "-o", tmp_path / f"v{suffix}", "--force"]
    shown = stderr_of(monkeypatch, Terminal(), argv)  # which undoes the patch once the command is done
    line = f"voxelize: writing {tmp_path / f'v{suffix}'}"
    assert seen == [line]
    assert f"\r{line}\r{' ' * len(line)}\r" in shown  # cleared once the file is written
    for line in shown.split("\n"):
        assert "warning:" not in line or line.rsplit("\r", 1)[-1].startswith("isoflow voxelize: warning:"), line
    assert "writing" not in stderr_of(monkeypatch, io.StringIO(), argv)  # a pipe or a log file


@pytest.mark.parametrize("argv, option, first, then", [
    (["info", "{blob}", "--labels", "--csv", "{tmp}/a.csv", "--csv", "{tmp}/b.csv"], "--csv",
     "--csv {tmp}/a.csv", "--csv {tmp}/b.csv"),
    (["surface", "{blob}", "-o", "{tmp}/a.ply", "--output", "{tmp}/b.ply"], "-o/--output",
     "-o {tmp}/a.ply", "--output {tmp}/b.ply"),
    (["surface", "{blob}", "-o", "{tmp}/a.ply", "--png", "{tmp}/a.png", "--png={tmp}/b.png"], "--png",
     "--png {tmp}/a.png", "--png={tmp}/b.png"),
    (["flow", "{blob}", "--out", "{tmp}/a", "--out", "{tmp}/b"], "--out", "--out {tmp}/a", "--out {tmp}/b"),
])
def test_an_output_given_twice_is_refused_naming_it(tmp_path, capsys, argv, option, first, then):
    """argparse keeps the last of an option given twice and drops the
    first without a word: ``-o a.ply -o b.ply`` wrote b.ply alone. One line
    naming the option and both values, exit status 2, no file written."""
    np.save(tmp_path / "blob.npy", np.ones((3, 3, 3), bool))
    fill = {"blob": tmp_path / "blob.npy", "tmp": tmp_path}
    with pytest.raises(SystemExit) as done:
        main([word.format(**fill) for word in argv])
    assert done.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == (f"isoflow {argv[0]}: error: argument {option}: given twice "
                            f"({first.format(**fill)}, then {then.format(**fill)}); give it once\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blob.npy"]


def test_settings_flags_and_options_that_gather_values_may_be_repeated():
    """What argparse itself makes of a repetition that drops no output:
    genus --resolution gathers every value, a flag stays set, a setting
    keeps its last value."""
    from isoflow.cli.main import build_parser

    parser = build_parser()
    assert parser.parse_args(["genus", "m.obj", "--resolution", "8", "--resolution", "12"]).resolution == [8, 12]
    # a setting given twice: the last, so that an alias's default can be replaced
    assert parser.parse_args(["info", "v.npy", "--connectivity", "6", "--connectivity", "26"]).connectivity == 26
    assert parser.parse_args(["info", "v.npy", "--json", "--json", "-q", "-q"]).json is True


def on_a_pseudo_terminal(argv: list[str], sized: str = "pass") -> str:
    """What the command line with ``argv`` shows on a pseudo-terminal
    (stdout and stderr), the first line the size the terminal reports
    once the code ``sized`` has run in the child."""
    import pty
    import select

    pid, fd = pty.fork()
    if pid == 0:  # the child: stdout and stderr are the terminal
        os.execvp(sys.executable, [sys.executable, "-c", f"import os, sys; {sized}; print(*os.get_terminal_size(2)); "
                                   "from isoflow.cli import console; sys.argv[0] = 'isoflow'; console()", *argv])
    out = b""
    while select.select([fd], [], [], 60)[0]:
        try:
            chunk = os.read(fd, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        out += chunk
    _, status = os.waitpid(pid, 0)
    text = out.decode()
    assert os.waitstatus_to_exitcode(status) == 0, text
    return text


@pytest.mark.skipif(not hasattr(os, "fork"), reason="a pseudo-terminal needs fork")
def test_a_terminal_that_reports_no_size_still_sees_the_bar(tmp_path):
    """A pseudo-terminal never sized (``script``, some containers' ttys)
    reports 0 columns and 0 rows (``os.get_terminal_size``), and tqdm then
    drew nothing: a long run was silent on it. The bar is drawn 80
    columns wide there."""
    np.save(tmp_path / "box.npy", np.ones((6, 7, 8), bool))
    text = on_a_pseudo_terminal(["flow", str(tmp_path / "box.npy"), "--steps", "2"])
    assert text.split()[:2] == ["0", "0"]  # the terminal reports no size
    assert "flow:" in text and "%|" in text, text


@pytest.mark.skipif(not hasattr(os, "fork"), reason="a pseudo-terminal needs fork")
def test_a_terminal_of_columns_and_no_rows_sees_the_bar(tmp_path):
    """A terminal that reports its columns and 0 rows (``stty rows 0``,
    some CI terminals) showed no bar: tqdm reads its row as below the
    screen. It is drawn there, within the columns the terminal reports."""
    np.save(tmp_path / "box.npy", np.ones((6, 7, 8), bool))
    text = on_a_pseudo_terminal(["flow", str(tmp_path / "box.npy"), "--steps", "2"],
                                "import fcntl, struct, termios; "
                                f"fcntl.ioctl(2, termios.TIOCSWINSZ, {struct.pack('HHHH', 0, 100, 0, 0)!r})")
    assert text.split()[:2] == ["100", "0"]  # as stty rows 0 sets it
    assert "flow:" in text and "%|" in text, text
    bar = next(line for line in text.split("\r") if "%|" in line)
    assert len(bar) <= 100


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
@pytest.mark.parametrize("when", ["check_streamed", "never_written"])
def test_a_signal_during_a_stores_read_back_says_the_file_is_written(tmp_path, capsys, monkeypatch, when):
    """Ctrl-C while a store's surface, written block by block, is read back
    in chunks, or once it is in place before that (while the store is
    looked over for chunks never written): exit 130 and one line saying
    the file is there and only its check was cut short, as for a volume
    in memory (it said only "interrupted"); the file is the whole surface,
    as trimesh reads it."""
    import trimesh

    zarr = pytest.importorskip("zarr")
    from isoflow.mesh import streamed_readback
    from isoflow.scale import chunks

    v = np.pad(np.ones((3, 4, 5), bool), 1)
    zarr.create_array(store=str(tmp_path / "v.zarr"), shape=v.shape, chunks=(2, 3, 4), dtype=bool)[...] = v
    module = streamed_readback if when == "check_streamed" else chunks
    work = getattr(module, when)

    def interrupted(*args, **kw):
        os.kill(os.getpid(), signal.SIGINT)
        return work(*args, **kw)

    monkeypatch.setattr(module, when, interrupted)
    out = tmp_path / "s.ply"
    assert main(["surface", str(tmp_path / "v.zarr"), "-o", str(out), "-q"]) == 130
    assert capsys.readouterr().err.strip().splitlines() == [
        f"isoflow: interrupted: {out} is written, not read back (--no-check skips the read-back)"]
    mesh = trimesh.load(out, process=False)
    assert mesh.is_watertight and mesh.volume == pytest.approx(60)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
@pytest.mark.parametrize("check", [True, False])
def test_a_signal_between_the_write_and_the_read_back_says_the_file_is_written(tmp_path, capsys, monkeypatch, check):
    """Ctrl-C after the surface is renamed into place but before its
    read-back begins (while its closed surfaces are counted): the file is
    whole, so the last line says it is written (it said only
    "interrupted"), and names --no-check only where the check was asked."""
    import trimesh

    from isoflow.digital.surface import QuadMesh

    np.save(tmp_path / "v.npy", np.pad(np.ones((3, 3, 3), bool), 1))
    components = QuadMesh.components

    def interrupted(self):
        os.kill(os.getpid(), signal.SIGINT)
        return components(self)

    monkeypatch.setattr(QuadMesh, "components", interrupted)
    out = tmp_path / "s.ply"
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(out), "-q", *([] if check else ["--no-check"])]) == 130
    hint = " (--no-check skips the read-back)" if check else ""
    assert capsys.readouterr().err.strip().splitlines() == [f"isoflow: interrupted: {out} is written, not read back{hint}"]
    mesh = trimesh.load(out, process=False)
    assert mesh.is_watertight and mesh.volume == pytest.approx(27)

