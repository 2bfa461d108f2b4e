"""Every IsoflowWarning is attributed to the caller's own line, however deep
inside isoflow it is raised, as NumPy's and pandas' warnings are."""

from __future__ import annotations

import inspect
import os
import subprocess
import sys
import warnings

import numpy as np

import isoflow
from isoflow import DigitalObject, IsoflowWarning


def here() -> int:
    """The line after the caller's."""
    return inspect.currentframe().f_back.f_lineno + 1


def test_warnings_name_the_callers_line(tmp_path):
    zarr = __import__("pytest").importorskip("zarr")
    store = zarr.create_array(str(tmp_path / "v.zarr"), shape=(4, 4, 4), chunks=(2, 4, 4), dtype="u1", fill_value=1)
    store[:2] = 0  # the other chunk is never written: read as the fill value
    with warnings.catch_warnings(record=True) as out:
        warnings.simplefilter("always")
        lines = [here()]
        isoflow.write_volume(DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5), tmp_path / "v.npy")
        lines.append(here())
        isoflow.write_labels(np.ones((2, 2, 2), np.uint8), tmp_path / "v.vox", pitch=0.5)
        lines.append(here())
        isoflow.read_volume(tmp_path / "v.zarr")
    found = [w for w in out if issubclass(w.category, IsoflowWarning)]
    assert ["npy", "MagicaVoxel", "never written"] == [
        next(k for k in ("npy", "MagicaVoxel", "never written") if k in str(w.message)) for w in found]
    assert [(w.filename, w.lineno) for w in found] == [(__file__, n) for n in lines]


def test_warning_from_a_users_script(tmp_path):
    script = tmp_path / "user.py"
    script.write_text("import warnings\n"
                      "import numpy as np\n"
                      "import isoflow\n"
                      "with warnings.catch_warnings(record=True) as out:\n"
                      "    warnings.simplefilter('always')\n"
                      "    isoflow.write_labels(np.ones((2, 2, 2), np.uint8), 'v.vox', pitch=0.5)\n"
                      "print(out[0].filename, out[0].lineno)\n")
    run = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == [str(script), "6"]
