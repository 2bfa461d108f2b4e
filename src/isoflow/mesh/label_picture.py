"""A picture of a label table (``isoflow info LABELS --labels --png``): a
table of thousands of rows is read by its distributions, so one figure
shows how many labels have each Betti pattern, how their volumes are
spread, and their surface area against their volume beside a ball's.

The panels' numbers (:func:`label_panels`) are computed apart from the
drawing (:func:`render_label_table`), so that they can be checked against
the table's own columns; matplotlib is imported through
:func:`isoflow.mesh.render.pyplot`, only when a picture is drawn.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import IsoflowError, counted, given_text, whole_given
from .render import pyplot, save_figure

#: the Betti patterns drawn as bars of their own, the most common first;
#: the labels of every other pattern make one bar, "other"
PATTERN_BARS = 8


@dataclass(frozen=True, eq=False)  # (the generated __eq__ would compare arrays, which has no one answer)
class LabelPanels:
    """The numbers a picture of a label table draws (:func:`label_panels`).

    Attributes
    ----------
    dimension : int
        3 for a table of ``volume`` and ``surface_area``, 2 for one of
        ``area`` and ``perimeter``.
    patterns : list of tuple of int
        The Betti patterns ``(b0, b1, b2)`` (2D: ``(b0, b1)``) drawn as
        bars, the most common first (ties in increasing order).
    counts : list of int
        The labels of each pattern of ``patterns``.
    other : int
        The labels of every other pattern (the "other" bar).
    other_patterns : int
        How many patterns make up ``other``.
    measured : numpy.ndarray
        bool per row of the table: whether its volume and surface area are
        drawn, that is, both positive float64 numbers (not NaN, inf or 0).
    size, boundary : numpy.ndarray
        The measured rows' volume and surface area (2D: area and
        perimeter), in the table's order.
    ball : numpy.ndarray
        bool per measured row: whether the label is a ball (Betti numbers
        ``(1, 0, 0)``; 2D: a disc, ``(1, 0)``).
    """

    dimension: int
    patterns: list[tuple[int, ...]]
    counts: list[int]
    other: int
    other_patterns: int
    measured: np.ndarray
    size: np.ndarray
    boundary: np.ndarray
    ball: np.ndarray

    @property
    def left_out(self) -> int:
        """The rows left out of the measured panels."""
        return int(np.count_nonzero(~self.measured))


def table_columns(table: Mapping[str, np.ndarray]) -> tuple[int, str, str, list[str]]:
    """The dimension of a label table and the names of its size, boundary
    and Betti columns.

    Parameters
    ----------
    table : mapping of str to numpy.ndarray
        A label table (:func:`isoflow.label_table`).

    Returns
    -------
    tuple
        ``(3, "volume", "surface_area", ["b0", "b1", "b2"])`` or
        ``(2, "area", "perimeter", ["b0", "b1"])``.

    Raises
    ------
    IsoflowError
        A table that holds neither set of columns.

    Examples
    --------
    >>> table_columns({"label": np.array([1]), "area": np.array([2.0]), "perimeter": np.array([6.0]),
    ...                "b0": np.array([1]), "b1": np.array([0])})
    (2, 'area', 'perimeter', ['b0', 'b1'])
    """
    if all(k in table for k in ("volume", "surface_area", "b0", "b1", "b2")):
        return 3, "volume", "surface_area", ["b0", "b1", "b2"]
    if all(k in table for k in ("area", "perimeter", "b0", "b1")):
        return 2, "area", "perimeter", ["b0", "b1"]
    raise IsoflowError("a picture of a label table needs the columns of isoflow.label_table: volume, surface_area, "
                       "b0, b1 and b2 (2D: area, perimeter, b0 and b1)")


def label_panels(table: Mapping[str, np.ndarray], bars: int = PATTERN_BARS) -> LabelPanels:
    """The numbers of each panel of :func:`render_label_table`.

    Parameters
    ----------
    table : mapping of str to numpy.ndarray
        A label table (:func:`isoflow.label_table`, 3D or 2D), or any
        mapping with its columns (a CSV read back, NaN where it is empty).
    bars : int
        The most common Betti patterns given a bar each; the others are
        counted together.

    Returns
    -------
    LabelPanels

    Examples
    --------
    >>> image = np.zeros((9, 9, 5), np.uint8)
    >>> image[1:4, 1:4, 1:4] = 1                     # a cube: a ball
    >>> image[5:8, 5:8, 1:4] = 2
    >>> image[6, 6, 1:4] = 0                         # a cube with a tunnel
    >>> image[1:4, 5:8, 1:4] = 3                     # another ball
    >>> from isoflow import label_table
    >>> panels = label_panels(label_table(image))
    >>> panels.patterns, panels.counts, panels.other
    ([(1, 0, 0), (1, 1, 0)], [2, 1], 0)
    >>> panels.size.tolist(), panels.ball.tolist()
    ([27.0, 24.0, 27.0], [True, False, True])
    """
    whole = whole_given(bars)
    if whole is None or whole < 1:
        raise IsoflowError(f"label_panels: bars must be a positive integer, got {given_text(bars)}")
    bars = whole
    dimension, size_key, boundary_key, betti_keys = table_columns(table)
    betti = np.stack([np.asarray(table[k], np.int64) for k in betti_keys], axis=1).reshape(-1, len(betti_keys))
    found, counts = np.unique(betti, axis=0, return_counts=True)
    # most labels first; np.unique gives ties in increasing order, kept by the stable sort
    order = np.argsort(-counts, kind="stable")
    shown = order[:bars]
    size = np.asarray(table[size_key], np.float64)
    boundary = np.asarray(table[boundary_key], np.float64)
    # a log axis holds positive finite numbers alone: a measure past float64
    # (a voxel size of 1e150 makes inf, of 1e-150 makes 0) or NaN (a CSV's
    # empty cell) is left out and counted in the figure's note
    with np.errstate(invalid="ignore"):
        measured = np.isfinite(size) & np.isfinite(boundary) & (size > 0) & (boundary > 0)
    ball = np.all(betti[measured] == np.eye(1, len(betti_keys), dtype=np.int64), axis=1)
    return LabelPanels(dimension=dimension, patterns=[tuple(int(b) for b in found[i]) for i in shown],
                       counts=[int(counts[i]) for i in shown], other=int(counts[order[bars:]].sum()),
                       other_patterns=max(len(found) - bars, 0), measured=measured, size=size[measured],
                       boundary=boundary[measured], ball=ball)


def ball_boundary(size: np.ndarray, dimension: int = 3) -> np.ndarray:
    """The surface area of the ball of each volume (2D: the perimeter of
    the disc of each area), the least a body of that volume can have (the
    isoperimetric inequality): ``(36 pi V^2)^(1/3)``, in 2D ``2 sqrt(pi A)``.

    Parameters
    ----------
    size : numpy.ndarray
        Volumes (2D: areas).
    dimension : {3, 2}

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> r = 2.0
    >>> bool(np.isclose(ball_boundary(np.array([4 / 3 * np.pi * r**3]))[0], 4 * np.pi * r**2))
    True
    >>> bool(np.isclose(ball_boundary(np.array([np.pi * r**2]), 2)[0], 2 * np.pi * r))
    True
    """
    size = np.asarray(size, np.float64)
    if dimension == 2:
        return 2.0 * np.sqrt(np.pi * size)
    return np.cbrt(36.0 * np.pi * size**2)


def log_bins(values: np.ndarray, most: int = 40) -> np.ndarray:
    """Edges of a histogram of positive ``values`` on a log axis, equal in
    log: about the square root of their number of bins, from 5 to
    ``most``; one value alone gets a bin around it.

    Parameters
    ----------
    values : numpy.ndarray
        Positive finite numbers, at least one.
    most : int
        The most bins.

    Returns
    -------
    numpy.ndarray
        The bins' edges, increasing.

    Examples
    --------
    >>> log_bins(np.array([1.0, 10.0, 100.0])).round(3).tolist()
    [1.0, 2.512, 6.31, 15.849, 39.811, 100.0]
    """
    lo, hi = float(values.min()), float(values.max())
    if lo == hi:
        return np.array([lo / 1.5, hi * 1.5])
    return np.geomspace(lo, hi, int(np.clip(np.sqrt(len(values)), 5, most)) + 1)


def plain_number(value: float, ticks: Sequence[float] = ()) -> str:
    """A tick's value as a plain number, with the fewest significant digits
    (three at least) that tell apart all of ``ticks``.

    Parameters
    ----------
    value : float
        The tick's value.
    ticks : sequence of float
        The axis's ticks that are labelled along with it.

    Returns
    -------
    str
        ``value`` written out (``%g`` form below 1e-4 and from 1e6 on).

    Examples
    --------
    >>> plain_number(0.152), plain_number(20.0), plain_number(2000.0), plain_number(1e200)
    ('0.152', '20', '2000', '1e+200')
    >>> ticks = [0.1502, 0.1504, 0.1506]
    >>> [plain_number(t, ticks) for t in ticks]
    ['0.1502', '0.1504', '0.1506']
    """
    def written(v: float, digits: int) -> str:
        if v == 0 or 1e-4 <= abs(v) < 1e6:  # positional, as an axis of 1000 and 2000 reads best
            return np.format_float_positional(v, precision=digits, fractional=False, trim="-")
        return f"{v:.{digits}g}"

    distinct = len(set(ticks))
    digits = next((d for d in range(3, 17) if len({written(t, d) for t in ticks}) == distinct), 17)
    return written(value, digits)


def plain_log_labels(axis: Any) -> None:
    """Label a matplotlib log axis's ticks as plain numbers (0.152, 20,
    1e+200); matplotlib still picks which ticks it labels. Its own labels
    of a narrow range (cells of like size, or a few labels asked for),
    ``1.52 x 10^-1`` at every tick, run into each other.

    Parameters
    ----------
    axis : matplotlib.axis.Axis
        The axis (``ax.xaxis``, ``ax.yaxis``), on a log scale.

    Examples
    --------
    >>> plt = pyplot()
    >>> fig, ax = plt.subplots()
    >>> ax.set_xscale("log")
    >>> _ = ax.set_xlim(0.15, 0.16)
    >>> plain_log_labels(ax.xaxis)
    >>> fig.canvas.draw()
    >>> shown = ax.xaxis.get_ticklabels(which="both")
    >>> [t.get_text() for t in shown if t.get_text() and 0.15 <= t.get_position()[0] <= 0.16]
    ['0.15', '0.152', '0.154', '0.156', '0.158', '0.16']
    >>> plt.close(fig)
    """
    from matplotlib.ticker import Formatter, LogFormatterSciNotation

    class Plain(Formatter):
        def __init__(self):
            self.which = LogFormatterSciNotation()  # the ticks matplotlib would label
            self.labelled: list[float] = []

        def set_axis(self, axis):
            super().set_axis(axis)
            self.which.set_axis(axis)

        def set_locs(self, locs):
            self.which.set_locs(locs)
            self.labelled = [t for t in locs if self.which(t)]

        def __call__(self, x, pos=None):
            return plain_number(x, self.labelled) if self.which(x, pos) else ""

    axis.set_major_formatter(Plain())
    axis.set_minor_formatter(Plain())


def pattern_name(pattern: tuple[int, ...]) -> str:
    """A Betti pattern as a bar's label; the ball's named.

    Parameters
    ----------
    pattern : tuple of int
        ``(b0, b1, b2)``, or ``(b0, b1)`` in 2D.

    Returns
    -------
    str

    Examples
    --------
    >>> pattern_name((1, 0, 0)), pattern_name((1, 2, 0)), pattern_name((1, 0))
    ('(1,0,0) ball', '(1,2,0)', '(1,0) disc')
    """
    text = "(" + ",".join(map(str, pattern)) + ")"
    if pattern == (1,) + (0,) * (len(pattern) - 1):
        return text + (" ball" if len(pattern) == 3 else " disc")
    return text


def render_label_table(table: Mapping[str, np.ndarray], path: str | os.PathLike, *, name: str = "",
                       connectivity: int | None = None, unit: str | None = None) -> Path:
    """Write a PNG of a label table: the labels by Betti pattern, the
    distribution of their volumes, and their surface area against their
    volume with a ball's as the reference. Written whole or not at all
    (:func:`isoflow.mesh.outputs.atomic_path`).

    Parameters
    ----------
    table : mapping of str to numpy.ndarray
        A label table (:func:`isoflow.label_table`, 3D or 2D).
    path : str or os.PathLike
        The PNG to write (replaced if it exists: the command line checks
        ``--force`` before the work).
    name : str
        What the title names (the file, its choice of labels).
    connectivity : int, optional
        The labels' connectivity, for the title.
    unit : str, optional
        The length unit of the table's world columns, for the axes.

    Returns
    -------
    Path
        ``path``.

    Notes
    -----
    Three panels: (1) how many labels have each ``(b0, b1, b2)`` pattern,
    the :data:`PATTERN_BARS` most common and "other"; (2) a histogram of
    the volumes on a log axis; (3) surface area against volume on log
    axes, balls ``(1, 0, 0)`` apart from the others, with the ball's
    ``A = (36 pi V^2)^(1/3)`` drawn (no body of that volume has less
    area; a digital ball's staircase has about 1.5 times it). A 2D table
    draws the same with ``(b0, b1)``, area and perimeter, and the disc's
    ``P = 2 sqrt(pi A)``. Rows whose volume or area is not a positive
    float64 number are counted in the figure's note, not drawn.

    Examples
    --------
    >>> import tempfile
    >>> from isoflow import label_table
    >>> image = np.zeros((8, 8, 8), np.uint8)
    >>> image[1:4, 1:4, 1:4], image[5:7, 1:7, 1:7] = 1, 2
    >>> out = Path(tempfile.mkdtemp()) / "labels.png"
    >>> render_label_table(label_table(image), out, name="cells.tif", connectivity=6).read_bytes()[:4]
    b'\\x89PNG'
    """
    panels = label_panels(table)
    plt = pyplot()
    from matplotlib.ticker import MaxNLocator  # (after pyplot: its backend first)

    size_word, boundary_word = ("volume", "surface area") if panels.dimension == 3 else ("area", "perimeter")
    power = (3, 2) if panels.dimension == 3 else (2, 1)
    units = [f" ({unit}^{p})" if p > 1 else f" ({unit})" for p in power] if unit else [" (no unit given)"] * 2
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8), dpi=100)
    _draw_patterns(axes[0], panels)
    if len(panels.size):
        ax = axes[1]
        ax.hist(panels.size, bins=log_bins(panels.size), color="tab:blue", edgecolor="white")
        ax.set_xscale("log")
        plain_log_labels(ax.xaxis)
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))  # a count of labels has no fractions
        ax.set_ylabel("labels")
        _draw_measures(axes[2], panels, boundary_word)
    else:
        for ax in axes[1:]:
            ax.text(0.5, 0.5, f"no label with a finite, positive {size_word} and {boundary_word}",
                    ha="center", va="center", transform=ax.transAxes, fontsize=8, wrap=True)
            ax.set_xticks([])
            ax.set_yticks([])
    axes[1].set_xlabel(size_word + units[0])
    axes[1].set_title(f"{size_word} of the labels", fontsize=9)
    axes[2].set_xlabel(size_word + units[0])
    axes[2].set_ylabel(boundary_word + units[1])
    axes[2].set_title(f"{boundary_word} against {size_word}", fontsize=9)
    n = len(panels.measured)
    head = f"{name}: " if name else ""
    conn = f", {connectivity}-connectivity" if connectivity else ""
    fig.suptitle(f"{head}{counted(n, 'label')}{conn}", fontsize=10)
    if panels.left_out:
        fig.text(0.5, 0.01, f"{counted(panels.left_out, 'label')} left out of the {size_word} and {boundary_word} "
                 f"panels: {size_word} or {boundary_word} not a positive float64 number (NaN, inf or 0)",
                 ha="center", fontsize=8, color="tab:red")
    fig.tight_layout(rect=(0, 0.04 if panels.left_out else 0, 1, 0.95))
    return save_figure(fig, path)


def _draw_patterns(ax, panels: LabelPanels) -> None:
    """Panel 1: a horizontal bar per Betti pattern, the most common on top."""
    from matplotlib.ticker import MaxNLocator

    names = [pattern_name(p) for p in panels.patterns]
    counts = list(panels.counts)
    colours = ["tab:green" if name.endswith((" ball", " disc")) else "tab:blue" for name in names]
    if panels.other:
        names.append(f"other ({counted(panels.other_patterns, 'pattern')})")
        counts.append(panels.other)
        colours.append("tab:grey")
    rows = np.arange(len(names))
    ax.barh(rows, counts, color=colours)
    ax.set_yticks(rows, names, fontsize=8)
    ax.invert_yaxis()
    for r, c in zip(rows, counts):
        ax.text(c, r, f" {c}", va="center", fontsize=7)
    ax.set_xlabel("labels")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # a count of labels has no fractions
    betti = "(b0, b1, b2)" if panels.dimension == 3 else "(b0, b1)"
    ax.set_title(f"labels by Betti numbers {betti}", fontsize=9)
    ax.margins(x=0.15)


def _draw_measures(ax, panels: LabelPanels, boundary_word: str) -> None:
    """Panel 3: boundary against size on log axes, balls apart, with the ball's curve."""
    point = 12 if len(panels.size) < 1000 else 3
    for pick, colour, what in ((~panels.ball, "tab:orange", "other topology"),
                               (panels.ball, "tab:green", "ball (1,0,0)" if panels.dimension == 3 else "disc (1,0)")):
        if pick.any():
            ax.scatter(panels.size[pick], panels.boundary[pick], s=point, alpha=0.6, color=colour, lw=0,
                       label=f"{what}: {int(pick.sum())}", rasterized=True)
    lo, hi = float(panels.size.min()), float(panels.size.max())
    curve = np.geomspace(lo / 1.2, hi * 1.2, 100) if hi > lo else np.array([lo / 1.5, hi * 1.5])
    shape = "ball" if panels.dimension == 3 else "disc"
    formula = "(36 pi V^2)^(1/3)" if panels.dimension == 3 else "2 sqrt(pi A)"
    ax.plot(curve, ball_boundary(curve, panels.dimension), color="black", lw=1, ls="--",
            label=f"the {shape}'s {boundary_word}: {formula}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    plain_log_labels(ax.xaxis)
    plain_log_labels(ax.yaxis)
    # below the curve no label lies (none has less boundary for its size),
    # so the lower right corner is empty; labels of much boundary for their
    # size lie in the upper left
    ax.legend(fontsize=7, loc="lower right")
