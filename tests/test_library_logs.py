"""A library's log records reach the user as one note line, never as a
traceback: trimesh logs "unable to load image!" with its traceback for a
PLY whose texture file is missing (trimesh's fuze.ply without "fuze uv.jpg").

isoflow's own PLY reader steps over texture coordinates and never opens
the texture, so such a file reaches trimesh only where that reader leaves
it (patched out here, as for a PLY it does not take)."""

import subprocess
import sys
from pathlib import Path

import pytest
import trimesh

from isoflow.cli import main


@pytest.fixture
def textured_ply(tmp_path):
    """A closed box whose PLY names a texture file that is not there."""
    box = trimesh.creation.box()
    lines = ["ply", "format ascii 1.0", "comment TextureFile fuze uv.jpg", f"element vertex {len(box.vertices)}",
             "property float x", "property float y", "property float z", "property float s", "property float t",
             f"element face {len(box.faces)}", "property list uchar int vertex_indices", "end_header"]
    lines += [f"{x} {y} {z} 0.5 0.5" for x, y, z in box.vertices]
    lines += [f"3 {a} {b} {c}" for a, b, c in box.faces]
    path = tmp_path / "fuze.ply"
    path.write_text("\n".join(lines) + "\n")
    return path


#: the command line with isoflow's PLY reader left out, so that trimesh reads the file
THROUGH_TRIMESH = ("import sys; import isoflow.mesh.ply as ply; ply.read_ply = lambda data, where='': None; "
                   "from isoflow.cli import main; sys.exit(main(sys.argv[1:]))")


@pytest.mark.parametrize("command", [["genus", "--resolution", "8", "--no-step"], ["info", "--resolution", "8"]])
def test_a_missing_texture_is_not_needed(textured_ply, command):
    """isoflow's reader takes the file: no texture is looked for, no note."""
    run = subprocess.run([sys.executable, "-m", "isoflow", command[0], str(textured_ply), *command[1:]],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "unable to load image" not in run.stderr and "Traceback" not in run.stderr


def test_genus_md_says_isoflow_s_reader_opens_no_texture():
    """docs/genus.md gave the missing texture of a PLY as the note a user
    sees; isoflow's own reader takes such a file, and no note comes."""
    text = " ".join((Path(__file__).resolve().parents[1] / "docs" / "genus.md").read_text().split())
    said = text[text.index("## Library log records"):text.index("## Measured")]
    assert "isoflow's own PLY reader steps over texture coordinates and never opens the texture" in said


@pytest.mark.parametrize("command", [["genus", "--resolution", "8", "--no-step"], ["info", "--resolution", "8"]])
def test_missing_texture_is_one_note_line(textured_ply, command):
    args = [sys.executable, "-c", THROUGH_TRIMESH, command[0], str(textured_ply), *command[1:]]
    run = subprocess.run(args, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "Traceback" not in run.stderr
    notes = [line for line in run.stderr.splitlines() if "unable to load image" in line]
    assert notes == [f"isoflow {command[0]}: note: trimesh.util: unable to load image! "
                     "(FileNotFoundError: fuze uv.jpg)"]
    quiet = subprocess.run(args + ["--quiet"], capture_output=True, text=True)
    assert quiet.returncode == 0 and quiet.stderr == ""


def test_in_process_main_says_it_once_and_leaves_logging_as_it_was(textured_ply, capfd, monkeypatch):
    import logging

    import isoflow.mesh.ply as ply

    monkeypatch.setattr(ply, "read_ply", lambda data, where="": None)  # trimesh reads the file
    handlers = list(logging.root.handlers)
    assert main(["genus", str(textured_ply), "--resolution", "8", "--no-step", "--json"]) == 0
    err = capfd.readouterr().err
    assert err.count("unable to load image") == 1 and "Traceback" not in err
    assert logging.root.handlers == handlers
