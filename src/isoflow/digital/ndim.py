"""Curvature in 1 to 4 dimensions: manifold configurations, codes, indices.

Section 6 of the paper proposes to carry the curvature codes of section 4 to
``n`` dimensions (eq. 6.1) and conjectures a digital Chern-Gauss-Bonnet theorem
``a^T n = 2^n (1 - g)`` (eq. 6.2) and an energy ``E = k^T n = 2^n (1 + g)``
(eq. 6.3). The window, the configurations and their histogram are the same
functions in every dimension (:mod:`isoflow.digital.configurations`), as are
the Euler shares ``a`` and well-composedness (:mod:`isoflow.digital.indices`)
and the cube's symmetries (:mod:`isoflow.digital.symmetry`). This module adds
what only the n-dimensional statements need, built from first principles
for ``n = 1 .. 4``:

* the Gauss-Bonnet sum and the energy of an image (:func:`gauss_bonnet_sum`,
  :func:`surface_energy`), under the object's connectivity: ``2n`` or
  ``3^n - 1``, the background taking the other;
* digitally well-composed and manifold configurations, and the homology of a
  vertex's link (:func:`manifold_configurations`, :func:`link_betti_numbers`);
* the per-axis curvature codes and the vertex indices of eqs. 4.8 and 6.1
  (:func:`curvature_code`, :func:`curvature_index`).

Exact GF(2) Betti numbers of small images
(:func:`isoflow.digital.homology.gf2_betti_numbers`) check
``chi = sum (-1)^i b_i`` independently of these tables. See ``docs/ndim.md``
for the derivations and the findings.
"""

from __future__ import annotations

import itertools
from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, given_text
from ..results import read_only
from .configurations import (
    check_dimension,
    configuration_histogram,
    configurations,
    full_window,
    octants,
    window_faces,
)
from .connectivity import resolve_connectivity
from .indices import CODE_CHARS, CONCAVE, CONVEX, FLAT, NONE, UNDEFINED, euler_lut, well_composed
from .symmetry import configuration_orbits

#: the two ways of merging the codes of the two halves across an axis
CODE_RULES = ("paper", "symmetric")


def _check_configs(config: ArrayLike, n: int) -> np.ndarray:
    c = np.asarray(config)
    if not np.issubdtype(c.dtype, np.integer):
        raise IsoflowError(f"configurations must be integers, got dtype {c.dtype}")
    size = 1 << (1 << n)
    if c.size and (c.min() < 0 or c.max() >= size):
        raise IsoflowError(f"configurations of a {n}D window must lie in 0..{size - 1}")
    return c.astype(np.int64)


def _weights(volume: ArrayLike, connectivity: int | None) -> tuple[np.ndarray, np.ndarray]:
    """The image's configuration histogram and its ``a`` (:func:`~isoflow.digital.indices.euler_lut`)."""
    hist = configuration_histogram(volume)
    ndim = int(np.log2(np.log2(len(hist))))  # 2^(2^n) configurations
    return hist, euler_lut(ndim, resolve_connectivity(ndim, connectivity))


# --------------------------------------------------------------------------
# Gauss-Bonnet in n dimensions (eqs. 6.2, 6.3)


def vertex_curvature(volume: ArrayLike, connectivity: int | None = None) -> np.ndarray:
    """``a(v)`` at every vertex (shape ``S + 1``): ``2^n`` x the local Euler share.

    The digital Gauss-Bonnet identity is ``vertex_curvature(X).sum() ==
    2^n * euler_characteristic(X)`` (the exact form of Theorems 10-11 and
    of eq. 6.2's left-hand side).

    Examples
    --------
    >>> import numpy as np
    >>> int(vertex_curvature(np.ones((3, 3, 3, 3), bool)).sum())  # 16 chi of a 4-box
    16
    """
    c = configurations(volume)
    return euler_lut(c.ndim, resolve_connectivity(c.ndim, connectivity))[c]


def gauss_bonnet_sum(volume: ArrayLike, connectivity: int | None = None) -> int:
    """``a^T n`` of eqs. 4.12, 4.13 and 6.2: the sum of ``a(v)`` over all vertices.

    Examples
    --------
    >>> import numpy as np
    >>> ring = np.pad(np.ones((3, 3), bool), 1)
    >>> ring[2, 2] = False  # a square with a hole: chi = 0
    >>> gauss_bonnet_sum(ring)
    0
    """
    hist, a = _weights(volume, connectivity)
    return int(hist @ a)


def surface_energy(volume: ArrayLike, connectivity: int | None = None) -> int:
    """``E = k^T n`` of eqs. 5.22 and 6.3 with ``k = a^2``: the sum of ``a(v)^2``.

    Examples
    --------
    >>> import numpy as np
    >>> surface_energy(np.ones((2, 2, 2), bool))  # 8 convex corners, a = 1
    8
    """
    hist, a = _weights(volume, connectivity)
    return int(hist @ (a * a))


@cache
def _sub_blocks(n: int) -> tuple[tuple[int, tuple[int, ...]], ...]:
    """Every sub-block of the window of dimension >= 2: (mask, antagonist pairs).

    A k-block is the set of ``2^k`` window cells with ``n - k`` coordinates
    fixed; its antagonist pairs are the cells opposite through its centre
    (differing in all k free coordinates), as bitmask pairs.
    """
    d = octants(n)
    blocks = []
    for free in itertools.product((0, 1), repeat=n):
        k = sum(free)
        if k < 2:
            continue
        for fixed in itertools.product((0, 1), repeat=n - k):
            it = iter(fixed)
            value = [None if f else next(it) for f in free]
            cells = [
                b for b in range(1 << n)
                if all(v is None or d[b, i] == v for i, v in enumerate(value))
            ]
            mask = sum(1 << b for b in cells)
            pairs = set()
            for b in cells:
                o = b ^ sum(1 << i for i in range(n) if free[i])
                pairs.add((1 << min(b, o)) | (1 << max(b, o)))
            blocks.append((mask, tuple(sorted(pairs))))
    return tuple(blocks)


@cache
def digitally_well_composed(n: int) -> np.ndarray:
    """Mask of boundary configurations without a critical sub-block.

    Digital well-composedness (Boutry, Geraud, Najman): no sub-block of
    dimension k >= 2 holds exactly one antagonist pair of object cells, or
    all its cells but one antagonist pair. Equal to :func:`well_composed`
    for n <= 3; strictly stronger in 4D.
    """
    n = check_dimension(n)
    c = np.arange(1 << (1 << n), dtype=np.int64)
    bad = np.zeros(c.shape, dtype=bool)
    for mask, pairs in _sub_blocks(n):
        sub = c & mask
        for pair in pairs:
            bad |= (sub == pair) | (sub == (mask ^ pair))
    return read_only(~bad & (c != 0) & (c != full_window(n)))


def gf2_rank(columns: list[int]) -> int:
    """Rank over GF(2) of vectors given as Python int bitsets."""
    pivots: dict[int, int] = {}
    rank = 0
    for v in columns:
        while v:
            top = v.bit_length() - 1
            if top in pivots:
                v ^= pivots[top]
            else:
                pivots[top] = v
                rank += 1
                break
    return rank


@cache
def _face_signs(n: int) -> tuple[tuple[int, ...], ...]:
    """Sign vectors ``e`` of :func:`window_faces`, in the same order."""
    return tuple(itertools.product((-1, 0, 1), repeat=n))


def link_betti_numbers(config: int, n: int) -> dict:
    """Reduced GF(2) Betti numbers of the vertex's link pieces in S^(n-1).

    The link of a lattice vertex is the boundary of the n-dimensional
    cross-polytope: a face ``e != 0`` of :func:`window_faces` of dimension k
    is a (k-1)-simplex. ``'object'`` is the closed union of the object
    cells' facets, ``'background'`` that of the background cells', and
    ``'boundary'`` their intersection (the link of the vertex in the
    boundary of X). Returns ``{piece: (b~_0, ..., b~_(n-1))}``.
    """
    n = check_dimension(n)
    c = _check_configs(config, n)
    if c.ndim:  # the link of one vertex: several are as many calls
        raise IsoflowError(f"link_betti_numbers takes one configuration, got an array of shape {c.shape}")
    c = int(c)
    full = full_window(n)
    signs = _face_signs(n)
    masks = [m for m, _ in window_faces(n)]
    out = {}
    for piece in ("object", "background", "boundary"):
        present = []
        for e, m in zip(signs, masks):
            if not any(e):
                continue
            a, b = (m & c) != 0, (m & (full ^ c)) != 0
            if (piece == "object" and a) or (piece == "background" and b) or (
                piece == "boundary" and a and b
            ):
                present.append(e)
        by_dim: dict[int, list] = {}
        for e in present:
            by_dim.setdefault(sum(1 for v in e if v) - 1, []).append(e)
        ids = {k: {e: i for i, e in enumerate(L)} for k, L in by_dim.items()}
        ranks = {}
        for k, L in by_dim.items():
            if k == 0:
                continue
            cols = []
            for e in L:
                v = 0
                for i in range(n):
                    if e[i]:
                        f = list(e)
                        f[i] = 0
                        v ^= 1 << ids[k - 1][tuple(f)]
                cols.append(v)
            ranks[k] = gf2_rank(cols)
        b = [len(by_dim.get(k, [])) - ranks.get(k, 0) - ranks.get(k + 1, 0) for k in range(n)]
        if b[0] > 0:
            b[0] -= 1  # reduced homology
        out[piece] = tuple(b)
    return out


@cache
def manifold_configurations(n: int) -> np.ndarray:
    """Mask of configurations where the boundary is locally an (n-1)-manifold.

    The paper's codes are for points of an "m = n - 1 dimensional digital
    manifold" (section 6). A boundary configuration qualifies iff every
    proper sub-block is non-critical (:func:`digitally_well_composed`, which
    makes the link of the vertex in the boundary a closed (n-2)-manifold)
    and that link is a GF(2)-homology (n-2)-sphere; the boundary near the
    vertex is then the cone over a sphere, a ball. Equal to
    :func:`well_composed` for n <= 3. In 4D it drops one digitally
    well-composed class: the two linked 8-cycles of the 4-cube graph, whose
    boundary is the cone over a torus (docs/ndim.md).
    """
    n = check_dimension(n)
    dwc = digitally_well_composed(n)
    if n <= 2:
        return dwc
    canon = configuration_orbits(n)
    sphere = tuple(1 if k == n - 2 else 0 for k in range(n))
    good = [
        r for r in np.unique(canon[dwc])
        if link_betti_numbers(int(r), n)["boundary"] == sphere
    ]
    return read_only(dwc & np.isin(canon, good))


def boundary_classes(n: int, well_composed_only: bool = True) -> np.ndarray:
    """Canonical representatives of the boundary classes (sorted).

    With ``well_composed_only`` the classes of :func:`well_composed`
    configurations (3 in 2D, the paper's 9 in 3D); otherwise every orbit
    except those of the empty and the full window.
    """
    n = check_dimension(n)
    canon = configuration_orbits(n)
    c = np.arange(canon.size)
    keep = well_composed(n) if well_composed_only else (c != 0) & (c != full_window(n))
    return np.unique(canon[keep])


def class_counts(n: int) -> dict:
    """Orbit statistics of the n-dimensional window.

    Keys: ``orbits`` (all configurations up to symmetry), ``boundary_orbits``
    (without empty/full), and ``<kind>_configurations`` / ``<kind>_classes``
    for kind ``well_composed`` (face-connected object and background),
    ``digitally_well_composed`` and ``manifold``.
    """
    n = check_dimension(n)
    canon = configuration_orbits(n)
    out = {
        "orbits": int(np.unique(canon).size),
        "boundary_orbits": int(boundary_classes(n, well_composed_only=False).size),
    }
    for name, mask in (
        ("well_composed", well_composed(n)),
        ("digitally_well_composed", digitally_well_composed(n)),
        ("manifold", manifold_configurations(n)),
    ):
        out[f"{name}_configurations"] = int(mask.sum())
        out[f"{name}_classes"] = int(np.unique(canon[mask]).size)
    return out


# --------------------------------------------------------------------------
# 5. curvature codes (eq. 4.3, 4.7, 6.1) and vertex indices (eq. 4.8, 6.1)


def _half_configs(c: np.ndarray, n: int, axis: int, side: int) -> np.ndarray:
    """The (n-1)-window on one side of the hyperplane ``x_axis = w_axis``.

    Cell ``d`` with ``d_axis == side`` goes to the (n-1)-bit index of ``d``
    with coordinate ``axis`` removed (the remaining axes keep their order).
    """
    d = octants(n)
    out = np.zeros(c.shape, dtype=np.int64)
    for b in range(1 << n):
        if d[b, axis] != side:
            continue
        rest = np.delete(d[b], axis)
        nb = int(sum(int(v) << i for i, v in enumerate(rest)))
        out |= ((c >> b) & 1) << nb
    return out


def _signs(codes: np.ndarray) -> np.ndarray:
    """``s`` of Definition 9: ``s(+) = 1, s(-) = -1, s(0) = s(∅) = 0``."""
    codes = np.asarray(codes)
    return np.where(np.abs(codes) <= 1, codes, 0).astype(np.int64)


def _check_codes(codes: ArrayLike) -> np.ndarray:
    """Code vectors of :func:`curvature_code`, or one line saying why not:
    a value that is no code (5, 0.5, a string) has no sign, and would
    count as flat."""
    c = np.asarray(codes)
    if c.ndim == 0 or not (np.issubdtype(c.dtype, np.integer) and not np.issubdtype(c.dtype, np.bool_)):
        raise IsoflowError(f"codes must be integer vectors (last axis: the n axes), got {c.dtype} of shape {c.shape}")
    if c.size and not np.isin(c, list(CODE_CHARS)).all():
        raise IsoflowError("codes must be -2 (UNDEFINED), -1 (CONCAVE), 0 (FLAT), 1 (CONVEX) or 2 (NONE), "
                           f"got {c[~np.isin(c, list(CODE_CHARS))].ravel()[0]}")
    return c.astype(np.int64)


def index_61(codes) -> np.ndarray:
    """Eq. 6.1: ``f = (sum_i s(alpha_i)) (prod_i |s(alpha_i)|)``, last axis = i.

    NaN where an axis code is UNDEFINED (the paper's code does not apply).
    """
    codes = _check_codes(codes)
    s = _signs(codes)
    f = (s.sum(axis=-1) * np.abs(s).prod(axis=-1)).astype(np.float64)
    return np.where((codes == UNDEFINED).any(axis=-1), np.nan, f)


def index_48(codes) -> np.ndarray:
    """Eq. 4.8: ``f = (sum_i s(alpha_i)) (sum_i |s(alpha_i)|)``, last axis = i.

    The paper defines it for n = 3 (values 0, +-1, +-3, +-9); the formula is
    evaluated for any n. NaN where an axis code is UNDEFINED.
    """
    codes = _check_codes(codes)
    s = _signs(codes)
    f = (s.sum(axis=-1) * np.abs(s).sum(axis=-1)).astype(np.float64)
    return np.where((codes == UNDEFINED).any(axis=-1), np.nan, f)


def _merge(a: np.ndarray, b: np.ndarray, rule: str) -> np.ndarray:
    """Code of an axis from the section codes of its two halves.

    ``'paper'`` (docs/mathematics.md): the more curved half wins, concave over
    convex over flat over none. ``'symmetric'``: a convex half against a
    concave half gives flat (0); otherwise the more curved half wins. Either
    way an UNDEFINED half makes the axis UNDEFINED.
    """
    if rule == "paper":
        rank = {NONE: 0, FLAT: 1, CONVEX: 2, CONCAVE: 3, UNDEFINED: 4}
    else:
        rank = {NONE: 0, FLAT: 1, CONVEX: 2, CONCAVE: 2, UNDEFINED: 4}
    order = np.zeros(5, dtype=np.int64)  # indexed by code + 2
    for code, r in rank.items():
        order[code + 2] = r
    ra, rb = order[a + 2], order[b + 2]
    out = np.where(ra >= rb, a, b)
    if rule == "symmetric":
        out = np.where((a * b == -1), FLAT, out)  # one convex, one concave
    return out


@cache
def _section_code_table(m: int, rule: str) -> np.ndarray:
    """Scalar code of every m-window seen as the section of an (m+1)-window.

    ``NONE`` if the window is uniform (no boundary in this section),
    ``UNDEFINED`` if it is not a manifold configuration, else the sign of its own eq.
    6.1 index (the paper's nD index, applied one dimension down). For m = 2
    this is the planar code of eq. 4.2: 1 of 4 convex, 2 adjacent flat, 3 of
    4 concave.
    """
    codes = _code_table(m, rule)
    c = np.arange(codes.shape[0])
    f = index_61(codes)
    out = np.where(np.isnan(f), UNDEFINED, np.sign(np.nan_to_num(f))).astype(np.int8)
    out[(c == 0) | (c == full_window(m))] = NONE
    return read_only(out)


@cache
def _code_table(n: int, rule: str) -> np.ndarray:
    """Per-axis codes of every configuration of the n-window, (2^(2^n), n) int8."""
    c = np.arange(1 << (1 << n), dtype=np.int64)
    wc = manifold_configurations(n)
    boundary = (c != 0) & (c != full_window(n))
    codes = np.full((c.size, n), NONE, dtype=np.int8)
    if n == 2:
        # A planar window is its own (only) section plane: both axes carry the
        # planar code of eq. 4.2 (1 of 4 convex, 2 adjacent flat, 3 concave),
        # except an axis across which both halves are uniform, where the
        # boundary is the line x_i = w_i itself: ∅, as in the 3D flat (0,0,∅).
        count = np.array([bin(int(v)).count("1") for v in c])
        planar = np.select([count == 1, count == 3], [CONVEX, CONCAVE], FLAT)
        for axis in range(2):
            uniform = np.ones(c.shape, dtype=bool)
            for side in (0, 1):
                h = _half_configs(c, 2, axis, side)
                uniform &= (h == 0) | (h == 3)
            codes[:, axis] = np.where(uniform, NONE, planar)
    else:
        section = _section_code_table(n - 1, rule).astype(np.int64)
        for axis in range(n):
            h0 = section[_half_configs(c, n, axis, 0)]
            h1 = section[_half_configs(c, n, axis, 1)]
            codes[:, axis] = _merge(h0, h1, rule)
    codes[boundary & ~wc] = UNDEFINED
    codes[~boundary] = NONE
    return read_only(codes)


def curvature_code(config, n: int, rule: str = "paper") -> np.ndarray:
    """Per-axis curvature code ``alpha`` (eqs. 4.3, 4.7, 6.1) of configurations.

    Returns int8 of shape ``config.shape + (n,)`` with values CONVEX (1),
    FLAT (0), CONCAVE (-1), NONE (2, the paper's ∅) and UNDEFINED (-2).

    Axis ``i`` looks at the section of the boundary by the hyperplane
    ``x_i = w_i`` through the vertex, i.e. at the two (n-1)-windows (halves)
    on either side of it. Each half gets a scalar section code: for n = 3
    the planar code of its 2x2 layer (eq. 4.2), for n = 4 the sign of the
    eq. 6.1 index of its 2x2x2 window (recursively); ∅ if uniform. The two
    halves are merged by ``rule`` (see :data:`CODE_RULES`; ``'paper'``
    reproduces the paper's codes of seven of the nine 3D classes). For n = 2
    both axes carry the planar code (∅ across the axis normal to a flat
    boundary). Off the boundary (empty or full window) every axis is NONE;
    where the boundary is not locally a manifold (:func:`manifold_configurations`;
    the well-composed configurations for n <= 3) every axis is UNDEFINED.
    """
    n = check_dimension(n)
    if n < 2:
        raise IsoflowError("curvature codes need n >= 2 (a 1D boundary point has no curvature)")
    if rule not in CODE_RULES:
        raise IsoflowError(f"rule must be one of {CODE_RULES}, got {given_text(rule)}")
    c = _check_configs(config, n)
    return _code_table(n, rule)[c]


def curvature_index(config, n: int, equation: str = "6.1", rule: str = "paper") -> np.ndarray:
    """Vertex index of eq. 6.1 ``(sum s)(prod |s|)`` or eq. 4.8 ``(sum s)(sum |s|)``.

    float64, NaN where the code is UNDEFINED (the boundary is not locally a
    manifold at the vertex); 0 off the boundary. See docs/ndim.md for where
    each applies.
    """
    codes = curvature_code(config, n, rule)
    if equation == "6.1":
        return index_61(codes)
    if equation == "4.8":
        return index_48(codes)
    raise IsoflowError(f"equation must be '6.1' or '4.8', got {given_text(equation)}")


def format_codes(codes: ArrayLike) -> str:
    """``(+,0,∅)``-style text of one code vector (:func:`curvature_code`).

    Examples
    --------
    >>> format_codes([1, 0, 2])
    '(+,0,∅)'
    """
    return "(" + ",".join(CODE_CHARS[int(v)] for v in np.asarray(codes).ravel()) + ")"
