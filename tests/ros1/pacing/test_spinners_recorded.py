"""Busy waits with no pausing point, recorded for real (issue 43, item 5): a node that waits for
its move_base goals with ``while (client.getState() != SUCCEEDED) {}`` (no spinOnce, no sleep,
no log line: nothing the pacing shim sees) starts, reaches both goals and is recorded twice into
identical logs; so does the same wait begun once its thread is real-time (``late``), and
``while (ros::ok()) { if (SUCCEEDED) {...; sleep} }`` runs to its end. Before
:mod:`usar_replay.ros1.pacing.spinners` the start gate gave up after 60 s ("the graph did not go
idle") and the log had no grade.

The package is ``tests/busy_wait_package.py``'s, built once into the usual build cache (some
100 s the first time, on a 2-core machine; cached after). Wall times against the ``ros::Rate``
shape: ``bench/bench_busy_wait.py`` (never asserted here).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import busy_wait_package
import pytest
from conftest import one_room

from usar_replay.core import msgs
from usar_replay.core.settings import RunSettings
from usar_replay.log.run import open_run
from usar_replay.ros1.process import Ros1Options
from usar_replay.ros1.record import record_ros1


@pytest.fixture(scope="module")
def package(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return busy_wait_package.write(tmp_path_factory.mktemp("pkg") / busy_wait_package.NAME)


def _record(package: Path, out: Path, shape: str) -> tuple[str, list[str]]:
    """One recording of ``shape`` on the one-room world: the log's sha256 and the node's log
    lines (``/rosout``)."""
    result = record_ros1(
        one_room(),
        out,
        package,
        RunSettings(),
        options=Ros1Options(launch=busy_wait_package.launch_file(shape)),
    )
    assert result.outcome == "done", result.outcome_reason
    lines = [
        m.msg.msg for m in open_run(out).messages(["/rosout"]) if isinstance(m.msg, msgs.Log)
    ]
    return hashlib.sha256(out.read_bytes()).hexdigest(), lines


def _reached(lines: list[str]) -> None:
    """Both goals reached, in order, then the end (the robot drove there and back)."""
    assert [line.split(" at ")[0] for line in lines] == [
        "goal 1 reached",
        "goal 2 reached",
        "all goals reached",
    ], lines
    first, second = (float(line.split(" at ")[1]) for line in lines[:2])
    assert 1.0 < first < second, lines  # half a metre away, and back


@pytest.mark.parametrize("shape", ["silent", "late"])
def test_a_silent_get_state_busy_wait_starts_runs_and_records_twice_the_same(
    package: Path, tmp_path: Path, shape: str
) -> None:
    digest, lines = _record(package, tmp_path / "a.mcap", shape)
    _reached(lines)
    again, _ = _record(package, tmp_path / "b.mcap", shape)
    assert again == digest


def test_a_busy_wait_on_ros_ok_that_sleeps_once_the_goal_ended_runs(
    package: Path, tmp_path: Path
) -> None:
    _digest, lines = _record(package, tmp_path / "ok.mcap", "ok")
    _reached(lines)
