"""A label table in memory says its progress and stops when asked: the
passes count their work where they do it, and look at the stop flag
there (isoflow.scale.ticks), so a long table (noise of many labels: tens
of seconds) is not silent, and Ctrl-C ends it within a step, not at the
end of the pass it lands in."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import Terminal, stderr_of

import isoflow
from isoflow.digital.label_table import STAGES
from isoflow.scale import cancel


def noise(n: int = 40, labels: int = 60, seed: int = 5) -> np.ndarray:
    """Labels touching each other by faces, edges and vertices, every one
    in many pieces (a walk per component), with background among them."""
    return np.random.default_rng(seed).integers(0, labels, (n, n + 1, n + 2)).astype(np.uint32)


def said_while(image: np.ndarray, **kwargs) -> tuple[dict, list[tuple[int, int]]]:
    said: list[tuple[int, int]] = []
    table = isoflow.label_table(image, progress=lambda done, total: said.append((done, total)), **kwargs)
    return table, said


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("method", ["compiled", "numpy"])
def test_the_progress_rises_to_its_end_and_the_table_is_the_same(method, threads):
    image = noise()
    for conn in (6, 26):
        table, said = said_while(image, connectivity=conn, method=method, threads=threads)
        done = [d for d, _ in said]
        assert len({t for _, t in said}) == 1 and said[-1] == (said[0][1], said[0][1])  # one total, reached
        assert done == sorted(done) and len(set(done)) == len(done)  # rising, nothing said twice
        plain = isoflow.label_table(image, conn, method=method, threads=threads)
        assert plain.keys() == table.keys()
        for key in plain:
            assert np.array_equal(plain[key], table[key]), key
        # every row is its label's own analyze (the table is not changed by being watched)
        for row in (0, len(table["label"]) // 2, -1):
            report = isoflow.analyze(image == table["label"][row], conn)
            assert table["euler_characteristic"][row] == report["euler_characteristic"]
            assert table["b1"][row] == report["betti"][1]
    # several stages said on the way, not only the end (the compiled pass: pieces, vertices, graph, walks)
    assert len(said) >= (4 if method == "compiled" else 3)


def test_a_stop_asked_before_ends_the_table_at_its_first_step():
    image = noise()
    cancel.request_stop()
    try:
        for threads in (1, 2):
            with pytest.raises(KeyboardInterrupt):
                isoflow.label_table(image, method="compiled", threads=threads)
    finally:
        cancel.clear_stop()
    assert len(isoflow.label_table(image, method="compiled")["label"]) == 59  # and it runs again once cleared


@pytest.mark.parametrize("threads", [1, 2])
def test_a_stop_asked_during_the_vertex_pass_ends_it_there(threads):
    """A stop asked (as the command line's signal handler asks it) once the
    vertex pass has begun: the table ends without reaching the walks."""
    image = noise(64, 200)
    said: list[int] = []
    shares = STAGES

    def progress(done: int, total: int) -> None:
        said.append(done)
        if done >= shares["pieces"]:
            cancel.request_stop()

    try:
        with pytest.raises(KeyboardInterrupt):
            isoflow.label_table(image, method="compiled", threads=threads, progress=progress)
    finally:
        cancel.clear_stop()
    assert max(said) < shares["pieces"] + shares["vertices"]  # no graph, no walks


def test_info_labels_shows_the_tables_bar_on_a_terminal(tmp_path, monkeypatch):
    np.save(tmp_path / "noise.npy", noise())
    shown = stderr_of(monkeypatch, Terminal(), ["info", tmp_path / "noise.npy", "--labels"])
    assert "label table:" in shown and "%|" in shown
    quiet = stderr_of(monkeypatch, Terminal(), ["info", tmp_path / "noise.npy", "--labels", "--quiet"])
    assert "label table" not in quiet


@pytest.mark.parametrize("threads", [1, 2])
def test_steps_of_one_layer_and_a_table_that_fills_within_them_give_each_labels_own_report(monkeypatch, threads):
    """The passes are cut into steps (a count and a look at the stop each):
    cut at every layer, and the vertex pass' pair table draining within a
    step, the table is still every label's own ``analyze``."""
    from isoflow.scale import pieces, ticks

    image = noise(18, 9, seed=11)
    image[4:12, 4:12, 4:12] = 3  # a large label enclosing others' pieces
    image[6:10, 6:10, 6:10] = 0
    image[7, 7, 7] = 5
    monkeypatch.setattr(ticks, "STEP_VOXELS", 1)
    monkeypatch.setattr(pieces, "FIRST_SLOTS", 64)
    for conn in (6, 26):
        table, said = said_while(image, connectivity=conn, method="compiled", threads=threads)
        # on one thread, said at every count that moves the bar: each layer of the vertex pass (on two, the
        # waiting thread says the sum every tenth of a second)
        assert threads == 2 or len(said) > image.shape[0]
        for row, label in enumerate(table["label"].tolist()):
            report = isoflow.analyze(image == label, conn)
            assert table["euler_characteristic"][row] == report["euler_characteristic"], (conn, label)
            assert [table[f"b{d}"][row] for d in range(3)] == list(report["betti"]), (conn, label)
            assert table["genera"][row] == tuple(s["genus"] for s in report["surfaces"]), (conn, label)


def test_a_2d_table_says_its_end():
    cells = noise(30, 20)[0]
    table, said = said_while(cells)
    assert said and said[-1][0] == said[-1][1] and len({t for _, t in said}) == 1
    assert table["euler_characteristic"].tolist() == [isoflow.analyze(cells == v, 4)["euler_characteristic"]
                                                      for v in table["label"].tolist()]


def test_an_image_made_in_slabs_says_one_rising_total(monkeypatch):
    """An image of more voxels than the pieces are numbered in is made in
    slabs, each said by the slabs' own count: still one bar, one total."""
    from isoflow.scale import pieces

    monkeypatch.setattr(pieces, "MAX_PIECE_VOXELS", 600)  # slabs of a few layers
    image = noise(12, 7)
    table, said = said_while(image, method="compiled")
    done = [d for d, _ in said]
    assert len({t for _, t in said}) == 1 and done == sorted(done) and said[-1][0] == said[-1][1]
    assert len(said) > 3
    assert table["euler_characteristic"].tolist() == [isoflow.analyze(image == v, 6)["euler_characteristic"]
                                                      for v in table["label"].tolist()]
