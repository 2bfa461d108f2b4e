"""Standard error that cannot take a line (a full disk or quota under
``2> log``, ``/dev/full`` stands for one; a descriptor closed by ``2>&-``;
no stderr at all): the line is lost, the command's work and exit status are
as they would be. A note printed before the report ended the command in a
traceback, exit status 1 and no report."""

import json
import os
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SRC = str(Path(__file__).resolve().parents[1] / "src")


@pytest.fixture
def plate(tmp_path):
    """A plate one voxel thick along x, whose reading as 3D is said in a note."""
    volume = np.zeros((1, 6, 7), bool)
    volume[0, 1:5, 1:6] = True
    volume[0, 2:4, 2:4] = False  # a hole: chi 0
    np.save(tmp_path / "plate.npy", volume)
    return tmp_path


def run(cwd: Path, argv: list[str], stderr) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": SRC}
    return subprocess.run([sys.executable, "-m", "isoflow", *argv], cwd=cwd, env=env, stdout=subprocess.PIPE,
                          stderr=stderr, text=True, timeout=300)


def expected(plate: Path) -> tuple[int, int]:
    from skimage.measure import euler_number

    volume = np.load(plate / "plate.npy")
    return int(euler_number(np.pad(volume, 1), connectivity=1)), int(volume.sum())


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
def test_a_note_that_stderr_cannot_take_leaves_the_report_as_it_is(plate):
    with open("/dev/full", "w") as full:
        done = run(plate, ["info", "plate.npy", "--json"], full)
    assert done.returncode == 0
    report = json.loads(done.stdout)
    assert (report["euler_characteristic"], report["voxels"]) == expected(plate) == (0, 16)
    with open("/dev/full", "w") as full:
        bad = run(plate, ["info", "missing.npy"], full)
    assert bad.returncode == 2 and bad.stdout == ""


@pytest.mark.skipif(not os.path.exists("/bin/sh"), reason="needs a POSIX shell to close standard error")
def test_a_closed_stderr_leaves_the_report_as_it_is(plate):
    env = {**os.environ, "PYTHONPATH": SRC}
    line = " ".join(map(shlex.quote, [sys.executable, "-m", "isoflow", "info", "plate.npy", "--json"]))
    done = subprocess.run(["/bin/sh", "-c", f"exec {line} 2>&-"], cwd=plate, env=env, stdout=subprocess.PIPE,
                          text=True, timeout=300)
    assert done.returncode == 0
    report = json.loads(done.stdout)
    assert (report["euler_characteristic"], report["voxels"]) == expected(plate)


def test_without_stderr_a_note_stays_out_of_standard_output(plate, monkeypatch, capsys):
    """Where Python has no stderr, print(file=sys.stderr) writes to
    standard output: the note went into the --json report."""
    from isoflow.cli.main import main

    monkeypatch.chdir(plate)
    monkeypatch.setattr(sys, "stderr", None)
    assert main(["info", "plate.npy", "--json"]) == 0
    monkeypatch.undo()
    report = json.loads(capsys.readouterr().out)
    assert (report["euler_characteristic"], report["voxels"]) == expected(plate)
