"""A flow run that is killed leaves the output directory as it was.

SIGTERM (``kill``, a batch system's time limit) cleans up as Ctrl-C does;
SIGKILL cannot be caught, so the next run into the directory removes what
a killed run left (``isoflow.mesh.outputs.remove_abandoned``, whose own
tests are in tests/mesh/test_outputs.py). Both on real processes."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from isoflow.flow.files import STAGE
from isoflow.mesh.outputs import TEMP_MARK

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")


def ball(n: int = 48) -> np.ndarray:
    g = np.indices((n, n, n)) - n / 2 + 0.5
    return (g**2).sum(0) < (0.42 * n) ** 2


def stages(directory):
    return sorted(directory.glob(f".{STAGE}{TEMP_MARK}*"))


def start_flow(tmp_path, out, *extra):
    np.save(tmp_path / "ball.npy", ball())
    return subprocess.Popen([sys.executable, "-m", "isoflow.cli", "flow", str(tmp_path / "ball.npy"), "--out",
                             str(out), *extra], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def wait_for_step_files(proc, out, timeout=60.0):
    """Wait until the run has written step files into its staging directory."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        # (a glob is a generator, true even when it finds nothing)
        if any(next(s.glob("step_*.ply"), None) is not None for s in stages(out)):
            return
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.02)
    raise AssertionError("the flow wrote no step file in time")


def test_sigterm_leaves_the_previous_run_and_no_staging_directory(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "flow.csv").write_text("the previous run\n")
    (out / "step_000.ply").write_text("previous\n")
    proc = start_flow(tmp_path, out, "--force")
    wait_for_step_files(proc, out)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    # the shell's convention for a process ended by SIGTERM: 128 + 15
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert err.startswith("isoflow: terminated") and len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err
    assert sorted(p.name for p in out.iterdir()) == ["flow.csv", "step_000.ply"]
    assert (out / "flow.csv").read_text() == "the previous run\n"
    assert stages(out) == []


def test_a_killed_runs_staging_directory_is_removed_by_the_next_run(tmp_path):
    out = tmp_path / "run"
    proc = start_flow(tmp_path, out)
    wait_for_step_files(proc, out)
    proc.send_signal(signal.SIGKILL)  # no clean-up can run
    proc.communicate(timeout=60)
    (left,) = stages(out)
    assert f"-{proc.pid}-" in left.name  # the name says whose it is
    # the next run into the directory: it is empty but for the abandoned
    # staging directory, so no --force is needed, and nothing is left of it
    rerun = subprocess.run([sys.executable, "-m", "isoflow.cli", "flow", str(tmp_path / "ball.npy"), "--out",
                            str(out), "--steps", "2", "-q"], capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stderr
    assert stages(out) == []
    assert sorted(p.name for p in out.glob("step_*.ply")) == ["step_000.ply", "step_001.ply", "step_002.ply"]



def test_a_killed_commits_step_entries_moved_aside_are_put_back_or_removed(tmp_path):
    """A run killed while it put its files in place (between moving a
    previous run's step store aside and renaming its own in) left that
    store at its hidden aside name alone: the next run into the directory
    puts it back under its name, whole, and removes the aside of a step
    whose new entry was in place, before it decides that the directory
    holds files."""
    import hashlib
    import os
    import socket

    out = tmp_path / "run"
    out.mkdir()
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()  # its pid is free now (until reused)
    host = hashlib.sha1(socket.gethostname().encode()).hexdigest()[:8]
    # named as isoflow.mesh.outputs.aside_name names them (docs/cli.md)
    missing = out / f".step_003.isoflow-old-{host}-{ended.pid}-0123abcd.zarr"
    (missing / "0").mkdir(parents=True)
    (missing / ".zgroup").write_text('{"zarr_format": 2}')
    (missing / "0" / "0.0.0").write_bytes(b"the previous run's step 3")
    replaced = out / f".step_002.isoflow-old-{host}-{ended.pid}-4567abcd.ply"
    replaced.write_bytes(b"the previous run's step 2")
    (out / "step_002.ply").write_bytes(b"the killed run's step 2, in place")
    running = out / f".step_004.isoflow-old-{host}-{os.getpid()}-89abcdef.ply"
    running.write_bytes(b"a running command's")
    np.save(tmp_path / "ball.npy", ball(8))
    rerun = subprocess.run([sys.executable, "-m", "isoflow.cli", "flow", str(tmp_path / "ball.npy"), "--out",
                            str(out), "--steps", "1", "-q"], capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 2, rerun.stderr
    assert "directory is not empty; pass --force" in rerun.stderr and "Traceback" not in rerun.stderr
    warned = [line for line in rerun.stderr.splitlines() if "warning" in line]
    assert len(warned) == 1 and "step_003.zarr" in warned[0] and missing.name in warned[0], rerun.stderr
    assert (out / "step_003.zarr" / "0" / "0.0.0").read_bytes() == b"the previous run's step 3"
    assert sorted(p.name for p in out.iterdir()) == sorted(["step_002.ply", "step_003.zarr", running.name])
    assert running.read_bytes() == b"a running command's"
