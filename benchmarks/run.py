"""isoflow against the tools a user would otherwise pick: time, peak memory, and
a check that everyone computes the same numbers.

    python benchmarks/run.py                          # 128^3 and 256^3
    python benchmarks/run.py --sizes 128 256 512 --repeat 3
    python benchmarks/run.py --sizes 64 --inputs ball --tools isoflow.info skimage.euler6
    python benchmarks/run.py --sizes 128 256 512 --tools isoflow.info isoflow.info.nosurf \
        skimage.euler6 skimage.euler26 --md benchmarks/results/info.md --json benchmarks/results/info.json

Inputs (generated once, cached as .npy in benchmarks/.cache/): a ball, a torus
and a smoothed random porous field (uniform noise, gaussian sigma 2, > 0.5,
seed 0), each ``size^3`` voxels.

Tasks, each measured in the same run on the same arrays:

``info`` (what ``isoflow info`` computes with its default flags:
  ``analyze(obj, 6)``, i.e. chi, Betti numbers, the class histogram n and
  every closed surface with its genus; ``isoflow.info.nosurf`` is
  ``surfaces=False``) against
  * ``skimage.measure.euler_number`` at connectivity 1 (6) and 3 (26): chi only;
  * the usual way to get Betti numbers: ``scipy.ndimage.label`` of the object
    (6-structure) and of the background (26-structure; cavities are background
    components off the array border) plus ``euler_number`` for chi;
  * the same with ``cc3d.connected_components`` (a dependency of isoflow's, which labels with it).
  isoflow's chi (6 and 26) and Betti numbers must equal the others' numbers,
  and its surfaces (count, faces, genus sum) the mesh's components when
  ``isoflow.mesh`` runs too.

``surface`` (the boundary quads: ``boundary_mesh(vol, 6)``) against
  * ``trimesh.voxel.VoxelGrid(vol).as_boxes()`` (12 triangles per voxel; only
    up to ``--boxes-max``, estimated beyond from the scaling of the two
    largest sizes run);
  * DGtal's digital surface (optional): the numpy array is copied element-wise
    into an ``SH3`` binary image (padded by one voxel, since DGtal leaves the
    surface open where the object touches the domain border), then
    ``makeLightDigitalSurfaces`` (all components) and ``getSurfelRange``. The
    copy and the extraction are timed and reported separately; a failing call
    is reported with its error. Its surfel count must equal isoflow's faces.

Every (tool, input, size) runs in a fresh child process (this script with the
hidden ``--child`` option): it imports and warms up the tool on a tiny array
(numba kernels compiled or loaded from their disk cache), loads the input
from the cache, resets the kernel's peak-RSS counter (``/proc/self/clear_refs``)
and records its RSS; ``ru_maxrss`` after the tool minus that RSS is the tool's
extra peak memory (its result included), given in bytes per voxel.

Seconds are the best of ``--repeat`` runs, fewer once a measurement has used
``--max-seconds`` (the slow peers run once at large sizes; the run count is
reported). ``ratio`` = other tool's seconds / isoflow's seconds on the same
input: > 1 means isoflow is faster. isoflow's numba kernels use every CPU
(they apply from 2M voxels); the peers run on one.

Whole commands (``--commands PAIRS``, default 3): ``isoflow info FILE --json``
as installed, with its default flags, against ``python -c "...
euler_number(np.load(FILE), connectivity=1)"``, each a fresh process
(imports, loading and all), alternated A B A B; medians, the median of the
pairs' ratios, each process's own peak RSS (``wait4``), and their printed chi
checked equal. Threads (``--threads N ...``, default 1 .. CPUs): the
in-process ``isoflow.info`` at the largest size with ``ISOFLOW_THREADS=N``,
interleaved, medians.

Writes the table to stdout, JSON (``--json``, with machine information) and a
markdown table (``--md``). Exits with 1 if any check fails.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import shlex
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CACHE = HERE / ".cache"
RESULTS = HERE / "results"
INPUT_VERSION = 1  # bump when a generator changes, to invalidate the cache


# --------------------------------------------------------------------------
# Inputs
# --------------------------------------------------------------------------


def _axes(n: int):
    c = (n - 1) / 2
    x = np.arange(n, dtype=np.float32) - c
    return x[:, None, None], x[None, :, None], x[None, None, :]


def ball(n: int) -> np.ndarray:
    x, y, z = _axes(n)
    return x**2 + y**2 + z**2 <= (0.45 * n) ** 2


def torus(n: int) -> np.ndarray:
    x, y, z = _axes(n)
    rho = np.sqrt(x**2 + y**2)
    return (rho - 0.3 * n) ** 2 + z**2 <= (0.12 * n) ** 2


def porous(n: int, seed: int = 0) -> np.ndarray:
    from scipy.ndimage import gaussian_filter

    field = np.random.default_rng(seed).random((n,) * 3, dtype=np.float32)
    gaussian_filter(field, 2.0, output=field)  # in place: 4 bytes/voxel at 512^3
    return field > 0.5


INPUTS = {"ball": ball, "torus": torus, "porous": porous}


def input_path(name: str, size: int) -> Path:
    return CACHE / f"{name}_{size}_v{INPUT_VERSION}.npy"


def ensure_input(name: str, size: int) -> Path:
    """Generate the input once (in a child, so that this driver stays small)."""
    path = input_path(name, size)
    if not path.exists():
        CACHE.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, __file__, "--make-input", name, str(size), str(path)], check=True)
    return path


def make_input(name: str, size: int, path: Path) -> None:
    vol = np.ascontiguousarray(INPUTS[name](size), dtype=bool)
    tmp = path.with_suffix(".tmp.npy")
    np.save(tmp, vol)
    tmp.replace(path)


# --------------------------------------------------------------------------
# Tools. Each is (group, label, fn(vol, measure)); ``measure(step, call,
# summary)`` times ``call`` and records its extra peak memory and the
# ``summary`` of its result. ``warmup(tiny)`` imports and exercises the tool.
# --------------------------------------------------------------------------


def _tiny() -> np.ndarray:
    v = np.zeros((6, 7, 8), bool)
    v[1:5, 1:6, 1:7] = True
    v[2:4, 3, 3] = False
    return v


def _border_labels(labels: np.ndarray) -> set:
    out = set()
    for axis in range(labels.ndim):
        for end in (0, -1):
            out.update(np.unique(np.take(labels, end, axis=axis)).tolist())
    out.discard(0)
    return out


def _info_summary(r):
    out = {"chi6": r["euler_characteristic"], "betti": r["betti"], "n": r["n"]}
    if r.get("surfaces") is not None:
        out["surfaces"] = len(r["surfaces"])
        out["faces"] = sum(s["faces"] for s in r["surfaces"])
        out["genus_sum"] = sum(s["genus"] for s in r["surfaces"])
    return out


def t_isoflow_info(vol, measure):
    from isoflow import DigitalObject, analyze
    from isoflow.digital.topology import euler_characteristic

    rep = measure("info", lambda: analyze(DigitalObject(vol), 6), _info_summary)
    del rep
    # not timed: chi at 26-connectivity, to check skimage's connectivity 3
    return {"chi26": int(euler_characteristic(vol, 26))}


def t_isoflow_info_nosurf(vol, measure):
    from isoflow import DigitalObject, analyze

    measure("info", lambda: analyze(DigitalObject(vol), 6, surfaces=False), _info_summary)


def w_isoflow(tiny):
    from isoflow import DigitalObject, analyze, boundary_mesh
    from isoflow.scale import compiled

    analyze(DigitalObject(tiny), 6)
    boundary_mesh(tiny, 6).components()
    if compiled.have_numba():  # load (or compile) the kernels used above MIN_VOXELS
        old, compiled.MIN_VOXELS = compiled.MIN_VOXELS, 0
        for c in (6, 26):
            analyze(DigitalObject(tiny), c)
            analyze(DigitalObject(tiny), c, surfaces=False)
        compiled.MIN_VOXELS = old


def t_euler(conn):
    def run(vol, measure):
        from skimage.measure import euler_number

        measure("euler", lambda: int(euler_number(vol, connectivity=conn)),
                lambda chi: {f"chi{6 if conn == 1 else 26}": chi})
    return run


def w_skimage(tiny):
    from skimage.measure import euler_number

    euler_number(tiny, 1), euler_number(tiny, 3)


def _betti(vol, label_obj, label_bg):
    from skimage.measure import euler_number

    chi = int(euler_number(vol, connectivity=1))
    lab, b0 = label_obj(vol)
    del lab
    lab, nbg = label_bg(~vol)
    b2 = int(nbg) - len(_border_labels(lab))
    del lab
    return {"chi6": chi, "betti": [int(b0), int(b0) + b2 - chi, b2]}


def t_scipy(vol, measure):
    from scipy.ndimage import generate_binary_structure, label

    s6, s26 = generate_binary_structure(3, 1), generate_binary_structure(3, 3)
    measure("betti", lambda: _betti(vol, lambda v: label(v, s6), lambda v: label(v, s26)), lambda r: r)


def w_scipy(tiny):
    from scipy.ndimage import generate_binary_structure, label

    label(tiny, generate_binary_structure(3, 3))
    w_skimage(tiny)


def t_cc3d(vol, measure):
    import cc3d

    measure("betti", lambda: _betti(vol, lambda v: cc3d.connected_components(v, connectivity=6, return_N=True),
                                    lambda v: cc3d.connected_components(v, connectivity=26, return_N=True)),
            lambda r: r)


def w_cc3d(tiny):
    import cc3d

    cc3d.connected_components(tiny, connectivity=26, return_N=True)
    w_skimage(tiny)


def t_isoflow_mesh(vol, measure):
    from isoflow import boundary_mesh

    def summary(m):  # not timed: the mesh's own components, to check info's surfaces
        comps = m.components()
        return {"faces": int(len(m.faces)), "vertices": int(len(m.vertices)), "surfaces": len(comps),
                "genus_sum": sum(c["genus"] for c in comps)}

    measure("mesh", lambda: boundary_mesh(vol, 6), summary)


def t_boxes(vol, measure):
    from trimesh.voxel import VoxelGrid

    measure("boxes", lambda: VoxelGrid(vol).as_boxes(), lambda m: {"triangles": int(len(m.faces))})
    return {"voxels": int(np.count_nonzero(vol))}


def w_boxes(tiny):
    from trimesh.voxel import VoxelGrid

    VoxelGrid(tiny).as_boxes()


def _dgtal_params():
    import dgtal

    p = dgtal.SH3.defaultParameters()
    p.set("surfaceComponents", "All")  # default "AnyBig" keeps one component
    return p


def t_dgtal(vol, measure):
    import dgtal

    SH3 = dgtal.SH3
    n0, n1, n2 = (s + 2 for s in vol.shape)
    # DGtal images run x fastest: numpy's last axis is DGtal's x
    dom = dgtal.kernel.DomainZ3i(dgtal.kernel.Point3D(0, 0, 0), dgtal.kernel.Point3D(n2 - 1, n1 - 1, n0 - 1))

    def copy():
        # the only numpy path in: a Python list (of bools, the cheapest kind)
        return SH3.makeBinaryImage(np.pad(vol, 1).ravel().tolist(), dom)

    bimg = measure("copy", copy, lambda b: {})
    if bimg is None:
        return None
    params = _dgtal_params()

    def surface():
        K = SH3.getKSpace(bimg, params)
        surfs = SH3.makeLightDigitalSurfaces(bimg, K, params)
        return surfs, [SH3.getSurfelRange(s, params) for s in surfs]

    measure("surface", surface, lambda r: {"components": len(r[0]), "faces": sum(len(s) for s in r[1])})


def w_dgtal(tiny):
    t_dgtal(tiny, lambda step, call, summary: call())


#: name -> (group, label, run, warmup, module needed)
TOOLS = {
    "isoflow.info": ("info", "isoflow analyze, default (chi, betti, n, surfaces)", t_isoflow_info, w_isoflow,
                     "isoflow"),
    "isoflow.info.nosurf": ("info", "isoflow analyze surfaces=False", t_isoflow_info_nosurf, w_isoflow, "isoflow"),
    "skimage.euler6": ("info", "skimage euler_number conn=1 (chi only)", t_euler(1), w_skimage, "skimage"),
    "skimage.euler26": ("info", "skimage euler_number conn=3 (chi only)", t_euler(3), w_skimage, "skimage"),
    "scipy.betti": ("info", "scipy label obj+bg + euler_number", t_scipy, w_scipy, "scipy"),
    "cc3d.betti": ("info", "cc3d label obj+bg + euler_number", t_cc3d, w_cc3d, "cc3d"),
    "isoflow.mesh": ("surface", "isoflow boundary_mesh", t_isoflow_mesh, w_isoflow, "isoflow"),
    "trimesh.boxes": ("surface", "trimesh VoxelGrid.as_boxes", t_boxes, w_boxes, "trimesh"),
    "dgtal.surface": ("surface", "DGtal", t_dgtal, w_dgtal, "dgtal"),
}
REFERENCE = {"info": ("isoflow.info", "info"), "surface": ("isoflow.mesh", "mesh")}
STEP_LABEL = {
    ("dgtal.surface", "copy"): "DGtal numpy->BinaryImage copy",
    ("dgtal.surface", "surface"): "DGtal makeLightDigitalSurfaces+getSurfelRange",
    ("dgtal.surface", "total"): "DGtal total from numpy (copy + surface)",
}


# --------------------------------------------------------------------------
# Child: one tool on one input
# --------------------------------------------------------------------------


def _rss() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _reset_peak() -> bool:
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")  # resets the peak RSS (VmHWM, hence ru_maxrss) to the current RSS
        return True
    except OSError:
        return False


def _maxrss() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # KiB on Linux


def child(tool: str, path: Path, repeat: int, max_seconds: float) -> dict:
    group, label, run, warmup, _ = TOOLS[tool]
    out: dict = {"tool": tool, "steps": []}
    try:
        warmup(_tiny())
    except Exception as e:  # noqa: BLE001 - report, do not crash the benchmark
        out["error"] = f"warmup: {type(e).__name__}: {e}"
        return out
    vol = np.load(path)
    out["rss_after_load"] = _rss()
    out["voxels"] = int(vol.size)

    def measure(step, call, summary):
        rec: dict = {"step": step, "times": []}
        out["steps"].append(rec)
        rec["peak_reset"] = _reset_peak()
        base = _rss()
        rec["rss_before"] = base
        result = None
        try:
            for _ in range(repeat):
                result = None  # free the previous result before the next run
                t = time.perf_counter()
                result = call()
                rec["times"].append(time.perf_counter() - t)
                if sum(rec["times"]) >= max_seconds:
                    break
        except Exception as e:  # noqa: BLE001
            rec["error"] = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"[:300]
            return None
        finally:
            rec["extra_peak_bytes"] = max(0, _maxrss() - base)
        rec["seconds"] = min(rec["times"])
        rec["runs"] = len(rec["times"])
        rec["result"] = summary(result)
        return result

    try:
        extra = run(vol, measure)
    except Exception as e:  # noqa: BLE001
        out["error"] = f"{type(e).__name__}: {e}"[:300]
        extra = None
    if extra:
        out["extra"] = extra
    return out


# --------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------


def run_child(tool, path, args, env=None, repeat=None) -> dict:
    cmd = [sys.executable, __file__, "--child", tool, str(path), "--repeat", str(repeat or args.repeat),
           "--max-seconds", str(args.max_seconds)]
    load = os.getloadavg()[0]
    t = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=args.child_timeout, env=env)
    except subprocess.TimeoutExpired:
        return {"tool": tool, "steps": [], "error": f"timeout after {args.child_timeout} s"}
    wall = time.perf_counter() - t
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if p.returncode != 0 or not lines:
        tail = (p.stderr or p.stdout).strip().splitlines()[-1:] or [f"exit {p.returncode}"]
        return {"tool": tool, "steps": [], "error": f"child exit {p.returncode}: {tail[0][:300]}", "child_wall_s": wall}
    res = json.loads(lines[-1])
    res["child_wall_s"] = wall
    res["loadavg_1min_before"] = load
    return res


# --------------------------------------------------------------------------
# Whole commands, as a user runs them: a fresh process each, default flags
# --------------------------------------------------------------------------

SKIMAGE_CODE = ("import sys, numpy as np; from skimage.measure import euler_number; "
                "print(euler_number(np.load(sys.argv[1]), connectivity=1))")


def commands(path: Path) -> dict:
    """name -> argv: ``isoflow info`` as installed (the console script next
    to this Python), and scikit-image's ``euler_number`` on the same file
    (connectivity 1 = isoflow's default 6, so that the numbers can be
    checked against each other)."""
    script = Path(sys.executable).with_name("isoflow")
    iso = [str(script)] if script.exists() else [sys.executable, "-m", "isoflow.cli"]
    return {"isoflow": iso + ["info", str(path), "--json"],
            "skimage": [sys.executable, "-c", SKIMAGE_CODE, str(path)]}


def shown(cmd: list[str]) -> str:
    """The command as a user types it, for the results: the program by its
    name and files relative to the repository, so that no path of the
    machine that ran it is recorded."""
    program = Path(cmd[0]).name
    program = "python" if program.startswith("python") else program
    return shlex.join([program, *(c.replace(f"{HERE.parent}{os.sep}", "") for c in cmd[1:])])


def timed(cmd, env=None, timeout=None) -> dict:
    """Wall seconds and peak RSS of one process (its own rusage, from wait4)."""
    import tempfile

    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t = time.perf_counter()
        p = subprocess.Popen(cmd, stdout=out, stderr=err, env=env)
        _, status, usage = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t
        p.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read().decode(), err.read().decode()
    rec = {"seconds": wall, "peak_rss": usage.ru_maxrss * 1024, "cpu_seconds": usage.ru_utime + usage.ru_stime}
    if p.returncode != 0:
        rec["error"] = (stderr.strip().splitlines() or [f"exit {p.returncode}"])[-1][:300]
    rec["stdout"] = stdout
    return rec


def run_commands(name: str, size: int, path: Path, repeat: int) -> dict:
    """isoflow and skimage alternately (A B A B ...), ``repeat`` pairs;
    medians, and the median of the pairs' ratios."""
    cmds = commands(path)
    runs = {k: [] for k in cmds}
    for _ in range(repeat):
        for k, cmd in cmds.items():
            runs[k].append(timed(cmd))
    res = {"input": name, "size": size, "pairs": repeat, "commands": {k: shown(c) for k, c in cmds.items()}}
    for k, rs in runs.items():
        ok = [r for r in rs if "error" not in r]
        res[k] = {
            "times": [r["seconds"] for r in rs],
            "seconds": float(np.median([r["seconds"] for r in ok])) if ok else None,
            "peak_rss": max(r["peak_rss"] for r in rs),
            "error": next((r["error"] for r in rs if "error" in r), None),
        }
    voxels = size**3
    input_bytes = path.stat().st_size
    for k in cmds:
        res[k]["beyond_input_b_per_voxel"] = (res[k]["peak_rss"] - input_bytes) / voxels
    ratios = [s["seconds"] / i["seconds"] for i, s in zip(runs["isoflow"], runs["skimage"])
              if "error" not in i and "error" not in s]
    res["ratio"] = float(np.median(ratios)) if ratios else None
    # the numbers they print agree
    try:
        report = json.loads(runs["isoflow"][0]["stdout"])
        res["isoflow_result"] = {"chi6": report["euler_characteristic"], "betti": report["betti"],
                                 "surfaces": None if report.get("surfaces") is None else len(report["surfaces"])}
        res["skimage_result"] = {"chi6": int(runs["skimage"][0]["stdout"].split()[-1])}
    except (ValueError, KeyError, IndexError) as e:
        res["check_error"] = f"{type(e).__name__}: {e}"
    return res


def print_command(c):
    iso, sk = c["isoflow"], c["skimage"]
    print(f"command {c['input']:<7}{c['size']:>5}^3  isoflow info {fmt_s(iso['seconds']):>8} s "
          f"({iso['beyond_input_b_per_voxel']:.2f} B/voxel beyond input)   skimage {fmt_s(sk['seconds']):>8} s   "
          f"ratio {c['ratio'] or 0:.2f}x", flush=True)


def run_threads(name: str, size: int, path: Path, counts, repeat: int, args) -> dict:
    """In-process ``analyze(vol, 6)`` with ``ISOFLOW_THREADS`` = each count,
    interleaved (1 2 ... 1 2 ...), ``repeat`` times; medians."""
    times = {t: [] for t in counts}
    for _ in range(repeat):
        for t in counts:
            env = dict(os.environ, ISOFLOW_THREADS=str(t))
            res = run_child("isoflow.info", path, args, env=env, repeat=1)
            st = (res.get("steps") or [{}])[0]
            if st.get("seconds"):
                times[t].append(st["seconds"])
    med = {t: float(np.median(v)) if v else None for t, v in times.items()}
    one = med.get(1)
    return {"input": name, "size": size, "times": {str(t): v for t, v in times.items()},
            "seconds": {str(t): v for t, v in med.items()},
            "speedup": {str(t): (one / v if one and v else None) for t, v in med.items()}}


def machine_info() -> dict:
    from importlib import metadata

    def ver(dist):
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            return None

    cpu = platform.processor()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = None
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                mem = int(line.split()[1]) * 1024
    except OSError:
        pass
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "cpus_usable": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "memory_bytes": mem,
        "loadavg_at_start": list(os.getloadavg()),
        "python": platform.python_version(),
        "versions": {d: ver(d) for d in ("isoflow", "numpy", "numba", "scipy", "scikit-image", "trimesh",
                                         "connected-components-3d", "dgtal")},
    }


def _available(module: str) -> str | None:
    """None if ``module`` imports in a child, else the error (cheap check up front)."""
    p = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True, text=True)
    if p.returncode == 0:
        return None
    return (p.stderr.strip().splitlines() or [f"exit {p.returncode}"])[-1][:200]


def estimate(rows, tool, step, name, size):
    """Power-law extrapolation t ~ size^p from the two largest sizes measured."""
    have = sorted((r["size"], r["seconds"]) for r in rows
                  if (r["tool"], r["step"], r["input"]) == (tool, step, name) and r.get("seconds")
                  and not r.get("estimated") and r["size"] < size)
    if not have:
        return None, None, None
    (s1, t1) = have[-1]
    linear = t1 * (size / s1) ** 3  # constant time per voxel
    if len(have) == 1:
        return linear, linear, f"from {s1}^3 assuming time ~ voxels"
    (s0, t0) = have[-2]
    p = math.log(t1 / t0) / math.log(s1 / s0)
    how = (f"from {s0}^3 -> {s1}^3 scaling (time ~ size^{p:.2f}); "
           f"time ~ voxels from {s1}^3 would give {fmt_s(linear)} s")
    return t1 * (size / s1) ** p, linear, how


def fmt_s(x):
    if x is None:
        return "-"
    return f"{x:.3f}" if x < 10 else f"{x:.1f}"


def build_rows(results, args):
    """Flatten the children's results into table rows with ratios and checks."""
    rows = []
    for (name, size, tool), res in results.items():
        group, label = TOOLS[tool][0], TOOLS[tool][1]
        if res.get("skipped"):
            steps = res.get("skip_steps", [None])
            for step in steps:
                rows.append({"group": group, "tool": tool, "step": step, "label": STEP_LABEL.get((tool, step), label),
                             "input": name, "size": size, "seconds": None, "note": res["skipped"]})
            continue
        if not res.get("steps"):
            rows.append({"group": group, "tool": tool, "step": None, "label": label, "input": name, "size": size,
                         "seconds": None, "error": res.get("error")})
            continue
        for st in res["steps"]:
            rows.append({
                "group": group, "tool": tool, "step": st["step"], "label": STEP_LABEL.get((tool, st["step"]), label),
                "input": name, "size": size, "seconds": st.get("seconds"), "runs": st.get("runs", 0),
                "times": st.get("times"),
                "extra_peak_bytes": st.get("extra_peak_bytes"),
                "extra_peak_bytes_per_voxel": (st["extra_peak_bytes"] / size**3
                                               if st.get("extra_peak_bytes") is not None else None),
                "peak_reset": st.get("peak_reset"),
                "result": st.get("result"), "error": st.get("error") or (res.get("error") if st is res["steps"][-1] else None),
                "child_wall_s": res.get("child_wall_s"),
                "loadavg_1min_before": res.get("loadavg_1min_before"),
            })
    # estimates for what was skipped as too slow
    for r in rows:
        if r["seconds"] is None and r.get("note", "").startswith("skipped above"):
            est, linear, how = estimate(rows, r["tool"], r["step"], r["input"], r["size"])
            if est is not None:
                r.update(seconds=est, estimated=True, estimate_voxel_linear_s=linear,
                         note=f"not run ({r['note']}): estimated {how}")
    # DGtal from numpy: the copy plus the extraction
    for key in sorted({(r["input"], r["size"]) for r in rows if r["tool"] == "dgtal.surface"}):
        part = {r["step"]: r for r in rows if r["tool"] == "dgtal.surface" and (r["input"], r["size"]) == key}
        if part.get("copy", {}).get("seconds") and part.get("surface", {}).get("seconds"):
            est = part["copy"].get("estimated") or part["surface"].get("estimated")
            rows.append({"group": "surface", "tool": "dgtal.surface", "step": "total",
                         "label": STEP_LABEL[("dgtal.surface", "total")], "input": key[0], "size": key[1],
                         "seconds": part["copy"]["seconds"] + part["surface"]["seconds"], "estimated": est,
                         "note": "sum of the two rows above" + (" (estimated)" if est else "")})
    # ratios against isoflow on the same input and size
    ref = {}
    for r in rows:
        for g, (tool, step) in REFERENCE.items():
            if (r["tool"], r["step"]) == (tool, step) and r["seconds"]:
                ref[(g, r["input"], r["size"])] = r["seconds"]
    for r in rows:
        t0 = ref.get((r["group"], r["input"], r["size"]))
        own = (r["tool"], r["step"]) == REFERENCE[r["group"]] or r["step"] == "copy"
        r["ratio"] = r["seconds"] / t0 if (t0 and r["seconds"] and not own) else None
    return rows


def check_commands(cmds) -> list[str]:
    fails = []
    for c in cmds:
        where = f"command {c['input']} {c['size']}"
        for k in ("isoflow", "skimage"):
            if c[k]["error"]:
                fails.append(f"{where}: {k} failed: {c[k]['error']}")
        if "check_error" in c:
            fails.append(f"{where}: output not read ({c['check_error']})")
        elif c["isoflow_result"]["chi6"] != c["skimage_result"]["chi6"]:
            fails.append(f"{where}: isoflow chi {c['isoflow_result']['chi6']} != skimage {c['skimage_result']['chi6']}")
    return fails


def check(results, sizes, names) -> list[str]:
    """isoflow's numbers against every other tool's, per input and size."""
    fails = []
    for size in sizes:
        for name in names:
            def res(tool, step, name=name, size=size):
                r = results.get((name, size, tool), {})
                for st in r.get("steps", []):
                    if st["step"] == step and "result" in st:
                        return st["result"] | r.get("extra", {})
                return None

            info = res("isoflow.info", "info")
            if info:
                for tool, key in (("skimage.euler6", "chi6"), ("skimage.euler26", "chi26"),
                                  ("scipy.betti", "chi6"), ("cc3d.betti", "chi6"),
                                  ("scipy.betti", "betti"), ("cc3d.betti", "betti")):
                    other = res(tool, "euler" if tool.startswith("skimage") else "betti")
                    if other is not None and other[key] != info[key]:
                        fails.append(f"{name} {size}: {tool} {key} {other[key]} != isoflow {info[key]}")
            mesh = res("isoflow.mesh", "mesh")
            if info and mesh:
                for key in ("faces", "surfaces", "genus_sum"):
                    if info.get(key) != mesh.get(key):
                        fails.append(f"{name} {size}: isoflow info {key} {info.get(key)} != mesh {mesh.get(key)}")
            if mesh:
                dg = res("dgtal.surface", "surface")
                if dg is not None and dg["faces"] != mesh["faces"]:
                    fails.append(f"{name} {size}: DGtal surfels {dg['faces']} != isoflow faces {mesh['faces']}")
                bx = res("trimesh.boxes", "boxes")
                if bx is not None and bx["triangles"] != 12 * bx["voxels"]:
                    fails.append(f"{name} {size}: as_boxes {bx['triangles']} triangles != 12 x {bx['voxels']} voxels")
    return fails


HEADER = ["task", "tool", "input", "size", "seconds", "runs", "extra peak B/voxel", "ratio", "note"]


def table_cells(r):
    est = r.get("estimated")
    sec = fmt_s(r["seconds"])
    note = r.get("error") or r.get("note") or ""
    res = r.get("result") or {}
    if not note and r["tool"] in ("isoflow.info", "isoflow.info.nosurf"):
        note = f"chi {res.get('chi6')}, betti {res.get('betti')}"
        if "surfaces" in res:
            note += f", {res['surfaces']} surfaces, {res['faces']} faces"
    elif not note and "faces" in res:
        note = f"{res['faces']} faces" + (f", {res['components']} components" if "components" in res else "")
    elif not note and "triangles" in res:
        note = f"{res['triangles']} triangles"
    mem = r.get("extra_peak_bytes_per_voxel")
    return [
        r["group"], r["label"], r["input"], f"{r['size']}^3",
        ("~" + sec) if est else sec,
        "est" if est else str(r.get("runs", "-") or "-"),
        "-" if mem is None else f"{mem:.2f}",
        "-" if r.get("ratio") is None else (("~" if est else "") + f"{r['ratio']:.1f}x"),
        note,
    ]


def print_row(r):
    c = table_cells(r)
    print(f"{c[0]:<8}{c[1]:<48}{c[2]:<7}{c[3]:>6}{c[4]:>10}{c[5]:>5}{c[6]:>9}{c[7]:>8}  {c[8]}", flush=True)


def _load_range(rows) -> str:
    loads = [r["loadavg_1min_before"] for r in rows if r.get("loadavg_1min_before") is not None]
    return f"{min(loads):.1f} to {max(loads):.1f}" if loads else "-"


def markdown_commands(cmds, meta) -> list[str]:
    if not cmds:
        return []
    lines = [
        "## Whole commands",
        "",
        "Each a fresh process, as a user runs it, alternated (isoflow, skimage, isoflow, ...) "
        f"{cmds[0]['pairs']} times; median seconds, median of the pairs' ratios; peak RSS of the process "
        "(interpreter, imports and input included) and that peak less the input file's size, per voxel.",
        "",
        f"* isoflow: `{cmds[0]['commands']['isoflow'].replace('benchmarks/.cache/', '')}`",
        f"* skimage: `{cmds[0]['commands']['skimage'].replace('benchmarks/.cache/', '')}`",
        "",
        "| input | size | isoflow info (default flags) | skimage euler_number | ratio | isoflow peak RSS | "
        "isoflow beyond input | skimage peak RSS | surfaces |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for c in cmds:
        iso, sk = c["isoflow"], c["skimage"]
        lines.append(
            f"| {c['input']} | {c['size']}^3 | {fmt_s(iso['seconds'])} s | {fmt_s(sk['seconds'])} s | "
            f"{c['ratio'] or 0:.2f}x | {iso['peak_rss'] / 2**20:.0f} MiB | {iso['beyond_input_b_per_voxel']:.2f} B/voxel | "
            f"{sk['peak_rss'] / 2**20:.0f} MiB | {(c.get('isoflow_result') or {}).get('surfaces')} |")
    return lines + [""]


def markdown_threads(scans) -> list[str]:
    if not scans:
        return []
    counts = list(scans[0]["seconds"])
    lines = ["## Threads", "",
             "In-process `analyze(vol, 6)` with `ISOFLOW_THREADS` set, interleaved; median seconds (speed-up "
             "over one thread).", "",
             "| input | size | " + " | ".join(f"{t} thread{'s' if t != '1' else ''}" for t in counts) + " |",
             "|---|---:|" + "---:|" * len(counts)]
    for sc in scans:
        cells = [f"{fmt_s(sc['seconds'][t])} s ({sc['speedup'][t] or 0:.2f}x)" for t in counts]
        lines.append(f"| {sc['input']} | {sc['size']}^3 | " + " | ".join(cells) + " |")
    return lines + [""]


def markdown(rows, meta, fails) -> str:
    lines = [
        "# isoflow benchmark (benchmarks/run.py)",
        "",
        f"`{meta['command']}`",
        "",
        f"Machine: {meta['machine']['cpu']}, {meta['machine']['cpu_count']} CPUs, "
        f"{(meta['machine']['memory_bytes'] or 0) / 2**30:.0f} GiB, {meta['machine']['platform']}; "
        f"Python {meta['machine']['python']}, "
        + ", ".join(f"{k} {v}" for k, v in meta["machine"]["versions"].items() if v) + ".",
        "",
        f"Seconds: best of up to {meta['repeat']} runs (fewer once a measurement used {meta['max_seconds']} s; "
        "`runs` says how many, `est` = not run, extrapolated). Extra peak memory: the child process's "
        "peak RSS during the tool minus its RSS with the input loaded, per input voxel. "
        "ratio = other tool's seconds / isoflow's on the same input (> 1: isoflow faster); "
        "`info` rows compare with isoflow analyze, `surface` rows with boundary_mesh.",
        "",
        f"Load average (1 min) before each child: {_load_range(rows)} on {meta['machine']['cpu_count']} CPUs "
        f"(the machine is shared; compare rows of one input and size, taken minutes apart at most). "
        f"Total run time {meta.get('total_seconds', 0) / 60:.1f} min.",
        "",
        "| " + " | ".join(HEADER) + " |",
        "|" + "|".join(["---"] * 3 + ["---:"] * 5 + ["---"]) + "|",
    ]
    for r in rows:
        lines.append("| " + " | ".join(c.replace("|", "/") for c in table_cells(r)) + " |")
    lines += [""] + markdown_commands(meta.get("commands", []), meta) + markdown_threads(meta.get("threads", []))
    lines += ["Checks: " + ("all tools agree with isoflow (chi at 6 and 26, Betti numbers, DGtal surfels = "
                                "isoflow faces, isoflow info's surfaces = the mesh's components, as_boxes = 12 triangles "
                                "per voxel, the commands' chi)." if not fails else
                                "FAILED:\n\n" + "\n".join(f"* {f}" for f in fails))]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[128, 256])
    ap.add_argument("--inputs", nargs="+", default=list(INPUTS), choices=list(INPUTS))
    ap.add_argument("--tools", nargs="+", default=list(TOOLS), choices=list(TOOLS))
    ap.add_argument("--repeat", type=int, default=3, help="runs per measurement; the best is kept")
    ap.add_argument("--max-seconds", type=float, default=20.0,
                    help="stop repeating a measurement once its runs took this long (default 20)")
    ap.add_argument("--boxes-max", type=int, default=256, help="largest size for trimesh as_boxes (estimated above)")
    ap.add_argument("--dgtal-max", type=int, default=256, help="largest size for DGtal (estimated above)")
    ap.add_argument("--child-timeout", type=float, default=900.0, help="seconds before a child is killed")
    ap.add_argument("--json", type=Path, default=RESULTS / "run.json")
    ap.add_argument("--md", type=Path, default=RESULTS / "run.md", help="markdown table")
    ap.add_argument("--commands", type=int, default=3, metavar="PAIRS",
                    help="whole-command pairs (isoflow info / skimage) per input and size; 0: none (default 3)")
    ap.add_argument("--threads", type=int, nargs="*", default=None, metavar="N",
                    help="thread counts for the in-process scan (default: 1 .. CPUs, largest size only)")
    ap.add_argument("--child", nargs=2, metavar=("TOOL", "NPY"), help=argparse.SUPPRESS)
    ap.add_argument("--make-input", nargs=3, metavar=("NAME", "SIZE", "NPY"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.make_input:
        name, size, path = args.make_input
        make_input(name, int(size), Path(path))
        return 0
    if args.child:
        print(json.dumps(child(args.child[0], Path(args.child[1]), args.repeat, args.max_seconds)), flush=True)
        return 0

    t_start = time.time()
    meta = {
        "command": "python benchmarks/run.py " + " ".join(sys.argv[1:] if argv is None else argv),
        "date": time.strftime("%Y-%m-%d %H:%M:%S %z"),
        "machine": machine_info(),
        "repeat": args.repeat, "max_seconds": args.max_seconds,
        "sizes": args.sizes, "inputs": args.inputs,
        "boxes_max": args.boxes_max, "dgtal_max": args.dgtal_max,
        "memory_method": "child process: ru_maxrss after the tool minus RSS with the input loaded, "
                         "peak reset through /proc/self/clear_refs after warm-up and loading",
    }
    missing = {}
    for tool in args.tools:
        mod = TOOLS[tool][4]
        if mod not in missing:
            missing[mod] = _available(mod)
    meta["unavailable"] = {m: e for m, e in missing.items() if e}
    for m, e in meta["unavailable"].items():
        print(f"note: {m} not importable ({e}); its rows are skipped", flush=True)

    # warm the numba cache once, so that no child has to compile
    subprocess.run([sys.executable, "-c", f"import sys; sys.path.insert(0, {str(HERE)!r}); import run; "
                    "run.w_isoflow(run._tiny())"], check=False)

    print(f"{'task':<8}{'tool':<48}{'input':<7}{'size':>6}{'seconds':>10}{'runs':>5}{'B/vox':>9}{'ratio':>8}  note")
    results: dict = {}
    for size in args.sizes:
        for name in args.inputs:
            path = ensure_input(name, size)
            for tool in args.tools:
                mod = TOOLS[tool][4]
                key = (name, size, tool)
                if missing.get(mod):
                    results[key] = {"skipped": f"{mod} not importable: {missing[mod]}"}
                    continue
                limit = {"trimesh.boxes": args.boxes_max, "dgtal.surface": args.dgtal_max}.get(tool)
                if limit is not None and size > limit:
                    results[key] = {"skipped": f"skipped above {limit}^3",
                                    "skip_steps": ["copy", "surface"] if tool == "dgtal.surface" else ["boxes"]}
                    continue
                results[key] = run_child(tool, path, args)
                for r in build_rows({key: results[key]}, args):
                    r["ratio"] = None
                    print_row(r)
    cmds = []
    if args.commands:
        print("\nWhole commands (a fresh process each, default flags):", flush=True)
        for size in args.sizes:
            for name in args.inputs:
                cmds.append(run_commands(name, size, ensure_input(name, size), args.commands))
                print_command(cmds[-1])
    meta["commands"] = cmds
    counts = args.threads if args.threads is not None else list(range(1, (os.cpu_count() or 1) + 1))
    scans = []
    if len(counts) > 1 and "isoflow.info" in args.tools:
        size = max(args.sizes)
        print(f"\nThreads ({size}^3, in process):", flush=True)
        for name in args.inputs:
            scans.append(run_threads(name, size, ensure_input(name, size), counts, args.repeat, args))
            print(f"threads {name:<7}{size:>5}^3  " + "  ".join(
                f"{t}: {fmt_s(v)} s" for t, v in scans[-1]["seconds"].items()), flush=True)
    meta["threads"] = scans
    rows = build_rows(results, args)
    fails = check(results, args.sizes, args.inputs) + check_commands(cmds)
    meta["total_seconds"] = time.time() - t_start
    meta["loadavg_at_end"] = list(os.getloadavg())

    print("\nFinal table (ratio = other / isoflow, > 1: isoflow faster):")
    order = {t: i for i, t in enumerate(TOOLS)}
    rows.sort(key=lambda r: (r["size"], args.inputs.index(r["input"]), r["group"] != "info",
                             order[r["tool"]], r["step"] or ""))
    for r in rows:
        print_row(r)
    print("\nchecks: " + ("all agree" if not fails else "FAILED\n  " + "\n  ".join(fails)))
    print(f"total {meta['total_seconds']:.0f} s")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"meta": meta, "checks_failed": fails, "rows": rows}, indent=1))
    if args.md:
        args.md.parent.mkdir(parents=True, exist_ok=True)
        args.md.write_text(markdown(rows, meta, fails))
    return 1 if fails else 0


if __name__ == "__main__":
    raise SystemExit(main())
