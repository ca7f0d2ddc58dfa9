"""sandbox/cpu_sets: each run claims CPUs no other usar run holds, through a real cpuset cgroup."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from usar_replay.sandbox import cpu_sets
from usar_replay.sandbox.kernel_sandbox import KernelSandbox, SandboxLimits

needs_cpusets = pytest.mark.skipif(
    not cpu_sets.usable_cpus(), reason="no writable cgroup v1 cpuset hierarchy here (not root?)"
)


def test_cpu_lists_parse_as_the_kernel_writes_them() -> None:
    assert cpu_sets.parse_cpus("0-2,5\n") == [0, 1, 2, 5]
    assert cpu_sets.parse_cpus("") == []


@needs_cpusets
def test_two_claims_never_share_a_cpu_and_a_release_gives_it_back() -> None:
    # the first waits for a CPU (another usar run, or the suite's other worker, may hold one);
    # then claims without waiting take what is left until none is: none shares a CPU, and the
    # last one fails, whatever other runs hold meanwhile (they only ever give CPUs back)
    first = cpu_sets.claim(1, wait_s=600)
    assert first is not None and len(first.cpus) == 1
    more: list[cpu_sets.CpuSet] = []
    try:
        assert first.cpus[0] not in cpu_sets.free_cpus()
        with pytest.raises(TimeoutError):
            while True:
                got = cpu_sets.claim(1, wait_s=0)
                assert got is not None
                more.append(got)
                assert len(more) <= len(cpu_sets.usable_cpus())
        held = [c for s in [first, *more] for c in s.cpus]
        assert len(held) == len(set(held))
    finally:
        for s in more:
            s.release()
        first.release()
    assert not os.path.exists(first.path)
    assert first.cpus[0] in cpu_sets.usable_cpus()


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
    # under the claims' lock, so no other run claims meanwhile (a release may still happen)
    with cpu_sets._locked() as group:
        before = cpu_sets._held(group)
        free = [c for c in cpu_sets.usable_cpus() if c not in before]
        cpu = free[0] if free else cpu_sets.usable_cpus()[0]
        stale = os.path.join(group, f"run-{dead.pid}-1")  # as a killed recorder leaves it
        os.mkdir(stale)
        with open(os.path.join(stale, "cpuset.cpus"), "w") as f:
            f.write(str(cpu))
        after = cpu_sets._held(group)  # what claim() and free_cpus() ask
    assert not os.path.exists(stale)
    assert after <= before
    if free:
        assert cpu not in after
