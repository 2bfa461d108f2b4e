"""The results of the Python API round-trip through their JSON."""

import json
import re

import numpy as np
import pytest

import isoflow
from isoflow.errors import IsoflowError


def test_a_flow_result_comes_back_from_its_json():
    # from_dict refused the JSON of to_dict: states is not in it
    ring = np.zeros((6, 6, 6), bool)
    ring[1:5, 1:5, 1:5] = True
    ring[2:4, 2:4, :] = False
    for guard in (False, True):
        run = isoflow.run_flow(ring, guard=guard)
        back = isoflow.FlowResult.from_dict(json.loads(json.dumps(run.to_dict())))
        assert back.to_dict() == run.to_dict() and back.states == []
        assert back.guard is guard and back.connectivity == 6


def test_a_report_comes_back_from_its_json():
    ring = np.ones((3, 3, 1), bool)
    ring[1, 1, 0] = False
    for conn in (6, 26):
        report = isoflow.analyze(ring, conn)
        assert isoflow.Report.from_dict(json.loads(json.dumps(report.to_dict()))) == report


def test_every_result_equals_the_dict_of_its_own_items():
    """Results read as mappings, so each equals a dict of the same items,
    a report as a flow result and a surface census do; and none is
    hashed by its fields (whose lists made a TypeError from inside)."""
    box = np.ones((5, 5, 5), bool)
    box[2, 2, 2] = False
    results = (isoflow.analyze(box), isoflow.analyze(box[1]), isoflow.run_flow(box, steps=2), isoflow.closed_surfaces(box))
    for result in results:
        items = dict(result)
        assert result == items and items == result and not result != items, type(result).__name__
        assert result == json.loads(json.dumps(result.to_dict())) or not isinstance(result, isoflow.Report)
        with pytest.raises(TypeError, match=type(result).__name__):
            hash(result)
    report = results[0]
    assert report["betti"] == [1, 0, 1] and report != dict(report, betti=[1, 0, 0])


def test_a_4d_report_comes_back_from_its_json():
    # the classes of a 4D report are keyed by configuration, ints, which JSON writes as strings: read
    # back, {"1": 16, ...} was not equal to {1: 16, ...}. A 2x2x2x2 block: 16 corners of 1 cell each
    # (configuration 1), 32 edge vertices of 2 (3), 24 face vertices of 4 (15), 8 of 8 (255)
    block = np.ones((2, 2, 2, 2), bool)
    report = isoflow.analyze(block, 80)
    back = isoflow.Report.from_dict(json.loads(json.dumps(report.to_dict())))
    assert back == report and back.classes == {1: 16, 3: 32, 15: 24, 255: 8}
    assert isoflow.Report.from_dict(report.to_dict()) == report  # int keys given stay as they are


def test_a_voxelization_comes_back_from_its_json():
    # from_dict refused the JSON of to_dict: the volume is not in it ("missing ... 'volume'")
    import pytest

    trimesh = pytest.importorskip("trimesh")
    from isoflow.mesh.fills import Voxelization

    obj, v = isoflow.voxelize_mesh(trimesh.creation.box((2, 2, 2)), resolution=4, details=True)
    back = Voxelization.from_dict(json.loads(json.dumps(v.to_dict())))
    assert back.to_dict() == v.to_dict() and back.volume is None
    assert back.voxels == 64 and back.origin.tolist() == [-1.0, -1.0, -1.0] and back.pitch == 0.5
    assert Voxelization.from_dict(dict(v)) == v and obj.voxels == 64


def test_a_surface_census_comes_back_from_its_json():
    # JSON makes the histogram and the Betti counts lists: read back, (1, 1) was not equal to [1, 1]
    from isoflow.digital.report import SurfaceCensus

    hollow = np.ones((3, 3, 3), bool)
    hollow[1, 1, 1] = False
    census = isoflow.closed_surfaces(hollow)
    back = SurfaceCensus.from_dict(json.loads(json.dumps(census.to_dict())))
    assert back == census and back.betti_counts == (1, 1) and [s["genus"] for s in back.surfaces] == [0, 0]
    assert back.hist.sum() == 4**3  # the lattice vertices of a 3x3x3 array


def test_a_4d_nifti_warns_of_the_fourth_axis_placement_it_cannot_keep(tmp_path):
    # the fourth axis's pitch and origin were dropped without a word, read
    # back as 1 and 0 (a .npy's dropped placement is warned of)
    import pytest

    pytest.importorskip("nibabel")
    obj = isoflow.DigitalObject(np.ones((2, 2, 2, 2), bool), pitch=(1, 1, 1, 0.5), origin=(1, 2, 3, 4))
    with pytest.warns(isoflow.IsoflowWarning, match="fourth axis's voxel size 0.5 and origin 4 are not written"):
        isoflow.write_volume(obj, tmp_path / "a.nii.gz")
    back = isoflow.read_volume(tmp_path / "a.nii.gz")
    assert back.spacing.tolist() == [1, 1, 1, 1] and back.origin.tolist() == [1, 2, 3, 0]


def test_objects_meshes_and_results_compare_by_their_arrays():
    # == raised NumPy's "truth value of an array ... is ambiguous": the
    # generated __eq__ compared the array fields as a tuple
    import pytest

    cube = np.ones((3, 3, 3), bool)
    obj = isoflow.DigitalObject(cube, pitch=0.5, origin=(1, 2, 3))
    assert obj == isoflow.DigitalObject(cube.copy(), pitch=0.5, origin=(1.0, 2.0, 3.0))
    assert obj != isoflow.DigitalObject(cube, pitch=0.5, origin=(1, 2, 4))
    assert obj != isoflow.DigitalObject(cube[:2], pitch=0.5, origin=(1, 2, 3))
    assert obj != isoflow.DigitalObject(cube, offset=(0, 0, 1), pitch=0.5, origin=(1, 2, 3))
    assert obj != "cube" and obj in [None, isoflow.DigitalObject(cube, pitch=0.5, origin=(1, 2, 3))]
    with pytest.raises(TypeError, match="unhashable type: 'DigitalObject'"):
        hash(obj)
    # the flow of a 3x3x3 box: 27, 8, 1 voxels, then nothing (docs/flow.md); two runs give equal states
    states = isoflow.run_flow(cube).states
    assert [s.voxels for s in states] == [27, 8, 1, 0] and states == isoflow.run_flow(cube).states
    assert states[1] != states[2]
    assert isoflow.boundary_mesh(cube) == isoflow.boundary_mesh(cube.copy())
    assert isoflow.boundary_mesh(cube) != isoflow.boundary_mesh(cube[:2])
    census = isoflow.closed_surfaces(cube)
    assert census == isoflow.closed_surfaces(cube) and census != isoflow.closed_surfaces(cube[:2])
    image = isoflow.LabelImage(cube.astype(np.uint8), np.ones(3), np.zeros(3))
    assert image == isoflow.LabelImage(cube.astype(np.uint8), np.ones(3), np.zeros(3))
    assert image != isoflow.LabelImage(cube.astype(np.uint8), np.full(3, 2.0), np.zeros(3))


def test_a_label_voxelization_comes_back_from_its_json():
    # from_dict refused the JSON of to_dict: the label array is not in it ("missing ... 'labels'")
    import pytest

    trimesh = pytest.importorskip("trimesh")
    from isoflow.mesh.label_voxels import LabelVoxelization

    boxes = [trimesh.creation.box((2, 2, 2)), trimesh.creation.box((2, 2, 2)).apply_translation((1, 0, 0))]
    r = isoflow.voxelize_meshes(boxes, pitch=0.5)
    back = LabelVoxelization.from_dict(json.loads(json.dumps(r.to_dict())))
    assert back.to_dict() == r.to_dict() and back.labels is None
    # two 2x2x2 boxes overlapping by half, at pitch 0.5: 64 voxels each, 32 of box 1 taken by box 2
    assert back.voxels == (32, 64) and back.overlaps == ((1, 2, 32),) and back.overlap_voxels == 32
    assert back.origin.tolist() == [-1.0, -1.0, -1.0] and back.names == ("mesh 1", "mesh 2")
    assert LabelVoxelization.from_dict(dict(r)) == r and r.labels.shape == (6, 4, 4)


def test_an_object_that_vanishes_is_the_empty_object_every_crop_gives():
    # flow_step of a vanishing object kept its dual lattice's offset, (-1, -1, -1), while an empty object crops
    # to offset zeros: the two empty objects, of the same parity, compared unequal
    import numpy as np

    cube = np.zeros((3, 3, 3), bool)
    cube[1, 1, 1] = True  # one voxel: its 8 vertices are convex corners, none is kept (eq. 5.15)
    gone = isoflow.flow_step(isoflow.DigitalObject(cube, offset=(4, 5, 6)))
    assert gone.voxels == 0 and gone.volume.shape == (0, 0, 0) and gone.parity == 1 and gone.offset == (0, 0, 0)
    assert gone == isoflow.DigitalObject(np.zeros((2, 2, 2), bool), offset=(-7, 0, 3), parity=1).cropped()
    pixel = np.ones((1, 1), bool)  # in 2D too (the planar flow)
    assert isoflow.flow_step(pixel).offset == (0, 0) and isoflow.flow_step(pixel).voxels == 0


def test_a_1d_array_is_counted_by_euler_characteristic_betti_numbers_and_analyze_alike():
    # euler_characteristic took a 1D array (docs/ndim.md: 1D to 4D) while betti_numbers and analyze
    # refused it ("a volume is 2D, 3D or 4D"); its runs, counted by scipy's labelling, are b0 and chi
    import numpy as np
    from scipy import ndimage

    rng = np.random.default_rng(7)
    for row in [rng.random(n) < p for n in (1, 2, 17, 200) for p in (0.2, 0.5, 0.9)] + [np.zeros(0, bool)]:
        runs = ndimage.label(row)[1]
        assert isoflow.euler_characteristic(row) == runs
        assert isoflow.betti_numbers(row) == [runs] == isoflow.betti_numbers(row, chi=runs)
        r = isoflow.analyze(row)
        assert r.betti == [runs] and r.euler_characteristic == runs and r.dimension == 1
        assert r.voxels == int(row.sum()) and r.a_dot_n == 2 * runs and r.classes["convex"] == 2 * runs
    import pytest

    with pytest.raises(isoflow.IsoflowError, match=r"^chi=2 is not this volume's Euler characteristic \(1 run\)"):
        isoflow.betti_numbers(np.ones(3, bool), chi=2)
    with pytest.raises(isoflow.IsoflowError, match=r"^connectivity 4 is not valid in 1D \(use 2\)"):
        isoflow.analyze(np.ones(3, bool), 4)


def test_the_repr_of_a_big_result_is_short_and_counts_what_it_leaves_out():
    # a noisy volume's report and census printed every one of its thousands
    # of surfaces (megabytes of repr), a long flow every step and state
    skimage_measure = pytest.importorskip("skimage.measure")
    noisy = np.random.default_rng(0).random((40, 40, 40)) < 0.3
    report, census = isoflow.analyze(noisy), isoflow.closed_surfaces(noisy)
    chi = skimage_measure.euler_number(noisy, connectivity=1)
    assert len(report.surfaces) > 1000 and len(census.surfaces) == len(report.surfaces)
    for result in (report, census):
        text = repr(result)
        assert len(text) < 3000 and f"... {len(result.surfaces) - 10} more]" in text
    assert f"euler_characteristic={chi}," in repr(report) and "n=[" in repr(report)
    z, y, x = np.mgrid[:40, :40, :40]
    flow = isoflow.run_flow((z - 20) ** 2 + (y - 20) ** 2 + (x - 20) ** 2 < 18**2)  # a ball: one step a layer
    assert len(flow.states) > 30 and len(repr(flow)) < 4000 and f"... {len(flow.states) - 10} more]" in repr(flow)
    # a small result's repr keeps every item: the nine classes of a 3D report
    box = isoflow.analyze(np.ones((2, 2, 2), bool))
    assert f"n={box.n}," in repr(box) and "more" not in repr(box)


@pytest.mark.parametrize(("pitch", "shown"), [
    (8.249e-11, "8.249e-11"), (1e-13, "1e-13"), (1e300, "1e+300"), (0.1 + 0.2, "0.3"), ((0.5, 1e-12, 2), "[0.5, 1e-12, 2.0]"),
])
def test_an_objects_repr_shows_its_pitch_to_twelve_significant_digits(pitch, shown):
    # 12 decimals showed 0.8249 Angstrom in metres as 8.2e-11 and 1e-13 as 0.0; 1e300 overflowed to inf
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # NumPy's "overflow encountered in multiply"
        text = repr(isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=pitch))
    assert f"pitch={shown}," in text


def test_analyze_zarr_places_an_ome_zarr_image_as_its_metadata_and_info_do(tmp_path, capsys):
    """``isoflow.analyze_zarr`` of an OME-Zarr image in millimetres gave its
    volume, area, box and centroid in voxels with no unit, where ``isoflow
    info STORE --json`` and ``analyze(read_volume(STORE))`` gave them in
    millimetres: the store's own scale, translation and axis unit place it
    now, and a value given replaces the store's. The store is written with
    zarr itself, the expected measures come from scikit-image's regionprops
    and the NGFF rule (scale per voxel, translation at voxel centres)."""
    zarr = pytest.importorskip("zarr")
    from skimage.measure import regionprops

    from isoflow.cli.main import main

    v = np.zeros((7, 6, 5), np.uint8)  # (x, y, z)
    v[1:6, 1:5, 1:4] = 1
    v[3, 2:4, 1:4] = 0  # a tunnel along z
    scale, shift = np.array([0.5, 0.25, 2.0]), np.array([10.0, -4.0, 1.0])  # (x, y, z)
    group = zarr.open_group(str(tmp_path / "img.zarr"), mode="w", zarr_format=2)
    group.create_array("0", data=np.ascontiguousarray(v.transpose(2, 1, 0)), chunks=(2, 3, 4))
    group.attrs["multiscales"] = [{
        "version": "0.4", "axes": [{"name": a, "type": "space", "unit": "millimeter"} for a in "zyx"],
        "datasets": [{"path": "0", "coordinateTransformations": [
            {"type": "scale", "scale": scale[::-1].tolist()}, {"type": "translation", "translation": shift[::-1].tolist()}]}]}]
    props = regionprops(v)[0]
    corner = shift - scale / 2  # the lowest corner of voxel 0
    want_box = np.concatenate([corner + scale * props.bbox[:3], corner + scale * props.bbox[3:]])
    want_centroid = shift + scale * np.asarray(props.centroid)

    report = isoflow.analyze_zarr(tmp_path / "img.zarr", 6)
    assert report.unit == "mm" and report.voxels == props.area
    assert report.volume == pytest.approx(props.area * scale.prod())
    np.testing.assert_allclose(report.bbox, want_box)
    np.testing.assert_allclose(report.centroid, want_centroid)
    assert report == isoflow.analyze(isoflow.read_volume(tmp_path / "img.zarr"), 6)
    capsys.readouterr()
    assert main(["info", str(tmp_path / "img.zarr"), "--json", "-q"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert {k: printed[k] for k in report} == report.to_dict()  # the same numbers under the same names

    given = isoflow.analyze_zarr(tmp_path / "img.zarr", 6, pitch=1.0, origin=(0, 0, 0))
    np.testing.assert_allclose(given.bbox, list(props.bbox))
    assert given.unit == "mm" and given.volume == props.area


@pytest.mark.parametrize("inside", ["0", "0/"])
def test_analyze_zarr_of_a_level_named_by_its_folder_is_refused_as_read_volume_refuses_it(tmp_path, inside):
    """``analyze_zarr("IMG.zarr/0")``, the level's folder inside an
    OME-Zarr image, read the array without the image's scale and unit:
    a cube of eight 0.5 mm voxels gave a volume of 8 (voxels, no unit)
    where its volume is 1 mm^3, in silence, while read_volume, read_labels
    and ``isoflow info`` refuse that path and name ``IMG.zarr:0``, which
    analyze_zarr reads placed."""
    pytest.importorskip("zarr")
    obj = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5, unit="mm")
    store = isoflow.write_volume(obj, tmp_path / "img.zarr")
    assert isoflow.analyze_zarr(f"{store}:0").volume == 8 * 0.5**3 == 1.0  # eight voxels of 0.125 mm^3
    for read in (isoflow.read_volume, isoflow.analyze_zarr):
        with pytest.raises(IsoflowError, match=re.escape(f"inside the zarr store {store}; name it as {store}:0")):
            read(f"{store}/{inside}")


def test_the_repr_of_a_small_mesh_or_label_image_is_one_short_line():
    """A notebook cell that ended in ``boundary_mesh(cube)`` printed every
    vertex and face of a small mesh (393 lines for a 4^3 cube: NumPy cuts
    an array only past 1000 numbers), and ``LabelImage`` every voxel of a
    small image. Their arrays are shown by shape and type, on one line,
    as a result's are kept short."""
    cube = np.ones((4, 4, 4), bool)
    text = repr(isoflow.boundary_mesh(cube, 6))
    # the boundary of a 4^3 cube: 5^3 - 3^3 lattice points, 6 * 4^2 squares
    assert "\n" not in text and len(text) < 400, text
    assert text.startswith("QuadMesh(vertices=array(..., shape=(98, 3), dtype=float64), faces=array(..., shape=(96, 4)")
    assert text.endswith("connectivity=6, pinched=0)")
    labels = np.arange(1000).reshape(10, 10, 10) % 5
    text = repr(isoflow.LabelImage(labels, np.full(3, 0.5), np.zeros(3), "mm"))
    assert "\n" not in text and len(text) < 200, text
    assert text == ("LabelImage(array=array(..., shape=(10, 10, 10), dtype=int64), spacing=array([0.5, 0.5, 0.5]), "
                    "origin=array([0., 0., 0.]), unit='mm', names=None, space=None)")


def test_a_label_image_of_nested_lists_holds_them_as_an_array():
    # the lists were kept: image.array.shape failed, and the repr printed every label
    cells = [[1, 1, 0], [0, 2, 2]]
    image = isoflow.LabelImage(cells, [0.5, 2.0], (0, 0))
    assert isinstance(image.array, np.ndarray) and image.array.shape == (2, 3)
    assert image.array.tolist() == cells
    assert repr(image).startswith("LabelImage(array=array(..., shape=(2, 3)")


def test_a_report_comes_back_from_what_info_json_printed(tmp_path, capsys):
    """``Report.from_dict`` of the object ``isoflow info FILE --json``
    printed refused it ("Report has no fields ['input', 'origin',
    'pitch']"): the keys the command adds about its input. It takes them
    now, and gives the report of the file in Python; a key that is neither
    a field nor one of the command's is still refused. The file is written
    with nibabel, its chi counted by scikit-image."""
    nibabel = pytest.importorskip("nibabel")
    from skimage.measure import euler_number

    from isoflow import data
    from isoflow.cli.main import main

    v = np.zeros((6, 5, 4), np.uint8)
    v[1:5, 1:4, 1:3] = 1
    v[2:4, 2, 1:3] = 0  # a tunnel
    nibabel.save(nibabel.Nifti1Image(v, np.diag([0.5, 0.5, 2.0, 1.0])), tmp_path / "ring.nii.gz")
    inputs = {str(tmp_path / "ring.nii.gz"): [], str(data.eight()): ["--resolution", "16"]}
    reports = []
    for path, options in inputs.items():
        capsys.readouterr()
        assert main(["info", path, *options, "--json", "-q"]) == 0
        printed = json.loads(capsys.readouterr().out)
        reports.append(isoflow.Report.from_dict(printed))
    ring, eight = reports
    assert ring == isoflow.analyze(isoflow.read_volume(tmp_path / "ring.nii.gz"))
    assert ring.euler_characteristic == euler_number(np.pad(v, 1), 1) == 0 and ring.volume == v.sum() * 0.5
    assert eight == isoflow.analyze(isoflow.voxelize_file(data.eight(), resolution=16)) and "voxelised" in printed
    with pytest.raises(TypeError, match=r"no fields \['genus_typo'\]"):
        isoflow.Report.from_dict({**printed, "genus_typo": 1})


def test_a_flow_result_comes_back_from_what_flow_json_printed(tmp_path, capsys):
    """``FlowResult.from_dict``, which says it reads ``isoflow flow
    --json``, refused what the command printed ("FlowResult has no fields
    ['input', 'unit']"). It takes the command's keys about its input now;
    step 0 is the file as nibabel and scikit-image read it."""
    nibabel = pytest.importorskip("nibabel")
    from skimage.measure import euler_number, regionprops

    from isoflow.cli.main import main

    v = np.zeros((7, 6, 5), np.uint8)
    v[1:6, 1:5, 1:4] = 1
    v[3, 2:4, 1:4] = 0  # a tunnel
    image = nibabel.Nifti1Image(v, np.diag([0.5, 0.25, 2.0, 1.0]))
    image.header.set_xyzt_units("mm")
    nibabel.save(image, tmp_path / "ring.nii.gz")
    assert main(["flow", str(tmp_path / "ring.nii.gz"), "--json", "-q"]) == 0
    printed = json.loads(capsys.readouterr().out)
    back = isoflow.FlowResult.from_dict(printed)
    assert back.to_dict() == isoflow.run_flow(isoflow.read_volume(tmp_path / "ring.nii.gz")).to_dict()
    first = back.steps[0]
    assert first["voxels"] == v.sum() and first["euler_characteristic"] == euler_number(np.pad(v, 1), 1) == 0
    box = np.array(regionprops(v)[0].bbox).reshape(2, 3) * [0.5, 0.25, 2.0] - np.array([0.5, 0.25, 2.0]) / 2
    np.testing.assert_allclose(first["bbox"], box.ravel())  # NIfTI places voxel centres: corner 0 is half a voxel lower
    with pytest.raises(TypeError, match=r"no fields \['steps_typo'\]"):
        isoflow.FlowResult.from_dict({**printed, "steps_typo": 1})


def test_a_flow_result_has_the_unit_that_flow_json_prints(tmp_path, capsys):
    """``isoflow flow --json`` printed ``unit`` but ``FlowResult`` had no
    such field, so Python could not tell the unit of the boxes it gave.
    The result holds it now, as nibabel reads the file's unit, and keeps it
    through ``to_dict`` and ``from_dict``."""
    nibabel = pytest.importorskip("nibabel")
    from isoflow.cli.main import main

    v = np.zeros((5, 5, 5), np.uint8)
    v[1:4, 1:4, 1:4] = 1
    image = nibabel.Nifti1Image(v, np.diag([0.5, 0.5, 0.5, 1.0]))
    image.header.set_xyzt_units("mm")
    nibabel.save(image, tmp_path / "cube.nii.gz")
    said = nibabel.load(tmp_path / "cube.nii.gz").header.get_xyzt_units()[0]
    assert main(["flow", str(tmp_path / "cube.nii.gz"), "--json", "-q"]) == 0
    printed = json.loads(capsys.readouterr().out)
    result = isoflow.run_flow(isoflow.read_volume(tmp_path / "cube.nii.gz"))
    assert printed["unit"] == result.unit == said == "mm"
    assert isoflow.FlowResult.from_dict(result.to_dict()).unit == said
    assert isoflow.run_flow(np.ones((2, 2, 2), bool)).unit is None


def test_an_object_answers_for_the_volume_it_was_given_after_the_caller_changes_its_array():
    """``DigitalObject(array)`` held the caller's bool array itself, so
    writing to the array afterwards changed the object's voxels and its
    report: the object holds the volume as it was given, and its voxels
    and Euler characteristic are those scikit-image gives of that volume."""
    from skimage.measure import euler_number

    rng = np.random.default_rng(5)
    volume = rng.random((9, 9, 9)) < 0.4
    given = volume.copy()
    obj = isoflow.DigitalObject(volume)
    flow = isoflow.run_flow(volume, max_steps=1)
    volume[...] = ~volume  # the caller reuses its array
    assert obj.voxels == np.count_nonzero(given) == flow.states[0].voxels
    assert isoflow.analyze(obj).euler_characteristic == euler_number(given, connectivity=1)  # 6-connectivity
    assert np.array_equal(flow.states[0].volume, given)
    assert obj.volume.flags.writeable is False


def test_an_object_answers_for_the_volume_it_was_given_after_the_owner_of_a_read_only_view_changes_it():
    """A read-only view of an array that its owner keeps writing (what a
    library hands out: ``a.view()`` made read-only, ``np.broadcast_to``,
    ``as_strided(..., writeable=False)``) was held as it was, not copied:
    the owner's writes changed the object's voxels, its flow and its
    report. The object, and a flow's first state, answer for the volume as
    it was given, as scikit-image and SciPy count it; a read-only array
    that owns its memory is still held without a copy."""
    from scipy import ndimage
    from skimage.measure import euler_number

    rng = np.random.default_rng(6)
    owner = rng.random((9, 9, 9)) < 0.4
    given = owner.copy()
    views = [owner.view(), np.broadcast_to(owner, owner.shape),
             np.lib.stride_tricks.as_strided(owner, writeable=False), owner[:, :, ::-1][:, :, ::-1]]
    for view in views:
        view.flags.writeable = False
    objects = [isoflow.DigitalObject(view) for view in views]
    flows = [isoflow.run_flow(view, max_steps=1) for view in views]
    owner[...] = ~owner  # the owner reuses its array
    for obj, flow in zip(objects, flows):
        assert obj.voxels == np.count_nonzero(given) == flow.states[0].voxels
        assert isoflow.analyze(obj).euler_characteristic == euler_number(given, connectivity=1)  # 6-connectivity
        assert isoflow.betti_numbers(obj.volume, 6)[0] == ndimage.label(given)[1]
        assert np.array_equal(flow.states[0].volume, given)
    kept = np.ones((3, 3, 3), bool)
    kept.flags.writeable = False
    assert np.shares_memory(isoflow.DigitalObject(kept).volume, kept)


def _peak_bytes(make):
    import gc
    import tracemalloc

    gc.collect()
    tracemalloc.start()
    try:
        made = make()
        return tracemalloc.get_traced_memory()[1], made
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("chunks", [64, 256])
def test_an_object_of_a_dask_array_holds_its_voxels_in_one_array(chunks):
    """``DigitalObject`` of a dask array computed it (one array of the
    volume) and then copied it (a second), as it copies memory a caller may
    still write: the computed array is made for the object, which holds it
    as it is. At most one bool volume and a few chunks at a time (dask's
    concatenation of the chunks was a second volume too); the object
    shares no memory with the array the dask array was made of, and keeps
    its voxels when that array is written."""
    da = pytest.importorskip("dask.array")
    n = 256
    given = np.zeros((n, n, n), bool)
    given[10:200, 20:100, 30:250] = True
    source = given.copy()
    lazy = da.from_array(source, chunks=chunks)  # (made before the count: dask hashes the array)
    isoflow.DigitalObject(lazy)  # dask's first computation keeps some memory of its own
    peak, obj = _peak_bytes(lambda: isoflow.DigitalObject(lazy))
    assert peak < 1.5 * given.nbytes, peak / given.nbytes
    assert not np.shares_memory(obj.volume, source) and obj.volume.flags.writeable is False
    source[...] = False  # the caller reuses its array
    assert obj.voxels == 190 * 80 * 220 == np.count_nonzero(given)
    assert np.array_equal(obj.volume, given)


@pytest.mark.parametrize("scheduler", ["synchronous", "threads", "processes"])
def test_an_object_of_a_dask_array_has_its_voxels_whichever_scheduler_computes_it(scheduler):
    # one that runs its tasks in other processes writes into no array of this one: read as NumPy reads it
    dask = pytest.importorskip("dask")
    da = pytest.importorskip("dask.array")
    volume = np.zeros((6, 7, 8), bool)
    volume[1:5, 2:6, 3:7] = True
    kept = da.from_delayed(dask.delayed(lambda: volume)(), volume.shape, bool)  # the task gives the array itself
    with dask.config.set(scheduler=scheduler):
        objects = [isoflow.DigitalObject(da.from_array(volume, chunks=3)), isoflow.DigitalObject(kept)]
    volume[...] = False
    for obj in objects:
        assert obj.voxels == 64 and not np.shares_memory(obj.volume, volume)


def test_a_dask_label_image_is_read_into_one_array_block_by_block(tmp_path):
    """A dask array that isoflow reads whole (write_labels, label_table,
    ...) was read by numpy.asarray: dask holds every computed block, then
    their concatenation, twice the image's bytes at the peak. Each block is
    now written into one array as it is computed: the image and a few
    blocks. The file written is the image, as numpy reads it back."""
    dask = pytest.importorskip("dask")
    da = pytest.importorskip("dask.array")
    zarr = pytest.importorskip("zarr")
    labels = np.zeros((128, 128, 128), np.uint8)
    labels[10:60, 10:60, 10:60] = 1
    labels[70:120, 5:100, 40:90] = 2
    store = zarr.open_array(tmp_path / "labels.zarr", mode="w", shape=labels.shape, chunks=(32,) * 3, dtype=np.uint8)
    store[:] = labels
    lazy = da.from_zarr(tmp_path / "labels.zarr")  # each block read from its file when computed
    isoflow.write_labels(lazy, tmp_path / "first.npy")  # the first computation imports the store's codecs
    # each thread holds a block or two being read: two threads, whatever the machine's cores, for a bound that
    # holds on any machine (every block and their concatenation was 2.1 times the image)
    with dask.config.set(scheduler="threads", num_workers=2):
        peak, _ = _peak_bytes(lambda: isoflow.write_labels(lazy, tmp_path / "labels.npy"))
    assert peak < 1.5 * labels.nbytes, peak / labels.nbytes
    assert np.array_equal(np.load(tmp_path / "labels.npy"), labels)


@pytest.mark.parametrize("dtype", [bool, np.uint8, np.uint32, np.float64])
@pytest.mark.parametrize(("shape", "chunks"), [((7, 11), (3, 4)), ((13, 5, 9), (4, 5, 2)), ((10, 3, 4), ((1, 6, 3), 2, 3))])
def test_a_dask_array_read_block_by_block_holds_what_numpy_reads(shape, chunks, dtype):
    # blocks that do not divide the shape, of uneven sizes, each in its place; whichever scheduler of threads runs them
    dask = pytest.importorskip("dask")
    da = pytest.importorskip("dask.array")
    from isoflow.scale.arrays import as_array

    values = (np.random.default_rng(7).random(shape) * 300).astype(dtype)
    lazy = da.from_array(values, chunks=chunks).map_blocks(np.copy, dtype=dtype)  # blocks computed, not views
    for scheduler in ("threads", "synchronous"):
        with dask.config.set(scheduler=scheduler):
            read = as_array(lazy)
        assert read.dtype == values.dtype and np.array_equal(read, np.asarray(lazy)) and np.array_equal(read, values)


class _Image:
    """An image class that hands ``np.asarray`` its own array, as an
    xarray DataArray of a NumPy array does."""

    def __init__(self, array):
        self.array = array

    def __array__(self, dtype=None, copy=None):
        return self.array if dtype is None else self.array.astype(dtype)


def test_an_object_given_an_image_that_holds_its_array_leaves_that_array_writeable_and_as_it_was():
    """``DigitalObject(image)`` of an object whose ``__array__`` gives its
    own bool array held that array uncopied and made it read-only: the
    caller's next write to its own array raised "assignment destination is
    read-only" (and write_volume, write_surface, run_flow, flow_step and
    to_manifold of such an image did the same). The caller's array stays
    writeable, and the object answers for the volume as it was given, as
    scikit-image counts it."""
    from skimage.measure import euler_number

    rng = np.random.default_rng(7)
    array = rng.random((8, 8, 8)) < 0.4
    given = array.copy()
    obj = isoflow.DigitalObject(_Image(array))
    flow = isoflow.run_flow(_Image(array), max_steps=1)
    isoflow.to_manifold(_Image(array), 26)
    assert array.flags.writeable
    array[...] = ~array  # the caller's own array, written as before
    assert obj.voxels == np.count_nonzero(given) == flow.states[0].voxels
    assert isoflow.analyze(obj).euler_characteristic == euler_number(given, connectivity=1)
    assert np.array_equal(flow.states[0].volume, given)


def test_results_and_objects_hold_read_only_arrays_when_made_and_when_unpickled():
    """A result and a digital object are frozen, but the arrays they held
    were writeable when made and again after ``pickle.loads`` (NumPy
    unpickles every array writeable): every array they hold is read-only,
    both ways, and the unpickled copy equals the original."""
    import pickle

    import trimesh

    box, other = trimesh.creation.box(), trimesh.creation.box().apply_translation([2, 0, 0])
    obj, voxelization = isoflow.voxelize_mesh(box, resolution=4, details=True)
    labels = isoflow.voxelize_meshes([box, other], resolution=8)
    flow = isoflow.run_flow(np.pad(np.ones((3, 3, 3), bool), 1))
    anisotropic = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=(0.5, 0.5, 2.0), origin=(1, 2, 3))
    for made in (obj, voxelization, labels, flow, anisotropic):
        back = pickle.loads(pickle.dumps(made))
        assert back == made
        for held in (made, back):
            arrays = [v for v in vars(held).values() if isinstance(v, np.ndarray)]
            arrays += [s.volume for s in getattr(held, "states", [])]
            assert arrays and all(a.flags.writeable is False for a in arrays), type(held).__name__


def test_a_label_images_voxel_size_cannot_be_changed_in_place():
    # frozen as its origin is: a write into the spacing would change every
    # world column of the table silently
    image = isoflow.LabelImage(np.ones((2, 2, 2), np.uint8), [1.0, 2.0, 3.0], [0.0, 0.0, 0.0])
    for field in (image.spacing, image.origin):
        with pytest.raises(ValueError, match="read-only"):
            field[0] = 5.0
    assert isoflow.label_table(image)["volume"].tolist() == [48.0]  # 8 voxels of 1 x 2 x 3


def test_voxelize_takes_a_pitch_of_one_number_in_an_array_as_the_object_does():
    import trimesh

    box = trimesh.creation.box()  # a unit cube: (1 / 0.25)^3 voxels
    for pitch in (np.array([0.25]), [0.25], (0.25,)):
        solid = isoflow.voxelize_mesh(box, pitch=pitch)
        assert solid.voxels == 64 and solid.pitch == 0.25
        assert isoflow.DigitalObject(np.ones((1, 1, 1), bool), pitch=pitch).pitch == 0.25
