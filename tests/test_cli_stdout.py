"""Standard output that cannot take the command's output (a full disk or
quota under a redirection; ``/dev/full`` stands for one): one line naming
standard output and the system's words for the cause, exit status 2, never
a traceback; a pipe closed early (``| head``) is no error."""

import errno
import os
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SRC = str(Path(__file__).resolve().parents[1] / "src")
ARGVS = [["info", "blob.npy", "--json"], ["info", "blob.npy"], ["completion", "bash"],
         ["info", "labels.npy", "--labels", "--csv", "-"], ["flow", "blob.npy", "--json"]]


def isoflow(cwd: Path, argv: list[str], stdout) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": SRC}
    return subprocess.run([sys.executable, "-m", "isoflow", *argv], cwd=cwd, env=env, stdout=stdout,
                          stderr=subprocess.PIPE, text=True, timeout=300)


@pytest.fixture
def inputs(tmp_path):
    blob = np.zeros((5, 5, 5), bool)
    blob[1:4, 1:4, 1:4] = True
    np.save(tmp_path / "blob.npy", blob)
    np.save(tmp_path / "labels.npy", blob.astype(np.uint8) * 3)
    return tmp_path


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
@pytest.mark.parametrize("argv", ARGVS, ids=lambda a: " ".join(a))
def test_a_full_standard_output_is_one_line(inputs, argv):
    with open("/dev/full", "w") as full:
        done = isoflow(inputs, argv, full)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert lines[-1] == f"isoflow {argv[0]}: error: standard output: cannot be written ({os.strerror(errno.ENOSPC)})"


def test_a_pipe_closed_early_is_no_error(inputs):
    env = {**os.environ, "PYTHONPATH": SRC}
    labels = np.zeros((40, 40, 40), np.uint16)
    labels.reshape(-1)[::16] = np.arange(1, labels.size // 16 + 1)  # 4000 labels: more than a pipe's buffer
    np.save(inputs / "many.npy", labels)
    with subprocess.Popen([sys.executable, "-m", "isoflow", "info", "many.npy", "--labels", "--csv", "-"],
                          cwd=inputs, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as proc:
        assert proc.stdout.read(10) == b"label,voxe"
        proc.stdout.close()
        err = proc.stderr.read().decode()
        assert proc.wait(timeout=300) == 0 and "Traceback" not in err and "Error" not in err, err


@pytest.mark.parametrize("encoding", ["cp1252", "ascii"])
def test_an_encoding_without_a_printed_character_is_written_escaped(inputs, encoding):
    """Standard output in an encoding that lacks a character the report
    prints (the class ``(0,0,∅)``: cp1252 is Windows' for a redirection,
    ``> report.txt``) ended ``isoflow info`` in UnicodeEncodeError."""
    from skimage.measure import euler_number

    blob = np.load(inputs / "blob.npy")
    blob[2, 2, :] = False  # a tunnel: chi 0
    np.save(inputs / "ring.npy", blob)
    env = {**os.environ, "PYTHONPATH": SRC, "PYTHONIOENCODING": encoding}
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", "ring.npy"], cwd=inputs, env=env,
                          capture_output=True, timeout=300)
    assert done.returncode == 0 and b"Traceback" not in done.stderr, done.stderr.decode()
    text = done.stdout.decode(encoding)
    chi = next(line.split()[-1] for line in text.splitlines() if line.strip().startswith("Euler characteristic"))
    assert int(chi) == euler_number(blob, connectivity=1) == 0
    assert "(0,0,\\u2205)" in text


@pytest.mark.skipif(not os.path.exists("/bin/sh"), reason="needs a POSIX shell to close standard output")
@pytest.mark.parametrize("argv", [["info", "blob.npy", "--json"], ["completion", "bash"]], ids=" ".join)
def test_a_closed_standard_output_is_one_line(inputs, argv):
    """Started with standard output closed (``>&-``), Python sets
    sys.stdout to None and print() drops what it is given: the report was
    lost and the command ended with exit status 0."""
    env = {**os.environ, "PYTHONPATH": SRC}
    line = " ".join(map(shlex.quote, [sys.executable, "-m", "isoflow", *argv]))
    done = subprocess.run(["/bin/sh", "-c", f"exec {line} >&-"], cwd=inputs, env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 2, done.stderr
    assert done.stderr == (f"isoflow {argv[0]}: error: standard output: cannot be written "
                           f"({os.strerror(errno.EBADF)})\n")


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
@pytest.mark.parametrize("argv", [[], ["--version"], ["-h"], ["info", "-h"]], ids=lambda a: " ".join(a) or "alone")
def test_what_is_printed_before_a_command_runs_fails_as_a_command_does(tmp_path, argv):
    """``isoflow`` alone and ``--version`` ended in a traceback (exit
    status 1) where standard output could not take them, and ``-h``, whose
    failure argparse drops, in exit status 0 with the help lost."""
    prog = " ".join(["isoflow", *argv[:1]]) if argv[:1] == ["info"] else "isoflow"
    with open("/dev/full", "w") as full:
        done = isoflow(tmp_path, argv, full)
    assert done.returncode == 2, done.stderr
    assert done.stderr == f"{prog}: error: standard output: cannot be written ({os.strerror(errno.ENOSPC)})\n"
    env = {**os.environ, "PYTHONPATH": SRC}
    line = " ".join(map(shlex.quote, [sys.executable, "-m", "isoflow", *argv]))
    closed = subprocess.run(["/bin/sh", "-c", f"exec {line} >&-"], cwd=tmp_path, env=env, capture_output=True,
                            text=True, timeout=300)
    assert closed.returncode == 2, closed.stderr
    assert closed.stderr == f"{prog}: error: standard output: cannot be written ({os.strerror(errno.EBADF)})\n"
