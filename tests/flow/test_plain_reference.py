"""Plain (unguarded) runs stay state for state what they were before topology
control was reworked (issue 10).

``plain_reference.json`` was written by ``python tests/flow/shapes.py`` from
the code of commit 0b245b6, before any change to the guard: per object and
connectivity, a digest of every state (shape, offset, parity, voxels), the
stop reason, the limit and the topology changes with their place. The objects
are seeded (tori, annulus prisms, linked rings, a figure eight, a hollow
ball, edge and vertex contacts, random unions of boxes and noise, in 3D and
2D). Both ways of stepping (``method="numpy"`` and ``"compiled"``, on bit
rows) must give them. The last, empty state of each run was digested again
when an empty object's offset became zeros (it kept the dual lattice's
offset of the step that emptied it); every other state is 0b245b6's. The
places of the topology changes were written again when a place became the
voxels around every stuck vertex and the parts vanishing or filling whole
there, and again when it took in the cavities closed off and grew until the
step split cleanly at its edge (each new box holds the old one;
test_change_place.py checks them).
"""

import json
from pathlib import Path

import pytest
from shapes import plain_runs

REFERENCE = json.loads(Path(__file__).with_name("plain_reference.json").read_text())


@pytest.fixture(scope="module", params=["numpy", "compiled"])
def now(request):
    """The runs of today's NumPy flow and of the flow on bit rows."""
    return plain_runs(request.param)


def test_same_objects(now):
    assert sorted(now) == sorted(REFERENCE) and len(REFERENCE) == 64


@pytest.mark.parametrize("key", sorted(REFERENCE))
def test_plain_run_is_unchanged(now, key):
    assert now[key] == REFERENCE[key]
