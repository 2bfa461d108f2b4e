"""Pictures: the curvature-coloured surface and plots of a flow over time.

matplotlib is imported here only, so that the rest of isoflow does not pay
for it. Large meshes are drawn with back faces culled and, past a budget,
a random subset of faces, so that a picture never takes minutes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: most faces drawn in one picture; beyond it a random subset is drawn
FACE_BUDGET = 60_000


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _draw_surface(ax, mesh, obj, elev: float, azim: float, budget: int, bounds=None) -> None:
    """Draw a boundary mesh into a 3D axes: faces coloured by the mean vertex
    angle gamma of their corners, shaded by their normal, back faces culled."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from .io import gamma_colours

    xyz = obj.world(mesh.vertices)
    faces = mesh.faces
    # Back-face culling: the view direction of matplotlib's camera.
    e, a = np.radians(elev), np.radians(azim)
    view = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    idx = np.flatnonzero(mesh.face_normals.astype(float) @ view > 0)
    if len(idx) > budget:
        idx = np.sort(np.random.default_rng(0).choice(idx, budget, replace=False))
    colours = gamma_colours(mesh.gamma, mesh.vertex_class).astype(float) / 255
    face_rgb = colours[faces[idx]].mean(axis=1)
    # Shade by the face normal so that the shape reads in a still picture.
    light = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    shade = 0.55 + 0.45 * np.clip(mesh.face_normals[idx].astype(float) @ light, 0, 1)
    ax.add_collection3d(Poly3DCollection(xyz[faces[idx]], facecolors=face_rgb * shade[:, None], edgecolors="none"))
    lo, hi = bounds if bounds is not None else (xyz.min(axis=0), xyz.max(axis=0))
    centre, half = (lo + hi) / 2, (hi - lo).max() / 2
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
        setter(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)


def render_surface(mesh, obj, path: Path, title: str = "", elev: float = 25, azim: float = -55) -> Path:
    """Write a PNG of the boundary mesh, faces coloured by the mean vertex
    angle gamma of their corners (blue concave, white flat, red convex)."""
    plt = _pyplot()
    fig = plt.figure(figsize=(7, 6), dpi=110)
    ax = fig.add_subplot(projection="3d")
    _draw_surface(ax, mesh, obj, elev, azim, FACE_BUDGET)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.set_title(f"{title}\nvertex angle: blue concave, white flat, red convex", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def render_flow_shapes(frames, path: Path, connectivity: int, panels: int = 6,
                       elev: float = 25, azim: float = -55) -> Path:
    """Write a PNG of the flowing object itself: up to ``panels`` of the
    ``(state, step record)`` frames of a 3D flow, evenly spaced from the first
    to the last, all in the first frame's box so that the shrinking shows,
    coloured like :func:`render_surface`."""
    from .surface import boundary_mesh

    plt = _pyplot()
    if len(frames) > panels:
        frames = [frames[round(k * (len(frames) - 1) / (panels - 1))] for k in range(panels)]
    box = frames[0][0].bbox()
    cols = min(3, len(frames))
    rows = -(-len(frames) // cols)
    fig = plt.figure(figsize=(3.2 * cols, 3.2 * rows), dpi=100)
    for k, (state, rec) in enumerate(frames):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        mesh = boundary_mesh(state.volume, connectivity)
        _draw_surface(ax, mesh, state, elev, azim, FACE_BUDGET // len(frames), bounds=box)
        ax.set_axis_off()
        ax.set_title(f"step {rec['step']}: {rec['voxels']} voxels, betti {tuple(rec['betti'])}", fontsize=8)
    fig.suptitle("digital curvature flow (blue concave, white flat, red convex)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def render_flow(result, path: Path, title: str = "") -> Path:
    """Write a PNG of a digital curvature flow (:class:`isoflow.flow.FlowResult`):
    voxels, energy ``E = k^T n`` and Betti numbers against the step, with the
    steps where the Betti numbers changed marked."""
    plt = _pyplot()
    steps = [s["step"] for s in result.steps]
    betti = np.array([s["betti"] for s in result.steps])
    fig, axes = plt.subplots(3, 1, figsize=(7, 7.5), dpi=110, sharex=True)
    axes[0].plot(steps, [s["voxels"] for s in result.steps], "o-", ms=3)
    axes[0].set_ylabel("voxels")
    axes[1].plot(steps, [s["energy"] for s in result.steps], "o-", ms=3, color="tab:red")
    axes[1].set_ylabel("energy E = k^T n")
    for i in range(betti.shape[1]):
        axes[2].step(steps, betti[:, i], where="post", label=f"b{i}")
    axes[2].set_ylabel("Betti numbers")
    axes[2].set_xlabel("step")
    from matplotlib.ticker import MaxNLocator

    axes[2].xaxis.set_major_locator(MaxNLocator(integer=True))
    axes[2].legend(loc="upper right", fontsize=8)
    for change in result.topology_changes:
        for ax in axes:
            ax.axvline(change["step"], color="grey", lw=0.8, ls=":")
    head = title or "digital curvature flow"
    fig.suptitle(
        f"{head}: {result.connectivity}-connectivity{', guard' if result.guard else ''}, "
        f"stopped: {result.stop_reason}",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return Path(path)
