"""The read-back of written surfaces, in process, this tree against another.

    python benchmarks/bench_readback.py --baseline ../main/src     # this tree vs another checkout's src
    python benchmarks/bench_readback.py --repeat 3 --json ''       # this tree only, no file written

Every ``isoflow surface ... -o FILE`` reads the file it wrote back and
compares it with isoflow's counts. Timed here, each tree in a child
process of its own (``PYTHONPATH`` its ``src``; numba's caches warmed by
one untimed call), best of ``--repeat``:

* **GLB of many labels**: label images of 1,000 and 5,000 small boxes
  (1 to 3 voxels a side, one per cell of a grid, seeded), written once as
  ``isoflow surface LABELS --labels -o OUT.glb --no-check`` by this tree;
  timed: ``check_scene_figures`` against the label table's figures
  (``scene_expected``), what the command runs after writing; it must find
  no problem.
* **OBJ of mixed polygons**: the surface of a random 60^3 volume (30 %
  filled, seeded), whose edge contacts give it quads and pentagons
  (275,000 faces); timed: ``check_surface_file``, which must agree.
* **A 3D Slicer segmentation**: a ``.seg.nrrd`` of the 5,000-label image
  with a header of 5,000 segments (ten fields each, as Slicer writes
  them); timed: ``read_labels`` and then the note naming its segments
  (``say_segments``), as ``isoflow info --labels`` and ``surface --labels``
  run them.

Inputs are made once under ``benchmarks/.cache/``. Results go to
``benchmarks/results/readback.json`` and a Markdown table on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / "benchmarks" / ".cache"

#: what a child process runs: every read-back timed in the tree it imports
CHILD = r"""
import argparse, contextlib, io, json, sys, time
import numpy as np
from isoflow.cli.labels import say_segments, scene_expected
from isoflow.digital.connectivity import resolve_connectivity
from isoflow.digital.label_table import label_table
from isoflow.digital.lattice import DigitalObject
from isoflow.digital.surface import boundary_mesh
from isoflow.mesh.readback import check_scene_figures, check_surface_file
from isoflow.mesh.volumes import read_labels

spec, repeat = json.loads(sys.argv[1]), int(sys.argv[2])


def best(call, check):
    check(call())  # numba's caches loaded, the answer checked
    spent = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        spent.append(time.perf_counter() - start)
    return min(spent)


out = {}
for name, (image, glb) in spec["glb"].items():
    labels = np.load(image)
    table = label_table(labels, 6)
    expected = scene_expected(table, [f"label_{v}" for v in table["label"].tolist()], np.ones(3))
    out[f"glb {name}"] = best(lambda: check_scene_figures(glb, expected), lambda found: found == [] or sys.exit(found))
volume, path = np.load(spec["obj"][0]), spec["obj"][1]
obj = DigitalObject(volume)
mesh = boundary_mesh(volume, resolve_connectivity(3, 6))
comps = mesh.components()
out["obj mixed polygons"] = best(lambda: check_surface_file(path, mesh, obj, components=comps),
                                 lambda found: found["agree"] or sys.exit(found["problem"]))
seg = spec["seg"]
args = argparse.Namespace(command="info", input=seg, quiet=False)
out["seg.nrrd read_labels"] = best(lambda: read_labels(seg), lambda image: None)


def read_and_note():
    read_labels(seg)
    with contextlib.redirect_stderr(io.StringIO()) as said:
        say_segments(args)
    return said.getvalue()


out["seg.nrrd read_labels + note"] = best(read_and_note, lambda said: "3D Slicer segments" in said or sys.exit(said))
print(json.dumps(out))
"""


def boxes(count: int, seed: int = 0) -> np.ndarray:
    """``count`` labels, each a box of 1 to 3 voxels a side in its own cell
    of 4^3 on a grid, uint16."""
    side = int(np.ceil(count ** (1 / 3)))
    image = np.zeros((4 * side + 1,) * 3, np.uint16)
    rng = np.random.default_rng(seed)
    cells = np.indices((side,) * 3).reshape(3, -1).T[:count]
    for label, (cell, size) in enumerate(zip(cells, rng.integers(1, 4, (count, 3))), 1):
        lo = 1 + 4 * cell
        image[lo[0]:lo[0] + size[0], lo[1]:lo[1] + size[1], lo[2]:lo[2] + size[2]] = label
    return image


def inputs() -> dict:
    """The inputs (module docs), made once."""
    import nrrd

    CACHE.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    spec: dict = {"glb": {}}
    for count in (1000, 5000):
        image, glb = CACHE / f"readback-boxes-{count}.npy", CACHE / f"readback-boxes-{count}.glb"
        if not glb.exists():
            np.save(image, boxes(count))
            subprocess.run([sys.executable, "-m", "isoflow", "surface", str(image), "--labels", "-o", str(glb),
                            "--no-check", "--force", "--quiet"], check=True, env=env, capture_output=True)
        spec["glb"][f"{count:,} labels"] = (str(image), str(glb))
    volume, obj = CACHE / "readback-random60.npy", CACHE / "readback-random60.obj"
    if not obj.exists():
        np.save(volume, np.random.default_rng(1).random((60, 60, 60)) < 0.3)
        subprocess.run([sys.executable, "-c", "import sys, numpy as np; from isoflow.mesh.export import write_surface; "
                        "write_surface(np.load(sys.argv[1]), sys.argv[2], check=False, force=True)", str(volume),
                        str(obj)], check=True, env=env)
    spec["obj"] = (str(volume), str(obj))
    seg = CACHE / "readback-5000.seg.nrrd"
    if not seg.exists():
        header = {"space": "left-posterior-superior", "space directions": np.eye(3), "space origin": np.zeros(3),
                  "kinds": ["domain"] * 3, "encoding": "gzip"}
        for i in range(5000):
            header.update({f"Segment{i}_ID": f"Segment_{i + 1}", f"Segment{i}_Name": f"structure {i + 1}",
                           f"Segment{i}_NameAutoGenerated": "0", f"Segment{i}_Color": "0.5 0.5 0.5",
                           f"Segment{i}_ColorAutoGenerated": "1", f"Segment{i}_Extent": "0 3 0 3 0 3",
                           f"Segment{i}_Layer": "0", f"Segment{i}_LabelValue": str(i + 1),
                           f"Segment{i}_Tags": "Segmentation.Status:inprogress|",
                           f"Segment{i}_Description": ""})
        nrrd.write(str(seg), np.load(CACHE / "readback-boxes-5000.npy"), header, index_order="F")
    spec["seg"] = str(seg)
    return spec


def timed(src: Path, spec: dict, repeat: int) -> dict:
    """The child's timings (CHILD) with ``src`` on its path."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    done = subprocess.run([sys.executable, "-c", CHILD, json.dumps(spec), str(repeat)], check=True, env=env,
                          capture_output=True, text=True, cwd=ROOT)
    return json.loads(done.stdout)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--baseline", type=Path, help="another checkout's src")
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "readback.json"))
    args = p.parse_args(argv)
    spec = inputs()
    ours = timed(ROOT / "src", spec, args.repeat)
    theirs = timed(args.baseline.resolve(), spec, args.repeat) if args.baseline else {}
    print("| read-back | this tree s | baseline s | speedup |")
    print("|---|---:|---:|---:|")
    rows = []
    for name, s in ours.items():
        b = theirs.get(name)
        rows.append({"read_back": name, "seconds": s, "baseline_seconds": b, "speedup": b / s if b else None})
        print(f"| {name} | {s:.3f} | " + (f"{b:.3f} | {b / s:.2f}x |" if b else "| |"))
    if args.json:
        given = argv if argv is not None else sys.argv[1:]
        given = ["BASELINE_SRC" if args.baseline and a == str(args.baseline) else a for a in given]
        meta = {"command": "python benchmarks/bench_readback.py " + " ".join(given),
                "machine": f"{platform.machine()}, python {platform.python_version()}", "repeat": args.repeat}
        Path(args.json).write_text(json.dumps({"meta": meta, "results": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
