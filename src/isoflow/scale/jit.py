"""numba's ``njit``, for every compiled pass of isoflow, with one start-up
cost taken off.

numba's first call of any function, even one loaded from its disk cache,
imports every implementation module it has. One of them
(``numba.np.arraymath``) imports ``scipy.linalg`` at import time only to
check that BLAS exists, an import that is a noticeable share of a short
command (``benchmarks/run.py`` times whole commands). isoflow's kernels use no BLAS, and
scipy, a dependency, provides it. So that module is imported here with the
check answered "yes" without the import, and the real check is put back at
once. numba's linear algebra, where anyone uses it, still imports scipy and
checks it when the function is compiled (``numba.np.linalg`` calls the
check there).

If numba has already been started in this process, or a numba version
lacks these names, nothing changes.

It also listens for numba's compile events: numba compiles a function only
where its disk cache has none, so the first one of isoflow's says
:data:`isoflow.scale.compiled.COMPILE_NOTE` (the command line prints it;
the first run after installing otherwise waits in silence).

Once numba is imported it calls
:data:`isoflow.scale.compiled.on_numba_import` where that is set (the
command line freezes numba's objects there, which live until it exits).
"""

from __future__ import annotations

from numba import njit

from . import compiled

__all__ = ["njit"]


def _import_arraymath_without_blas_probe() -> None:
    import sys

    if "numba.np.arraymath" in sys.modules:  # numba started already
        return
    try:
        from numba.np import linalg
    except ImportError:  # pragma: no cover - another numba layout
        return
    probe = getattr(linalg, "ensure_blas", None)
    if probe is None:  # pragma: no cover
        return
    linalg.ensure_blas = lambda: None
    try:
        from numba.np import arraymath
    except ImportError:  # pragma: no cover
        return
    finally:
        linalg.ensure_blas = probe
    if getattr(arraymath, "ensure_blas", None) is not None:
        arraymath.ensure_blas = probe  # later calls check for real


def _note_compiles() -> None:
    try:
        from numba.core import event
    except ImportError:  # pragma: no cover - another numba layout
        return

    from .compiled import note_compile

    class FirstCompile(event.Listener):
        def on_start(self, ev):
            func = getattr(ev.data.get("dispatcher"), "py_func", None)
            if getattr(func, "__module__", "").startswith("isoflow."):
                note_compile()

        def on_end(self, ev):
            pass

    event.register("numba:compile", FirstCompile())


def _plain_error_messages() -> None:
    """numba's messages as plain text, without colorama.

    numba marks up the text of its errors (also those it makes and drops
    while it types a function) inside colorama's ``init()`` ... ``deinit()``,
    which replace ``sys.stderr`` with a wrapper and then put back the stream
    ``init()`` found. Compiling on one thread (the info command warms numba
    up while the main thread reads the input) while another replaces
    ``sys.stderr`` (``contextlib.redirect_stderr``, pytest's capsys) leaves
    ``sys.stderr`` set to a stale stream afterwards: what is printed next
    goes there. Plain text needs no terminal state; the default scheme
    (``no_color``) only made the text bold."""
    try:
        from numba.core import config, errors
    except ImportError:  # pragma: no cover - another numba layout
        return
    if getattr(config, "COLOR_SCHEME", None) != "no_color" or not hasattr(errors, "termcolor"):
        return  # colours a user asked for (NUMBA_COLOR_SCHEME), or another layout
    # numba's modules keep the one instance termcolor() made (ir, typeinfer,
    # typeof, ...): its markup is made plain rather than the instance replaced
    scheme = errors.termcolor()
    if hasattr(scheme, "_markup"):
        scheme._markup = lambda msg, color=None, style=None: msg


_import_arraymath_without_blas_probe()
_note_compiles()
_plain_error_messages()
if compiled.on_numba_import is not None:
    compiled.on_numba_import()
