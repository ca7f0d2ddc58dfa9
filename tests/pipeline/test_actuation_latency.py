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


def test_a_tick_without_a_frame_is_sent_before_the_outputs_in_flight_are_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With the latency, a tick's messages follow from the tick before's commands: one
    without a camera frame goes to the mission before the recorder reads the outputs of the
    tick in flight (the mission takes it up at once); one with a frame waits for them (the
    outputs may switch the course's detector). The log is the one the plain order gives."""
    from usar_replay.core import contract
    from usar_replay.process.mission_process import MissionProcess

    events: list[tuple[str, int, bool]] = []
    send, receive = MissionProcess.send, MissionProcess.receive

    def sending(self: MissionProcess, t_ns: int, inputs: list[tuple[str, str, bytes]]) -> None:
        events.append(("send", t_ns, any(w[0] == contract.IMAGE for w in inputs)))
        send(self, t_ns, inputs)

    def receiving(self: MissionProcess) -> object:
        events.append(("receive", 0, False))
        return receive(self)

    monkeypatch.setattr(MissionProcess, "send", sending)
    monkeypatch.setattr(MissionProcess, "receive", receiving)
    mission = tmp_path / "driver.py"
    mission.write_text(DRIVER, encoding="utf-8")
    log = tmp_path / "ahead.mcap"
    settings = RunSettings(record=RecordSettings(max_sim_time_s=1.0, actuation_latency_ticks=1))
    record(quick_room(), log, settings, mission=str(mission))
    sends = [i for i, e in enumerate(events) if e[0] == "send"]
    assert len(sends) >= 15
    ahead = framed = 0
    for i in sends[1:]:
        # the receive just before this send: the tick in flight's outputs read first?
        read_first = events[i - 1][0] == "receive"
        if events[i][2]:
            assert read_first, events[i - 3 : i + 1]
            framed += 1
        else:
            assert not read_first, events[i - 3 : i + 1]
            ahead += 1
    assert ahead > 0 and framed > 0
    # two ticks in flight at the most: each send ahead is followed by the receive it skipped
    in_flight = 0
    for kind, _, _ in events:
        in_flight += 1 if kind == "send" else -1
        assert 0 <= in_flight <= 2


CRASHER = textwrap.dedent(
    """
    from usar_replay.api import Node, Odometry, Twist, Vector3

    class Crasher(Node):
        def __init__(self) -> None:
            super().__init__("crasher")
            self.seen = 0
            self.cmd = self.create_publisher(Twist, "/explorer/cmd_vel")
            self.create_subscription(Odometry, "/explorer/odom", self.on_odom)

        def on_odom(self, _msg: Odometry) -> None:
            self.seen += 1
            if self.seen == 6:
                raise RuntimeError("the crasher gives up")
            self.cmd.publish(Twist(linear=Vector3(x=0.2)))

    def main() -> None:
        Crasher()
    """
)


def test_a_mission_that_crashes_with_ticks_sent_ahead_ends_as_without(tmp_path: Path) -> None:
    """A crash while the next tick was already sent: the same verdict, the same log, with the
    latency as without it (the outputs before the crash read and written first)."""
    mission = tmp_path / "crasher.py"
    mission.write_text(CRASHER, encoding="utf-8")
    ends = {}
    for latency in (0, 1):
        log = tmp_path / f"crash-{latency}.mcap"
        settings = RunSettings(
            record=RecordSettings(max_sim_time_s=2.0, actuation_latency_ticks=latency)
        )
        result = record(quick_room(), log, settings, mission=str(mission))
        run = open_run(log)
        ticks = sorted({m.log_time_ns for m in run.messages(["/explorer/odom"])})
        ends[latency] = (result.outcome, len(ticks))
        assert "the crasher gives up" in result.outcome_reason
    assert ends[0] == ends[1] and ends[0][0] == "crashed"
