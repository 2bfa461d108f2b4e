"""The graph of pieces from the vertex pass' pairs
(:func:`isoflow.scale.piece_graph.entries_graph`), built from pairs held
in several blocks and on several threads, against the graph a plain loop
over the pairs in order builds."""

import numpy as np
import pytest

from isoflow.scale.compiled import have_numba, using

pytestmark = pytest.mark.skipif(not have_numba(), reason="numba not installed")

NONE = 4


def random_pairs(rng, n, count):
    """``count`` pairs of pieces 0 .. n - 1 (the smaller high), with kinds
    1 .. NONE and packed sheets and quarters each way, some with none."""
    a = rng.integers(0, n, count)
    b = (a + rng.integers(1, n, count)) % n
    keys = (np.minimum(a, b).astype(np.uint64) << np.uint64(32)) | np.maximum(a, b).astype(np.uint64)
    kind = rng.integers(1, NONE + 1, count).astype(np.uint8)
    sheets = rng.integers(0, 3, (count, 2)).astype(np.uint64)
    sums = sheets | (rng.integers(0, 9, (count, 2)).astype(np.uint64) << np.uint64(32))
    return keys, kind, sums


def plain_graph(keys, kind, sums, n):
    """Each piece's edges in the order of the pairs: a plain loop."""
    edges = [[] for _ in range(n)]
    for key, how, (pq, qp) in zip(keys.tolist(), kind.tolist(), sums.tolist()):
        sheets_pq, sheets_qp = pq & 0xFFFFFFFF, qp & 0xFFFFFFFF
        if how >= NONE and sheets_pq == 0 and sheets_qp == 0:
            continue
        p, q = key >> 32, key & 0xFFFFFFFF
        edges[p].append((q, how, sheets_pq, pq >> 32 if sheets_pq else 0))
        edges[q].append((p, how, sheets_qp, qp >> 32 if sheets_qp else 0))
    return edges


def as_edges(graph, n):
    start, to, kind, sheets, quarters = (g.tolist() for g in graph)
    return [list(zip(to[start[p]:start[p + 1]], kind[start[p]:start[p + 1]], sheets[start[p]:start[p + 1]],
                     quarters[start[p]:start[p + 1]])) for p in range(n)]


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_pairs_in_blocks_on_threads_give_the_plain_graph(rng, threads, monkeypatch):
    from isoflow.scale import piece_graph

    monkeypatch.setattr(piece_graph, "PAIRS_PER_THREAD", 7)  # runs of a few pairs, cut across the blocks
    for _ in range(20):
        n = int(rng.integers(2, 40))
        keys, kind, sums = random_pairs(rng, n, int(rng.integers(0, 120)))
        cuts = np.sort(rng.integers(0, len(keys) + 1, int(rng.integers(0, 5))))
        blocks = [(k, c, s) for k, c, s in zip(np.split(keys, cuts), np.split(kind, cuts), np.split(sums, cuts))]
        with using(threads):
            graph = piece_graph.entries_graph(blocks, n, NONE)
            whole = piece_graph.pair_graph(keys, kind, sums, n, NONE)
        assert as_edges(graph, n) == plain_graph(keys, kind, sums, n)
        assert all(np.array_equal(a, b) for a, b in zip(graph, whole))



@pytest.mark.parametrize("threads", [1, 2])
def test_each_run_lets_a_block_go_as_soon_as_it_is_placed(rng, threads, monkeypatch):
    """The list of blocks is taken over (empty on return) and each run lets
    go of its part of a block once it has placed it: when a run places a
    block, the blocks that run placed before are gone already, and none
    is left at the end. The graph is the plain loop's."""
    import weakref

    from isoflow.scale import piece_graph

    monkeypatch.setattr(piece_graph, "PAIRS_PER_THREAD", 40)  # with 2 threads, runs of 5 blocks each
    n = 30
    keys, kind, sums = random_pairs(rng, n, 200)
    blocks = [(k.copy(), c.copy(), s.copy()) for k, c, s in
              zip(np.split(keys, 10), np.split(kind, 10), np.split(sums, 10))]
    refs = [weakref.ref(block[0]) for block in blocks]
    fill, seen = piece_graph._fill_pair_graph, []

    def watched(k, *args):
        placing = next(i for i, ref in enumerate(refs) if ref() is k.base)
        run = placing * threads // 10
        seen.append((placing, [refs[i]() is not None for i in range(10) if i * threads // 10 == run and i < placing]))
        return fill(k, *args)

    monkeypatch.setattr(piece_graph, "_fill_pair_graph", watched)
    with using(threads):
        graph = piece_graph.entries_graph(blocks, n, NONE)
    assert blocks == [] and not any(ref() is not None for ref in refs)
    assert sorted(i for i, _ in seen) == list(range(10))
    assert not any(any(before) for _, before in seen), seen
    assert as_edges(graph, n) == plain_graph(keys, kind, sums, n)
