"""PNG input (2D masks and label images, as Cellpose and PASCAL VOC save
them): every mode read as the pixels' labels, row j and column i as pixel
(i, j); colours, animations and damaged files refused in one line."""

import json

import numpy as np
import pytest
from in_process import isoflow_here

from isoflow import analyze, label_table

Image = pytest.importorskip("PIL.Image")


def run(*args, cwd):
    """The command's exit status, stdout and stderr in ``cwd``, run in this
    process (what it reports is tested, not the shell: tests/in_process.py)."""
    return isoflow_here(*args, cwd=cwd)


def one_line_exit_2(proc, words):
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert words in proc.stderr, proc.stderr


@pytest.fixture
def cells():
    """Cells numbered past 255 (16 bits), touching by edges and corners, with holes."""
    rng = np.random.default_rng(11)
    image = rng.integers(0, 4, (21, 34)).astype(np.uint16) * 300
    image[5:15, 5:25] = 7
    image[8:11, 9:12] = 0
    return image


def test_a_16_bit_label_png_is_its_cells(tmp_path, cells):
    Image.fromarray(cells).save(tmp_path / "cp_masks.png")
    proc = run("info", "cp_masks.png", "--labels", "--json", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["shape"] == [34, 21] and out["dtype"] == "uint16"  # (x, y): columns, then rows
    table = label_table(cells.T)
    assert [row["label"] for row in out["labels"]] == table["label"].tolist() == [7, 300, 600, 900]
    for r, row in enumerate(out["labels"]):
        assert [row[k] for k in ("voxels", "euler_characteristic", "b0", "b1")] == [
            int(table[k][r]) for k in ("voxels", "euler_characteristic", "b0", "b1")]
    assert out["labels"][0]["b1"] == 1  # label 7's hole


def test_palette_indices_grey_as_colour_and_masks(tmp_path, cells):
    small = (cells // 300).astype(np.uint8)  # indices 0 .. 3
    palette = Image.fromarray(small, mode="P")
    palette.putpalette([0, 0, 0, 200, 10, 10, 10, 200, 10, 10, 10, 200] + [0] * 744)  # colours unlike the indices
    palette.save(tmp_path / "voc.png")
    Image.fromarray(np.stack([small] * 3 + [np.full_like(small, 255)], axis=-1), mode="RGBA").save(tmp_path / "g.png")
    mask = cells == 7
    Image.fromarray(mask).save(tmp_path / "bilevel.png")
    Image.fromarray(mask.astype(np.uint8)).save(tmp_path / "mask.png")
    want = label_table(small.T)
    for name in ("voc.png", "g.png"):
        proc = run("info", name, "--labels", "--json", cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        rows = json.loads(proc.stdout)["labels"]
        assert [r["label"] for r in rows] == want["label"].tolist() == [1, 2, 3], name
        assert [r["voxels"] for r in rows] == want["voxels"].tolist(), name
    report = analyze(mask.T)
    for name in ("bilevel.png", "mask.png"):
        proc = run("info", name, "--json", cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        got = json.loads(proc.stdout)
        assert [got["voxels"], got["betti"], got["n"]] == [report["voxels"], report["betti"], report["n"]], name
    text = run("info", "mask.png", cwd=tmp_path).stdout.splitlines()
    assert text[0] == f"mask.png: 2D, shape 34x21, {report['voxels']} pixels, 4-connectivity"
    b0, b1 = report["betti"]
    assert text[1].startswith("  pixel size             1 x 1, origin [0, 0]"), text[1]  # PNG keeps no size
    betti = next(line for line in text if line.startswith("  Betti numbers"))
    assert betti == f"  Betti numbers          {b0} component{'s' * (b0 != 1)}, {b1} hole{'s' * (b1 != 1)}"


def test_colours_animations_damaged_files_and_writing_are_refused(tmp_path, cells):
    small = (cells // 300).astype(np.uint8)
    Image.fromarray(np.stack([small, 2 * small, small], axis=-1)).save(tmp_path / "colour.png")
    frames = [Image.fromarray(small), Image.fromarray(small[::-1].copy())]
    frames[0].save(tmp_path / "anim.png", save_all=True, append_images=frames[1:])
    (tmp_path / "bad.png").write_bytes(b"\x89PNG\r\n\x1a\nnot a png")
    one_line_exit_2(run("info", "colour.png", "--labels", cwd=tmp_path), "colour.png: holds colours, not labels")
    one_line_exit_2(run("info", "anim.png", cwd=tmp_path), "anim.png: an animated PNG of 2 frames")
    one_line_exit_2(run("info", "bad.png", cwd=tmp_path), "bad.png: not a readable PNG file")
    from isoflow import data

    one_line_exit_2(run("voxelize", data.bob(), "--resolution", "8", "-o", "m.png", cwd=tmp_path),
                    "m.png: PNG holds 2D images, this volume is 3D")  # refused before the voxelisation
    assert not (tmp_path / "m.png").exists()


def sixteen_bit_png(path, channels, colour_type):
    """A PNG of 16 bits a channel, written by hand: Pillow writes none in colour."""
    import struct
    import zlib

    height, width = channels.shape[:2]
    rows = b"".join(b"\x00" + channels[j].astype(">u2").tobytes() for j in range(height))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 16, colour_type, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def test_16_bit_colour_is_refused_not_cut_to_8_bits(tmp_path, cells):
    # Pillow keeps the high byte of each 16-bit colour channel: cells 300, 600
    # and 900 would read as 1, 2 and 3 and cell 7 as background
    sixteen_bit_png(tmp_path / "rgb.png", np.stack([cells] * 3, axis=-1), 2)
    sixteen_bit_png(tmp_path / "la.png", np.stack([cells, np.full_like(cells, 65535)], axis=-1), 4)
    for name in ("rgb.png", "la.png"):
        one_line_exit_2(run("info", name, "--labels", cwd=tmp_path), f"{name}: a PNG of 16-bit colour")
    sixteen_bit_png(tmp_path / "grey.png", cells, 0)  # 16-bit grey is read whole
    proc = run("info", "grey.png", "--labels", "--json", cwd=tmp_path)
    assert [row["label"] for row in json.loads(proc.stdout)["labels"]] == [7, 300, 600, 900], proc.stderr


@pytest.mark.parametrize("dtype", [">u2", ">i2"])
def test_big_endian_labels_are_written_as_their_values(tmp_path, cells, dtype):
    """Labels in a big-endian type (as a NRRD or HDF5 file gives them) are
    the same labels: Pillow reads the file back as the values given."""
    from isoflow import write_labels

    labels = cells.T.astype(dtype)  # (x, y): row j, column i of the file is pixel (i, j)
    path = write_labels(labels, tmp_path / "cells.png")
    with Image.open(path) as image:
        assert image.mode == "I;16"
        assert np.array_equal(np.asarray(image), cells)
