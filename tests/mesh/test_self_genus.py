"""A surface isoflow writes, given back to genus, is judged against the voxels
it came from, whose edge and vertex contacts the file splits and a reader
welds. The Betti numbers compared are scipy's and scikit-image's."""

import numpy as np
import pytest
import scipy.ndimage as ndi
from skimage.measure import euler_number

from isoflow.mesh.export import write_surface
from isoflow.mesh.genus import verify_genus

# an STL's warning that readers weld the contacts is what these files are about
pytestmark = pytest.mark.filterwarnings("ignore:.*STL keeps no shared vertices")


def betti(vol: np.ndarray, connectivity: int) -> list[int]:
    """(b0, b1, b2) by scipy's labelling and scikit-image's Euler number:
    the background takes the other connectivity, and a cavity is a
    background component off the padded border."""
    ball = ndi.generate_binary_structure(3, 1 if connectivity == 6 else 3)
    other = ndi.generate_binary_structure(3, 3 if connectivity == 6 else 1)
    b0 = ndi.label(vol, ball)[1]
    b2 = ndi.label(~np.pad(vol, 1), other)[1] - 1
    chi = euler_number(vol, connectivity=1 if connectivity == 6 else 3)
    return [b0, b0 + b2 - chi, b2]


def contacts(vol: np.ndarray) -> tuple[int, int]:
    """Edge contacts (a 2x2 around a lattice edge of two diagonal voxels)
    and vertex contacts (a 2x2x2 of two opposite cells of one kind)."""
    a = np.pad(vol, 1)
    edges = 0
    for ax in range(3):
        b = np.moveaxis(a, ax, 0)
        q00, q11, q01, q10 = b[:, :-1, :-1], b[:, 1:, 1:], b[:, :-1, 1:], b[:, 1:, :-1]
        edges += int(np.sum((q00 == q11) & (q01 == q10) & (q00 != q01)))
    c = np.stack([a[i:a.shape[0] - 1 + i, j:a.shape[1] - 1 + j, k:a.shape[2] - 1 + k]
                  for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    n = c.sum(axis=0)
    pairs = [(0, 7), (1, 6), (2, 5), (3, 4)]
    vertices = sum(int(np.sum((n == 2) & c[x] & c[y]) + np.sum((n == 6) & ~c[x] & ~c[y])) for x, y in pairs)
    return edges, vertices


def random_volume(seed: int) -> np.ndarray:
    """A random volume with edge and vertex contacts of both kinds, whose
    6- and 26-connected Betti numbers differ, filling its bounding box."""
    rng = np.random.default_rng(seed)
    while True:
        vol = rng.random((7, 8, 6)) < 0.45
        vol[0, 0, 0] = vol[-1, -1, -1] = True  # the bounding box is the array
        edges, vertices = contacts(vol)
        if edges and vertices and betti(vol, 6) != betti(vol, 26):
            return vol


@pytest.mark.parametrize("suffix", ["ply", "stl", "glb"])
@pytest.mark.parametrize("connectivity", [6, 26])
@pytest.mark.parametrize("seed", [0, 1])
def test_written_surface_agrees_with_its_voxels(tmp_path, suffix, connectivity, seed):
    vol = random_volume(seed)
    path = write_surface(vol, tmp_path / f"s.{suffix}", connectivity)
    # the longest side is 8 voxels: 8 and 16 across lay the voxels' own grid
    v = verify_genus(path, resolutions=[8, 16], connectivity=connectivity, step=False)
    want = betti(vol, connectivity)
    assert [d["betti"] for d in v.digital] == [want, want]
    assert (v.kind, v.reference, v.bodies, v.reference_source) == ("agree", want[1], want[0], "voxels")
    facts = next(n.facts for n in v.notes if n.kind == "voxel_contacts")
    assert (facts["betti"], facts["other"]) == (want, betti(vol, 32 - connectivity))
    assert facts["voxels"] == int(vol.sum())
    assert facts["written"] == connectivity


def test_other_connectivity_says_how_the_file_was_written(tmp_path):
    vol = random_volume(2)
    path = write_surface(vol, tmp_path / "s.ply", 26)
    v = verify_genus(path, resolutions=[8, 16], connectivity=6, step=False)
    assert (v.kind, v.reference) == ("agree", betti(vol, 6)[1])
    b0, b1, b2 = betti(vol, 26)
    assert f"26-connected, {b0} component" in v.verdict
    assert "the file was written 26-connected (--connectivity 26 reads it as written)" in v.verdict


def test_rabbit_surface_is_its_voxels_genus(tmp_path):
    # the brief's case: 48 edge contacts, 4 vertex contacts of voxels and 2
    # of background, b1 = 2 at 6-connectivity where the split surface has
    # genus 0
    from isoflow.mesh.voxelize import voxelize_file

    obj = voxelize_file("meshes/rabbit.obj", resolution=64)
    vol = np.asarray(obj.volume)
    assert contacts(vol) == (48, 6)
    path = write_surface(obj, tmp_path / "r.stl", 6)
    v = verify_genus(path, resolutions=[64, 128], step=False)
    want = betti(vol, 6)
    assert want == [1, 2, 0] and [d["betti"] for d in v.digital] == [want, want]
    assert (v.kind, v.reference, v.bodies) == ("agree", want[1], want[0])


def test_info_says_why_the_surfaces_genus_is_not_b1(tmp_path):
    # six voxels around a diagonal of a 2x2x2 block: the two empty corners
    # meet at its centre, a vertex contact of the background that the
    # surface splits; 6-connected, the ring has a tunnel through it
    import subprocess
    import sys

    vol = np.ones((2, 2, 2), bool)
    vol[0, 0, 0] = vol[1, 1, 1] = False
    assert contacts(vol) == (0, 1) and betti(vol, 6) == [1, 1, 0]
    np.save(tmp_path / "ring.npy", vol)
    r = subprocess.run([sys.executable, "-m", "isoflow", "info", str(tmp_path / "ring.npy")], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    assert ("pinched vertices       1 (split in the mesh, joined by the connectivity: the surfaces' genus, 0 in all, "
            "counts the sheets apart there, where the connectivity makes 1 tunnel)") in r.stdout


@pytest.mark.parametrize("suffix", ["ply", "stl"])
@pytest.mark.parametrize("seed", [3, 4])
def test_genus_reads_a_file_at_the_connectivity_it_was_written(tmp_path, capsys, suffix, seed):
    import json

    from isoflow.cli import main

    vol = random_volume(seed)
    np.save(tmp_path / "v.npy", vol)
    out = tmp_path / f"s.{suffix}"
    assert main(["surface", str(tmp_path / "v.npy"), "--connectivity", "26", "-o", str(out), "-q"]) == 0
    capsys.readouterr()

    def genus(*extra: str) -> dict:
        assert main(["genus", str(out), "--resolution", "8", "16", "--no-step", "--json", *extra]) == 0
        return json.loads(capsys.readouterr().out)

    as_written = genus()
    want = betti(vol, 26)
    assert [(d["connectivity"], d["betti"]) for d in as_written["digital"]] == [(26, want)] * 2
    assert (as_written["kind"], as_written["reference"], as_written["bodies"]) == ("agree", want[1], want[0])
    assert {"kind": "written_connectivity", "facts": {"connectivity": 26}} in as_written["notes"]
    assert "digital rows 26-connected, as the file was written" in as_written["verdict"]
    # an explicit connectivity wins over the file's
    asked = genus("--connectivity", "6")
    want = betti(vol, 6)
    assert [(d["connectivity"], d["betti"]) for d in asked["digital"]] == [(6, want)] * 2
    assert (asked["kind"], asked["reference"]) == ("agree", want[1])
    assert "written_connectivity" not in [n["kind"] for n in asked["notes"]]
    # the Python default reads the file as the command line does
    assert [d["betti"] for d in verify_genus(out, resolutions=[8, 16], step=False).digital] == [betti(vol, 26)] * 2


@pytest.mark.parametrize("suffix", ["ply", "obj", "stl", "glb"])
def test_genus_reads_each_label_file_at_the_connectivity_it_was_written(tmp_path, capsys, suffix):
    # surface --labels -o DIR/ recorded no connectivity in its files: genus
    # read a 26-connected label's surface 6-connected
    import json

    from isoflow.cli import main

    vol = random_volume(3)
    np.save(tmp_path / "seg.npy", vol.astype(np.uint8) * 5)
    assert main(["surface", str(tmp_path / "seg.npy"), "--labels", "--connectivity", "26", "-o", f"{tmp_path}/out/",
                 "--suffix", suffix, "-q"]) == 0
    capsys.readouterr()
    assert main(["genus", str(tmp_path / "out" / f"label_5.{suffix}"), "--resolution", "8", "--no-step", "--json",
                 "-q"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert [(d["connectivity"], d["betti"]) for d in found["digital"]] == [(26, betti(vol, 26))]


def test_genus_reads_an_stl_of_a_long_name_at_the_connectivity_it_was_written(tmp_path, capsys):
    # the 80-byte header cut "26-connectivity" off after a long input name
    import json

    from isoflow.cli import main

    vol = random_volume(4)
    name = tmp_path / ("subject_0001_session_02_acquisition_t1w_" * 2 + "mask.npy")
    np.save(name, vol)
    out = tmp_path / "s.stl"
    assert main(["surface", str(name), "--connectivity", "26", "-o", str(out), "-q"]) == 0
    capsys.readouterr()
    assert main(["genus", str(out), "--resolution", "8", "--no-step", "--json", "-q"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert [(d["connectivity"], d["betti"]) for d in found["digital"]] == [(26, betti(vol, 26))]
    assert trimesh_header(out).startswith("isoflow surface of subject_0001_")


def trimesh_header(path) -> str:
    """An STL's 80-byte header as trimesh reads it."""
    import trimesh

    return trimesh.load(path, process=False).metadata["header"]
