"""sandbox/cgroups: one face over both versions; a run's groups as this machine's version has them
(v1 here, v2 in the VM of tests/vm)."""

from __future__ import annotations

import os

import pytest

from usar_replay.sandbox import cgroups


def test_the_version_is_the_mounts() -> None:
    unified = os.path.exists("/sys/fs/cgroup/cgroup.controllers")
    assert cgroups.version() == (2 if unified else 1)
    got = cgroups.support()
    assert got.version == cgroups.version()
    assert set(got.writable) <= set(cgroups.CONTROLLERS)


def test_a_run_gets_its_groups_and_loses_them() -> None:
    """v1: a pids and a memory cgroup in their own hierarchies; v2: one cgroup for both."""
    got = cgroups.support()
    if not {"pids", "memory"} <= set(got.writable):
        pytest.skip(f"no pids and memory cgroups usar can write here ({got.why or got.where})")
    pids, memory = cgroups.run_groups(f"usar-face-{os.getpid()}", processes=9, memory_mb=128)
    assert pids is not None and memory is not None
    assert (pids == memory) is (cgroups.version() == 2)
    with open(os.path.join(pids, "pids.max")) as f:
        assert f.read().strip() == "9"
    for path in {pids, memory}:
        cgroups.remove(path)
        assert not os.path.exists(path)


def test_no_limits_no_pids_group() -> None:
    pids, memory = cgroups.run_groups(f"usar-none-{os.getpid()}", processes=0, memory_mb=0)
    assert pids is None
    if memory is not None:
        cgroups.remove(memory)
