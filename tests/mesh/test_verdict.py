"""verify_genus's result: a frozen GenusVerdict whose to_dict() is what
``isoflow genus --json`` prints, with the verdict's kind and the stop as
data and the words in one place."""

import contextlib
import dataclasses
import io
import json
from pathlib import Path

import pytest

from isoflow.cli import main
from isoflow.mesh.genus import verify_genus
from isoflow.mesh.verdict import GenusVerdict, Note, Stop, option_flag, verdict_text

MESHES = Path(__file__).resolve().parents[2] / "meshes"


def json_of(*argv) -> dict:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["genus", *map(str, argv), "--json"]) == 0
    return json.loads(out.getvalue())


def without_seconds(d: dict) -> dict:
    return {**d, "digital": [{**e, "seconds": None} for e in d["digital"]]}


def test_to_dict_is_what_the_command_prints():
    v = verify_genus(MESHES / "plate_holes.STL", (16, 32), max_resolution=32)
    printed = json_of(MESHES / "plate_holes.STL", "--resolution", 16, 32, "--max-resolution", 32)
    assert without_seconds(v.to_dict()) == without_seconds(printed)
    assert list(printed) == list(GenusVerdict.KEYS)


def test_the_verdict_reads_as_a_mapping_and_is_frozen():
    v = verify_genus(MESHES / "torus.obj", (16, 32))
    assert isinstance(v, GenusVerdict) and v["verdict"] == v.verdict == verdict_text(v)
    assert dict(v) == v.to_dict() and v["agree"] is v.agree and len(v) == len(v.to_dict())
    with pytest.raises(KeyError):
        v["kind"]  # fields beyond the JSON's keys are attributes
    with pytest.raises(dataclasses.FrozenInstanceError):
        v.agree = True


def test_the_stop_and_the_facts_are_data():
    v = verify_genus(MESHES / "plate_holes.STL", (16, 32), max_resolution=32)
    assert v.kind == "disagree" and v.reference == 5 and v.reference_source == "mesh"
    assert v.stop == Stop("max_resolution", limit=32, resolution=64, option="max_resolution")
    # the option is data; the words spell it as the command line does
    assert option_flag(v.stop.option) == "--max-resolution" and "(32, --max-resolution)" in v.verdict
    coarse = [n for n in v.notes if n.kind == "coarse"]
    assert coarse == [] and all(isinstance(n, Note) for n in v.notes)
    v = verify_genus(MESHES / "rabbit.obj", (32, 64), time_limit=1e-6)
    assert v.kind == "not_converged" and v.stop.kind == "time_limit" and v.stop.option == "time_limit"
    assert v.stop.limit == 1e-6 and v.stop.resolution == 128 and v.stop.estimate > 0
    assert [n.kind for n in v.notes][:1] == ["overlap"] and v.notes[0].facts["components"] == 9


def test_no_option_name_in_the_deciding_code():
    """The library decides with data; only the words (mesh/verdict.py) turn
    a parameter into its command-line spelling."""
    source = (Path(__file__).resolve().parents[2] / "src/isoflow/mesh/genus.py").read_text()
    import re

    assert re.findall(r"--[a-z]", source) == []


def test_the_solid_line_counts_bodies_and_cavities(tmp_path, capsys):
    """Two boxes apart, one of them hollow (a box inside it, facing in):
    the solid is 2 bodies with 1 cavity, its 3 shells what trimesh splits
    the mesh into; the line used to say "3 boundary surfaces" only."""
    import trimesh

    from isoflow.mesh.genus import solid_report

    outer = trimesh.creation.box(extents=(4, 4, 4))
    hole = trimesh.creation.box(extents=(2, 2, 2))
    hole.invert()
    apart = trimesh.creation.box(extents=(1, 1, 1))
    apart.apply_translation((6, 0, 0))
    mesh = trimesh.util.concatenate([outer, hole, apart])
    parts = mesh.split(only_watertight=False)
    want_bodies = sum(1 for p in parts if p.volume > 0)
    assert (len(parts), want_bodies) == (3, 2)
    report = solid_report(mesh.vertices, mesh.faces)
    assert (report["bodies"], report["cavities"], report["surfaces"]) == (want_bodies, 1, 3)
    assert report["volume"] == pytest.approx(mesh.volume)
    mesh.export(tmp_path / "m.obj")
    assert main(["genus", str(tmp_path / "m.obj"), "--resolution", "16", "--no-step"]) == 0
    assert "solid       genus 0, 2 bodies, 1 cavity, volume 57 " in capsys.readouterr().out


def test_resolutions_asked_past_max_resolution_are_tried_and_not_blamed_on_it():
    """--max-resolution caps the doubling only (docs/genus.md): 48 asked
    with the cap at 16 is tried, and the verdict said it was stopped by
    "the largest resolution allowed (16, --max-resolution)"."""
    v = verify_genus(MESHES / "torus.obj", (48,), max_resolution=16)
    assert [d["resolution"] for d in v.digital] == [48]
    assert v.stop == Stop("asked", limit=16, resolution=48, option="max_resolution")
    assert "largest resolution allowed" not in v.verdict
    assert "stopped by the resolutions asked (48 is past --max-resolution 16, which caps only the doubling)" in v.verdict
    printed = json_of(MESHES / "torus.obj", "--resolution", 48, "--max-resolution", 16)
    assert printed["verdict"] == v.verdict  # at the cap itself, the cap stops it: test_the_stop_and_the_facts_are_data
