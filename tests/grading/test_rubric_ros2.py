"""grading/rubric_ros2: the ROS 2 final project's rubric, fed a hand-made run message by
message (what a log of the project holds), line by line."""

from __future__ import annotations

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import quat_from_yaw
from usar_replay.grading.rubric_ros2 import NO_DETECTOR, POINTS, TRUTH, Grader
from usar_replay.world.ros2_world import ros2_final_world, task_of

S = 1_000_000_000
WORLD = ros2_final_world()
TASK = task_of(WORLD)


def _truth(x: float, y: float) -> msgs.PoseStamped:
    return msgs.PoseStamped(pose=msgs.Pose(position=msgs.Point(x=x, y=y)))


def _tf(parent: str, child: str, x: float, y: float, yaw: float, t_ns: int) -> msgs.TFMessage:
    return msgs.TFMessage(
        transforms=(
            msgs.TransformStamped(
                header=msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id=parent),
                child_frame_id=child,
                transform=msgs.Transform(
                    translation=msgs.Vector3(x=x, y=y), rotation=quat_from_yaw(yaw)
                ),
            ),
        )
    )


def _odom(x: float, y: float, t_ns: int) -> msgs.Odometry:
    return msgs.Odometry(
        header=msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id=contract.ROS2_ODOM_FRAME),
        pose=msgs.PoseWithCovariance(pose=msgs.Pose(position=msgs.Point(x=x, y=y))),
    )


def _run(*, frame: str = TASK.frame_id, marker_id: int = TASK.marker_id) -> Grader:
    """A run of the project: odometry broadcast, aruco_target reached, the marker detected,
    final_destination broadcast in ``frame`` with the parameters of ``marker_id``, the
    destination reached."""
    g = Grader(WORLD)
    ox, oy, oyaw = TASK.origins[frame]
    g.feed(contract.TF_STATIC, _tf(contract.MAP, frame, ox, oy, oyaw, 0), S)
    g.feed(contract.odom(contract.ROS2_ROBOT), _odom(0.1, 0.0, S), S)
    g.feed(contract.TF, _tf(contract.ROS2_ODOM_FRAME, contract.ROS2_BASE_FRAME, 0.1, 0, 0, S), S)
    g.feed(TRUTH, _truth(*TASK.aruco_target), 2 * S)
    g.feed(contract.ARUCO_MARKERS, msgs.ArucoMarkers(marker_ids=(TASK.marker_id,)), 3 * S)
    dx, dy = TASK.destinations[marker_id]
    g.feed(contract.TF, _tf(frame, contract.FINAL_DESTINATION_FRAME, dx, dy, 0, 4 * S), 4 * S)
    g.feed(TRUTH, _truth(*TASK.destination), 9 * S)
    return g


def test_a_run_that_does_everything_gets_every_point() -> None:
    g = _run()
    report = g.report("run.mcap")
    assert report.failed_ids() == []
    assert report.points == report.max_points == sum(POINTS.values()) == 60
    assert report.check("time_limit").measured == "8.0 s"
    assert report.check("tf.odom_to_base").measured == "worst 0.00 cm off odometry"
    [found] = g.found_markers()
    assert found.marker_id == TASK.marker_id and found.text.endswith("at 3.0 s")


def test_another_markers_destination_fails_the_choice_and_the_place() -> None:
    other = (TASK.marker_id + 1) % 4
    report = _run(marker_id=other).report("run.mcap")
    assert report.failed_ids() == ["destination.chosen", "final_destination.broadcast"]
    assert report.check("destination.chosen").measured.endswith(f"= aruco_{other}")


def test_a_destination_in_another_frame_is_named_by_its_parent() -> None:
    report = _run(frame="origin2").report("run.mcap")
    assert "final_destination.broadcast" in report.failed_ids()
    assert report.check("final_destination.broadcast").measured == "worst: parent 'origin2'"


def test_without_aruco_markers_the_detection_line_says_why() -> None:
    """Nothing ever on /aruco_markers: the run is graded and marker.detected asks about the
    detector node; one message with another ID is "IDs seen"."""
    g = Grader(WORLD)
    g.feed(TRUTH, msgs.PoseStamped(), S)
    assert g.report("x").check("marker.detected").measured == NO_DETECTOR
    other = (TASK.marker_id + 1) % 4
    g.feed(contract.ARUCO_MARKERS, msgs.ArucoMarkers(marker_ids=(other,)), 2 * S)
    assert g.report("x").check("marker.detected").measured == f"IDs seen: {other}"
    assert g.found_markers() == ()
