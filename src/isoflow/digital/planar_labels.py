"""The label table of a 2D label image: a cell segmentation, a grain map of
a micrograph, one slice of a volume (``isoflow info LABELS --labels`` on a
2D image).

A label's object is the pixels of that label; everything else is its
complement, and every row equals what
:func:`isoflow.digital.analysis.analyze` reports for ``image == label`` in
2D, found for all labels at once:

* every lattice vertex sees at most four labels, and the configuration of
  each (section 4: the 16 of a 2x2 block) comes from the same block, so one
  pass over the vertices gives every label's ``a^T n = 4 chi`` (eq. 4.12),
  its planar classes ``n`` (eq. 4.9) and its energy, what
  :func:`~isoflow.digital.analysis.report_from_histogram` reads from one
  object's configuration histogram;
* the components of every label come from one labelling of the whole image
  (cc3d's, which joins pixels of equal value), so ``b0`` needs no pass per
  label, and ``b1 = b0 - chi`` (the holes: in the plane there is no
  cavity);
* the perimeter is the pixel edges between the label and anything else,
  each times its length.
"""

from __future__ import annotations

from typing import Literal, cast

import numpy as np

from ..errors import warn
from ..scale.memory import check_fits
from .float64 import scaled_counts, scaled_faces, underflow_line
from .indices import NOT_WELL_COMPOSED, PLANAR_LABELS, euler_lut, planar_class_lut

#: the columns of a 2D table, in order ("bbox", "centroid" and "n" stand for
#: their numbered columns); ``area`` and ``perimeter`` are a 3D table's
#: ``volume`` and ``surface_area`` one dimension down
PLANAR_COLUMNS = ("label", "voxels", "area", "perimeter", "bbox", "centroid", "euler_characteristic", "b0", "b1",
                  "n", "non_well_composed", "energy")

#: vertices whose configurations are read at a time (memory: a few arrays
#: of this many)
VERTICES_AT_ONCE = 1 << 20
#: bytes beyond the image at the peak, checked before the work: per pixel
#: (the dense labels, the padded copies, the labelling, the runs), per
#: vertex of a chunk (its blocks' labels and configurations) and per label
#: (its sums and the table's columns); measured (tracemalloc): 10 bytes a
#: pixel on a 4096^2 cell map, 37 on a 1024^2 one (one chunk), 300 a pixel
#: where every pixel is a label
PIXEL_BYTES, CHUNK_BYTES, LABEL_BYTES = 8, 40, 320
#: labels are counted in a configuration histogram (16 counts a label)
#: where there are at most this share of a label per pixel, else their
#: features are summed directly (:func:`label_features`)
HISTOGRAM_LABELS = 1 / 16


def planar_table(image: np.ndarray, conn: int, spacing: np.ndarray, origin: np.ndarray,
                 wanted: np.ndarray | None, background: bool = False) -> dict[str, np.ndarray]:
    """The table of a 2D label image (the columns of :data:`PLANAR_COLUMNS`).

    Parameters
    ----------
    image : (ny, nx) integer or bool array
        The label image.
    conn : {4, 8}
        Every label's connectivity; its complement takes the other one.
    spacing, origin : (2,) float arrays
        Pixel size per axis, and the world position of pixel (0, 0)'s
        lowest corner.
    wanted : array of the image's type, optional
        The labels to report, in this order (None: every nonzero label
        present, in increasing order); an absent one gets a row of zeros
        (NaN box and centroid).
    background : bool
        With ``wanted`` None, label 0's row too, where any pixel is 0.

    Returns
    -------
    dict of str to numpy.ndarray
        One row per label, as :func:`isoflow.label_table` describes.

    Examples
    --------
    >>> image = np.array([[1, 1, 1, 0],
    ...                   [1, 0, 1, 2],
    ...                   [1, 1, 1, 0]], np.uint8)
    >>> t = planar_table(image, 4, np.ones(2), np.zeros(2), None)
    >>> t["label"].tolist(), t["voxels"].tolist(), t["b1"].tolist(), t["perimeter"].tolist()
    ([1, 2], [8, 1], [1, 0], [16.0, 4.0])
    """
    shape = "x".join(map(str, image.shape))
    need = PIXEL_BYTES * image.size + CHUNK_BYTES * min(image.size, VERTICES_AT_ONCE)
    check_fits(need, f"the label table of a {shape} label image")
    values, dense = dense_labels(image)
    k = len(values) + 1  # dense index 0: the outside of the image
    check_fits(need + LABEL_BYTES * k, f"the label table of a {shape} label image of {k - 1:,} values")
    padded = np.pad(dense, 1)  # the outside of the image as dense index 0 around it
    features = label_features(padded, k, conn)
    counts, sums, lo, hi = _places(dense, k)
    b0 = _components(dense, conn, k)
    edges = _boundary_edges(padded, k)
    if wanted is None:
        rows = np.flatnonzero(((values != 0) | background) & (counts[1:] > 0)) + 1
        labels = values[rows - 1]
    elif not len(values):  # an image of no pixels: every label absent
        rows, labels = np.zeros(len(wanted), np.int64), np.asarray(wanted, dtype=values.dtype)
    else:
        at = np.minimum(np.searchsorted(values, wanted), len(values) - 1)
        rows = np.where(values[at] == wanted, at + 1, 0)  # row 0: an absent label's zeros
        labels = np.asarray(wanted, dtype=values.dtype)
    chi = features[:, 0] // 4
    # a pixel size of 1e200 makes areas and perimeters past float64: inf
    # in the float columns, as a 3D table's volumes, not a NumPy warning on
    # the user's terminal; an area below float64's smallest number is 0
    # with a warning, as a 3D table's volume
    with np.errstate(over="ignore", under="ignore"):
        out: dict[str, np.ndarray] = {"label": labels, "voxels": counts[rows],
                                      "area": scaled_counts(counts[rows], spacing),
                                      # summed as analyze sums them, so that the two agree to the last bit
                                      "perimeter": scaled_faces(edges[rows], spacing)}
    if bool(((out["area"] == 0) & (out["voxels"] > 0)).any()):
        warn(underflow_line("the areas of labels", spacing))
    present = counts[rows] > 0
    # an absent label's box is NaN (0 / 0), and a corner past float64 (an
    # origin near 1.8e308) is inf, as ``analyze`` gives it, not a NumPy warning
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for d in range(2):
            out[f"bbox-{d}"] = np.where(present, origin[d] + spacing[d] * lo[rows, d], np.nan)
        for d in range(2):
            out[f"bbox-{d + 2}"] = np.where(present, origin[d] + spacing[d] * (hi[rows, d] + 1), np.nan)
        for d in range(2):
            out[f"centroid-{d}"] = np.where(present, origin[d] + spacing[d] * (sums[rows, d] / counts[rows] + 0.5),
                                            np.nan)
    out["euler_characteristic"] = chi[rows]
    out["b0"] = b0[rows]
    out["b1"] = b0[rows] - chi[rows]
    for c in range(len(PLANAR_LABELS)):
        out[f"n-{c}"] = features[rows, 1 + c]
    out["non_well_composed"] = features[rows, 4]
    out["energy"] = features[rows, 1] + features[rows, 3]  # k = a^2: 1 at convex and concave vertices, 0 at flat
    return out


def dense_labels(image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The image's values as dense indices from 1: ``(values, dense)``,
    ``dense`` (uint32, the image's shape) holding ``i + 1`` where the image
    holds ``values[i]``. Values within a span of a sixteenth of the pixels
    (cell numbers 1 .. N, the common case) are offsets from the smallest,
    some of them absent (no sort); others are sorted out by ``np.unique``."""
    if not image.size:
        return np.zeros(0, image.dtype), np.zeros(image.shape, np.uint32)
    low, high = image.min(), image.max()
    if int(high) - int(low) < max(1 << 10, image.size // 16):
        values = np.arange(int(high) - int(low) + 1).astype(image.dtype) + low  # (modulo the type: exact)
        dense = np.empty(image.shape, np.uint32)
        if image.dtype == np.uint64:  # (its values need not fit an int64)
            np.add(image - low, np.uint64(1), out=dense, casting="unsafe")
        else:  # in int64 a buffer at a time, so that int8 -128 .. 127 does not wrap
            np.subtract(image, int(low) - 1, out=dense, dtype=np.int64, casting="unsafe")
        return values, dense
    values, inverse = np.unique(image, return_inverse=True)
    # (2^32 values or more would need far more than the memory check lets through)
    return values, (inverse.reshape(image.shape) + 1).astype(np.uint32)


#: the columns of :func:`label_features`: the Euler share (``a^T n = 4
#: chi``, eq. 4.12), the three planar classes (eq. 4.9) and the
#: configurations that are not well-composed
FEATURES = ("euler", "convex", "flat", "concave", "non_well_composed")


def feature_rows(conn: int) -> np.ndarray:
    """(16, 5) int64: what a vertex of each configuration adds to its
    label's :data:`FEATURES`."""
    cls = planar_class_lut()
    rows = np.stack([euler_lut(2, conn), cls == 0, cls == 1, cls == 2, cls == NOT_WELL_COMPOSED],
                    axis=1).astype(np.int64)
    assert not rows[15].any()  # a block of one label adds nothing to it: the passes skip those
    return rows


def label_features(padded: np.ndarray, k: int, conn: int) -> np.ndarray:
    """(k, 5) int64: per label (dense index 1 .. k - 1 of ``padded``, the
    dense labels with a ring of 0, the outside, around them), its
    :data:`FEATURES` summed over the lattice vertices:
    each vertex adds, for every label it sees, the row of that label's
    configuration there (bit ``d0 + 2 d1`` for the pixel ``w - 1 + d`` of
    vertex ``w``, as :func:`~isoflow.digital.configurations.configurations`
    numbers them), counted at the first of the block's pixels that holds
    the label. A configuration histogram per label would take 16 counts a
    label, too many where nearly every pixel is a label of its own."""
    rows = feature_rows(conn)
    ny, nx = padded.shape[0] - 2, padded.shape[1] - 2
    counts = np.zeros((k, 16), np.int64) if k <= HISTOGRAM_LABELS * ny * nx else None
    out = np.zeros((k, len(FEATURES)), np.int64)
    step = max(1, VERTICES_AT_ONCE // (nx + 1))
    for y0 in range(0, ny + 1, step):
        y1 = min(ny + 1, y0 + step)
        q = [padded[y0 + (b & 1):y1 + (b & 1), (b >> 1):nx + 1 + (b >> 1)].reshape(-1) for b in range(4)]
        mixed = (q[0] != q[1]) | (q[0] != q[2]) | (q[0] != q[3])  # (a block of one label adds nothing)
        q = [c[mixed] for c in q]
        # each pair of the block's pixels compared once, the masks built a byte a vertex
        same = {(r, p): (q[r] == q[p]).view(np.uint8) for p in range(4) for r in range(p)}
        labels, masks = [], []
        for p in range(4):
            first = q[p] != 0
            mask = np.full(len(q[p]), 1 << p, np.uint8)
            for r in range(4):
                if r != p:
                    equal = same[min(r, p), max(r, p)]
                    mask |= equal << np.uint8(r)
                    if r < p:
                        first &= equal == 0
            masks.append(mask[first])
            labels.append(q[p][first])
        label, mask = np.concatenate(labels).astype(np.int64), np.concatenate(masks)
        if counts is not None:  # few labels: a histogram, weighed once at the end
            counts += np.bincount(label * 16 + mask, minlength=16 * k).reshape(k, 16)
        else:
            for f in range(len(FEATURES)):
                out[:, f] += np.bincount(label, weights=rows[mask, f], minlength=k).astype(np.int64)
    if counts is not None:
        out += counts @ rows
    out[0] = 0  # the outside is no label
    return out


def _places(dense: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per dense label: pixel count, coordinate sums (k, 2) and the lowest
    and highest pixel of its box (k, 2 each; 0 and -1 where absent)."""
    # from the runs of the rows (a run: a stretch of one label along axis
    # 1), far fewer than the pixels; sums of whole numbers below 2^53 in
    # float64 are exact
    ny, nx = dense.shape
    begins = np.ones((ny, nx), bool)
    np.not_equal(dense[:, 1:], dense[:, :-1], out=begins[:, 1:])
    if k * (ny + nx) <= dense.size and np.count_nonzero(begins) > dense.size // RUNS_PER_PIXEL:
        return _places_by_lines(dense, k)
    y, x0 = np.nonzero(begins)
    run_label = dense[y, x0]
    x1 = np.append(x0[1:] - 1, nx - 1)  # a run ends before the next begins, or at its row's end
    x1[np.flatnonzero(np.diff(y))] = nx - 1
    length = x1 - x0 + 1
    counts = np.bincount(run_label, weights=length, minlength=k).astype(np.int64)
    sums = np.stack([np.bincount(run_label, weights=y * length, minlength=k),
                     np.bincount(run_label, weights=(x0 + x1) * length // 2, minlength=k)], axis=1)
    lo, hi = np.full((k, 2), np.iinfo(np.int64).max, np.int64), np.full((k, 2), -1, np.int64)
    np.minimum.at(lo[:, 0], run_label, y)
    np.maximum.at(hi[:, 0], run_label, y)
    np.minimum.at(lo[:, 1], run_label, x0)
    np.maximum.at(hi[:, 1], run_label, x1)
    lo[counts == 0] = 0
    return counts, sums, lo, hi


#: :func:`_places` reads the rows' runs, unless there are more than one per
#: this many pixels (noise of a few labels, a run nearly every pixel), where
#: it counts each label's pixels per row and per column
#: (:func:`_places_by_lines`), if those counts are no more than the pixels
RUNS_PER_PIXEL = 4


def _places_by_lines(dense: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_places` from each dense label's pixels counted per row and
    per column ((ny + nx) x k counts): its pixel count, coordinate sums,
    and first and last row and column that hold it.

    Examples
    --------
    >>> dense = np.array([[1, 2, 1], [2, 1, 2]], np.uint32)
    >>> [a.tolist() for a in _places_by_lines(dense, 3)] == [a.tolist() for a in _places(dense, 3)]
    True
    """
    ny, nx = dense.shape
    lines = []
    for axis, n in ((0, ny), (1, nx)):
        at = np.arange(n, dtype=np.int64).reshape((n, 1) if axis == 0 else (1, n)) * k
        # (uint32 labels plus int64 offsets: the sum is int64, with no copy of the labels first)
        lines.append(np.bincount((dense + at).reshape(-1), minlength=n * k).reshape(n, k))
    counts = lines[0].sum(axis=0)
    sums = np.stack([lines[0].T @ np.arange(ny), lines[1].T @ np.arange(nx)], axis=1).astype(np.float64)
    lo, hi = np.zeros((k, 2), np.int64), np.full((k, 2), -1, np.int64)
    for d, per_line in enumerate(lines):
        held = per_line > 0
        some = held.any(axis=0)
        lo[some, d] = np.argmax(held, axis=0)[some]
        hi[some, d] = len(per_line) - 1 - np.argmax(held[::-1], axis=0)[some]
    return counts, sums, lo, hi


def _components(dense: np.ndarray, conn: int, k: int) -> np.ndarray:
    """Per dense label, its components under ``conn`` (4 or 8): one
    labelling of the whole image, which joins neighbours of equal value."""
    import cc3d

    parts, count = cc3d.connected_components(dense, connectivity=cast(Literal[4, 8], conn), return_N=True)
    label_of = np.zeros(count + 1, np.int64)
    label_of[parts.reshape(-1)] = dense.reshape(-1)
    return np.bincount(label_of[1:], minlength=k)[:k]


def _boundary_edges(padded: np.ndarray, k: int) -> np.ndarray:
    """(k, 2): per dense label (``padded``: as :func:`label_features`
    takes it), the pixel edges it shares with another value or the outside,
    between neighbours along axis 0 and along axis 1."""
    out = np.zeros((k, 2), np.int64)
    for axis in range(2):
        a = padded[:-1, :] if axis == 0 else padded[:, :-1]
        b = padded[1:, :] if axis == 0 else padded[:, 1:]
        differ = a != b
        out[:, axis] = np.bincount(a[differ], minlength=k)[:k] + np.bincount(b[differ], minlength=k)[:k]
    out[0] = 0
    return out
