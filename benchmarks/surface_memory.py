"""The peak of each part of ``isoflow surface``, in process, against its estimate.

    python benchmarks/surface_memory.py VOLUME.npy OUT.stl [--ascii] [--triangulate] [--png P.png]

Runs the command through ``isoflow.cli.main`` (``--force --quiet``) with
the memory check, the writer, the read-back and the picture wrapped. The
peak (``VmHWM``) is reset by writing ``5`` to ``/proc/self/clear_refs``
at the check and before the read-back and the picture; each part's
growth is its peak less ``VmRSS`` when it began. Prints one JSON line:
``mesh_estimate`` and ``mesh_peak_above_check`` (the check to the end of
the write), ``readback_estimate`` and ``readback_growth``, ``png_growth``;
bytes. Linux only. docs/surface.md, "Memory: the check before meshing".
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def status() -> tuple[int, int]:
    """Resident bytes now and at the peak since the last reset."""
    fields = dict(line.split(":", 1) for line in open("/proc/self/status"))
    return int(fields["VmRSS"].split()[0]) * 1024, int(fields["VmHWM"].split()[0]) * 1024


def reset_peak() -> None:
    Path("/proc/self/clear_refs").write_text("5")


def main(argv: list[str]) -> int:
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
        rss = status()[0]
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

    memory.check_fits, export.write_mesh_file, readback.check_surface_file, render.render_surface = \
        fits_at, write_at, check_at, draw_at
    rec["code"] = cli(["surface", argv[0], "-o", *argv[1:], "--force", "--quiet"])
    rec["args"] = " ".join(Path(a).name for a in argv)
    print(json.dumps(rec))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
