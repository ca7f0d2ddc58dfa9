"""The ROS 2 final project as a second assignment: world, parameters, the broken tf tree, the
built-in mission end to end (record, 60/60, bit-identical replay, view), and the faulty
examples, each losing exactly its rubric lines.

The recordings use a 320x240 camera (the marker is 1.1 m away: 25 px wide) to keep the cost
down: about 40 s of sim time each (1-2 min of wall time on 2 busy cores). The fast suite records
the built-in mission and the faulty run without a broadcaster (15 s); the two faulty runs that
drive to a wrong destination, and seeded variants, are marked slow.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import pytest

from usar_replay.core import contract, msgs
from usar_replay.core.settings import RecordSettings, RunSettings
from usar_replay.grading.grade import GradeReport, grade_file
from usar_replay.log.run import open_run
from usar_replay.node.executor import PublishPolicy
from usar_replay.pipeline.record import RecordResult, record
from usar_replay.pipeline.replay import outputs_digest, replay
from usar_replay.world import assignment, scenario, scenario_toml
from usar_replay.world.ros2_world import make_ros2_variant, ros2_final_world, task_of

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "ros2_final"
ALL_LINES = {
    "tf.odom_to_base",
    "aruco_target.reached",
    "marker.detected",
    "destination.chosen",
    "final_destination.broadcast",
    "destination.reached",
    "time_limit",
}


def small_camera(scn: scenario.Scenario) -> scenario.Scenario:
    return dataclasses.replace(scn, camera=dataclasses.replace(scn.camera, width=320, height=240))


# --- the world and its parameters (no simulation) ---------------------------------------------


def test_usar_scenarios_are_unchanged_in_toml() -> None:
    """The new fields stay out of a US&R file, so existing scenarios and logs read the same."""
    text = scenario_toml.to_toml(scenario.course_world())
    assert "assignment" not in text and "[task" not in text


def test_parameters_are_the_courses_and_never_the_marker() -> None:
    world = ros2_final_world()
    params = assignment.ROS2_FINAL.parameters(world, RunSettings())
    assert params["aruco_target.x"] == 3.6 and params["aruco_target.y"] == 1.2
    assert params["final_destination.frame_id"] == "origin1"
    assert params["final_destination.aruco_3.y"] == 1.0
    own = {k for k in params if not k.startswith(("mission.", "detector.", "use_sim_time"))}
    assert own == {
        "aruco_target.x",
        "aruco_target.y",
        "final_destination.frame_id",
        *(f"final_destination.aruco_{k}.{c}" for k in range(4) for c in "xy"),
    }  # never the marker's ID or pose, nor the origins' poses (those come from tf)


def test_the_mission_may_broadcast_base_footprint_but_not_the_simulators_links() -> None:
    asg = assignment.ROS2_FINAL
    policy = PublishPolicy(asg.sim_topics, asg.sim_frames)

    def tf(parent: str, child: str) -> msgs.TFMessage:
        return msgs.TFMessage(
            transforms=(
                msgs.TransformStamped(header=msgs.Header(frame_id=parent), child_frame_id=child),
            )
        )

    assert policy.message_problem("/tf", tf("robot1/odom", "robot1/base_footprint")) == ""
    assert policy.message_problem("/tf", tf("origin1", "final_destination")) == ""
    assert "simulator" in policy.message_problem("/tf", tf("map", "origin2"))
    assert "simulator" in policy.message_problem("/tf", tf("map", "robot1/odom"))
    assert "simulator" in policy.topic_problem(contract.ROS2_IMAGE)


def test_simulator_leaves_the_tree_broken_and_publishes_the_origins() -> None:
    from usar_replay.sim.simulator import SimRobot, Simulator

    world = ros2_final_world()
    asg = assignment.ROS2_FINAL
    with Simulator(
        small_camera(world),
        renderer="tiny",
        robots=(SimRobot(contract.ROS2_FRAMES, *asg.starts(world)[0]),),
        camera_robot=asg.camera_robot,
        base_tf=asg.sim_base_tf,
        static_frames=asg.static_links(world),
    ) as sim:
        assert sim.tf().transforms == ()
        static = {(t.header.frame_id, t.child_frame_id) for t in sim.tf_static().transforms}
        assert static == {
            ("map", "robot1/odom"),
            ("robot1/base_footprint", "robot1/camera_rgb_frame"),
            ("robot1/camera_rgb_frame", "robot1/camera_rgb_optical_frame"),
            *(("map", o) for o in contract.ORIGIN_FRAMES),
        }
        odom = sim.odometry("robot1")
        assert (odom.header.frame_id, odom.child_frame_id) == (
            "robot1/odom",
            "robot1/base_footprint",
        )
        assert sim.camera_info().header.frame_id == "robot1/camera_rgb_optical_frame"


# --- the built-in mission, end to end -----------------------------------------------------------


@pytest.fixture(scope="module")
def builtin_log(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, RecordResult]:
    path = tmp_path_factory.mktemp("ros2") / "ros2_final.mcap"
    return path, record(small_camera(ros2_final_world()), path, RunSettings())


def test_builtin_mission_gets_60_of_60(builtin_log: tuple[Path, RecordResult]) -> None:
    path, result = builtin_log
    assert result.outcome == "done", result.outcome_reason
    assert result.mission == "ros2-final"
    report = grade_file(path)
    assert report.failed_ids() == [], report.to_dict()
    assert report.points == report.max_points == 60
    assert {c.id for c in report.checks} == ALL_LINES
    # the robot had to turn to find the marker: detected after aruco_target was reached
    reached = report.check("aruco_target.reached").evidence_ns
    detected = report.check("marker.detected").evidence_ns
    assert reached is not None and detected is not None and detected > reached
    # `usar record`'s summary counts the project's marker as its rubric does (it has no
    # /explorer/marker_poses)
    assert [f.marker_id for f in result.found] == [task_of(ros2_final_world()).marker_id]
    assert result.markers_found == {} and result.markers_total == 1


def test_builtin_log_has_the_projects_topics(builtin_log: tuple[Path, RecordResult]) -> None:
    path, _ = builtin_log
    run = open_run(path)
    assert run.require_scenario().assignment == "ros2-final"
    topics = set(run.reader.topics)
    assert {
        contract.ARUCO_MARKERS,
        contract.ROS2_IMAGE,
        "/robot1/odom",
        "/robot1/cmd_vel",
    } <= topics
    ids = {
        mid
        for m in run.messages([contract.ARUCO_MARKERS])
        if isinstance(m.msg, msgs.ArucoMarkers)
        for mid in m.msg.marker_ids
    }
    assert ids == {1}
    parents = {
        (t.header.frame_id, t.child_frame_id)
        for m in run.messages([contract.TF])
        if isinstance(m.msg, msgs.TFMessage)
        for t in m.msg.transforms
    }
    assert parents == {("robot1/odom", "robot1/base_footprint"), ("origin1", "final_destination")}


def test_builtin_replay_is_bit_identical_and_grades_the_same(
    builtin_log: tuple[Path, RecordResult],
) -> None:
    from usar_replay.grading.rubric_ros2 import GRADE_TOPICS, Grader

    path, _ = builtin_log
    run = open_run(path)
    grader = Grader(run.require_scenario())
    report = replay(run, grade_sink=grader.feed, grade_topics=GRADE_TOPICS)
    assert report.identical, report.lines()
    assert report.digest == outputs_digest(path)
    replayed: GradeReport = grader.report("replayed")
    assert replayed.checks == grade_file(path).checks


def test_view_saves_the_run(builtin_log: tuple[Path, RecordResult], tmp_path: Path) -> None:
    path, _ = builtin_log
    out = tmp_path / "run.rrd"
    proc = subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", "view", "--save", str(out), str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_size > 100_000


def _pixels_of(png: bytes, color: str) -> int:
    """How many pixels of the picture are ``color`` (``#rrggbb``, within anti-aliasing)."""
    import cv2
    import numpy as np

    bgr = cv2.imdecode(np.frombuffer(png, dtype=np.uint8), cv2.IMREAD_COLOR)
    want = np.array([int(color[i : i + 2], 16) for i in (5, 3, 1)], dtype=np.int16)
    return int(np.count_nonzero(np.all(np.abs(bgr.astype(np.int16) - want) <= 12, axis=2)))


def test_report_draws_robot1s_path(builtin_log: tuple[Path, RecordResult]) -> None:
    """The HTML report takes the robot, its camera and its colour from the assignment: robot1's
    true path is on the map, its evidence points too, and its first detection frame is shown."""
    from usar_replay.grading import htmlreport

    path, _ = builtin_log
    run = open_run(path)
    world = run.require_scenario()
    report = grade_file(path)
    pic = htmlreport.collect(run)
    assert list(pic.paths) == ["robot1"] and len(pic.paths["robot1"]) > 200
    assert [d.marker_id for d in pic.detections] == [1]
    page = htmlreport.run_page(run, report, pic)
    assert "marker 1: first detected at" in page and "No marker was detected" not in page
    # the path is drawn in robot1's colour: far more of it than the start square and legend
    color = htmlreport.robot_color(assignment.ROS2_FINAL, "robot1")
    assert color != htmlreport.OTHER_ROBOT_COLOR
    drawn = _pixels_of(htmlreport.map_png(world, report, pic), color)
    no_path = htmlreport.RunPicture(paths={"robot1": pic.paths["robot1"][:1]})
    assert drawn > _pixels_of(htmlreport.map_png(world, report, no_path), color) + 500


def test_scene_draws_robot1(builtin_log: tuple[Path, RecordResult]) -> None:
    """The viewer's scene takes robot1's frames, camera and colour from the assignment: its true
    poses and path, its body under ``robot1/base_footprint``, its detections' outlines."""
    from usar_replay.viewer.scene import OTHER_ROBOT_COLOR, Scene

    path, _ = builtin_log
    run = open_run(path)
    scene = Scene(run.scenario, marker_size=run.settings.detector.marker_size)
    for m in run.messages():
        scene.feed(m.topic, m.msg, m.log_time_ns)
    scene.close()
    assert scene.robots == ["robot1"]
    assert len(scene.truth["robot1"].times) > 200
    assert len(scene.paths["robot1"].kept) > 20 and len(scene.paths["robot1"].rows.times) > 10
    base = scene.frame_paths[contract.ROS2_BASE_FRAME]
    assert base.startswith("/map/") and base.endswith("/robot1/base_footprint")
    assert scene.body_entities() == {"robot1": base + "/robot_body"}
    assert scene.robot_color("robot1") != OTHER_ROBOT_COLOR
    assert scene.pinhole_entity.endswith("/robot1/camera_rgb_optical_frame/pinhole")
    assert "id 1" in scene.detections.labels


# --- faulty examples: each loses exactly its lines ----------------------------------------------


def _record_example(tmp_path: Path, name: str, max_sim_time_s: float | None = None) -> GradeReport:
    settings = RunSettings(record=RecordSettings(max_sim_time_s=max_sim_time_s))
    path = tmp_path / f"{name}.mcap"
    result = record(
        small_camera(ros2_final_world()), path, settings, mission=str(EXAMPLES / f"{name}.py")
    )
    assert result.outcome in ("done", "max_sim_time"), result.outcome_reason
    return grade_file(path)


def test_no_odom_broadcaster_never_localises(tmp_path: Path) -> None:
    report = _record_example(tmp_path, "no_odom_broadcaster", max_sim_time_s=15.0)
    assert set(report.failed_ids()) == ALL_LINES
    assert report.check("tf.odom_to_base").measured == "never broadcast"
    assert report.check("aruco_target.reached").measured.startswith("closest 3.79")


@pytest.mark.slow
def test_destination_read_in_map_instead_of_origin(tmp_path: Path) -> None:
    report = _record_example(tmp_path, "wrong_frame")
    assert set(report.failed_ids()) == {
        "final_destination.broadcast",
        "destination.reached",
        "time_limit",
    }
    assert "parent 'map'" in report.check("final_destination.broadcast").measured


@pytest.mark.slow
def test_wrong_id_to_destination_mapping(tmp_path: Path) -> None:
    report = _record_example(tmp_path, "wrong_mapping")
    assert set(report.failed_ids()) == {
        "destination.chosen",
        "final_destination.broadcast",
        "destination.reached",
        "time_limit",
    }
    assert report.check("destination.chosen").measured == "(-1.000, -1.000) = aruco_2"


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 3])
def test_seeded_variants_get_60_of_60(seed: int, tmp_path: Path) -> None:
    world = small_camera(make_ros2_variant(ros2_final_world(), seed))
    path = tmp_path / f"seed{seed}.mcap"
    result = record(world, path, RunSettings())
    assert result.outcome == "done", result.outcome_reason
    assert grade_file(path).failed_ids() == []
