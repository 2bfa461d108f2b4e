"""A report's closed surfaces are held as two columns (``ClosedSurfaces``)
and read as the list of dicts they replace: checked against that list made
independently, from trimesh's split of the boundary mesh as written to a
file (each component's Euler characteristic, and its quads as its area in
unit voxels), sorted as the report sorts them (most faces first, then least
chi)."""

import copy
import gc
import json
import pickle
import tracemalloc

import numpy as np
import pytest
import trimesh
from conftest import ball, torus
from in_process import isoflow_here

import isoflow
from isoflow import ClosedSurfaces, Report, analyze, closed_surfaces, write_surface


def trimesh_surfaces(vol: np.ndarray, tmp_path) -> list[dict]:
    """The old list, from the file: one dict per connected piece of the mesh."""
    path = write_surface(vol, tmp_path / "s.ply", 6)
    pieces = trimesh.load(path, process=False).split(only_watertight=False)
    found = []
    for p in pieces:
        assert p.is_watertight
        chi = int(p.euler_number)
        # unit voxels: every quad (or pentagon about a doubled edge's midpoint) has area 1
        found.append({"euler_characteristic": chi, "genus": 1 - chi // 2, "faces": int(round(p.area))})
    return sorted(found, key=lambda s: (-s["faces"], s["euler_characteristic"]))


def ring() -> np.ndarray:
    v = np.ones((3, 3, 2), bool)
    v[1, 1] = False
    return np.pad(v, 1)


def two_balls() -> np.ndarray:
    return np.concatenate([ball(3), np.pad(ball(2), 1)], axis=0)  # 10 and 8 + 2 voxels a side


def hollow_ball() -> np.ndarray:
    return ball(5) & ~ball(2, 14)


OBJECTS = {
    "ring": ring,
    "torus": lambda: torus(5, 2),
    "two balls": two_balls,
    "ball with a cavity": hollow_ball,
    "noise": lambda: np.random.default_rng(7).random((9, 10, 11)) < 0.3,
}


def found(sequence, value, start):
    try:
        return sequence.index(value, start)
    except ValueError:
        return None


@pytest.mark.parametrize("name", sorted(OBJECTS))
def test_the_surfaces_read_as_the_list_of_dicts(name, tmp_path):
    vol = OBJECTS[name]()
    want = trimesh_surfaces(vol, tmp_path)
    r = analyze(vol, 6)
    s = r.surfaces
    assert isinstance(s, ClosedSurfaces) and isinstance(closed_surfaces(vol, 6).surfaces, ClosedSurfaces)
    assert closed_surfaces(vol, 6).surfaces == s
    # equal both ways, to the list and to its own kind; unequal to a changed list
    assert s == want and want == s and not (s != want) and not (want != s)
    changed = [dict(d) for d in want]
    changed[-1]["faces"] += 1
    assert s != changed and changed != s and s != want[:-1] and s != tuple(want)
    assert len(s) == len(want) and bool(s) and list(s) == want and s.tolist() == want
    assert [s[i] for i in range(-len(s), len(s))] == want + want
    with pytest.raises(IndexError):
        s[len(s)]
    assert s[1:] == want[1:] and want[:2] == s[:2] and s[::-1] == want[::-1] and not s[:0] and s[:0] == []
    assert repr(s) == repr(want) and str(s) == str(want)
    assert json.dumps(r.to_dict()["surfaces"]) == json.dumps(want)
    assert s + want == want + want == want + s and s + s == want + want
    assert want[0] in s and s.index(want[-1]) == want.index(want[-1])
    # as the list counts and finds: a surface's dict, and nothing else, by value
    for probe in (want[0], want[-1], changed[-1], {**want[0], "genus": want[0]["genus"] + 1}, "x", None):
        assert s.count(probe) == want.count(probe) and (probe in s) == (probe in want)
    assert found(s, want[-1], 1) == found(want, want[-1], 1) and found(s, want[0], -1) == found(want, want[0], -1)
    with pytest.raises(ValueError):
        s.index(changed[-1])
    for back in (pickle.loads(pickle.dumps(s)), copy.copy(s), copy.deepcopy(s)):
        assert back == want and type(back) is ClosedSurfaces
    table = s.columns()
    assert {k: v.tolist() for k, v in table.items()} == {k: [d[k] for d in want] for k in want[0]}
    assert all(v.dtype == np.int64 and not v.flags.writeable for v in table.values())
    assert r.genus == [d["genus"] for d in want]
    # the report read back from its JSON holds its surfaces as columns again, and equals it both ways
    back = Report.from_dict(json.loads(json.dumps(r.to_dict())))
    assert back == r and r == back and type(back.surfaces) is ClosedSurfaces
    assert pickle.loads(pickle.dumps(r)) == r


def test_a_pandas_table_of_the_surfaces():
    pandas = pytest.importorskip("pandas")
    s = analyze(hollow_ball(), 6).surfaces
    frame = pandas.DataFrame(s.columns())
    assert list(frame.columns) == ["euler_characteristic", "genus", "faces"]
    assert frame.to_dict("records") == s


def test_a_report_of_wrong_surfaces_is_refused_in_one_line():
    r = analyze(ring(), 6).to_dict()
    r["surfaces"] = [{"euler_characteristic": 0, "genus": 2, "faces": 48}]
    with pytest.raises(isoflow.IsoflowError, match=r"^surfaces\[0\]: genus 2, where euler_characteristic 0 gives"):
        Report.from_dict(r)
    r["surfaces"] = [{"euler_characteristic": 0.5, "genus": 1, "faces": 48}]
    with pytest.raises(isoflow.IsoflowError, match=r"^surfaces\[0\]: euler_characteristic 0.5, not an integer"):
        Report.from_dict(r)
    r["surfaces"] = [{"genus": 1, "faces": 48}]
    with pytest.raises(isoflow.IsoflowError, match=r"^surfaces\[0\]: \['faces', 'genus'\], where a surface has"):
        Report.from_dict(r)


def test_a_noisy_report_holds_its_surfaces_in_a_few_bytes_each():
    """A million surfaces held a dict apiece took about 230 bytes each: 13
    times the volume of a noisy object."""
    analyze(np.random.default_rng(3).random((16, 16, 16)) < 0.3)  # the modules and tables, loaded
    gc.collect()
    tracemalloc.start()
    try:
        vol = np.random.default_rng(1).random((128, 128, 128)) < 0.3
        r = analyze(vol)
        gc.collect()
        held = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    assert len(r.surfaces) > 100_000
    assert held < 40 * len(r.surfaces) + vol.nbytes, (held, len(r.surfaces))


def test_info_prints_the_surfaces_of_a_noisy_volume_as_the_list(tmp_path):
    vol = OBJECTS["noise"]()
    np.save(tmp_path / "v.npy", vol)
    want = trimesh_surfaces(vol, tmp_path)
    printed = isoflow_here("info", tmp_path / "v.npy", "--json").stdout
    got = json.loads(printed)
    assert got["surfaces"] == want
    # the surfaces written from their columns, the rest by json: the text json.dumps writes of it all
    assert printed == json.dumps(got) + "\n"
    text = isoflow_here("info", tmp_path / "v.npy").stdout
    lines = [f"    #{i}: genus {d['genus']}, chi {d['euler_characteristic']}, {d['faces']} faces"
             for i, d in enumerate(want[:10])]
    assert f"  closed surfaces        {len(want)}\n" + "\n".join(lines) + f"\n    ... {len(want) - 10} more\n" in text


def _one_voxel():
    vol = np.zeros((3, 3, 3), bool)
    vol[1, 1, 1] = True
    return vol


@pytest.mark.parametrize("vol, surfaces", [
    (np.zeros((4, 4, 4), bool), []),
    (_one_voxel(), [{"euler_characteristic": 2, "genus": 0, "faces": 6}]),  # a cube's six faces
    (np.eye(5, dtype=bool), None),  # 2D: closed curves, no key
], ids=["empty", "one voxel", "2d"])
def test_info_json_of_no_one_or_no_surfaces_is_what_json_writes(vol, surfaces, tmp_path):
    np.save(tmp_path / "v.npy", vol)
    printed = isoflow_here("info", tmp_path / "v.npy", "--json").stdout
    got = json.loads(printed)
    assert printed == json.dumps(got) + "\n"
    assert got.get("surfaces") == surfaces
