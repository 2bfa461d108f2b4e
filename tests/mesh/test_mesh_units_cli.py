"""A mesh file that says its length unit (a 3MF model's ``unit``, glTF's
metres) gives it to the volume voxelised from it, as a volume file gives
its own: ``voxelize -o`` writes it, ``flow --json`` reports it. trimesh's
``Scene.units`` is the reference for what each file declares."""

import json
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from in_process import isoflow_here

trimesh = pytest.importorskip("trimesh")
pytest.importorskip("lxml")  # trimesh's 3MF reader
nib = pytest.importorskip("nibabel")

# trimesh's names for the units of these files, in isoflow's spelling
SPELLED = {"inch": "in", "millimeter": "mm", "millimeters": "mm", "meters": "m", "centimeter": "cm"}


def isoflow(*args: object) -> subprocess.CompletedProcess:
    """The command's exit status, stdout and stderr, run in this process
    (what it reports is tested, not the shell: tests/in_process.py)."""
    return isoflow_here(*args)


def box_3mf(path: Path, unit: str | None) -> Path:
    """A 2x3x4 box as trimesh writes a 3MF, its model's unit attribute set
    to ``unit`` (left out where None)."""
    trimesh.creation.box((2, 3, 4)).export(path.with_suffix(".tmp.3mf"))
    with zipfile.ZipFile(path.with_suffix(".tmp.3mf")) as src, zipfile.ZipFile(path, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename.endswith(".model"):
                data = data.replace(b' unit="millimeter"', b"" if unit is None else f' unit="{unit}"'.encode())
            dst.writestr(item, data)
    return path


@pytest.mark.parametrize("unit", ["inch", "centimeter", None])
def test_voxelize_writes_the_unit_a_3mf_declares(tmp_path, unit):
    mesh = box_3mf(tmp_path / "box.3mf", unit)
    declared = trimesh.load(mesh).units  # the 3MF default, millimetres, where the model says none
    assert SPELLED[declared] == SPELLED[unit or "millimeter"]
    done = isoflow("voxelize", mesh, "--pitch", "0.5", "-o", tmp_path / "box.npz")
    assert done.returncode == 0, done.stderr
    with np.load(tmp_path / "box.npz") as f:
        assert str(f["unit"]) == SPELLED[declared]
        assert int(f["volume"].sum()) == 4 * 6 * 8  # the box in half units: the grid is unchanged


def test_a_3mf_in_millimetres_gives_a_nifti_in_millimetres(tmp_path):
    mesh = box_3mf(tmp_path / "box.3mf", "millimeter")
    done = isoflow("voxelize", mesh, "--pitch", "0.5", "-o", tmp_path / "box.nii.gz")
    assert done.returncode == 0 and "warning" not in done.stderr, done.stderr
    assert nib.load(tmp_path / "box.nii.gz").header.get_xyzt_units()[0] == "mm"


def test_flow_of_a_glb_reports_metres_and_of_an_stl_no_unit(tmp_path):
    box = trimesh.creation.box((2, 3, 4))
    box.export(tmp_path / "box.glb")
    box.export(tmp_path / "box.stl")
    assert trimesh.load(tmp_path / "box.glb").units == "meters"  # glTF 2.0: all distances in metres
    assert trimesh.load(tmp_path / "box.stl").units is None
    for name, unit in (("box.glb", "m"), ("box.stl", None)):
        done = isoflow("flow", tmp_path / name, "--pitch", "0.5", "--json", "-q")
        assert done.returncode == 0, done.stderr
        assert json.loads(done.stdout)["unit"] == unit


def test_isoflows_own_glb_declares_no_metres(tmp_path):
    """isoflow's GLB of a volume in mm holds the mm numbers as they are;
    voxelised again it was read as metres, 1000 times the size. Its
    ``asset.generator`` is isoflow's: no unit is declared, and the volume
    voxelised back holds the original's voxels (the same count, trimesh's
    volume of the GLB in voxels)."""
    import isoflow as iso

    volume = np.zeros((8, 8, 8), bool)
    volume[2:6, 2:6, 2:6] = True
    iso.write_volume(iso.DigitalObject(volume, pitch=0.5, unit="mm"), tmp_path / "v.npz")
    assert isoflow("surface", tmp_path / "v.npz", "-o", tmp_path / "v.glb", "-q").returncode == 0
    assert json.loads(bytes(memoryview((tmp_path / "v.glb").read_bytes())[20:20 + int.from_bytes(
        (tmp_path / "v.glb").read_bytes()[12:16], "little")]))["asset"]["generator"] == "isoflow"
    done = isoflow("voxelize", tmp_path / "v.glb", "--pitch", "0.5", "-o", tmp_path / "back.npz")
    assert done.returncode == 0, done.stderr
    done = isoflow("info", tmp_path / "back.npz", "--json")
    got = json.loads(done.stdout)
    assert got["unit"] is None and got["voxels"] == volume.sum()
    assert got["voxels"] * 0.125 == pytest.approx(trimesh.load(tmp_path / "v.glb", force="mesh").volume)


def test_a_store_and_a_label_image_keep_the_unit_too(tmp_path):
    mesh = box_3mf(tmp_path / "box.3mf", "inch")
    assert trimesh.load(mesh).units == "inch"
    done = isoflow("voxelize", mesh, "--pitch", "0.5", "-o", tmp_path / "box.zarr")
    assert done.returncode == 0, done.stderr
    attrs = json.loads((tmp_path / "box.zarr" / ".zattrs").read_text())
    assert [a.get("unit") for a in attrs["multiscales"][0]["axes"]] == ["inch"] * 3  # NGFF's UDUNITS name
    done = isoflow("voxelize", mesh, "--split", "--pitch", "0.5", "-o", tmp_path / "labels.npz")
    assert done.returncode == 0, done.stderr
    with np.load(tmp_path / "labels.npz") as f:
        assert str(f["unit"]) == "in"


def test_meshes_in_different_units_are_refused_for_one_grid(tmp_path):
    """A 2 mm box and a 2 in box are drawn by their numbers as one size:
    one label image of both would be wrong by 25.4 in one of them."""
    mm = box_3mf(tmp_path / "mm.3mf", "millimeter")
    inch = box_3mf(tmp_path / "inch.3mf", "inch")
    assert {trimesh.load(mm).units, trimesh.load(inch).units} == {"millimeter", "inch"}
    done = isoflow("voxelize", mm, inch, "--pitch", "0.5", "-o", tmp_path / "labels.npz")
    assert done.returncode == 2 and not (tmp_path / "labels.npz").exists()
    assert len(done.stderr.splitlines()) == 1 and "Traceback" not in done.stderr
    assert "mm.3mf in mm" in done.stderr and "inch.3mf in in" in done.stderr
    # one unit, or a mesh of bare numbers beside it, is voxelised as before
    stl = tmp_path / "box.stl"
    trimesh.creation.box((2, 3, 4)).export(stl)
    for meshes in ((mm, mm), (mm, stl)):
        done = isoflow("voxelize", *meshes, "--pitch", "0.5", "-o", tmp_path / "ok.npz", "--force")
        assert done.returncode == 0, done.stderr


def test_voxelize_meshes_in_python_refuses_them_too(tmp_path):
    import isoflow as iso

    mm = box_3mf(tmp_path / "mm.3mf", "millimeter")
    trimesh.creation.box((2, 3, 4)).export(tmp_path / "box.glb")  # metres, by the glTF specification
    assert trimesh.load(tmp_path / "box.glb").units == "meters"
    with pytest.raises(iso.IsoflowError, match=r"mm\.3mf in mm, .*box\.glb in m\b"):
        iso.voxelize_meshes([mm, tmp_path / "box.glb"], pitch=0.5)
    assert iso.voxelize_meshes([mm, trimesh.creation.box((2, 3, 4))], pitch=0.5).voxels == (0, 192)


def test_info_of_a_3mf_says_its_pitch_and_origin_in_its_unit(tmp_path):
    mesh = box_3mf(tmp_path / "box.3mf", "inch")
    done = isoflow("info", mesh, "--pitch", "0.5")
    assert done.returncode == 0, done.stderr
    grid = next(line for line in done.stdout.splitlines() if line.lstrip().startswith("voxelised"))
    assert "pitch 0.5 in," in grid and grid.endswith("] in")
    assert "volume                 24 in^3" in done.stdout  # 2 x 3 x 4 inches


def test_meshes_voxelised_into_labels_give_their_unit_to_the_file_and_the_result(tmp_path, monkeypatch):
    """Two 3MF parts in microns: the label image's NIfTI header says
    microns (nibabel), and so does ``voxelize_meshes``'s result, which had
    no unit. Each model's unit is read once (it was read twice, by the
    command for the file and by the bodies for the refusal of mixed
    units)."""
    import isoflow as iso
    from isoflow.mesh import mesh_units

    parts = [box_3mf(tmp_path / f"{name}.3mf", "micron") for name in ("a", "b")]
    assert {trimesh.load(p).units for p in parts} == {"micron"}
    done = isoflow("voxelize", *parts, "--pitch", "0.5", "-o", tmp_path / "labels.nii.gz")
    assert done.returncode == 0, done.stderr
    assert nib.load(tmp_path / "labels.nii.gz").header.get_xyzt_units()[0] == "micron"
    read = []
    real = mesh_units.threemf_unit
    monkeypatch.setattr(mesh_units, "threemf_unit", lambda path: read.append(path) or real(path))
    r = iso.voxelize_meshes(parts, pitch=0.5)
    assert r.unit == "µm" and r.to_dict()["unit"] == "µm" and sorted(read) == sorted(parts)
    assert iso.voxelize_meshes([parts[0], trimesh.creation.box((2, 3, 4))], pitch=0.5).unit is None


def box_dae(path: Path, meter: str | None) -> Path:
    """A 2x3x4 box as trimesh writes COLLADA (no ``<unit>``), its asset
    given ``<unit meter="METER"/>`` where ``meter`` is given."""
    pytest.importorskip("collada")  # trimesh's COLLADA reader and writer
    data = trimesh.exchange.dae.export_collada(trimesh.creation.box((2, 3, 4)))
    assert b"<unit" not in data
    if meter is not None:
        data = data.replace(b"<up_axis>", f'<unit meter="{meter}" name="some unit"/>\n    <up_axis>'.encode())
    path.write_bytes(data)
    return path


def test_a_dae_in_millimetres_is_voxelised_and_reported_as_a_3mf_in_millimetres_is(tmp_path):
    """COLLADA's ``<unit meter="0.001">`` was not read: the volume had no
    unit, and its NIfTI none. It is read as trimesh reads it (metres a
    unit; metres where none is given, COLLADA's default), and a DAE in
    millimetres reports and writes what a 3MF in millimetres does."""
    dae, threemf = box_dae(tmp_path / "box.dae", "0.001"), box_3mf(tmp_path / "box.3mf", "millimeter")
    assert trimesh.load(dae).units == "0.001 * meters"
    for mesh in (dae, threemf):
        done = isoflow("voxelize", mesh, "--pitch", "0.5", "-o", tmp_path / f"{mesh.suffix[1:]}.nii.gz")
        assert done.returncode == 0 and "warning" not in done.stderr, done.stderr
        assert nib.load(tmp_path / f"{mesh.suffix[1:]}.nii.gz").header.get_xyzt_units()[0] == "mm"
    said = [isoflow("info", mesh, "--pitch", "0.5").stdout for mesh in (dae, threemf)]
    assert said[0].replace(str(dae), "") == said[1].replace(str(threemf), "")
    assert "volume                 24 mm^3" in said[0]  # 2 x 3 x 4 millimetres
    # inches by their metres, COLLADA's default of metres, and a ZAE (its DAE zipped) as its DAE
    zae = tmp_path / "box.zae"
    with zipfile.ZipFile(zae, "w") as z:
        z.write(box_dae(tmp_path / "in.dae", "0.0254"), "in.dae")
    for mesh, theirs, ours in ((tmp_path / "in.dae", "0.0254 * meters", "in"), (zae, "0.0254 * meters", "in"),
                               (box_dae(tmp_path / "plain.dae", None), "meters", "m")):
        assert trimesh.load(mesh).units == theirs
        done = isoflow("info", mesh, "--pitch", "0.5", "--json")
        assert done.returncode == 0, done.stderr
        assert json.loads(done.stdout)["unit"] == ours
