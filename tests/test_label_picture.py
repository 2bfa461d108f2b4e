"""``isoflow info LABELS --labels --png``: a picture of the label table,
its panels' numbers against the table's columns and the image itself, the
PNG read back by Pillow, and --force as every output takes it."""

import json
import subprocess
import sys
from collections import Counter

import numpy as np
import pytest
from scipy import ndimage
from test_input_errors import fails  # one line on stderr, exit 2

from isoflow import label_table
from isoflow.cli import main
from isoflow.mesh import label_picture
from isoflow.mesh.label_picture import ball_boundary, label_panels, render_label_table

Image = pytest.importorskip("PIL.Image")


@pytest.fixture
def cells(rng):
    """Labels 1-6 of random voxels (many components each), two balls (7, 8),
    a ring with a tunnel (9), and label 10 as two cubes meeting at an edge:
    two components at 6-connectivity, one at 26."""
    image = rng.choice([0, 1, 2, 3, 4, 5, 6], size=(14, 12, 10), p=[0.4, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1])
    image = image.astype(np.uint16)
    image[0:3, 0:3, 0:3] = 7
    image[10:14, 8:12, 0:4] = 8
    image[4:9, 4:9, 0:2] = 9
    image[6, 6, 0:2] = 0
    image[:, :, 6:10] = 0
    image[2:4, 2:4, 6:8] = 10
    image[4:6, 4:6, 6:8] = 10
    return image


def betti_counts(table) -> Counter:
    return Counter(zip(table["b0"].tolist(), table["b1"].tolist(), table["b2"].tolist()))


def components(image, label, conn):
    structure = ndimage.generate_binary_structure(3, {6: 1, 18: 2, 26: 3}[conn])
    return ndimage.label(image == label, structure)[1]


@pytest.mark.parametrize("conn", [6, 26])
def test_the_panels_count_what_the_table_and_the_image_hold(cells, conn):
    pitch = np.array([0.5, 2.0, 1.5])
    table = label_table(cells, conn, pitch=pitch)
    panels = label_panels(table, bars=3)
    # the bars: the three most common patterns and the rest, every row once
    counts = betti_counts(table)
    assert sum(panels.counts) + panels.other == len(table["label"]) == 10
    assert panels.other_patterns == len(counts) - 3
    assert [counts[p] for p in panels.patterns] == panels.counts
    assert panels.counts == sorted(counts.values(), reverse=True)[:3]
    # every row measured; the volumes are the voxels counted by NumPy times the voxel's volume, in the rows' order
    assert panels.measured.all()
    voxels = np.bincount(cells.ravel())
    assert panels.size.tolist() == pytest.approx((voxels[table["label"]] * pitch.prod()).tolist())
    faces = [sum(np.count_nonzero(np.diff(np.pad(cells == v, 1).astype(np.int8), axis=d)) * np.prod(np.delete(pitch, d))
                 for d in range(3)) for v in table["label"].tolist()]
    assert panels.boundary.tolist() == pytest.approx(faces)
    # the balls: one component (scipy's count at this connectivity), no tunnel, no cavity; the cubes 7 and 8
    # are, and so is label 10 at 26-connectivity
    balls = [v for v, b1, b2 in zip(table["label"].tolist(), table["b1"].tolist(), table["b2"].tolist())
             if components(cells, v, conn) == 1 and b1 == b2 == 0]
    assert balls == ([7, 8] if conn == 6 else [7, 8, 10])
    assert table["label"][panels.measured][panels.ball].tolist() == balls
    # label 10 is two cubes meeting at an edge: two components at 6, one at 26, as scipy counts them
    row = table["label"].tolist().index(10)
    assert table["b0"][row] == components(cells, 10, conn) == (2 if conn == 6 else 1)
    # no body of a volume has less surface than the ball of that volume (the isoperimetric inequality)
    assert (panels.boundary >= ball_boundary(panels.size)).all()


def test_the_picture_is_a_png_pillow_reads_with_something_drawn(tmp_path, cells):
    out = render_label_table(label_table(cells, 26), tmp_path / "cells.png", name="cells.npy", connectivity=26,
                             unit="mm")
    with Image.open(out) as im:
        assert im.format == "PNG"
        width, height = im.size
        pixels = np.asarray(im.convert("RGB"))
    assert width > 2 * height > 400  # three panels side by side
    inked = np.any(pixels < 200, axis=2)
    assert 0.02 < inked.mean() < 0.6  # not blank, not a block of colour
    assert len(np.unique(pixels.reshape(-1, 3), axis=0)) > 20


def test_measures_past_float64_are_left_out_with_a_note(tmp_path, cells):
    """A voxel of 1e150 has a volume of 1e450, past float64's largest
    number: the topology is drawn, the measured panels leave every row out."""
    table = label_table(cells, pitch=1e150)
    assert np.isinf(table["volume"]).all()
    panels = label_panels(table)
    assert panels.left_out == len(table["label"]) and len(panels.size) == 0
    assert sum(panels.counts) + panels.other == len(table["label"])
    with Image.open(render_label_table(table, tmp_path / "far.png")) as im:
        assert im.size[0] > im.size[1]


def test_a_2d_table_draws_area_and_perimeter(tmp_path):
    cells = np.zeros((12, 12), np.int32)
    cells[1:4, 1:4] = 1  # a disc
    cells[5:10, 5:10] = 2
    cells[7, 7] = 0  # an annulus
    table = label_table(cells, pitch=0.5)
    panels = label_panels(table)
    assert panels.dimension == 2 and sorted(panels.patterns) == [(1, 0), (1, 1)]
    assert panels.size.tolist() == [9 * 0.25, 24 * 0.25] and panels.ball.tolist() == [True, False]
    # the disc's perimeter, 2 pi r, from its area pi r^2
    assert ball_boundary(np.array([np.pi * 4.0]), 2)[0] == pytest.approx(2 * np.pi * 2.0)
    render_label_table(table, tmp_path / "cells.png")
    assert (tmp_path / "cells.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def isoflow(*args, cwd):
    return subprocess.run([sys.executable, "-m", "isoflow", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_png_from_the_shell_needs_force_to_replace_and_labels_to_draw(tmp_path, cells):
    np.save(tmp_path / "seg.npy", cells)
    done = isoflow("info", "seg.npy", "--labels", "--connectivity", "26", "--png", "seg.png", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "seg.png: picture of 10 labels (Betti numbers, volume, surface area)"
    first = (tmp_path / "seg.png").read_bytes()
    again = isoflow("info", "seg.npy", "--labels", "--png", "seg.png", cwd=tmp_path)
    assert again.returncode == 2 and again.stderr.strip().splitlines() == [
        "isoflow info: error: seg.png: exists; pass --force to overwrite"]
    assert (tmp_path / "seg.png").read_bytes() == first
    forced = isoflow("info", "seg.npy", "--labels", "--png", "seg.png", "--force", cwd=tmp_path)
    assert forced.returncode == 0, forced.stderr
    replaced = (tmp_path / "seg.png").read_bytes()
    assert replaced[:8] == b"\x89PNG\r\n\x1a\n" and replaced != first  # 6-connectivity: label 10 split in two
    alone = isoflow("info", "seg.npy", "--png", "one.png", cwd=tmp_path)
    assert alone.returncode == 2 and len(alone.stderr.strip().splitlines()) == 1
    assert "--png draws the table of --labels" in alone.stderr and not (tmp_path / "one.png").exists()
    assert sorted(f.name for f in tmp_path.iterdir()) == ["seg.npy", "seg.png"]  # no temporary left


def test_a_choice_of_labels_from_a_zarr_store_draws_those_rows(tmp_path, capsys, monkeypatch, cells):
    pytest.importorskip("zarr")
    from test_formats_cli import ome_group

    ome_group(tmp_path / "seg.zarr", [{"type": "scale", "scale": [2.0, 0.5, 1.0]}], data=cells)
    drawn = {}

    def keep(table, path, **kw):
        drawn.update(table=table, **kw)
        return render_label_table(table, path, **kw)

    monkeypatch.setattr(label_picture, "render_label_table", keep)
    assert main(["info", str(tmp_path / "seg.zarr"), "--labels", "9,2,7-8", "--png", str(tmp_path / "c.png"),
                 "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["labels"]
    assert [r["label"] for r in rows] == drawn["table"]["label"].tolist() == [9, 2, 7, 8]
    assert drawn["name"] == "seg.zarr --labels 9,2,7-8" and drawn["connectivity"] == 6
    # the store's scale is z, y, x: the voxel is 1 x 0.5 x 2 along x, y, z
    panels = label_panels(drawn["table"])
    assert panels.size.tolist() == [np.count_nonzero(cells == v) * 1.0 for v in (9, 2, 7, 8)]
    assert Counter(dict(zip(panels.patterns, panels.counts))) == betti_counts(drawn["table"])
    with Image.open(tmp_path / "c.png") as im:
        assert im.format == "PNG"


def test_a_failed_picture_leaves_the_csv_as_it_was(tmp_path, capsys, monkeypatch, cells):
    np.save(tmp_path / "seg.npy", cells)
    (tmp_path / "t.csv").write_text("old\n")
    (tmp_path / "t.png").write_bytes(b"old")

    def full(fig, path):
        from isoflow.errors import IsoflowError

        label_picture.pyplot().close(fig)
        raise IsoflowError(f"{path}: could not write (No space left on device)")

    monkeypatch.setattr(label_picture, "save_figure", full)
    fails(capsys, "info", tmp_path / "seg.npy", "--labels", "--csv", tmp_path / "t.csv", "--png", tmp_path / "t.png",
          "--force", words=("t.png", "No space left", "nothing was replaced"))
    assert (tmp_path / "t.csv").read_text() == "old\n" and (tmp_path / "t.png").read_bytes() == b"old"
    assert sorted(f.name for f in tmp_path.iterdir()) == ["seg.npy", "t.csv", "t.png"]


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_an_interrupted_picture_names_the_csv_and_the_picture(tmp_path, capsys, monkeypatch, cells):
    """Ctrl-C while the picture of ``--csv`` and ``--png`` is drawn: exit
    130, both files as they were and no temporary, and the line names
    both (it named the picture alone: "t.png: nothing was replaced")."""
    import os
    import signal

    np.save(tmp_path / "seg.npy", cells)
    (tmp_path / "t.csv").write_text("old\n")
    (tmp_path / "t.png").write_bytes(b"old")
    draw = label_picture.render_label_table

    def interrupted(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        return draw(*args, **kwargs)

    monkeypatch.setattr(label_picture, "render_label_table", interrupted)
    assert main(["info", str(tmp_path / "seg.npy"), "--labels", "--csv", str(tmp_path / "t.csv"), "--png",
                 str(tmp_path / "t.png"), "--force"]) == 130
    assert capsys.readouterr().err.strip().splitlines() == [
        f"isoflow: interrupted: {tmp_path / 't.csv'} and {tmp_path / 't.png'}: nothing was replaced"]
    assert (tmp_path / "t.csv").read_text() == "old\n" and (tmp_path / "t.png").read_bytes() == b"old"
    assert sorted(f.name for f in tmp_path.iterdir()) == ["seg.npy", "t.csv", "t.png"]


def drawn_figure_problems(fig) -> list[str]:
    """What a reader could not read in a drawn figure: tick labels of one
    axis that run into each other, scatter points under the legend, a count
    axis with fractions."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    problems = []
    for i, ax in enumerate(fig.axes):
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels(which="both")
                     if t.get_visible() and t.get_text()]
            if any(a.overlaps(b) for k, a in enumerate(boxes) for b in boxes[k + 1:]):
                problems.append(f"panel {i}: {name} tick labels overlap")
        legend = ax.get_legend()
        for points in ax.collections if legend is not None else ():
            box = legend.get_window_extent(renderer)
            at = ax.transData.transform(points.get_offsets())
            if ((at[:, 0] >= box.x0) & (at[:, 0] <= box.x1) & (at[:, 1] >= box.y0) & (at[:, 1] <= box.y1)).any():
                problems.append(f"panel {i}: the legend hides points")
    for i, axis in ((0, fig.axes[0].xaxis), (1, fig.axes[1].yaxis)):  # the bars' and the histogram's counts
        lo, hi = sorted(axis.get_view_interval())
        if any(not float(v).is_integer() for v in axis.get_majorticklocs() if lo <= v <= hi):
            problems.append(f"panel {i}: a count axis with fractions")
    return problems


@pytest.mark.parametrize("pick", [None, range(3, 25)])
def test_a_picture_of_cells_of_like_size_is_readable(tmp_path, monkeypatch, pick):
    """A few cells of like size (or a few labels asked for out of many)
    span less than a decade of area: matplotlib's log-axis labels
    (1.52 x 10^-1 at every tick) ran into each other, the legend in the
    upper left hid the labels of much perimeter, and the count axes had
    fractions of a label."""
    rng = np.random.default_rng(4)
    cells = np.zeros((40, 40), np.int32)
    for k in range(30):  # cells of 12 to 20 pixels, some with a hole or in two pieces
        y, x = divmod(k, 6)
        h, w = int(rng.integers(3, 5)), int(rng.integers(4, 6))
        cells[y * 8:y * 8 + h, x * 6:x * 6 + w] = k + 1
        if k % 4 == 0:
            cells[y * 8 + 1, x * 6 + 1] = 0
        if k % 5 == 0:
            cells[y * 8 + h + 1, x * 6] = k + 1
    table = label_table(cells, pitch=0.1, labels=pick)
    seen = []

    def check(fig, path):
        seen.extend(drawn_figure_problems(fig))
        return save_figure(fig, path)

    save_figure = label_picture.save_figure
    monkeypatch.setattr(label_picture, "save_figure", check)
    render_label_table(table, tmp_path / "cells.png", unit="µm")
    assert seen == []
