"""How often do the paper's claims about the digital curvature flow hold?

    python benchmarks/theorems.py                     # default sample, about 15-30 minutes
    python benchmarks/theorems.py --count 10 --no-guard   # a quick look

Runs the flow (isoflow.flow.run.run_flow, the reading of docs/flow.md) on
many objects -- random unions of boxes, dumbbells, solid tori and square
annulus prisms, digital balls, smoothed random blobs, two linked square rings,
and the sample meshes voxelised at 32 and 64 voxels across (when
``isoflow.mesh.voxelize`` is available) -- and counts, per family and
connectivity, how often each claim holds:

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
* **guard** -- with topology control (issue 10), how often the run ends
  ``converged`` at a fixed point; **guard minimal** -- how often that end
  state is minimal: no simple voxel left, and one voxel for every component
  without tunnels or cavities. Every guarded state's Betti numbers are
  asserted equal to the input's. The stop reasons of the plain and the
  guarded runs, and the guarded steps by kind, are tabulated too.

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

CLAIMS = ("T20-23 cuboid", "single voxel", "T21 (1,0,0)", "kept, other inputs", "T24", "T25", "guard",
          "guard minimal")
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


def linked_rings(rng):
    """Two square rings, each through the other's hole (a Hopf link), apart,
    in a random orientation: b = (2, 2, 0) at 6 and at 26."""
    thick = int(rng.integers(1, 3))
    side = int(rng.integers(3 * thick + 4, 3 * thick + 10))
    mid = (side - thick) // 2
    a = int(rng.integers(thick + 1, side - 2 * thick))  # ring 2's wall inside ring 1's hole
    v = np.zeros((a + side, side, side), bool)

    def ring(lo, axes):
        sl = [slice(None)] * 3
        c = 3 - sum(axes)
        for ax in axes:
            sl[ax] = slice(lo[ax], lo[ax] + side)
        sl[c] = slice(lo[c], lo[c] + thick)
        v[tuple(sl)] = True
        for ax in axes:
            sl[ax] = slice(lo[ax] + thick, lo[ax] + side - thick)
        v[tuple(sl)] = False

    ring((0, 0, mid), (0, 1))
    first = v.copy()
    ring((a, mid, 0), (0, 2))
    v[first] = True
    return np.transpose(v, rng.permutation(3))


FAMILIES = {
    "union of boxes": union_of_boxes,
    "dumbbell": dumbbell,
    "solid torus": solid_torus,
    "annulus prism": annulus_prism,
    "digital ball": digital_ball,
    "random blob": blob,
    "linked rings": linked_rings,
}


def mesh_objects(directories, resolutions=(32, 64)):
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
                    vol = vx.voxelize(v, f, resolution=res)[0]
                except Exception as exc:  # a mesh the voxeliser refuses: say so, go on
                    print(f"{p.name} at {res}: skipped ({exc.__class__.__name__}: {exc})", file=sys.stderr)
                    continue
                if vol.any():
                    out.append((f"{p.name}@{res}", vol))
    return out


# --------------------------------------------------------------------------
# Claims
# --------------------------------------------------------------------------


def minimal_end(volume, connectivity) -> bool:
    """No simple voxel left, and one voxel per component without tunnels or
    cavities."""
    from scipy import ndimage

    from isoflow.digital.simple import simple_points
    from isoflow.digital.topology import betti_numbers

    if simple_points(volume, np.argwhere(volume), connectivity).any():
        return False
    full = connectivity == 26
    labels, n = ndimage.label(volume, ndimage.generate_binary_structure(3, 3 if full else 1))
    for c in range(1, n + 1):
        comp = labels == c
        if betti_numbers(comp, connectivity)[1:] == [0, 0] and comp.sum() != 1:
            return False
    return True


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
        out["guard minimal"] = out["guard"] and minimal_end(g.states[-1].volume, connectivity)
        info["guarded"] = g.stop_reason
        info["kinds"] = g.guard_steps
        info["end"] = (g.steps[-1]["voxels"], tuple(first))
    return out, info


def _slug(claim: str) -> str:
    return "".join(c if c.isalnum() else "-" for c in claim).strip("-").replace("--", "-")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=40, help="objects per synthetic family")
    ap.add_argument("--seed", type=int, default=2013)
    ap.add_argument("--connectivity", type=int, nargs="+", default=[6, 26])
    ap.add_argument("--no-guard", action="store_true", help="skip the guarded runs")
    ap.add_argument("--guard-max-voxels", type=int, default=10**6, help="guarded runs only below this size")
    ap.add_argument("--meshes", nargs="*", default=[str(ROOT / "meshes")])
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
    kinds = defaultdict(lambda: defaultdict(int))  # (conn, family) -> guarded step kind -> count
    ends = defaultdict(list)  # (conn, family) -> [(end voxels, betti)]
    t0 = time.time()
    for conn in args.connectivity:
        for family, name, v in objects:
            guard = not args.no_guard and v.sum() <= args.guard_max_voxels
            res, info = check(v, conn, guard)
            for run in ("plain", "guarded"):
                if run in info:
                    stops[(conn, run)][info[run]] += 1
            for key in (family, "all"):
                for kind, n in (info.get("kinds") or {}).items():
                    kinds[(conn, key)][kind] += n
                if "end" in info:
                    ends[(conn, key)].append(info["end"])
            for claim, ok in res.items():
                for key in (family, "all"):
                    tally[(conn, key)][claim][1] += 1
                    tally[(conn, key)][claim][0] += bool(ok)
                if not ok and claim not in INFO:
                    n = int(v.sum())
                    if (claim, conn) not in smallest or n < smallest[(claim, conn)][0]:
                        smallest[(claim, conn)] = (n, name, v)
    elapsed = time.time() - t0

    for conn in args.connectivity:  # counterexamples of an earlier run that no longer fail
        for old in (out / "counterexamples").glob(f"*_{conn}.npy"):
            old.unlink()
    for (claim, conn), (_, _, v) in smallest.items():
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
    if kinds:
        lines += [
            "## Guarded runs: steps by kind and end states",
            "",
            "Steps: the whole flow step / the flow step with its stuck blocks resolved / thinning on the same "
            "lattice. End voxels: median and largest over the family; for inputs without tunnels or cavities "
            "the end is one voxel per component.",
            "",
            "| connectivity | family | flow | partial | thinning | end voxels (median, max) | "
            "end voxels = b0, inputs without tunnels or cavities |",
            "|---|---|---|---|---|---|---|",
        ]
        for conn in args.connectivity:
            for fam in families:
                k, e = kinds[(conn, fam)], ends[(conn, fam)]
                if not e:
                    continue
                vox = np.array([n for n, _ in e])
                trivial = [(n, b) for n, b in e if b[1:] == (0, 0)]
                ok = sum(n == b[0] for n, b in trivial)
                name = f"**{fam}**" if fam == "all" else fam
                lines.append(
                    f"| {conn} | {name} | {k['flow']} | {k['partial']} | {k['thinning']} | "
                    f"{int(np.median(vox))}, {int(vox.max())} | {f'{ok}/{len(trivial)}' if trivial else '-'} |"
                )
        lines.append("")
    lines += ["## Smallest counterexamples", "", "| claim | connectivity | input | voxels | file |", "|---|---|---|---|---|"]
    for (claim, conn), (n, name, _) in sorted(smallest.items(), key=lambda kv: (kv[0][1], kv[0][0])):
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
