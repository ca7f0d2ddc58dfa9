"""The viewer's scene (usar_replay.viewer.scene) on hand-made messages: no rerun, no log file.

Each test feeds a few messages built here and checks the columns the viewer would send: where a
tf frame lands in the entity tree, where a detection's outline lands in the image, which marker a
broadcast is nearest to, how the true path grows.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from usar_replay.core import contract, msgs, rotations
from usar_replay.viewer.scene import (
    PATH_ROW_PERIOD_NS,
    Scene,
    escape_path_part,
    frame_entity_paths,
    media_type,
    project,
    robot_body,
)
from usar_replay.world.scenario import Marker, RobotStart, Scenario

S = 1_000_000_000
OPTICAL_PATH = (
    "/map/explorer_tf/odom/explorer_tf/base_footprint/explorer_tf/camera_rgb_frame"
    "/explorer_tf/camera_rgb_optical_frame"
)


def tf(parent: str, child: str, t_ns: int, xyz: tuple[float, float, float], yaw: float = 0.0):  # type: ignore[no-untyped-def]
    return msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=xyz[0], y=xyz[1], z=xyz[2]),
            rotation=rotations.quat_from_yaw(yaw),
        ),
    )


def static_tree(scene: Scene) -> None:
    """map -> explorer odom (static), the camera chain (static, the optical rotation)."""
    optical = msgs.TransformStamped(
        header=msgs.Header(frame_id=contract.CAMERA_FRAME),
        child_frame_id=contract.OPTICAL_FRAME,
        transform=msgs.Transform(rotation=msgs.Quaternion(x=-0.5, y=0.5, z=-0.5, w=0.5)),
    )
    scene.feed(
        contract.TF_STATIC,
        msgs.TFMessage(
            transforms=(
                tf(contract.MAP, contract.odom_frame("explorer"), 0, (1.0, 0.0, 0.0)),
                tf(contract.base_frame("explorer"), contract.CAMERA_FRAME, 0, (0.07, 0, 0.12)),
                optical,
            )
        ),
        S,
    )


def world() -> Scenario:
    return Scenario(
        name="scene-test",
        walls=(),
        markers=(Marker(id=3, x=2.0, y=0.0, yaw=math.pi), Marker(id=7, x=-2.0, y=0.0, yaw=0.0)),
        explorer=RobotStart(name="explorer", x=1.0, y=0.0),
        follower=RobotStart(name="follower", x=0.0, y=-1.0),
    )


CAMERA = msgs.CameraInfo(
    header=msgs.Header(frame_id=contract.OPTICAL_FRAME),
    width=640,
    height=480,
    k=(500.0, 0.0, 320.0, 0.0, 500.0, 240.0, 0.0, 0.0, 1.0),
)


# --- entity paths --------------------------------------------------------------------------------


def test_escape_path_part_follows_rerun_rules() -> None:
    assert escape_path_part("base_footprint-2.v") == "base_footprint-2.v"
    assert escape_path_part("d e") == "d\\ e"
    assert escape_path_part("a:b$c") == "a\\:b\\$c"
    assert escape_path_part("tab\tnl\n") == "tab\\tnl\\n"
    assert escape_path_part("é日") == "é日"  # letters of any script stay
    assert escape_path_part("\x00😀") == "\\u{0000}\\u{1F600}"


def test_the_tf_tree_is_the_entity_tree() -> None:
    scene = Scene(None)
    static_tree(scene)
    odom, base = contract.odom_frame("explorer"), contract.base_frame("explorer")
    scene.feed(contract.TF, msgs.TFMessage(transforms=(tf(odom, base, 2 * S, (0.5, 0, 0)),)), 2 * S)
    paths = scene.frame_paths
    assert paths[contract.OPTICAL_FRAME] == OPTICAL_PATH
    assert scene.pinhole_entity == OPTICAL_PATH + "/pinhole"
    assert scene.image_entity == OPTICAL_PATH + "/pinhole/image"
    # static transforms once each, the dynamic one as a column at its stamp
    assert set(scene.tf_static) == {odom, contract.CAMERA_FRAME, contract.OPTICAL_FRAME}
    assert scene.tf_dynamic[base].times == [2 * S]
    assert scene.tf_dynamic[base].translations == [(0.5, 0.0, 0.0)]
    assert scene.body_entities() == {"explorer": paths[base] + "/robot_body"}


def test_frame_entity_paths_cut_cycles() -> None:
    paths = frame_entity_paths({"a": "b", "b": "a", "c": "a"})
    assert paths["c"].endswith("/a/c") and paths["c"].count("/") <= 3


# --- what is drawn -------------------------------------------------------------------------------


def test_a_detection_outline_is_its_pose_projected_through_k() -> None:
    """A 0.2 m marker 2 m straight ahead, facing the camera: a 50 px square about the centre."""
    scene = Scene(None, marker_size=0.2)
    scene.feed(contract.CAMERA_INFO, CAMERA, S)
    facing = msgs.Quaternion(x=1.0, y=0.0, z=0.0, w=0.0)  # marker z towards the camera
    detection = msgs.FiducialTransform(
        fiducial_id=4,
        transform=msgs.Transform(translation=msgs.Vector3(z=2.0), rotation=facing),
    )
    broken = msgs.FiducialTransform(
        fiducial_id=5,
        transform=msgs.Transform(translation=msgs.Vector3(z=2.0), rotation=msgs.Quaternion(w=0)),
    )
    scene.feed(contract.FIDUCIALS, msgs.FiducialTransformArray(transforms=(detection, broken)), S)
    scene.feed(contract.FIDUCIALS, msgs.FiducialTransformArray(), 2 * S)
    rows = scene.detections
    assert rows.times == [S, 2 * S] and rows.lengths == [1, 0]  # a row per frame, even empty
    assert rows.labels == ["id 4"]  # the zero quaternion is left out, not drawn wrong
    outline = rows.items[0]
    assert outline.shape == (5, 2)  # closed: the first corner again
    assert outline[0] == pytest.approx(outline[4])
    assert sorted({round(u) for u, _ in outline}) == [295, 345]
    assert sorted({round(v) for _, v in outline}) == [215, 265]
    # ArUco's corner order: top-left first in the image, then clockwise
    assert outline[0] == pytest.approx([295, 215]) and outline[1] == pytest.approx([345, 215])


def test_a_detection_a_tick_late_is_drawn_at_its_frame() -> None:
    """With ``record.detection_latency_ticks`` 1 the course's detections of a frame come a
    tick later, stamped with the frame: the outline goes at the frame's time, over the image
    it was found in; a stamp that is no time before the message's (0, the future, long ago)
    leaves it at the message's own time."""
    scene = Scene(None, marker_size=0.2)
    scene.feed(contract.CAMERA_INFO, CAMERA, S)
    tick = 50_000_000

    def array(stamp_ns: int) -> msgs.FiducialTransformArray:
        return msgs.FiducialTransformArray(
            header=msgs.Header(stamp=msgs.Time.from_ns(stamp_ns), frame_id="camera")
        )

    scene.feed(contract.FIDUCIALS, array(S), S + tick)  # frame S, delivered a tick later
    scene.feed(contract.FIDUCIALS, array(3 * S), 2 * S)  # from the future: its own time
    scene.feed(contract.FIDUCIALS, array(S), 5 * S)  # long before: its own time
    assert scene.detections.times == [S, 2 * S, 5 * S]


def test_projection_of_a_point_behind_the_camera_is_none() -> None:
    assert project(np.array([[0.0, 0.0, -1.0]]), CAMERA) is None


def test_marker_frame_is_looked_up_in_map_and_labelled_with_the_nearest_true_marker() -> None:
    scene = Scene(world())
    static_tree(scene)
    odom, base = contract.odom_frame("explorer"), contract.base_frame("explorer")
    for t in (S, 3 * S):  # the robot stands at map (1.5, 0)
        scene.feed(contract.TF, msgs.TFMessage(transforms=(tf(odom, base, t, (0.5, 0, 0)),)), t)
    # 0.45 m ahead of the robot, 0.2 m up -> map (1.95, 0, 0.2): 5 cm off marker 3 (z 0.2)
    broadcast = tf(base, contract.MARKER_FRAME, 2 * S, (0.45, 0.0, 0.2))
    scene.feed(contract.TF, msgs.TFMessage(transforms=(broadcast,)), 2 * S)
    rows = scene.marker_frame_rows
    assert rows.times == [2 * S] and rows.lengths == [1]
    assert rows.items[0] == pytest.approx((1.95, 0.0, 0.2))
    assert rows.labels == ["marker_frame ~3: 5.0 cm off"]
    # a broadcast that cannot be looked up (past the robot's last pose) is a warning, not a point
    lost = tf(base, contract.MARKER_FRAME, 10 * S, (0.45, 0.0, 0.2))
    scene.feed(contract.TF, msgs.TFMessage(transforms=(lost,)), 10 * S)
    assert rows.lengths == [1]
    assert scene.texts["/logs/tf"].levels == ["WARN"]


def test_true_and_stored_markers_are_points_per_row() -> None:
    scene = Scene(None)
    true = msgs.FiducialTransformArray(
        transforms=(
            msgs.FiducialTransform(
                fiducial_id=1, transform=msgs.Transform(translation=msgs.Vector3(x=1, y=2, z=0.3))
            ),
        )
    )
    scene.feed(contract.TRUTH_MARKERS, true, S)
    scene.feed(contract.MARKER_POSES, msgs.FiducialTransformArray(), S)
    assert scene.true_markers.items == [(1.0, 2.0, 0.3)]
    assert scene.true_markers.labels == ["true 1"]
    assert scene.true_marker_xyz == {1: (1.0, 2.0, 0.3)}
    assert scene.stored_markers.lengths == [0]


def test_cmd_vel_rosout_goals_and_goal_status() -> None:
    scene = Scene(None)
    twist = msgs.Twist(linear=msgs.Vector3(x=0.2), angular=msgs.Vector3(z=-0.5))
    scene.feed(contract.cmd_vel("follower"), twist, S)
    scene.feed(contract.ROSOUT, msgs.Log(level=30, name="explorer", msg="stuck"), S)
    scene.feed(contract.ROSOUT, msgs.Log(level=99, msg="odd level"), S)
    goal = msgs.PoseStamped(
        pose=msgs.Pose(
            position=msgs.Point(x=1, y=2), orientation=rotations.quat_from_yaw(math.pi / 2)
        )
    )
    scene.feed(contract.goal("explorer"), goal, 2 * S)
    status = msgs.DiagnosticStatus(level=2, name="3", message="aborted", hardware_id="explorer")
    scene.feed(contract.goal_status("explorer"), status, 3 * S)
    assert scene.scalars["/plots/follower/cmd_vel/linear_x"] == ([S], [0.2])
    assert scene.scalars["/plots/follower/cmd_vel/angular_z"] == ([S], [-0.5])
    assert scene.plotted_robots() == ["follower"]
    rosout = scene.texts["/logs/rosout"]
    assert rosout.texts == ["[explorer] stuck", "odd level"]
    assert rosout.levels == ["WARN", "INFO"]
    origin, vector = scene.goals["explorer"].items[0]
    assert origin == pytest.approx((1.0, 2.0, 0.02))
    assert vector == pytest.approx((0.0, 0.3, 0.0))  # 0.3 m along the goal's heading
    goals = scene.texts["/logs/goals"]
    assert goals.texts == ["explorer: goal 3 aborted"] and goals.levels == ["ERROR"]
    assert scene.robots == ["follower", "explorer"]


def test_true_path_grows_once_per_sim_second_and_ends_where_the_robot_ended() -> None:
    scene = Scene(None)
    topic = contract.truth_pose("explorer")
    step = PATH_ROW_PERIOD_NS // 4
    for i in range(10):  # 0.1 m per quarter second, 2.25 s in all
        pose = msgs.PoseStamped(pose=msgs.Pose(position=msgs.Point(x=0.1 * i)))
        scene.feed(topic, pose, S + i * step)
    path = scene.paths["explorer"]
    assert path.rows.times == [S, 2 * S, 3 * S]
    scene.close()
    assert path.rows.times[-1] == S + 9 * step
    last = path.rows.items[-1]
    assert len(last) == 10 and last[-1] == pytest.approx((0.9, 0.0, 0.01))
    assert [len(r) for r in path.rows.items] == [1, 5, 9, 10]  # it grows
    assert len(scene.truth["explorer"].times) == 10


def test_images_are_taken_out_in_batches_with_their_media_type() -> None:
    scene = Scene(None)
    png = msgs.CompressedImage(format="png", data=b"\x89PNG" + bytes(96))
    jpeg = msgs.CompressedImage(format="jpeg", data=b"\xff\xd8" + bytes(48))
    scene.feed(contract.IMAGE, png, S)
    scene.feed(contract.IMAGE, jpeg, 2 * S)
    assert scene.pending_image_bytes == 150
    batch = scene.take_images()
    assert batch.times == [S, 2 * S] and batch.media_types == ["image/png", "image/jpeg"]
    assert batch.blobs[0] == png.data  # the recorded bytes, not decoded
    assert scene.pending_image_bytes == 0 and scene.images_taken == 2
    assert scene.take_images().times == []
    assert media_type(msgs.CompressedImage(format="jpeg", data=b"??")) == "image/jpeg"


def test_odd_messages_are_counted_and_ignored() -> None:
    scene = Scene(None)
    scene.feed("/unknown", None, 5 * S)
    scene.feed(contract.cmd_vel("explorer"), msgs.String(data="not a twist"), 6 * S)
    scene.add_note("incomplete log: cut")
    assert scene.messages == 2 and scene.end_ns == 6 * S
    assert not scene.scalars
    assert scene.texts["/logs/view"].times == [6 * S]  # a note sits at the end of the log


def test_the_body_is_the_waffle_footprint() -> None:
    centre, half = robot_body()
    assert centre[0] == pytest.approx(contract.WAFFLE.body_offset)
    assert half[2] * 2 == pytest.approx(contract.WAFFLE.body_height)
    xs = [x for x, _ in contract.WAFFLE.footprint]
    assert centre[0] + half[0] == pytest.approx(max(xs))


def test_the_scene_imports_no_rerun() -> None:
    code = (
        "import sys, usar_replay.viewer.scene as s; "
        "print(sorted({'rerun', 'mcap'} & set(sys.modules)))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
