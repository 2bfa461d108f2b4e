"""The peak of each part of ``isoflow surface``, in process, against its estimate.

    python benchmarks/surface_memory.py VOLUME.npy OUT.stl [--ascii] [--triangulate] [--png P.png] [--no-check]
    python benchmarks/surface_memory.py --numpy VOLUME.npy OUT.ply    # meshed by the NumPy passes

Runs the command through ``isoflow.cli.main`` (``--force --quiet``) with
the memory check, the writer, the read-back and the picture wrapped. The
peak (``VmHWM``) is reset by writing ``5`` to ``/proc/self/clear_refs``
at the check and before the read-back and the picture; each part's
growth is its peak less ``VmRSS`` when it began. Prints one JSON line:
``rss_at_check``, ``mesh_estimate`` and ``mesh_peak_above_check`` (the
check to the end of the write), ``readback_estimate`` (``readback_fixed``
of it), ``rss_at_readback`` (``VmRSS`` as it begins) and
``readback_growth``, ``png_growth``, and ``peak``, the whole process's
(the largest ``VmHWM`` before each reset and at the end, what
``/usr/bin/time -f %M`` gives); bytes. ``--numpy``: the mesh made by
``method="numpy"`` (the command takes it below 159^3), the rest of the
command as it runs. Linux only. docs/surface.md, "Memory: the check
before meshing".
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def status() -> tuple[int, int]:
    """Resident bytes now and at the peak since the last reset."""
    fields = dict(line.split(":", 1) for line in open("/proc/self/status"))
    return int(fields["VmRSS"].split()[0]) * 1024, int(fields["VmHWM"].split()[0]) * 1024


PEAK = [0]  # the process's peak, kept across the resets


def reset_peak() -> None:
    PEAK[0] = max(PEAK[0], status()[1])
    Path("/proc/self/clear_refs").write_text("5")


def main(argv: list[str]) -> int:
    numpy_passes = argv[:1] == ["--numpy"]
    argv = argv[numpy_passes:]
    from isoflow.cli import main as cli
    from isoflow.mesh import export, readback, render
    from isoflow.mesh.outputs import staged
    from isoflow.scale import memory

    rec: dict = {}
    fits, write, check, draw = memory.check_fits, export.write_mesh_file, readback.check_surface_file, render.render_surface

    def fits_at(need, what, *args, **kwargs):
        if "boundary mesh" in what:
            rec["mesh_estimate"], rec["rss_at_check"] = int(need), status()[0]
            reset_peak()
        return fits(need, what, *args, **kwargs)

    def write_at(*args, **kwargs):
        done = write(*args, **kwargs)
        rec["mesh_peak_above_check"] = status()[1] - rec["rss_at_check"]
        return done

    def check_at(path, mesh, obj, **kwargs):
        rec["readback_estimate"] = readback.readback_memory(mesh, Path(path).suffix, readback.text_lines(staged(path)))
        rec["readback_fixed"] = readback.readback_fixed()
        rss = rec["rss_at_readback"] = status()[0]
        reset_peak()
        done = check(path, mesh, obj, **kwargs)
        rec["readback_growth"], rec["skipped"] = status()[1] - rss, done.get("skipped")
        return done

    def draw_at(*args, **kwargs):
        rss = status()[0]
        reset_peak()
        done = draw(*args, **kwargs)
        rec["png_growth"] = status()[1] - rss
        return done

    if numpy_passes:  # the mesh as method="numpy" makes it (the command takes it below 159^3), the rest as it is
        from isoflow.digital import surface

        how = surface.mesh_method
        surface.mesh_method = lambda volume, method="auto", record=False: how(
            volume, "numpy" if method == "auto" else method, record)
    memory.check_fits, export.write_mesh_file, readback.check_surface_file, render.render_surface = \
        fits_at, write_at, check_at, draw_at
    rec["code"] = cli(["surface", argv[0], "-o", *argv[1:], "--force", "--quiet"])
    rec["args"] = " ".join(Path(a).name for a in argv)
    rec["peak"] = max(PEAK[0], status()[1])
    print(json.dumps(rec))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
