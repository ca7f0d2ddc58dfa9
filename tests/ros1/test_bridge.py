"""The graph paces the clock (docs/ros1.md, "Pacing"): two recordings of the example package,
and a third under two CPU hogs, compared message for message (the bridge's start gating, pacing
and end detection together)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from example_worlds import quick_room
from proctools import child

from usar_replay.core import contract
from usar_replay.core.settings import RunSettings
from usar_replay.log.run import open_run

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "ros1" / "usar_course"


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
            hogs = [child("while True: pass") for _ in range(2)]
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
    # the end included: the run ends in the tick the package's shutdown began, whatever the
    # machine's load (ros1/shutdown_watch)
    everything = [
        [(m.log_time_ns, m.topic, bytes(m.data)) for m in open_run(p).messages(decode=False)]
        for p in three_recordings
    ]
    assert everything[0] == everything[1] == everything[2]


def test_the_nodes_screen_output_is_identical_too(
    three_recordings: tuple[Path, Path, Path],
) -> None:
    # rosconsole's lines without its ${time} (wall time): the same on every recording
    outputs = [
        {
            name: data
            for name, data in open_run(p).reader.attachments.items()
            if name.startswith(contract.NODE_OUTPUT_ATTACHMENT_PREFIX)
        }
        for p in three_recordings
    ]
    assert outputs[0], "no node output kept"
    assert b"mission complete" in b"".join(outputs[0].values())
    assert outputs[0] == outputs[1] == outputs[2]


_QUITTER = """#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
// a second node that ends on its own after 40 loops (2 s of sim time); the mission goes on
int main(int argc, char** argv) {
  ros::init(argc, argv, "quitter");
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<geometry_msgs::PoseStamped>("/quitter/pose", 10);
  ros::Rate rate(20.0);
  for (int i = 0; ros::ok() && i < 40; ++i) {
    geometry_msgs::PoseStamped p;
    p.header.stamp = ros::Time::now();
    p.header.frame_id = "map";
    p.pose.orientation.w = 1.0;
    pub.publish(p);
    ros::spinOnce();
    rate.sleep();
  }
  ROS_INFO("quitter done");
  ros::shutdown();
  return 0;
}
"""


@pytest.mark.slow  # a build of its own and two recordings (some 3 minutes)
def test_a_node_that_ends_mid_run_does_not_end_the_run(tmp_path: Path) -> None:
    # the example with a second node (not required) that calls ros::shutdown() after 2 s: its
    # shutdown is held in the tick it began (ros1/shutdown_watch), and the run goes on to the
    # mission's own end, the same on two recordings
    from usar_replay.ros1.record import record_ros1

    pkg = tmp_path / "usar_course"
    shutil.copytree(EXAMPLE, pkg)
    (pkg / "src" / "quitter.cpp").write_text(_QUITTER)
    with (pkg / "CMakeLists.txt").open("a") as f:
        f.write(
            "add_executable(quitter src/quitter.cpp)\n"
            "add_dependencies(quitter ${catkin_EXPORTED_TARGETS})\n"
            "target_link_libraries(quitter ${catkin_LIBRARIES})\n"
        )
    launch = pkg / "launch" / "usar_course.launch"
    text = launch.read_text().replace(
        "</launch>",
        '  <node pkg="usar_course" type="quitter" name="quitter" output="screen"/>\n</launch>',
    )
    launch.write_text(text)
    logs = []
    for name in ("a", "b"):
        path = tmp_path / f"{name}.mcap"
        result = record_ros1(quick_room(), path, pkg, RunSettings())
        assert result.outcome == "done", result
        logs.append(
            [
                (m.log_time_ns, m.topic, m.publisher, bytes(m.data))
                for m in open_run(path).messages(decode=False)
            ]
        )
    a, b = logs
    quitter = [t for t, topic, _p, _d in a if topic == "/quitter/pose"]
    assert len(quitter) >= 30
    last_tick = max(t for t, *_ in a)
    assert last_tick > quitter[-1] + 20 * 10**9  # the mission went on long after it
    done = [t for t, topic, _p, data in a if topic == contract.ROSOUT and b"quitter done" in data]
    assert len(done) == 1
    assert a == b
