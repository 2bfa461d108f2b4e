"""Speed of the digital curvature flow, against one morphological erosion.

    python benchmarks/bench_flow.py                 # everything, 256^3 ball
    python benchmarks/bench_flow.py --json benchmarks/results/bench_flow.json
    python benchmarks/bench_flow.py --baseline OTHER/src   # also time another checkout's commands

The peer is ``scipy.ndimage.binary_erosion`` of the same volume (a user's
idea of "one step of a morphological filter"). Inputs are made once and
cached in ``benchmarks/.cache/``: a digital ball filling 90% of a
``size^3`` array, a smoothed random porous field (uniform noise, gaussian
sigma 2, > 0.5, seed 0), a solid torus (R = 0.3 n, r = 0.15 n) in 128^3.

1. ``step_in_process``: one flow step with its record (voxels, parity,
   Betti numbers, chi, energy, bbox) of the ball and of the porous field,
   as ``run_flow`` takes it, by each method (``compiled``: bit rows,
   ``numpy``: the arrays of the reference implementation), against one
   erosion, timed alternately (erosion, compiled, numpy, ...), best of
   ``--repeat``; wall and CPU seconds (the CPU seconds of all threads).
2. ``commands``: whole commands in fresh processes, best of ``--repeat``,
   alternately: ``isoflow flow BALL.npy --steps 5 --json`` and ``--steps
   25``, whose difference over 20 is one step with its record; the same
   for ``python -c`` scripts that load the ball and run 1 and 21 erosions;
   the ratio of the two per-operation times. With ``--baseline SRC``, the
   flow commands of the isoflow source tree ``SRC`` (today's main, say)
   beside.
3. ``to_the_limit``: whole commands ``isoflow flow BALL.npy --json`` and
   ``--guard``, to the limit point (the plain flow until the ball vanishes,
   the guarded one to its fixed point), alternately, best of ``--repeat``;
   the guarded time over the plain one. ``--baseline-limit`` also times the
   baseline tree's plain run (minutes).
4. ``torus``: the torus flowed to its end plain and guarded at 6 and 26 in
   process, by each method.
5. ``small`` (only when asked, ``--only small``): ``--small-count``
   plain flows of small volumes (balls of 20-44 across, to their end, at
   6 and 26 in turn) in one fresh process per method (``auto``,
   ``numpy``, ``compiled``), as a user's loop runs them, alternately,
   best of ``--repeat``; wall and CPU seconds of the whole process,
   whose results are checked equal across the methods. With
   ``--baseline SRC``, the baseline tree's ``auto`` beside.
6. ``zarr`` (only when asked, ``--only zarr``): a ``--zarr-size``^3 ball
   written as a zarr store slab by slab, then ``isoflow flow BALL.zarr
   --out DIR --volumes .zarr --steps --zarr-steps`` as a whole command (the
   flow block by block): its wall and CPU seconds and the peak resident
   memory of the process (``ru_maxrss``).

Every run checks that the methods agree on the records they produce. Only
relative paths and figures are written.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
CACHE = Path(__file__).resolve().parent / ".cache"

from timing import timed_command  # noqa: E402

from isoflow import DigitalObject  # noqa: E402
from isoflow.flow.engines import flow_engine  # noqa: E402
from isoflow.flow.run import run_flow  # noqa: E402


def ball(n: int) -> np.ndarray:
    x = np.indices((n,) * 3, dtype=np.float32) - (n - 1) / 2
    return (x**2).sum(0) <= (0.45 * n) ** 2


def porous(n: int, seed: int = 0) -> np.ndarray:
    from scipy.ndimage import gaussian_filter

    field = np.random.default_rng(seed).random((n,) * 3, dtype=np.float32)
    return gaussian_filter(field, 2.0) > 0.5


def torus(n: int) -> np.ndarray:
    x = np.indices((n,) * 3, dtype=np.float32) - (n - 1) / 2
    rho = np.sqrt(x[0] ** 2 + x[1] ** 2)
    return (rho - 0.3 * n) ** 2 + x[2] ** 2 <= (0.15 * n) ** 2


def cached(name: str, n: int) -> Path:
    path = CACHE / f"flow_{name}{n}.npy"
    if not path.exists():
        CACHE.mkdir(exist_ok=True)
        np.save(path, {"ball": ball, "porous": porous, "torus": torus}[name](n))
    return path


def clocks():
    return time.perf_counter(), time.process_time()


def since(start) -> tuple[float, float]:
    wall, cpu = clocks()
    return wall - start[0], cpu - start[1]


def step_with_record(method: str, obj: DigitalObject, conn: int = 6):
    """One step and its record, as a run takes them (the state packed
    first, outside the clock, as a run holds it between steps)."""
    engine = flow_engine(method, obj, conn)
    state = engine.start(obj)

    def go():
        new = engine.step(state)
        return engine.record(new, 1)

    return go


def alternate(fns: dict, repeat: int) -> tuple[dict, dict]:
    """Time each function in turn, ``repeat`` rounds; the best wall and CPU
    seconds of each, and each one's last result."""
    best = {k: (np.inf, np.inf) for k in fns}
    out = {}
    for _ in range(repeat):
        for k, fn in fns.items():
            start = clocks()
            out[k] = fn()
            wall, cpu = since(start)
            best[k] = (min(best[k][0], wall), min(best[k][1], cpu))
    return {k: {"wall_s": round(w, 4), "cpu_s": round(c, 4)} for k, (w, c) in best.items()}, out


def step_in_process(size: int, repeat: int) -> dict:
    from scipy.ndimage import binary_erosion

    report = {}
    for name in ("ball", "porous"):
        vol = np.load(cached(name, size))
        obj = DigitalObject(vol)
        fns = {"erosion": lambda vol=vol: binary_erosion(vol), "compiled": step_with_record("compiled", obj),
               "numpy": step_with_record("numpy", obj)}
        fns["compiled"]()  # numba's start, outside the clock
        times, out = alternate(fns, repeat)
        assert out["compiled"] == out["numpy"], "the methods' records differ"
        for k in ("compiled", "numpy"):
            times[k]["over_erosion_wall"] = round(times[k]["wall_s"] / times["erosion"]["wall_s"], 3)
            times[k]["over_erosion_cpu"] = round(times[k]["cpu_s"] / times["erosion"]["cpu_s"], 3)
        report[f"{name}{size}"] = {"voxels": obj.voxels, **times}
        print(f"{name} {size}^3, one step with its record: compiled {1000 * times['compiled']['wall_s']:.1f} ms "
              f"({times['compiled']['over_erosion_wall']}x an erosion; CPU {times['compiled']['over_erosion_cpu']}x), "
              f"numpy {1000 * times['numpy']['wall_s']:.0f} ms ({times['numpy']['over_erosion_wall']}x), "
              f"erosion {1000 * times['erosion']['wall_s']:.0f} ms")
    return report


def command(args: list[str], src: Path | None = None) -> tuple[float, float]:
    """Wall and CPU seconds (the child's, all threads) of one command,
    with the isoflow of the source tree ``src`` when given."""
    return timed_command(args, None if src is None else str(src))


def flow_command(path: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "isoflow.cli", "flow", str(path), "--json", *extra]


def erosion_command(path: Path, count: int) -> list[str]:
    script = ("import sys, numpy, scipy.ndimage as n; v = numpy.load(sys.argv[1]); "
              f"[n.binary_erosion(v) for _ in range({count})]")
    return [sys.executable, "-c", script, str(path)]


def best_commands(cmds: dict, repeat: int) -> dict:
    best = {k: (np.inf, np.inf) for k in cmds}
    for _ in range(repeat):
        for k, (argv, src) in cmds.items():
            wall, cpu = command(argv, src)
            best[k] = (min(best[k][0], wall), min(best[k][1], cpu))
    return {k: {"wall_s": round(w, 3), "cpu_s": round(c, 3)} for k, (w, c) in best.items()}


def per_operation(times: dict, few: str, many: str, count: int) -> dict:
    return {c: round((times[many][c] - times[few][c]) / count, 4) for c in ("wall_s", "cpu_s")}


def commands(size: int, repeat: int, baseline: Path | None) -> dict:
    path = cached("ball", size)
    here = ROOT / "src"
    cmds = {"flow_5": (flow_command(path, "--steps", "5"), here), "flow_25": (flow_command(path, "--steps", "25"), here),
            "erode_1": (erosion_command(path, 1), None), "erode_21": (erosion_command(path, 21), None)}
    if baseline is not None:
        cmds["baseline_flow_5"] = (flow_command(path, "--steps", "5"), baseline)
        cmds["baseline_flow_25"] = (flow_command(path, "--steps", "25"), baseline)
    command(cmds["flow_5"][0], here)  # numba's cache, outside the clock
    times = best_commands(cmds, repeat)
    step = per_operation(times, "flow_5", "flow_25", 20)
    erosion = per_operation(times, "erode_1", "erode_21", 20)
    out = {"commands": times, "step": step, "erosion": erosion,
           "step_over_erosion_wall": round(step["wall_s"] / erosion["wall_s"], 3),
           "step_over_erosion_cpu": round(step["cpu_s"] / erosion["cpu_s"], 3)}
    line = (f"whole commands, ball {size}^3: a step with its record {1000 * step['wall_s']:.1f} ms, an erosion "
            f"{1000 * erosion['wall_s']:.1f} ms: {out['step_over_erosion_wall']}x (CPU {out['step_over_erosion_cpu']}x)")
    if baseline is not None:
        old = per_operation(times, "baseline_flow_5", "baseline_flow_25", 20)
        out["baseline_step"] = old
        out["baseline_step_over_erosion_wall"] = round(old["wall_s"] / erosion["wall_s"], 3)
        line += f"; baseline's step {1000 * old['wall_s']:.0f} ms ({out['baseline_step_over_erosion_wall']}x)"
    print(line)
    return out


def to_the_limit(size: int, repeat: int, baseline: Path | None) -> dict:
    path = cached("ball", size)
    here = ROOT / "src"
    cmds = {"plain": (flow_command(path), here), "guarded": (flow_command(path, "--guard"), here)}
    if baseline is not None:
        cmds["baseline_plain"] = (flow_command(path), baseline)
    times = best_commands(cmds, repeat)
    out = {"commands": times, "guarded_over_plain_wall": round(times["guarded"]["wall_s"] / times["plain"]["wall_s"], 3),
           "guarded_over_plain_cpu": round(times["guarded"]["cpu_s"] / times["plain"]["cpu_s"], 3)}
    r = run_flow(np.load(path), keep_states=False)
    out["steps"] = len(r.steps) - 1
    out["limit"] = r.limit
    print(f"ball {size}^3 to its limit ({out['steps']} steps) as a whole command: plain {times['plain']['wall_s']:.2f} s, "
          f"guarded {times['guarded']['wall_s']:.2f} s ({out['guarded_over_plain_wall']}x; CPU "
          f"{out['guarded_over_plain_cpu']}x)" + (f", baseline plain {times['baseline_plain']['wall_s']:.1f} s"
                                                  if baseline is not None else ""))
    return out


def zarr_ball(n: int) -> Path:
    """A ball filling 90% of an n^3 store, written slab by slab (no n^3
    array in memory)."""
    import zarr

    path = CACHE / f"flow_ball{n}.zarr"
    if (path / "0").exists():
        return path
    CACHE.mkdir(exist_ok=True)
    root = zarr.open_group(str(path), mode="w", zarr_format=2)
    z = root.create_array("0", shape=(n, n, n), chunks=(32, 256, 256), dtype=np.uint8, fill_value=0)
    yz = np.indices((n, n), dtype=np.float32) - (n - 1) / 2
    for a in range(0, n, 32):
        x = np.arange(a, min(a + 32, n), dtype=np.float32)[:, None, None] - (n - 1) / 2
        z[a:a + 32] = (x**2 + (yz**2).sum(0)) <= (0.45 * n) ** 2
    return path


def zarr_flow(n: int, steps: int) -> dict:
    import shutil
    import tempfile

    path = zarr_ball(n)
    out = Path(tempfile.mkdtemp()) / "run"
    argv = [sys.executable, "-m", "isoflow.cli", "flow", str(path), "--out", str(out), "--volumes", ".zarr",
            "--steps", str(steps), "--json", "-q"]
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    done = subprocess.run(argv, env=env, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    shutil.rmtree(out.parent, ignore_errors=True)
    rec = json.loads(done.stdout)
    out = {"size": n, "steps": steps, "wall_s": round(wall, 1),
           "cpu_s": round((r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime), 1),
           "peak_rss_gib": round(r1.ru_maxrss / 2**20, 3), "voxels": [s["voxels"] for s in rec["steps"]]}
    print(f"ball {n}^3 from zarr, {steps} steps block by block: {wall:.0f} s, peak memory "
          f"{out['peak_rss_gib']} GiB (the largest child process so far)")
    return out


def torus_runs(n: int, repeat: int) -> dict:
    obj = DigitalObject(np.load(cached("torus", n)))
    out = {"voxels": obj.voxels}
    for conn in (6, 26):
        fns = {f"{m}_{g}": (lambda m=m, g=g, conn=conn: run_flow(obj, connectivity=conn, guard=g == "guarded",
                                                                  keep_states=False,
                                                        method=m))
               for m in ("compiled", "numpy") for g in ("plain", "guarded")}
        times, got = alternate(fns, repeat)
        for g in ("plain", "guarded"):
            assert got[f"compiled_{g}"].to_dict() == got[f"numpy_{g}"].to_dict(), "the methods' runs differ"
        guarded = got["compiled_guarded"]
        out[str(conn)] = {**times, "plain_steps": len(got["compiled_plain"].steps) - 1,
                          "guarded_steps": len(guarded.steps) - 1, "guarded_kinds": guarded.guard_steps,
                          "guarded_stop": guarded.stop_reason}
        print(f"torus {n}^3 at {conn}: plain {times['compiled_plain']['wall_s']:.2f} s (numpy "
              f"{times['numpy_plain']['wall_s']:.2f} s), guarded {times['compiled_guarded']['wall_s']:.2f} s (numpy "
              f"{times['numpy_guarded']['wall_s']:.2f} s), {guarded.guard_steps}")
    return out


#: the loop of ``small``: argv[1] flows, method argv[2]; prints a digest of
#: every run's records (the same whichever method ran them)
SMALL_LOOP = """
import hashlib, json, sys
import numpy as np
from isoflow.flow.run import run_flow

count, method = int(sys.argv[1]), sys.argv[2]
digest = hashlib.sha1()
for i in range(count):
    n = 20 + (7 * i) % 25
    x = np.indices((n,) * 3, dtype=np.float32) - (n - 1) / 2
    ball = (x**2).sum(0) <= (0.45 * n) ** 2
    r = run_flow(ball, connectivity=(6, 26)[i % 2], keep_states=False, method=method)
    digest.update(json.dumps(r.to_dict(), sort_keys=True).encode())
print(digest.hexdigest())
"""


def small_flows(count: int, repeat: int, baseline: Path | None) -> dict:
    here = str(ROOT / "src")
    cmds = {m: ([sys.executable, "-c", SMALL_LOOP, str(count), m], here) for m in ("auto", "numpy", "compiled")}
    if baseline is not None:
        cmds["baseline_auto"] = ([sys.executable, "-c", SMALL_LOOP, str(count), "auto"], str(baseline))
    digests = {m: subprocess.run(argv, env=dict(os.environ, PYTHONPATH=src), check=True, capture_output=True,
                                 text=True).stdout for m, (argv, src) in cmds.items()}  # (numba's cache warm, too)
    assert len(set(digests.values())) == 1, f"the methods' runs differ: {digests}"
    times = best_commands(cmds, repeat)
    print(f"{count} small flows in one process, CPU seconds: " + ", ".join(f"{k} {v['cpu_s']:.2f}" for k, v in times.items()))
    return {"count": count, "commands": times}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=256, help="side of the ball and porous field (default 256)")
    ap.add_argument("--torus", type=int, default=128, help="side of the torus (default 128)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--baseline", type=Path, help="another isoflow source tree whose commands are timed beside")
    ap.add_argument("--baseline-limit", action="store_true", help="also run the baseline's flow to the limit")
    ap.add_argument("--only", nargs="+", choices=["step", "commands", "limit", "torus", "zarr", "small"])
    ap.add_argument("--small-count", type=int, default=200, help="flows in the loop of --only small (default 200)")
    ap.add_argument("--zarr-size", type=int, default=1024, help="side of the ball flowed from zarr (--only zarr)")
    ap.add_argument("--zarr-steps", type=int, default=20)
    ap.add_argument("--json", help="also write the figures to this file")
    args = ap.parse_args(argv)
    report = {"machine": platform.platform(), "python": platform.python_version(), "numpy": np.__version__,
              "cpus": len(os.sched_getaffinity(0)), "baseline": args.baseline is not None}
    parts = args.only or ["step", "commands", "limit", "torus"]
    if "step" in parts:
        report["step_in_process"] = step_in_process(args.size, args.repeat)
    if "commands" in parts:
        report["commands"] = commands(args.size, args.repeat, args.baseline)
    if "limit" in parts:
        report["to_the_limit"] = to_the_limit(args.size, args.repeat,
                                              args.baseline if args.baseline_limit else None)
    if "torus" in parts:
        report[f"torus{args.torus}"] = torus_runs(args.torus, args.repeat)
    if "small" in parts:
        report[f"small_flows{args.small_count}"] = small_flows(args.small_count, args.repeat, args.baseline)
    if "zarr" in parts:
        report[f"zarr_ball{args.zarr_size}"] = zarr_flow(args.zarr_size, args.zarr_steps)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
