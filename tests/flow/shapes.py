"""Seeded test objects for the flow tests, whose topology is known by
construction: solid tori, annulus prisms, linked rings, a figure eight, a
hollow ball, random unions of boxes (with edge and vertex contacts) and their
2D counterparts. Shared by ``test_guard_limits.py`` and
``test_plain_reference.py`` (``python tests/flow/shapes.py`` rewrites the
plain-run reference; see that test)."""

from __future__ import annotations

import numpy as np


def solid_torus(R: float, r: float, axis: int = 2) -> np.ndarray:
    size = int(2 * (R + r) + 4)
    x = np.indices((size,) * 3).astype(float) - (size - 1) / 2
    others = [i for i in range(3) if i != axis]
    rho = np.sqrt(x[others[0]] ** 2 + x[others[1]] ** 2)
    return (rho - R) ** 2 + x[axis] ** 2 <= r**2


def annulus_prism(outer: int = 8, wall: int = 1, height: int = 3) -> np.ndarray:
    v = np.ones((outer, outer, height), bool)
    v[wall:outer - wall, wall:outer - wall] = False
    return v


def square_ring(lo, side: int, thick: int, plane_axes, shape) -> np.ndarray:
    """A square ring (frame) of outer side ``side`` and wall ``thick``, one
    voxel (``thick`` voxels) across, in the plane of ``plane_axes``."""
    v = np.zeros(shape, bool)
    a, b = plane_axes
    c = 3 - a - b
    sl = [slice(None)] * 3
    sl[a] = slice(lo[a], lo[a] + side)
    sl[b] = slice(lo[b], lo[b] + side)
    sl[c] = slice(lo[c], lo[c] + thick)
    v[tuple(sl)] = True
    sl[a] = slice(lo[a] + thick, lo[a] + side - thick)
    sl[b] = slice(lo[b] + thick, lo[b] + side - thick)
    v[tuple(sl)] = False
    return v


def linked_rings(side: int = 7, thick: int = 1, a: int | None = None) -> np.ndarray:
    """Two square rings through each other's hole, apart (a Hopf link):
    b = (2, 2, 0). Each ring's wall passes through the other's hole with a
    gap of at least one voxel on each side; ``a`` is where ring 2's near
    wall starts along axis 0 (inside ring 1's hole)."""
    assert side >= 3 * thick + 4
    n = 2 * side
    shape = (n, n, n)
    mid = (side - thick) // 2
    a = thick + 1 if a is None else a
    r1 = square_ring((0, 0, mid), side, thick, (0, 1), shape)
    r2 = square_ring((a, mid, 0), side, thick, (0, 2), shape)
    assert not (r1 & r2).any()
    v = r1 | r2
    return v[: a + side, :side, :side]


def figure_eight(side: int = 7, thick: int = 2, height: int = 2) -> np.ndarray:
    """Two square annuli sharing a wall: one component, two tunnels."""
    v = np.ones((2 * side - thick, side, height), bool)
    h = side - 2 * thick
    v[thick:thick + h, thick:thick + h] = False
    v[side:side + h, thick:thick + h] = False
    return v


def hollow_ball(radius: float = 4.5, hole: float = 2.0) -> np.ndarray:
    size = int(2 * radius + 4)
    x = np.indices((size,) * 3) - (size - 1) / 2
    d = (x**2).sum(0)
    return (d <= radius**2) & (d > hole**2)


def union_of_boxes(rng, size: int = 10, count: int = 4, ndim: int = 3) -> np.ndarray:
    """Random boxes; with several boxes, edge and vertex contacts occur."""
    v = np.zeros((size,) * ndim, bool)
    for _ in range(count):
        lo = rng.integers(0, size - 1, ndim)
        hi = lo + rng.integers(1, 6, ndim)
        v[tuple(slice(a, b) for a, b in zip(lo, hi))] = True
    return v


def contacts(ndim: int = 3) -> np.ndarray:
    """Boxes touching only along an edge and at a vertex (and, in 2D, at a
    corner): joined under the larger adjacency, apart under the smaller."""
    if ndim == 2:
        v = np.zeros((7, 7), bool)
        v[:3, :3] = v[3:5, 3:6] = v[5:, 6:] = True
        return v
    v = np.zeros((7, 7, 7), bool)
    v[:3, :3, :] = True  # a bar
    v[3:5, 3:5, 2:5] = True  # edge contact with the bar
    v[5:, 5:, 5:] = True  # vertex contact with the second box
    return v


def planar_annulus(outer: int = 9, wall: int = 1) -> np.ndarray:
    v = np.ones((outer, outer), bool)
    v[wall:outer - wall, wall:outer - wall] = False
    return v


def planar_disc_ring(R: float = 6.0, r: float = 2.0) -> np.ndarray:
    size = int(2 * R + 4)
    x = np.indices((size, size)) - (size - 1) / 2
    d = np.sqrt((x**2).sum(0))
    return (d <= R) & (d > r)


def planar_figure_eight(side: int = 7, wall: int = 1) -> np.ndarray:
    v = np.ones((2 * side - wall, side), bool)
    h = side - 2 * wall
    v[wall:wall + h, wall:wall + h] = False
    v[side:side + h, wall:wall + h] = False
    return v


def plain_reference_objects():
    """(name, volume) of the objects whose plain runs are pinned."""
    rng = np.random.default_rng(1994)
    out = [
        ("torus-4-1.5", solid_torus(4, 1.5)),
        ("torus-6-2.5", solid_torus(6, 2.5, axis=0)),
        ("annulus-1", annulus_prism(8, 1, 3)),
        ("annulus-2", annulus_prism(10, 2, 4)),
        ("linked", linked_rings(7, 1, a=4)),
        ("eight", figure_eight()),
        ("hollow", hollow_ball()),
        ("contacts", contacts()),
        ("contacts-2d", contacts(2)),
        ("annulus-2d", planar_annulus()),
        ("ring-2d", planar_disc_ring()),
        ("eight-2d", planar_figure_eight()),
    ]
    for i in range(6):
        out.append((f"boxes-{i}", union_of_boxes(rng)))
    for i in range(6):
        out.append((f"boxes-2d-{i}", union_of_boxes(rng, size=14, count=5, ndim=2)))
    for i in range(4):
        out.append((f"noise-{i}", rng.random((6, 7, 5)) < 0.55))
        out.append((f"noise-2d-{i}", rng.random((10, 9)) < 0.55))
    return out


def state_digest(obj) -> str:
    """A digest of one state: shape, offset, parity and voxels."""
    import hashlib

    h = hashlib.sha1()
    h.update(repr((obj.volume.shape, tuple(obj.offset), obj.parity)).encode())
    h.update(np.packbits(obj.volume).tobytes())
    return h.hexdigest()[:16]


def plain_runs(method: str = "numpy"):
    """The plain runs of :func:`plain_reference_objects` at both
    connectivities, stepped by ``method`` (``numpy``: the reference)."""
    from isoflow import DigitalObject
    from isoflow.flow.run import run_flow

    runs = {}
    for name, v in plain_reference_objects():
        for conn in (6, 26):
            r = run_flow(DigitalObject(v), connectivity=conn, method=method)
            runs[f"{name}@{conn}"] = {
                "states": [state_digest(s) for s in r.states],
                "stop_reason": r.stop_reason,
                "changes": [[c["step"], c["before"], c["after"], c["where"]] for c in r.topology_changes],
                "limit": r.limit,
            }
    return runs


if __name__ == "__main__":
    import json
    from pathlib import Path

    path = Path(__file__).with_name("plain_reference.json")
    runs = plain_runs()
    lines = [f"{json.dumps(k)}: {json.dumps(runs[k], sort_keys=True)}" for k in sorted(runs)]
    path.write_text("{\n" + ",\n".join(lines) + "\n}\n")
    print(f"wrote {path}")
