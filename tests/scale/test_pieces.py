"""The pieces of a label image (every value's 6-connected components, the
value 0 too) are cc3d's components of each value, numbered in C order of
their first voxel, with their counts, boxes and coordinate sums."""

import numpy as np
import pytest

from isoflow.scale.compiled import have_numba

pytestmark = pytest.mark.skipif(not have_numba(), reason="numba not installed")


def test_pieces_are_each_values_face_components(rng):
    import cc3d

    from isoflow.scale.pieces import label_pieces

    for _ in range(40):
        shape = tuple(rng.integers(2, 12, 3))
        image = rng.integers(0, rng.integers(2, 5), shape).astype(np.int16) - 1  # -1 too
        found = label_pieces(image)
        ids = found["ids"]
        # C order of first voxels: the first voxel of piece p comes before that of p + 1
        first = np.unique(ids.ravel(), return_index=True)[1]
        assert (np.diff(first) > 0).all() and found["n"] == len(first)
        for value in np.unique(image):
            theirs = cc3d.connected_components((image == value).astype(np.uint8), connectivity=6)
            ours = np.where(image == value, ids, 0)
            # the same partition: a one-to-one map between the two numberings
            pairs = np.unique(np.stack([ours[image == value], theirs[image == value]]), axis=1)
            assert len(np.unique(pairs[0])) == len(np.unique(pairs[1])) == pairs.shape[1]
        for p in range(1, found["n"] + 1):
            where = np.argwhere(ids == p)
            assert found["counts"][p] == len(where)
            assert (found["lo"][p] == where.min(axis=0)).all() and (found["hi"][p] == where.max(axis=0)).all()
            assert (found["sums"][p] == where.sum(axis=0)).all()
            assert found["values"][p] == np.uint16(image[tuple(where[0])])


@pytest.mark.parametrize("nz", [1, 63, 64, 65, 200, 9000])
def test_pieces_of_long_rows_on_several_threads(rng, nz):
    """Rows around a word of 64 voxels and longer than a batch of rows, cut
    into runs of every length (single voxels too), in slabs on one to three
    threads: cc3d's components of each value, the same on every count of
    threads."""
    import cc3d

    from isoflow.scale.compiled import using
    from isoflow.scale.pieces import label_pieces

    shape = (7, 5, nz) if nz > 1 else (40, 9, 1)
    # runs of random lengths along z, shared by neighbouring rows often
    cuts = rng.random(shape) < rng.choice([0.02, 0.3, 0.9], size=shape[:2] + (1,))
    image = (np.cumsum(cuts, axis=2) % 3).astype(np.uint32)
    image[rng.random(shape) < 0.01] = 7
    found = [label_pieces(image)]
    for threads in (2, 3):
        with using(threads):
            found.append(label_pieces(image))
    for f in found:
        assert (f["ids"] == found[0]["ids"]).all() and f["n"] == found[0]["n"]
        assert (f["counts"] == found[0]["counts"]).all() and (f["sums"] == found[0]["sums"]).all()
        assert (f["lo"] == found[0]["lo"]).all() and (f["hi"] == found[0]["hi"]).all()
    ids = found[0]["ids"]
    for value in np.unique(image):
        theirs = cc3d.connected_components((image == value).astype(np.uint8), connectivity=6)
        pairs = np.unique(np.stack([ids[image == value], theirs[image == value]]), axis=1)
        assert len(np.unique(pairs[0])) == len(np.unique(pairs[1])) == pairs.shape[1]
    # the statistics are each piece's, from its voxels
    n = found[0]["n"] + 1
    assert (found[0]["counts"] == np.bincount(ids.ravel(), minlength=n)).all()
    coords = np.indices(shape).reshape(3, -1)
    for d in range(3):
        assert (found[0]["sums"][:, d] == np.bincount(ids.ravel(), coords[d], minlength=n)).all()
        lo, hi = np.full(n, np.iinfo(np.int64).max), np.full(n, -1)
        np.minimum.at(lo, ids.ravel(), coords[d])
        np.maximum.at(hi, ids.ravel(), coords[d])
        assert (found[0]["lo"][1:, d] == lo[1:]).all() and (found[0]["hi"][1:, d] == hi[1:]).all()


@pytest.mark.parametrize("nz", [64, 100])
def test_pieces_when_the_runs_outgrow_their_buffers_between_layers(rng, nz):
    """A slab whose runs fill their buffers after some of its layers (noise
    of a few values: a run every other voxel) stops there and goes on with
    larger buffers, its layers' run starts kept for the joins with the
    next layer: cc3d's components of each value, in one slab and in three."""
    import cc3d

    from isoflow.scale import pieces
    from isoflow.scale.compiled import using

    image = rng.integers(0, 3, (40, 30, nz)).astype(np.uint8)
    image[10:30, 5:25, 10:50] = 3  # one block across the layers where the buffers fill
    # the first buffers hold about two batches of rows, so that they fill once a batch of layers is done
    assert pieces.MARK_VOXELS // nz < 40 * 30 and 40 * 30 * nz // 16 < 2 * (pieces.MARK_VOXELS // nz) * nz
    for threads in (1, 3):
        with using(threads):
            found = pieces.label_pieces(image)
        ids = found["ids"]
        count = 0
        for value in np.unique(image):
            theirs, n = cc3d.connected_components((image == value).astype(np.uint8), connectivity=6,
                                                  return_N=True)
            pairs = np.unique(np.stack([ids[image == value], theirs[image == value]]), axis=1)
            assert len(np.unique(pairs[0])) == len(np.unique(pairs[1])) == pairs.shape[1] == n
            count += n
        assert found["n"] == count
        assert (found["counts"][1:] == np.bincount(ids.ravel())[1:]).all()


def test_a_growable_buffer_keeps_its_entries_moved_or_copied(rng):
    """A buffer grown, with no array of it held, keeps its entries and is
    zero beyond them; grown while an array of it is held (it cannot move
    its pages then), it copies them, and the array held still reads what it
    did; shrunk, it keeps what fits."""
    from isoflow.scale.memory import Growable

    values = rng.integers(-(2**31), 2**31, 300_000).astype(np.int32)
    buffer = Growable(300_000, np.int32)
    a = buffer.array()
    a[:] = values
    del a
    for size in (1_000_000, 5_000_000):
        buffer.resize(size, used=300_000)
        b = buffer.array()
        assert len(b) == size and (b[:300_000] == values).all() and not b[300_000:].any()
        del b
    held = buffer.array()
    buffer.resize(6_000_000, used=300_000)
    assert (held[:300_000] == values).all()
    b = buffer.array()
    assert len(b) == 6_000_000 and (b[:300_000] == values).all() and not b[300_000:].any()
    del b
    buffer.resize(1000, used=300_000)
    assert (buffer.array() == values[:1000]).all()


def test_contact_table_counts_each_pair_of_voxels_once():
    """Every pair of voxels of a 3x3x3 neighbourhood is in exactly one block
    of BLOCK_PAIRS, with the adjacency its offset says."""
    from isoflow.scale.pieces import BLOCK_PAIRS

    seen = {}
    for w in np.ndindex(3, 3, 3):  # vertices of a 2x2x2 cube of voxels, and around it
        for o1, o2, how in BLOCK_PAIRS:
            a = tuple(np.array(w) - 1 + [(o1 >> d) & 1 for d in range(3)])
            b = tuple(np.array(w) - 1 + [(o2 >> d) & 1 for d in range(3)])
            if all(0 <= c < 2 for c in a + b):
                key = tuple(sorted((a, b)))
                assert key not in seen
                seen[key] = how
    assert len(seen) == 28  # every pair of the 8 voxels
    assert all(how == int(np.abs(np.subtract(*k)).sum()) for k, how in seen.items())


def test_a_pair_table_drain_writes_out_keeps_and_empties_as_three_passes_did(rng, monkeypatch):
    """On random streams of pairs, each drain of a thread's pair table
    writes out exactly the pairs behind the sweep (one of the two pieces
    ends before the layer), keeps the others with their kind and sums, and
    leaves the old table (the next one) with every slot empty: what
    counting, draining and then clearing the spare in passes of their own
    gave, tables of several sizes, grown (asked to, or crowded by the
    pairs kept) and reused."""
    from isoflow.scale import pieces

    monkeypatch.setattr(pieces, "FIRST_SLOTS", 128)  # a drain leaves it at most 30 % full: room for a batch
    npieces, base = 400, 1
    top = rng.integers(0, 60, npieces).astype(np.int64)  # piece p ends in layer top[p - base]
    sink = pieces.PairSink(top, base, 1)
    rehashed, rehash = [], pieces._rehash
    monkeypatch.setattr(pieces, "_rehash", lambda old, new: rehashed.append(len(new)) or rehash(old, new))

    def done(key, below):
        p, q = key >> 32, key & 0xFFFFFFFF
        return (p != 0 and top[p - base] < below) or (q != 0 and top[q - base] < below)

    def merged(entries, into):
        for key, kind, a, b in entries:
            old = into.get(key, (pieces.NONE, 0, 0))
            into[key] = (min(old[0], kind), old[1] + a, old[2] + b)

    want_open, want_out, sizes = {}, {}, []
    for below in [*range(0, 61, 3), None]:
        if below is not None:  # a batch of pairs, repeated keys among them, through the near cache
            count = int(rng.integers(1, 41))
            p = rng.integers(0, npieces, count)
            q = np.minimum(p + rng.integers(1, 12, count), npieces)
            keys = (p.astype(np.uint64) << np.uint64(32)) | q.astype(np.uint64)
            kinds, a, b = rng.integers(1, 4, count), rng.integers(0, 9, count), rng.integers(0, 9, count)
            sink.near[:count] = np.stack([keys, kinds.astype(np.uint64), a.astype(np.uint64), b.astype(np.uint64)], 1)
            merged(zip(keys.tolist(), kinds.tolist(), a.tolist(), b.tolist()), want_open)
        keep = sink.drain(0, below, grow=below is not None and below % 9 == 0)
        sizes.append(len(sink.pairs))
        for key in [k for k in want_open if below is None or done(k, below)]:
            merged([(key, *want_open.pop(key))], want_out)
        held = sink.pairs[sink.pairs[:, 0] != pieces.EMPTY]
        assert keep == len(want_open) == len(held)
        assert {int(k): (int(c), int(s), int(t)) for k, c, s, t in held} == want_open
        out = {}
        merged(((int(k), int(c), int(s[0]), int(s[1])) for keys, kind, sums, n in sink.blocks
                for k, c, s in zip(keys[:n], kind[:n], sums[:n])), out)
        assert out == want_out
        spare = sink.spare
        assert (spare[:, 0] == pieces.EMPTY).all() and (spare[:, 1] == pieces.NONE).all() and not spare[:, 2:].any()
    # the table grew, asked to and because the pairs kept crowded it, and was used again at its size
    assert not want_open and len(want_out) > 100 and rehashed and len(set(sizes)) > 1 and len(sizes) > len(set(sizes))



@pytest.mark.parametrize("threads", [1, 2])
def test_the_features_let_each_windows_counts_go_once_added(rng, threads, monkeypatch):
    """The threads' counts of configurations, each over its window of
    pieces (windows that overlap), are added window by window: when a
    window is added, the counts of the windows before it are gone, and
    the list is empty at the end (the counts and the whole table of
    features are not held at once). The features are the counts times
    the groups' rows, summed over the windows (NumPy's matrix product)."""
    import weakref

    from isoflow.scale import pieces
    from isoflow.scale.compiled import using

    windows, npieces = [(0, 50), (40, 100), (100, 100), (95, 160)], 160
    rows = rng.integers(-3, 4, (7, 5))
    counts = [rng.integers(0, 3, (hi - lo, 7)).astype(np.uint32) for lo, hi in windows]
    want = np.zeros((npieces, 5), np.int64)
    for (lo, hi), part in zip(windows, counts):
        want[lo:hi] += part.astype(np.int64) @ rows
    del part  # the list holds the counts alone
    refs = [weakref.ref(part) for part in counts]
    add, gone = pieces._add_features, []

    def watched(part, *args):
        w = next(i for i, ref in enumerate(refs) if ref() is part.base)
        gone.append([refs[i]() is None for i in range(w)])
        return add(part, *args)

    monkeypatch.setattr(pieces, "_add_features", watched)
    with using(threads):
        got = pieces.features_of(counts, windows, npieces, rows)
    assert np.array_equal(got, want)
    assert counts == [] and all(ref() is None for ref in refs)
    assert len(gone) >= 3 and all(all(before) for before in gone), gone
