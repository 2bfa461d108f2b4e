"""Heavy imports begun ahead, on a thread of their own, while a command
works.

``surface --labels`` reads the surfaces it writes back with trimesh, whose
import (scipy and networkx behind it) would otherwise be paid after the
surfaces are made, on the way to the answer. Their making runs mostly in
compiled passes that release Python's lock, so trimesh imported on another
thread meanwhile takes little from the main thread. Where the main thread
has little such work (one small surface), the two threads only contend for
the lock, and the command is slower: ``surface`` of one object does not
import ahead.

The main thread joins the thread before its first use of the module: a
``from trimesh.exchange.gltf import load_glb`` made while the other thread
is still inside ``import trimesh`` finds the package half made (Python
waits for a module being imported elsewhere only when it is the one
named, not for its parent package) and fails. Until the join the main
thread must import nothing the module imports.

The thread only imports: it is a daemon (it never holds up the process's
exit); signals are handled on the main thread as before (the handlers run
there only, so trimesh's import guards, which catch every exception, find
no KeyboardInterrupt to swallow on the thread), and the join is
interrupted by them as any wait is; an import that fails there is left for
the main thread's own import of the module to raise as it always has (a
failed import leaves no module behind).
"""

from __future__ import annotations

import importlib
import threading

#: the name of the thread that imports ahead
THREAD_NAME = "isoflow: importing ahead"


def import_ahead(*names: str) -> threading.Thread:
    """Import the modules ``names``, in order, on a daemon thread started
    now; the thread stops at the first that fails to import, and says
    nothing: the caller's own import of it raises the error. The caller
    joins the thread before it uses any of them (see the module's notes).

    Parameters
    ----------
    *names : str
        Modules' full names (``"trimesh"``).

    Returns
    -------
    threading.Thread
        The thread, started.

    Examples
    --------
    >>> import sys
    >>> import_ahead("colorsys", "no_such_module_here").join()
    >>> "colorsys" in sys.modules, "no_such_module_here" in sys.modules
    (True, False)
    """
    def run() -> None:
        for name in names:
            try:
                importlib.import_module(name)
            except Exception:  # the main thread's own import raises it, in its place
                return

    thread = threading.Thread(target=run, name=THREAD_NAME, daemon=True)
    thread.start()
    return thread
