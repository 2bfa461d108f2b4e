"""The shell against the closed scanline, and one source tree against
another, on the 81,920-triangle icosphere (issue 24).

Usage::

    PYTHONPATH=src python benchmarks/bench_shell_ab.py --other ../main/src [--rounds 3] [--repeat 4]

Each round runs one process per source tree, this one (``src``) and
``--other``'s, in turn (interleaved, so that a busy machine weighs on both
alike); each process times ``voxelize(..., fill="shell")`` and
``voxelize(...)`` (the winding rule's closed scanline) at 256, 512 and 1024
across ``--repeat`` times each, wall and processor seconds, and a digest
of the voxels (the two trees must agree, bit for bit, or nothing is
reported).  Reported: the best of all rounds per tree, size and fill
(benchmarks/results/shell_ab.json).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

RESOLUTIONS = (256, 512, 1024)

CHILD = """
import hashlib, json, sys, time
import numpy as np, trimesh
from isoflow.mesh.voxelize import voxelize
s = trimesh.creation.icosphere(subdivisions=6)
v, f = np.asarray(s.vertices), np.asarray(s.faces)
voxelize(v, f, resolution=16, fill="shell"); voxelize(v, f, resolution=16)
out = {}
for res in %(res)r:
    for fill in ("shell", "winding"):
        wall = cpu = float("inf")
        for _ in range(%(repeat)d):
            w, c = time.perf_counter(), time.process_time()
            vol = voxelize(v, f, resolution=res, fill=fill)[0]
            wall, cpu = min(wall, time.perf_counter() - w), min(cpu, time.process_time() - c)
        out[f"{fill} {res}"] = [wall, cpu, hashlib.sha1(np.packbits(vol).tobytes()).hexdigest()]
        del vol
print(json.dumps(out))
"""


def run_tree(src: str, repeat: int) -> dict:
    env = dict(os.environ, PYTHONPATH=src)
    code = CHILD % {"res": RESOLUTIONS, "repeat": repeat}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--other", required=True, help="the other tree's src folder (e.g. main's)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=4)
    args = ap.parse_args()
    here = str(Path(__file__).resolve().parents[1] / "src")
    best: dict[str, dict[str, list[float]]] = {"this": {}, "other": {}}
    digests: dict[str, set[str]] = {}
    for _ in range(args.rounds):
        for name, src in (("other", args.other), ("this", here)):
            for key, (wall, cpu, digest) in run_tree(src, args.repeat).items():
                old = best[name].get(key, [float("inf"), float("inf")])
                best[name][key] = [min(old[0], wall), min(old[1], cpu)]
                digests.setdefault(key, set()).add(digest)
    differ = sorted(key for key, d in digests.items() if len(d) > 1)
    if differ:  # the trees must give the same voxels before their times mean anything
        print(f"the two trees' voxels differ: {', '.join(differ)}", file=sys.stderr)
        return 1
    rows = []
    for res in RESOLUTIONS:
        row = {"resolution": res}
        for name in ("this", "other"):
            (sw, sc), (ww, wc) = best[name][f"shell {res}"], best[name][f"winding {res}"]
            row[name] = {"shell_wall_s": sw, "shell_cpu_s": sc, "winding_wall_s": ww, "winding_cpu_s": wc,
                         "winding_over_shell_wall": ww / sw, "winding_over_shell_cpu": wc / sc}
        row["shell_other_over_this_wall"] = row["other"]["shell_wall_s"] / row["this"]["shell_wall_s"]
        row["shell_other_over_this_cpu"] = row["other"]["shell_cpu_s"] / row["this"]["shell_cpu_s"]
        rows.append(row)
        t, o = row["this"], row["other"]
        print(f"{res}: this shell {t['shell_wall_s']:.3f} s ({t['shell_cpu_s']:.3f} cpu) vs winding "
              f"{t['winding_wall_s']:.3f} s ({t['winding_cpu_s']:.3f}): {t['winding_over_shell_wall']:.2f}x "
              f"({t['winding_over_shell_cpu']:.2f}x cpu); other's shell {o['shell_wall_s']:.3f} s "
              f"({o['shell_cpu_s']:.3f} cpu): this {row['shell_other_over_this_wall']:.2f}x "
              f"({row['shell_other_over_this_cpu']:.2f}x cpu)", flush=True)
    out = Path(__file__).with_name("results") / "shell_ab.json"
    out.write_text(json.dumps({"benchmark": "issue 24: the shell against the closed scanline, two trees",
                               "timing": f"best of {args.rounds} interleaved rounds x {args.repeat} runs",
                               "load_average": os.getloadavg()[0], "cpus": os.cpu_count(),
                               "python": platform.python_version(), "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
