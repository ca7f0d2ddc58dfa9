"""sandbox/cgroup_v1: a run's pids and memory cgroups, each in its own hierarchy."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

from usar_replay.sandbox import cgroup_v1, cgroups


def test_a_controllers_folder_is_read_from_the_processes_cgroup_lines() -> None:
    text = "12:pids:/a/b\n4:cpu,cpuacct:/c\n0::/\n"
    assert cgroup_v1.controller_root("pids", text) == "/sys/fs/cgroup/pids/a/b"
    assert cgroup_v1.controller_root("cpuacct", text) == "/sys/fs/cgroup/cpuacct/c"
    assert cgroup_v1.controller_root("memory", text) is None


def test_tcp_buffers_get_a_quarter_of_the_run_at_least_64_mib() -> None:
    assert cgroup_v1.tcp_limit_mb(0) == 64 and cgroup_v1.tcp_limit_mb(3072) == 768


needs_v1 = pytest.mark.skipif(
    cgroups.version() != 1 or not cgroup_v1.writable("pids") or not cgroup_v1.writable("memory"),
    reason="no writable cgroup v1 pids and memory hierarchies here",
)


@needs_v1
def test_a_runs_groups_hold_their_limits_and_go_with_what_is_left_in_them() -> None:
    name = f"usar-test-{os.getpid()}"
    pids = cgroup_v1.make_pids(name, 7)
    memory = cgroup_v1.make_memory(name, 256)
    assert pids is not None and memory is not None and pids != memory
    assert Path(pids, "pids.max").read_text().strip() == "7"
    assert Path(memory, "memory.limit_in_bytes").read_text().strip() == str(256 << 20)
    left = subprocess.Popen(["sleep", "600"])
    Path(pids, "cgroup.procs").write_text(str(left.pid))
    cgroup_v1.remove(pids)
    cgroup_v1.remove(memory)
    assert left.wait(timeout=30) == -9  # killed: the cgroup could not go with it in it
    assert not os.path.exists(pids) and not os.path.exists(memory)
