"""The array core on a device: volumes that are not NumPy arrays.

No GPU is lent to the CI machine, so CuPy itself cannot run here. The
stand-in is ``array_api_strict`` on its simulated device "device1": the
reference implementation of the array API standard, which refuses every
function outside the standard (``pad``, ``bincount``, ``view``, ...) and every
implicit conversion to NumPy (``numpy.asarray`` raises on that device), just
as CuPy refuses ``numpy.asarray`` of a GPU array. A core that ran here reads a
CuPy volume on its GPU with the same code; the values are checked against
scikit-image and shapes of known topology.
"""

import json
import sys

import numpy as np
import pytest
from conftest import ball, random_volume, torus
from skimage.measure import euler_number

from isoflow import DigitalObject, analyze, betti_numbers, euler_characteristic
from isoflow.cli import main
from isoflow.digital.analysis import voxels_from_histogram
from isoflow.digital.configurations import configuration_histogram, configurations
from isoflow.errors import IsoflowError
from isoflow.scale import arrays

xps = pytest.importorskip("array_api_strict")
DEVICE = xps.Device("device1")
SKIMAGE = {6: 1, 26: 3, 4: 1, 8: 2}


def on_device(volume: np.ndarray):
    return xps.asarray(volume, device=DEVICE)


def test_the_stand_in_refuses_implicit_host_copies():
    # What makes the tests below mean something: any np.asarray of the
    # volume inside the core would raise.
    with pytest.raises(RuntimeError):
        np.asarray(on_device(np.ones((2, 2), bool)))


def test_configurations_stay_on_the_device(rng):
    v = rng.random((5, 6, 7)) < 0.5
    codes = configurations(on_device(v))
    assert codes.device == DEVICE
    assert (arrays.to_host(codes) == configurations(v)).all()


@pytest.mark.parametrize("ndim", [2, 3])
def test_histogram_on_the_device_equals_host(rng, ndim):
    # 70 rows with slab 64: the slab seam is crossed; odd sizes on every axis
    shape = (70, 9, 11)[:ndim]
    v = rng.random(shape) < 0.4
    assert (configuration_histogram(on_device(v)) == configuration_histogram(v)).all()


def test_histogram_brings_back_only_the_counts(rng, monkeypatch):
    copied = []
    real = arrays.to_host

    def spy(x):
        copied.append(int(np.prod(x.shape)))
        return real(x)

    monkeypatch.setattr(arrays, "to_host", spy)
    configuration_histogram(on_device(rng.random((20, 20, 20)) < 0.5))
    assert copied and max(copied) <= 256


@pytest.mark.parametrize("conn", [6, 26])
def test_chi_on_the_device_equals_skimage(rng, conn):
    for _ in range(40):
        v = random_volume(rng, 8)
        assert euler_characteristic(on_device(v), conn) == euler_number(
            v, connectivity=SKIMAGE[conn]
        )


@pytest.mark.parametrize("conn", [4, 8])
def test_chi_on_the_device_in_2d(rng, conn):
    for _ in range(40):
        v = random_volume(rng, 14, ndim=2)
        assert euler_characteristic(on_device(v), conn) == euler_number(
            v, connectivity=SKIMAGE[conn]
        )


def test_betti_numbers_on_the_device():
    solid = ball(6)
    hollow = solid & ~ball(3, size=solid.shape[0])
    ring = torus(6, 2)
    assert betti_numbers(on_device(solid)) == [1, 0, 0]
    assert betti_numbers(on_device(hollow)) == [1, 0, 1]
    assert betti_numbers(on_device(ring)) == [1, 1, 0]
    assert betti_numbers(on_device(np.concatenate([ring, ring]))) == [2, 2, 0]


def test_device_volumes_follow_the_host_rule_for_values(rng):
    # 0/1 in another dtype is read as the bool volume; other values are
    # refused on the device as on the host
    v = rng.random((9, 8, 7)) < 0.5
    assert euler_characteristic(on_device(v.astype(np.uint8))) == euler_number(v, connectivity=1)
    with pytest.raises(IsoflowError, match="not a binary volume"):
        euler_characteristic(on_device(v.astype(np.uint8) * 3))
    with pytest.raises(IsoflowError, match="not a binary image"):  # 2D: an image, as on the host
        euler_characteristic(on_device(v[:, :, 0].astype(np.uint8) * 3))


def test_4d_histogram_on_the_device_equals_host(rng):
    v = rng.random((5, 4, 6, 3)) < 0.4
    assert (configuration_histogram(on_device(v)) == configuration_histogram(v)).all()


@pytest.mark.parametrize("conn", [6, 26])
def test_report_of_a_device_volume_equals_the_host_report(rng, conn):
    v = rng.random((17, 13, 11)) < 0.45
    host = analyze(DigitalObject(v), conn)
    device = analyze(on_device(v), conn)
    assert device == host
    assert device["a_dot_n"] == 8 * euler_number(v, connectivity=SKIMAGE[conn])


def test_voxel_count_from_the_histogram(rng):
    for ndim in (2, 3):
        for _ in range(20):
            v = random_volume(rng, 9, ndim=ndim)
            assert voxels_from_histogram(configuration_histogram(v)) == int(v.sum())


# ---------------------------------------------------------------- isoflow info --gpu


def fake_cupy(monkeypatch, free_bytes: int):
    """A `cupy` whose GPU is the stand-in device: the CLI's --gpu wiring
    (memory check, upload, analysis of the device array) runs end to end."""
    import types

    runtime = types.SimpleNamespace(memGetInfo=lambda: (free_bytes, 2 * free_bytes))
    module = types.SimpleNamespace(
        cuda=types.SimpleNamespace(runtime=runtime), asarray=on_device
    )
    monkeypatch.setitem(sys.modules, "cupy", module)


def test_info_gpu_reports_what_info_reports(tmp_path, capsys, monkeypatch):
    v = torus(6, 2)
    np.save(tmp_path / "t.npy", v)
    assert main(["info", str(tmp_path / "t.npy"), "--json"]) == 0
    host = json.loads(capsys.readouterr().out)
    fake_cupy(monkeypatch, free_bytes=2**30)
    assert main(["info", str(tmp_path / "t.npy"), "--json", "--gpu"]) == 0
    gpu = json.loads(capsys.readouterr().out)
    assert gpu == host and gpu["betti"] == [1, 1, 0]


def test_info_gpu_places_the_world_measures_as_info_does(tmp_path, capsys, monkeypatch):
    # the device array is bare: the file's voxel size, origin and unit go with it
    import isoflow

    v = torus(6, 2)
    isoflow.write_volume(DigitalObject(v, pitch=(0.5, 1.0, 2.0), origin=(1, 2, 3), unit="mm"), tmp_path / "t.npz")
    assert main(["info", str(tmp_path / "t.npz"), "--json"]) == 0
    host = json.loads(capsys.readouterr().out)
    fake_cupy(monkeypatch, free_bytes=2**30)
    assert main(["info", str(tmp_path / "t.npz"), "--json", "--gpu"]) == 0
    gpu = json.loads(capsys.readouterr().out)
    assert gpu == host and gpu["unit"] == "mm"
    assert gpu["volume"] == pytest.approx(int(v.sum()) * 1.0)  # voxels of 0.5 x 1 x 2


@pytest.mark.parametrize("ndim", [2, 3])
def test_world_measures_of_a_device_volume_equal_the_host_ones(rng, ndim):
    for _ in range(10):
        v = random_volume(rng, 9, ndim=ndim)
        pitch = rng.uniform(0.5, 2.0, ndim)
        assert analyze(on_device(v), pitch=pitch, unit="mm") == analyze(v, pitch=pitch, unit="mm")


def test_info_gpu_refuses_a_volume_larger_than_the_free_memory(tmp_path, capsys, monkeypatch):
    np.save(tmp_path / "t.npy", torus(6, 2))
    fake_cupy(monkeypatch, free_bytes=1000)
    assert main(["info", str(tmp_path / "t.npy"), "--gpu"]) == 2
    err = capsys.readouterr().err.strip()
    assert "GPU memory" in err and "drop --gpu" in err and len(err.splitlines()) == 1


def test_info_gpu_without_cupy_is_one_clear_line(tmp_path, capsys, monkeypatch):
    np.save(tmp_path / "t.npy", torus(6, 2))
    monkeypatch.setitem(sys.modules, "cupy", None)  # import cupy -> ImportError
    assert main(["info", str(tmp_path / "t.npy"), "--gpu"]) == 2
    err = capsys.readouterr().err.strip()
    assert "CuPy" in err and "isoflow[gpu]" in err and len(err.splitlines()) == 1
