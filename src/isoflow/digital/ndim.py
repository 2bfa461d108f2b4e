"""Vertex configurations, Euler shares and curvature codes in 1 to 4 dimensions.

Section 6 of the paper proposes to carry the curvature codes of section 4 to
``n`` dimensions (eq. 6.1) and conjectures a digital Chern-Gauss-Bonnet theorem
``a^T n = 2^n (1 - g)`` (eq. 6.2) and an energy ``E = k^T n = 2^n (1 + g)``
(eq. 6.3). This module builds, for ``n = 1 .. 4``, every table needed to test
those statements, from first principles and nothing typed in:

* the ``2^n n!`` symmetries of the n-cube acting on octant bits and on whole
  configurations (:func:`hyperoctahedral_group`);
* for every configuration, ``2^n`` times its share of the Euler characteristic
  for the two extreme adjacencies (:func:`euler_lut`), so that the exact
  Gauss-Bonnet identity ``sum_v a(v) = 2^n chi(X)`` holds on every image;
* orbits, well-composed classes, the per-axis curvature codes and the vertex
  indices of eqs. 4.8 and 6.1 (:func:`curvature_code`, :func:`curvature_index`);
* exact GF(2) Betti numbers of small images
  (:func:`isoflow.digital.homology.betti_numbers`) check
  ``chi = sum (-1)^i b_i`` independently of these tables.

Conventions (shared with :mod:`isoflow.digital.configurations`): a binary image of
dimension ``n`` is a boolean array; cell ``v`` is the closed cube
``[v, v+1]``; lattice vertex ``w`` is the common corner of the ``2^n`` cells
``w - 1 + d``, ``d`` in ``{0,1}^n``; cell ``d`` of the window is bit
``d_0 + 2 d_1 + 4 d_2 + 8 d_3`` of the configuration; an image of shape ``S``
has ``prod(S_i + 1)`` vertices (one background layer is padded on every side).

Adjacencies: ``'min'`` is the ``2n``-adjacency of the object (4 in 2D, 6 in
3D, 8 in 4D) with the ``(3^n - 1)``-adjacency of the background; ``'max'`` is
the ``(3^n - 1)``-adjacency of the object (8, 26, 80) with ``2n`` for the
background. See ``docs/ndim.md`` for the derivations and the findings.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..errors import IsoflowError

#: largest dimension handled (4D already has 2^16 configurations)
MAX_DIM = 4
#: the two extreme adjacencies of the object
ADJACENCIES = ("min", "max")

#: per-axis code values (same numbers as :mod:`isoflow.digital.indices`): eq. 4.3's
#: ``+``, ``0``, ``-`` and ``∅`` (no boundary across that axis), and
#: ``UNDEFINED`` where the boundary is not locally a manifold at the vertex
#: (:func:`manifold_configurations`), so that the paper's codes do not apply.
CONVEX, FLAT, CONCAVE, NONE, UNDEFINED = 1, 0, -1, 2, -2
CODE_CHARS = {CONVEX: "+", FLAT: "0", CONCAVE: "-", NONE: "∅", UNDEFINED: "?"}
#: the two ways of merging the codes of the two halves across an axis
CODE_RULES = ("paper", "symmetric")


# --------------------------------------------------------------------------
# validation helpers


def check_dim(n) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise IsoflowError(f"dimension n must be an integer 1..{MAX_DIM}, got {n!r}")
    n = int(n)
    if not 1 <= n <= MAX_DIM:
        raise IsoflowError(f"dimension n must be 1..{MAX_DIM}, got {n}")
    return n


def check_adjacency(adjacency) -> str:
    if adjacency not in ADJACENCIES:
        raise IsoflowError(f"adjacency must be 'min' or 'max', got {adjacency!r}")
    return adjacency


def as_binary(volume) -> np.ndarray:
    """The image as a boolean array of dimension 1..4, or IsoflowError."""
    try:
        x = np.asarray(volume)
    except Exception as exc:  # ragged lists and the like
        raise IsoflowError(f"volume is not an array: {exc}") from None
    if x.dtype != np.bool_:
        raise IsoflowError(f"volume must be a boolean array, got dtype {x.dtype}")
    if not 1 <= x.ndim <= MAX_DIM:
        raise IsoflowError(
            f"volume must have 1..{MAX_DIM} dimensions, got {x.ndim} (shape {x.shape})"
        )
    return x


def _config_dtype(n: int):
    return np.uint8 if n <= 3 else np.uint16


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def num_configurations(n: int) -> int:
    """``2^(2^n)``: the number of configurations of the n-dimensional window."""
    n = check_dim(n)
    return 1 << (1 << n)


def _check_configs(config, n: int) -> np.ndarray:
    c = np.asarray(config)
    if not np.issubdtype(c.dtype, np.integer):
        raise IsoflowError(f"configurations must be integers, got dtype {c.dtype}")
    size = 1 << (1 << n)
    if c.size and (c.min() < 0 or c.max() >= size):
        raise IsoflowError(f"configurations of a {n}D window must lie in 0..{size - 1}")
    return c.astype(np.int64)


# --------------------------------------------------------------------------
# the window


@lru_cache(maxsize=None)
def octants(n: int) -> np.ndarray:
    """Offsets ``d`` of the ``2^n`` cells of the window, row ``b`` = bit ``b``.

    Bit ``b`` is ``d_0 + 2 d_1 + 4 d_2 + 8 d_3``, i.e. ``d_i = (b >> i) & 1``.
    """
    n = check_dim(n)
    b = np.arange(1 << n)
    return _readonly(((b[:, None] >> np.arange(n)) & 1).astype(np.int8))


def _full(n: int) -> int:
    return (1 << (1 << n)) - 1


def _axis_side_mask(n: int, axis: int, side: int) -> int:
    """Bitmask of the window cells with ``d_axis == side`` (one half)."""
    d = octants(n)
    return int(sum(1 << b for b in range(1 << n) if d[b, axis] == side))


@lru_cache(maxsize=None)
def window_faces(n: int) -> tuple[tuple[int, int], ...]:
    """The ``3^n`` faces of the lattice incident to a vertex, as (mask, k).

    A face incident to vertex ``w`` is ``w + prod_i F_i`` with ``F_i`` one of
    ``{0}``, ``[-1, 0]``, ``[0, 1]`` (``e_i = 0, -1, +1``); ``k`` is its
    dimension (the number of ``e_i != 0``). ``mask`` is the set of window
    cells that contain it: ``d_i = (e_i > 0)`` where ``e_i != 0``, ``d_i``
    free where ``e_i = 0``. The same masks are exactly the blocks of
    ``2^(n-k)`` face-adjacent cells of the window (the faces of the dual
    complex), which is why both Euler tables below come from one list.
    """
    n = check_dim(n)
    d = octants(n)
    faces = []
    for e in itertools.product((-1, 0, 1), repeat=n):
        ok = np.ones(1 << n, dtype=bool)
        for i, ei in enumerate(e):
            if ei != 0:
                ok &= d[:, i] == (1 if ei > 0 else 0)
        mask = int(sum(1 << int(b) for b in np.flatnonzero(ok)))
        faces.append((mask, sum(1 for ei in e if ei != 0)))
    return tuple(faces)


# --------------------------------------------------------------------------
# 1. the hyperoctahedral group


@dataclass(frozen=True)
class CubeGroup:
    """The ``2^n n!`` symmetries of the n-cube (all arrays read-only).

    Element ``g`` is the axis permutation ``axis_permutations[g]`` (``p``)
    and the reflections ``flips[g]`` (``f``); it maps image ``X`` to
    ``np.transpose(np.flip(X, axes where f), p)`` (:func:`apply_symmetry`).
    On window offsets it sends ``d`` to ``e`` with ``e_j = d_{p_j} xor
    f_{p_j}``, i.e. octant bit ``b`` to ``bit_permutations[g, b]``, and the
    configuration ``c`` of a vertex of ``X`` to the configuration
    ``configuration_permutations[g, c]`` of the corresponding vertex of the
    transformed image. Element 0 is the identity.
    """

    n: int
    axis_permutations: np.ndarray  # (G, n) int8
    flips: np.ndarray  # (G, n) bool
    bit_permutations: np.ndarray  # (G, 2^n) int16
    configuration_permutations: np.ndarray  # (G, 2^(2^n)) uint8 / uint16

    def __len__(self) -> int:
        return len(self.axis_permutations)


@lru_cache(maxsize=None)
def hyperoctahedral_group(n: int) -> CubeGroup:
    """The symmetries of the n-cube on octant bits and on configurations.

    Generated as every axis permutation (``n!``) combined with every set of
    reflections (``2^n``): 2, 8, 48, 384 elements for n = 1..4. The induced
    action on the ``2^(2^n)`` configurations is vectorised: a configuration
    is split into bytes and each byte's image is looked up in a (G, 256)
    table, so the (384, 65536) table of 4D costs two gathers.
    """
    n = check_dim(n)
    d = octants(n).astype(np.int64)
    weights = 1 << np.arange(n)
    perms, flips, bitperms = [], [], []
    for p in itertools.permutations(range(n)):
        p = np.array(p)
        for f in itertools.product((0, 1), repeat=n):
            f = np.array(f)
            e = d[:, p] ^ f[p]  # e_j = d_{p_j} xor f_{p_j}
            perms.append(p)
            flips.append(f.astype(bool))
            bitperms.append(e @ weights)
    bitperms = np.array(bitperms, dtype=np.int64)  # (G, 2^n)
    nbits = 1 << n
    nconf = 1 << nbits
    dtype = _config_dtype(n)
    conf = np.arange(nconf, dtype=np.int64)
    out = np.zeros((len(bitperms), nconf), dtype=dtype)
    for lo in range(0, nbits, 8):
        width = min(8, nbits - lo)
        byte = np.arange(1 << width)
        # image of every value of this byte under every g: (G, 2^width)
        table = np.zeros((len(bitperms), 1 << width), dtype=np.int64)
        for j in range(width):
            table |= ((byte[None, :] >> j) & 1) << bitperms[:, lo + j : lo + j + 1]
        out |= table.astype(dtype)[:, (conf >> lo) & ((1 << width) - 1)]
    return CubeGroup(
        n=n,
        axis_permutations=_readonly(np.array(perms, dtype=np.int8)),
        flips=_readonly(np.array(flips, dtype=bool)),
        bit_permutations=_readonly(bitperms.astype(np.int16)),
        configuration_permutations=_readonly(out),
    )


def apply_symmetry(volume, g: int) -> np.ndarray:
    """Image of ``volume`` under element ``g`` of :func:`hyperoctahedral_group`.

    Flips the axes with ``flips[g]``, then transposes with
    ``axis_permutations[g]`` (output axis ``j`` is input axis ``p_j``).
    """
    x = as_binary(volume)
    group = hyperoctahedral_group(x.ndim)
    if not 0 <= int(g) < len(group):
        raise IsoflowError(f"symmetry index must be 0..{len(group) - 1}, got {g}")
    flip_axes = tuple(int(i) for i in np.flatnonzero(group.flips[g]))
    y = np.flip(x, axis=flip_axes) if flip_axes else x
    return np.transpose(y, tuple(int(i) for i in group.axis_permutations[g]))


# --------------------------------------------------------------------------
# 2. Euler lookup tables


@lru_cache(maxsize=None)
def euler_lut(n: int, adjacency: str = "min") -> np.ndarray:
    """``2^n`` times each configuration's local share of chi (int32, read-only).

    This is the vector ``a`` of eqs. 4.10 and 6.2 extended to every
    configuration, so that for every image ``sum_v lut[config(v)] = 2^n chi``.

    * ``'max'`` ((3^n - 1)-adjacency): chi of the union of the closed cells.
      Its cells are the lattice faces; a k-face has ``2^k`` vertices, so
      each vertex gets ``(-1)^k / 2^k`` of it. The k-faces incident to ``w``
      are the ``3^n`` faces of :func:`window_faces`; one is in the union iff
      ANY window cell containing it is in X. Hence
      ``lut = sum_faces (-1)^k 2^(n-k) [mask & c != 0]``.
    * ``'min'`` (2n-adjacency): chi of the cubical complex whose vertices are
      the cell centres and whose j-faces are the blocks of ``2^j`` cells ALL
      in X. A block is seen by the ``2^(n-j)`` vertices whose window holds
      it, so its weight ``(-1)^j`` is shared as ``(-1)^j 2^j / 2^n``. Hence
      ``lut = sum_blocks (-1)^j 2^j [mask & c == mask]`` (``j = n - k``).
    """
    n = check_dim(n)
    check_adjacency(adjacency)
    c = np.arange(1 << (1 << n), dtype=np.int64)
    lut = np.zeros(c.shape, dtype=np.int64)
    for mask, k in window_faces(n):
        if adjacency == "max":
            lut += (-1) ** k * (1 << (n - k)) * ((c & mask) != 0)
        else:
            j = n - k
            lut += (-1) ** j * (1 << j) * ((c & mask) == mask)
    return _readonly(lut.astype(np.int32))


# --------------------------------------------------------------------------
# 3. configurations and the Euler characteristic


def configurations(volume) -> np.ndarray:
    """Configuration of every lattice vertex of a 1D..4D boolean image.

    Returns an array of shape ``S + 1`` (uint8 for n <= 3, uint16 for n = 4):
    the OR of the ``2^n`` shifted copies of the padded image, copy ``d``
    shifted into bit ``d_0 + 2 d_1 + 4 d_2 + 8 d_3`` (vertex ``w`` sees cell
    ``w - 1 + d``, i.e. padded index ``w + d``).
    """
    x = as_binary(volume)
    n = x.ndim
    dtype = _config_dtype(n)
    padded = np.pad(x, 1)
    shape = tuple(s + 1 for s in x.shape)
    conf = np.zeros(shape, dtype=dtype)
    for b, d in enumerate(octants(n)):
        window = tuple(slice(int(di), int(di) + s) for di, s in zip(d, shape))
        conf |= padded[window].astype(dtype) << dtype(b)
    return conf


def configuration_histogram(volume) -> np.ndarray:
    """The paper's vector ``n`` (eq. 4.9) per configuration: counts over vertices."""
    x = as_binary(volume)
    return np.bincount(configurations(x).ravel(), minlength=1 << (1 << x.ndim))


def vertex_curvature(volume, adjacency: str = "min") -> np.ndarray:
    """``a(v)`` at every vertex (shape ``S + 1``): ``2^n`` x the local Euler share.

    The digital Gauss-Bonnet identity is ``vertex_curvature(X).sum() ==
    2^n * euler_characteristic(X)`` (the exact form of Theorems 10-11 and of
    eq. 6.2's left-hand side).
    """
    x = as_binary(volume)
    return euler_lut(x.ndim, adjacency)[configurations(x)]


def gauss_bonnet_sum(volume, adjacency: str = "min") -> int:
    """``a^T n`` of eqs. 4.12, 4.13 and 6.2: the sum of ``a(v)`` over all vertices."""
    x = as_binary(volume)
    lut = euler_lut(x.ndim, adjacency).astype(np.int64)
    return int(configuration_histogram(x) @ lut)


def euler_characteristic(volume, adjacency: str = "min") -> int:
    """chi of a 1D..4D binary image from the configuration histogram.

    ``chi = (n^T a) / 2^n`` with ``n`` the ``np.bincount`` of the
    configurations and ``a`` = :func:`euler_lut`. The division is exact.
    """
    x = as_binary(volume)
    total = gauss_bonnet_sum(x, adjacency)
    q, r = divmod(total, 1 << x.ndim)
    assert r == 0, "Euler shares must add up to a multiple of 2^n"
    return q


def surface_energy(volume, adjacency: str = "min") -> int:
    """``E = k^T n`` of eqs. 5.22 and 6.3 with ``k = a^2``: sum of ``a(v)^2``."""
    x = as_binary(volume)
    lut = euler_lut(x.ndim, adjacency).astype(np.int64)
    return int(configuration_histogram(x) @ (lut * lut))


# --------------------------------------------------------------------------
# 4. classes up to symmetry


@lru_cache(maxsize=None)
def configuration_orbits(n: int) -> np.ndarray:
    """Canonical representative (least image under the group) of every configuration."""
    n = check_dim(n)
    perms = hyperoctahedral_group(n).configuration_permutations
    return _readonly(perms.min(axis=0).astype(np.int64))


def _shift_along(sets: np.ndarray, n: int, axis: int) -> np.ndarray:
    """Face neighbours across ``axis`` of a set of window cells (bitmask)."""
    step = 1 << axis  # bit distance between d and d xor e_axis
    lo = _axis_side_mask(n, axis, 0)
    hi = _axis_side_mask(n, axis, 1)
    return ((sets & lo) << step) | ((sets & hi) >> step)


def _face_connected(sets: np.ndarray, n: int) -> np.ndarray:
    """Whether each non-empty cell set is connected under face adjacency.

    Breadth-first growth from the lowest cell, vectorised over all sets.
    """
    sets = sets.astype(np.int64)
    reach = sets & -sets  # lowest set bit
    while True:
        grown = reach.copy()
        for axis in range(n):
            grown |= _shift_along(reach, n, axis)
        grown &= sets
        if np.array_equal(grown, reach):
            return reach == sets
        reach = grown


@lru_cache(maxsize=None)
def well_composed(n: int) -> np.ndarray:
    """Boolean mask over configurations: well-composed boundary configurations.

    Both the object cells and the background cells of the window are
    non-empty and each is connected under face adjacency of the window's
    cells (cells whose bits differ in one coordinate). For n <= 3 these are
    exactly the configurations where the boundary is locally a manifold
    (section 4.2: "on the boundary of a 6-connected object"); for n = 4 the
    condition is weaker (see :func:`manifold_configurations`).
    """
    n = check_dim(n)
    c = np.arange(1 << (1 << n), dtype=np.int64)
    bg = _full(n) ^ c
    boundary = (c != 0) & (bg != 0)
    ok = np.zeros(c.shape, dtype=bool)
    ok[boundary] = _face_connected(c[boundary], n) & _face_connected(bg[boundary], n)
    return _readonly(ok)


@lru_cache(maxsize=None)
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


@lru_cache(maxsize=None)
def digitally_well_composed(n: int) -> np.ndarray:
    """Mask of boundary configurations without a critical sub-block.

    Digital well-composedness (Boutry, Geraud, Najman): no sub-block of
    dimension k >= 2 holds exactly one antagonist pair of object cells, or
    all its cells but one antagonist pair. Equal to :func:`well_composed`
    for n <= 3; strictly stronger in 4D.
    """
    n = check_dim(n)
    c = np.arange(1 << (1 << n), dtype=np.int64)
    bad = np.zeros(c.shape, dtype=bool)
    for mask, pairs in _sub_blocks(n):
        sub = c & mask
        for pair in pairs:
            bad |= (sub == pair) | (sub == (mask ^ pair))
    return _readonly(~bad & (c != 0) & (c != _full(n)))


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


@lru_cache(maxsize=None)
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
    n = check_dim(n)
    c = int(_check_configs(config, n))
    full = _full(n)
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


@lru_cache(maxsize=None)
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
    n = check_dim(n)
    dwc = digitally_well_composed(n)
    if n <= 2:
        return dwc
    canon = configuration_orbits(n)
    sphere = tuple(1 if k == n - 2 else 0 for k in range(n))
    good = [
        r for r in np.unique(canon[dwc])
        if link_betti_numbers(int(r), n)["boundary"] == sphere
    ]
    return _readonly(dwc & np.isin(canon, good))


def boundary_classes(n: int, well_composed_only: bool = True) -> np.ndarray:
    """Canonical representatives of the boundary classes (sorted).

    With ``well_composed_only`` the classes of :func:`well_composed`
    configurations (3 in 2D, the paper's 9 in 3D); otherwise every orbit
    except those of the empty and the full window.
    """
    n = check_dim(n)
    canon = configuration_orbits(n)
    c = np.arange(canon.size)
    keep = well_composed(n) if well_composed_only else (c != 0) & (c != _full(n))
    return np.unique(canon[keep])


def class_counts(n: int) -> dict:
    """Orbit statistics of the n-dimensional window.

    Keys: ``orbits`` (all configurations up to symmetry), ``boundary_orbits``
    (without empty/full), and ``<kind>_configurations`` / ``<kind>_classes``
    for kind ``well_composed`` (face-connected object and background),
    ``digitally_well_composed`` and ``manifold``.
    """
    n = check_dim(n)
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


def index_61(codes) -> np.ndarray:
    """Eq. 6.1: ``f = (sum_i s(alpha_i)) (prod_i |s(alpha_i)|)``, last axis = i.

    NaN where an axis code is UNDEFINED (the paper's code does not apply).
    """
    codes = np.asarray(codes)
    s = _signs(codes)
    f = (s.sum(axis=-1) * np.abs(s).prod(axis=-1)).astype(np.float64)
    return np.where((codes == UNDEFINED).any(axis=-1), np.nan, f)


def index_48(codes) -> np.ndarray:
    """Eq. 4.8: ``f = (sum_i s(alpha_i)) (sum_i |s(alpha_i)|)``, last axis = i.

    The paper defines it for n = 3 (values 0, +-1, +-3, +-9); the formula is
    evaluated for any n. NaN where an axis code is UNDEFINED.
    """
    codes = np.asarray(codes)
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


@lru_cache(maxsize=None)
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
    out[(c == 0) | (c == _full(m))] = NONE
    return _readonly(out)


@lru_cache(maxsize=None)
def _code_table(n: int, rule: str) -> np.ndarray:
    """Per-axis codes of every configuration of the n-window, (2^(2^n), n) int8."""
    c = np.arange(1 << (1 << n), dtype=np.int64)
    wc = manifold_configurations(n)
    boundary = (c != 0) & (c != _full(n))
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
    return _readonly(codes)


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
    n = check_dim(n)
    if n < 2:
        raise IsoflowError("curvature codes need n >= 2 (a 1D boundary point has no curvature)")
    if rule not in CODE_RULES:
        raise IsoflowError(f"rule must be one of {CODE_RULES}, got {rule!r}")
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
    raise IsoflowError(f"equation must be '6.1' or '4.8', got {equation!r}")


def code_string(codes) -> str:
    """``(+,0,∅)``-style text of one code vector."""
    return "(" + ",".join(CODE_CHARS[int(v)] for v in np.asarray(codes).ravel()) + ")"
