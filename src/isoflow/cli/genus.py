"""``isoflow genus``: a mesh's genus, from the mesh, its peers and its voxels."""

from __future__ import annotations

import argparse
import json
import sys

from ..errors import betti_words, counted, terminal_text
from .inputs import add_mesh_rule, mesh_fill, resolution_value, seconds_value
from .progress import progress_bar


def add_parser(sub: argparse._SubParsersAction, add_command) -> None:
    p = add_command(sub, "genus", "verify a mesh's genus: mesh, manifold3d, pymeshlab and digital side by side")
    p.add_argument("mesh", help="a mesh file: any format trimesh reads")
    # extend: "--resolution 32 --resolution 64" tries both, as "--resolution 32 64" does
    p.add_argument("--resolution", type=resolution_value, nargs="+", action="extend",
                   help="voxels along the longest side, tried first (default: 64 128, or --max-resolution and "
                        "its half where that is below 128; repeated, all are tried); "
                        "then doubled until the digital Betti numbers of the last two agree")
    p.add_argument("--max-resolution", type=resolution_value,
                   help="stop doubling beyond this (default 1024); the resolutions given are tried whatever it says")
    p.add_argument("--time-limit", type=seconds_value, metavar="SECONDS",
                   help="stop doubling when the next resolution would end past this (default 60)")
    p.add_argument("--no-step", action="store_true", help="only the resolutions given, no doubling")
    add_mesh_rule(p)
    p.add_argument("--connectivity", type=int, choices=(6, 26), default=None,
                   help="digital connectivity (default: the one the file records where isoflow wrote it, else 6)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_genus)


def cmd_genus(args: argparse.Namespace) -> int:
    from ..mesh.genus import verify_genus

    res = args.resolution  # None: the defaults within --max-resolution (default_resolutions)
    kw = {k: v for k, v in (("max_resolution", args.max_resolution), ("time_limit", args.time_limit)) if v is not None}
    with progress_bar(args, "genus") as show:

        def stepped(entry: dict) -> None:  # the automatic stepping, one line per resolution on a terminal
            if show is not None:
                from tqdm import tqdm

                # through the bar's writer: a plain print continued the bar's
                # line, which the bar then drew again below it
                tqdm.write(f"genus: resolution {entry['resolution']}: Betti numbers {tuple(entry['betti'])} "
                           f"({entry['seconds']:.1f} s)", file=sys.stderr)

        report = verify_genus(args.mesh, res, args.connectivity, progress=show, step=not args.no_step, on_resolution=stepped,
                              strict=args.strict, fill=mesh_fill(args), **kw)
    if args.json:
        print(json.dumps(report.to_dict()))
    else:
        print(format_genus(report, terminal_text(args.mesh)))
    return 0


#: what the digital lines call the voxels of each fill
FILL_WORDS = {"winding": "solid", "shell": "shell (--fill shell)", "flood": "flood fill (--fill flood)"}


def _open_words(boundary_edges: int) -> str:
    # pymeshlab gives an open surface a genus (that of the closed one its
    # holes filled by disks make): a bare "genus 0" reads as a closed
    # surface's, beside a mesh line that says the mesh is open
    return (f" (of the surface with its holes filled: {counted(boundary_edges, 'boundary edge')})"
            if boundary_edges else "")


def _volume(volume: float | None) -> str:
    return "volume beyond float64's range" if volume is None else f"volume {volume:.6g}"


def _filled_words(report) -> str:
    # a flood fill's target beside the solid's own genus: the verdict
    # compares the voxels with it, so the witness line says it too
    if report.get("filled_genus") is None:
        return ""
    solid = report["solid"]
    return (f"; with its cavities filled (what --fill flood voxelises): genus {report['filled_genus']}, "
            f"{counted(solid['filled_bodies'], 'body', 'bodies')}")


def _loaded_words(m: dict) -> str:
    """The faces as loaded where the repairs (repeated faces dropped, edges
    split at T-junctions) changed their count: the digital rows voxelise
    those, as voxelize reads the file, and the mesh rows count the rest."""
    loaded = m.get("faces_as_loaded")
    if loaded is None or loaded == m["faces"]:
        return ""
    return f" once repaired ({loaded} as loaded, which the digital rows voxelise)"


def _mesh_genus_words(m: dict) -> str:
    # an open surface has a genus with its boundary loops (chi = 2 - 2g - b
    # per component): a bare "None" would name no value where there is one
    if m["genus"] is None and m.get("genus_with_boundary") is not None:
        return (f"genus {m['genus_with_boundary']} with {counted(m['boundary_loops'], 'boundary loop')} "
                "(an open surface: no genus as a closed one)")
    per = ", ".join("?" if g is None else str(g) for g in m["genus_per_component"][:12])
    more = ", ..." if len(m["genus_per_component"]) > 12 else ""
    return f"{'no genus' if m['genus'] is None else 'genus ' + str(m['genus'])} (per component: {per}{more})"


def format_genus(report, name: str) -> str:
    """The verdict as a terminal reads it: one line per witness."""
    m, m3, pm = report["mesh"], report["manifold3d"], report["pymeshlab"]
    solid = report["solid"]
    own, other = report["self_intersecting_faces"], report["faces_crossing_other_components"]
    crossings = ("?" if own is None else
                 f"{counted(own, 'face')} {'crosses its' if own == 1 else 'cross their'} own component, "
                 f"{other} {'crosses' if other == 1 else 'cross'} another component")
    lines = [
        f"{name}: {counted(m['vertices'], 'vertex', 'vertices')}, {counted(m['faces'], 'face')}" + _loaded_words(m),
        f"  mesh        watertight {m['watertight']}, {counted(m['components'], 'component')}, V-E+F {m['euler_number']}, "
        + _mesh_genus_words(m),
        f"  crossings   {crossings} (exact test)",
        "  manifold3d  " + (f"refused: {m3['error']}" if "error" in m3 else
                           f"genus {m3['genus']} over {counted(m3['components'], 'component')} "
                           f"(genus() of the whole mesh: {m3['genus_whole_mesh']})"),
        "  solid       " + (f"genus {solid['genus']}, {counted(solid['bodies'], 'body', 'bodies')}, "
                            f"{counted(solid['cavities'], 'cavity', 'cavities')}, {_volume(solid['volume'])} "
                            + ("(manifold3d: the outward components less the inside-out ones, approximate)"
                               if solid.get("approximate") else "(manifold3d's union of the components)")
                            + _filled_words(report)
                            if "genus" in solid else f"none ({solid['error']})"),
        "  pymeshlab   " + (f"genus {pm.get('genus')}" + (f" ({pm['error']})" if "error" in pm else
                                                        _open_words(pm.get("boundary_edges", 0)))),
    ]
    what = FILL_WORDS[report.get("fill", "winding")]
    for d in report["digital"]:
        b = d["betti"]
        lines.append(f"  digital {d['resolution']:>4}  {d['connectivity']}-conn {what}: {betti_words(b)} -> genus {d['genus']}")
    lines.append(f"  verdict     {report['verdict']}")
    return "\n".join(lines)
