"""Speed of the digital curvature flow.

    python benchmarks/bench_flow.py            # 128^3 ball to the end, one 256^3 step, guarded 128^3 torus
    python benchmarks/bench_flow.py --json benchmarks/results/bench_flow.json

Times (wall clock, best of ``--repeat`` for the single steps):

* a digital ball in a 128^3 array flowed until it vanishes, the bare steps
  (``flow_step``) and the full ``run_flow`` (which also takes the Betti
  numbers, Euler characteristic and energy of every state);
* one step of a 256^3 ball and of a 256^3 porous object (smoothed noise:
  a surface in every direction, the worst case for the segment search);
* a solid torus in a 128^3 array (R = 0.3 n, r = 0.15 n) run to the end
  plain (``run_flow``: until it vanishes) and guarded (``run_flow(...,
  guard=True)``: to its fixed point, a closed curve), at 6 and 26, timed in
  pairs (plain, guarded, plain, guarded: ``--repeat`` pairs, medians), with
  the time per step of each and their ratio; and the first (largest) step
  alone: ``flow_step`` against ``guarded_step``. Both runs record the Betti
  numbers and energy of every state, so the per-step ratio is what a user
  of ``isoflow flow --guard`` waits for.

Why a step costs what it costs: one pass builds the configuration bytes
(three shifted ORs), one table look-up gives the unconditional moves, one
finds the convex-edge and flat vertices (the only ones whose move depends on
their segments); then, per axis, a contiguous copy of the lines along it, one
comparison with the shifted array marks the run starts, one ``flatnonzero``
lists them, one
cumulative sum numbers the runs, so that every edge/flat vertex reads its
run's first vertex and the next run's start -- a constant number of
whole-array passes (about a dozen over ``(n+1)^3`` elements) plus work
proportional to the surface.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from isoflow import DigitalObject  # noqa: E402
from isoflow.flow.motion import flow_step  # noqa: E402
from isoflow.flow.run import run_flow  # noqa: E402
from isoflow.flow.guard import guarded_step  # noqa: E402


def ball(n: int) -> np.ndarray:
    x = np.indices((n,) * 3, dtype=np.float32) - (n - 1) / 2
    return (x**2).sum(0) <= (0.45 * n) ** 2


def torus(n: int) -> np.ndarray:
    x = np.indices((n,) * 3, dtype=np.float32) - (n - 1) / 2
    rho = np.sqrt(x[0] ** 2 + x[1] ** 2)
    return (rho - 0.3 * n) ** 2 + x[2] ** 2 <= (0.15 * n) ** 2


def paired(a, b, repeat):
    """Time ``a`` and ``b`` alternately (a b a b ...): medians and last results."""
    ta, tb = [], []
    for _ in range(repeat):
        for fn, times in ((a, ta), (b, tb)):
            t = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t)
            if fn is a:
                ra = out
            else:
                rb = out
    return float(np.median(ta)), float(np.median(tb)), ra, rb


def guarded_torus(n: int, repeat: int) -> dict:
    """Plain and guarded runs of the n^3 torus, timed in pairs (module docstring)."""
    obj = DigitalObject(torus(n))
    out = {"voxels": obj.voxels}
    for conn in (6, 26):
        tp, tg, plain, guarded = paired(
            lambda: run_flow(obj, connectivity=conn, keep_states=False),
            lambda: run_flow(obj, connectivity=conn, guard=True, keep_states=False),
            repeat,
        )
        sp, sg = len(plain.steps) - 1, len(guarded.steps) - 1
        t1p, t1g, _, first = paired(lambda: flow_step(obj, conn), lambda: guarded_step(obj, conn, [1, 1, 0]), repeat)
        out[str(conn)] = {
            "plain_steps": sp,
            "plain_total_s": round(tp, 3),
            "plain_per_step_s": round(tp / sp, 4),
            "guarded_steps": sg,
            "guarded_kinds": guarded.guard_steps,
            "guarded_stop": guarded.stop_reason,
            "guarded_end_voxels": guarded.steps[-1]["voxels"],
            "guarded_total_s": round(tg, 3),
            "guarded_per_step_s": round(tg / sg, 4),
            "per_step_ratio": round((tg / sg) / (tp / sp), 2),
            "first_step_plain_s": round(t1p, 3),
            "first_step_guarded_s": round(t1g, 3),
            "first_step_ratio": round(t1g / t1p, 2),
            "first_step_kind": first.kind,
        }
        o = out[str(conn)]
        print(
            f"torus in {n}^3 ({obj.voxels} voxels), {conn}-connectivity: plain {sp} steps {tp:.2f} s "
            f"({1000 * tp / sp:.0f} ms/step), guarded {sg} steps {tg:.2f} s ({1000 * tg / sg:.0f} ms/step, "
            f"{o['guarded_kinds']}, {o['guarded_stop']} at {o['guarded_end_voxels']} voxels): "
            f"{o['per_step_ratio']}x per step; first step {1000 * t1p:.0f} ms plain, {1000 * t1g:.0f} ms guarded "
            f"({o['first_step_ratio']}x)"
        )
    return out


def porous(n: int, seed: int = 0) -> np.ndarray:
    from scipy.ndimage import gaussian_filter

    field = np.random.default_rng(seed).random((n,) * 3, dtype=np.float32)
    return gaussian_filter(field, 2.0) > 0.5


def best(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--small", type=int, default=128)
    ap.add_argument("--large", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", help="also write the figures to this file")
    args = ap.parse_args(argv)
    report = {"machine": platform.platform(), "python": platform.python_version(), "numpy": np.__version__}

    obj = DigitalObject(ball(args.small))
    flow_step(DigitalObject(ball(8)))  # build the lookup tables once
    t = time.perf_counter()
    cur, steps = obj, 0
    while cur.voxels:
        cur = flow_step(cur)
        steps += 1
    bare = time.perf_counter() - t
    t = time.perf_counter()
    result = run_flow(obj, keep_states=False)
    full = time.perf_counter() - t
    report[f"ball{args.small}_to_the_end"] = {
        "voxels": obj.voxels,
        "steps": steps,
        "flow_step_total_s": round(bare, 3),
        "flow_step_per_step_s": round(bare / steps, 4),
        "run_flow_total_s": round(full, 3),
        "run_flow_per_step_s": round(full / steps, 4),
        "limit": result.limit,
    }
    print(
        f"ball in {args.small}^3 ({obj.voxels} voxels): vanishes after {steps} steps; "
        f"flow_step {bare:.2f} s ({1000 * bare / steps:.1f} ms/step); "
        f"run_flow with Betti numbers and energy {full:.2f} s ({1000 * full / steps:.1f} ms/step); "
        f"limit {result.limit['center']} ({result.limit['last_shape']})"
    )

    for name, make in (("ball", ball), ("porous", porous)):
        big = DigitalObject(make(args.large))
        secs, new = best(lambda: flow_step(big), args.repeat)
        report[f"{name}{args.large}_one_step_s"] = round(secs, 3)
        print(f"one step of a {args.large}^3 {name} ({big.voxels} voxels -> {new.voxels}): {secs:.2f} s")

    report[f"torus{args.small}_plain_vs_guarded"] = guarded_torus(args.small, args.repeat)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
