"""One closed surface per label as whole commands (issue 25, item 5):
``isoflow surface LABELS --labels -o OUT.glb`` (with its read-back by
trimesh, and with ``--no-check``) against pyvista's ``contour_labels``
(VTK's SurfaceNets: one shared surface between touching labels, not
closed per label) writing its mesh, the tools alternated, medians. The
ratios are against ``contour_labels('all')``, every label's boundary as
isoflow writes it; pyvista's default (``'external'``: only where a label
meets the background) is timed beside it.

    python benchmarks/bench_label_surfaces.py                 # 256^3 with 1,000 labels, 128^3 with 12,500
    python benchmarks/bench_label_surfaces.py --inputs 128:12500 --repeat 1 --json ''

Inputs: the grain maps of ``bench_labels.py`` (cached in
``benchmarks/.cache/``). Results go to
``benchmarks/results/label_surfaces.json`` and a Markdown table on stdout;
in each row the faces written (isoflow: triangles of every label's own
surface; pyvista: the faces of its shared surfaces).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_labels import ROOT, cached

PYVISTA = ("import sys, numpy as np, pyvista as pv; a = np.load(sys.argv[1]); "
           "g = pv.ImageData(dimensions=a.shape); g.point_data['labels'] = a.ravel(order='F'); "
           "m = g.contour_labels(sys.argv[3], smoothing=False); m.save(sys.argv[2]); print(m.n_cells)")
#: the peer the ratios are taken against: every label's boundary, where
#: two labels touch as where a label meets the background (pyvista's
#: default, ``external``, leaves out the faces between labels)
PEER = "pyvista contour_labels('all') + save"


def commands(path: Path, out: Path) -> dict[str, list[str]]:
    glb = str(out / "labels.glb")
    ours = [sys.executable, "-m", "isoflow", "surface", str(path), "--labels", "-o", glb, "--force"]
    return {"isoflow surface --labels": ours, "isoflow surface --labels --no-check": ours + ["--no-check"],
            PEER: [sys.executable, "-c", PYVISTA, str(path), str(out / "all.vtp"), "all"],
            "pyvista contour_labels() + save": [sys.executable, "-c", PYVISTA, str(path), str(out / "ext.vtp"),
                                                "external"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--inputs", nargs="+", default=["256:1000", "128:12500"], help="SIZE:LABELS grain maps")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "label_surfaces.json"))
    args = ap.parse_args(argv)
    results = []
    for spec in args.inputs:
        size, count = map(int, spec.split(":"))
        path = cached(size, count)
        with tempfile.TemporaryDirectory() as tmp:
            cmds = commands(path, Path(tmp))
            times: dict[str, list[float]] = {name: [] for name in cmds}
            said: dict[str, str] = {}
            for _ in range(args.repeat):
                for name, cmd in cmds.items():
                    start = time.perf_counter()
                    done = subprocess.run(cmd, check=True, capture_output=True, text=True, cwd=ROOT)
                    times[name].append(time.perf_counter() - start)
                    said[name] = done.stdout.strip().splitlines()[-1]
        for name, spent in times.items():
            faces = said[name].split(" faces")[0].split()[-1] if "faces" in said[name] else said[name]
            results.append({"size": size, "labels": count, "command": name, "seconds": statistics.median(spent),
                            "runs": spent, "faces": int(faces.replace(",", ""))})
            print(f"{size}^3 {count} labels, {name}: {results[-1]['seconds']:.2f} s", file=sys.stderr)
    lines = ["| size | labels | command | seconds (median) | faces | vs pyvista |", "|---|---:|---|---:|---:|---:|"]
    for r in results:
        theirs = next(x["seconds"] for x in results if x["size"] == r["size"] and x["labels"] == r["labels"]
                      and x["command"] == PEER)
        lines.append(f"| {r['size']}^3 | {r['labels']:,} | {r['command']} | {r['seconds']:.2f} | {r['faces']:,} | "
                     f"{r['seconds'] / theirs:.2f}x |")
    print("\n".join(lines))
    if args.json:
        meta = {"command": "python benchmarks/bench_label_surfaces.py " + " ".join(argv or sys.argv[1:]),
                "machine": f"{platform.machine()}, python {platform.python_version()}"}
        Path(args.json).write_text(json.dumps({"meta": meta, "results": results}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
