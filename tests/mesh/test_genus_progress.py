"""verify_genus reports the progress of its whole resolution ladder as one
count that only grows, each resolution weighted by its grid's size."""

from pathlib import Path

from isoflow import verify_genus

TORUS = Path(__file__).resolve().parents[2] / "meshes" / "torus.obj"


def test_ladder_progress_is_one_growing_count():
    seen = []
    report = verify_genus(TORUS, [32, 16], progress=lambda done, total: seen.append((done, total)))
    ladder = [d["resolution"] for d in report["digital"]]
    assert ladder[:2] == [16, 32]
    done = [d for d, _ in seen]
    assert done == sorted(done)
    # the last report is the whole ladder done, each rung weighing its resolution^3
    assert seen[-1] == (sum(r**3 for r in ladder),) * 2
    assert 16**3 in done  # the 16 rung ends at its share of the count
    # while the first rung runs, the total already holds both resolutions asked
    assert seen[0][1] == 16**3 + 32**3
