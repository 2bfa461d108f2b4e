"""The binary glTF scene writer (isoflow.mesh.gltf): the file as trimesh
and pymeshlab read it, node by node, against the arrays written, and the
layout rules of the glTF 2.0 specification checked on the file's own JSON;
and the scene's read-back check, which names a node that reads wrong."""

import io
import json
import struct

import numpy as np
import pytest
import trimesh

from isoflow.digital.lattice import DigitalObject
from isoflow.digital.surface import boundary_mesh
from isoflow.mesh import export
from isoflow.mesh.readback import check_scene_file, scene_nodes

#: bytes of each glTF component type, and components of each element type
COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def scene_parts(rng, count=5, large=False):
    """Boundary meshes of random objects (edge and vertex contacts, at 6
    and 26), one of them far from the origin (stored under a node matrix);
    ``large`` adds, second, a slab's of 72,194 vertices, past what uint16
    indices can number."""
    parts, written = [], []
    if large:
        vol = np.zeros((4, 190, 190), bool)
        vol[1:3, 1:189, 1:189] = True
        obj, mesh = DigitalObject(vol, pitch=(0.5, 1.0, 2.0)), boundary_mesh(vol, 6)
        parts.append(export.glb_part("slab", mesh, obj))
        written.append(("slab", mesh, obj, mesh.components()))
    for t in range(count):
        vol = rng.random((5, 4, 6)) < 0.45
        vol[2, 2, 2] = True
        conn = 6 if t % 2 else 26
        far = t == count - 1
        obj = DigitalObject(vol, pitch=(0.5, 1.0, 2.0), origin=(4e6, -3.0, 1e-3) if far else (1.0, 2.0, 3.0))
        mesh = boundary_mesh(vol, conn)
        parts.append(export.glb_part(f"part_{t}", mesh, obj))
        written.append((f"part_{t}", mesh, obj, mesh.components()))
    if large:
        parts.insert(1, parts.pop(0))
        written.insert(1, written.pop(0))
    return parts, written


@pytest.mark.parametrize("large", [False, True])
def test_scene_reads_back_node_by_node_as_written(tmp_path, rng, large):
    parts, _ = scene_parts(rng, large=large)
    path = export.write_glb_scene(tmp_path / "s.glb", parts, comment="a test")
    scene = trimesh.load(path, force="scene", process=False)
    assert sorted(scene.graph.nodes_geometry) == sorted(name for name, *_ in parts)
    for name, columns, triangles, frame in parts:
        transform, geometry = scene.graph[name]
        tm = scene.geometry[geometry]
        np.testing.assert_array_equal(tm.faces, triangles)
        stored = np.column_stack([columns[k] for k in "xyz"]) if frame is None else frame[0]
        np.testing.assert_array_equal(tm.vertices, np.asarray(stored, np.float32))
        if frame is not None:
            np.testing.assert_allclose(transform, frame[1])
        rgb = np.column_stack([columns[k] for k in ("red", "green", "blue")])
        np.testing.assert_array_equal(tm.visual.vertex_colors[:, :3], export.linear_bytes(rgb))  # glTF's linear
        for key in ("config", "class", "gamma", "a", "f"):
            got = np.asarray(tm.vertex_attributes[f"_{key}"])
            np.testing.assert_array_equal(got.reshape(len(rgb), -1)[:, 0], columns[key])
        assert "a test" in json.dumps(tm.metadata)


@pytest.mark.parametrize("large", [False, True])
def test_scene_follows_the_specifications_layout(tmp_path, rng, large):
    parts, _ = scene_parts(rng, large=large)
    data = export.write_glb_scene(tmp_path / "s.glb", parts).read_bytes()
    magic, version, total = struct.unpack_from("<4sII", data)
    assert (magic, version, total) == (b"glTF", 2, len(data))
    text_length, kind = struct.unpack_from("<I4s", data, 12)
    assert kind == b"JSON" and text_length % 4 == 0
    tree = json.loads(data[20:20 + text_length])
    bin_length, kind = struct.unpack_from("<I4s", data, 20 + text_length)
    assert kind == b"BIN\0" and bin_length % 4 == 0 and 28 + text_length + bin_length == len(data)
    binary = data[28 + text_length:]
    assert tree["buffers"] == [{"byteLength": bin_length}]
    for view in tree["bufferViews"]:
        assert view["byteOffset"] % 4 == 0 and view["byteOffset"] + view["byteLength"] <= bin_length
    # a view that two vertex attributes' accessors share declares its stride (section 3.6.2.4)
    for v, view in enumerate(tree["bufferViews"]):
        shared = [a for a in tree["accessors"][len(parts):] if a["bufferView"] == v]
        if len(shared) > 1:
            element = COMPONENT_BYTES[shared[0]["componentType"]] * COMPONENTS[shared[0]["type"]]
            assert view.get("byteStride") == element and 4 <= element <= 252 and element % 4 == 0
    for mesh in tree["meshes"]:
        primitive, = mesh["primitives"]
        for key, at in [("indices", primitive["indices"]), *primitive["attributes"].items()]:
            acc = tree["accessors"][at]
            view = tree["bufferViews"][acc["bufferView"]]
            size = COMPONENT_BYTES[acc["componentType"]]
            element = size * COMPONENTS[acc["type"]]
            assert acc["count"] >= 1 and acc["byteOffset"] % size == 0 and view["byteOffset"] % size == 0
            assert acc["byteOffset"] + acc["count"] * element <= view["byteLength"]
            if key != "indices":
                assert element % 4 == 0 and (key.startswith("_") or key in ("POSITION", "COLOR_0"))
            if key == "POSITION":  # required bounds, equal to the data's
                start = view["byteOffset"] + acc["byteOffset"]
                xyz = np.frombuffer(binary, np.float32, 3 * acc["count"], start).reshape(-1, 3)
                assert acc["min"] == xyz.min(axis=0).tolist() and acc["max"] == xyz.max(axis=0).tolist()
        check_indices(tree, binary, primitive)
    assert [n["name"] for n in tree["nodes"]] == [name for name, *_ in parts]
    types = [tree["accessors"][m["primitives"][0]["indices"]]["componentType"] for m in tree["meshes"]]
    assert types == [5125 if len(columns["x"]) > 65535 else 5123 for _, columns, *_ in parts]
    # a view holds one component type: the spec is silent on mixing them
    for v in {tree["accessors"][i]["bufferView"] for i in range(len(parts))}:
        assert len({a["componentType"] for a in tree["accessors"] if a["bufferView"] == v}) == 1


def check_indices(tree, binary, primitive):
    """A primitive's indices as the specification has them: an unsigned
    type, in a view of indices without a stride, each naming a vertex, and
    none the type's largest value (a primitive restart)."""
    acc = tree["accessors"][primitive["indices"]]
    view = tree["bufferViews"][acc["bufferView"]]
    assert acc["type"] == "SCALAR" and acc["componentType"] in (5121, 5123, 5125) and acc["count"] % 3 == 0
    assert view["target"] == 34963 and "byteStride" not in view
    dtype = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32}[acc["componentType"]]
    index = np.frombuffer(binary, dtype, acc["count"], view["byteOffset"] + acc["byteOffset"])
    vertices = tree["accessors"][primitive["attributes"]["POSITION"]]["count"]
    assert index.max() < vertices and index.max() < np.iinfo(dtype).max


@pytest.mark.parametrize("large", [False, True])
def test_scene_opens_in_pymeshlab_closed(tmp_path, rng, large):
    """pymeshlab loads a layer per node, each the node's closed surface."""
    pymeshlab = pytest.importorskip("pymeshlab")
    parts, written = scene_parts(rng, large=large)
    path = export.write_glb_scene(tmp_path / "s.glb", parts)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    assert ms.mesh_number() == len(parts)
    faces, vertices = [], []
    for layer in range(ms.mesh_number()):
        ms.set_current_mesh(layer)
        measures = ms.get_topological_measures()
        assert measures["boundary_edges"] == 0 and measures["non_two_manifold_edges"] == 0
        m = ms.current_mesh()
        faces.append(m.face_number())
        vertices.append(m.vertex_number())
        euler = m.vertex_number() - measures["edges_number"] + m.face_number()
        assert euler in [mesh.euler_characteristic for _, mesh, _, _ in written]
    assert sorted(faces) == sorted(len(t) for _, _, t, _ in parts)
    assert sorted(vertices) == sorted(len(columns["x"]) for _, columns, _, _ in parts)


@pytest.mark.parametrize("count", [65535, 65536])
def test_a_mesh_at_the_edge_of_uint16_indices_reads_back(tmp_path, count):
    """A strip of triangles over ``count`` vertices, its last triangle on
    the last vertex: 65,535 vertices still fit uint16 indices (the last
    index, 65534, is no restart value), 65,536 do not; trimesh and
    pymeshlab read each strip's every triangle."""
    triangles = np.column_stack([np.arange(count - 2), np.arange(1, count - 1), np.arange(2, count)])
    triangles[1::2] = triangles[1::2, [0, 2, 1]]  # one winding along the strip
    t = np.arange(count, dtype=np.float64)
    columns = {"x": t, "y": t % 2, "z": np.zeros(count), **{c: np.full(count, 200, np.uint8) for c in ("red", "green", "blue")}}
    path = export.write_glb_scene(tmp_path / "s.glb", [("strip", columns, triangles, None)])
    tm = trimesh.load(path, force="mesh", process=False)
    np.testing.assert_array_equal(tm.faces, triangles)
    data = path.read_bytes()
    tree = json.loads(data[20:20 + struct.unpack_from("<I", data, 12)[0]])
    assert tree["accessors"][0]["componentType"] == (5123 if count <= 65535 else 5125)
    pymeshlab = pytest.importorskip("pymeshlab")
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    assert (ms.current_mesh().vertex_number(), ms.current_mesh().face_number()) == (count, count - 2)


def test_scene_read_back_agrees_and_names_a_node_that_reads_wrong(tmp_path, rng):
    parts, written = scene_parts(rng, 7)
    path = export.write_glb_scene(tmp_path / "s.glb", parts)
    assert check_scene_file(path, written) == []
    # a node that lost a triangle: the union is open, each node is measured alone
    name, columns, triangles, frame = parts[3]
    parts[3] = (name, columns, triangles[1:], frame)
    export.write_glb_scene(tmp_path / "s.glb", parts, force=True)
    problems = check_scene_file(path, written)
    assert len(problems) == 1 and "node part_3" in problems[0] and "watertight False" in problems[0]
    # a node whose mesh is another closed surface: its figures differ
    parts[3] = ("part_3",) + parts[2][1:]
    export.write_glb_scene(tmp_path / "s.glb", parts, force=True)
    problems = check_scene_file(path, written)
    assert any("node part_3" in p for p in problems) and not any("node part_2" in p for p in problems)


def glb_tree(data: bytes) -> dict:
    """The JSON chunk of a GLB's bytes."""
    return json.loads(data[20:20 + struct.unpack_from("<I", data, 12)[0]])


def with_tree(path, tree: dict) -> None:
    """Rewrite the GLB at ``path`` with ``tree`` as its JSON, its binary chunk as it is."""
    data = path.read_bytes()
    rest = data[20 + struct.unpack_from("<I", data, 12)[0]:]
    text = json.dumps(tree).encode()
    text += b" " * (-len(text) % 4)
    path.write_bytes(struct.pack("<4sIII4s", b"glTF", 2, 20 + len(text) + len(rest), len(text), b"JSON") + text + rest)


def other_reader(monkeypatch):
    """trimesh's step from a parsed glTF to its meshes (its private
    ``_read_buffers``) as a trimesh might have it that takes other
    arguments: the read-back then gives the file to ``load_glb``."""
    import trimesh.exchange.gltf as gltf

    real = gltf._read_buffers
    monkeypatch.setattr(gltf, "_read_buffers", lambda *args, **kwargs: real(*args, **kwargs))


@pytest.mark.parametrize("reader", ["parsed", "load_glb"])
def test_scene_read_back_gives_trimesh_the_geometry_accessors_alone(tmp_path, rng, monkeypatch, reader):
    """trimesh's glTF reader makes an array of every accessor, 8 a node in
    isoflow's scenes, and the read-back measures two: the reader is given
    those alone, and each node reads as trimesh reads it from the whole
    file (its triangles, its positions placed by its transform). The JSON
    is handed to trimesh's step after its parse as parsed, not written out
    again for ``load_glb`` to parse (through ``load_glb`` where trimesh's
    step takes other arguments), with the file's binary chunk as its
    buffer; the positions' view without its stride, the row of every
    position."""
    import trimesh.exchange.gltf as gltf

    parts, written = scene_parts(rng, 6)
    path = export.write_glb_scene(tmp_path / "s.glb", parts)
    data = path.read_bytes()
    tree = glb_tree(data)
    assert len(tree["accessors"]) == 8 * len(parts)
    chunk = data[20 + struct.unpack_from("<I", data, 12)[0] + 8:]
    scene = trimesh.load(path, force="scene", process=False)
    if reader == "load_glb":
        other_reader(monkeypatch)
    given, loaded, step, load = [], [], gltf._read_buffers, gltf.load_glb

    def spy_step(header, buffers, mesh_kwargs, resolver, **kwargs):
        given.append((header, [bytes(b) for b in buffers]))
        return step(header=header, buffers=buffers, mesh_kwargs=mesh_kwargs, resolver=resolver, **kwargs)

    def spy_load(fh, *args, **kwargs):
        loaded.append(fh.read())
        return load(io.BytesIO(loaded[-1]), *args, **kwargs)

    monkeypatch.setattr(gltf, "load_glb", spy_load)
    if reader == "parsed":
        monkeypatch.setattr(gltf, "_read_buffers", spy_step)
    nodes = scene_nodes(path)
    if reader == "parsed":
        assert loaded == [] and len(given) == 1 and given[0][1] == [chunk]
        header = given[0][0]
    else:
        assert len(loaded) == 1 and loaded[0].endswith(chunk)
        header = glb_tree(loaded[0])
    assert len(header["accessors"]) == 2 * len(parts)
    positions = {header["accessors"][m["primitives"][0]["attributes"]["POSITION"]]["bufferView"]
                 for m in header["meshes"]}
    assert len(positions) == 1 and "byteStride" not in header["bufferViews"][positions.pop()]
    assert [v.get("byteStride") for v in tree["bufferViews"]].count(12) == 1  # the file's own: the positions'
    assert sorted(nodes) == sorted(scene.graph.nodes_geometry)
    for name, (vertices, triangles) in nodes.items():
        transform, geometry = scene.graph[name]
        np.testing.assert_array_equal(triangles, scene.geometry[geometry].faces)
        np.testing.assert_allclose(vertices, trimesh.transform_points(scene.geometry[geometry].vertices, transform),
                                   rtol=1e-12, atol=0)
    assert check_scene_file(path, written) == []


@pytest.mark.parametrize("reader", ["parsed", "load_glb"])
def test_a_node_whose_triangles_the_file_holds_altered_is_refused(tmp_path, rng, monkeypatch, reader):
    """One node's triangle turned over in the file's binary chunk, as
    written: trimesh reads that node (and no other) as not consistently
    wound, and the read-back names it, whichever way trimesh is given the
    file."""
    parts, written = scene_parts(rng, 5)
    path = export.write_glb_scene(tmp_path / "s.glb", parts)
    assert check_scene_file(path, written) == []
    data = bytearray(path.read_bytes())
    tree = glb_tree(bytes(data))
    at = 20 + struct.unpack_from("<I", data, 12)[0] + 8  # the binary chunk
    node = tree["nodes"][2]
    indices = tree["accessors"][tree["meshes"][node["mesh"]]["primitives"][0]["indices"]]
    size = COMPONENT_BYTES[indices["componentType"]]
    first = at + tree["bufferViews"][indices["bufferView"]].get("byteOffset", 0) + indices.get("byteOffset", 0)
    data[first:first + size], data[first + size:first + 2 * size] = (data[first + size:first + 2 * size],
                                                                     data[first:first + size])
    path.write_bytes(bytes(data))
    scene = trimesh.load(path, force="scene", process=False)
    wound = {name: scene.geometry[scene.graph[name][1]].is_winding_consistent for name in scene.graph.nodes_geometry}
    assert [name for name, ok in wound.items() if not ok] == [node["name"]]
    if reader == "load_glb":
        other_reader(monkeypatch)
    problems = check_scene_file(path, written)
    assert len(problems) == 1 and f"node {node['name']}:" in problems[0] and "watertight False" in problems[0], problems


def test_scene_read_back_reads_the_binary_chunk_where_it_lies(tmp_path, rng):
    """The read-back's reader takes the binary chunk from the file mapped
    into memory, not read: the memory the read-back allocates (Python's
    and numpy's, as tracemalloc counts them) stays below the chunk's size,
    most of which (colours and curvature attributes) it does not measure.
    A read of the chunk allocated all of it, and trimesh's slice of each
    buffer view out of it all of it again."""
    import tracemalloc

    parts, _ = scene_parts(rng, large=True)
    path = export.write_glb_scene(tmp_path / "s.glb", parts)
    data = path.read_bytes()
    chunk = struct.unpack_from("<I", data, 20 + struct.unpack_from("<I", data, 12)[0])[0]
    assert chunk > 4 * 10 ** 6 and len(data) < chunk + 10 ** 5
    scene_nodes(path, as_read=True)  # trimesh's imports, outside the count
    tracemalloc.start()
    try:
        nodes = scene_nodes(path, as_read=True)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < chunk / 2, (peak, chunk)
    scene = trimesh.load(path, force="scene", process=False)
    for name, (vertices, triangles) in nodes.items():
        transform, geometry = scene.graph[name]
        np.testing.assert_array_equal(triangles, scene.geometry[geometry].faces)
        np.testing.assert_allclose(vertices, trimesh.transform_points(scene.geometry[geometry].vertices, transform),
                                   rtol=1e-12, atol=0)


def _past_its_view(tree, at):
    view = tree["bufferViews"][tree["accessors"][at]["bufferView"]]
    tree["accessors"][at]["byteOffset"] = view["byteLength"]


@pytest.mark.parametrize("corrupt", [
    lambda t, m: _past_its_view(t, m["attributes"]["_gamma"]),
    lambda t, m: t["accessors"][m["attributes"]["COLOR_0"]].update(componentType=9999),
    lambda t, m: t["accessors"][m["attributes"]["_a"]].update(count=10 ** 7),
    lambda t, m: t["accessors"][m["attributes"]["_f"]].update(type="VEC9"),
    lambda t, m: m["attributes"].update(_config=len(t["accessors"])),
    lambda t, m: _past_its_view(t, m["attributes"]["POSITION"]),
    lambda t, m: t["bufferViews"][0].update(byteLength=10 ** 9),
    lambda t, m: t["accessors"][m["attributes"]["POSITION"]].update(byteOffset=-12),
], ids=["attribute-past-its-view", "unknown-component-type", "count-past-its-view", "unknown-type",
        "attribute-of-no-accessor", "positions-past-their-view", "view-past-the-buffer", "positions-before-their-view"])
def test_a_scene_trimesh_cannot_read_reads_back_as_unreadable(tmp_path, rng, corrupt):
    """A scene whose accessor trimesh's reader fails on, one the figures
    use or not, is still refused as unreadable: trimesh.load of the whole
    file fails on each of these."""
    parts, written = scene_parts(rng, 4)
    path = export.write_glb_scene(tmp_path / "s.glb", parts)
    tree = glb_tree(path.read_bytes())
    corrupt(tree, tree["meshes"][2]["primitives"][0])
    with_tree(path, tree)
    with pytest.raises((AssertionError, IndexError, KeyError, ValueError)):  # trimesh's reader's failures
        trimesh.load(path, force="scene", process=False)
    problems = check_scene_file(path, written)
    assert len(problems) == 1 and "trimesh cannot read it" in problems[0], problems


def test_sets_of_parts_read_back_node_by_node_in_the_order_asked(tmp_path, rng):
    """Parts given as columns in two sets (as the batches of label boxes
    are), written in another order than they are given: trimesh reads
    each node with its own part's positions, triangles and attributes, and
    the nodes are listed in the order asked."""
    from isoflow.mesh.gltf import SceneParts
    parts, _ = scene_parts(rng, 6)
    meshes = [{"name": name, "positions": np.column_stack([c[k] for k in "xyz"]) if frame is None else frame[0],
               "triangles": triangles, "colors": np.column_stack([c["red"], c["green"], c["blue"],
                                                                  np.full(len(c["x"]), 255, np.uint8)]),
               "attributes": {f"_{k}": c[k] for k in ("config", "class", "gamma", "a", "f")},
               "matrix": None if frame is None else frame[1]} for name, c, triangles, frame in parts]
    sets = [SceneParts.of_meshes(meshes[:2]), SceneParts.of_meshes(meshes[2:])]
    order = np.array([4, 0, 5, 2, 1, 3])
    path = export.write_glb_sets(tmp_path / "s.glb", sets, order)
    data = path.read_bytes()
    tree = json.loads(data[20:20 + struct.unpack_from("<I", data, 12)[0]])
    assert [n["name"] for n in tree["nodes"]] == [meshes[p]["name"] for p in order]
    scene = trimesh.load(path, force="scene", process=False)
    for mesh in meshes:
        transform, geometry = scene.graph[mesh["name"]]
        tm = scene.geometry[geometry]
        np.testing.assert_array_equal(tm.faces, mesh["triangles"])
        np.testing.assert_array_equal(tm.vertices, np.asarray(mesh["positions"], np.float32))
        np.testing.assert_allclose(transform, np.eye(4) if mesh["matrix"] is None else mesh["matrix"])
        np.testing.assert_array_equal(np.asarray(tm.vertex_attributes["_class"]).reshape(len(tm.vertices), -1)[:, 0],
                                      mesh["attributes"]["_class"])


# ------------------------------------------------ extensions trimesh ignores

#: the commands that read a mesh, OUT the output where they write one
MESH_COMMANDS = [["genus"], ["voxelize", "--resolution", "8", "-o", "OUT"],
                 ["voxelize", "--split", "--resolution", "8", "-o", "OUT"]]


def refusal(capsys, tmp_path, command, path) -> str:
    """The one line, no traceback, of ``command`` (of :data:`MESH_COMMANDS`)
    refusing the mesh ``path`` with exit status 2, nothing written."""
    from isoflow.cli import main

    out = tmp_path / "out.npz"
    assert main([command[0], str(path), *[str(out) if w == "OUT" else w for w in command[1:]]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0], err
    assert not out.exists()
    return err[0]


def instanced_boxes_glb(path, offsets, extensions_used=("EXT_mesh_gpu_instancing",)) -> None:
    """A GLB of one unit box drawn at each of ``offsets`` by
    EXT_mesh_gpu_instancing (its TRANSLATION accessor, one row each)."""
    box = trimesh.creation.box()
    v, f = box.vertices.astype(np.float32), box.faces.astype(np.uint32)
    t = np.asarray(offsets, np.float32)
    binary = v.tobytes() + f.tobytes() + t.tobytes()
    views = [(0, v.nbytes), (v.nbytes, f.nbytes), (v.nbytes + f.nbytes, t.nbytes)]
    tree = {
        "asset": {"version": "2.0"}, "extensionsUsed": list(extensions_used), "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 2}}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [{"buffer": 0, "byteOffset": o, "byteLength": n} for o, n in views],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3",
                       "min": v.min(0).tolist(), "max": v.max(0).tolist()},
                      {"bufferView": 1, "componentType": 5125, "count": f.size, "type": "SCALAR"},
                      {"bufferView": 2, "componentType": 5126, "count": len(t), "type": "VEC3"}],
    }
    text = json.dumps(tree).encode()
    text += b" " * (-len(text) % 4)
    binary += bytes(-len(binary) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    path.write_bytes(b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(text)) + b"JSON" + text
                     + struct.pack("<I", len(binary)) + b"BIN\0" + binary)


@pytest.mark.parametrize("command", MESH_COMMANDS)
def test_instanced_gltf_is_refused_not_read_as_one_copy(tmp_path, capsys, command):
    """Three unit boxes, 3 apart, drawn by EXT_mesh_gpu_instancing: trimesh
    reads one box (volume 1, not 3), which isoflow counted as the model."""
    from isoflow.cli import main

    path = tmp_path / "boxes.glb"
    instanced_boxes_glb(path, [[0, 0, 0], [3, 0, 0], [0, 3, 0]])
    read = trimesh.load(path, force="mesh", process=False)
    assert read.volume == pytest.approx(1.0)  # one copy of the three
    out = tmp_path / "out.npz"
    assert main([command[0], str(path), *[str(out) if w == "OUT" else w for w in command[1:]]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "node 0 draws its mesh 3 times by the glTF extension EXT_mesh_gpu_instancing" in err[0]
    assert str(path) in err[0] and not out.exists()


def test_meshopt_compressed_gltf_is_refused(tmp_path, capsys):
    from isoflow.cli import main

    path = tmp_path / "packed.glb"
    instanced_boxes_glb(path, [[0, 0, 0]], extensions_used=("EXT_meshopt_compression", "EXT_mesh_gpu_instancing"))
    assert main(["genus", str(path)]) == 2
    err = capsys.readouterr().err
    assert "compressed by the glTF extension EXT_meshopt_compression" in err and "Traceback" not in err


def test_a_gltf_without_its_buffer_file_names_it(tmp_path, capsys):
    """A glTF scene written with its .bin beside it, then copied without
    it: trimesh said "FileNotFoundError: gltf_buffer_0.bin"."""
    from isoflow.cli import main

    scene = trimesh.Scene([trimesh.creation.box()])
    for name, data in scene.export(file_type="gltf").items():
        (tmp_path / name).write_bytes(data)
    tree = json.loads((tmp_path / "model.gltf").read_text())
    uri = tree["buffers"][0]["uri"]
    assert main(["genus", str(tmp_path / "model.gltf"), "--no-step", "--resolution", "8"]) == 0
    capsys.readouterr()
    (tmp_path / uri).unlink()
    assert main(["genus", str(tmp_path / "model.gltf")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"model.gltf: buffer 0 is the file '{uri}', which is not there ({tmp_path / uri})" in err[0]


def fan_capped_box_glb(path, fans: int = 1) -> None:
    """A GLB of a unit box whose top is a primitive of its own drawn as a
    triangle fan (glTF mode 6) of its four corners (``fans`` such
    primitives, each the same fan), the other ten triangles a primitive
    of mode 4."""
    box = trimesh.creation.box()
    v = box.vertices.astype(np.float32)
    top = np.all(v[box.faces][:, :, 2] > 0, axis=1)
    sides = box.faces[~top].astype(np.uint32)
    corners = np.flatnonzero(v[:, 2] > 0)
    # the four top corners around the centre, counter-clockwise seen from above (outward)
    fan = corners[np.argsort(np.arctan2(v[corners, 1], v[corners, 0]))].astype(np.uint32)
    binary = v.tobytes() + sides.tobytes() + fan.tobytes()
    views = [(0, v.nbytes), (v.nbytes, sides.nbytes), (v.nbytes + sides.nbytes, fan.nbytes)]
    tree = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "box"}],
        "meshes": [{"name": "capped", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4},
                                                     *[{"attributes": {"POSITION": 0}, "indices": 2, "mode": 6}]
                                                     * fans]}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [{"buffer": 0, "byteOffset": o, "byteLength": n} for o, n in views],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3",
                       "min": v.min(0).tolist(), "max": v.max(0).tolist()},
                      {"bufferView": 1, "componentType": 5125, "count": sides.size, "type": "SCALAR"},
                      {"bufferView": 2, "componentType": 5125, "count": fan.size, "type": "SCALAR"}],
    }
    text = json.dumps(tree).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    path.write_bytes(b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(text)) + b"JSON" + text
                     + struct.pack("<I", len(binary)) + b"BIN\0" + binary)


@pytest.mark.parametrize("archived", [False, True], ids=["file", "in a zip"])
@pytest.mark.parametrize("command", MESH_COMMANDS)
def test_a_triangle_fan_trimesh_skips_is_refused(tmp_path, capsys, command, archived):
    """trimesh reads a glTF primitive of mode 6 as nothing: the box comes
    back open, its top missing, and was voxelised and counted so."""
    import zipfile

    path = tmp_path / "capped.glb"
    fan_capped_box_glb(path)
    read = trimesh.load(path, force="mesh", process=False)
    assert len(read.faces) == 10 and not read.is_watertight  # the fan's two triangles are not read
    where = str(path)
    if archived:
        with zipfile.ZipFile(tmp_path / "model.zip", "w") as z:
            z.write(path, "capped.glb")
        path, where = tmp_path / "model.zip", f"{tmp_path / 'model.zip'}:capped.glb"
    line = refusal(capsys, tmp_path, command, path)
    assert f"{where}: mesh 0 ('capped') primitive 1 is drawn as a triangle fan (glTF mode 6)" in line


def test_triangle_fans_are_named_in_a_sentence(tmp_path, capsys):
    """Three fan primitives: the first named, the other two counted, and
    the verb agrees with them (the count once followed the sentence's
    verb in brackets: "primitive 1 is drawn as a triangle fan (glTF mode 6)
    (and 2 more)")."""
    path = tmp_path / "capped.glb"
    fan_capped_box_glb(path, fans=3)
    assert len(trimesh.load(path, force="mesh", process=False).faces) == 10  # none of the three fans is read
    line = refusal(capsys, tmp_path, ["genus"], path)
    assert f"{path}: mesh 0 ('capped') primitive 1 and 2 more are drawn as triangle fans (glTF mode 6), " in line


def box_gltf(path, modes) -> None:
    """A ``.gltf`` (its buffer embedded as base64) of a unit box's eight
    corners drawn by one primitive per mode of ``modes``: mode 4 its twelve
    triangles, 1 its edges as lines, 2 and 3 its corners as a line loop
    and strip, 0 its corners as points."""
    import base64

    box = trimesh.creation.box()
    v = box.vertices.astype(np.float32)
    by_mode = {4: box.faces.astype(np.uint32).ravel(), 1: box.edges_unique.astype(np.uint32).ravel(),
               2: np.arange(8, dtype=np.uint32), 3: np.arange(8, dtype=np.uint32), 0: None}
    blobs = [v.tobytes()]
    accessors = [{"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3",
                  "min": v.min(0).tolist(), "max": v.max(0).tolist()}]
    primitives = []
    for mode in modes:
        primitive = {"attributes": {"POSITION": 0}, "mode": mode}
        if by_mode[mode] is not None:
            blobs.append(by_mode[mode].tobytes())
            accessors.append({"bufferView": len(blobs) - 1, "componentType": 5125, "count": by_mode[mode].size,
                              "type": "SCALAR"})
            primitive["indices"] = len(accessors) - 1
        primitives.append(primitive)
    starts = np.cumsum([0] + [len(b) for b in blobs])
    data = b"".join(blobs)
    tree = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "box"}],
        "meshes": [{"name": "edged", "primitives": primitives}],
        "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": int(o), "byteLength": len(b)} for o, b in zip(starts, blobs)],
        "accessors": accessors,
    }
    path.write_text(json.dumps(tree))


@pytest.mark.parametrize("mode", [1, 2, 3], ids=["LINES", "LINE_LOOP", "LINE_STRIP"])
@pytest.mark.parametrize("command", [*MESH_COMMANDS, ["info"]])
def test_a_gltf_of_lines_is_refused_naming_them(tmp_path, capsys, command, mode):
    """A box's edges or corners drawn as glTF lines: trimesh reads no
    face; the line said "no triangles read (empty mesh, or not a
    valid GLTF file)", or, split, "no node of the scene holds a triangle
    mesh", neither saying what the file holds."""

    path = tmp_path / "edges.gltf"
    box_gltf(path, [mode])
    read = trimesh.load(path, force="scene")  # a path of the lines (of a loop or strip: nothing)
    assert not any(isinstance(g, trimesh.Trimesh) and len(g.faces) for g in read.geometry.values())
    line = refusal(capsys, tmp_path, command, path)
    assert f"{path}: no triangles read: its primitives are lines (glTF mode {mode}), not triangles" in line


@pytest.mark.parametrize("split", [False, True])
def test_lines_beside_triangles_are_named_in_a_note(tmp_path, capsys, split):
    """A box's triangles and, as primitives of the same mesh, its edges as
    lines and its corners as points (as CAD exporters add edges): trimesh
    reads the triangles and leaves the others out without a word; the box
    is voxelised whole (volume 1, as trimesh's volume of the triangles),
    and a note names what was left out."""
    from isoflow import read_volume
    from isoflow.cli import main

    path = tmp_path / "edged.gltf"
    box_gltf(path, [4, 1, 0])
    read = trimesh.load(path, force="mesh", process=False)
    assert len(read.faces) == 12 and read.volume == pytest.approx(1.0)
    out = tmp_path / "out.npz"
    assert main(["voxelize", str(path), "--resolution", "8", "-o", str(out), *(["--split"] if split else [])]) == 0
    err = capsys.readouterr().err
    assert (f"note: {path}: read without 2 primitives of lines (glTF mode 1) and points (glTF mode 0), mesh 0 "
            "('edged') primitive 1 the first: they hold no face and bound no solid") in err, err
    obj = read_volume(out)
    assert np.count_nonzero(np.asarray(obj.volume)) * float(np.prod(np.broadcast_to(obj.pitch, 3))) == pytest.approx(read.volume)
