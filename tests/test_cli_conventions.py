"""The command line as people expect it: --version, the command list, --quiet
on every command, progress bars only on a terminal, shell completion."""

from __future__ import annotations

import fcntl
import importlib.metadata
import io
import os
import shutil
import struct
import subprocess
import sys
import termios
from pathlib import Path

import numpy as np
import pytest

import isoflow
from conftest import torus
from isoflow.cli import main

ROOT = Path(__file__).resolve().parents[1]
TORUS = ROOT / "meshes" / "torus.obj"
COMMANDS = ("info", "surface", "voxelize", "genus", "flow", "completion")


def isoflow_cmd(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "isoflow.cli", *map(str, args)],
                          capture_output=True, text=True, **kwargs)


class Terminal(io.StringIO):
    """A stderr that says it is a terminal and keeps what is written."""

    def isatty(self):
        return True


def stderr_of(monkeypatch, stream, argv) -> str:
    monkeypatch.setattr(sys, "stderr", stream)
    assert main([str(a) for a in argv]) == 0
    monkeypatch.undo()
    return stream.getvalue()


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


def test_zsh_and_tcsh_scripts(capsys):
    assert main(["completion", "zsh"]) == 0
    assert capsys.readouterr().out.startswith("#compdef isoflow")
    assert main(["completion", "tcsh"]) == 0
    assert "complete isoflow" in capsys.readouterr().out
    with pytest.raises(SystemExit) as bad:
        main(["completion", "cmd.exe"])
    assert bad.value.code == 2 and "invalid choice" in capsys.readouterr().err
