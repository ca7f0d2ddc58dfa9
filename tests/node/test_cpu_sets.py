"""node/cpu_sets: each run claims CPUs no other usar run holds, through a real cpuset cgroup."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from usar_replay.node import cpu_sets
from usar_replay.node.kernel_sandbox import KernelSandbox, SandboxLimits

needs_cpusets = pytest.mark.skipif(
    not cpu_sets.usable_cpus(), reason="no writable cgroup v1 cpuset hierarchy here (not root?)"
)


def test_cpu_lists_parse_as_the_kernel_writes_them() -> None:
    assert cpu_sets.parse_cpus("0-2,5\n") == [0, 1, 2, 5]
    assert cpu_sets.parse_cpus("") == []


@needs_cpusets
def test_two_claims_never_share_a_cpu_and_a_release_gives_it_back() -> None:
    free = cpu_sets.free_cpus()
    if not free:
        pytest.skip("every CPU is held by another usar run")
    first = cpu_sets.claim(1, wait_s=0)
    assert first is not None and len(first.cpus) == 1
    try:
        assert first.cpus[0] not in cpu_sets.free_cpus()
        if len(free) > 1:
            second = cpu_sets.claim(1, wait_s=0)
            assert second is not None and set(second.cpus).isdisjoint(first.cpus)
            second.release()
        else:
            with pytest.raises(TimeoutError):
                cpu_sets.claim(1, wait_s=0)
    finally:
        first.release()
    assert not os.path.exists(first.path)
    assert first.cpus[0] in cpu_sets.free_cpus()


@needs_cpusets
def test_the_recorder_is_pinned_to_its_runs_cpus_and_restored() -> None:
    before = os.sched_getaffinity(0)
    got = cpu_sets.claim(1, wait_s=60)
    assert got is not None
    try:
        got.pin_caller()
        assert os.sched_getaffinity(0) == set(got.cpus)
    finally:
        got.release()
    assert os.sched_getaffinity(0) == before


@needs_cpusets
def test_a_process_in_the_set_cannot_widen_its_cpus() -> None:
    """A real process started in the run's set asks for every CPU: the kernel keeps it in
    the set (what a node that calls sched_setaffinity gets)."""
    got = cpu_sets.claim(1, wait_s=60)
    assert got is not None
    code = (
        "import os\nos.sched_setaffinity(0, range(os.cpu_count()))\n"
        "print(sorted(os.sched_getaffinity(0)))"
    )
    with KernelSandbox(SandboxLimits(processes=16), cpus=got) as box:
        done = subprocess.run(
            box.launch([sys.executable, "-c", code]), capture_output=True, text=True, timeout=60
        )
    assert done.stdout.strip() == str(list(got.cpus)), done.stderr
    assert not os.path.exists(got.path)  # the sandbox's close gave the set back


@needs_cpusets
def test_a_set_whose_owner_is_gone_is_removed_by_the_next_claim() -> None:
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    free = cpu_sets.free_cpus()
    if not free:
        pytest.skip("every CPU is held by another usar run")
    with cpu_sets._locked() as group:  # a stale set, as a killed recorder leaves
        stale = os.path.join(group, f"run-{dead.pid}-1")
        os.mkdir(stale)
        with open(os.path.join(stale, "cpuset.cpus"), "w") as f:
            f.write(str(free[0]))
    assert free[0] in cpu_sets.free_cpus()
    assert not os.path.exists(stale)
