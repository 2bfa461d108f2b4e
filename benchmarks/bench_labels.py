"""The label table against the tools a user would otherwise pick (issue 25).

    python benchmarks/bench_labels.py                                  # 256^3: 1,000 and 100,000 labels
    python benchmarks/bench_labels.py --size 512 --labels 1000 --commands 3
    python benchmarks/bench_labels.py --size 128 --labels 100 --repeat 1 --json ''   # a quick look

Input (generated, cached in benchmarks/.cache/): a grain map, Voronoi cells
of jittered seeds on a grid (one per cell, ``--labels`` of them: the grid
is the factorisation of the count nearest a cube), with pores cut in (balls
of label 0, about 1.5 % of the volume); ``uint32``.

In process, in fresh child processes, the tools alternated, best of
``--repeat`` children; each child loads imports and numba's cached code on
a 160^3 corner, loads the input, resets its peak RSS (through
``/proc/self/clear_refs``), calls the tool once untimed and once timed
(the peak memory: the largest over both and over the children):

* ``isoflow.label_table(image, 6)``: every label's row with its surfaces;
* ``isoflow.analyze(image > 0, 6)``: one binary report of the same volume
  (the grains' union), and ``analyze(image == L, 6)`` for one label: what
  a loop over the labels pays per label;
* ``skimage.measure.regionprops_table(image, properties=("label", "area",
  "euler_number"))``: voxel counts and the Euler characteristic (26).

With more than one ``--labels`` count, the census of each input (its
runs, and its lattice vertices whose block holds two values or more, three
or more) says how much more boundary the larger count has, which any pass
that follows the boundary pays for.

With more than one ``--labels`` count, one more input separates what the
number of labels costs from what the boundary costs: the map of the most
labels with its labels folded onto the fewest (label ``(L - 1) % M + 1``:
the same grains and pores, so nearly the same boundary, a neighbouring
grain sharing a label about once in ``M / 14``; every label then ``N / M``
grains). ``label_table`` on it against the map as it is says whether a
label costs anything beyond its boundary.

With ``--stages N``, one more child times the label table's stages warm,
best of N each: the pieces, the vertex pass and the rest (the graph of
pieces, the surfaces, the columns).

Extra peak memory is the child's peak RSS during the tool less its RSS
with the input loaded, per voxel. Whole commands (``--commands N``,
alternated): ``isoflow info FILE.npy --labels --json`` against ``python -c``
running the same ``regionprops_table`` on ``np.load(FILE)``; medians.

Results go to ``benchmarks/results/labels.json`` (``--json``) and a
Markdown table on stdout, with the issue's ratios (label_table over one
binary analyze, regionprops_table over info --labels as whole commands,
label_table at the most labels over the fewest, bytes per voxel); paths in
them are relative to the repository.
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CACHE = ROOT / "benchmarks" / ".cache"


def grid_for(count: int) -> tuple[int, int, int]:
    """Three factors of ``count``, as near a cube as they come."""
    best = (count, 1, 1)
    for a in range(1, round(count ** (1 / 3)) + 2):
        if count % a:
            continue
        for b in range(a, int(np.sqrt(count // a)) + 2):
            if (count // a) % b == 0:
                c = count // a // b
                if max(a, b, c) < max(best):
                    best = tuple(sorted((a, b, c)))
    return best


def grains(size: int, count: int, seed: int = 0) -> np.ndarray:
    """The grain map (see the module docs)."""
    from numba import njit

    @njit(cache=False)
    def voronoi(out, seeds, cells, cell):
        nx, ny, nz = out.shape
        for x in range(nx):
            i = min(int(x / cell[0]), cells[0] - 1)
            for y in range(ny):
                j = min(int(y / cell[1]), cells[1] - 1)
                for z in range(nz):
                    k = min(int(z / cell[2]), cells[2] - 1)
                    best, label = 1e30, 0
                    for a in range(max(i - 1, 0), min(i + 2, cells[0])):
                        for b in range(max(j - 1, 0), min(j + 2, cells[1])):
                            for c in range(max(k - 1, 0), min(k + 2, cells[2])):
                                s = (a * cells[1] + b) * cells[2] + c
                                d = ((x + .5 - seeds[s, 0]) ** 2 + (y + .5 - seeds[s, 1]) ** 2
                                     + (z + .5 - seeds[s, 2]) ** 2)
                                if d < best:
                                    best, label = d, s + 1
                    out[x, y, z] = label

    rng = np.random.default_rng(seed)
    cells = np.array(grid_for(count))
    cell = size / cells
    index = np.indices(cells).reshape(3, -1).T
    seeds = (index + rng.uniform(0.1, 0.9, index.shape)) * cell
    out = np.empty((size,) * 3, np.uint32)
    voronoi(out, seeds, cells, cell)
    radius = 0.3 * float(cell.min())  # pores about a third of a grain across
    pores = int(0.015 * size**3 / (4 / 3 * np.pi * radius**3)) + 1
    for c in rng.uniform(0, size, (pores, 3)):
        r = radius * rng.uniform(0.6, 1.4)
        lo = np.maximum(np.floor(c - r).astype(int), 0)
        hi = np.minimum(np.ceil(c + r).astype(int) + 1, size)
        g = np.ogrid[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]]
        inside = sum((g[a] + 0.5 - c[a]) ** 2 for a in range(3)) <= r * r
        out[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]][inside] = 0
    return out


def cached_array(name: str, make) -> Path:
    """``benchmarks/.cache/NAME.npy``, made by ``make()`` the first time."""
    CACHE.mkdir(parents=True, exist_ok=True)
    path = CACHE / f"{name}.npy"
    if not path.exists():
        np.save(path, make())
    return path


def cached(size: int, count: int) -> Path:
    return cached_array(f"grains-{size}-{count}", lambda: grains(size, count))


def folded(size: int, count: int, fewer: int) -> Path:
    """The grain map of ``count`` labels with its labels folded onto
    ``fewer`` (see the module docs), cached."""
    def make():
        image = np.load(cached(size, count))
        return np.where(image > 0, (image - 1) % fewer + 1, 0).astype(image.dtype)

    return cached_array(f"grains-{size}-{count}-as-{fewer}", make)


TOOLS = {
    "isoflow.label_table": "label_table(image, 6)",
    "isoflow.analyze.union": "analyze(image > 0, 6)",
    "isoflow.analyze.one": "analyze(image == label, 6)",
    "skimage.regionprops_table": "regionprops_table(image, properties=('label', 'area', 'euler_number'))",
}


def _tool(name: str):
    if name.startswith("isoflow"):
        import isoflow

        if name == "isoflow.label_table":
            return lambda image: isoflow.label_table(image, 6)
        if name == "isoflow.analyze.union":
            return lambda image: isoflow.analyze(image > 0, 6)
        return lambda image: isoflow.analyze(image == image[tuple(s // 2 for s in image.shape)], 6)
    from skimage.measure import regionprops_table

    return lambda image: regionprops_table(image, properties=("label", "area", "euler_number"))


def child(name: str, path: Path, repeat: int) -> dict:
    """One tool in this (child) process: best seconds of ``repeat`` calls
    after a first, untimed one on the whole input (every compiled path it
    takes loaded), and the extra peak bytes of all of them."""
    run = _tool(name)
    # imports and numba's cached code, most of it, on a corner (so that the
    # first call's peak is the tool's, not the loading's)
    run(np.ascontiguousarray(np.load(path, mmap_mode="r")[:160, :160, :160]))
    image = np.load(path)
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")  # the peak RSS back to the current RSS
    base = _rss()
    result = run(image)
    best = float("inf")
    for _ in range(repeat):
        result = None  # the last call's result is not part of the next one's peak
        start = time.perf_counter()
        result = run(image)
        best = min(best, time.perf_counter() - start)
    extra = max(0, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - base)
    rows = len(result["label"]) if isinstance(result, dict) and "label" in result else None
    return {"seconds": best, "extra_peak_bytes": extra, "bytes_per_voxel": extra / image.size, "rows": rows}


def stages(path: Path, repeat: int) -> dict:
    """The label table's stages in this (child) process, warm, best of
    ``repeat`` each: the pieces (``piece_runs``), the vertex pass and the
    rest (the graph of pieces, the surfaces, the columns)."""
    import isoflow.digital.label_table as lt
    from isoflow.scale.pieces import piece_runs, vertex_pass

    image = np.load(path)
    lt.label_table(image)
    best = {"pieces": float("inf"), "vertex_pass": float("inf"), "rest": float("inf")}
    for _ in range(repeat):
        t0 = time.perf_counter()
        pieces = piece_runs(image)
        t1 = time.perf_counter()
        want = lt.wanted_pieces(pieces["values"], image.dtype, None)
        passed = vertex_pass(image, pieces, want, lt.feature_table(6), lt.pass_tables(6, True), keep_runs=False)
        t2 = time.perf_counter()
        lt.columns(lt.rows_of_pieces(pieces, passed, image.dtype, 6, None), np.ones(3), np.zeros(3), True)
        t3 = time.perf_counter()
        for key, dt in (("pieces", t1 - t0), ("vertex_pass", t2 - t1), ("rest", t3 - t2)):
            best[key] = min(best[key], dt)
    return best


def census(path: Path) -> dict:
    """How much boundary the input has, which a pass that follows the
    boundary pays for: its runs (maximal stretches of one value along the
    last axis), and its lattice vertices whose 2x2x2 block holds two
    values or more, three or more (the outside a value of its own)."""
    image = np.load(path, mmap_mode="r")
    nx, ny, nz = image.shape
    runs, by_values = 0, np.zeros(9, np.int64)
    for x0 in range(0, nx + 1, 16):  # vertex layers x0 .. x1 - 1, from voxel layers x0 - 1 .. x1 - 1
        x1 = min(x0 + 16, nx + 1)
        lo, hi = max(x0 - 1, 0), min(x1, nx)
        block = np.full((x1 - x0 + 1, ny + 2, nz + 2), -1, np.int64)
        block[lo - x0 + 1:hi - x0 + 1, 1:-1, 1:-1] = image[lo:hi]
        octants = [block[dx:dx + x1 - x0, dy:dy + ny + 1, dz:dz + nz + 1]
                   for dx in (0, 1) for dy in (0, 1) for dz in (0, 1)]
        ordered = np.sort(np.stack(octants, axis=-1), axis=-1)
        by_values += np.bincount(1 + np.count_nonzero(np.diff(ordered, axis=-1), axis=-1).ravel(), minlength=9)
        layers = np.asarray(image[x0:min(x1, nx)])
        runs += layers.shape[0] * ny + int(np.count_nonzero(layers[:, :, 1:] != layers[:, :, :-1]))
    return {"runs": runs, "boundary_vertices": int(by_values[2:].sum()), "vertices_of_3_or_more": int(by_values[3:].sum())}


def _rss() -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    return 0


def in_child(name: str, path: Path, repeat: int) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", name, str(path), "--repeat", str(repeat)],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def commands(path: Path, pairs: int, options: tuple[str, ...] = ()) -> dict:
    """Whole commands, alternated: medians of wall seconds and their ratio
    (``options``: more of ``isoflow info``'s)."""
    ours = [sys.executable, "-m", "isoflow", "info", str(path), "--labels", "--json", *options]
    script = ("import sys, numpy as np; from skimage.measure import regionprops_table; "
              "t = regionprops_table(np.load(sys.argv[1]), properties=('label', 'area', 'euler_number')); "
              "print(len(t['label']))")
    theirs = [sys.executable, "-c", script, str(path)]
    times: dict[str, list[float]] = {"isoflow": [], "skimage": []}
    for _ in range(pairs):
        for key, cmd in (("isoflow", ours), ("skimage", theirs)):
            start = time.perf_counter()
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
            times[key].append(time.perf_counter() - start)
    med = {k: statistics.median(v) for k, v in times.items()}
    return {"isoflow_seconds": med["isoflow"], "skimage_seconds": med["skimage"],
            "ratio": med["skimage"] / med["isoflow"], "pairs": pairs}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--labels", type=int, nargs="+", default=[1000, 100_000])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--commands", type=int, default=1, help="pairs of whole commands per input (0: none)")
    ap.add_argument("--tools", nargs="+", default=list(TOOLS), choices=list(TOOLS))
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "labels.json"))
    ap.add_argument("--stages", type=int, default=0,
                    help="also time the label table's stages in one warm child, best of N (0: not)")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        work = stages if args.child[0] == "stages" else lambda path, repeat: child(args.child[0], path, repeat)
        print(json.dumps(work(Path(args.child[1]), args.repeat)))
        return 0
    results = []
    for count in args.labels:
        path = cached(args.size, count)
        best: dict[str, dict] = {}
        for _ in range(args.repeat):  # the tools alternated, a fresh child each, best of --repeat
            for name in args.tools:
                rec = in_child(name, path, 1)
                old = best.get(name)
                if old is None or rec["seconds"] < old["seconds"]:
                    rec["bytes_per_voxel"] = max(rec["bytes_per_voxel"], old["bytes_per_voxel"] if old else 0)
                    best[name] = rec
                else:
                    old["bytes_per_voxel"] = max(old["bytes_per_voxel"], rec["bytes_per_voxel"])
        for name in args.tools:
            rec = {"size": args.size, "labels": count, "tool": name, "call": TOOLS[name], **best[name]}
            results.append(rec)
            print(f"{args.size}^3 {count} labels {name}: {rec['seconds']:.3f} s, "
                  f"{rec['bytes_per_voxel']:.2f} B/voxel", file=sys.stderr)
        if len(args.labels) > 1:
            results.append({"size": args.size, "labels": count, "tool": "census", **census(path)})
        if args.stages:
            results.append({"size": args.size, "labels": count, "tool": "stages",
                            **in_child("stages", path, args.stages)})
        if args.commands:
            results.append({"size": args.size, "labels": count, "tool": "commands",
                            "input": str(path.relative_to(ROOT)), **commands(path, args.commands)})
    if len(args.labels) > 1 and "isoflow.label_table" in args.tools:
        few, many = min(args.labels), max(args.labels)
        path = folded(args.size, many, few)
        best_one = min((in_child("isoflow.label_table", path, 1) for _ in range(args.repeat)), key=lambda r: r["seconds"])
        results.append({"size": args.size, "labels": few, "folded_from": many, "tool": "folded",
                        "input": str(path.relative_to(ROOT)), "call": TOOLS["isoflow.label_table"], **best_one,
                        **census(path)})
        print(f"{args.size}^3 {many} labels folded onto {few}: label_table {best_one['seconds']:.3f} s", file=sys.stderr)
    summary = targets(results)
    print(markdown(args, results))
    print("\n".join(f"* {line}" for line in summary["lines"]))
    if args.json:
        meta = {"command": "python benchmarks/bench_labels.py " + " ".join(argv or sys.argv[1:]),
                "machine": f"{platform.processor() or platform.machine()}, {_cpus()} CPUs", "python":
                platform.python_version(), "load_average": list(np.round(__import__("os").getloadavg(), 2))}
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps({"meta": meta, "results": results, "targets": summary["ratios"]},
                                              indent=1) + "\n")
    return 0


def targets(results: list[dict]) -> dict:
    """The issue's three ratios and the memory per voxel, from this run:
    label_table over one binary analyze of the same volume (at most 3),
    regionprops_table over info --labels as whole commands (at least 3),
    label_table at the most labels over the fewest, same size, in process and
    as whole commands (at most 2),
    and label_table's extra peak bytes per voxel (at most 8)."""
    def seconds(tool, count):
        return next((r["seconds"] for r in results if r["tool"] == tool and r["labels"] == count), None)

    counts = sorted({r["labels"] for r in results})
    ratios: dict[str, float] = {}
    lines = []
    for count in counts:
        ours, union = seconds("isoflow.label_table", count), seconds("isoflow.analyze.union", count)
        if ours and union:
            ratios[f"label_table/analyze at {count}"] = ours / union
            lines.append(f"{count:,} labels: label_table {ours / union:.2f}x one binary analyze (target <= 3)")
        for r in results:
            if r["labels"] == count and r["tool"] == "commands":
                ratios[f"commands regionprops/isoflow at {count}"] = r["ratio"]
                lines.append(f"{count:,} labels: whole commands, regionprops_table {r['ratio']:.2f}x the time of "
                             f"info --labels (target >= 3)")
            if r["labels"] == count and r["tool"] == "isoflow.label_table":
                ratios[f"bytes/voxel at {count}"] = r["bytes_per_voxel"]
                lines.append(f"{count:,} labels: label_table {r['bytes_per_voxel']:.2f} B/voxel beyond the input "
                             f"(target <= 8)")
    for r in results:
        if r["tool"] == "folded" and seconds("isoflow.label_table", r["folded_from"]):
            ratio = seconds("isoflow.label_table", r["folded_from"]) / r["seconds"]
            ratios[f"label_table {r['folded_from']}/{r['folded_from']} folded onto {r['labels']}"] = ratio
            mine = next((c["boundary_vertices"] for c in results if c["tool"] == "census"
                         and c["labels"] == r["folded_from"]), None)
            lines.append(f"label_table at {r['folded_from']:,} labels {ratio:.2f}x its time on the same map folded onto "
                         f"{r['labels']:,} labels (boundary vertices {r['boundary_vertices']:,} against {mine or 0:,}): "
                         "what the labels cost beyond their boundary")
    if len(counts) > 1 and seconds("isoflow.label_table", counts[0]) and seconds("isoflow.label_table", counts[-1]):
        ratio = seconds("isoflow.label_table", counts[-1]) / seconds("isoflow.label_table", counts[0])
        ratios[f"label_table {counts[-1]}/{counts[0]}"] = ratio
        lines.append(f"label_table at {counts[-1]:,} labels {ratio:.2f}x its time at {counts[0]:,} (target <= 2)")
        whole = {r["labels"]: r["isoflow_seconds"] for r in results if r["tool"] == "commands"}
        if counts[0] in whole and counts[-1] in whole:  # what a user waits for, start-up and the JSON text included
            ratio = whole[counts[-1]] / whole[counts[0]]
            ratios[f"commands isoflow {counts[-1]}/{counts[0]}"] = ratio
            lines.append(f"info --labels --json at {counts[-1]:,} labels {ratio:.2f}x its time at {counts[0]:,} as whole "
                         "commands (target <= 2)")
        grown = [r for r in results if r["tool"] == "census" and r["labels"] in (counts[0], counts[-1])]
        if len(grown) == 2:
            few, many = sorted(grown, key=lambda r: r["labels"])
            for key in ("runs", "boundary_vertices", "vertices_of_3_or_more"):
                ratios[f"{key} {counts[-1]}/{counts[0]}"] = many[key] / few[key]
            lines.append("the input grows from {:,} to {:,} labels: runs {:.2f}x, boundary vertices {:.2f}x, vertices "
                         "of three values or more {:.2f}x".format(counts[0], counts[-1], *(
                             many[k] / few[k] for k in ("runs", "boundary_vertices", "vertices_of_3_or_more"))))
    return {"ratios": ratios, "lines": lines}


def _cpus() -> int:
    from isoflow.scale.compiled import available_cpus

    return available_cpus()


def markdown(args, results: list[dict]) -> str:
    lines = ["| size | labels | tool | seconds | extra peak B/voxel | vs label_table |", "|---|---:|---|---:|---:|---:|"]
    for count in args.labels:
        rows = [r for r in results if r["labels"] == count and r["tool"] not in ("commands", "stages", "census", "folded")]
        ours = next((r["seconds"] for r in rows if r["tool"] == "isoflow.label_table"), None)
        for r in rows:
            ratio = f"{r['seconds'] / ours:.2f}x" if ours else "-"
            lines.append(f"| {r['size']}^3 | {count:,} | {r['call']} | {r['seconds']:.3f} | "
                         f"{r['bytes_per_voxel']:.2f} | {ratio} |")
        for r in results:
            if r["labels"] == count and r["tool"] == "commands":
                lines.append(f"| {r['size']}^3 | {count:,} | whole commands: isoflow info --labels --json "
                             f"{r['isoflow_seconds']:.2f} s, regionprops_table {r['skimage_seconds']:.2f} s | - | - | "
                             f"{r['ratio']:.2f}x |")
            if r["labels"] == count and r["tool"] == "folded":
                lines.append(f"| {r['size']}^3 | {count:,} | the {r['folded_from']:,}-label map folded onto {count:,} "
                             f"labels: {r['call']} | {r['seconds']:.3f} | {r['bytes_per_voxel']:.2f} | - |")
            if r["labels"] == count and r["tool"] == "stages":
                lines.append(f"| {r['size']}^3 | {count:,} | stages, warm: pieces {r['pieces']:.3f} s, vertex pass "
                             f"{r['vertex_pass']:.3f} s, the rest {r['rest']:.3f} s | - | - | - |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
