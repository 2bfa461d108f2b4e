"""A GLB as other programs read it. MeshLab (pymeshlab): where ``surface``
stores voxel units under a node's transform, MeshLab keeps the transform
apart from the vertices, so the command says so and names the filter that
puts them in place; where the world positions are stored, it says nothing.
Blender: the turn formats.md gives undoes its importer's +Y up."""

import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

import isoflow
from isoflow.cli import main

pymeshlab = pytest.importorskip("pymeshlab")

ROOT = Path(__file__).resolve().parents[1]

#: name, voxel size, origin: a model far from the origin, a CT scan's
#: placement (millimetres), and one float32 holds to a millionth of a voxel
PLACEMENTS = [("far", (0.1, 0.2, 0.3), (4e6, -2e6, 1e6)),
              ("scan", (0.5, 0.5, 0.8), (-120.3, -200.7, 50.2)),
              ("near", (0.5, 0.5, 0.5), (1.0, 2.0, 3.0))]


def contacts(seed: int = 1) -> np.ndarray:
    """A random volume with edge and vertex contacts."""
    return np.random.default_rng(seed).random((6, 7, 5)) < 0.4


def world_box(mask: np.ndarray, pitch, origin) -> np.ndarray:
    """The world bounds of a mask's voxels, from its indices."""
    at = np.argwhere(mask)
    return np.asarray(origin) + np.asarray(pitch) * np.array([at.min(axis=0), at.max(axis=0) + 1])


def meshlab_boxes(path, freeze: bool = False) -> dict:
    """Each layer of a file as pymeshlab loads it: label -> the bounds of
    its vertices (after Freeze Current Matrix on every layer where
    ``freeze``)."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    if freeze:
        ms.apply_matrix_freeze(alllayers=True)
    boxes = {}
    for i in range(ms.mesh_number()):
        v = ms.mesh(i).vertex_matrix()
        boxes[ms.mesh(i).label()] = np.array([v.min(axis=0), v.max(axis=0)])
    return boxes


@pytest.mark.parametrize("name, pitch, origin", PLACEMENTS, ids=[p[0] for p in PLACEMENTS])
def test_surface_says_where_meshlab_reads_the_glb_in_voxel_units(tmp_path, capsys, name, pitch, origin):
    mask = contacts()
    isoflow.write_volume(isoflow.DigitalObject(mask, pitch=pitch, origin=origin), tmp_path / "v.npz")
    assert main(["surface", str(tmp_path / "v.npz"), "-o", str(tmp_path / "s.glb")]) == 0
    err = capsys.readouterr().err
    world = world_box(mask, pitch, origin)
    (box,) = meshlab_boxes(tmp_path / "s.glb").values()
    apart = not np.allclose(box, world, rtol=0, atol=1e-6 * min(pitch))
    assert apart == (name != "near")
    assert ("Freeze Current Matrix" in err) == apart, err
    (frozen,) = meshlab_boxes(tmp_path / "s.glb", freeze=True).values()
    assert np.allclose(frozen, world, rtol=0, atol=1e-6 * min(pitch))  # the filter the note names places it
    assert main(["surface", str(tmp_path / "v.npz"), "-o", str(tmp_path / "s.glb"), "--force", "-q"]) == 0
    assert "Freeze" not in capsys.readouterr().err


def test_surface_labels_says_meshlab_needs_every_layer_frozen(tmp_path, capsys):
    """pymeshlab opens every node of a label scene as a layer named as the
    node; the note asks for every layer, and each layer then lies at its
    label's voxels."""
    image = np.random.default_rng(3).integers(0, 4, (8, 9, 7)).astype(np.uint8)
    pitch, origin = (0.1, 0.2, 0.3), (1e6, 0.0, 0.0)
    isoflow.write_labels(image, tmp_path / "seg.nrrd", pitch=pitch, origin=origin)
    assert main(["surface", str(tmp_path / "seg.nrrd"), "--labels", "-o", str(tmp_path / "seg.glb")]) == 0
    err = capsys.readouterr().err
    assert "Freeze Current Matrix with Apply to all visible Layers" in err and "all 3 nodes" in err, err
    boxes = meshlab_boxes(tmp_path / "seg.glb", freeze=True)
    assert sorted(boxes) == ["label_1", "label_2", "label_3"]
    for label in (1, 2, 3):
        assert np.allclose(boxes[f"label_{label}"], world_box(image == label, pitch, origin), rtol=0, atol=1e-7)
    assert main(["surface", str(tmp_path / "seg.nrrd"), "--labels", "-o", str(tmp_path / "out") + "/",
                 "--suffix", ".glb"]) == 0
    err = capsys.readouterr().err
    assert "all 3 files" in err and "Freeze Current Matrix (pymeshlab" in err, err
    (box,) = meshlab_boxes(tmp_path / "out" / "label_2.glb", freeze=True).values()
    assert np.allclose(box, world_box(image == 2, pitch, origin), rtol=0, atol=1e-7)


def test_the_turn_formats_md_gives_blender_puts_the_glb_back(tmp_path):
    """Blender's importer puts a glTF point (x, y, z) at (x, -z, y) and a
    node's matrix M at C M C^T (C that swizzle, glTF-Blender-IO's
    ``locs_yup_to_zup``); the turn formats.md gives, -90 degrees about x
    on the objects' world matrices, gives back the positions trimesh reads,
    a node's transform (far) or none (near) alike."""
    text = " ".join((ROOT / "docs" / "formats.md").read_text().split())
    assert 'o.matrix_world = Matrix.Rotation(-pi / 2, 4, "X") @ o.matrix_world' in text
    swizzle = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
    turn = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]])  # Matrix.Rotation(-pi/2, 4, "X")
    for name, pitch, origin in PLACEMENTS:
        isoflow.write_volume(isoflow.DigitalObject(contacts(), pitch=pitch, origin=origin), tmp_path / f"{name}.npz")
        path = tmp_path / f"{name}.glb"
        assert main(["surface", str(tmp_path / f"{name}.npz"), "-o", str(path), "-q", "--no-check"]) == 0
        scene = trimesh.load(path, process=False)
        (node,) = scene.graph.nodes_geometry
        matrix, geometry = scene.graph[node]
        local = np.column_stack([scene.geometry[geometry].vertices, np.ones(len(scene.geometry[geometry].vertices))])
        in_blender = (swizzle @ matrix @ swizzle.T) @ (swizzle @ local.T)
        back = (turn @ in_blender).T[:, :3]
        world = trimesh.load(path, force="mesh", process=False).vertices
        assert np.allclose(back, world, rtol=1e-12, atol=0)
        assert not np.allclose(in_blender.T[:, :3], world, rtol=1e-12, atol=0)  # the import alone turns it


def blender_srgb(stored: np.ndarray) -> np.ndarray:
    """A GLB's COLOR_0 bytes as Blender shows them: glTF's linear values
    turned to sRGB (glTF-Blender-IO's ``colors_linear_to_srgb``), in bytes."""
    c = np.asarray(stored, np.float64) / 255.0
    srgb = np.where(c >= 0.0031308, 1.055 * np.power(c, 1.0 / 2.4) - 0.055, c * 12.92)
    return np.round(255.0 * srgb).astype(np.int64)


def by_place(vertices, colours) -> np.ndarray:
    """Colours in the order of their vertices' positions (and colours):
    two files of one surface side by side, whatever their vertex order."""
    rows = np.column_stack([np.asarray(vertices, np.float64), colours])
    return rows[np.lexsort(rows.T[::-1])][:, 3:]


def test_the_glb_colours_are_the_ply_colours_once_blender_reads_them(tmp_path):
    """glTF's COLOR_0 is linear, and Blender's importer turns it to sRGB
    for display: the GLB's colours, so turned, are the PLY's (sRGB bytes,
    as PLY readers show them) to 2 of 255 (8 bits of linear), for one
    surface and for a label scene's nodes."""
    pitch, origin = (0.5, 0.5, 0.5), (1.0, 2.0, 3.0)  # float32 holds it: world positions in both files
    isoflow.write_volume(isoflow.DigitalObject(contacts(), pitch=pitch, origin=origin), tmp_path / "v.npz")
    image = np.random.default_rng(3).integers(0, 3, (6, 5, 7)).astype(np.uint8)
    isoflow.write_labels(image, tmp_path / "seg.nrrd", pitch=pitch, origin=origin)
    for out in ("s.ply", "s.glb"):
        assert main(["surface", str(tmp_path / "v.npz"), "-o", str(tmp_path / out), "-q"]) == 0
    assert main(["surface", str(tmp_path / "seg.nrrd"), "--labels", "-o", str(tmp_path / "seg.glb"), "-q"]) == 0
    assert main(["surface", str(tmp_path / "seg.nrrd"), "--labels", "-o", str(tmp_path / "ply") + "/", "--suffix", ".ply",
                 "-q"]) == 0
    pairs = [(tmp_path / "s.ply", tmp_path / "s.glb", None)]
    pairs += [(tmp_path / "ply" / f"label_{k}.ply", tmp_path / "seg.glb", f"label_{k}") for k in (1, 2)]
    for ply_path, glb_path, node in pairs:
        ply = trimesh.load(ply_path, process=False)
        scene = trimesh.load(glb_path, process=False)
        glb = scene.geometry[scene.graph[node][1]] if node else next(iter(scene.geometry.values()))
        want = by_place(ply.vertices, ply.visual.vertex_colors[:, :3])
        shown = by_place(glb.vertices, blender_srgb(glb.visual.vertex_colors[:, :3]))
        assert len(np.unique(want, axis=0)) > 2 and np.abs(shown - want).max() <= 2, (ply_path.name, node)


#: placements whose GLB node transform float32 cannot hold: a voxel size
#: past its largest number, one it makes 0, a corner past its range
BEYOND_FLOAT32 = [(1e150, 0.0), (1e-150, 0.0), (1e36, 1e43)]


@pytest.mark.parametrize("pitch, origin", BEYOND_FLOAT32, ids=["1e150", "1e-150", "at 1e43"])
def test_a_glb_placed_beyond_float32_says_which_readers_cannot_place_it(tmp_path, capsys, pitch, origin):
    """Blender, web viewers and the Khronos validator hold a node's matrix
    in float32 (the validator finds one past float32 not decomposable to
    TRS: NODE_MATRIX_NON_TRS), trimesh in float64: the GLB is written, as
    trimesh reads it where its voxels are, and the note says which readers
    cannot place it and names the files that keep the positions."""
    mask = contacts()
    isoflow.write_volume(isoflow.DigitalObject(mask, pitch=pitch, origin=(origin, 0.0, 0.0)), tmp_path / "v.npz")
    assert main(["surface", str(tmp_path / "v.npz"), "-o", str(tmp_path / "s.glb")]) == 0
    err = capsys.readouterr().err
    assert "the Khronos validator hold the transform in float32" in err and "write .ply or .obj" in err, err
    with np.errstate(over="ignore", under="ignore"):  # trimesh's determinant of the matrix
        scene = trimesh.load(tmp_path / "s.glb", process=False)
        matrix = scene.graph[next(iter(scene.graph.nodes_geometry))][0]
        held = matrix.astype(np.float32)
        bounds = trimesh.load(tmp_path / "s.glb", force="mesh", process=False).bounds
    assert not (np.all(np.isfinite(held)) and np.all(np.diag(held)[:3] != 0))  # what float32 readers get
    assert np.allclose(bounds, world_box(mask, pitch, (origin, 0.0, 0.0)), rtol=1e-12, atol=0)
    isoflow.write_labels(mask.astype(np.uint8) * 2, tmp_path / "seg.nrrd", pitch=pitch, origin=(origin, 0.0, 0.0))
    assert main(["surface", str(tmp_path / "seg.nrrd"), "--labels", "-o", str(tmp_path / "seg.glb")]) == 0
    assert "hold the transform in float32" in capsys.readouterr().err


def test_a_glb_placed_within_float32_holds_a_matrix_float32_keeps(tmp_path, capsys):
    """At a voxel size of 1e30 from 1e38 (float32's range, but not its
    precision there) the node's matrix is written, every entry a finite
    float32 and the voxel size nonzero in it, and the note says nothing of
    float32 readers."""
    isoflow.write_volume(isoflow.DigitalObject(contacts(), pitch=1e30, origin=(1e38, 0.0, 0.0)), tmp_path / "v.npz")
    assert main(["surface", str(tmp_path / "v.npz"), "-o", str(tmp_path / "s.glb")]) == 0
    err = capsys.readouterr().err
    assert "Freeze Current Matrix" in err and "Khronos" not in err, err
    scene = trimesh.load(tmp_path / "s.glb", process=False)
    matrix = scene.graph[next(iter(scene.graph.nodes_geometry))][0]
    with np.errstate(over="ignore"):
        held = matrix.astype(np.float32)
    assert np.all(np.isfinite(held)) and np.all(np.diag(held)[:3] != 0) and matrix[0, 0] == 1e30


def test_label_surfaces_of_huge_voxels_print_no_numpy_warning(tmp_path, capsys):
    """A label image of voxels of 1e150 (volumes past float64) printed
    NumPy's "overflow encountered in reduce" (and, to a .glb, "in cast")
    on the terminal under ``surface --labels`` and ``info --labels``; each
    label's PLY is still where its voxels are, as trimesh reads it."""
    image = contacts().astype(np.uint8) * 2
    isoflow.write_labels(image, tmp_path / "seg.nrrd", pitch=1e150)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # a warning NumPy would print is an error here
        assert main(["surface", str(tmp_path / "seg.nrrd"), "--labels", "-o", str(tmp_path / "out") + "/",
                     "--suffix", ".ply", "-q"]) == 0
        assert main(["info", str(tmp_path / "seg.nrrd"), "--labels"]) == 0
        assert main(["surface", str(tmp_path / "seg.nrrd"), "--labels", "-o", str(tmp_path / "seg.glb"), "-q"]) == 0
    assert capsys.readouterr().err == ""
    bounds = trimesh.load(tmp_path / "out" / "label_2.ply", process=False).bounds
    assert np.allclose(bounds, world_box(image == 2, 1e150, (0.0, 0.0, 0.0)), rtol=1e-12, atol=0)


def glb_json(path) -> dict:
    """The JSON chunk of a GLB, read by the spec's layout: a 12-byte
    header, then the chunk's length, its type "JSON" and its bytes."""
    import json
    import struct

    data = Path(path).read_bytes()
    length, kind = struct.unpack_from("<I4s", data, 12)
    assert data[:4] == b"glTF" and kind == b"JSON"
    return json.loads(data[20:20 + length])


@pytest.mark.parametrize("name", ["bob_small.nii.gz", "bob_small.npz"])
def test_a_surface_glb_node_is_named_after_its_input(tmp_path, capsys, name):
    # the node was trimesh's default "geometry_0", Blender's object name
    pytest.importorskip("nibabel")
    mask = contacts()
    isoflow.write_volume(isoflow.DigitalObject(mask, pitch=(0.5, 0.5, 0.5)), tmp_path / name)
    assert main(["surface", str(tmp_path / name), "-o", str(tmp_path / "s.glb"), "-q"]) == 0
    doc = glb_json(tmp_path / "s.glb")
    assert [n["name"] for n in doc["nodes"]] == ["bob_small"] == [m["name"] for m in doc["meshes"]]
    scene = trimesh.load(tmp_path / "s.glb")
    assert list(scene.geometry) == ["bob_small"] and scene.graph.nodes_geometry == ["bob_small"]
    assert list(meshlab_boxes(tmp_path / "s.glb")) == ["bob_small"]  # MeshLab's layer name
    # written from Python, the node is named after the file written
    isoflow.write_surface(isoflow.DigitalObject(mask), tmp_path / "part.glb")
    assert [n["name"] for n in glb_json(tmp_path / "part.glb")["nodes"]] == ["part"]
