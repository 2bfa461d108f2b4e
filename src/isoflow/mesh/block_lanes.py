"""A block of voxel centres decided with its centres in SIMD lanes: the
block's first-order model plus its near triangles summed at every centre
at once, and the centres that the model leaves undecided summed exactly
over the whole cap.

These are the steps of :mod:`isoflow.mesh.winding`'s rule ``R =
round(w_C)`` that cost per centre: the model of a block (its far part's
value, gradient and bound, :func:`isoflow.mesh.captree.evaluate`) costs
one walk of the cap's tree, but its near triangles and the exact sum
cost a solid angle per centre and triangle.  Here each of those loops
runs over the centres of the block for one triangle at a time
(:func:`isoflow.mesh.solid_angles.winding_lanes`), so the arithmetic is
that of the scalar code, lane by lane: the same values up to rounding,
and rounding is what :data:`TIE_WINDING` absorbs.

The rule's codes live here (the lanes write them).
"""

from __future__ import annotations

import math

import numpy as np

from ..scale.jit import njit
from .captree import dist_triangle
from .solid_angles import winding_lanes

#: centres whose w_C is this close to a half-integer are decided by the tie rule
TIE_WINDING = 1e-9
#: codes of a centre that the mesh's own sum decided
FORCE_IN, FORCE_OUT = 127, -128
#: a centre the kernel leaves to be summed over M (then FORCE_IN or FORCE_OUT)
TIE_PENDING = -127
#: a centre that the model of its block did not decide (evaluated on its own next)
UNDECIDED = -126
#: the largest |R| the int8 rule holds beside these codes
MAX_R = 125
#: centres painted at once, in one run of lanes
PAINT_LANES = 64


@njit(cache=True, nogil=True)
def centres(i, j, k, j0, j1, k0, k1, m, origin, pitch, X, Y, Z):
    """``m`` centres of the block ``j0 <= j < j1, k0 <= k < k1`` into
    ``X, Y, Z``, from centre (i, j, k) on (k fastest, then j, then i)."""
    for c in range(m):
        X[c] = origin[0] + pitch * (i + 0.5)
        Y[c] = origin[1] + pitch * (j + 0.5)
        Z[c] = origin[2] + pitch * (k + 0.5)
        k += 1
        if k == k1:
            k, j = k0, j + 1
            if j == j1:
                j, i = j0, i + 1


@njit(cache=True, nogil=True)
def on_triangles(T, nlen, which, m, px, py, pz, tol):
    """Whether p lies within ``tol`` of one of the triangles ``T[which[:m]]``."""
    for q in range(m):
        t = which[q]
        ax, ay, az = T[t, 0, 0] - px, T[t, 0, 1] - py, T[t, 0, 2] - pz
        bx, by, bz = T[t, 1, 0] - px, T[t, 1, 1] - py, T[t, 1, 2] - pz
        cx, cy, cz = T[t, 2, 0] - px, T[t, 2, 1] - py, T[t, 2, 2] - pz
        det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        if abs(det) <= tol * nlen[t] and dist_triangle(T, t, px, py, pz) <= tol:
            return True
    return False


#: centres queued for the exact sum before it runs (over all of them at once)
QUEUE = 512


@njit(cache=True, nogil=True)
def queue_centres(rule, box, i0, i1, j0, j1, k0, k1, every, origin, pitch, Q, at, nq):
    """Queue the block's centres (all of them with ``every``, else those
    marked :data:`UNDECIDED`) for :func:`exact_queue`: their positions
    into ``Q`` and their indices in ``rule`` into ``at``, after the ``nq``
    queued already.  Returns the new length (the caller leaves room for
    the block)."""
    for i in range(i0, i1):
        for j in range(j0, j1):
            for k in range(k0, k1):
                if every or rule[i - box[0], j - box[1], k - box[2]] == UNDECIDED:
                    Q[0, nq] = origin[0] + pitch * (i + 0.5)
                    Q[1, nq] = origin[1] + pitch * (j + 0.5)
                    Q[2, nq] = origin[2] + pitch * (k + 0.5)
                    at[nq, 0], at[nq, 1], at[nq, 2] = i - box[0], j - box[1], k - box[2]
                    nq += 1
    return nq


@njit(cache=True, nogil=True)
def exact_queue(rule, Q, at, nq, tol, T, nlen, w, gap):
    """R at the ``nq`` queued centres from the exact sum over the cap's
    triangles ``T`` (in lanes, all the queue at once):
    :data:`TIE_PENDING` where a centre lies within ``tol`` of the cap or
    its ``w_C`` within :data:`TIE_WINDING` of a half-integer.  Returns
    -1 where |R| would exceed :data:`MAX_R`, else ``nq``."""
    winding_lanes(T, nlen, Q[0], Q[1], Q[2], nq, tol, w, gap)
    every = np.arange(T.shape[0])
    big = False
    for m in range(nq):
        x = w[m]
        val = math.floor(x - TIE_WINDING + 0.5)
        i, j, k = at[m, 0], at[m, 1], at[m, 2]
        if (gap[m] <= 0 and on_triangles(T, nlen, every, T.shape[0], Q[0, m], Q[1, m], Q[2, m], tol)) or val != math.floor(
                x + TIE_WINDING + 0.5):
            rule[i, j, k] = TIE_PENDING
        else:
            big |= not _put(rule, i, j, k, val)
    return -1 if big else nq


@njit(cache=True, nogil=True)
def _copy_triangle(T, t, Tn, q):
    """``Tn[q] = T[t]`` element by element: an array assigned to an array
    makes numba compile its shape-mismatch message (string formatting),
    seconds of a first run's compile."""
    for a in range(3):
        for b in range(3):
            Tn[q, a, b] = T[t, a, b]


@njit(cache=True, nogil=True)
def near_lanes(T, nlen, near, nn, cross, nc, qx, qy, qz, X, Y, Z, n, tol, w, gap, J, Tn, ln):
    """At each centre ``i < n``: ``w[i]`` the near triangles' winding
    number plus the jumps of the crossing ones between q and the centre
    (``w_t = -s / 2 +`` a continuous part, s the side of t's plane), and
    ``gap[i] <= 0`` where a near triangle's or a crossing one's plane
    passes within ``tol`` of it (``J`` is scratch)."""
    for q in range(nn):
        _copy_triangle(T, near[q], Tn, q)
        ln[q] = nlen[near[q]]
    winding_lanes(Tn[:nn], ln, X, Y, Z, n, tol, w, gap)
    for i in range(n):
        J[i] = 0.0
    for c in range(nc):
        t = cross[c]
        ax, ay, az = T[t, 0, 0], T[t, 0, 1], T[t, 0, 2]
        ux, uy, uz = T[t, 1, 0] - ax, T[t, 1, 1] - ay, T[t, 1, 2] - az
        vx, vy, vz = T[t, 2, 0] - ax, T[t, 2, 1] - ay, T[t, 2, 2] - az
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        here = 1.0 if (qx - ax) * nx + (qy - ay) * ny + (qz - az) * nz > 0 else 0.0
        margin = tol * nlen[t]
        for i in range(n):
            sp = (X[i] - ax) * nx + (Y[i] - ay) * ny + (Z[i] - az) * nz
            J[i] += here - (1.0 if sp > 0 else 0.0)
            gap[i] = min(gap[i], abs(sp) - margin)
    for i in range(n):
        w[i] += J[i]


@njit(cache=True, nogil=True)
def paint_lanes(rule, box, i0, i1, j0, j1, k0, k1, w, grad, base, curv, qx, qy, qz, T, nlen, near, nn, cross, nc,
                origin, pitch, tol, X, Y, Z, wl, gap, J, Tn, ln, split):
    """R on the block's centres p from its model at q,
    ``round(w + grad . (p - q) + w_near(p) +- (base + curv |p - q|^2))``
    (the model's remainder at p), with the near
    triangles summed in lanes (:func:`near_lanes`) over runs of
    :data:`PAINT_LANES` centres: :data:`UNDECIDED` where the interval holds
    a half-integer, :data:`TIE_PENDING` on a near or crossing triangle.
    Returns how many are undecided, or -1 where |R| would exceed
    :data:`MAX_R`; with ``split``, the block's size at its first undecided
    centre (the block is split, and its children paint it again)."""
    n = (i1 - i0) * (j1 - j0) * (k1 - k0)
    for q in range(nn):
        _copy_triangle(T, near[q], Tn, q)
        ln[q] = nlen[near[q]]
    left = 0
    big = False
    ci, cj, ck = i0, j0, k0  # the next run's first centre
    for start in range(0, n, PAINT_LANES):
        m = min(PAINT_LANES, n - start)
        centres(ci, cj, ck, j0, j1, k0, k1, m, origin, pitch, X, Y, Z)
        near_lanes(T, nlen, near, nn, cross, nc, qx, qy, qz, X, Y, Z, m, tol, wl, gap, J, Tn, ln)
        for c in range(m):
            i, j, k = ci - box[0], cj - box[1], ck - box[2]
            ck += 1
            if ck == k1:
                ck, cj = k0, cj + 1
                if cj == j1:
                    cj, ci = j0, ci + 1
            dx, dy, dz = X[c] - qx, Y[c] - qy, Z[c] - qz
            x = w + grad[0] * dx + grad[1] * dy + grad[2] * dz + wl[c]
            bound = base + curv * (dx * dx + dy * dy + dz * dz)
            val = math.floor(x - bound + 0.5)
            if gap[c] <= 0 and (on_triangles(T, nlen, near, nn, X[c], Y[c], Z[c], tol)
                                or _on_crossing(T, nlen, cross, nc, X[c], Y[c], Z[c], tol)):
                rule[i, j, k] = TIE_PENDING
            elif val != math.floor(x + bound + 0.5):
                if split:
                    return n
                rule[i, j, k] = UNDECIDED
                left += 1
            else:
                big |= not _put(rule, i, j, k, val)
    return -1 if big else left


@njit(cache=True, nogil=True, inline="always")
def _put(rule, i, j, k, val):
    """R = val at (i, j, k); False (nothing written) where |R| exceeds :data:`MAX_R`."""
    if val > MAX_R or val < -MAX_R:
        return False
    rule[i, j, k] = val
    return True


@njit(cache=True, nogil=True)
def _on_crossing(T, nlen, cross, nc, px, py, pz, tol):
    """Whether p lies within ``tol`` of a crossing triangle's plane (there,
    within the ball, the triangle itself)."""
    for c in range(nc):
        t = cross[c]
        ux, uy, uz = T[t, 1, 0] - T[t, 0, 0], T[t, 1, 1] - T[t, 0, 1], T[t, 1, 2] - T[t, 0, 2]
        vx, vy, vz = T[t, 2, 0] - T[t, 0, 0], T[t, 2, 1] - T[t, 0, 1], T[t, 2, 2] - T[t, 0, 2]
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        if abs((px - T[t, 0, 0]) * nx + (py - T[t, 0, 1]) * ny + (pz - T[t, 0, 2]) * nz) <= tol * nlen[t]:
            return True
    return False
