"""Benchmark: meshes that are not closed (issue 24, items 4 and 5).

    PYTHONPATH=src python benchmarks/bench_winding.py [--out benchmarks/results/winding.json]
        [--repeat 3] [--baseline OTHER_SRC] [--skip-igl] [--tets-res 32]
        [--only soup bunny startup tets closed signal]

Cases, each timed in the same run (best of ``--repeat``; A B A B where two
things are compared):

* ``soup``: 100 random triangles in the unit cube (benchmarks/generated.py,
  seed 1) at 256 across: ``isoflow voxelize`` as a whole command, and
  ``voxelize`` in process against libigl's ``fast_winding_number`` on the
  same voxel centres (``--skip-igl`` leaves libigl out: a minute or more);
  the voxels that differ from libigl's ``|w| > 1/2`` are counted.
* ``bunny``: the Stanford bunny scan that pymeshlab ships (holes in its
  base) at 256 across, as a whole command.
* ``startup``: the soup and the bunny at 8 across as whole commands: what
  every command pays to start and to read its file.
* ``tets``: the tetrahedral quad mesh (96,000 faces, libigl's ``cube_40k``
  in kind) at ``--tets-res`` across: the whole command, and in process
  against libigl's ``fast_winding_number`` (approximate) on the same
  centres.
* ``closed``: an 81,920-triangle icosphere at 256 and 512 across, in
  process, against pyvista's ``voxelize_binary_mask`` at the same spacing.
* ``signal``: ``isoflow voxelize`` of the tetrahedral quads at 256 across,
  SIGTERM after 10 s: seconds from the signal to the exit, and the status.

``--baseline SRC`` (another checkout's ``src``) times the same whole
commands with that isoflow too, interleaved, and reports the ratio.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from generated import random_soup, tet_quads, write_obj  # noqa: E402

from isoflow.mesh.voxelize import voxelize  # noqa: E402


def best(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        out = None
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def command(src: Path, args: list[str]) -> float:
    env = dict(os.environ, PYTHONPATH=str(src))
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "isoflow", *args, "-q", "--force"], env=env, check=True,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def commands(args, label: str, cmd: list[str]) -> dict:
    """The whole command with this checkout (and the baseline), A B A B."""
    mine, base = [], []
    for _ in range(args.repeat):
        mine.append(command(ROOT / "src", cmd))
        if args.baseline:
            base.append(command(Path(args.baseline), cmd))
    row = {"case": label, "command_s": min(mine)}
    if base:
        row["baseline_command_s"] = min(base)
        row["speedup_vs_baseline"] = min(base) / min(mine)
    print(row, flush=True)
    return row


def centres(vol, origin, pitch):
    return origin + (np.argwhere(np.ones(vol.shape, bool)) + 0.5) * pitch


def soup_case(args, tmp: Path) -> list[dict]:
    v, f = random_soup()
    path = write_obj(tmp / "soup100.obj", v, f)
    rows = [commands(args, "soup100 @256 command", ["voxelize", str(path), "--resolution", "256",
                                                      "-o", str(tmp / "s.npz")])]
    voxelize(v, f, resolution=16)
    t_iso, (vol, origin, pitch) = best(lambda: voxelize(v, f, resolution=256), args.repeat)
    row = {"case": "soup100 @256 in process", "isoflow_s": t_iso, "voxels": int(vol.sum())}
    if not args.skip_igl:
        import igl

        q = centres(vol, origin, pitch)
        t = time.perf_counter()
        w = igl.fast_winding_number(v, f, q)
        row["igl_fast_winding_number_s"] = time.perf_counter() - t
        row["ratio_igl_over_isoflow"] = row["igl_fast_winding_number_s"] / t_iso
        row["differ_from_igl_fwn"] = int((vol.reshape(-1) != (np.abs(w) > 0.5)).sum())
    print(row, flush=True)
    return rows + [row]


def bunny_case(args, tmp: Path) -> list[dict]:
    import pymeshlab

    path = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "bunny10k_textured.obj"
    if not path.is_file():
        return []
    return [commands(args, "bunny10k scan (holes) @256 command",
                     ["voxelize", str(path), "--resolution", "256", "-o", str(tmp / "b.npz")])]


def startup_case(args, tmp: Path) -> list[dict]:
    """The soup and the bunny at 8 across: the command's start-up and the
    file's loading, the voxels next to nothing."""
    import pymeshlab

    rows = [commands(args, "soup100 @8 command (start-up, loading)",
                     ["voxelize", str(write_obj(tmp / "soup100.obj", *random_soup())), "--resolution", "8",
                      "-o", str(tmp / "s8.npz")])]
    path = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / "bunny10k_textured.obj"
    if path.is_file():
        rows.append(commands(args, "bunny10k scan @8 command (start-up, loading)",
                             ["voxelize", str(path), "--resolution", "8", "-o", str(tmp / "b8.npz")]))
    return rows


def tets_case(args, tmp: Path) -> list[dict]:
    """The tetrahedral quads: the whole command (against the baseline), and
    in process against libigl's fast_winding_number on the same centres
    (which does not turn faces over as isoflow's reading does, so its
    voxels are not compared)."""
    v, f = tet_quads()
    res = args.tets_res
    rows = [commands(args, f"tet quads (96,000 faces) @{res} command",
                     ["voxelize", str(write_obj(tmp / "tets.obj", v, f)), "--resolution", str(res),
                      "-o", str(tmp / "t.npz")])]
    voxelize(v[:9], np.array([[0, 1, 2], [3, 4, 5]]), resolution=8)
    t, (vol, origin, pitch) = best(lambda: voxelize(v, f, resolution=res), 1)
    row = {"case": f"tet quads (96,000 faces) @{res} in process", "isoflow_s": t, "voxels": int(vol.sum())}
    if not args.skip_igl:
        import igl

        q = centres(vol, origin, pitch)
        t0 = time.perf_counter()
        igl.fast_winding_number(v, f, q)
        row["igl_fast_winding_number_s"] = time.perf_counter() - t0
        row["ratio_igl_over_isoflow"] = row["igl_fast_winding_number_s"] / t
    print(row, flush=True)
    return rows + [row]


def closed_case(args, tmp: Path) -> list[dict]:
    import pyvista as pv
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=6)
    v, f = np.asarray(sphere.vertices), np.asarray(sphere.faces)
    poly = pv.PolyData(v, np.hstack([np.full((len(f), 1), 3), f]).ravel())
    voxelize(v, f, resolution=16)
    rows = []
    for res in (256, 512):
        t_iso, _ = best(lambda res=res: voxelize(v, f, resolution=res), args.repeat)
        t_pv, _ = best(lambda res=res: poly.voxelize_binary_mask(spacing=2.0 / res), args.repeat)
        row = {"case": f"icosphere 81,920 faces @{res} in process", "isoflow_s": t_iso, "pyvista_s": t_pv,
               "ratio_pyvista_over_isoflow": t_pv / t_iso}
        print(row, flush=True)
        rows.append(row)
    path = tmp / "sphere.ply"
    sphere.export(path)
    rows.append(commands(args, "icosphere 81,920 faces @256 command",
                         ["voxelize", str(path), "--resolution", "256", "-o", str(tmp / "c.npz")]))
    return rows


def signal_case(args, tmp: Path) -> list[dict]:
    path = write_obj(tmp / "tets.obj", *tet_quads())
    out = tmp / "sig.npz"
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    proc = subprocess.Popen([sys.executable, "-m", "isoflow", "voxelize", str(path), "--resolution", "256",
                             "-o", str(out)], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    time.sleep(10)
    sent = time.perf_counter()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate()
    row = {"case": "tet quads @256 command, SIGTERM after 10 s", "exit_after_signal_s": time.perf_counter() - sent,
           "status": proc.returncode, "output_written": out.exists(), "stderr": err.strip().splitlines()[-1:]}
    print(row, flush=True)
    return [row]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "winding.json"))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--baseline", help="another checkout's src directory, timed A B A B")
    ap.add_argument("--skip-igl", action="store_true")
    ap.add_argument("--tets-res", type=int, default=32)
    ap.add_argument("--only", nargs="*", default=["soup", "bunny", "startup", "tets", "closed", "signal"])
    args = ap.parse_args()
    cases = {"soup": soup_case, "bunny": bunny_case, "startup": startup_case, "tets": tets_case,
             "closed": closed_case, "signal": signal_case}
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for name in args.only:
            rows += cases[name](args, Path(d))
    out = Path(args.out)
    result = {"machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                          "load_average": os.getloadavg()},
              "command": "python benchmarks/bench_winding.py " + " ".join(
                  "BASELINE_SRC" if a == args.baseline else a.replace(str(ROOT) + "/", "") for a in sys.argv[1:]),
              "rows": rows}
    if args.baseline:
        result["baseline"] = "another checkout's src (given on the command line)"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
