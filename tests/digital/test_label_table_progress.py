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
