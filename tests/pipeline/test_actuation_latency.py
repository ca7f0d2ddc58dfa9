"""``record.actuation_latency_ticks``: the mission thinks while the simulator steps.

With 1, a tick's ``cmd_vel`` acts from the step after the next one (the default for a ROS 1
package, whose graph then reacts beside the simulator); with 0 from the next step (a Python
mission's default). The log stores the value that ran, and a replay reproduces such a log bit
for bit.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from example_worlds import quick_room

from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import record, with_latency
from usar_replay.pipeline.replay import replay

DRIVER = textwrap.dedent(
    """
    from usar_replay.api import Node, Odometry, Twist, Vector3

    class Driver(Node):
        def __init__(self) -> None:
            super().__init__("driver")
            self.cmd = self.create_publisher(Twist, "/explorer/cmd_vel")
            self.create_subscription(Odometry, "/explorer/odom", self.on_odom)

        def on_odom(self, _msg: Odometry) -> None:
            self.cmd.publish(Twist(linear=Vector3(x=0.2)))

    def main() -> None:
        Driver()
    """
)


def _xs(log: Path) -> list[float]:
    """The explorer's true x at each tick."""
    run = open_run(log)
    return [m.msg.pose.position.x for m in run.messages(["/ground_truth/explorer/pose"])]


@pytest.fixture(scope="module")
def driven(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    """The driver recorded for 0.5 s of sim time with each latency."""
    folder = tmp_path_factory.mktemp("latency")
    mission = folder / "driver.py"
    mission.write_text(DRIVER, encoding="utf-8")
    logs = {}
    for latency in (0, 1):
        settings = RunSettings(
            record=RecordSettings(max_sim_time_s=0.5, actuation_latency_ticks=latency)
        )
        logs[latency] = folder / f"latency-{latency}.mcap"
        record(quick_room(), logs[latency], settings, mission=str(mission))
    return logs


def test_a_command_acts_one_tick_later(driven: dict[int, Path]) -> None:
    now, later = _xs(driven[0]), _xs(driven[1])
    assert len(now) == len(later) >= 8
    start = now[0]
    assert later[0] == start and now[1] > start + 0.001  # moved in the step after tick 0
    assert later[1] == pytest.approx(start, abs=1e-4)  # with 1: not yet
    assert later[2] > start + 0.001
    # the same commands, one tick later: the same path, one tick later
    assert later[2:] == pytest.approx(now[1:-1], abs=1e-4)


def test_the_log_stores_the_latency_that_ran(driven: dict[int, Path]) -> None:
    for latency, log in driven.items():
        assert open_run(log).settings.record.actuation_latency_ticks == latency
    # unset: 0 for a Python mission (record's default), 1 where a ROS 1 record asks for it
    unset = RunSettings()
    assert unset.record.actuation_latency_ticks is None
    assert with_latency(unset, 1).record.actuation_latency_ticks == 1
    assert with_latency(_settings(0), 1).record.actuation_latency_ticks == 0


def _settings(latency: int) -> RunSettings:
    return RunSettings(record=RecordSettings(actuation_latency_ticks=latency))


def test_the_built_in_mission_with_latency_replays_bit_for_bit(tmp_path: Path) -> None:
    """The built-in explorer switches the course's detector on and off: with the latency the
    switch still acts from the next frame, as replay's own detections assume."""
    log = tmp_path / "builtin.mcap"
    result = record(quick_room(), log, _settings(1))
    assert result.outcome == "done" and len(result.found) == 1
    report = replay(log)
    assert report.identical, report.divergence
    assert report.topics["/fiducial_transforms"].identical > 0
