"""The graph paces the clock (docs/ros1.md, "Pacing"): idle detection, end detection and the
one-CPU policy on real processes, and two recordings of the example package compared message
for message."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from example_worlds import quick_room

from usar_replay.core.settings import RunSettings
from usar_replay.log.run import open_run
from usar_replay.ros1.proc_watch import ProcWatch
from usar_replay.ros1.quiescence import Quiescence
from usar_replay.ros1.scheduling import OneCpu

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "ros1" / "usar_course"


def _child(code: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen([sys.executable, "-c", code])


def _wait_for(predicate: object, what: str, timeout_s: float = 20.0) -> None:
    """Poll a condition (not a fixed sleep): fail after ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while not predicate():  # type: ignore[operator]
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.005)


def test_a_thread_polling_the_clock_must_wake_before_the_graph_is_idle() -> None:
    # 10 ms naps, as roscpp's ros::Time::waitForValid: idle only once it woke and slept again
    child = _child("import time\nwhile True: time.sleep(0.01)")
    try:
        quiet = Quiescence(own_tid=threading.get_native_id())
        _wait_for(lambda: len(quiet.refresh()) > 1, "the child")
        quiet.refresh(package=[child.pid])
        _wait_for(lambda: quiet.threads()[child.pid].polling, "the child's nap")
        before = quiet.threads()[child.pid].runs
        assert quiet.wait(5.0)
        assert quiet.threads()[child.pid].runs > before
    finally:
        child.kill()
        child.wait()


def test_a_busy_graph_is_not_idle_and_the_cap_ends_the_wait() -> None:
    child = _child("while True: pass")
    try:
        quiet = Quiescence(own_tid=threading.get_native_id())
        _wait_for(lambda: len(quiet.refresh()) > 1, "the child")
        quiet.refresh(package=[child.pid])
        assert not quiet.wait(0.05)
    finally:
        child.kill()
        child.wait()


def test_bytes_in_a_socket_of_the_graph_keep_it_busy() -> None:
    import socket

    a, b = socket.socketpair()
    with a, b:
        quiet = Quiescence(own_tid=threading.get_native_id())
        quiet.refresh()
        a.sendall(b"x")  # an unknown socket with bytes: the tree's sockets are looked up
        assert quiet.sockets_waiting() >= 1
        b.recv(1)
        already = quiet.sockets_waiting()  # what this test process has waiting elsewhere
        a.sendall(b"unread")
        assert quiet.sockets_waiting() == already + 6
        assert not quiet.wait(0.02)
        b.recv(16)
        assert quiet.sockets_waiting() == already


def test_the_end_is_seen_in_the_process_table_with_the_exit_code() -> None:
    # a launcher that does not collect its node (as roslaunch, until its next poll)
    launcher = _child(
        "import subprocess, sys, time\n"
        "subprocess.Popen([sys.executable, '-c', 'import sys; sys.exit(3)'])\n"
        "time.sleep(60)"
    )
    try:
        watch = ProcWatch(launcher.pid)
        _wait_for(watch.ended, "the node's exit")
        assert len(watch.seen) == 1
        (failure,) = watch.failures()
        assert failure.endswith("exit code 3")
    finally:
        launcher.kill()
        launcher.wait()


def test_the_graph_runs_on_one_cpu_under_sched_rr() -> None:
    child = _child("import time\ntime.sleep(60)")
    try:
        pin = OneCpu(child.pid)
        _wait_for(lambda: pin.apply() > 0 or child.pid in pin.done, "the child's threads")
        assert os.sched_getaffinity(child.pid) == {pin.cpu}
        if os.geteuid() == 0:
            assert os.sched_getscheduler(child.pid) == os.SCHED_RR
        else:
            assert pin.refused
    finally:
        child.kill()
        child.wait()


def _outputs(path: Path) -> list[tuple[int, str, bytes]]:
    """What the package and the bridge published, tick by tick (not the simulator's)."""
    return [
        (m.log_time_ns, m.topic, bytes(m.data))
        for m in open_run(path).messages(decode=False)
        if m.publisher == "mission"
    ]


@pytest.fixture(scope="module")
def three_recordings(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """The example package on the quick room three times, the third while two CPU hogs
    load both cores."""
    from usar_replay.ros1.record import record_ros1

    out = tmp_path_factory.mktemp("pacing")
    paths = (out / "a.mcap", out / "b.mcap", out / "loaded.mcap")
    for path in paths:
        hogs = []
        if path.stem == "loaded":
            hogs = [_child("while True: pass") for _ in range(2)]
        try:
            result = record_ros1(quick_room(), path, EXAMPLE, RunSettings())
        finally:
            for hog in hogs:
                hog.kill()
                hog.wait()
        assert result.outcome == "done", result
    return paths


def test_two_recordings_and_a_loaded_third_are_identical_message_for_message(
    three_recordings: tuple[Path, Path, Path],
) -> None:
    a, b, loaded = (_outputs(p) for p in three_recordings)
    assert len(a) > 100
    assert a == b
    assert a == loaded


def test_the_simulator_side_is_identical_too(three_recordings: tuple[Path, Path, Path]) -> None:
    everything = [
        [(m.log_time_ns, m.topic, bytes(m.data)) for m in open_run(p).messages(decode=False)]
        for p in three_recordings
    ]
    assert everything[0] == everything[1] == everything[2]
