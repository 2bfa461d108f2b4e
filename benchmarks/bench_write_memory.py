"""Peak memory of each volume writer beside the volume it writes, against
the ``write_bytes`` that the voxeliser's memory check counts for it.

    python benchmarks/bench_write_memory.py                       # masks 512^3, labels 320^3
    python benchmarks/bench_write_memory.py --sizes 256 --only .h5 .tif

Each write runs in a fresh process: the format's library is loaded first
(a write of a 4^3 volume), then the volume is made a slab at a time (no
temporary of its size), the peak resident memory is reset
(``/proc/self/clear_refs``), the volume is written with
``isoflow.write_volume`` (a mask) or ``isoflow.write_labels`` (labels),
and the rise of ``VmHWM`` over the resident memory before the write,
divided by the voxels, is the writer's bytes per voxel. A mask is
written random (half the voxels set: what gzip shrinks least), a ball and
full (what MagicaVoxel lists whole); labels random over their type's
range (the most a compressor keeps) and in constant 16^3 blocks (as a
label image of meshes is). ``estimate`` is
``write_bytes_per_voxel(path, labels=...)`` (the registry's
``write_bytes``, or ``label_bytes`` for labels) times the bytes per voxel
of the array (1 for a mask), as ``voxelize -o`` counts it; ``ratio`` is
the estimate over the measured bytes (from 0.95 to 2 is the aim; none
where the writer holds under 0.05 bytes a voxel). A writer that holds a
fixed amount too (a buffer, chunks encoded at once) shows bytes per voxel
that fall as the volume grows: compare two sizes.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = r"""
import json, sys
from pathlib import Path
import numpy as np
import isoflow

suffix, dtype, content, n, folder, most = json.loads(sys.argv[1])
dtype = np.dtype(dtype)


def status(key):
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) * 1024 for line in fh if line.startswith(key))


def make(n):
    vol = np.empty((n, n, n), dtype)
    rng = np.random.default_rng(0)
    top = 1 if dtype == bool else min(int(np.iinfo(dtype).max), most)  # the format's largest label at most
    ax = np.arange(n)
    for i in range(n):  # a slab at a time: no temporary of the volume's size before the write
        if content == "random":
            vol[i] = rng.random((n, n)) < 0.5 if dtype == bool else rng.integers(0, top, (n, n), dtype, endpoint=True)
        elif content == "full":
            vol[i] = top
        elif content == "ball":
            vol[i] = ((i - n / 2) ** 2 + (ax[:, None] - n / 2) ** 2 + (ax[None, :] - n / 2) ** 2) < (0.45 * n) ** 2
        else:  # constant 16^3 blocks, their labels spread over the type
            block = (i // 16) * 4096 + (ax[:, None] // 16) * 64 + ax[None, :] // 16
            vol[i] = 1 + (block * 7919) % top if top > 1 else block % 2
    if dtype != bool:
        vol.flat[-1] = top  # the labels need their type (write_labels narrows a type wider than its labels)
    return vol


def write(vol, path):
    if dtype == bool:
        isoflow.write_volume(vol, path)
    else:
        isoflow.write_labels(vol, path)


def made(n):  # a mask as voxelize gives it to write_volume: an object
    return isoflow.DigitalObject(make(n)) if dtype == bool else make(n)


write(made(4), str(Path(folder) / ("warm" + suffix)))  # the library's modules loaded before the peak is taken
vol = made(n)
with open("/proc/self/clear_refs", "w") as fh:
    fh.write("5")  # VmHWM from the resident memory now: the volume's
before = status("VmRSS")
write(vol, str(Path(folder) / ("out" + suffix)))
array = vol.volume if dtype == bool else vol
print(json.dumps({"peak": status("VmHWM") - before, "voxels": array.size, "itemsize": array.dtype.itemsize}))
"""

#: a suffix that the registry does not list, written by a writer of its own (TIFF's OME branch)
EXTRA_SUFFIXES = (".ome.tif",)


def label_types(max_label: int | None) -> tuple[str, ...]:
    """The label types a format is measured with: uint16 and uint32 as far
    as its largest label reaches (labels above it are refused), uint8
    where it keeps no more (MagicaVoxel's 255 colours), none where it
    keeps a mask alone (binvox); a label image that needs its type (its
    largest label at the type's top, or the format's)."""
    if max_label == 1:
        return ()
    if max_label is not None and max_label < 2**16 - 1:
        return ("uint8",)
    if max_label is not None and max_label < 2**31 - 1:
        return ("uint16",)
    return ("uint16", "uint32")  # MGH's int32 takes uint32 labels up to 2**31 - 1


def measure(suffix: str, dtype: str, content: str, n: int, folder: str, most: int) -> dict:
    done = subprocess.run([sys.executable, "-c", CHILD, json.dumps([suffix, dtype, content, n, folder, most])],
                          capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"{suffix} {dtype} {content} {n}: {done.stderr.strip().splitlines()[-1]}")
    return json.loads(done.stdout)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[512], help="sides of the masks (MagicaVoxel: 256 at most)")
    ap.add_argument("--label-sizes", type=int, nargs="+", default=[320], help="sides of the label images")
    ap.add_argument("--only", nargs="+", help="these suffixes only (e.g. .h5 .tif)")
    ap.add_argument("--json", type=Path, help="write the rows here too")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
    from isoflow.mesh.formats.registry import format_for, volume_suffixes
    from isoflow.mesh.volumes import write_bytes_per_voxel

    rows = []
    print(f"{'suffix':9} {'array':7} {'content':7} {'side':>5} {'B/voxel':>8} {'estimate':>8} {'ratio':>6}")
    for suffix in (*volume_suffixes(writable=True), *EXTRA_SUFFIXES):
        if args.only and suffix not in args.only:
            continue
        fmt = format_for("x" + suffix, writing=True)
        assert fmt is not None, suffix
        cases = [("bool", c, s) for c in ("random", "ball", "full") for s in args.sizes]
        cases += [(t, c, s) for t in label_types(fmt.max_label) for c in ("random", "blocks") for s in args.label_sizes]
        for dtype, content, n in cases:
            n = min(n, 256) if suffix == ".vox" else n
            with tempfile.TemporaryDirectory() as folder:
                got = measure(suffix, dtype, content, n, folder, fmt.max_label or 2**64 - 1)
            per_voxel = got["peak"] / got["voxels"]
            estimate = write_bytes_per_voxel("x" + suffix, labels=dtype != "bool") * got["itemsize"]
            # a writer that holds next to nothing has no ratio worth reading
            ratio = round(estimate / per_voxel, 2) if per_voxel >= 0.05 else None
            rows.append({"suffix": suffix, "array": dtype, "content": content, "side": n,
                         "bytes_per_voxel": round(per_voxel, 3), "estimate": round(estimate, 3), "ratio": ratio})
            shown = "-" if ratio is None else f"{ratio:.2f}"
            print(f"{suffix:9} {dtype:7} {content:7} {n:5d} {per_voxel:8.3f} {estimate:8.3f} {shown:>6}", flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
