"""Grey with an alpha channel (PNG ``LA`` and ``RGBA``, TIFF ExtraSamples):
the grey is the image only where the alpha adds nothing to it; an alpha
that shows other pixels (black ink on a transparent sheet, as an image
editor exports a painted layer) is refused in one line whose command saves
the alpha as the mask, which is then read as Pillow or tifffile reads the
alpha."""

import json
import shlex
import subprocess
import sys

import numpy as np
import pytest
from in_process import isoflow_here

Image = pytest.importorskip("PIL.Image")
measure = pytest.importorskip("skimage.measure")


def run(*args, cwd):
    """The command's exit status, stdout and stderr in ``cwd``, run in this
    process (what it reports is tested, not the shell: tests/in_process.py)."""
    return isoflow_here(*args, cwd=cwd)


@pytest.fixture
def ink():
    """A ring (one hole) and a dot: what is drawn, as 0/255."""
    drawn = np.zeros((9, 12), np.uint8)
    drawn[1:7, 2:8] = 255
    drawn[3:5, 4:6] = 0
    drawn[7, 10] = 255
    return drawn


def _saved(path, grey, alpha, how):
    """``grey`` with ``alpha`` saved as ``how`` writes it."""
    if how == "LA.png":
        Image.fromarray(np.stack([grey, alpha], axis=-1), mode="LA").save(path)
    elif how == "RGBA.png":
        Image.fromarray(np.stack([grey] * 3 + [alpha], axis=-1), mode="RGBA").save(path)
    else:
        tifffile = pytest.importorskip("tifffile")
        planar = how == "planes.tif"
        pixels = np.stack([grey, alpha], axis=0 if planar else -1)
        tifffile.imwrite(path, pixels, photometric="minisblack", extrasamples=["unassalpha"],
                         planarconfig="separate" if planar else "contig")


def _alpha_read_by_its_library(path):
    """The alpha as Pillow or tifffile reads it."""
    if path.suffix == ".png":
        with Image.open(path) as image:
            return np.asarray(image.getchannel("A"))
    tifffile = pytest.importorskip("tifffile")
    with tifffile.TiffFile(path) as tif:
        series = tif.series[0]
        return np.take(series.asarray(), -1, axis=series.axes.index("S"))


@pytest.mark.parametrize("how", ["LA.png", "RGBA.png", "contig.tif", "planes.tif"])
def test_ink_on_a_transparent_sheet_is_refused_and_its_command_saves_the_drawing(tmp_path, ink, how):
    path = tmp_path / f"layer.{how.split('.')[1]}"
    _saved(path, np.zeros_like(ink), ink, how)  # black ink: the grey is 0 everywhere
    alpha = _alpha_read_by_its_library(path)
    assert np.array_equal(alpha, ink)
    proc = run("info", path.name, "--json", cwd=tmp_path)
    assert proc.returncode == 2 and proc.stdout == "", proc.stdout
    line = proc.stderr.strip()
    assert len(line.splitlines()) == 1 and line.startswith(f"isoflow info: error: {path.name}: its alpha channel ("), line
    assert f"at {np.count_nonzero(alpha)} of {alpha.size} pixels" in line
    command = shlex.split(line.split("(or save the grey alone): ", 1)[1])
    assert command[:2] == ["python", "-c"]
    subprocess.run([sys.executable, *command[1:]], check=True, cwd=tmp_path)
    saved = tmp_path / f"layer_alpha{path.suffix}"
    proc = run("info", saved.name, "--json", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert got["voxels"] == np.count_nonzero(alpha)
    assert got["euler_characteristic"] == measure.euler_number(alpha.T != 0, connectivity=1)


@pytest.mark.parametrize("how", ["LA.png", "RGBA.png", "contig.tif", "planes.tif"])
def test_a_mask_cut_out_of_its_background_is_read_as_its_grey(tmp_path, ink, how):
    """Transparent exactly where the grey is 0: the alpha and the grey are
    one mask, read as the grey."""
    path = tmp_path / f"cut.{how.split('.')[1]}"
    _saved(path, ink, ink, how)
    proc = run("info", path.name, "--json", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert got["voxels"] == np.count_nonzero(_alpha_read_by_its_library(path))
    assert got["euler_characteristic"] == measure.euler_number(ink.T != 0, connectivity=1)


def test_the_refusal_formats_md_quotes_is_the_one_given(tmp_path, ink):
    """docs/formats.md quotes the line for a 9x12 ink layer saved as LA."""
    from pathlib import Path

    _saved(tmp_path / "layer.png", np.zeros_like(ink), ink, "LA.png")
    proc = run("info", "layer.png", cwd=tmp_path)
    assert proc.returncode == 2
    line = proc.stderr.strip().removeprefix("isoflow info: error: ")
    docs = Path(__file__).resolve().parents[2] / "docs" / "formats.md"
    text = " ".join(docs.read_text().split())
    assert f"`{line}`" in text
