"""``isoflow voxelize A B C -o LABELS`` as run (issue 25 item 6): the label
image written in every format and read back by isoflow and by the format's
own library (labels, pitch, origin), the overlap note and ``--overlap
error``, ``--split`` of a multi-body STL and of a glTF scene, and ``info
--labels`` on the result against each mesh's own voxelisation."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from in_process import isoflow_here
from test_input_errors import fails  # one line on stderr, exit 2

from isoflow import analyze
from isoflow.cli import main
from isoflow.mesh.load import load_mesh
from isoflow.mesh.volumes import read_labels, read_volume
from isoflow.mesh.voxelize import voxelize

ROOT = Path(__file__).resolve().parents[1]
TORUS = ROOT / "meshes" / "torus.obj"


def ball(tmp_path, name, radius, centre):
    s = trimesh.creation.icosphere(3, radius)
    s.apply_translation(centre)
    s.export(tmp_path / name)
    return tmp_path / name


def alone(path, pitch, origin, shape):
    return voxelize(*load_mesh(path), pitch=pitch, grid=(origin, shape), details=True).volume


@pytest.fixture
def overlapping(tmp_path):
    return ball(tmp_path, "a.stl", 1.0, (0, 0, 0)), ball(tmp_path, "b.obj", 0.8, (1.1, 0.3, -0.2))


def test_two_overlapping_meshes_into_nifti_read_back_by_nibabel(tmp_path, capsys, overlapping):
    import nibabel as nib

    a, b = overlapping
    out = tmp_path / "labels.nii.gz"
    assert main(["voxelize", str(a), str(b), "--resolution", "40", "-o", str(out)]) == 0
    printed, err = capsys.readouterr()
    img = nib.load(out)
    labels = np.asarray(img.dataobj)
    assert img.get_data_dtype() == np.uint8 and set(np.unique(labels)) == {0, 1, 2}
    pitch = np.asarray(img.header.get_zooms()[:3], float)
    origin = img.affine[:3, 3] - pitch / 2  # the affine places voxel 0's centre
    A, B = (alone(p, float(pitch[0]), origin, labels.shape) for p in (a, b))
    assert np.array_equal(labels == 2, B) and np.array_equal(labels == 1, A & ~B)  # the later mesh wins
    shared = int((A & B).sum())
    assert f"note: {out}: {shared} voxels lie inside two or more meshes (labels 1 and 2: {shared})" in err
    assert f"{out}: 2 labels in a {'x'.join(map(str, labels.shape))} grid (uint8)" in printed
    assert f"{int((A & ~B).sum()):,}  {a}" in printed and f"{int(B.sum()):,}  {b}" in printed
    back = read_labels(out)  # isoflow's reader: the same array, pitch and origin
    assert np.array_equal(back.array, labels) and np.allclose(back.spacing, pitch) and np.allclose(back.origin, origin)
    assert np.array_equal(read_volume(out, label=2).volume, B)


def test_overlap_error_refuses_in_one_line_and_writes_nothing(tmp_path, capsys, overlapping):
    a, b = overlapping
    out = tmp_path / "labels.nii.gz"
    line = fails(capsys, "voxelize", a, b, "--resolution", "40", "--overlap", "error", "-o", out,
                 words=("the meshes overlap", "voxels lie inside two or more meshes (labels 1 and 2: "))
    assert not out.exists() and "--overlap later" in line
    # nothing is listed: the line says which mesh each label is (it named numbers alone)
    assert f"), label 1 {a}, 2 {b}; " in line, line
    assert main(["voxelize", str(a), str(b), "--resolution", "40", "-o", str(out)]) == 0
    capsys.readouterr()
    fails(capsys, "voxelize", a, b, "--resolution", "40", "-o", out, words=("exists",))  # no --force


@pytest.mark.parametrize("suffix", [".npz", ".nrrd", ".h5", ".tif", ".zarr", ".vox"])
def test_every_format_keeps_the_labels_and_its_library_reads_them(tmp_path, capsys, overlapping, suffix):
    a, b = overlapping
    out = tmp_path / f"labels{suffix}"
    assert main(["voxelize", str(a), str(b), "--resolution", "24", "-o", str(out)]) == 0
    capsys.readouterr()
    back = read_labels(out)
    assert back.array.dtype == np.uint8 and set(np.unique(back.array)) == {0, 1, 2}
    ref = tmp_path / "ref.npz"
    assert main(["voxelize", str(a), str(b), "--resolution", "24", "-o", str(ref)]) == 0
    capsys.readouterr()
    ref = read_labels(ref)
    assert np.array_equal(back.array, ref.array)
    if suffix == ".nrrd":
        import nrrd

        data, header = nrrd.read(str(out), index_order="F")
        assert np.array_equal(data, ref.array) and np.allclose(np.diag(header["space directions"]), ref.spacing)
    elif suffix == ".h5":
        import h5py

        with h5py.File(out) as f:
            ds = f[next(iter(f))]
            assert np.array_equal(ds[()], ref.array) and np.allclose(ds.attrs["origin"], ref.origin)
    elif suffix == ".tif":
        import tifffile

        assert np.array_equal(tifffile.imread(out).T, ref.array)
    elif suffix in (".npz", ".zarr"):
        assert np.allclose(back.spacing, ref.spacing) and np.allclose(back.origin, ref.origin)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint32, np.uint64])
def test_write_labels_keeps_the_type_in_nifti_and_nibabel_reads_it(tmp_path, dtype):
    """write_labels writes a label image "in its own integer type": 64-bit
    labels too (nibabel refused uint64 data unless its type is named, a
    ValueError out of write_labels)."""
    nib = pytest.importorskip("nibabel")
    from isoflow import write_labels

    labels = np.zeros((4, 3, 2), dtype)
    labels[1, 1, 1], labels[3, 2, 1] = 1, np.iinfo(dtype).max
    path = write_labels(labels, tmp_path / "l.nii.gz", pitch=(0.5, 1.0, 2.0), origin=(1, 2, 3))
    image = nib.load(path)
    assert image.get_data_dtype() == dtype and np.array_equal(np.asarray(image.dataobj), labels)
    assert [float(z) for z in image.header.get_zooms()] == [0.5, 1.0, 2.0]
    back = read_labels(path)
    assert np.array_equal(back.array, labels) and back.origin.tolist() == [1.0, 2.0, 3.0]


@pytest.mark.parametrize("dtype", [np.int16, np.int32, ">i4", np.int64])
def test_a_signed_label_image_read_from_nifti_is_written_back(tmp_path, dtype):
    # read_labels gives an int16 or int32 NIfTI's labels (and scipy.ndimage.label makes them) signed, which
    # write_labels refused ("unsigned integers, got 3D int32"); written as the unsigned type of their width
    nib = pytest.importorskip("nibabel")
    from scipy import ndimage

    from isoflow import label_table, write_labels
    from isoflow.errors import IsoflowError

    mask = np.zeros((6, 5, 4), bool)
    mask[0:2, 0:2, 0:2] = mask[3:6, 2:5, 1:4] = True
    cells = ndimage.label(mask)[0].astype(dtype)
    native = np.dtype(dtype).newbyteorder("=")
    nib.save(nib.Nifti1Image(cells.astype(native), np.diag([0.5, 1.0, 2.0, 1.0]), dtype=native), tmp_path / "seg.nii.gz")
    image = read_labels(tmp_path / "seg.nii.gz")
    assert image.array.dtype.kind == "i"
    path = write_labels(image.array, tmp_path / "back.nii.gz", pitch=image.spacing, origin=image.origin)
    written = nib.load(path)
    assert written.get_data_dtype() == np.dtype(np.dtype(dtype).str.replace("i", "u")).newbyteorder("=")
    back = read_labels(path)
    assert np.array_equal(back.array, cells) and back.spacing.tolist() == [0.5, 1.0, 2.0]
    assert label_table(back)["voxels"].tolist() == [8, 27]
    with pytest.raises(IsoflowError, match="holds labels from 0 on, this one holds -1"):
        write_labels(cells - 1, tmp_path / "negative.nii.gz")
    assert not (tmp_path / "negative.nii.gz").exists()


def test_a_format_that_keeps_fewer_labels_is_refused_before_any_work(tmp_path, capsys, overlapping):
    a, b = overlapping
    fails(capsys, "voxelize", a, b, "--resolution", "24", "-o", tmp_path / "l.binvox",
          words=("binvox keeps one label", "write .nii.gz"))
    assert not (tmp_path / "l.binvox").exists()


def test_split_of_a_multi_body_stl_gives_a_label_per_body(tmp_path, capsys):
    parts = []
    for k in range(5):
        s = trimesh.creation.icosphere(2, 0.4)
        s.apply_translation((k, 0.2 * k * k, 0))
        parts.append(s)
    path = tmp_path / "bodies.stl"
    trimesh.util.concatenate(parts).export(path)
    bodies = len(trimesh.load(path).split(only_watertight=False))
    out = tmp_path / "bodies.npz"
    assert main(["voxelize", str(path), "--split", "--resolution", "48", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    labels = read_labels(out).array
    assert bodies == 5 and set(np.unique(labels)) == set(range(bodies + 1))
    assert f"{bodies} labels" in printed and f"{path}:{bodies}" in printed
    # one body: one label, in the singular
    one = tmp_path / "one.stl"
    parts[0].export(one)
    assert len(trimesh.load(one).split(only_watertight=False)) == 1
    assert main(["voxelize", str(one), "--split", "--resolution", "8", "-o", str(tmp_path / "one.npz")]) == 0
    assert capsys.readouterr().out.startswith(f"{tmp_path / 'one.npz'}: 1 label in a ")


def test_split_of_a_soup_whose_corners_were_rounded_apart_gives_a_label_per_solid(tmp_path, capsys, rng):
    """Two icospheres written face by face, each copy of a corner moved by
    ~1e-8 of the diagonal (rounded apart): one label per sphere, as
    trimesh counts after merging vertices to 6 digits (the corners are
    first put on that grid, so its rounding joins every copy), each of the
    welded sphere's voxels; the welded spheres give the same labels."""
    spheres = [trimesh.creation.icosphere(3).apply_translation(t) for t in ((0, 0, 0), (3, 0, 0))]
    welded = trimesh.util.concatenate(spheres)
    welded.vertices = np.round(welded.vertices, 6)
    soup = welded.vertices[welded.faces].reshape(-1, 3)
    soup = soup + rng.uniform(-1e-8, 1e-8, soup.shape) * np.linalg.norm(welded.extents)
    path, exact = tmp_path / "soup.ply", tmp_path / "exact.ply"
    trimesh.Trimesh(soup, np.arange(len(soup)).reshape(-1, 3), process=False).export(path)
    welded.export(exact)
    read = trimesh.load(path, process=False)
    assert len(np.unique(read.vertices, axis=0)) > 3 * len(welded.vertices)  # the copies of a corner mostly apart
    read.merge_vertices(digits_vertex=6)
    bodies = len(read.split(only_watertight=False))
    assert bodies == 2
    counts = {}
    for name, mesh in (("soup", path), ("exact", exact)):
        out = tmp_path / f"{name}.npz"
        assert main(["voxelize", str(mesh), "--split", "--resolution", "48", "-o", str(out)]) == 0
        assert f"{bodies} labels" in capsys.readouterr().out
        counts[name] = np.bincount(read_labels(out).array.ravel())
    assert len(counts["exact"]) == bodies + 1 and counts["exact"][1:].min() > 0
    assert counts["soup"].tolist() == counts["exact"].tolist()


def test_split_parts_two_boxes_that_touch_along_an_edge(tmp_path, capsys):
    """Two unit cubes sharing an edge (an STL of them, welded when read):
    a label each, of one cube's voxels each."""
    boxes = [trimesh.creation.box().apply_translation(t) for t in ((0, 0, 0), (1, 1, 0))]
    path = tmp_path / "two_boxes.stl"
    trimesh.util.concatenate(boxes).export(path)
    out = tmp_path / "l.npz"
    assert main(["voxelize", str(path), "--split", "--resolution", "16", "-o", str(out)]) == 0
    assert "2 labels" in capsys.readouterr().out
    labels = read_labels(out).array
    counts = np.bincount(labels.ravel())
    assert len(counts) == 3 and counts[1] == counts[2] == 8**3  # a cube of 8 voxels a side (pitch 1/8)


def test_split_of_a_glb_scene_by_node_and_info_labels_chi(tmp_path, capsys):
    """A scene of named nodes: a torus (chi 0), a ball and a box; info
    --labels on the label image gives each label the Euler characteristic
    of the node's mesh voxelised alone on the same grid."""
    torus = trimesh.load(TORUS, force="mesh")
    torus.apply_scale(1 / torus.extents.max())
    scene = trimesh.Scene()
    scene.add_geometry(torus, node_name="ring", geom_name="torus")
    scene.add_geometry(trimesh.creation.icosphere(3, 0.3), node_name="ball", geom_name="ball",
                       transform=trimesh.transformations.translation_matrix([1.2, 0, 0]))
    scene.add_geometry(trimesh.creation.box((0.4, 0.5, 0.6)), node_name="crate", geom_name="crate",
                       transform=trimesh.transformations.translation_matrix([0, 1.1, 0]))
    path = tmp_path / "scene.glb"
    scene.export(path)
    out = tmp_path / "scene.nii.gz"
    assert main(["voxelize", str(path), "--split", "--resolution", "64", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    rows = [line.split() for line in printed.splitlines()[2:]]
    assert [r[2] for r in rows] == [f"{path}:ring", f"{path}:ball", f"{path}:crate"]  # the file's order
    image = read_labels(out)
    report = json.loads(_run(capsys, "info", out, "--labels", "--json"))
    chis = {row["label"]: row["euler_characteristic"] for row in report["labels"]}
    for label, node in enumerate(("ring", "ball", "crate"), 1):
        transform, geometry = scene.graph[node]
        mesh = scene.geometry[geometry].copy().apply_transform(transform)
        own = voxelize(mesh.vertices, mesh.faces, pitch=float(image.spacing[0]), grid=(image.origin, image.array.shape),
                       details=True).volume
        assert np.array_equal(image.array == label, own), node
        assert chis[label] == analyze(np.pad(own, 1))["euler_characteristic"], node
    assert chis == {1: 0, 2: 1, 3: 1}  # a solid torus, a solid ball and box


def test_fill_applies_to_every_mesh(tmp_path, capsys):
    panel = ROOT / "tests" / "mesh" / "data" / "panel.obj"
    box = tmp_path / "box.stl"
    trimesh.creation.box((1, 1, 1)).apply_translation((0, 0, 3)).export(box)
    out = tmp_path / "l.npz"
    assert main(["voxelize", str(panel), str(box), "--resolution", "32", "--fill", "shell", "-o", str(out)]) == 0
    capsys.readouterr()
    image = read_labels(out)
    for label, path in enumerate((panel, box), 1):
        shell = voxelize(*load_mesh(path), pitch=float(image.spacing[0]), grid=(image.origin, image.array.shape),
                         fill="shell", details=True).volume
        assert shell.any() and np.array_equal(image.array == label, shell)


def test_the_command_in_a_subprocess(tmp_path, overlapping):
    a, b = overlapping
    out = tmp_path / "l.nrrd"
    p = isoflow_here("voxelize", str(a), str(b), "--pitch", "0.1", "-o", str(out))
    assert p.returncode == 0, p.stderr
    assert "2 labels" in p.stdout and "inside two or more meshes" in p.stderr
    assert read_labels(out).spacing.tolist() == [0.1, 0.1, 0.1]


def _run(capsys, *args):
    assert main([*map(str, args)]) == 0, capsys.readouterr().err
    return capsys.readouterr().out


def test_overlap_error_on_one_mesh_is_refused_and_with_split_compares_its_bodies(tmp_path):
    """``--overlap error`` on one mesh was silently ignored: a mesh of two
    overlapping balls was written as their union, the check asked for never
    made. It is refused (naming --split and --strict) before the mesh is
    read; with --split it compares the mesh's bodies; --overlap later, the
    default, stays accepted with one mesh."""
    a, b = trimesh.creation.icosphere(3, 1.0), trimesh.creation.icosphere(3, 0.8)
    b.apply_translation((1.1, 0.3, -0.2))
    both = tmp_path / "two.obj"
    trimesh.util.concatenate([a, b]).export(both)
    out = tmp_path / "o.npz"

    def run(*args):
        return isoflow_here("voxelize", str(both), "--resolution", "20",
                               "-o", str(out), *args)

    p = run("--overlap", "error")
    assert p.returncode == 2 and not out.exists(), p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert "--overlap error compares several meshes" in line and "--split" in line and "--strict" in line
    p = run("--overlap", "error", "--split")
    assert p.returncode == 2 and not out.exists()
    # the labels are the file's bodies, and are said to be (the shell said "meshes", as for files given)
    assert "the bodies overlap" in p.stderr and "(labels 1 and 2: " in p.stderr and "meshes" not in p.stderr
    p = run("--overlap", "later")
    assert p.returncode == 0 and out.exists(), p.stderr
    p = run("--split", "--force")
    assert p.returncode == 0 and "inside two or more bodies" in p.stderr and "later body's label wins" in p.stderr


def test_split_of_a_glb_labels_its_nodes_in_the_files_order(tmp_path, capsys):
    """``voxelize scene.glb --split`` gave the labels in the order of the
    node names: nodes written ``b``, ``a``, ``c`` came out as labels 1 =
    ``a``, 2 = ``b``. Label i is the file's i-th node (the order of the
    GLB's JSON chunk, read here without isoflow or trimesh's graph), the
    printed table names it, and its voxels lie in that node's box as
    trimesh places it."""
    import struct

    scene = trimesh.Scene()
    for x, name in enumerate(("b", "a", "c")):
        scene.add_geometry(trimesh.creation.box((1, 1, 1)), node_name=name, geom_name=f"box_{name}",
                           transform=trimesh.transformations.translation_matrix([3.0 * x, 0, 0]))
    path, out = tmp_path / "scene.glb", tmp_path / "labels.npz"
    scene.export(path)
    data = path.read_bytes()
    length = struct.unpack_from("<I", data, 12)[0]
    nodes = [node["name"] for node in json.loads(data[20:20 + length])["nodes"]]
    assert nodes == ["b", "a", "c"]  # the file's order, which sorting the names would change
    table = _run(capsys, "voxelize", path, "--split", "--pitch", "0.25", "-o", out)
    rows = [line.split() for line in table.splitlines() if line.split()[:1] in (["1"], ["2"], ["3"])]
    assert [(int(r[0]), r[-1]) for r in rows] == [(i, f"{path}:{n}") for i, n in enumerate(nodes, 1)]
    saved = np.load(out)  # NumPy's reading of the file: the labels, the pitch and the origin
    labels, pitch, origin = saved["volume"], float(saved["pitch"]), saved["origin"]
    reread = trimesh.load_scene(path)
    for i, name in enumerate(nodes, 1):
        centre = origin + pitch * (np.argwhere(labels == i).mean(0) + 0.5)
        lo, hi = reread.geometry[reread.graph[name][1]].copy().apply_transform(reread.graph[name][0]).bounds
        assert np.all(lo <= centre) and np.all(centre <= hi), (i, name, centre)


def _glb(path, nodes, meshes):
    """A GLB written by hand: ``nodes`` of ``(name, mesh index,
    translation)``, ``meshes`` each a list of primitives ``(vertices,
    faces)`` (trimesh writes one primitive per mesh, so it cannot make
    such a file)."""
    import struct

    blob, views, accessors, gltf_meshes = b"", [], [], []
    for primitives in meshes:
        written = []
        for v, f in primitives:
            for array, kind, component in ((np.asarray(v, np.float32), "VEC3", 5126),
                                           (np.asarray(f, np.uint32).ravel(), "SCALAR", 5125)):
                views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": array.nbytes})
                accessor = {"bufferView": len(views) - 1, "componentType": component, "count": len(array), "type": kind}
                if kind == "VEC3":
                    accessor.update(min=array.min(0).tolist(), max=array.max(0).tolist())
                accessors.append(accessor)
                blob += array.tobytes()
            written.append({"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1})
        gltf_meshes.append({"primitives": written})
    header = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}],
              "nodes": [{"name": n, "mesh": m, "translation": t} for n, m, t in nodes], "meshes": gltf_meshes,
              "buffers": [{"byteLength": len(blob)}], "bufferViews": views, "accessors": accessors}
    text = json.dumps(header).encode()
    text += b" " * (-len(text) % 4)
    path.write_bytes(b"glTF" + struct.pack("<II", 2, 28 + len(text) + len(blob)) + struct.pack("<I", len(text))
                     + b"JSON" + text + struct.pack("<I", len(blob)) + b"BIN\0" + blob)
    return path


def _two_whole_cubes(capsys, path, box, out):
    """``voxelize PATH --split --pitch 0.25 -o OUT`` gives the labels
    ``FILE:cube`` and ``FILE:crate``, each of the unit cube's
    (1 / 0.25)^3 = 64 voxels, label 1 those whose centres trimesh's
    ``contains`` finds inside ``box``."""
    table = _run(capsys, "voxelize", path, "--split", "--pitch", "0.25", "-o", out)
    rows = [line.split() for line in table.splitlines()[2:]]
    assert [(r[0], r[1], r[2]) for r in rows] == [("1", "64", f"{path}:cube"), ("2", "64", f"{path}:crate")]
    saved = np.load(out)
    labels, pitch, origin = saved["volume"], float(saved["pitch"]), saved["origin"]
    centres = origin + pitch * (np.indices(labels.shape).reshape(3, -1).T + 0.5)
    inside = box.contains(centres).reshape(labels.shape)
    assert inside.sum() == 64 and np.array_equal(labels == 1, inside)


def test_split_of_a_glb_keeps_a_node_of_several_primitives_one_closed_label(tmp_path, capsys):
    """A glTF mesh of two materials is two primitives of one node: a cube
    whose top face is the second. ``--split`` gave each primitive a label,
    named by trimesh's random suffix (``cube_3f9a1c``, another each run),
    each an open piece of the cube: 62 and 2 voxels. The node is one label,
    ``FILE:cube``, and its voxels are the whole cube's: (1 / 0.25)^3 = 64,
    those whose centres trimesh's ``contains`` finds inside the cube. In an
    archive the scene of that one node is named by its member alone."""
    import zipfile

    box = trimesh.creation.box((1, 1, 1))
    path = _glb(tmp_path / "mat.glb", [("cube", 0, [0, 0, 0]), ("crate", 1, [3, 0, 0])],
                [[(box.vertices, box.faces[2:]), (box.vertices, box.faces[:2])], [(box.vertices, box.faces)]])
    _two_whole_cubes(capsys, path, box, tmp_path / "labels.npz")
    archive = tmp_path / "arch.zip"
    _glb(tmp_path / "one.glb", [("cube", 0, [0, 0, 0])], [[(box.vertices, box.faces[2:]), (box.vertices, box.faces[:2])]])
    with zipfile.ZipFile(archive, "w") as z:
        z.write(tmp_path / "one.glb", "one.glb")
    table = _run(capsys, "voxelize", archive, "--split", "--pitch", "0.25", "-o", tmp_path / "arch.npz")
    assert [line.split()[:3] for line in table.splitlines()[2:]] == [["1", "64", f"{archive}:one.glb"]]


def _dae(path, box, nodes):
    """A COLLADA file written as its schema spells it: the geometry
    ``cubegeo`` of ``box``'s corners in two ``<triangles>`` of two
    materials (its first two faces the second), placed by each of
    ``nodes`` (name, x offset)."""
    points = " ".join(f"{c:g}" for c in box.vertices.ravel())
    parts = "".join(f'<triangles count="{len(f)}" material="{m}"><input semantic="VERTEX" source="#cubeverts" '
                    f'offset="0"/><p>{" ".join(map(str, f.ravel()))}</p></triangles>'
                    for m, f in (("side", box.faces[2:]), ("top", box.faces[:2])))
    placed = "".join(f'<node id="{n}" name="{n}"><translate>{x} 0 0</translate>'
                     '<instance_geometry url="#cubegeo"/></node>' for n, x in nodes)
    path.write_text(
        '<?xml version="1.0"?><COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">'
        '<library_geometries><geometry id="cubegeo"><mesh><source id="cubepos">'
        f'<float_array id="cubepos-array" count="{box.vertices.size}">{points}</float_array><technique_common>'
        f'<accessor source="#cubepos-array" count="{len(box.vertices)}" stride="3"><param name="X" type="float"/>'
        '<param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>'
        '<vertices id="cubeverts"><input semantic="POSITION" source="#cubepos"/></vertices>'
        f'{parts}</mesh></geometry></library_geometries><library_visual_scenes><visual_scene id="scene">{placed}'
        '</visual_scene></library_visual_scenes><scene><instance_visual_scene url="#scene"/></scene></COLLADA>')
    return path


def test_split_of_a_dae_keeps_a_placed_geometry_of_several_primitives_one_closed_label(tmp_path, capsys):
    """A COLLADA geometry of two materials is two ``<triangles>`` of one
    geometry: a cube whose top face is the second, placed by the nodes
    ``cube`` and ``crate``. trimesh reads a mesh per primitive, named by the
    geometry's id (``cubegeo``, ``cubegeo_1``, ...), and ``--split`` gave
    each a label, an open piece of a cube. Each node is one label,
    ``FILE:NODE``, and its voxels are the whole cube's: (1 / 0.25)^3 = 64,
    those whose centres trimesh's ``contains`` finds inside the cube. In a
    ZAE (a zip of the DAE) as well."""
    import zipfile

    pytest.importorskip("collada")
    box = trimesh.creation.box((1, 1, 1))
    path = _dae(tmp_path / "mat.dae", box, [("cube", 0), ("crate", 3)])
    read = trimesh.load_scene(path)
    assert sorted(len(g.faces) for g in read.geometry.values()) == [2, 2, 10, 10]  # a piece per primitive
    assert not any(g.is_watertight for g in read.geometry.values())
    _two_whole_cubes(capsys, path, box, tmp_path / "labels.npz")
    zae = tmp_path / "mat.zae"
    with zipfile.ZipFile(zae, "w") as z:
        z.write(path, "mat.dae")
    table = _run(capsys, "voxelize", zae, "--split", "--pitch", "0.25", "-o", tmp_path / "zae.npz")
    assert [line.split()[:3] for line in table.splitlines()[2:]] == [["1", "64", f"{zae}:cube"],
                                                                    ["2", "64", f"{zae}:crate"]]


@pytest.mark.parametrize("kind", ["zip", "tar.gz"])
def test_split_of_an_archive_refuses_an_empty_mesh_member_as_given_alone(tmp_path, capsys, kind):
    """An empty STL in an archive was dropped without a word: ``--split``
    labelled the archive's other meshes alone. It is refused as the file
    given alone is, in one line naming the member (as the archive's own
    library lists it), with ``--split`` or not; an empty file that is no
    mesh (a readme) is no mesh left out."""
    import tarfile
    import zipfile

    ball(tmp_path, "p10.stl", 1.0, (0, 0, 0))
    (tmp_path / "empty.stl").write_bytes(b"")
    (tmp_path / "readme.txt").write_bytes(b"")
    archive = tmp_path / f"arch2.{kind}"
    if kind == "zip":
        with zipfile.ZipFile(archive, "w") as z:
            for name in ("p10.stl", "empty.stl", "readme.txt"):
                z.write(tmp_path / name, name)
        with zipfile.ZipFile(archive) as z:
            sizes = {i.filename: i.file_size for i in z.infolist()}
    else:
        with tarfile.open(archive, "w:gz") as t:
            for name in ("p10.stl", "empty.stl", "readme.txt"):
                t.add(tmp_path / name, name)
        with tarfile.open(archive) as t:
            sizes = {m.name: m.size for m in t.getmembers()}
    assert sizes["empty.stl"] == 0 and sizes["p10.stl"] > 0  # the member is there, and empty
    alone = fails(capsys, "voxelize", tmp_path / "p10.stl", tmp_path / "empty.stl", "--resolution", "16",
                  "-o", tmp_path / "x.npz")
    assert alone.endswith("empty.stl: an empty file (0 bytes), not a readable STL file")
    for split in (["--split"], []):
        fails(capsys, "voxelize", archive, *split, "--resolution", "16", "-o", tmp_path / "z.npz",
              words=(f"{archive}:empty.stl: an empty file (0 bytes), not a readable STL file",))
        assert not (tmp_path / "z.npz").exists()


def test_split_of_an_archive_refuses_a_member_without_triangles(tmp_path, capsys):
    """A binary STL member of no facet (its 84 bytes: header and a count
    of 0) was dropped too; alone it is "no triangles read"."""
    import struct
    import zipfile

    ball(tmp_path, "p10.stl", 1.0, (0, 0, 0))
    (tmp_path / "zero.stl").write_bytes(b"\0" * 80 + struct.pack("<I", 0))
    assert len(trimesh.load_scene(tmp_path / "zero.stl").geometry) == 0  # trimesh reads nothing from it
    archive = tmp_path / "a3.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.write(tmp_path / "p10.stl", "p10.stl")
        z.write(tmp_path / "zero.stl", "zero.stl")
    fails(capsys, "voxelize", archive, "--split", "--resolution", "16", "-o", tmp_path / "z.npz",
          words=(f"{archive}:zero.stl: no triangles read",))


@pytest.mark.parametrize("member, data", [("zero.stl", b"\0" * 80 + b"\0\0\0\0"),  # a header, 0 facets
                                          ("points.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n")],  # v lines alone
                         ids=["stl_of_no_facet", "obj_of_points"])
def test_an_archive_without_split_refuses_a_member_without_triangles(tmp_path, capsys, member, data):
    """trimesh merges an archive's meshes into one, and a member of bytes
    but no triangle was left out of it without a word (the merge has the
    ball's faces alone), where --split refuses it: without --split it is
    refused too, in one line naming the member."""
    import zipfile

    ball(tmp_path, "p10.stl", 1.0, (0, 0, 0))
    (tmp_path / member).write_bytes(data)
    read = trimesh.load_scene(tmp_path / member).geometry.values()
    assert not any(isinstance(g, trimesh.Trimesh) and len(g.faces) for g in read)  # trimesh reads no triangle
    archive = tmp_path / "a4.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.write(tmp_path / "p10.stl", "p10.stl")
        z.write(tmp_path / member, member)
    merged = trimesh.load(archive, force="mesh", process=False)
    assert len(merged.faces) == len(trimesh.load(tmp_path / "p10.stl", process=False).faces)
    for split in (["--split"], []):
        line = fails(capsys, "voxelize", archive, *split, "--resolution", "16", "-o", tmp_path / "z.npz",
                     words=(f"{archive}:{member}: no triangles read",))
        assert "\n" not in line
        assert not (tmp_path / "z.npz").exists()
    fails(capsys, "genus", archive, "--resolution", "8", words=(f"{archive}:{member}: no triangles read",))


def test_a_directory_among_the_meshes_is_said_to_be_one(tmp_path, capsys, monkeypatch):
    """``voxelize b1.stl . -o l2.nii.gz`` said the output "lies inside the
    input ." (the test for a zarr store given as input): a directory is
    no mesh, and the line says that of it."""
    trimesh.creation.box().export(tmp_path / "b1.stl")
    monkeypatch.chdir(tmp_path)
    assert Path(".").is_dir()
    line = fails(capsys, "voxelize", "b1.stl", ".", "--resolution", "8", "-o", "l2.nii.gz",
                 words=(".: is a directory, not a mesh file",))
    assert "lies inside" not in line and not Path("l2.nii.gz").exists()


def test_a_degenerate_node_is_noted_as_bounding_nothing_alone(tmp_path, capsys):
    """A glTF node of collinear triangles (trimesh gives it zero area) got
    a note saying both "its edges balance, so it bounds a solid" and "the
    mesh bounds nothing"; it says the one true thing."""
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float) + 5
    line = trimesh.Trimesh(v, [[0, 1, 2], [1, 2, 3], [0, 2, 3], [0, 1, 3]], process=False)
    assert line.area == 0 and len(line.faces) == 4  # faces kept, none of any area
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(), node_name="box", geom_name="box")
    scene.add_geometry(line, node_name="line", geom_name="line")
    path = tmp_path / "scene.glb"
    scene.export(path)
    assert main(["voxelize", str(path), "--split", "--resolution", "16", "-o", str(tmp_path / "s.npz")]) == 0
    err = capsys.readouterr().err
    noted = [n for n in err.splitlines() if f"note: {path}:line:" in n]
    assert len(noted) == 1, err
    assert "bounds nothing" in noted[0] and "bounds a solid" not in noted[0], noted[0]
    assert np.count_nonzero(np.load(tmp_path / "s.npz")["volume"] == 2) == 0  # and no voxel has its label


def ascii_solids(path, solids):
    """An ASCII STL of several solids, each ``(name, mesh)`` written as
    ``solid NAME`` ... ``endsolid NAME`` by trimesh's ASCII writer."""
    text = ""
    for name, mesh in solids:
        facets = trimesh.exchange.stl.export_stl_ascii(mesh).split("\n", 1)[1].rsplit("endsolid", 1)[0]
        text += f"solid {name}\n{facets}endsolid {name}\n"
    path.write_text(text)
    return path


@pytest.fixture
def named_solids(tmp_path):
    """Two overlapping boxes and a ball apart, as the named solids of one
    ASCII STL (none sharing an edge with another: every one a connected
    body of its own too)."""
    bracket = trimesh.creation.box((1.3137, 0.7071, 0.9173)).apply_translation((0.0523, 0.1147, -0.0689))
    plate = trimesh.creation.box((0.8117, 1.1213, 0.6029)).apply_translation((0.6131, 0.3719, 0.1303))
    bolt = trimesh.creation.icosphere(3, 0.4513).apply_translation((2.2071, 0.1039, 0.0517))
    return ascii_solids(tmp_path / "parts.stl", [("bracket", bracket), ("plate", plate), ("bolt", bolt)])


def test_split_of_an_ascii_stl_of_named_solids_gives_a_label_per_solid(named_solids):
    """``--split`` of an ASCII STL of named solids gave a label per
    connected body, ``parts.stl:1``, ``:2``, ``:3``, the solids' names
    unsaid. Label i is the file's i-th solid, ``parts.stl:NAME`` as
    trimesh names the solids it reads, and holds the voxel centres that
    trimesh's ``contains`` finds in that solid alone, less those a later
    solid takes."""
    from isoflow import voxelize_meshes

    scene = trimesh.load_scene(named_solids)  # the solids by name, in the file's order
    assert list(scene.geometry) == ["bracket", "plate", "bolt"]
    r = voxelize_meshes([named_solids], pitch=0.05, split=True)
    assert r.names == tuple(f"{named_solids}:{name}" for name in scene.geometry)
    centres = r.origin + r.pitch * (np.indices(r.labels.shape).reshape(3, -1).T + 0.5)
    painted = np.zeros(len(centres), np.int64)
    inside = []
    for label, solid in enumerate(scene.geometry.values(), 1):
        inside.append(solid.contains(centres))
        painted[inside[-1]] = label  # the later solid's label wins
    assert np.array_equal(r.labels.ravel(), painted)
    lost = {(i, j): n for i, j, n in r.overlaps}
    assert lost.get((1, 2), 0) == np.count_nonzero(inside[0] & inside[1]) > 0  # the boxes overlap
    for label, own in enumerate(inside, 1):
        taken = sum(n for (i, _), n in lost.items() if i == label)
        assert r.voxels[label - 1] + taken == np.count_nonzero(own), label


def test_voxelize_split_prints_the_names_of_the_solids(tmp_path, capsys, named_solids):
    """The command's table names each label's solid, in the file's order."""
    out = tmp_path / "parts.npz"
    table = _run(capsys, "voxelize", named_solids, "--split", "--pitch", "0.05", "-o", out)
    rows = [line.split() for line in table.splitlines() if line.split()[:1] in (["1"], ["2"], ["3"])]
    assert [(int(r[0]), r[-1]) for r in rows] == [(1, f"{named_solids}:bracket"), (2, f"{named_solids}:plate"),
                                                  (3, f"{named_solids}:bolt")]
    assert set(np.unique(read_labels(out).array).tolist()) == {0, 1, 2, 3}


def test_voxelize_split_of_an_archive_follows_each_stl_s_order_of_solids(tmp_path, capsys, named_solids):
    """In an archive, an STL's named solids were labelled in the order of
    their names (trimesh's scene of the member holds them by name), the
    same file given alone in the file's order. Labels follow the members'
    natural order, then each member's solids as its text lists them."""
    import re
    import zipfile

    archive = tmp_path / "parts.zip"
    with zipfile.ZipFile(archive, "w") as z:
        z.write(named_solids, "b_parts.stl")
        trimesh.creation.box((0.5, 0.5, 0.5)).apply_translation((4.0, 0, 0)).export(tmp_path / "a_box.stl")
        z.write(tmp_path / "a_box.stl", "a_box.stl")
    solids = re.findall(r"^solid (\S+)$", named_solids.read_text(), re.MULTILINE)
    assert solids != sorted(solids)  # the file's order is not that of the names
    out = tmp_path / "parts.npz"
    _run(capsys, "voxelize", archive, "--split", "--pitch", "0.05", "-o", out)
    names = read_labels(out).names
    assert list(names.values()) == [f"{archive}:a_box.stl", *(f"{archive}:b_parts.stl:{s}" for s in solids)]
    assert list(names) == list(range(1, len(solids) + 2))


def test_named_solids_keep_their_bodies_together_and_repeated_names_are_made_unique(tmp_path):
    """A solid of two bodies is one label; a name two solids share is
    made unique as trimesh names the solids (``lid``, ``lid_1``)."""
    from isoflow import voxelize_meshes

    balls = trimesh.util.concatenate([trimesh.creation.icosphere(2, 0.3).apply_translation((x, 0, 0))
                                      for x in (0, 1)])
    assert len(balls.split(only_watertight=False)) == 2
    lids = [trimesh.creation.box((0.5, 0.5, 0.2)).apply_translation((x, 1.5, 0)) for x in (0, 1.5)]
    path = ascii_solids(tmp_path / "kit.stl", [("pair", balls), ("lid", lids[0]), ("lid", lids[1])])
    names = list(trimesh.load_scene(path).geometry)
    assert names == ["pair", "lid", "lid_1"]
    r = voxelize_meshes([path], pitch=0.05, split=True)
    assert r.names == tuple(f"{path}:{name}" for name in names)
    assert analyze(r.labels == 1)["betti"][0] == 2  # the pair's two balls, one label


def test_split_of_an_ascii_stl_of_unnamed_solids_keeps_a_label_per_body(tmp_path):
    """Solids that name nothing keep the labels of connected bodies,
    ``FILE:1`` ... in the order of their first face, however the solids
    group them: here three solids, one of two balls, are four bodies."""
    from isoflow import voxelize_meshes

    balls = [trimesh.creation.icosphere(2, 0.3).apply_translation((x, 0, 0)) for x in (0, 1, 2, 3)]
    solids = [("", balls[0]), ("", trimesh.util.concatenate(balls[1:3])), ("", balls[3])]
    path = ascii_solids(tmp_path / "unnamed.stl", solids)
    bodies = len(trimesh.load(path, force="mesh").split(only_watertight=False))
    r = voxelize_meshes([path], pitch=0.05, split=True)
    assert bodies == 4 and r.names == tuple(f"{path}:{k}" for k in range(1, bodies + 1))


@pytest.mark.parametrize("several", [False, True])
def test_a_grid_past_memory_for_magicavoxel_is_refused_for_the_formats_side(tmp_path, capsys, several):
    """A MagicaVoxel output asked of a grid past the memory budget was
    refused for memory, naming the finest grid that fits there (thousands
    across), which the format then refuses at 256 a side once voxelised.
    The refusal names the format's side, and its advice works when
    followed."""
    a = ball(tmp_path, "a.stl", 1.0, (0, 0, 0))
    meshes = [a, ball(tmp_path, "b.stl", 0.5, (3, 0, 0))] if several else [a]
    out = tmp_path / "big.vox"
    line = fails(capsys, "voxelize", *meshes, "--resolution", "1000000", "-o", out)
    assert "MagicaVoxel models are at most 256 voxels a side" in line and line.endswith("(--resolution 256)")
    assert "fits in" not in line and not out.exists()
    assert main(["voxelize", *map(str, meshes), "--resolution", "256", "-o", str(out)]) == 0
    assert max(read_volume(out).volume.shape) <= 256


@pytest.mark.parametrize("several", [False, True])
def test_a_grid_past_float64_for_magicavoxel_names_its_sides_in_a_short_line(tmp_path, capsys, several):
    """``--pitch 1e-200`` over a ball 2 across asks for a grid of 2e200
    voxels a side. The MagicaVoxel refusal wrote each side as every one of
    its 201 digits (a line of over 600 characters); a reader wants the
    size, as every other refusal of a grid writes it (``2.000e+200``)."""
    a = ball(tmp_path, "a.stl", 1.0, (0, 0, 0))
    meshes = [a, ball(tmp_path, "b.stl", 0.5, (0.2, 0, 0))] if several else [a]
    line = fails(capsys, "voxelize", *meshes, "--pitch", "1e-200", "-o", tmp_path / "big.vox",
                 words=("MagicaVoxel models are at most 256 voxels a side",))
    sides = line.split("this object is ")[1].split(";")[0].split("x")
    assert len(sides) == 3 and all(len(side) < 12 and float(side) > 1e199 for side in sides), line



def test_a_flat_mesh_on_a_plane_between_voxels_names_the_shell_it_touches(tmp_path, capsys):
    """A unit cube and a unit square lying on its bottom face, on a shared
    grid of pitch 0.1 from the cube's corner: the square lies on the grid's
    plane z = 0, and the voxels it touches are the 10 x 10 of the bottom
    layer. The note said the surface's shell had 0 voxels, while --fill
    shell gave those 100."""
    cube = trimesh.creation.box(extents=(1, 1, 1))
    cube.apply_translation((0.5, 0.5, 0.5))
    cube.export(tmp_path / "cube.obj")
    square = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3]])
    square.export(tmp_path / "square.obj")
    args = ["voxelize", str(tmp_path / "cube.obj"), str(tmp_path / "square.obj"), "--pitch", "0.1"]
    assert main([*args, "-o", str(tmp_path / "winding.npz")]) == 0
    note = next(line for line in capsys.readouterr().err.splitlines() if "square.obj: mesh has" in line)
    assert "(the surface's shell has 100)" in note, note
    assert main([*args, "--fill", "shell", "-o", str(tmp_path / "shell.npz")]) == 0
    assert int(np.count_nonzero(read_labels(tmp_path / "shell.npz").array == 2)) == 100


def test_split_of_a_scene_given_in_python_keeps_a_node_of_several_primitives_one_label(tmp_path):
    """The scene trimesh loads from such a file, given to voxelize_meshes:
    without the file's order the primitives of one node are still the
    node's one closed label (64 voxels of 0.25), named by the node."""
    from isoflow import voxelize_meshes

    box = trimesh.creation.box((1, 1, 1))
    path = _glb(tmp_path / "mat.glb", [("cube", 0, [0, 0, 0]), ("crate", 1, [3, 0, 0])],
                [[(box.vertices, box.faces[2:]), (box.vertices, box.faces[:2])], [(box.vertices, box.faces)]])
    scene = trimesh.load(path, force="scene")
    assert len(scene.graph.nodes_geometry) == 3  # the cube's two primitives and the crate
    result = voxelize_meshes([scene], pitch=0.25, split=True)
    assert sorted(result.names) == ["mesh 1:crate", "mesh 1:cube"] and result.voxels == (64, 64)


@pytest.mark.parametrize("meshes", [1, 2])
def test_a_grid_longer_than_nifti_holds_is_one_line_and_no_file(tmp_path, meshes):
    """A thin rod 40000 voxels long written as .nii.gz was nibabel's
    HeaderDataError as a traceback, after all the work: NIfTI-1's dim[]
    is int16 (nibabel's own header refuses the shape). It is one line
    naming the file, the shape and the formats that hold it, exit 2, and
    no file; the same grid as .nrrd is written, read back by pynrrd."""
    nib = pytest.importorskip("nibabel")
    nrrd = pytest.importorskip("nrrd")
    with pytest.raises(nib.spatialimages.HeaderDataError):
        nib.Nifti1Header().set_data_shape((40000, 2, 2))
    rod = trimesh.creation.box(extents=(40000, 2, 2))
    rod.export(tmp_path / "rod.stl")
    paths = [tmp_path / "rod.stl"]
    if meshes == 2:
        cube = trimesh.creation.box(extents=(2, 2, 2))
        cube.apply_translation((0, 3, 0))
        cube.export(tmp_path / "cube.stl")
        paths.append(tmp_path / "cube.stl")
    command = [sys.executable, "-m", "isoflow", "voxelize", *map(str, paths), "--pitch", "1", "-q"]
    done = subprocess.run([*command, "-o", str(tmp_path / "rod.nii.gz")], capture_output=True, text=True)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert "rod.nii.gz: NIfTI-1 holds at most 32767 voxels a side" in lines[0], lines
    assert "40000x" in lines[0] and ".nrrd" in lines[0], lines
    assert not (tmp_path / "rod.nii.gz").exists()
    done = subprocess.run([*command, "-o", str(tmp_path / "rod.nrrd")], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    data, _ = nrrd.read(str(tmp_path / "rod.nrrd"))
    assert data.shape[0] == 40000 and np.count_nonzero(data == 1) == 40000 * 2 * 2


@pytest.mark.parametrize("kind", ["one", "several", "zarr"])
def test_a_pitch_coarser_than_the_mesh_is_refused_naming_the_option(tmp_path, kind):
    """The command names ``--pitch``, not a Python function nor ``pitch=``
    (its message said ``pitch=1e+300``), for one mesh, several and a zarr
    store, in one line, exit 2, nothing written."""
    box = tmp_path / "box.stl"
    trimesh.creation.box().export(box)
    meshes = [box, box] if kind == "several" else [box]
    out = tmp_path / ("v.zarr" if kind == "zarr" else "v.npz")
    p = isoflow_here("voxelize", *map(str, meshes), "--pitch", "1e300", "-o", str(out))
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr, p.stderr
    assert "voxelize: --pitch 1e+300 is more than 2**40 times the mesh's size" in p.stderr, p.stderr
    assert "voxelize_" not in p.stderr and "pitch=" not in p.stderr
    assert not out.exists()
