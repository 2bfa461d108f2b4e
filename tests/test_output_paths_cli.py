"""Output paths as a user gives them, run as the user runs the command (a
subprocess): a suffix in any case, an existing output replaced with
--force, outputs that collide; the file is read back by its own library."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
TORUS = ROOT / "meshes" / "torus.obj"


def run(*args) -> subprocess.CompletedProcess:
    """The command line in a subprocess, as a user runs it."""
    return subprocess.run([sys.executable, "-m", "isoflow", *map(str, args)], capture_output=True, text=True)


@pytest.mark.parametrize("suffix", [".Nii", ".Nii.gz"])
def test_a_nifti_suffix_in_mixed_case_is_the_file_written(tmp_path, suffix):
    # nib.save wrote "torus.nii(.gz)" beside the named file and left the named one empty, over the old one
    nib = pytest.importorskip("nibabel")
    out = tmp_path / f"torus{suffix}"
    out.write_bytes(b"old")
    p = run("voxelize", TORUS, "--resolution", 16, "-o", out, "--force", "-q")
    assert p.returncode == 0, p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == [out.name]  # no stray or temporary file
    img = nib.Nifti1Image.from_file_map(nib.Nifti1Image.make_file_map({"image": str(out)}))
    assert int(np.asarray(img.dataobj).sum()) > 0
    back = run("info", out, "--json")  # and isoflow reads the file it wrote
    assert back.returncode == 0, back.stderr
