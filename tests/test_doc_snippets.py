"""The snippets of README.md and docs/*.md use isoflow as it is: every
``isoflow.NAME(...)`` of a Python snippet (or a name imported from isoflow)
exists and takes the keywords the snippet gives; every command line of a
shell snippet is one the parser takes, and every option an inline command
names is that command's; the keys the pages name for ``info --json`` and
``flow --json`` are the keys printed, and every key printed is named. The
snippets need files they do not make, so they are read, not run."""

from __future__ import annotations

import argparse
import ast
import contextlib
import inspect
import io
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import isoflow
from isoflow.cli.main import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def snippets(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), re.S)


def calls(code: str) -> list[tuple[str, list[str], int]]:
    """(public name, keywords, line) of every call of a public function."""
    tree = ast.parse(code)
    imported = {a.asname or a.name: a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
                and node.module == "isoflow" for a in node.names}
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) and f.value.id == "isoflow":
            name = f.attr
        elif isinstance(f, ast.Name) and f.id in imported:
            name = imported[f.id]
        else:
            continue
        found.append((name, [k.arg for k in node.keywords if k.arg], node.lineno))
    return found


@pytest.mark.parametrize("page", [p for p in PAGES if snippets(p)], ids=lambda p: p.name)
def test_snippets_call_the_api_as_it_is(page):
    wrong = []
    for code in snippets(page):
        for name, keywords, line in calls(code):
            if name not in isoflow.__all__:
                wrong.append(f"line {line}: isoflow.{name} is not public")
                continue
            obj = getattr(isoflow, name)
            if not callable(obj) or isinstance(obj, type):
                continue
            params = inspect.signature(obj).parameters
            if any(p.kind is p.VAR_KEYWORD for p in params.values()):
                continue
            wrong += [f"line {line}: {name}() takes no {k}=" for k in keywords if k not in params]
    assert not wrong, wrong


#: a command line of isoflow's in a snippet, up to a comment, pipe, redirection or the span's end
COMMAND = re.compile(r"(?<![\w/.-])isoflow (info|surface|voxelize|genus|flow|completion)\b(?!:)[^#|&>`)\"\n]*")
#: isoflow's commands, which a paragraph about a command's keys names too
COMMANDS = {"info", "surface", "voxelize", "genus", "flow", "completion"}


def shell_lines(page: Path) -> list[str]:
    """The lines of the page's fenced shell snippets (```bash, ```sh, or a
    plain fence), continuation lines joined."""
    lines, fence = [], None
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            fence = line[3:].strip() if fence is None else None
            continue
        if fence in ("bash", "sh", "shell", "console", ""):
            if lines and lines[-1].endswith("\\"):
                lines[-1] = lines[-1][:-1] + line
            else:
                lines.append(line)
    return lines


def refusal(argv: list[str]) -> str | None:
    """What the parser says of a command line, or None where it takes it."""
    said = io.StringIO()
    try:
        with contextlib.redirect_stderr(said), contextlib.redirect_stdout(io.StringIO()):
            build_parser().parse_args(argv)
    except SystemExit:
        return said.getvalue().strip().splitlines()[-1]
    return None


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_shell_snippets_are_command_lines_the_parser_takes(page):
    wrong = []
    for line in shell_lines(page):
        for match in COMMAND.finditer(line):
            text = match.group(0).strip()
            if "[" in text or "..." in text:  # a synopsis, not a command line
                continue
            said = refusal(shlex.split(text)[1:])
            if said:
                wrong.append(f"{text}: {said}")
    assert not wrong, wrong


def options_of(command: str) -> set[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    return {option for action in sub._actions for option in action.option_strings}


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_inline_commands_name_options_the_command_has(page):
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    wrong = []
    for span in re.findall(r"`([^`]+)`", text):
        for match in COMMAND.finditer(span):
            options = options_of(match.group(1))
            for option in re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", match.group(0)):
                if option not in options:
                    wrong.append(f"{match.group(0).strip()}: isoflow {match.group(1)} has no {option}")
    assert not wrong, wrong


def named_keys(page: str, opening: str) -> set[str]:
    """The identifiers in backticks in the paragraph of ``page`` that begins
    with ``opening``, less the names of commands."""
    text = (ROOT / "docs" / page).read_text()
    start = text.index(opening)
    paragraph = text[start:text.index("\n\n", start)]
    return set(re.findall(r"`([a-z][a-z0-9_]*)`", paragraph)) - COMMANDS


def keys_in(value) -> set[str]:
    """Every key of a JSON value, at any depth."""
    if isinstance(value, dict):
        return set(value).union(*(keys_in(v) for v in value.values()))
    if isinstance(value, list):
        return set().union(*(keys_in(v) for v in value))
    return set()


def printed(capsys, argv: list[str]) -> dict:
    capsys.readouterr()
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_the_keys_named_for_info_json_are_those_printed(tmp_path, capsys):
    volume = np.zeros((7, 7, 7), bool)
    volume[1:6, 1:6, 1:6] = True
    volume[2:5, 2:5, 1:6] = False  # a tube: a tunnel, one closed surface
    np.save(tmp_path / "tube.npy", volume)
    report = printed(capsys, ["info", str(tmp_path / "tube.npy"), "--json"])
    named = named_keys("cli.md", "`info --json` prints one object with")
    assert set(report) <= named, set(report) - named
    # a mesh's report adds the grid its voxels are
    mesh = printed(capsys, ["info", str(ROOT / "meshes" / "torus.obj"), "--resolution", "8", "--json", "-q"])
    assert set(mesh) <= named, set(mesh) - named
    # a 2D report keys its classes by name (convex, flat, concave)
    np.save(tmp_path / "square.npy", np.pad(np.ones((3, 3), bool), 1))
    planar = printed(capsys, ["info", str(tmp_path / "square.npy"), "--json"])
    assert set(planar) <= named, set(planar) - named
    printed_keys = keys_in(report) | keys_in(mesh) | keys_in(planar)
    assert named <= printed_keys, named - printed_keys
    bare = printed(capsys, ["info", str(tmp_path / "tube.npy"), "--json", "--no-surfaces"])
    assert set(report) - set(bare) == {"surfaces", "pinched_vertices", "doubled_edges"}


def test_the_keys_named_for_flow_json_are_those_printed(tmp_path, capsys):
    volume = np.zeros((8, 8, 8), bool)
    volume[1:7, 1:7, 1:7] = True
    volume[3:5, 3:5, 1:7] = False  # a ring: the guard keeps its tunnel
    np.save(tmp_path / "ring.npy", volume)
    named = named_keys("flow.md", "`--json` prints one object:")
    plain = printed(capsys, ["flow", str(tmp_path / "ring.npy"), "--json"])
    guarded = printed(capsys, ["flow", str(tmp_path / "ring.npy"), "--guard", "--json"])
    top = set(plain) | set(guarded)
    assert top <= named, top - named
    assert named <= keys_in(plain) | keys_in(guarded), named - keys_in(plain) - keys_in(guarded)


def _cells(*cells: tuple[int, ...]) -> np.ndarray:
    """A 4D image of the given cells (coordinates 0 or 1, in a 2x2x2x2 box)."""
    image = np.zeros((2, 2, 2, 2), bool)
    for cell in cells:
        image[cell] = True
    return image


#: the objects of ndim.md's eq. 6.3 table, by the text of its object column
ENERGY_OBJECTS = {
    "boxes": [_cells((0, 0, 0, 0)), _cells((0, 0, 0, 0), (1, 0, 0, 0))],
    "two cells sharing a 2-face / an edge / a vertex": [
        _cells((0, 0, 0, 0), (1, 1, 0, 0)), _cells((0, 0, 0, 0), (1, 1, 1, 0)), _cells((0, 0, 0, 0), (1, 1, 1, 1))],
    "an L: cells `(0,0,0,0), (1,0,0,0), (0,1,0,0)` (well-composed)": [
        _cells((0, 0, 0, 0), (1, 0, 0, 0), (0, 1, 0, 0))],
    "two cells sharing a 2-face (two components)": [_cells((0, 0, 0, 0), (1, 1, 0, 0))],
}


def test_the_4d_energies_of_ndim_md_are_the_code_s(tmp_path, capsys):
    """ndim.md's table of eq. 6.3 gave ``E = 226`` for two cells sharing a
    corner where ``isoflow info`` prints ``energy 30``: the table's ``E`` is
    ``ndim.surface_energy`` (every vertex), the report's sums the 45
    manifold classes. Each row's two figures are the code's, at each
    adjacency it names; and the report's for two cells is the 32 corners
    less two per shared vertex (each a single cell, ``a = 1``)."""
    from isoflow.digital.ndim import surface_energy

    text = (ROOT / "docs" / "ndim.md").read_text()
    header = "| adjacency | cells | object | Betti | `E` | `2^n (1 + g)` | `info`'s `energy` |"
    table = text[text.index(header):].split("\n\n")[0].splitlines()[2:]
    assert len(table) == len(ENERGY_OBJECTS)
    for row in table:
        adjacency, _, name, _, energy, _, reported = (c.strip() for c in row.strip("|").split("|"))
        images = ENERGY_OBJECTS[name]
        said = [[int(x) for x in column.split(" / ")] * (len(images) if " / " not in column else 1)
                for column in (energy, reported)]
        for image, e, r in zip(images, *said):
            for conn in {"both": (8, 80), "full": (80,), "face": (8,)}[adjacency]:
                np.save(tmp_path / "c.npy", image)
                report = printed(capsys, ["info", str(tmp_path / "c.npy"), "--json", "--connectivity", str(conn)])
                assert (surface_energy(image, conn), report["energy"]) == (e, r), (name, conn)
                if image.sum() == 2 and name != "boxes":
                    shared = 2 ** (4 - int(np.abs(np.subtract(*np.argwhere(image))).sum()))
                    assert r == 32 - 2 * shared, name
    assert "its energy is `E = 238` (`info`'s\n`energy` leaves out the centre vertex, not a manifold point, `a = 14`: 42)" in text
    block = np.zeros((4, 4, 4, 4), bool)
    block[1:3, 1:3, 1:3, 1:3] = True
    block[1, 1, 1, 1] = block[2, 2, 2, 2] = False
    assert (surface_energy(block, 8), isoflow.analyze(block, 8).energy) == (238, 42)
    corner = isoflow.analyze(_cells((0, 0, 0, 0), (1, 1, 1, 1)), 8)  # the inequality is E's, not the report's
    assert "not keep it (the two cells sharing a vertex under face adjacency are two\ncomponents, and `energy` 30 < 32)" in text
    assert (corner.betti[0], corner.energy) == (2, 30) and surface_energy(_cells((0, 0, 0, 0), (1, 1, 1, 1)), 8) >= 32


def test_the_cube_sides_named_for_the_compiled_thresholds_are_the_first_that_take_them():
    """large-volumes.md and dependencies.md said 2 million voxels was 128^3
    (126^3 = 2,000,376 already takes the compiled passes): every ``N
    million voxels (S^3)`` and ``N million, S^3`` of the pages names the
    smallest cube at the threshold, and the thresholds are the code's."""
    from isoflow.scale.compiled import least_voxels

    said = re.compile(r"(\d) million(?: voxels)?,? \((\d+)\^3\)|(\d) million, (\d+)\^3")
    seen = set()
    for page in PAGES:
        for m in said.finditer(" ".join(page.read_text().split())):
            millions, side = (int(g) for g in (m.group(1, 2) if m.group(1) else m.group(3, 4)))
            assert millions * 1_000_000 in (least_voxels(), least_voxels(surfaces=True)), (page.name, m.group(0))
            assert (side - 1) ** 3 < millions * 1_000_000 <= side ** 3, (page.name, m.group(0))
            seen.add((page.name, millions))
    assert {("large-volumes.md", 2), ("large-volumes.md", 4), ("dependencies.md", 2), ("surface.md", 4)} <= seen


def test_the_flow_figures_of_flow_md_are_the_code_s():
    """flow.md's small examples, each run as the page says: the 3x4x5 box,
    the rectangle, the L of five squares, Example 19's limit, the two cubes
    sharing an edge at 6 and 26, one thinning step of the box and the
    solid torus of the pictures."""
    import sys

    from isoflow.flow.guard import thinning_step

    text = " ".join((ROOT / "docs" / "flow.md").read_text().split())

    def voxels(volume, connectivity=6):
        return [s["voxels"] for s in isoflow.run_flow(volume, connectivity=connectivity).steps]

    assert "the 3x4x5 box gives 60, 24, 6, 0 voxels" in text
    assert voxels(np.ones((3, 4, 5), bool)) == [60, 24, 6, 0]
    assert "A rectangle loses one row and one column per step" in text
    assert voxels(np.ones((3, 6), bool), 4) == [18, 10, 4, 0]
    assert "the L of five squares with arms of length 3 gives 5, 3, 1, 0 pixels" in text
    ell = np.zeros((3, 3), bool)
    ell[:, 0] = ell[2, :] = True
    assert voxels(ell, 4) == [5, 3, 1, 0]
    assert "the limit is the point `(1,1,1)`" in text and "the single cube `[0.5, 1.5]^3`" in text
    run = isoflow.run_flow(isoflow.read_object(isoflow.data.example19()))
    assert run.steps[1]["bbox"] == [0.5] * 3 + [1.5] * 3 and run.limit["center"] == [1.0, 1.0, 1.0]
    assert ("Two 2x2x2 cubes sharing an edge become two separate points under 6 and stay one piece joined along "
            "the shared edge under 26") in text
    cubes = np.zeros((4, 4, 2), bool)
    cubes[:2, :2] = cubes[2:, 2:] = True
    two = isoflow.run_flow(cubes, steps=1, connectivity=6).steps[1]
    one = isoflow.run_flow(cubes, steps=1, connectivity=26).steps[1]
    assert (two["voxels"], two["betti"][0], one["betti"][0]) == (2, 2, 1)
    assert "One thinning step of a 3x4x5 box removes its outer layer" in text
    box = np.zeros((5, 6, 7), bool)
    box[1:4, 1:5, 1:6] = True
    inner = np.zeros_like(box)
    inner[2:3, 2:4, 2:5] = True
    assert np.array_equal(thinning_step(box, 6), inner)
    assert "A solid torus (R = 7, r = 3, 1280 voxels)" in text
    sys.path.insert(0, str(ROOT / "tests" / "flow"))
    try:
        import shapes
    finally:
        sys.path.remove(str(ROOT / "tests" / "flow"))
    assert int(shapes.solid_torus(7, 3).sum()) == 1280


def test_the_stl_rule_of_formats_md_is_the_code_s(tmp_path, capsys):
    """formats.md said that an STL that would move a vertex is refused;
    ``surface`` writes one wherever float32 keeps the corners apart (a
    pitch of 1/3 moves them) and refuses only where it would merge them
    (a pitch of 0.1 at 4e6, where float32 positions are 0.25 apart)."""
    text = " ".join((ROOT / "docs" / "formats.md").read_text().split())
    rule = text[text.index("Binary STL holds float32 only"):]
    rule = rule[:rule.index("Tested on")]
    assert "written where float32 keeps" in rule and "refused (exit 2, nothing written) where float32 would merge" in rule
    volume = np.zeros((6, 6, 6), bool)
    volume[1:5, 1:5, 1:5] = True
    isoflow.write_volume(isoflow.DigitalObject(volume, pitch=1 / 3), tmp_path / "third.npz")
    assert main(["surface", str(tmp_path / "third.npz"), "-o", str(tmp_path / "third.stl"), "-q"]) == 0
    corners = np.fromfile(tmp_path / "third.stl", dtype=np.uint8)[84:].reshape(-1, 50)[:, 12:48].copy()
    moved = corners.view(np.float32).astype(float) * 3
    assert not np.allclose(moved, np.round(moved), rtol=0, atol=1e-12)  # float32 moved them, and it is written
    isoflow.write_volume(isoflow.DigitalObject(volume, pitch=0.1, origin=(4e6, 0, 0)), tmp_path / "far.npz")
    capsys.readouterr()
    assert main(["surface", str(tmp_path / "far.npz"), "-o", str(tmp_path / "far.stl")]) == 2
    assert "would merge" in capsys.readouterr().err and not (tmp_path / "far.stl").exists()


def test_the_readme_s_label_table_of_a_file_is_in_its_world_units(tmp_path):
    """README.md said ``label_table(read_labels(FILE))`` is "in its voxel
    units"; the file's voxel size and origin place and scale the rows."""
    import nibabel

    readme = (ROOT / "README.md").read_text()
    line = next(s for s in readme.splitlines() if "isoflow.label_table(isoflow.read_labels(" in s)
    assert "voxel units" not in line and "voxel size and origin" in line
    image = np.zeros((4, 4, 4), np.uint8)
    image[1:3, 1:3, 1:3] = 3
    nibabel.save(nibabel.Nifti1Image(image, np.diag([0.5, 0.5, 2.0, 1.0])), tmp_path / "seg.nii.gz")
    table = isoflow.label_table(isoflow.read_labels(tmp_path / "seg.nii.gz"))
    assert table["voxels"].tolist() == [8] and table["volume"].tolist() == [8 * 0.5 * 0.5 * 2.0]


def test_cli_md_s_calibration_and_measure_lines_are_one_file_s(tmp_path):
    """cli.md quoted info's calibration line and measure lines as of one
    file, but no file gives them: voxels of 0.5 x 0.5 x 2 mm at the origin
    0 have no corner at 1.25 or 2.45, nor 939.4 of them a volume of 469.7
    mm^3. Its example is a ball in such a NIfTI file; the lines are worked
    out here from the voxels with NumPy, and the page and the command give
    them alike."""
    import nibabel

    pitch = np.array([0.5, 0.5, 2.0])
    i, j, k = np.indices((16, 18, 10))
    ball = ((i - 8) * 0.5) ** 2 + ((j - 9.5) * 0.5) ** 2 + ((k - 5) * 2.0) ** 2 <= 3.5**2
    affine = np.diag([*pitch, 1.0])
    affine[:3, 3] = pitch / 2  # NIfTI places voxel centres: voxel 0's lowest corner at 0
    image = nibabel.Nifti1Image(ball.astype(np.uint8), affine)
    image.header.set_xyzt_units("mm")
    nibabel.save(image, tmp_path / "ball.nii.gz")

    faces = [np.count_nonzero(np.diff(np.pad(ball, 1), axis=a)) for a in range(3)]
    area = sum(n * np.prod(np.delete(pitch, a)) for a, n in enumerate(faces))
    voxels = np.argwhere(ball)
    low, high, centre = voxels.min(0) * pitch, (voxels.max(0) + 1) * pitch, (voxels.mean(0) + 0.5) * pitch
    listed = lambda v: ", ".join(f"{x:g}" for x in v)
    quoted = ["voxel size 0.5 x 0.5 x 2 mm, origin [0, 0, 0] mm, frame RAS",
              f"volume {len(voxels) * pitch.prod():g} mm^3, surface area {area:g} mm^2",
              f"bounding box [{listed(low)}] to [{listed(high)}] mm, centroid [{listed(centre)}] mm"]

    page = " ".join((ROOT / "docs" / "cli.md").read_text().split())
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", "ball.nii.gz"], capture_output=True, text=True,
                          cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    printed = [" ".join(line.split()) for line in done.stdout.splitlines()[1:4]]
    assert printed == quoted
    for line in quoted:
        assert f"`{line}`" in page, line
    assert f"({len(voxels)} voxels)" in page


def test_getting_started_says_which_values_a_file_may_hold(tmp_path):
    """getting-started.md said 2 or 255 is refused; an array of them is,
    but a file of 0 and one other value is read as that value's mask (as
    formats.md says), and one of two other values is a label image."""
    text = " ".join((ROOT / "docs" / "getting-started.md").read_text().split())
    assert "A file is read as a mask where it holds 0 and one other value" in text
    volume = np.zeros((4, 4, 4), np.uint8)
    volume[1:3, 1:3, 1:3] = 255
    with pytest.raises(isoflow.IsoflowError):
        isoflow.analyze(volume)
    np.save(tmp_path / "mask.npy", volume)
    assert isoflow.read_volume(tmp_path / "mask.npy").voxels == 8
    volume[1, 1, 1] = 2
    np.save(tmp_path / "labels.npy", volume)
    with pytest.raises(isoflow.IsoflowError, match="--label"):
        isoflow.read_volume(tmp_path / "labels.npy")
    assert isoflow.read_volume(tmp_path / "labels.npy", label=2).voxels == 1


def test_the_pages_say_surface_takes_3d_volumes_only(tmp_path, capsys):
    """cli.md and the README listed 2D volumes (PNG masks) among
    ``surface``'s inputs; ``surface`` refuses them in one line."""
    cli = " ".join((ROOT / "docs" / "cli.md").read_text().split())
    assert "a 2D or 3D boolean or 0/1 array (3D only for `surface`; 4D for `info`)" in cli
    assert "2D PNG for `info` and `flow`" in " ".join((ROOT / "README.md").read_text().split())
    np.save(tmp_path / "square.npy", np.ones((3, 3), bool))
    capsys.readouterr()
    assert main(["surface", str(tmp_path / "square.npy"), "-o", str(tmp_path / "square.ply")]) == 2
    assert "needs a 3D object" in capsys.readouterr().err
    assert main(["flow", str(tmp_path / "square.npy"), "-q"]) == 0


def test_the_glb_curvature_columns_are_as_formats_md_says(tmp_path):
    """formats.md listed the GLB's ``_config``, ``_gamma``... beside the
    PLY's columns as if alike; the file's accessors are VEC4 (glTF's 4-byte
    alignment), the value first: what the page now says, checked on the
    file's own JSON and on trimesh's reading against the PLY's columns."""
    import struct

    import trimesh

    text = " ".join((ROOT / "docs" / "formats.md").read_text().split())
    assert "are each a `VEC4` whose first component is the value" in text and "`[:, 0]` is the PLY's `gamma`" in text
    volume = np.zeros((4, 4, 3), bool)
    volume[1:3, 1:3, 1] = True
    volume[1, 1, 1] = False  # an L of three voxels: convex, flat and concave vertices
    np.save(tmp_path / "v.npy", volume)
    for suffix in (".glb", ".ply"):
        assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / f"s{suffix}"), "-q"]) == 0
    data = (tmp_path / "s.glb").read_bytes()
    gltf = json.loads(data[20:20 + struct.unpack("<I", data[12:16])[0]])
    attributes = gltf["meshes"][0]["primitives"][0]["attributes"]
    types = {name: (gltf["accessors"][i]["type"], gltf["accessors"][i]["componentType"]) for name, i in attributes.items()}
    assert types["_config"] == ("VEC4", 5121) and all(types[f"_{n}"] == ("VEC4", 5120) for n in ("class", "gamma", "a", "f"))
    glb = next(iter(trimesh.load(tmp_path / "s.glb", process=False).geometry.values()))
    ply = trimesh.load(tmp_path / "s.ply", process=False)
    row = np.lexsort(ply.vertices.T)
    order = np.lexsort(glb.vertices.T)
    columns = ply.metadata["_ply_raw"]["vertex"]["data"]
    for name in ("config", "class", "gamma", "a", "f"):
        got = glb.vertex_attributes[f"_{name}"]
        assert got.shape == (len(ply.vertices), 4) and not got[:, 1:].any()
        assert (got[order, 0] == columns[name][row]).all()


def test_surface_md_names_what_the_file_holds(tmp_path):
    """surface.md pointed to a "DESIGN section 3" that is nowhere in the
    project and said every vertex carries the codes and the normal, which
    no file holds; it now names the PLY's columns, which the header lists,
    and the tables that give the normal from ``config``: on one voxel,
    each corner's normal points away from the voxel's centre."""
    import trimesh

    text = " ".join((ROOT / "docs" / "surface.md").read_text().split())
    assert "DESIGN" not in text and not list(ROOT.glob("DESIGN*"))
    assert "DESIGN" not in isoflow.ClosedSurface.__doc__  # the API page's text
    np.save(tmp_path / "v.npy", np.ones((1, 1, 1), bool))
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "s.ply"), "-q"]) == 0
    header = (tmp_path / "s.ply").read_bytes().split(b"end_header")[0].decode()
    columns = [line.split()[-1] for line in header.splitlines() if line.startswith("property ") and "list" not in line]
    named = [c for c in columns if c not in ("x", "y", "z", "red", "green", "blue")]
    assert "written as the PLY columns " + ", ".join(f"`{c}`" for c in named[:-1]) + f", `{named[-1]}`" in text
    assert "`isoflow.normal_lut()[config]`" in text
    ply = trimesh.load(tmp_path / "s.ply", process=False)
    config = ply.metadata["_ply_raw"]["vertex"]["data"]["config"]
    assert (isoflow.normal_lut()[config] == np.sign(ply.vertices - 0.5)).all()


def test_the_glb_transform_is_read_as_formats_md_says(tmp_path):
    """formats.md said that readers apply a GLB node's transform; trimesh
    applies it when it makes one mesh, pymeshlab keeps it apart (voxel
    units, the transform beside them) until ``apply_matrix_freeze``: what
    the page now says, on the file ``surface`` writes at 4e6 with a pitch
    of 0.1, and that a pitch of 0.5 at (1, 2, 3) has no transform."""
    import pymeshlab
    import trimesh

    text = " ".join((ROOT / "docs" / "formats.md").read_text().split())
    assert "trimesh applies it when it makes one mesh of the scene" in text
    assert ("pymeshlab keeps it apart: `MeshSet.load_new_mesh(path)` gives a mesh whose `vertex_matrix()` is in "
            "voxel units") in text
    assert "a pitch of 0.5 at (1, 2, 3) is stored in world units with no transform" in text
    volume = np.zeros((4, 4, 4), bool)
    volume[1:3, 1:3, 1:3] = True
    corners = np.array([[1.0, 1.0, 1.0], [3.0, 3.0, 3.0]])  # the object's box in voxel units
    for name, pitch, origin in (("far", 0.1, (4e6, 2e6, -3e6)), ("near", 0.5, (1.0, 2.0, 3.0))):
        isoflow.write_volume(isoflow.DigitalObject(volume, pitch=pitch, origin=origin), tmp_path / f"{name}.npz")
        path = tmp_path / f"{name}.glb"
        assert main(["surface", str(tmp_path / f"{name}.npz"), "-o", str(path), "-q"]) == 0
        world = np.asarray(origin) + pitch * corners
        assert np.allclose(trimesh.load(path, force="mesh", process=False).bounds, world, rtol=0, atol=1e-9)
        geometry = next(iter(trimesh.load(path).geometry.values()))
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(path))
        mesh = ms.current_mesh()
        box = np.array([mesh.vertex_matrix().min(axis=0), mesh.vertex_matrix().max(axis=0)])
        if name == "near":  # float32 holds the world positions: no transform, both readers alike
            assert np.array_equal(mesh.transform_matrix(), np.eye(4)) and np.allclose(box, world, rtol=0, atol=1e-6)
            assert np.allclose(geometry.bounds, world, rtol=0, atol=1e-6)
            continue
        assert np.array_equal(box, corners) and np.array_equal(geometry.bounds, corners)  # voxel units
        transform = np.diag([pitch, pitch, pitch, 1.0])
        transform[:3, 3] = origin
        assert np.array_equal(mesh.transform_matrix(), transform)
        placed = mesh.transformed_vertex_matrix()
        assert np.allclose([placed.min(axis=0), placed.max(axis=0)], world, rtol=0, atol=1e-6)
        assert np.array_equal(ms.get_geometric_measures()["bbox"].min(), corners[0])
        ms.save_current_mesh(str(tmp_path / "saved.ply"))
        assert np.allclose(trimesh.load(tmp_path / "saved.ply").bounds, corners, atol=1e-6)  # the transform lost
        ms.apply_filter("apply_matrix_freeze")
        frozen = ms.current_mesh().vertex_matrix()
        assert np.allclose([frozen.min(axis=0), frozen.max(axis=0)], world, rtol=0, atol=1e-6)


def test_the_readme_says_which_install_reads_the_volumes_it_uses():
    """The README's install line is ``pip install -e .`` and its snippets
    wrote and read ``.nii.gz``, ``.tif`` and ``.zarr`` volumes, whose
    libraries pyproject.toml lists under ``formats`` only: a new user met
    "NIfTI files need nibabel" with nothing in the README saying so."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    core = {re.split(r"[<>=\[ ]", d)[0].lower() for d in project["dependencies"]}
    formats = {re.split(r"[<>=\[ ]", d)[0].lower() for d in project["optional-dependencies"]["formats"]}
    readme = (ROOT / "README.md").read_text()
    code = "\n".join(re.findall(r"```(?:bash|python)\n(.*?)```", readme, re.S))
    library = {".nii.gz": "nibabel", ".tif": "tifffile", ".zarr": "zarr", ".h5": "h5py", ".nrrd": "pynrrd"}
    extra = {suffix for suffix, name in library.items() if suffix in code and name not in core and name in formats}
    assert extra and "pip install -e '.[formats]'" in readme
    python = "\n".join(snippets(ROOT / "README.md")).splitlines()
    assert all("isoflow[formats]" in line for line in python if any(f'{s}"' in line for s in extra) and "write_" in line)
    assert "pillow" in core  # PNG masks, said to come with the plain install


def test_the_files_the_readme_names_are_in_a_checkout():
    """The README listed ``docs/api.rst`` among the pages "readable here
    too"; Sphinx's build writes it (.gitignore), so a fresh clone has none.
    Every file the README links or names is tracked by git, or its line
    says the build writes it."""
    import shutil
    import subprocess

    git = shutil.which("git")
    if git is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    tracked = set(subprocess.run([git, "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split())
    missing = []
    for line in (ROOT / "README.md").read_text().splitlines():
        named = re.findall(r"\]\(([^)#]+)\)", line) + re.findall(r"`([\w.-]+/[\w./-]*\.\w+)`", line)
        missing += [name for name in named if name not in tracked and "written by the build" not in line]
    assert not missing, missing


def test_cli_md_says_what_a_shortened_option_prints(capsys):
    """cli.md said a shortened option (``--res``) is "refused in one line";
    the command prints its usage first, as for any argument it does not know
    (the usage lists the options), then the error line the page quotes."""
    text = " ".join((ROOT / "docs" / "cli.md").read_text().split())
    quoted = "unrecognized arguments: --res 32 (--res: did you mean --resolution?)"
    assert "refused in one line naming the options it begins" not in text
    assert f"with the command's usage and one error line naming the options it begins (`{quoted}`)" in text
    with pytest.raises(SystemExit) as done:
        main(["info", str(ROOT / "meshes" / "bob_small.ply"), "--res", "32"])
    err = capsys.readouterr().err
    assert done.value.code == 2 and err.startswith("usage: isoflow info ") and "--resolution" in err
    assert err.strip().splitlines()[-1] == f"isoflow info: error: {quoted}"


def test_large_volumes_md_gives_the_first_compile_as_measured():
    """The first compile was quoted as "about 12 s" for `isoflow info`; on
    an empty NUMBA_CACHE_DIR it took 21 to 24 s at a load average near 5.
    The page gives a range, the load it was measured at and the machine,
    and the run from the cache far below the compile."""
    text = " ".join((ROOT / "docs" / "large-volumes.md").read_text().split())
    said = re.search(r"caches them \((\d+) to (\d+) s for `isoflow info` of a (\d+)\^3 ball, .*? on the project's "
                     r"shared 2-core machine at a load average of ([\d.]+) to ([\d.]+), .*?; ([\d.]+) to ([\d.]+) s "
                     r"from the cache", text)
    assert said, "large-volumes.md: the first compile's range, load and machine"
    low, high, _, load_low, load_high, cached_low, cached_high = map(float, said.groups())
    assert low < high and load_low <= load_high and cached_low <= cached_high < low / 10


def synopses(page: Path) -> list[tuple[str, str]]:
    """(command, text) of every synopsis in the page's fenced blocks: a line
    ``isoflow CMD ... [--option ...]`` with the indented lines of brackets
    that go on with it."""
    found: list[tuple[str, str]] = []
    for block in re.findall(r"```[^\n]*\n(.*?)```", page.read_text(), re.S):
        going_on = False
        for line in block.splitlines():
            match = COMMAND.match(line)
            if match and "[" in line:
                found.append((match.group(1), line))
                going_on = True
            elif going_on and line.startswith(" ") and line.strip().startswith("["):
                found[-1] = (found[-1][0], found[-1][1] + " " + line.strip())
            else:
                going_on = False
    return found


@pytest.mark.parametrize("page", [p for p in PAGES if synopses(p)], ids=lambda p: p.name)
def test_a_synopsis_lists_every_option_of_its_command(page):
    """A synopsis a page gives (genus.md's) names each option of the command
    in one of its spellings, and no option the command lacks (-h aside)."""
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    for command, text in synopses(page):
        named = set(re.findall(r"(?<![\w-])--?[a-z][a-z0-9-]*", text))
        spellings = [set(a.option_strings) for a in commands[command]._actions
                     if a.option_strings and "--help" not in a.option_strings]
        assert named <= set().union(*spellings), (command, sorted(named - set().union(*spellings)))
        assert all(named & s for s in spellings), (command, [sorted(s) for s in spellings if not named & s])
