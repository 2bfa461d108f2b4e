"""The boundary mesh against VTK's flying edges, in memory and as commands.

    python benchmarks/bench_mesh.py                        # 512^3 ball and porous, 3 rounds
    python benchmarks/bench_mesh.py --sizes 256 --repeat 5
    python benchmarks/bench_mesh.py --small                # where method="auto" switches

Every measurement runs in a fresh process; the tools of one round run one
after another on the same input, so that a busy machine slows the pair
alike, and the table gives medians over the rounds and the median of the
per-round ratios.

* ``isoflow``: ``boundary_mesh(volume, 6)`` (``method="auto"``: the bit
  rows at these sizes), the mesh with its per-vertex configuration and
  sheet, from which every attribute (class, gamma, a, f, code, normal) is a
  table look-up;
* ``vtk``: pyvista's ``contour([0.5], method="flying_edges")`` on the same
  volume as uint8 image data (VTK's flying edges, the defaults: point
  scalars, no normals);
* ``numpy``: ``boundary_mesh(..., method="numpy")``, the NumPy mesh (with
  ``--numpy``; it is slow at 512^3);
* ``command``: ``isoflow surface IN.npy -o OUT.ply`` as a user runs it:
  load, mesh, write the binary PLY, read it back with trimesh and compare
  (whole process, imports included).

Time: the call alone (after a warm-up call on a tiny volume, which imports
the tool and loads numba's cached passes). Peak: the call's peak resident
memory above the resident memory before it (``/proc/self/clear_refs`` then
``ru_maxrss``), the input volume already loaded; for the command, the
process's ``ru_maxrss``.

``--small`` runs the cold start that ``method="auto"`` weighs: a fresh
process that meshes one volume of 96^3 .. 192^3 with each method, imports
and numba's start included.

Inputs are benchmarks/run.py's (a ball of radius 0.45 n and a smoothed
random porous field), cached as .npy in benchmarks/.cache/. Results go to
benchmarks/results/mesh.json (no absolute paths).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

from run import ensure_input  # noqa: E402  (benchmarks/run.py: the shared inputs)


def _rss() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _reset_peak() -> None:
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def _maxrss() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _isoflow(method):
    from isoflow.digital.surface import boundary_mesh

    def run(vol):
        m = boundary_mesh(vol, 6, method=method)
        return {"vertices": len(m.vertices), "faces": len(m.faces), "midpoints": m.midpoints}

    return run


def _vtk():
    import pyvista as pv

    def run(vol):
        m = pv.wrap(vol.view(np.uint8)).contour([0.5], method="flying_edges")
        return {"vertices": int(m.n_points), "triangles": int(m.n_cells)}

    return run


TOOLS = {"isoflow": lambda: _isoflow("auto"), "numpy": lambda: _isoflow("numpy"), "vtk": _vtk}


def child(tool: str, path: str) -> dict:
    """One call of one tool on one input, in this (fresh) process."""
    run = TOOLS[tool]()
    tiny = np.zeros((6, 7, 8), bool)
    tiny[1:5, 1:6, 1:7] = True
    run(tiny)  # imports, numba's cached passes
    if tool == "isoflow":
        from isoflow.digital.surface import boundary_mesh

        boundary_mesh(tiny, 6, method="compiled")
    vol = np.load(path)
    _reset_peak()
    before = _rss()
    t = time.perf_counter()
    result = run(vol)
    seconds = time.perf_counter() - t
    return {"seconds": seconds, "extra_peak_bytes": _maxrss() - before, **result}


def run_child(tool: str, path: Path) -> dict:
    cmd = [sys.executable, __file__, "--child", tool, str(path)]
    p = subprocess.run(cmd, capture_output=True, text=True, env=_env())
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if p.returncode or not lines:
        return {"error": (p.stderr or p.stdout).strip().splitlines()[-1:] or [f"exit {p.returncode}"]}
    return json.loads(lines[-1])


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def run_command(path: Path) -> dict:
    """``isoflow surface IN.npy -o OUT.ply``, whole process."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "surface.ply"
        code = ("import resource, sys, time; t = time.perf_counter(); from isoflow.cli import main; "
                "rc = main(sys.argv[1:]); print('{\"seconds\": %.4f, \"peak_bytes\": %d, \"rc\": %d}' % "
                "(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, rc))")
        t = time.perf_counter()
        p = subprocess.run([sys.executable, "-c", code, "surface", str(path), "-o", str(out), "--quiet"],
                           capture_output=True, text=True, env=_env())
        wall = time.perf_counter() - t
        lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
        if p.returncode or not lines:
            return {"error": (p.stderr or p.stdout).strip().splitlines()[-1:]}
        res = json.loads(lines[-1])
        res.update(wall_seconds=wall, file_bytes=out.stat().st_size,
                   checked="trimesh reads it back" in p.stdout)
        return res


def bench(sizes, inputs, repeat, tools, command) -> list[dict]:
    rows = []
    for size in sizes:
        for name in inputs:
            path = ensure_input(name, size)
            rounds = []
            for r in range(repeat):
                order = tools if r % 2 == 0 else tools[::-1]  # alternate who goes first
                got = {tool: run_child(tool, path) for tool in order}
                if command:
                    got["command"] = run_command(path)
                rounds.append(got)
                print(f"{name} {size}^3 round {r + 1}: " + ", ".join(
                    f"{t} {g.get('seconds', float('nan')):.2f} s" for t, g in got.items()), flush=True)
            rows.append({"input": name, "size": size, "rounds": rounds, "summary": summarise(rounds, tools)})
    return rows


def summarise(rounds, tools) -> dict:
    out = {}
    for tool in [*tools, "command"]:
        got = [r[tool] for r in rounds if tool in r and "error" not in r[tool]]
        if not got:
            continue
        out[tool] = {"seconds": statistics.median(g["seconds"] for g in got)}
        peak = "extra_peak_bytes" if "extra_peak_bytes" in got[0] else "peak_bytes"
        out[tool][peak] = statistics.median(g[peak] for g in got)
    if "vtk" in out and "isoflow" in out:
        pairs = [r for r in rounds if "error" not in r.get("vtk", {"error": 1})
                 and "error" not in r.get("isoflow", {"error": 1})]
        out["time_ratio_isoflow_over_vtk"] = statistics.median(r["isoflow"]["seconds"] / r["vtk"]["seconds"]
                                                               for r in pairs)
        out["peak_ratio_isoflow_over_vtk"] = statistics.median(
            r["isoflow"]["extra_peak_bytes"] / r["vtk"]["extra_peak_bytes"] for r in pairs)
    return out


SMALL = ("import sys, time; t = time.perf_counter(); import numpy as np; "
         "from isoflow.digital.surface import boundary_mesh; vol = np.load(sys.argv[1]); "
         "t1 = time.perf_counter(); boundary_mesh(vol, 6, method=sys.argv[2]); "
         "print(time.perf_counter() - t1)")


def small(sizes, repeat) -> list[dict]:
    """Cold processes: one mesh each, numba's start included."""
    rows = []
    for size in sizes:
        path = ensure_input("porous", size)
        times = {"numpy": [], "compiled": []}
        for r in range(repeat):
            for method in (("numpy", "compiled") if r % 2 == 0 else ("compiled", "numpy")):
                p = subprocess.run([sys.executable, "-c", SMALL, str(path), method], capture_output=True, text=True,
                                   env=_env(), check=True)
                times[method].append(float(p.stdout.split()[-1]))
        row = {"size": size, **{m: statistics.median(v) for m, v in times.items()}}
        print(f"porous {size}^3 cold: numpy {row['numpy']:.2f} s, compiled {row['compiled']:.2f} s", flush=True)
        rows.append(row)
    return rows


def table(rows) -> str:
    lines = ["| input | isoflow s | vtk s | ratio | isoflow peak MB | vtk peak MB | ratio | surface cmd s |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        s = r["summary"]
        iso, vtk, cmd = s.get("isoflow", {}), s.get("vtk", {}), s.get("command", {})
        lines.append(
            f"| {r['input']} {r['size']}^3 | {iso.get('seconds', float('nan')):.2f} | "
            f"{vtk.get('seconds', float('nan')):.2f} | {s.get('time_ratio_isoflow_over_vtk', float('nan')):.2f} | "
            f"{iso.get('extra_peak_bytes', 0) / 1e6:.0f} | {vtk.get('extra_peak_bytes', 0) / 1e6:.0f} | "
            f"{s.get('peak_ratio_isoflow_over_vtk', float('nan')):.2f} | {cmd.get('seconds', float('nan')):.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[512])
    ap.add_argument("--inputs", nargs="+", default=["ball", "porous"], choices=["ball", "porous", "torus"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--numpy", action="store_true", help="also time the NumPy mesh")
    ap.add_argument("--no-command", action="store_true", help="skip the isoflow surface command")
    ap.add_argument("--small", action="store_true", help="cold start of each method at 96^3 .. 192^3")
    ap.add_argument("--out", default=str(HERE / "results" / "mesh.json"))
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(*args.child)))
        return 0
    meta = {"python": platform.python_version(), "machine": platform.machine(), "cpus": os.cpu_count(),
            "date": time.strftime("%Y-%m-%d %H:%M"), "argv": [a for a in sys.argv[1:] if not a.startswith("/")]}
    if args.small:
        result = {"meta": meta, "small": small([96, 128, 160, 192], args.repeat)}
    else:
        tools = ["isoflow", "vtk"] + (["numpy"] if args.numpy else [])
        rows = bench(args.sizes, args.inputs, args.repeat, tools, not args.no_command)
        print(table(rows))
        result = {"meta": meta, "rows": rows, "table": table(rows)}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    old = json.loads(out.read_text()) if out.exists() else {}
    old.update({"small": result["small"]} if args.small else {"rows": result["rows"], "table": result["table"]})
    old["meta"] = meta
    out.write_text(json.dumps(old, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
