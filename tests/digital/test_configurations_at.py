"""``configurations_at`` reads the configuration of some lattice vertices
only; it must equal the whole lattice's (``configurations``) there, and the
definition itself: bit ``d_0 + 2 d_1 + 4 d_2 + 8 d_3`` set where the cell
at vertex ``w - 1 + d`` is in the object, cells outside the array out."""

import numpy as np
import pytest
from conftest import random_volume

from isoflow.digital.configurations import configurations, configurations_at


def by_definition(volume: np.ndarray, w: np.ndarray) -> int:
    code = 0
    for bit in range(2 ** volume.ndim):
        cell = w - 1 + np.array([(bit >> i) & 1 for i in range(volume.ndim)])
        if np.all(cell >= 0) and np.all(cell < volume.shape) and volume[tuple(cell)]:
            code |= 1 << bit
    return code


@pytest.mark.parametrize("ndim", [2, 3, 4])
def test_configurations_at_every_vertex_is_the_whole_lattices(ndim):
    # random volumes: faces, edges and vertices in contact, and the border
    rng = np.random.default_rng(2013 + ndim)
    for _ in range(20):
        volume = random_volume(rng, 5 if ndim == 4 else 7, ndim)
        every = np.argwhere(np.ones(tuple(n + 1 for n in volume.shape), bool))
        got = configurations_at(volume, every)
        assert got.tolist() == configurations(volume)[tuple(every.T)].tolist()
        some = every[rng.choice(len(every), min(12, len(every)), replace=False)]
        assert configurations_at(volume, some).tolist() == [by_definition(volume, w) for w in some]
