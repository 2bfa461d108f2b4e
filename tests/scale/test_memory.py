"""The memory budget (isoflow.scale.memory.default_budget) under a control
group's limit: a container's, or a batch job's as Slurm sets it. The
machine's MemAvailable does not see such a limit, and work past it is
killed without a word; the budget is 90 % of the least room, each group's
limit less its usage short of its inactive file cache, up to the root. The
groups are fake trees written here, their rooms worked out by hand."""

from pathlib import Path

import pytest

from isoflow.cli import main
from isoflow.scale import memory

GIB = 1 << 30


def fake_linux(tmp_path: Path, monkeypatch, cgroup: str, groups: dict[str, dict[str, str]],
               available: int = 60 * GIB) -> None:
    """``/proc/self/cgroup`` holding ``cgroup``, ``/proc/meminfo`` saying
    ``available``, and under the groups' root each folder of ``groups``
    with its files."""
    proc, root = tmp_path / "proc", tmp_path / "cgroup"
    proc.mkdir()
    (proc / "cgroup").write_text(cgroup)
    (tmp_path / "meminfo").write_text(f"MemTotal: 99999999 kB\nMemAvailable: {available // 1024} kB\n")
    for folder, files in groups.items():
        (root / folder).mkdir(parents=True, exist_ok=True)
        for name, text in files.items():
            (root / folder / name).write_text(text)
    monkeypatch.setattr(memory, "PROC_SELF", proc)
    monkeypatch.setattr(memory, "MEMINFO", tmp_path / "meminfo")
    monkeypatch.setattr(memory, "CGROUPS", root)


def test_a_v2_groups_limit_less_its_usage_short_of_its_file_cache(tmp_path, monkeypatch):
    fake_linux(tmp_path, monkeypatch, "0::/user.slice/job_42\n", {
        "user.slice": {"memory.max": "max\n", "memory.current": str(30 * GIB)},
        "user.slice/job_42": {"memory.max": str(4 * GIB), "memory.current": str(GIB),
                              "memory.stat": f"anon 123\ninactive_file {GIB // 2}\nactive_file 7\n"}})
    assert memory.cgroup_room() == 4 * GIB - (GIB - GIB // 2)
    assert memory.default_budget() == (4 * GIB - GIB // 2) * 9 // 10


def test_a_v1_parent_group_with_less_room_sets_the_budget(tmp_path, monkeypatch):
    """Slurm's cgroup v1 layout: the job's group inside the user's; the
    user's group, nearly full, leaves less than the job's own limit."""
    fake_linux(tmp_path, monkeypatch, "12:pids:/slurm\n4:memory:/slurm/uid_1/job_7\n1:cpu:/\n", {
        "memory/slurm/uid_1/job_7": {"memory.limit_in_bytes": str(8 * GIB), "memory.usage_in_bytes": str(2 * GIB),
                                     "memory.stat": "total_inactive_file 0\n"},
        "memory/slurm/uid_1": {"memory.limit_in_bytes": str(6 * GIB), "memory.usage_in_bytes": str(5 * GIB)},
        "memory/slurm": {"memory.limit_in_bytes": "9223372036854771712", "memory.usage_in_bytes": str(5 * GIB)}})
    assert memory.cgroup_room() == GIB
    assert memory.default_budget() == GIB * 9 // 10


@pytest.mark.parametrize("limit", ["max\n", "9223372036854771712\n"])
def test_without_a_limit_the_budget_is_the_machines(tmp_path, monkeypatch, limit):
    name = "memory.max" if limit == "max\n" else "memory/memory.limit_in_bytes"
    folder, file = name.rsplit("/", 1) if "/" in name else ("", name)
    fake_linux(tmp_path, monkeypatch, "0::/\n" if folder == "" else "4:memory:/\n",
               {folder: {file: limit}}, available=10 * GIB)
    assert memory.cgroup_room() is None
    assert memory.default_budget() == 10 * GIB * 9 // 10


def test_a_containers_own_group_seen_as_the_root(tmp_path, monkeypatch):
    """Inside a container /proc names the group by the host's path, which
    is not there: the root the container sees is its group."""
    fake_linux(tmp_path, monkeypatch, "0::/docker/0123abcd\n",
               {"": {"memory.max": str(2 * GIB), "memory.current": str(GIB // 4)}})
    assert memory.default_budget() == (2 * GIB - GIB // 4) * 9 // 10


def test_voxelize_under_a_jobs_limit_is_refused_up_front_with_what_fits(tmp_path, monkeypatch, capsys):
    """A grid that the machine's memory holds but the job's limit does not:
    refused before any work, naming the resolution that fits the job's
    room (before, the budget was the machine's MemAvailable, and the job
    was killed by the kernel as the grid filled)."""
    from isoflow import data

    fake_linux(tmp_path, monkeypatch, "0::/job\n",
               {"job": {"memory.max": str(256 << 20), "memory.current": str(16 << 20)}})
    out = tmp_path / "t.npy"
    assert main(["voxelize", str(data.torus()), "--resolution", "1500", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    budget = (256 - 16 << 20) * 9 // 10
    assert len(err) == 1 and f"more than the memory budget of {budget / (1 << 20):.1f} MiB" in err[0], err
    assert "at most --resolution" in err[0] and not out.exists()
