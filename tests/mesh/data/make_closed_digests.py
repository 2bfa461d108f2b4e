"""Write closed_digests.json: digests of the volumes that isoflow's scanline
gave before issue 14 (commit 0b245b6) on every closed sample mesh.

The old module is read from git (``git show 0b245b6:src/isoflow/mesh/scanline.py``)
and run on the same grid (isoflow.mesh.grid) as today's voxeliser.  Run from
the repository root::

    python tests/mesh/data/make_closed_digests.py
"""

import hashlib
import json
import subprocess
import sys
import types
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
COMMIT = "0b245b6"
RESOLUTIONS = (24, 64, 101)
DIRS = (ROOT / "meshes",)


def main():
    sys.path.insert(0, str(ROOT / "src"))
    from isoflow.mesh.grid import voxel_grid
    from isoflow.mesh.load import load_mesh, mesh_defects

    code = subprocess.run(["git", "show", f"{COMMIT}:src/isoflow/mesh/scanline.py"], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout
    old = types.ModuleType("old_scanline")
    exec(code, old.__dict__)
    out = {"commit": COMMIT, "how": __doc__.split("\n\n")[1].replace("\n", " "), "volumes": []}
    names = sorted({p.name for d in DIRS if d.is_dir() for p in d.iterdir()
                    if p.suffix.lower() in (".obj", ".ply", ".off", ".stl")})
    for name in names:
        path = next(d / name for d in DIRS if (d / name).is_file())
        v, f = load_mesh(path)
        d = mesh_defects(v, f)
        if d["boundary_edges"] or d["inconsistent_edges"]:
            continue  # not closed: no volume of today's to compare with
        for res in RESOLUTIONS:
            pitch, origin, shape, what, (shift, e, origin_s, pitch_s) = voxel_grid(v, f, None, res)
            vs = np.ldexp(v - shift, -e)
            vol = old.scanline(shape, old.scan_plan(vs, f, origin_s, pitch_s, shape), None)
            out["volumes"].append({
                "mesh": name, "resolution": res, "shape": list(shape), "voxels": int(vol.sum()),
                "sha256": hashlib.sha256(np.packbits(vol).tobytes()).hexdigest()})
    dest = Path(__file__).with_name("closed_digests.json")
    dest.write_text(json.dumps(out, indent=1) + "\n")
    print(f"{dest}: {len(out['volumes'])} volumes")


if __name__ == "__main__":
    main()
