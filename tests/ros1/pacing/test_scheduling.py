"""ros1/pacing/scheduling: the graph's threads on one CPU under SCHED_RR."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from proctools import child as start_child
from proctools import wait_for

from usar_replay.ros1.pacing.scheduling import OneCpu


def test_the_graph_runs_on_one_cpu_under_sched_rr() -> None:
    child = start_child("import time\ntime.sleep(60)")
    try:
        pin = OneCpu(child.pid)
        wait_for(lambda: pin.apply() > 0 or child.pid in pin.done, "the child's threads")
        assert os.sched_getaffinity(child.pid) == {pin.cpu}
        if os.geteuid() == 0:
            policy = os.sched_getscheduler(child.pid)
            assert policy == os.SCHED_RR | os.SCHED_RESET_ON_FORK  # never inherited
        else:
            assert pin.refused
    finally:
        child.kill()
        child.wait()


def test_without_a_cpu_set_of_its_own_the_graph_is_only_pinned() -> None:
    """No SCHED_RR outside a run's own CPU set: it could starve a CPU someone else needs."""
    child = start_child("import time\ntime.sleep(60)")
    try:
        pin = OneCpu(child.pid, realtime=False)
        wait_for(lambda: pin.apply() > 0 or child.pid in pin.done, "the child's threads")
        assert os.sched_getaffinity(child.pid) == {pin.cpu}
        assert os.sched_getscheduler(child.pid) == os.SCHED_OTHER and pin.refused
    finally:
        child.kill()
        child.wait()


def test_the_named_process_passes_real_time_priority_on_and_no_other_does(
    tmp_path: Path,
) -> None:
    """The bridge's threads (usar's code) get plain SCHED_RR, so rospy's new connection
    threads are real-time from birth; every other process's carry the reset flag."""
    if os.geteuid() != 0:
        pytest.skip("no SCHED_RR without root")
    (tmp_path / "fake_bridge.py").write_text("import time\ntime.sleep(60)\n")
    bridge = subprocess.Popen([sys.executable, "-m", "fake_bridge"], cwd=tmp_path)
    other = start_child("import time\ntime.sleep(60)")
    try:
        pin = OneCpu(bridge.pid, realtime=True, passes_on=b"fake_bridge")
        wait_for(lambda: pin.apply() > 0 or bridge.pid in pin.done, "the bridge's threads")
        pin.root = other.pid
        wait_for(lambda: pin.apply() > 0 or other.pid in pin.done, "the other's threads")
        assert os.sched_getscheduler(bridge.pid) == os.SCHED_RR
        assert os.sched_getscheduler(other.pid) == os.SCHED_RR | os.SCHED_RESET_ON_FORK
    finally:
        for proc in (bridge, other):
            proc.kill()
            proc.wait()


def test_the_spared_process_keeps_its_cpus_and_policy(tmp_path: Path) -> None:
    """The idle check's watcher (``spares``) is left as it started: its CPUs and SCHED_OTHER,
    so it never takes the graph's CPU from the graph; the process beside it is pinned."""
    (tmp_path / "fake_watcher.py").write_text("import time\ntime.sleep(60)\n")
    watcher = subprocess.Popen([sys.executable, "-m", "fake_watcher"], cwd=tmp_path)
    other = start_child("import time\ntime.sleep(60)")
    cpus = sorted(os.sched_getaffinity(0))
    try:
        pin = OneCpu(watcher.pid, cpu=cpus[-1], realtime=False, spares=b"fake_watcher")
        wait_for(lambda: pin.apply() > 0 or watcher.pid in pin.done, "the watcher's threads")
        pin.root = other.pid
        wait_for(lambda: pin.apply() > 0 or other.pid in pin.done, "the other's threads")
        assert os.sched_getaffinity(watcher.pid) == set(cpus)
        assert os.sched_getscheduler(watcher.pid) == os.SCHED_OTHER
        assert os.sched_getaffinity(other.pid) == {cpus[-1]}
    finally:
        for proc in (watcher, other):
            proc.kill()
            proc.wait()


def test_beside_a_real_time_graph_the_spared_process_shares_its_cpu(tmp_path: Path) -> None:
    """Where the graph gets SCHED_RR, the watcher is pinned to the graph's CPU, as an ordinary
    process (it runs there only while the graph does not)."""
    (tmp_path / "fake_watcher.py").write_text("import time\ntime.sleep(60)\n")
    watcher = subprocess.Popen([sys.executable, "-m", "fake_watcher"], cwd=tmp_path)
    cpus = sorted(os.sched_getaffinity(0))
    try:
        # until its exec the child shows this process's command line (the real watcher, started
        # long before the first tick's pinning, also sets its own policy back to SCHED_OTHER)
        wait_for(
            lambda: b"fake_watcher" in Path(f"/proc/{watcher.pid}/cmdline").read_bytes(),
            "the watcher's exec",
        )
        pin = OneCpu(watcher.pid, cpu=cpus[0], realtime=True, spares=b"fake_watcher")
        wait_for(lambda: pin.apply() > 0 or watcher.pid in pin.done, "the watcher's threads")
        assert os.sched_getaffinity(watcher.pid) == {cpus[0]}
        assert os.sched_getscheduler(watcher.pid) == os.SCHED_OTHER
    finally:
        watcher.kill()
        watcher.wait()


def test_threads_are_listed_again_only_once_a_pid_was_given_out() -> None:
    """OneCpu.apply lists the run's threads only when /proc/loadavg's last PID moved (a new
    thread anywhere takes one): with none made, no listing; a thread the child makes later is
    pinned at the next apply."""
    code = (
        "import sys, threading, time\n"
        "sys.stdin.readline()\n"
        "threading.Thread(target=time.sleep, args=(60,), daemon=True).start()\n"
        "time.sleep(60)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE)
    listed: list[int] = []
    try:
        pin = OneCpu(child.pid, realtime=False)
        tids = pin._tids

        def counted() -> list[int]:
            listed.append(1)
            return tids()

        pin._tids = counted  # type: ignore[method-assign]
        wait_for(lambda: pin.apply() > 0 or child.pid in pin.done, "the child's threads")
        before = len(listed)
        if (pin._last_pid_now(), child.pid) == pin._last_pid:  # no PID given out meanwhile
            assert pin.apply() == 0 and len(listed) == before
        assert child.stdin is not None
        child.stdin.write(b"go\n")
        child.stdin.flush()
        wait_for(lambda: len(os.listdir(f"/proc/{child.pid}/task")) == 2, "the child's thread")
        new = pin.apply()
        assert new == 1 and len(listed) > before
        (thread,) = set(map(int, os.listdir(f"/proc/{child.pid}/task"))) - {child.pid}
        assert os.sched_getaffinity(thread) == {pin.cpu}
    finally:
        child.kill()
        child.wait()
        pin.close()


def test_a_thread_moved_aside_as_a_spinner_is_pinned_but_stays_sched_idle() -> None:
    """The idle check moves a thread that spins with no pausing point to SCHED_IDLE
    (:mod:`usar_replay.ros1.pacing.spinners`): at real-time priority on the graph's only CPU
    it would hold that CPU from the thread that sets what it waits for."""
    if os.geteuid() != 0:
        pytest.skip("no SCHED_RR without root")
    child = start_child("import time\ntime.sleep(60)")
    try:
        os.sched_setscheduler(child.pid, os.SCHED_IDLE | os.SCHED_RESET_ON_FORK, os.sched_param(0))
        pin = OneCpu(child.pid)
        wait_for(lambda: pin.apply() > 0 or child.pid in pin.done, "the child's threads")
        assert os.sched_getaffinity(child.pid) == {pin.cpu}
        assert os.sched_getscheduler(child.pid) & ~os.SCHED_RESET_ON_FORK == os.SCHED_IDLE
    finally:
        child.kill()
        child.wait()
