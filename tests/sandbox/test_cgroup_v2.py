"""sandbox/cgroup_v2: the delegated subtree and each run's one cgroup.

The first tests are the backend's pure parts (run everywhere). The rest need a machine whose
``/sys/fs/cgroup`` is cgroup v2 and writable by usar (a stock Debian 12 as root: the VM of
``tests/vm``, which runs this file inside it); here (cgroup v1) they skip, saying so."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from usar_replay.sandbox import cgroup_v2, cgroups, cpu_sets
from usar_replay.sandbox.kernel_sandbox import KernelSandbox, SandboxLimits


def test_the_v2_path_is_read_from_the_processes_cgroup_line() -> None:
    text = "12:pids:/x\n0::/user.slice/user-0.slice/session-3.scope\n"
    assert cgroup_v2.unified_path(text) == "/user.slice/user-0.slice/session-3.scope"
    assert cgroup_v2.unified_path("0::/\n") == "/"
    assert cgroup_v2.unified_path("4:memory:/a\n") is None  # v1 only: no unified path
    assert cgroup_v2.parse_controllers("cpuset cpu io memory pids\n") == (
        "cpuset", "cpu", "io", "memory", "pids",
    )  # fmt: skip


MOUNTINFO_HOST_NS = (
    "1190 1189 0:26 /docker/4f2a /sys/fs/cgroup rw,nosuid,nodev,noexec,relatime - cgroup2 "
    "cgroup rw,nsdelegate,memory_recursiveprot\n"
    "1191 1189 0:27 / /proc rw - proc proc rw\n"
)
"""A container sharing the host's cgroup namespace (``--cgroupns=host``): its mount shows only
its own subtree, from the root ``/docker/4f2a``."""


def test_the_own_folder_is_the_path_less_the_mounts_root() -> None:
    own = cgroup_v2._own("0::/docker/4f2a/app\n", MOUNTINFO_HOST_NS)
    assert own == "/sys/fs/cgroup/app"
    assert cgroup_v2._own("0::/docker/4f2a\n", MOUNTINFO_HOST_NS) == "/sys/fs/cgroup"
    assert cgroup_v2._own("0::/docker/other\n", MOUNTINFO_HOST_NS) is None  # not mounted here
    machine = "30 23 0:26 / /sys/fs/cgroup rw - cgroup2 cgroup2 rw,nsdelegate\n"
    assert cgroup_v2._own("0::/user.slice/s.scope\n", machine) == (
        "/sys/fs/cgroup/user.slice/s.scope"
    )
    assert cgroup_v2._own("0::/a\n", "") == "/sys/fs/cgroup/a"  # no mountinfo: root /


def test_the_scope_is_asked_of_systemd_with_delegation_and_this_process() -> None:
    root = cgroup_v2.scope_argv("usar-42.scope", 42, user=False)
    assert root[:2] == ["busctl", "call"] and "--user" not in root
    assert "StartTransientUnit" in root and "usar-42.scope" in root
    # the properties, each (name, type, value...): this process moved in, its cgroup delegated
    at = root.index("PIDs")
    assert root[at : at + 4] == ["PIDs", "au", "1", "42"]
    assert root[root.index("Delegate") : root.index("Delegate") + 3] == ["Delegate", "b", "true"]
    assert root[root.index("ssa(sv)a(sa(sv))") + 3] == "4"  # the count of properties given
    assert root[-1] == "0"  # no auxiliary units
    assert cgroup_v2.scope_argv("usar-42.scope", 42, user=True)[:2] == ["busctl", "--user"]


def test_the_drop_in_delegates_cpuset_to_a_users_manager() -> None:
    assert cgroup_v2.DROP_IN_PATH == "/etc/systemd/system/user@.service.d/delegate.conf"
    lines = cgroup_v2.DROP_IN.splitlines()
    assert lines[0] == "[Service]"
    assert set(lines[1].removeprefix("Delegate=").split()) >= set(cgroup_v2.NEED)


def test_a_v1_machine_gets_no_v2_subtree() -> None:
    if cgroups.version() == 2:
        pytest.skip("this machine is cgroup v2")
    got = cgroup_v2.subtree()
    assert got.path is None and "not cgroup v2" in got.why
    assert not os.path.exists("/sys/fs/cgroup/usar")  # nothing made in v1's tmpfs


def _v2() -> bool:
    return cgroups.version() == 2 and cgroup_v2.subtree().path is not None


needs_v2 = pytest.mark.skipif(
    not _v2(), reason="no cgroup v2 subtree usar can write here (cgroup v1, or not delegated)"
)


def _read(path: str, name: str) -> str:
    return Path(path, name).read_text().strip()


@needs_v2
def test_usar_moves_itself_into_a_leaf_and_enables_the_controllers() -> None:
    """As root every controller; as a user, what the user's manager delegates (a stock one:
    memory and pids, the missing cpuset named)."""
    got = cgroup_v2.subtree()
    assert got.path is not None
    if os.geteuid() == 0:
        assert got.enabled == cgroup_v2.NEED, got.why
        assert cgroups.support().writable == cgroups.CONTROLLERS
    else:
        assert got.user_manager and {"memory", "pids"} <= set(got.enabled), got.why
        assert "cpuset" in got.enabled or "cpuset not delegated" in got.why
    own = cgroup_v2.unified_path(Path("/proc/self/cgroup").read_text())
    assert own is not None and "/sys/fs/cgroup" + own == os.path.join(got.path, "usar-self")
    on = _read(got.path, "cgroup.subtree_control").split()
    assert set(got.enabled) <= set(on)
    assert _read(got.path, "cgroup.procs") == ""  # the no-internal-process rule holds


@needs_v2
def test_a_runs_memory_is_bound_as_a_whole() -> None:
    """Four processes of 40 MiB each, under a run limit of 96 MiB: no process is past a limit
    of its own, the run is, and the kernel ends it as a whole (``memory.oom.group``)."""
    child = "x = bytearray(40 << 20)\nimport time\ntime.sleep(60)"
    parent = (
        "import subprocess, sys\n"
        f"ps = [subprocess.Popen([sys.executable, '-c', {child!r}]) for _ in range(4)]\n"
        "[p.wait() for p in ps]\n"
    )
    with KernelSandbox(SandboxLimits(memory_mb=0, run_memory_mb=96)) as box:
        assert box.memory_cgroup is not None and box.memory_cgroup == box.cgroup
        assert _read(box.memory_cgroup, "memory.max") == str(96 << 20)
        assert _read(box.memory_cgroup, "memory.swap.max") == "0"
        assert _read(box.memory_cgroup, "memory.oom.group") == "1"
        proc = subprocess.Popen(box.launch([sys.executable, "-c", parent]))
        assert proc.wait(timeout=120) == -9
        assert box.oom_killed()
        assert not box.tcp_refused()  # v2: socket buffers are in the memory above


@needs_v2
def test_a_run_under_its_memory_limit_is_not_out_of_memory() -> None:
    with KernelSandbox(SandboxLimits(memory_mb=0, run_memory_mb=96)) as box:
        proc = subprocess.Popen(box.launch([sys.executable, "-c", "x = bytearray(8 << 20)"]))
        assert proc.wait(timeout=60) == 0
        assert not box.oom_killed()


@needs_v2
def test_a_runs_processes_are_bound_as_a_whole() -> None:
    script = "for i in $(seq 30); do sleep 5 & done; wait; echo done"
    with KernelSandbox(SandboxLimits(processes=8)) as box:
        assert box.cgroup is not None and _read(box.cgroup, "pids.max") == "8"
        assert box.rlimits()["NPROC"] == 0  # the cgroup bounds it, not RLIMIT_NPROC
        done = subprocess.run(box.launch(["/bin/sh", "-c", script]), capture_output=True,
                              text=True, timeout=60)  # fmt: skip
        path = box.cgroup
        assert box.processes_refused(), done.stderr
    assert not os.path.exists(path)


@needs_v2
def test_closing_a_run_kills_what_is_left_and_removes_its_cgroup() -> None:
    box = KernelSandbox(SandboxLimits(processes=16))
    path = box.cgroup
    assert path is not None
    done = subprocess.run(box.launch(["/bin/sh", "-c", "sleep 600 >/dev/null 2>&1 & echo $!"]),
                          capture_output=True, text=True, timeout=60)  # fmt: skip
    left = int(done.stdout.strip())
    assert str(left) in _read(path, "cgroup.procs").split()  # outlived its shell, in the run
    box.close()
    assert not os.path.exists(path)
    try:  # gone, or a zombie its reaper has not collected yet (it may go while read)
        state = Path(f"/proc/{left}/status").read_text()
    except FileNotFoundError:
        state = "gone"
    assert state == "gone" or "zombie" in state


@needs_v2
def test_each_run_gets_cpus_of_its_own_in_its_one_cgroup() -> None:
    if len(cpu_sets.usable_cpus()) < 2:
        pytest.skip("fewer than two CPUs for usar here")
    first = cpu_sets.claim(1, wait_s=60)
    second = cpu_sets.claim(1, wait_s=60)
    assert first is not None and second is not None
    try:
        assert set(first.cpus).isdisjoint(second.cpus)
        base = cgroup_v2.subtree().path
        assert os.path.dirname(first.path) == base
        assert cpu_sets.parse_cpus(_read(first.path, "cpuset.cpus")) == list(first.cpus)
        assert os.path.isdir(first.record) and first.record.startswith(cpu_sets.registry())
        code = (
            "import os\nos.sched_setaffinity(0, range(os.cpu_count()))\n"
            "print(sorted(os.sched_getaffinity(0)))"
        )
        with KernelSandbox(SandboxLimits(processes=16, run_memory_mb=256), cpus=first) as box:
            assert box.cgroup == box.memory_cgroup == first.path  # one cgroup: v2
            done = subprocess.run(box.launch([sys.executable, "-c", code]), capture_output=True,
                                  text=True, timeout=60)  # fmt: skip
        assert done.stdout.strip() == str(list(first.cpus)), done.stderr
        assert not os.path.exists(first.path) and not os.path.exists(first.record)
    finally:
        second.release()
    assert not os.path.exists(second.path)


def test_the_ways_to_a_subtree_in_order() -> None:
    """Which ways usar tries, by where it starts (the whole choice, without a machine)."""

    def ways(**given: bool) -> list[str]:
        base = {"in_leaf": False, "delegated": False, "at_mount": False, "root": True}
        base |= {"machine_root": True}
        return cgroup_v2.plan(**{**base, "systemd": True, **given})

    assert ways(in_leaf=True) == ["parent"]  # a batch's run process: the driver's subtree
    assert ways(delegated=True) == ["own"]  # systemd-run --scope -p Delegate=yes usar ...
    assert ways(delegated=True, at_mount=True, systemd=False) == ["root", "own"]  # no systemd
    assert ways(delegated=True, at_mount=True, root=False) == ["own"]
    # a container's own cgroup namespace (Docker on v2): its root holds processes, moved first
    assert ways(delegated=True, at_mount=True, machine_root=False) == ["own"]
    assert ways() == ["scope", "top-down"]  # root in a login session's scope
    assert ways(root=False) == ["scope"]  # a user: the user's own manager
    assert ways(systemd=False) == ["top-down"]  # root, a read-only container: tried, refused
    assert ways(root=False, systemd=False) == []


def test_a_cgroup_holding_processes_is_not_written_until_they_move(tmp_path: Path) -> None:
    """Where a cgroup other than the machine's root still holds processes, nothing is enabled
    (``+cpuset +pids`` there would make it a thread root and ``+memory`` then fails for good);
    once its processes are gone it is, and the machine's root may hold processes and hand on
    (the kernel's rules, shown in the VM: tests/vm). A folder of plain files stands in for the
    cgroup: what is asserted is what usar writes."""
    base = tmp_path / "docker-1.scope"
    base.mkdir()
    (base / "cgroup.controllers").write_text("cpuset cpu io memory hugetlb pids rdma misc\n")
    (base / "cgroup.subtree_control").write_text("\n")
    (base / "cgroup.type").write_text("domain\n")
    (base / "cgroup.procs").write_text("1\n7\n")
    enabled, why = cgroup_v2._enable(str(base))
    assert enabled == () and "holds processes" in why, why
    assert (base / "cgroup.subtree_control").read_text() == "\n"  # not a byte written
    (base / "cgroup.procs").write_text("")
    enabled, why = cgroup_v2._enable(str(base))
    assert set(enabled) == set(cgroup_v2.NEED) and why == "", why
    (base / "cgroup.type").unlink()  # the machine's root: no cgroup.type, processes allowed
    (base / "cgroup.procs").write_text("1\n")
    (base / "cgroup.subtree_control").write_text("\n")
    enabled, _ = cgroup_v2._enable(str(base))
    assert set(enabled) == set(cgroup_v2.NEED)
