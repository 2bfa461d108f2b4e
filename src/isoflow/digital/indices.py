"""Curvature indices of vertices (section 4 of the paper) as lookup tables.

Every table here is indexed by the configuration byte of
:mod:`isoflow.digital.configurations` and derived from the geometry of the 2x2x2
window: which octants are in the object, which of them share faces, how the
window splits into layers. Nothing is typed in; the tests compare the derived
tables with the paper's eqs. 4.4-4.11.

The nine classes (docs/mathematics.md) are numbered by their vertex angle: class
``gamma + 4`` for ``gamma`` in ``-4..4`` eighths, so that the histogram of
classes *is* the paper's vector ``n = (n_-4, ..., n_4)`` of eq. 4.9.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError
from ..scale.arrays import NotBinary, as_array, binary, refuse_object
from .configurations import check_dimension, face_connected, full_window, octants, read_only, window_faces
from .connectivity import is_face_connectivity, resolve_connectivity

#: class value of a configuration that is not well-composed
NOT_WELL_COMPOSED = -1
#: class value of configurations 0 and 255 (not on the surface)
OFF_SURFACE = -2

#: paper's label of class ``gamma + 4`` (eq. 4.6, 4.7); the two classes with
#: a = -2 are named by the paper's labels (+,-,-)+ and (-,-,-)-.
CLASS_LABELS = (
    "(-,-,-)-",  # gamma -4: saddle, a face-connected path turning in 3 axes
    "(+,-,-)",  # gamma -3: 5 octants
    "(-,0,0)",  # gamma -2: concave edge, 6 octants
    "(-,-,-)",  # gamma -1: concave corner, 7 octants
    "(0,0,∅)",  # gamma 0: flat, a 2x2 layer
    "(+,+,+)",  # gamma 1: convex corner, 1 octant
    "(+,0,0)",  # gamma 2: convex edge, 2 octants
    "(+,+,-)",  # gamma 3: 3 octants
    "(+,-,-)+",  # gamma 4: a cube and its three face neighbours
)
#: eq. 4.10 and 4.11 as functions of the class would be typed-in; they are
#: instead derived (see ``a_lut``) and checked against these in the tests.

#: per-axis planar code values (eq. 4.3): convex, flat, concave, undefined (∅)
CONVEX, FLAT, CONCAVE, NONE = 1, 0, -1, 2
#: code value for an axis of a configuration that is not well-composed
UNDEFINED = -2
#: how the paper writes each code value
CODE_CHARS = {CONVEX: "+", FLAT: "0", CONCAVE: "-", NONE: "∅", UNDEFINED: "?"}


def _bits(config: int, nbits: int) -> list[int]:
    return [(config >> b) & 1 for b in range(nbits)]


@cache
def _halves(ndim: int, axis: int, side: int) -> tuple[int, ...]:
    """The bits of the window cells on one side of ``axis`` (a 2x2 layer in 3D)."""
    return tuple(int(b) for b in np.flatnonzero(octants(ndim)[:, axis] == side))


# --------------------------------------------------------------------------
# Euler characteristic shares (the digital Gauss-Bonnet weights, eq. 4.10)
# --------------------------------------------------------------------------


def euler_lut(ndim: int | np.integer = 3, connectivity: int | np.integer | None = None) -> np.ndarray:
    """``2^n`` times every configuration's share of chi: the vector ``a``.

    Summed over all vertices the table gives ``2^n chi`` on every image,
    whatever its connectivity: the exact digital Gauss-Bonnet identity
    ``a^T n = 2^n chi`` (eqs. 4.10-4.13 and 6.2). On the well-composed
    boundary configurations both connectivities give the paper's ``a``.

    Parameters
    ----------
    ndim : int
        1 to 4.
    connectivity : int, optional
        The object's: ``2n`` (4, 6, 8 in 2D, 3D, 4D) or ``3^n - 1`` (8, 26,
        80); the background takes the other. None: ``2n``, the paper's
        (as for :func:`isoflow.analyze`).

    Returns
    -------
    numpy.ndarray
        int64, read-only, indexed by configuration (:func:`~isoflow.digital.configurations.configurations`).

    Notes
    -----
    Each incident lattice face (mask, k) of
    :func:`~isoflow.digital.configurations.window_faces` contributes:

    * full adjacency: chi of the union of the closed cells. A k-face is in
      the union iff ANY window cell containing it is in X, and it has
      ``2^k`` vertices, so ``lut = sum (-1)^k 2^(n-k) [c & mask != 0]``;
    * face adjacency: chi of the cubical complex whose vertices are the
      cell centres and whose j-faces are the blocks of ``2^j`` cells ALL in
      X, each seen by ``2^(n-j)`` vertices, so
      ``lut = sum (-1)^j 2^j [c & mask == mask]`` (``j = n - k``).

    Examples
    --------
    A single voxel's eight corners each hold one eighth of its chi = 1:

    >>> euler_lut(3, 6)[1], euler_lut(3, 26)[1]
    (np.int64(1), np.int64(1))

    A pixel's four corners in the plane, at its default 4-connectivity:

    >>> euler_lut(2)[1], len(euler_lut(2))
    (np.int64(1), 16)
    """
    n = check_dimension(ndim, "ndim")
    return _euler_table(n, resolve_connectivity(n, connectivity))


@cache
def _euler_table(n: int, connectivity: int) -> np.ndarray:
    """:func:`euler_lut` of a checked dimension and connectivity, built once."""
    face = is_face_connectivity(connectivity, n)
    c = np.arange(1 << (1 << n), dtype=np.int64)
    lut = np.zeros(c.shape, dtype=np.int64)
    for mask, k in window_faces(n):
        if face:
            lut += (-1) ** (n - k) * (1 << (n - k)) * ((c & mask) == mask)
        else:
            lut += (-1) ** k * (1 << (n - k)) * ((c & mask) != 0)
    return read_only(lut)


# --------------------------------------------------------------------------
# Well-composedness and the nine classes
# --------------------------------------------------------------------------


@cache
def well_composed(ndim: int = 3) -> np.ndarray:
    """Which configurations are well-composed boundary configurations.

    Both the object cells and the background cells of the window are
    non-empty and each is connected under the face adjacency of the cells:
    no edge- or corner-only contact. For n <= 3 these are exactly the
    configurations where the boundary is locally a manifold (section 4.2;
    126 of the 256 in 3D, the paper's nine classes up to symmetry); in 4D
    the condition is weaker (:func:`isoflow.digital.ndim.manifold_configurations`).

    Examples
    --------
    >>> int(well_composed(3).sum()), int(well_composed(2).sum())
    (126, 12)
    """
    n = check_dimension(ndim, "ndim")
    c = np.arange(1 << (1 << n), dtype=np.int64)
    bg = full_window(n) ^ c
    boundary = (c != 0) & (bg != 0)
    ok = np.zeros(c.shape, dtype=bool)
    ok[boundary] = face_connected(c[boundary], n) & face_connected(bg[boundary], n)
    return read_only(ok)


def _planar_code(cells: list[int], bits: list[int]) -> int:
    """Code of a 2x2 layer as a planar configuration (eq. 4.2 classes)."""
    inside = [c for c in cells if bits[c]]
    if len(inside) in (0, 4):
        return NONE
    if len(inside) == 1:
        return CONVEX
    if len(inside) == 3:
        return CONCAVE
    a, b = inside
    return FLAT if bin(a ^ b).count("1") == 1 else UNDEFINED


def _hub(bits: list[int]) -> bool:
    """Does one object octant share a face with every other object octant?

    That makes the object, locally, a cube with some of its face neighbours:
    a convex bump. It is what decides the sign of the vertex angle below.
    """
    obj = [b for b in range(len(bits)) if bits[b]]
    for h in obj:
        if all(o == h or bin(o ^ h).count("1") == 1 for o in obj):
            return True
    return False


@cache
def _tables_3d():
    wc = well_composed(3)
    n_cfg = 256
    gamma = np.zeros(n_cfg, dtype=np.int64)
    cls = np.full(n_cfg, NOT_WELL_COMPOSED, dtype=np.int64)
    codes = np.full((n_cfg, 3), UNDEFINED, dtype=np.int64)
    normal2 = np.zeros((n_cfg, 3), dtype=np.int64)
    for c in range(n_cfg):
        bits = _bits(c, 8)
        count = sum(bits)
        # Definition 14 / eq. 5.13: n = 1/2 (a1 e1 + a2 e2 + a3 e3), a_i in
        # {-1,0,1}: outward is where the window holds less object.
        for ax in range(3):
            lo = sum(bits[b] for b in _halves(3, ax, 0))
            hi = sum(bits[b] for b in _halves(3, ax, 1))
            normal2[c, ax] = np.sign(lo - hi)
        if c in (0, 255):
            cls[c] = OFF_SURFACE
            continue
        if not wc[c]:
            continue
        # Per-axis code: the more curved of the two layers across the axis
        # (concave over convex over flat over none), docs/mathematics.md.
        rank = {CONCAVE: 3, CONVEX: 2, FLAT: 1, NONE: 0}
        for ax in range(3):
            layer = [_planar_code(_halves(3, ax, s), bits) for s in (0, 1)]
            codes[c, ax] = max(layer, key=lambda v: rank[v])
        flat = any(
            sum(bits[b] for b in _halves(3, ax, 0)) in (0, 4) and count == 4
            for ax in range(3)
        )
        # Eq. 4.6: gamma = i/8 or -(8-i)/8 "since i/8 = 1 - (8-i)/8". The
        # positive form belongs to the convex bumps (a hub octant), the
        # negative one to everything else; a flat layer has angle 0.
        if flat:
            gamma[c] = 0
        elif _hub(bits):
            gamma[c] = count
        else:
            gamma[c] = count - 8
        cls[c] = gamma[c] + 4
    # The two classes with a = -2 carry the paper's labels as codes.
    for c in np.flatnonzero(cls == 8):
        codes[c] = (CONVEX, CONCAVE, CONCAVE)
    for c in np.flatnonzero(cls == 0):
        codes[c] = (CONCAVE, CONCAVE, CONCAVE)
    # cached and handed out by the public gamma_lut, class_lut, code_lut and
    # normal_lut: a caller's write into one changed every later analyze
    return read_only(gamma), read_only(cls), read_only(codes), read_only(normal2)


def gamma_lut() -> np.ndarray:
    """The vertex angle ``gamma`` of eq. 4.6, in eighths, of every configuration.

    ``gamma = i/8`` for a convex bump of ``i`` octants (one octant sharing a
    face with every other) and ``-(8 - i)/8`` otherwise; 0 on a flat layer,
    off the boundary and on configurations that are not well-composed.

    Returns
    -------
    numpy.ndarray
        256 int64 values in ``-4 .. 4``, indexed by configuration.

    Examples
    --------
    A convex corner (one octant) and a concave corner (seven):

    >>> int(gamma_lut()[0b00000001]), int(gamma_lut()[0b11111110])
    (1, -1)
    """
    return _tables_3d()[0]


def class_lut() -> np.ndarray:
    """The class of every configuration: ``gamma + 4`` (eq. 4.6), so that the
    classes' histogram is the paper's ``n = (n_-4, ..., n_4)`` of eq. 4.9.

    Returns
    -------
    numpy.ndarray
        256 int64 values: 0..8 on the 126 well-composed boundary
        configurations (labels in :data:`CLASS_LABELS`),
        :data:`NOT_WELL_COMPOSED` (-1) on the other 128 boundary ones,
        :data:`OFF_SURFACE` (-2) on 0 and 255.

    Examples
    --------
    >>> c = class_lut()
    >>> CLASS_LABELS[c[0b00000011]], int(c[0b10000001]), int(c[255])
    ('(+,0,0)', -1, -2)
    """
    return _tables_3d()[1]


def code_lut() -> np.ndarray:
    """The per-axis codes ``(alpha_1, alpha_2, alpha_3)`` of eqs. 4.3 and 4.7.

    Across each axis the window splits into two 2x2 layers; each is, as a
    planar configuration, convex (1 of 4), flat (2 adjacent), concave (3 of
    4) or not on the boundary, and the more curved of the two gives the
    axis's code (the reading of docs/mathematics.md).

    Returns
    -------
    numpy.ndarray
        int64, shape (256, 3): :data:`CONVEX` (1), :data:`FLAT` (0),
        :data:`CONCAVE` (-1), :data:`NONE` (2, the paper's ∅), and
        :data:`UNDEFINED` (-2) off the well-composed boundary.

    Examples
    --------
    A convex edge, two octants along axis 0, is ``(+,0,0)`` up to the order
    of the axes:

    >>> sorted(code_lut()[0b00000011].tolist())
    [0, 0, 1]
    """
    return _tables_3d()[2]


def normal_lut() -> np.ndarray:
    """Twice the normal vector of Definition 14 (eq. 5.13) of every configuration.

    ``n = 1/2 (a_1 e_1 + a_2 e_2 + a_3 e_3)`` with ``a_i`` in ``{-1, 0, 1}``:
    outward is where the window holds less object.

    Returns
    -------
    numpy.ndarray
        int64, shape (256, 3): ``2 n``.

    Examples
    --------
    A single voxel in the window's octant 0 (below the vertex on every
    axis): the normal at its far corner points away from it, up every axis.

    >>> normal_lut()[0b00000001].tolist()
    [1, 1, 1]
    """
    return _tables_3d()[3]


@cache
def f_lut() -> np.ndarray:
    """The vertex index ``f`` of eq. 4.8 of every configuration.

    ``f = (sum_i s(alpha_i)) (sum_i |s(alpha_i)|)`` with ``s(+) = 1``,
    ``s(-) = -1`` and ``s(0) = s(∅) = 0`` (Definition 9); its values are
    0, ±1, ±3, ±9. The flow reads "negative" as ``f < 0`` (section 5).

    Returns
    -------
    numpy.ndarray
        256 int64 values.

    Examples
    --------
    >>> int(f_lut()[0b00000001]), int(f_lut()[0b11111110])  # convex and concave corners
    (9, -9)
    """
    codes = code_lut()
    s = np.where(np.isin(codes, (CONVEX, CONCAVE)), codes, 0)
    return read_only(s.sum(axis=1) * np.abs(s).sum(axis=1))  # cached: shared with every later caller


def a_lut(connectivity: int | np.integer | None = 6) -> np.ndarray:
    """The Gauss-Bonnet weight ``a`` of eq. 4.10 of every 3D configuration.

    ``a = 8 x`` the vertex's share of the Euler characteristic, so that
    ``a^T n = 8 chi`` for every object (Theorems 10-11). On the 126
    well-composed boundary configurations it does not depend on the
    connectivity; elsewhere it does (:func:`euler_lut` in any dimension).

    Parameters
    ----------
    connectivity : {6, 26} or None
        The object's (None: the paper's 6, as for :func:`isoflow.analyze`).

    Returns
    -------
    numpy.ndarray
        256 int64 values.

    Examples
    --------
    Two voxels sharing only an edge: two components under 6, one under 26.

    >>> import numpy as np
    >>> from isoflow.digital.configurations import configuration_histogram
    >>> v = np.zeros((2, 2, 1), bool)
    >>> v[0, 0, 0] = v[1, 1, 0] = True
    >>> h = configuration_histogram(v)
    >>> int(h @ a_lut(6)) // 8, int(h @ a_lut(26)) // 8
    (2, 1)
    """
    return euler_lut(3, connectivity)


def code_string(config: int) -> str:
    """The configuration's code as the paper writes it.

    Examples
    --------
    >>> code_string(0b00000011), code_string(0), code_string(0b10000001)
    ('(+,0,0)', 'exterior', 'not-well-composed')
    """
    cls = int(class_lut()[config])
    if cls == OFF_SURFACE:
        return "interior" if config else "exterior"
    if cls == NOT_WELL_COMPOSED:
        return "not-well-composed"
    if cls in (0, 8):
        return CLASS_LABELS[cls]
    return "(" + ",".join(CODE_CHARS[int(v)] for v in code_lut()[config]) + ")"


def class_histogram(config_hist: ArrayLike) -> np.ndarray:
    """The paper's vector ``n = (n_-4, ..., n_4)`` of eq. 4.9.

    Parameters
    ----------
    config_hist : array_like
        The 256 configuration counts
        (:func:`~isoflow.digital.configurations.configuration_histogram`).

    Returns
    -------
    numpy.ndarray
        Nine int64 counts, indexed by class ``gamma + 4``
        (:data:`CLASS_LABELS`).

    Examples
    --------
    A box has 8 convex corners, convex edges along its 12 edges and flat
    vertices on its faces:

    >>> import numpy as np
    >>> from isoflow.digital.configurations import configuration_histogram
    >>> n = class_histogram(configuration_histogram(np.ones((3, 3, 3), bool)))
    >>> dict(zip(CLASS_LABELS, n.tolist()))["(+,+,+)"], int(n[6]), int(n[4])
    (8, 24, 24)
    """
    hist = as_array(config_hist, "config_hist")
    if hist.shape != (256,) or hist.dtype.kind not in "iuf":
        # (a 2D histogram has 16 counts, a 4D one 65536: a bare IndexError or a wrong n otherwise)
        raise IsoflowError(f"class_histogram takes the 256 counts of a 3D configuration histogram, got "
                           f"{'an array of type ' + str(hist.dtype) if hist.dtype.kind not in 'iuf' else hist.shape}")
    check_counts(hist)
    cls = class_lut()
    on = cls >= 0
    return np.bincount(cls[on], weights=hist[on], minlength=9).astype(np.int64)


def check_counts(hist: np.ndarray) -> None:
    """Refuse a histogram entry that is no count: the classes' sums of
    NaN, negative or fractional entries are no counts either (NaN cast to
    the most negative int64)."""
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(hist) | (hist < 0) | (hist != np.round(hist)) if hist.dtype.kind == "f" else hist < 0
    if bad.any():
        at = int(np.flatnonzero(bad)[0])
        raise IsoflowError(f"config_hist: entry {at} is {hist[at].item()!r}, not a count "
                           f"(a configuration histogram holds whole numbers >= 0)")


# --------------------------------------------------------------------------
# The plane (eq. 4.2)
# --------------------------------------------------------------------------

#: classes of a 2D boundary vertex, indexed by 1 - sign: convex, flat, concave
PLANAR_LABELS = ("convex", "flat", "concave")


@cache
def planar_class_lut() -> np.ndarray:
    """0 convex (1 pixel of 4), 1 flat (2 adjacent), 2 concave (3 of 4),
    :data:`NOT_WELL_COMPOSED` (2 diagonal), :data:`OFF_SURFACE` (0 or 4)."""
    out = np.full(16, OFF_SURFACE, dtype=np.int64)
    cells = list(range(4))  # the 2x2 window's bits
    for c in range(1, 15):
        code = _planar_code(cells, _bits(c, 4))
        out[c] = NOT_WELL_COMPOSED if code == UNDEFINED else 1 - code
    return out


def planar_index(points: ArrayLike) -> np.ndarray:
    """Four times the planar curvature index ``r`` of eq. 4.2, at every point.

    Parameters
    ----------
    points : array_like
        A 2D binary array of lattice points (bool or 0/1).

    Returns
    -------
    numpy.ndarray
        int64 of the same shape: ``4 r = 4 - 2 sum_k f_k + sum_k f_k f_k+1
        f_k+2`` over the 4-neighbours ``k`` in {1, 3, 5, 7} (the products are
        the unit squares at the point): +1, 0, -1 at convex, flat, concave
        boundary points, 0 inside and off the set. A thin part turns more:
        2 at the end of a line one point wide (a half turn), 4 at an
        isolated point, -2 where three such lines meet and -4 where four
        cross.

    Raises
    ------
    IsoflowError
        When ``points`` is not 2D or holds values other than 0 and 1.

    Notes
    -----
    Summed over the points it gives ``4 chi`` of the point set read with
    4-connectivity (vertices, 4-adjacent edges and full unit squares): the
    planar Gauss-Bonnet theorem.

    Examples
    --------
    A 3x3 square of points: four convex corners, four flat edge midpoints.

    >>> import numpy as np
    >>> r = planar_index(np.ones((3, 3), bool))
    >>> r.tolist(), int(r.sum()) // 4
    ([[1, 0, 1], [0, 0, 0], [1, 0, 1]], 1)

    A line of points, one wide: its two ends turn by half a turn each.

    >>> planar_index(np.ones((1, 4), bool)).tolist()
    [[2, 0, 0, 2]]
    """
    # a 2D mask of 0/1 only, as every mask of the API: another shape has no
    # planar index, and 0.5 or NaN are no lattice points. The shape is
    # checked first: [1, 2, 3] is a 1D list, which no values make a mask of
    refuse_object(points, "points")
    given = as_array(points, "points")
    if given.ndim != 2:
        raise IsoflowError(f"points: planar_index takes a 2D array, got a {given.ndim}D array of shape {given.shape}")
    try:
        grid = binary(given, "points")
    except NotBinary as exc:
        # label_table, offered for a label image, has no planar index: one label's points have
        label = exc.kind == "labels" and given.dtype.kind in "iu"
        first = given[(given != 0) & (given != 1)].flat[0] if label else None
        hint = f", or one label's points: planar_index(image == {first})" if label else ""
        raise NotBinary(exc.bare + hint, exc.bare, every=False, ndim=2, kind=exc.kind) from None
    f = np.pad(grid, 1).astype(np.int8)
    c = f[1:-1, 1:-1]
    # x1..x8 anticlockwise from (m+1, n): eq. 4.1 with diagonals in between.
    ring = [
        f[2:, 1:-1], f[2:, 2:], f[1:-1, 2:], f[:-2, 2:],
        f[:-2, 1:-1], f[:-2, :-2], f[1:-1, :-2], f[2:, :-2],
    ]
    four = ring[0] + ring[2] + ring[4] + ring[6]
    squares = sum(ring[k] * ring[k + 1] * ring[(k + 2) % 8] for k in (0, 2, 4, 6))
    return (c * (4 - 2 * four + squares)).astype(np.int64)
