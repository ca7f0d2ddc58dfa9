"""The pacing shim (usar_replay/ros1/pacing/shim.py, catkin/usar_pacing): busy-polling nodes run.

The library is built as usar's underlay builds it (a real catkin_make), checked to link
nothing of ROS and to leave a process without roscpp alone; then the example package's busy
shapes (``examples/ros1/usar_course``, ``~busy``) are recorded on the one-room world to a
graded end: ``busy_scan.launch`` (``while (ros::ok()) { ...; publish; ros::spinOnce(); }``
with no sleep) twice, identical message for message, and ``busy_wait.launch`` (``while
(!connected) ROS_INFO(...)`` before the first clock, ``while (goal not done) ROS_INFO(...)``
with no spin). Before the shim, the first ran at the wall cap (0.33x, not repeatable) and the
second never passed the start-up gate.
"""

from __future__ import annotations

import platform
import subprocess
from collections import Counter
from pathlib import Path

import pytest
from clitools import usar
from conftest import one_room

from usar_replay.core.settings import RunSettings
from usar_replay.grading.grade import grade_file
from usar_replay.log.run import open_run
from usar_replay.ros1.building import workspace as build
from usar_replay.ros1.pacing import shim
from usar_replay.ros1.process import Ros1Options

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "ros1" / "usar_course"


def test_preloaded_puts_the_shim_first_and_keeps_what_was_there(tmp_path: Path) -> None:
    lib = tmp_path / "under" / shim.LIBRARY
    lib.parent.mkdir(parents=True)
    lib.write_bytes(b"")
    env = shim.preloaded({"PATH": "/usr/bin", "LD_PRELOAD": "/x/libother.so"}, [tmp_path / "u"])
    assert "LD_PRELOAD" in env and env["LD_PRELOAD"] == "/x/libother.so"  # no shim there
    env = shim.preloaded({"PATH": "/usr/bin", "LD_PRELOAD": "/x/libother.so"}, [tmp_path / "under"])
    assert env == {"PATH": "/usr/bin", "LD_PRELOAD": f"{lib}:/x/libother.so"}
    assert shim.preloaded({}, [str(tmp_path / "under")]) == {"LD_PRELOAD": str(lib)}


@pytest.fixture(scope="module")
def library() -> Path:
    """The shim as usar's underlay builds it (the build cache's, built once)."""
    lib = shim.library([build.underlay()])
    assert lib is not None
    return lib


def test_the_shim_wraps_roscpps_poll_points_and_links_nothing_of_ros(library: Path) -> None:
    dynamic = subprocess.run(
        ["readelf", "-d", str(library)], capture_output=True, text=True, check=True
    ).stdout
    needed = {line.split("[")[1].split("]")[0] for line in dynamic.splitlines() if "NEEDED" in line}
    assert not [n for n in needed if "ros" in n or "console" in n], needed
    symbols = subprocess.run(
        ["nm", "-DC", "--defined-only", str(library)], capture_output=True, text=True, check=True
    ).stdout
    for name in (
        "ros::spinOnce()",
        "ros::CallbackQueue::callAvailable(ros::WallDuration)",
        "ros::console::print(ros::console::FilterBase*",
    ):
        assert name in symbols, name


def test_a_process_without_roscpp_runs_as_before(library: Path) -> None:
    # roslaunch and a rospy node get the shim too (the package's environment): nothing changes
    env = shim.preloaded(build.catkin_env(), [library.parents[2]])
    done = subprocess.run(
        ["/usr/bin/python3", "-c", "import rospy; print('rospy', rospy.__name__)"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, "rospy rospy\n", "")


SLEEPER = r"""
// A thread sleeping in sim time (ros::Duration::sleep), the clock set by hand as roscpp's
// /clock callback does: prints the call the sleeper blocks in and what its sleep returned.
// With an argument the sleep begins before the first /clock (time 0), as a node's ros::Rate
// loop or ros::Duration(1).sleep() that starts at once: roscpp counts it from the first time.
#include <ros/duration.h>
#include <ros/time.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

static std::string word(long tid, const char* file, int nth) {
  std::ifstream in("/proc/self/task/" + std::to_string(tid) + "/" + file);
  std::string w;
  for (int i = 0; i <= nth; ++i) in >> w;
  return w;
}

// until the sleeper is blocked in a call, having run since `runs` (schedstat's third field,
// the times it was given a CPU); the call it is blocked in
static std::string settled(long tid, const std::string& runs) {
  std::string call;
  for (long i = 0; i < 100000000; ++i) {
    call = word(tid, "syscall", 0);
    if (call != "running" && !call.empty() && word(tid, "schedstat", 2) != runs) break;
    sched_yield();
  }
  return call;
}

int main(int argc, char**) {
  const bool from_zero = argc > 1;
  ros::Time::init();
  ros::Time::setNow(ros::Time(from_zero ? 0 : 1, 0));  // sim time from here on
  std::atomic<long> tid{0};
  std::atomic<int> result{-1};
  std::thread sleeper([&] {
    tid = syscall(SYS_gettid);
    result = ros::Duration(0.5).sleep() ? 1 : 0;
  });
  while (tid == 0) sched_yield();
  std::string call = settled(tid, "");
  if (from_zero) {
    std::string runs = word(tid, "schedstat", 2);
    ros::Time::setNow(ros::Time(1, 0));  // the first time: the sleep counts from here
    settled(tid, runs);
  }
  ros::Time::setNow(ros::Time(1, 400000000));  // not yet
  int early = result;
  ros::Time::setNow(ros::Time(1, 500000000));
  for (int i = 0; i < 300 && result == -1; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::printf("%s %d %d\n", call.c_str(), early, static_cast<int>(result));
  std::fflush(stdout);
  std::_Exit(0);  // a sleeper still asleep is not joined
}
"""


def _sleeper(library: Path, tmp_path: Path, shimmed: bool, *args: str) -> list[str]:
    """:data:`SLEEPER` built and run (with the shim preloaded or not): its three words."""
    (tmp_path / "sleeper.cpp").write_text(SLEEPER, encoding="utf-8")
    subprocess.run(
        ["g++", "-std=c++17", "-O1", "-o", "sleeper", "sleeper.cpp", "-lrostime", "-lpthread"],
        cwd=tmp_path,
        check=True,
    )
    env = {"PATH": "/usr/bin:/bin", **({"LD_PRELOAD": str(library)} if shimmed else {})}
    sleeper = str(tmp_path / "sleeper")
    done = subprocess.run([sleeper, *args], env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


@pytest.mark.parametrize("shimmed", [True, False])
def test_a_sim_time_sleep_waits_for_the_clock_blocked_not_napping(
    library: Path, tmp_path: Path, shimmed: bool
) -> None:
    """``ros::Duration::sleep`` in sim time (``ros::Rate::sleep`` calls it): roscpp's naps
    1 ms at a time (``clock_nanosleep``), which the idle check must wait out every tick; with
    the shim the thread waits on the process's clock (``futex``) and wakes when roscpp sets
    the time. Either way the sleep ends when, and only when, the time reaches its end."""
    call, early, result = _sleeper(library, tmp_path, shimmed)
    assert (early, result) == ("-1", "1")  # not at 1.4 s of a 0.5 s sleep from 1.0 s; at 1.5 s
    futex, clock_nanosleep = {"aarch64": ("98", "115")}.get(platform.machine(), ("202", "230"))
    assert call == (futex if shimmed else clock_nanosleep), call


def test_a_sleep_begun_before_the_first_clock_counts_from_the_first_time(
    library: Path, tmp_path: Path
) -> None:
    """roscpp's ``Duration::sleep`` begun at time 0 waits for the first time and sleeps its
    length from there; the shim's did not, and a node whose ``ros::Rate`` loop (or a
    ``Duration(1).sleep()``) ran before the first ``/clock`` slept until the run's end."""
    _call, early, result = _sleeper(library, tmp_path, True, "from-zero")
    assert (early, result) == ("-1", "1")  # not at 1.4 s of 0.5 s from 1.0 s; at 1.5 s


def _record(out: Path, launch: str) -> list[tuple[int, str, bytes]]:
    """One recording of the example package with ``launch`` on the one-room world, graded to
    60/60; what the package and the bridge published (not the simulator's), tick by tick."""
    from usar_replay.ros1.record import record_ros1

    result = record_ros1(
        one_room(), out, EXAMPLE, RunSettings(), options=Ros1Options(launch=launch)
    )
    run = open_run(out)
    assert result.outcome == "done", result.outcome_reason
    report = grade_file(out)
    assert report.points == report.max_points == 60, [
        (c.id, c.measured) for c in report.checks if not c.passed
    ]
    return [
        (m.log_time_ns, m.topic, bytes(m.data))
        for m in run.messages(decode=False)
        if m.publisher == "mission"
    ]


@pytest.fixture(scope="module")
def busy_scan(
    tmp_path_factory: pytest.TempPathFactory,
) -> tuple[Path, list[tuple[int, str, bytes]]]:
    """``busy_scan.launch`` recorded once: the log and its outputs."""
    out = tmp_path_factory.mktemp("busy") / "scan.mcap"
    return out, _record(out, "busy_scan.launch")


@pytest.mark.slow
def test_a_busy_scan_loop_runs_to_a_graded_end_the_same_twice(
    tmp_path: Path, busy_scan: tuple[Path, list[tuple[int, str, bytes]]]
) -> None:
    """Slow: a second live recording (about a minute on 2 CPUs). The fast suite holds the
    package's side of it in :func:`test_a_busy_scan_log_replays_bit_for_bit` (the graph re-run
    against the log's inputs gives the same bytes) and the simulator's in tests/sim."""
    _, a = busy_scan
    b = _record(tmp_path / "b.mcap", "busy_scan.launch")
    assert len(a) > 100
    assert a == b


def test_a_busy_scan_log_replays_bit_for_bit(
    busy_scan: tuple[Path, list[tuple[int, str, bytes]]],
) -> None:
    log, a = busy_scan
    assert len(a) > 100
    # paced to a few passes of the loop per tick (not thousands of cmd_vels)
    sent = [t for t, topic, _ in a if topic == "/explorer/cmd_vel"]
    assert len(sent) <= 3 * len(set(sent))
    done = usar("replay", str(log))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "bit for bit" in done.stdout


def test_a_busy_wait_before_the_first_clock_runs_to_a_graded_end_the_same_twice(
    tmp_path: Path,
) -> None:
    """Recorded twice, identical: its second action client, built after the first /clock,
    connects in the tick it registered in (the bridge holds /clock for a new registration's
    connections), not in whichever tick roscpp's 100 ms wall-clock poll made it."""
    out = _record(tmp_path / "wait.mcap", "busy_wait.launch")
    per_tick = Counter(t for t, topic, _ in out if topic == "/rosout")
    # the busy wait's own log lines: five in most ticks (not thousands), and every tick alike
    assert Counter(per_tick.values()).most_common(1)[0][0] == 5
    assert max(per_tick.values()) <= 20
    assert _record(tmp_path / "again.mcap", "busy_wait.launch") == out
