"""Pictures of a flow: its figures against the step, and the object at a
few steps (matplotlib is imported through :func:`isoflow.mesh.render.pyplot`,
only when a picture is drawn)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..digital.surface import boundary_mesh
from ..errors import counted
from ..mesh.render import FACE_BUDGET, colour_key, draw_surface, pyplot, save_figure


def render_flow_shapes(frames, path: Path, connectivity: int, panels: int = 6,
                       elev: float = 25, azim: float = -55) -> Path:
    """Write a PNG of the flowing object itself: up to ``panels`` of the
    ``(state, step record)`` frames of a flow, evenly spaced from the first
    to the last, all in the first frame's box so that the shrinking shows.
    A 3D state is drawn as its surface, coloured like
    :func:`isoflow.mesh.render.render_surface`; a 2D state as its pixels
    (:func:`draw_pixels`)."""
    plt = pyplot()
    if len(frames) > panels:
        frames = [frames[round(k * (len(frames) - 1) / (panels - 1))] for k in range(panels)]
    box = frames[0][0].bbox()
    if frames[0][0].ndim == 2:
        return _render_planar_shapes(plt, frames, box, path)
    cols = min(3, len(frames))
    rows = -(-len(frames) // cols)
    fig = plt.figure(figsize=(3.2 * cols, 3.2 * rows), dpi=100)
    classes = []  # the distinct vertex classes, for the key (not the meshes: they can be large)
    for k, (state, rec) in enumerate(frames):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        mesh = boundary_mesh(state.volume, connectivity)
        classes.append(np.unique(mesh.vertex_class))
        draw_surface(ax, mesh, state, elev, azim, FACE_BUDGET // len(frames), bounds=box)
        ax.set_axis_off()
        ax.set_title(f"step {rec['step']}: {counted(rec['voxels'], 'voxel')}, betti {tuple(rec['betti'])}", fontsize=8)
    fig.suptitle(f"digital curvature flow ({colour_key(classes)})", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def _render_planar_shapes(plt, frames, box, path: Path) -> Path:
    """:func:`render_flow_shapes` of a 2D flow: each state's pixels in the
    first state's box, widened by a pixel, since a state can grow half a
    pixel past its input before it shrinks; an axis whose pixel size is 1
    counts pixels and is ticked in whole numbers."""
    from matplotlib.ticker import MaxNLocator

    cols = min(3, len(frames))
    rows = -(-len(frames) // cols)
    # constrained layout spaces the rows for the titles and tick labels of panels of equal aspect as they
    # are drawn; tight_layout, which lays out the panels as boxes, lets a row's titles cross the x tick labels above
    fig = plt.figure(figsize=(3.2 * cols, 3.2 * rows), dpi=100, layout="constrained")
    pad = frames[0][0].spacing
    for k, (state, rec) in enumerate(frames):
        ax = fig.add_subplot(rows, cols, k + 1)
        draw_pixels(ax, state)
        ax.set_xlim(box[0][0] - pad[0], box[1][0] + pad[0])
        ax.set_ylim(box[1][1] + pad[1], box[0][1] - pad[1])  # y down, as draw_pixels draws it
        for axis, size in zip((ax.xaxis, ax.yaxis), pad):
            if size == 1:  # coordinates in pixels (a PNG's, an uncalibrated image's): not ticked in half pixels
                axis.set_major_locator(MaxNLocator(integer=True))
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)
        ax.set_title(f"step {rec['step']}: {counted(rec['voxels'], 'pixel')}, betti {tuple(rec['betti'])}", fontsize=8)
    fig.suptitle("digital curvature flow", fontsize=9)
    return save_figure(fig, path)


def draw_pixels(ax, state) -> None:
    """Draw a 2D object's pixels into a matplotlib axes, in world
    coordinates, as an image viewer shows the file: x (axis 0) to the
    right, y (axis 1) down, since a PNG's or a TIFF's rows are its y
    (:func:`isoflow.read_volume`), so the mask looks as it does in any
    viewer; a ``.npy`` array appears as ``imshow(array.T)`` shows it.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw into.
    state : DigitalObject
        A 2D object.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow import DigitalObject
    >>> fig = pyplot().figure()
    >>> draw_pixels(fig.add_subplot(), DigitalObject(np.eye(3, dtype=bool)))
    >>> pyplot().close(fig)
    """
    lo = state.world(np.zeros(2))
    hi = state.world(np.array(state.volume.shape, float))
    ax.imshow(state.volume.T, origin="upper", extent=(lo[0], hi[0], hi[1], lo[1]), cmap="Greys", vmin=0, vmax=1.6,
              interpolation="nearest")


def draw_betti(ax, steps: list, betti: np.ndarray) -> None:
    """Draw the Betti numbers ``betti`` (one row per state, one column per
    number) against ``steps`` into a matplotlib axes, ticked in whole
    numbers. Betti numbers are often equal (a torus keeps b0 = b1 = 1), so
    each line is drawn narrower than the one before it, on top of it: a
    line of one width would hide the one below it entirely.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw into.
    steps : list of int
        The step of each state.
    betti : numpy.ndarray
        The Betti numbers, ``(states, numbers)``.

    Examples
    --------
    >>> fig = pyplot().figure()
    >>> ax = fig.add_subplot()
    >>> draw_betti(ax, [0, 1, 2], np.array([[1, 1, 0], [1, 1, 0], [1, 0, 0]]))
    >>> [line.get_linewidth() for line in ax.get_lines()]
    [5.0, 3.0, 1.0]
    >>> pyplot().close(fig)
    """
    from matplotlib.ticker import MaxNLocator

    count = betti.shape[1]
    for i in range(count):
        width = 1.0 + 4.0 * (count - 1 - i) / max(count - 1, 1)
        # a marker at every state: a step line alone draws nothing for a run of
        # one state (--steps 0) and no more than a tick for the last state
        ax.step(steps, betti[:, i], where="post", marker="o", ms=2.5 + width, lw=width, label=f"b{i}")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel("Betti numbers")


def render_flow(result, path: Path, title: str = "") -> Path:
    """Write a PNG of a digital curvature flow (:class:`isoflow.flow.run.FlowResult`):
    voxels, energy ``E = k^T n`` and Betti numbers against the step, with the
    steps where the Betti numbers changed marked; every axis, all of whole
    numbers, is ticked in whole numbers."""
    from matplotlib.ticker import MaxNLocator

    plt = pyplot()
    steps = [s["step"] for s in result.steps]
    betti = np.array([s["betti"] for s in result.steps])
    fig, axes = plt.subplots(3, 1, figsize=(7, 7.5), dpi=110, sharex=True)
    axes[0].plot(steps, [s["voxels"] for s in result.steps], "o-", ms=3)
    axes[0].set_ylabel("pixels" if len(result.steps[0]["betti"]) == 2 else "voxels")
    axes[1].plot(steps, [s["energy"] for s in result.steps], "o-", ms=3, color="tab:red")
    axes[1].set_ylabel("energy E = k^T n")
    for ax in axes[:2]:  # counts and sums of whole weights: a few voxels would be ticked 0.2, 0.4, ...
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    draw_betti(axes[2], steps, betti)
    axes[2].set_xlabel("step")
    axes[2].xaxis.set_major_locator(MaxNLocator(integer=True))
    if len(steps) == 1:  # a range of no length: the locator ticks it in fractions of a step
        axes[2].set_xticks(steps)
    axes[2].legend(loc="best", fontsize=8)
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
    return save_figure(fig, path)
