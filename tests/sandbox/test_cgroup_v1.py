"""sandbox/cgroup_v1: a run's pids and memory cgroups, each in its own hierarchy."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

from usar_replay.sandbox import cgroup_v1, cgroups


def test_a_controllers_folder_is_read_from_the_processes_cgroup_lines() -> None:
    text = "12:pids:/a/b\n4:cpu,cpuacct:/c\n0::/\n"
    assert cgroup_v1.controller_root("pids", text, "") == "/sys/fs/cgroup/pids/a/b"
    assert cgroup_v1.controller_root("cpuacct", text, "") == "/sys/fs/cgroup/cpuacct/c"
    assert cgroup_v1.controller_root("memory", text, "") is None


ID = "8c0ff6ccf4db4701620e04ba21028ae389c03beee3696205efe9e9852062cdb7"
# a --privileged Docker 20.10 container on a v1 host, the host's cgroup namespace (measured;
# options abridged)
DOCKER_CGROUP = (
    f"8:pids:/docker/{ID}\n4:memory:/docker/{ID}\n3:cpuset:/docker/{ID}\n0::/docker/{ID}\n"
)
DOCKER_MOUNTS = f"""\
88 86 0:57 / /sys/fs/cgroup rw,nosuid,nodev,noexec,relatime - tmpfs tmpfs rw,mode=755
110 88 0:29 /docker/{ID} /sys/fs/cgroup/cpu rw,nosuid,nodev,noexec - cgroup cgroup rw,cpu
112 88 0:31 /docker/{ID} /sys/fs/cgroup/cpuset rw,nosuid,nodev,noexec - cgroup cgroup rw,cpuset
113 88 0:32 /docker/{ID} /sys/fs/cgroup/memory rw,nosuid,nodev,noexec - cgroup cgroup rw,memory
117 88 0:36 /docker/{ID} /sys/fs/cgroup/pids rw,nosuid,nodev,noexec - cgroup cgroup rw,pids
"""


def test_a_container_sharing_the_hosts_namespace_finds_its_folder_at_the_mounts_top() -> None:
    # /proc/self/cgroup says /docker/<id>, and the mount shows that folder already
    assert cgroup_v1.controller_root("memory", DOCKER_CGROUP, DOCKER_MOUNTS) == (
        "/sys/fs/cgroup/memory"
    )
    below = DOCKER_CGROUP.replace(f"pids:/docker/{ID}", f"pids:/docker/{ID}/usar-self")
    assert cgroup_v1.controller_root("pids", below, DOCKER_MOUNTS) == (
        "/sys/fs/cgroup/pids/usar-self"
    )


def test_a_machines_own_mounts_keep_the_path_and_a_cgroup_outside_the_mount_has_none() -> None:
    host = "35 31 0:32 / /sys/fs/cgroup/memory rw,relatime - cgroup cgroup rw,memory\n"
    text = "4:memory:/process_api/a b\n"
    assert (
        cgroup_v1.controller_root("memory", text, host) == "/sys/fs/cgroup/memory/process_api/a b"
    )
    other = "35 31 0:32 /other /sys/fs/cgroup/memory rw - cgroup cgroup rw,memory\n"
    assert cgroup_v1.controller_root("memory", text, other) is None
    combined = r"32 31 0:29 /x\040y /sys/fs/cgroup/cpu,cpuacct rw - cgroup cgroup rw,cpu,cpuacct"
    assert cgroup_v1.controller_root("cpuacct", "2:cpu,cpuacct:/x y/z\n", combined) == (
        "/sys/fs/cgroup/cpu,cpuacct/z"
    )


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
