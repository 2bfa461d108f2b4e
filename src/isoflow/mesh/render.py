"""Pictures of a boundary surface, coloured by the vertex angle gamma.

matplotlib is imported here only, so that the rest of isoflow does not pay
for it. Large meshes are drawn with back faces culled and, past a budget,
a random subset of faces, so that a picture never takes minutes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .export import gamma_colours

#: most faces drawn in one picture; beyond it a random subset is drawn
FACE_BUDGET = 60_000
#: peak bytes a picture adds: matplotlib's imports and the figure of at
#: most FACE_BUDGET faces (measured, rounded up: docs/surface.md, "Memory:
#: the check before meshing"; a large mesh's meshing peaks above it)
PICTURE_BYTES = 100 << 20


def pyplot():
    """matplotlib's pyplot on the Agg backend (files only, no screen needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path) -> Path:
    """Save and close a matplotlib figure, written whole or not at all
    (:func:`isoflow.mesh.outputs.atomic_path`; the format follows the suffix)."""
    from .outputs import atomic_path

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp)
    finally:
        pyplot().close(fig)
    return Path(path)


def draw_surface(ax, mesh, obj, elev: float, azim: float, budget: int, bounds=None) -> None:
    """Draw a boundary mesh into a 3D axes: faces coloured by the mean vertex
    angle gamma of their corners, shaded by their normal, back faces culled."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

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


def colour_key(vertex_classes) -> str:
    """The key to the colours :func:`gamma_colours` gives a picture's vertices.

    Parameters
    ----------
    vertex_classes : iterable of numpy.ndarray
        The ``vertex_class`` of each mesh the picture draws (or of its
        distinct values).

    Returns
    -------
    str
        The gamma scale, then green and grey where some vertex is not
        well-composed or is the midpoint of a doubled edge: a picture of a
        thin ring was half green with no word on what green is.

    Examples
    --------
    >>> from isoflow.digital.surface import boundary_mesh
    >>> colour_key([boundary_mesh(np.ones((2, 2, 2), bool)).vertex_class])
    'blue concave, white flat, red convex'
    >>> contact = np.zeros((2, 2, 2), bool); contact[0, 0, 0] = contact[1, 1, 1] = True
    >>> colour_key([boundary_mesh(contact, 26).vertex_class])
    'blue concave, white flat, red convex, green not well-composed'
    """
    classes: set[int] = set()
    for vertex_class in vertex_classes:
        classes.update(np.unique(vertex_class).tolist())
    key = "blue concave, white flat, red convex"
    if -1 in classes:
        key += ", green not well-composed"
    if -2 in classes:
        key += ", grey edge midpoints"
    return key


def render_surface(mesh, obj, path: Path, title: str = "", elev: float = 25, azim: float = -55) -> Path:
    """Write a PNG of the boundary mesh, faces coloured by the mean vertex
    angle gamma of their corners (blue concave, white flat, red convex;
    green, grey: :func:`colour_key`)."""
    plt = pyplot()
    fig = plt.figure(figsize=(7, 6), dpi=110)
    ax = fig.add_subplot(projection="3d")
    draw_surface(ax, mesh, obj, elev, azim, FACE_BUDGET)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.set_title(f"{title}\nvertex angle: {colour_key([mesh.vertex_class])}", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)
