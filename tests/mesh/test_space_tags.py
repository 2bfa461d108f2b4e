"""A surface's anatomical frame in its file's header, as 3D Slicer reads it
(``vtkMRMLModelStorageNode::GetCoordinateSystemFromFileHeader``: the text
``SPACE=RAS`` or ``SPACE=LPS`` anywhere in a binary STL's 80-byte header,
in one PLY comment, in the OBJ's leading comments; no tag: LPS). The
expected frames are the volume files' own (nibabel's affine is RAS, the
NRRD's ``space`` as pynrrd writes it); the expected vertex count and
bounds are those of a box of voxels placed by nibabel's affine."""

import numpy as np
import pytest
import trimesh

from isoflow import DigitalObject
from isoflow.cli import main

nib = pytest.importorskip("nibabel")
nrrd = pytest.importorskip("nrrd")

#: a solid box of voxels, off the array's border
LO, HI = np.array([2, 3, 1]), np.array([6, 6, 7])
SHAPE = (8, 9, 9)
PITCH = np.array([0.5, 0.75, 1.25])
ORIGIN = np.array([12.5, -31.25, 47.0])  # voxel 0's centre


def box() -> np.ndarray:
    v = np.zeros(SHAPE, np.uint8)
    v[tuple(slice(a, b) for a, b in zip(LO, HI))] = 1
    return v


def box_corners() -> int:
    """The lattice points on a solid box's boundary."""
    n = HI - LO
    return int(np.prod(n + 1) - np.prod(n - 1))


def nifti(path):
    affine = np.diag([*PITCH, 1.0])
    affine[:3, 3] = ORIGIN
    nib.save(nib.Nifti1Image(box(), affine), str(path))
    img = nib.load(str(path))
    # the box's outer corners: the extreme voxel centres, half a voxel out
    lo = nib.affines.apply_affine(img.affine, LO - 0.5)
    hi = nib.affines.apply_affine(img.affine, HI - 0.5)
    return np.minimum(lo, hi), np.maximum(lo, hi)


def space_nrrd(path, space):
    nrrd.write(str(path), box(), {"space": space, "space directions": np.diag(PITCH), "space origin": ORIGIN,
                                  "kinds": ["domain"] * 3}, index_order="F")
    return ORIGIN + PITCH * (LO - 0.5), ORIGIN + PITCH * (HI - 0.5)


def headers(path) -> list[str]:
    """The header texts 3D Slicer searches for the tag, one per place it
    looks: a binary STL's 80 bytes, each PLY comment, the OBJ's comment
    lines before its first other line (vtkOBJReader's comment)."""
    data = path.read_bytes()
    suffix = path.suffix
    if suffix == ".stl":
        return [data[:80].decode("latin-1")]
    if suffix == ".ply":
        head = data.split(b"end_header", 1)[0].decode("latin-1")
        return [line[len("comment "):] for line in head.splitlines() if line.startswith("comment ")]
    lines = []
    for line in data.decode("latin-1").splitlines():
        if not line.startswith("#"):
            break
        lines.append(line[1:])
    return ["\n".join(lines)]


def slicer_frame(path) -> str | None:
    """The frame 3D Slicer takes from the file's header, None where it
    finds none (it then assumes LPS)."""
    for text in headers(path):
        if "SPACE=RAS" in text:
            return "RAS"
        if "SPACE=LPS" in text:
            return "LPS"
    return None


def surface(capsys, source, out, *extra):
    assert main(["surface", str(source), "-o", str(out), "-q", *extra]) == 0, capsys.readouterr().err
    return out


OUTPUTS = [("s.stl", ()), ("s.ply", ()), ("s.ply", ("--ascii",)), ("s.obj", ())]


def check_unchanged(path, bounds):
    """Read back as before: the box's corners and its world bounds."""
    mesh = trimesh.load(str(path), force="mesh")
    assert len(mesh.vertices) == box_corners()
    np.testing.assert_allclose(mesh.bounds, np.array(bounds), rtol=0, atol=1e-5)


@pytest.mark.parametrize("name,extra", OUTPUTS)
def test_a_nifti_surface_says_ras_as_slicer_reads_it(tmp_path, capsys, name, extra):
    bounds = nifti(tmp_path / "seg.nii.gz")
    out = surface(capsys, tmp_path / "seg.nii.gz", tmp_path / name, *extra)
    assert slicer_frame(out) == "RAS"
    check_unchanged(out, bounds)


@pytest.mark.parametrize("name,extra", OUTPUTS)
def test_an_lps_nrrd_surface_says_lps(tmp_path, capsys, name, extra):
    bounds = space_nrrd(tmp_path / "seg.nrrd", "left-posterior-superior")
    out = surface(capsys, tmp_path / "seg.nrrd", tmp_path / name, *extra)
    assert slicer_frame(out) == "LPS"
    check_unchanged(out, bounds)


@pytest.mark.parametrize("name,extra", OUTPUTS)
def test_no_frame_or_one_slicer_has_no_tag_for_gives_no_tag(tmp_path, capsys, name, extra):
    np.save(tmp_path / "seg.npy", box().astype(bool))
    space_nrrd(tmp_path / "las.nrrd", "left-anterior-superior")
    for source in ("seg.npy", "las.nrrd"):
        out = surface(capsys, tmp_path / source, tmp_path / f"{source}.{name}", *extra)
        assert slicer_frame(out) is None
        assert not any("SPACE=" in text for text in headers(out))


def test_the_stl_header_keeps_isoflows_text_before_the_tag(tmp_path, capsys):
    nifti(tmp_path / "seg.nii.gz")
    out = surface(capsys, tmp_path / "seg.nii.gz", tmp_path / "s.stl")
    header = headers(out)[0]
    assert header.startswith("isoflow surface of seg.nii.gz, 6-connectivity")
    assert "SPACE=RAS" in header
    assert main(["genus", str(out), "--json"]) == 0  # the connectivity it records still reads
    capsys.readouterr()


def test_the_tagged_files_read_in_meshlab_as_before(tmp_path, capsys):
    pymeshlab = pytest.importorskip("pymeshlab")
    bounds = nifti(tmp_path / "seg.nii.gz")
    for name, extra in OUTPUTS:
        out = surface(capsys, tmp_path / "seg.nii.gz", tmp_path / f"{len(extra)}{name}", *extra)
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(out))
        m = ms.current_mesh()
        box_ = m.bounding_box()
        np.testing.assert_allclose([box_.min(), box_.max()], np.array(bounds), rtol=0, atol=1e-5)
        # STL keeps no shared vertices (MeshLab unifies them, or not)
        assert m.vertex_number() == box_corners() or name.endswith(".stl")


def test_the_flow_step_meshes_say_the_frame(tmp_path, capsys):
    nifti(tmp_path / "seg.nii.gz")
    assert main(["flow", str(tmp_path / "seg.nii.gz"), "--steps", "2", "--out", str(tmp_path / "fl"), "-q"]) == 0
    capsys.readouterr()
    steps = sorted((tmp_path / "fl").glob("step_*.ply"))
    assert steps
    assert [slicer_frame(p) for p in steps] == ["RAS"] * len(steps)


@pytest.mark.parametrize("suffix", [".stl", ".ply", ".obj"])
def test_each_label_file_says_the_frame(tmp_path, capsys, suffix):
    space_nrrd(tmp_path / "seg.nrrd", "left-posterior-superior")
    assert main(["surface", str(tmp_path / "seg.nrrd"), "--labels", "all", "-o", f"{tmp_path / 'lab'}/",
                 "--suffix", suffix, "-q"]) == 0, capsys.readouterr().err
    files = sorted((tmp_path / "lab").glob(f"*{suffix}"))
    assert files
    assert [slicer_frame(p) for p in files] == ["LPS"] * len(files)


@pytest.mark.parametrize("space", ["RAS", "LPS"])
@pytest.mark.parametrize("suffix", [".stl", ".ply"])
def test_a_surface_written_block_by_block_says_its_frame(tmp_path, space, suffix):
    from isoflow.mesh.surface_blocks import write_surface_blocks

    frame = DigitalObject(np.zeros(SHAPE, bool), pitch=PITCH, origin=ORIGIN, space=space)
    written = write_surface_blocks(box().astype(bool), tmp_path / f"s{suffix}", frame=frame, block_shape=(4, 4, 4))
    assert slicer_frame(written["path"]) == space
    mesh = trimesh.load(str(written["path"]), force="mesh")
    assert len(mesh.vertices) == box_corners()


@pytest.mark.parametrize("suffix", [".stl", ".ply", ".obj"])
def test_write_surface_says_the_objects_frame(tmp_path, suffix):
    import isoflow

    obj = DigitalObject(box().astype(bool), pitch=PITCH, space="lps")
    out = isoflow.write_surface(obj, tmp_path / f"s{suffix}")
    assert slicer_frame(out) == "LPS"
    assert slicer_frame(isoflow.write_surface(DigitalObject(box().astype(bool)), tmp_path / f"n{suffix}")) is None
