"""One n-dimensional core: the paper's classes among the n-D tables, chi in
every dimension against scikit-image, and 4D volumes through `isoflow info`."""

import json

import numpy as np
from conftest import random_volume
from scipy.ndimage import generate_binary_structure, label
from skimage.measure import euler_number

from isoflow.cli import main
from isoflow.digital import homology as hom
from isoflow.digital import indices as I
from isoflow.digital import ndim as nd
from isoflow.digital import symmetry as S
from isoflow.digital.topology import betti_numbers, euler_characteristic


def test_the_nine_classes_are_the_well_composed_boundary_classes():
    # the 3D tables' classes (the paper's nine) are the orbits of the
    # well-composed boundary configurations under the cube's 48 symmetries
    canon = S.configuration_orbits(3)
    ours = sorted(set(canon[I.class_lut() >= 0].tolist()))
    assert ours == sorted(nd.boundary_classes(3).tolist())
    assert len(ours) == 9


def test_one_euler_characteristic_in_every_dimension(rng):
    # scikit-image counts chi in 2D and 3D (connectivity 1: faces, ndim: all);
    # in 1D chi is the number of runs
    for _ in range(150):
        ndim = 2 + int(rng.integers(0, 2))
        v = random_volume(rng, 9 if ndim == 3 else 14, ndim=ndim)
        for conn, sk in zip((4, 8) if ndim == 2 else (6, 26), (1, ndim)):
            assert euler_characteristic(v, conn) == euler_number(v, connectivity=sk)
        line = rng.random(int(rng.integers(1, 30))) < 0.5
        runs = int(np.count_nonzero(np.diff(np.concatenate([[0], line.astype(int)])) == 1))
        assert euler_characteristic(line) == euler_characteristic(line, 2) == runs


def info(capsys, path, *extra):
    assert main(["info", str(path), "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)


def test_info_on_4d_volumes(tmp_path, capsys):
    annulus = np.ones((5, 5), bool)
    annulus[2, 2] = False
    disc = np.ones((3, 4), bool)
    cases = {
        "annulus_x_disc": (hom.product_image(annulus, disc), 0),
        "annulus_x_annulus": (hom.product_image(annulus, annulus), 0),
        "ball": (hom.ball(3.5, 4), 1),
        "box_minus_box": (hom.box_minus_box(6, 2, 4), 0),
    }
    for name, (vol, chi) in cases.items():
        np.save(tmp_path / f"{name}.npy", vol)
        for conn, full in ((8, False), (80, True)):
            r = info(capsys, tmp_path / f"{name}.npy", "--connectivity", str(conn))
            assert r["dimension"] == 4 and r["euler_characteristic"] == chi
            assert r["a_dot_n"] == 16 * chi
            structure = generate_binary_structure(4, 4 if full else 1)
            assert r["betti"][0] == label(vol, structure)[1]
    # the box minus an inner box encloses one background component (b3)
    assert info(capsys, tmp_path / "box_minus_box.npy")["betti"][3] == 1


def test_4d_betti_numbers_use_the_right_neighbourhoods(rng):
    # b0 at 8-adjacency counts face-connected cells, at 80-adjacency cells
    # touching anywhere: scipy's labelling with rank-1 / rank-4 structures
    faces, full = generate_binary_structure(4, 1), generate_binary_structure(4, 4)
    for _ in range(30):
        v = rng.random(tuple(rng.integers(2, 6, 4))) < 0.3
        assert betti_numbers(v, 8)[0] == label(v, faces)[1]
        assert betti_numbers(v, 80)[0] == label(v, full)[1]
    # two cells meeting at a corner: two components at 8, one at 80
    corner = np.zeros((2, 2, 2, 2), bool)
    corner[0, 0, 0, 0] = corner[1, 1, 1, 1] = True
    assert betti_numbers(corner, 8)[0] == 2 and betti_numbers(corner, 80)[0] == 1
    # two background cells meeting at a corner inside a solid block: under
    # 80 the background is face-connected, so they are two enclosed pieces
    block = np.ones((4, 4, 4, 4), bool)
    block[1, 1, 1, 1] = block[2, 2, 2, 2] = False
    assert betti_numbers(block, 80)[3] == 2 and betti_numbers(block, 8)[3] == 1


def test_4d_info_refuses_a_volume_beyond_the_memory_budget(tmp_path, capsys, monkeypatch):
    from isoflow.scale import memory

    np.save(tmp_path / "v4.npy", np.ones((6, 6, 6, 6), bool))
    monkeypatch.setattr(memory, "default_budget", lambda: 6**4)  # 1 byte per voxel
    assert main(["info", str(tmp_path / "v4.npy")]) == 2
    err = capsys.readouterr().err.strip()
    assert "6x6x6x6" in err and "budget" in err and len(err.splitlines()) == 1
