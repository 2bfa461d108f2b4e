"""How often do the paper's claims about the digital curvature flow hold?

    python benchmarks/theorems.py                     # default sample, about 2-4 minutes
    python benchmarks/theorems.py --count 10 --no-guard   # a quick look

Runs the flow (isoflow.flow.run.run_flow, the reading of DESIGN section 4) on
many objects -- random unions of boxes, dumbbells, solid tori and square
annulus prisms, digital balls, smoothed random blobs, and the sample meshes
voxelised at 24-32 voxels across (when ``isoflow.voxelize`` is available) --
and counts, per family and connectivity, how often each claim holds:

* **T20/22/23** -- the flow ends in a cuboid, then a point: the run vanishes
  and its last non-empty state is a full box (``cuboid``); also the share
  whose last state is a single voxel.
* **T21** -- the topology is kept if there is no tunnel: the Betti numbers of
  every non-empty state equal the input's, counted over connected inputs
  without tunnels or cavities, Betti numbers (1,0,0) (the claim: the proof of
  Theorem 24 reads it as "topologically a cuboid"), and separately over all
  other inputs (several components, tunnels, cavities: not claimed; a small
  component vanishing before the others already counts as a change).
* **T24** -- ``E >= 8 (1 + g)`` for every non-empty state that is one
  component without cavities (g = b1).
* **T25** -- the energy ``E = k^T n`` never increases from one step to the
  next (non-empty states).
* **guard** -- with topology control, how often the run converges (one
  shape kept) rather than being blocked; the stop reasons of the plain and
  the guarded runs are tabulated too.

For every claim the smallest failing input (fewest voxels) is saved as
``results/counterexamples/<claim>_<connectivity>.npy`` (a boolean array; run
``isoflow flow FILE`` on it). The table goes to ``results/theorems.md``.
Failures are reported as they are: nothing is tuned to make a claim hold.
"""

from __future__ import annotations

import argparse
import glob
import json
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "src"))

from isoflow import DigitalObject  # noqa: E402
from isoflow.flow.run import run_flow  # noqa: E402

CLAIMS = ("T20-23 cuboid", "single voxel", "T21 (1,0,0)", "kept, other inputs", "T24", "T25", "guard")
#: columns that are not claims of the paper: no counterexample is saved
INFO = ("single voxel", "kept, other inputs")


# --------------------------------------------------------------------------
# Objects
# --------------------------------------------------------------------------


def union_of_boxes(rng, size=16):
    v = np.zeros((size,) * 3, bool)
    for _ in range(rng.integers(2, 6)):
        lo = rng.integers(0, size - 2, 3)
        hi = lo + rng.integers(1, 9, 3)
        v[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]] = True
    return v


def dumbbell(rng):
    n = int(rng.integers(3, 9))
    bar = int(rng.integers(1, 8))
    w = int(rng.integers(1, min(4, n)))
    v = np.zeros((2 * n + bar, n, n), bool)
    v[:n] = v[n + bar:] = True
    a = int(rng.integers(0, n - w + 1))
    b = int(rng.integers(0, n - w + 1))
    v[n:n + bar, a:a + w, b:b + w] = True
    return v


def solid_torus(rng):
    R = rng.uniform(3, 8)
    r = rng.uniform(1, min(R - 0.5, 3.5))
    size = int(2 * (R + r) + 4)
    x = np.indices((size,) * 3).astype(float) - (size - 1) / 2
    rho = np.sqrt(x[0] ** 2 + x[1] ** 2)
    return (rho - R) ** 2 + x[2] ** 2 <= r**2


def annulus_prism(rng):
    hole = int(rng.integers(1, 8))
    wall = int(rng.integers(1, 5))
    outer = hole + 2 * wall
    v = np.ones((outer, outer + int(rng.integers(0, 4)), int(rng.integers(1, 10))), bool)
    v[wall:wall + hole, wall:wall + hole] = False
    return v


def digital_ball(rng):
    radius = rng.uniform(1.5, 12)
    size = int(2 * radius + 4)
    x = np.indices((size,) * 3) - (size - 1) / 2 + rng.uniform(-0.5, 0.5, (3, 1, 1, 1))
    return (x**2).sum(0) <= radius**2


def blob(rng, size=14):
    from scipy.ndimage import gaussian_filter

    f = gaussian_filter(rng.random((size,) * 3), rng.uniform(1.2, 2.5))
    return f > np.quantile(f, rng.uniform(0.4, 0.8))


FAMILIES = {
    "union of boxes": union_of_boxes,
    "dumbbell": dumbbell,
    "solid torus": solid_torus,
    "annulus prism": annulus_prism,
    "digital ball": digital_ball,
    "random blob": blob,
}


def mesh_objects(directories, resolutions=(24, 32)):
    """(name, volume) of every sample mesh voxelised, if isoflow.voxelize exists."""
    try:
        from isoflow.mesh import voxelize as vx
    except ImportError:
        print("isoflow.voxelize is not available: skipping the sample meshes", file=sys.stderr)
        return []
    out = []
    seen = set()
    for d in directories:
        for path in sorted(glob.glob(str(Path(d) / "*"))):
            p = Path(path)
            if p.suffix.lower() not in (".obj", ".off", ".ply", ".stl") or p.name in seen:
                continue
            seen.add(p.name)
            for res in resolutions:
                try:
                    v, f = vx.load_mesh(p)
                    vol = vx.voxelize(v, f, resolution=res, allow_open=True)[0]
                except Exception as exc:  # a mesh the voxeliser refuses: say so, go on
                    print(f"{p.name} at {res}: skipped ({exc.__class__.__name__}: {exc})", file=sys.stderr)
                    continue
                if vol.any():
                    out.append((f"{p.name}@{res}", vol))
    return out


# --------------------------------------------------------------------------
# Claims
# --------------------------------------------------------------------------


def check(volume, connectivity, guard):
    """Which claims apply to this input and whether they hold."""
    obj = DigitalObject(volume)
    r = run_flow(obj, connectivity=connectivity)
    nonempty = [s for s in r.steps if s["voxels"]]
    first = nonempty[0]["betti"]
    out = {}
    vanished = r.stop_reason == "vanished"
    out["T20-23 cuboid"] = vanished and r.limit["last_shape"] == "cuboid"
    out["single voxel"] = vanished and nonempty[-1]["voxels"] == 1
    kept = all(s["betti"] == first for s in nonempty)
    out["T21 (1,0,0)" if first == [1, 0, 0] else "kept, other inputs"] = kept
    t24 = [s for s in nonempty if s["betti"][0] == 1 and s["betti"][2] == 0]
    if t24:
        out["T24"] = all(s["energy"] >= 8 * (1 + s["betti"][1]) for s in t24)
    energy = [s["energy"] for s in nonempty]
    out["T25"] = all(b <= a for a, b in zip(energy, energy[1:]))
    info = {"plain": r.stop_reason}
    if guard:
        g = run_flow(obj, connectivity=connectivity, guard=True)
        assert all(s["betti"] == first for s in g.steps), "the guard let the Betti numbers change"
        out["guard"] = g.stop_reason == "converged"
        info["guarded"] = g.stop_reason
    return out, info


def _slug(claim: str) -> str:
    return "".join(c if c.isalnum() else "-" for c in claim).strip("-").replace("--", "-")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=40, help="objects per synthetic family")
    ap.add_argument("--seed", type=int, default=2013)
    ap.add_argument("--connectivity", type=int, nargs="+", default=[6, 26])
    ap.add_argument("--no-guard", action="store_true", help="skip the guarded runs")
    ap.add_argument("--guard-max-voxels", type=int, default=20000, help="guarded runs only below this size")
    ap.add_argument("--meshes", nargs="*", default=[str(ROOT / "meshes"), str(ROOT.parent / "shared" / "meshes")])
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)

    rng = np.random.default_rng(args.seed)
    objects = []
    for family, make in FAMILIES.items():
        for _ in range(args.count):
            v = make(rng)
            if v.any():
                objects.append((family, family, v))
    for name, v in mesh_objects(args.meshes):
        objects.append(("sample mesh", name, v))

    out = Path(args.out)
    (out / "counterexamples").mkdir(parents=True, exist_ok=True)
    tally = defaultdict(lambda: defaultdict(lambda: [0, 0]))  # (conn, family) -> claim -> [holds, applies]
    smallest = {}  # (claim, conn) -> (voxels, name, volume)
    stops = defaultdict(lambda: defaultdict(int))  # (conn, plain/guarded) -> reason -> count
    t0 = time.time()
    for conn in args.connectivity:
        for family, name, v in objects:
            guard = not args.no_guard and v.sum() <= args.guard_max_voxels
            res, info = check(v, conn, guard)
            for run, reason in info.items():
                stops[(conn, run)][reason] += 1
            for claim, ok in res.items():
                for key in (family, "all"):
                    tally[(conn, key)][claim][1] += 1
                    tally[(conn, key)][claim][0] += bool(ok)
                if not ok and claim not in INFO:
                    n = int(v.sum())
                    if (claim, conn) not in smallest or n < smallest[(claim, conn)][0]:
                        smallest[(claim, conn)] = (n, name, v)
    elapsed = time.time() - t0

    for (claim, conn), (n, name, v) in smallest.items():
        slug = _slug(claim)
        np.save(out / "counterexamples" / f"{slug}_{conn}.npy", v)

    lines = [
        "# The paper's claims about the digital curvature flow, measured",
        "",
        f"`python benchmarks/theorems.py --count {args.count} --seed {args.seed}`: "
        f"{len(objects)} objects, {elapsed:.0f} s. Each cell: inputs where the claim holds / inputs it applies to.",
        "Guarded runs only for inputs of at most "
        f"{args.guard_max_voxels} voxels{' (skipped)' if args.no_guard else ''}.",
        "",
    ]
    families = list(FAMILIES) + (["sample mesh"] if any(f == "sample mesh" for f, _, _ in objects) else []) + ["all"]
    for conn in args.connectivity:
        lines += [f"## {conn}-connectivity", "", "| family | " + " | ".join(CLAIMS) + " |", "|---" * (len(CLAIMS) + 1) + "|"]
        for fam in families:
            row = tally[(conn, fam)]
            cells = []
            for claim in CLAIMS:
                h, a = row[claim]
                cells.append(f"{h}/{a}" if a else "-")
            name = f"**{fam}**" if fam == "all" else fam
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += ["## How the runs stopped", "", "| connectivity | run | stop reasons |", "|---|---|---|"]
    for (conn, run), reasons in sorted(stops.items()):
        text = ", ".join(f"{k} {v}" for k, v in sorted(reasons.items(), key=lambda kv: -kv[1]))
        lines.append(f"| {conn} | {run} | {text} |")
    lines.append("")
    lines += ["## Smallest counterexamples", "", "| claim | connectivity | input | voxels | file |", "|---|---|---|---|---|"]
    for (claim, conn), (n, name, v) in sorted(smallest.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        slug = _slug(claim)
        lines.append(f"| {claim} | {conn} | {name} | {n} | `counterexamples/{slug}_{conn}.npy` |")
    lines.append("")
    text = "\n".join(lines)
    (out / "theorems.md").write_text(text)
    (out / "theorems.json").write_text(
        json.dumps({f"{c}/{fam}": {k: v for k, v in row.items()} for (c, fam), row in tally.items()}, indent=1)
    )
    print(text)


if __name__ == "__main__":
    main()
