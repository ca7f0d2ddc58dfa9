"""batch.machine: what this machine gives a run, from the runs' own lookups (issue 44)."""

from __future__ import annotations

import pytest

from usar_replay.batch import machine
from usar_replay.sandbox import cgroups, container, cpu_sets, kernel_pools, kernel_sandbox


def test_this_machine_as_ci_has_it() -> None:
    """CI runs as root with bubblewrap, cgroup v1 and Debian's ROS 1: a whole isolation."""
    found = {f.name: f for f in machine.check()}
    assert list(found) == [
        "kernel sandbox",
        "container",
        "cgroups",
        "CPU sets",
        "real-time priority",
        "size-limited folders",
        "kernel pools",
        "ROS 1",
    ]
    assert found["size-limited folders"].ok  # root: each run's and build's tmpfs
    assert found["kernel pools"].ok, found["kernel pools"].means  # user namespaces, libseccomp
    assert found["ROS 1"].ok, found["ROS 1"].means
    if machine.isolated(list(found.values())):
        assert machine.warning(list(found.values())) == ""


def test_no_cpu_sets_is_said_with_what_it_means(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(cpu_sets, "usable_cpus", lambda: [])
    monkeypatch.setattr(cgroups, "support", lambda: cgroups.Support(1, ("memory", "pids")))
    monkeypatch.setattr(container, "read", lambda: container.Signs())
    findings = machine.check()
    assert not machine.isolated(findings)
    line = next(f for f in findings if f.name == "cgroups")
    assert not line.ok and "not cpuset" in line.said
    assert "a neighbour can change a ROS 1 run's log" in line.means
    line = machine.warning(findings)
    assert line.startswith("usar: warning: isolation is partial here (cgroups, CPU sets")
    assert "usar doctor" in line and "\n" not in line


def test_no_bubblewrap_is_said(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(kernel_sandbox, "bwrap_available", lambda: (False, "no bwrap here"))
    monkeypatch.setattr(kernel_sandbox, "installed", lambda: False)
    sandbox = machine.check()[0]
    assert (sandbox.ok, sandbox.said) == (False, "no bwrap here")
    assert "apt-get install bubblewrap" in sandbox.means


def test_a_container_with_bubblewrap_is_pointed_to_its_flags_not_to_installing_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    why = "/usr/bin/bwrap cannot create namespaces here (bwrap: No permissions to create new ns)"
    monkeypatch.setattr(kernel_sandbox, "bwrap_available", lambda: (False, why))
    monkeypatch.setattr(kernel_sandbox, "installed", lambda: True)
    monkeypatch.setattr(container, "read", lambda: container.Signs(dockerenv=True, seccomp=2))
    monkeypatch.setattr(kernel_pools, "pool_limits_available", lambda: False)
    found = {f.name: f for f in machine.check()}
    sandbox, pools = found["kernel sandbox"], found["kernel pools"]
    assert "apt-get" not in sandbox.means and "the flags the container line names" in sandbox.means
    assert "unshare --user failed" in pools.said
    assert "the flags the container line names" in pools.means and "util-linux" not in pools.means
    monkeypatch.setattr(container, "read", lambda: container.Signs())  # the machine itself
    found = {f.name: f for f in machine.check()}
    assert "allow user namespaces" in found["kernel sandbox"].means
    assert "allow user namespaces" in found["kernel pools"].means


def test_without_root_no_folder_is_size_limited(monkeypatch: pytest.MonkeyPatch) -> None:
    import os

    monkeypatch.setattr(os, "geteuid", lambda: 1000)
    folders = next(f for f in machine.check() if f.name == "size-limited folders")
    assert not folders.ok and "can fill the disk" in folders.means


def test_unbounded_kernel_pools_are_said(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(kernel_pools, "pool_limits_available", lambda: False)
    monkeypatch.setattr(kernel_pools, "keyring_filter", lambda: None)
    findings = machine.check()
    pools = next(f for f in findings if f.name == "kernel pools")
    assert not pools.ok and "inotify" in pools.said and "keys" in pools.said
    assert "run one at a time" in pools.means and not machine.isolated(findings)
    assert "kernel pools" in machine.warning(findings)
