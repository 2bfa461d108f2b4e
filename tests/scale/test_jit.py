"""numba started by isoflow skips only its import-time BLAS probe
(scale/jit.py): a large volume's report never imports scipy.linalg, and
numba's linear algebra still works afterwards. Run in a fresh process, as a
command runs."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from isoflow.scale import compiled

pytestmark = pytest.mark.skipif(not compiled.have_numba(), reason="numba not installed")


def test_compiled_report_does_not_import_scipy_linalg_and_numba_blas_still_works():
    script = textwrap.dedent("""
        import sys
        import numpy as np
        from isoflow.digital.analysis import analyze
        from isoflow.scale.compiled import use_compiled

        rng = np.random.default_rng(7)
        vol = rng.random((SIDE,) * 3) < 0.3  # edge and vertex contacts everywhere
        assert use_compiled(vol)
        report = analyze(vol, 6, surfaces=False)
        print("scipy.linalg" in sys.modules)
        from skimage.measure import euler_number  # (imports scipy.linalg)

        assert report["euler_characteristic"] == euler_number(vol, connectivity=1)

        # the probe is back: numba's np.dot compiles, through scipy's BLAS
        import numba.np.arraymath as arraymath
        import numba.np.linalg as linalg
        assert arraymath.ensure_blas is linalg.ensure_blas
        assert linalg.ensure_blas.__module__ == "numba.np.linalg"
        from numba import njit

        a, b = rng.random((3, 4)), rng.random((4, 2))
        assert np.allclose(njit(lambda x, y: np.dot(x, y))(a, b), a @ b)
        print("scipy.linalg" in sys.modules)
    """)
    from conftest import compiled_side

    script = script.replace("SIDE", str(compiled_side()))
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "True"]


def test_numba_messages_leave_sys_stderr_alone(monkeypatch):
    """numba marked up its messages (also those it makes and drops while it
    types) between colorama's init() and deinit(), which swap sys.stderr for
    a wrapper and put back the stream init() saw: a compile on one thread
    while another had replaced sys.stderr (capsys, redirect_stderr) left the
    stale stream in place, and an isoflow command's error line went there
    (the suite's rare "no line on stderr" failures)."""
    from numba.core import errors

    import isoflow.scale.jit  # noqa: F401  (what every compiled pass imports)

    swapped = []
    monkeypatch.setattr(errors, "init", lambda *a, **k: swapped.append("init"), raising=False)
    monkeypatch.setattr(errors, "deinit", lambda *a, **k: swapped.append("deinit"), raising=False)
    scheme = errors.termcolor()
    assert [scheme.errmsg("a"), scheme.highlight("b"), scheme.code("c"), scheme.reset("d")] == ["a", "b", "c", "d"]
    assert swapped == []
