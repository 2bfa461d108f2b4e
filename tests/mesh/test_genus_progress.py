"""verify_genus reports the progress of its whole resolution ladder as one
count that only grows, each rung weighted by its grid's size."""

from pathlib import Path

from isoflow import verify_genus

TORUS = Path(__file__).resolve().parents[2] / "meshes" / "torus.obj"


def test_ladder_progress_is_one_growing_count():
    seen = []
    report = verify_genus(TORUS, [32, 16], progress=lambda done, total: seen.append((done, total)))
    assert [d["resolution"] for d in report["digital"]] == [16, 32]
    done = [d for d, _ in seen]
    assert {t for _, t in seen} == {1000}
    assert done == sorted(done) and done[-1] == 1000
    # the 16 rung ends at 16^3 / (16^3 + 32^3) = 1/9 of the ladder
    assert round(1000 / 9) in done
    assert len(seen) >= 4  # reports inside both rungs, not just at their ends
