"""The log contract as code: every topic, frame, key and body dimension, in one place.

Why one module: a recording is read back by replay, the grader, the viewer, ``usar info`` and
a user's mission code. If any of them spelled a topic or a frame on its own, a rename in one
would silently split them (a replay comparing the wrong topic is still "identical"). So every
other module imports names from here, and no other module spells a topic or frame literal.

Names follow the course stack (``course-world.md``): the explorer's and follower's frames are
prefixed ``<robot>_tf/``, the camera topics are the TurtleBot3 waffle's, detections are
aruco_detect's ``/fiducial_transforms``. Frames follow REP-103/105 (``map`` x east, y north;
optical frames z forward, x right, y down).

The roles of topics decide who may do what:

* :data:`SIM_TOPICS`: what the simulator publishes (and so what a mission receives as input);
* :data:`GROUND_TRUTH_TOPICS`: what only the grader and the viewer read; a mission never sees
  them and may not publish them;
* everything a mission publishes is a mission output, compared byte for byte by replay.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "CAMERA_FRAME",
    "CAMERA_INFO",
    "CLOCK",
    "ENABLE_DETECTIONS",
    "FIDUCIALS",
    "COURSE_VIEW_IMAGE",
    "COURSE_VIEW_INFO",
    "COURSE_VIEW_TOPICS",
    "GROUND_TRUTH_TOPICS",
    "IMAGE",
    "MAP",
    "MAP_TOPIC",
    "MARKER_FRAME",
    "MARKER_POSES",
    "MISSION_ATTACHMENT",
    "NODE_OUTPUT_ATTACHMENT_PREFIX",
    "OPTICAL_FRAME",
    "ARUCO_MARKERS",
    "MISSION_ARUCO_MARKERS",
    "MISSION_COPIES",
    "FINAL_DESTINATION_FRAME",
    "ORIGIN_FRAMES",
    "ROBOTS",
    "ROS1_ATTACHMENT",
    "ROS2_BASE_FRAME",
    "ROS2_CAMERA_FRAME",
    "ROS2_CAMERA_INFO",
    "ROS2_FRAMES",
    "ROS2_IMAGE",
    "ROS2_ODOM_FRAME",
    "ROS2_OPTICAL_FRAME",
    "ROS2_ROBOT",
    "RobotFrames",
    "ROSOUT",
    "RUN_METADATA",
    "RobotBody",
    "SCENARIO_ATTACHMENT",
    "SETTINGS_ATTACHMENT",
    "SIM_TOPICS",
    "START_TIME_NS",
    "STATUS_METADATA",
    "TF",
    "TF_STATIC",
    "TRUTH_MARKERS",
    "WAFFLE",
    "base_frame",
    "cmd_vel",
    "amcl_pose",
    "goal",
    "goal_status",
    "is_ground_truth",
    "odom",
    "odom_frame",
    "plan",
    "robot_of_topic",
    "sim_frames",
    "truth_pose",
]

# --- frames ---------------------------------------------------------------------------------------

MAP = "map"
"""The fixed world frame (REP-105)."""
MARKER_FRAME = "marker_frame"
"""The frame the mission broadcasts for a detected marker (the assignment's name)."""
CAMERA_FRAME = "explorer_tf/camera_rgb_frame"
"""The explorer's camera body frame (x forward, REP-103)."""
OPTICAL_FRAME = "explorer_tf/camera_rgb_optical_frame"
"""The explorer's camera optical frame (z forward, x right, y down); images are stamped in it."""

ROBOTS = ("explorer", "follower")
"""The robots of the US&R mission, in the order the simulator publishes them."""
ROS2_ROBOT = "robot1"
"""The one robot of the ROS 2 final project (assignment ``ros2-final``)."""


def odom_frame(robot: str) -> str:
    """``explorer`` -> ``explorer_tf/odom``."""
    return f"{robot}_tf/odom"


def base_frame(robot: str) -> str:
    """``explorer`` -> ``explorer_tf/base_footprint``."""
    return f"{robot}_tf/base_footprint"


# --- topics ---------------------------------------------------------------------------------------

TF = "/tf"
TF_STATIC = "/tf_static"
MAP_TOPIC = "/map"
"""nav_msgs/OccupancyGrid of walls and fixed obstacles, published once (latched) at the start,
as map_server does."""
IMAGE = "/explorer/camera/rgb/image_raw/compressed"
CAMERA_INFO = "/explorer/camera/rgb/camera_info"
FIDUCIALS = "/fiducial_transforms"
"""aruco_detect's output: one ``FiducialTransformArray`` per camera frame it searched. In the
US&R world the recorder runs the course's detector (trusted: the rubric counts only its
detections) and this is a mission *input*, published by ``sim``; a mission may not publish it."""
ENABLE_DETECTIONS = "/aruco_detect/enable_detections"
"""std_msgs/Bool switching the built-in mission's detector on (true) and off (false): the
topic form of aruco_detect's ``enable_detections`` service. The explorer turns detection on
only while it searches at a target, so frames taken on the way are not decoded at all."""
MARKER_POSES = "/explorer/marker_poses"
"""The listener's stored marker poses in ``map``."""
ROSOUT = "/rosout"
TRUTH_MARKERS = "/ground_truth/markers"
"""True marker poses (face normal along the marker frame's +x in ``map``)."""
COURSE_VIEW_INFO = "/usar/course_camera/region/camera_info"
"""The course camera's ``CameraInfo`` (1920x1080 in the course world) with ``roi`` the region
the recorder rendered for the frame of the same tick: written by the ``recorder`` only when a
marker can be in view, never sent to a mission (:mod:`usar_replay.sim.course_view`)."""
COURSE_VIEW_IMAGE = "/usar/course_camera/region/image_raw/compressed"
"""That region's grey levels (``CompressedImage``, lossless PNG): what the course's detector
searched, so replay re-detects from the log alone."""
COURSE_VIEW_TOPICS: tuple[str, ...] = (COURSE_VIEW_INFO, COURSE_VIEW_IMAGE)
CLOCK = "/clock"
"""rosgraph_msgs/Clock: not written to the log (log time is sim time), named for the node API."""

_GROUND_TRUTH_PREFIX = "/ground_truth/"


def cmd_vel(robot: str) -> str:
    return f"/{robot}/cmd_vel"


def odom(robot: str) -> str:
    return f"/{robot}/odom"


def amcl_pose(robot: str) -> str:
    """``/explorer/amcl_pose``: amcl's estimate in ``map`` (usar's stand-in publishes it)."""
    return f"/{robot}/amcl_pose"


def goal(robot: str) -> str:
    return f"/{robot}/goal"


def plan(robot: str) -> str:
    return f"/{robot}/plan"


def goal_status(robot: str) -> str:
    return f"/{robot}/goal_status"


def truth_pose(robot: str) -> str:
    return f"{_GROUND_TRUTH_PREFIX}{robot}/pose"


_ROBOT_TOPICS: dict[str, str] = {
    fn(r): r
    for r in (*ROBOTS, ROS2_ROBOT)
    for fn in (cmd_vel, odom, goal, plan, goal_status, truth_pose)
}


def robot_of_topic(topic: str) -> str | None:
    """Which robot a per-robot topic belongs to (``/follower/cmd_vel`` -> ``follower``), by
    lookup in the contract rather than by splitting the string; None for shared topics."""
    return _ROBOT_TOPICS.get(topic)


def is_ground_truth(topic: str) -> bool:
    """Ground truth is for the grader and the viewer only: never a mission input or output."""
    return topic.startswith(_GROUND_TRUTH_PREFIX)


SIM_TOPICS: tuple[str, ...] = (
    TF_STATIC,
    MAP_TOPIC,
    TF,
    CAMERA_INFO,
    IMAGE,
    *(odom(r) for r in ROBOTS),
)
"""What the simulator publishes to the mission, in the order it publishes them at one tick."""

GROUND_TRUTH_TOPICS: tuple[str, ...] = (*(truth_pose(r) for r in ROBOTS), TRUTH_MARKERS)


def sim_frames(robots: tuple[str, ...] = ROBOTS) -> tuple[str, ...]:
    """The tf links the simulator publishes (as child frames): a mission may not broadcast
    them (it would fight the simulator over where the robot is)."""
    return tuple(
        f
        for r in robots
        for f in (
            odom_frame(r),
            base_frame(r),
            f"{r}_tf/camera_rgb_frame",
            f"{r}_tf/camera_rgb_optical_frame",
        )
    )


# --- the ROS 2 final project (assignment ``ros2-final``) ------------------------------------------
#
# One robot, ``robot1``, with the course's ROS 2 frame names (``robot1/odom``, no ``_tf``). Its
# tf tree is broken on purpose: the simulator does NOT publish ``robot1/odom ->
# robot1/base_footprint`` (the students' first task is the node that broadcasts it from
# ``/robot1/odom``). ``origin1..origin4`` are static children of ``map``.

ROS2_ODOM_FRAME = "robot1/odom"
ROS2_BASE_FRAME = "robot1/base_footprint"
ROS2_CAMERA_FRAME = "robot1/camera_rgb_frame"
ROS2_OPTICAL_FRAME = "robot1/camera_rgb_optical_frame"
ROS2_IMAGE = "/robot1/camera/rgb/image_raw/compressed"
ROS2_CAMERA_INFO = "/robot1/camera/rgb/camera_info"
ARUCO_MARKERS = "/aruco_markers"
"""ros2_aruco's output: one ``ros2_aruco_interfaces/msg/ArucoMarkers`` per camera frame with a
marker in it. In the ROS 2 final project's world the recorder runs the course's detector
(trusted: the rubric counts only its detections) and this is a mission *input*, published by
``sim``; what a mission publishes here is renamed :data:`MISSION_ARUCO_MARKERS`."""
MISSION_ARUCO_MARKERS = "/mission/aruco_markers"
"""Where a mission's own ``/aruco_markers`` go when the world provides the trusted ones (a
mission written before the course's detector, which starts its own ``aruco_node``): recorded as
the mission's output, compared by replay, never graded, and delivered only to the mission's
subscribers on this name (its ``/aruco_markers`` subscribers get the course's detections)."""
MISSION_COPIES = {ARUCO_MARKERS: MISSION_ARUCO_MARKERS}
"""Trusted world topics a mission may still publish on: its messages are renamed to these
names (ROS's remapping) instead of being refused, so older missions keep running."""
FINAL_DESTINATION_FRAME = "final_destination"
"""The frame the mission broadcasts for the destination the marker chose (the project's name)."""
ORIGIN_FRAMES = ("origin1", "origin2", "origin3", "origin4")
"""Static children of ``map`` that ``final_destination.frame_id`` names."""


@dataclass(frozen=True, slots=True)
class RobotFrames:
    """One robot's names: what the simulator publishes and what a mission may not broadcast."""

    robot: str
    odom: str
    base: str
    camera: str
    optical: str

    @classmethod
    def usar(cls, robot: str) -> RobotFrames:
        """The US&R naming: ``explorer_tf/odom`` ..."""
        return cls(
            robot,
            odom_frame(robot),
            base_frame(robot),
            f"{robot}_tf/camera_rgb_frame",
            f"{robot}_tf/camera_rgb_optical_frame",
        )


ROS2_FRAMES = RobotFrames(
    ROS2_ROBOT, ROS2_ODOM_FRAME, ROS2_BASE_FRAME, ROS2_CAMERA_FRAME, ROS2_OPTICAL_FRAME
)


# --- the log file ---------------------------------------------------------------------------------

SCENARIO_ATTACHMENT = "scenario.toml"
"""MCAP attachment: the world the run used (``usar_replay.world.scenario_toml`` TOML)."""
SETTINGS_ATTACHMENT = "settings.toml"
"""MCAP attachment: every setting of the run (``usar_replay.core.settings`` TOML); replay uses
it."""
MISSION_ATTACHMENT = "mission.toml"
"""MCAP attachment: which mission code ran (target, module, sha256 of its source)."""
ROS1_ATTACHMENT = "ros1.toml"
"""MCAP attachment of a ROS 1 run: the package, how it was started, its nodes, the build time,
the parameters its nodes read, the settings that applied (:mod:`usar_replay.log.ros1_run`)."""
NODE_OUTPUT_ATTACHMENT_PREFIX = "ros1/output/"
"""MCAP attachments of a ROS 1 run: each node's stdout and stderr (``ros1/output/<node>.txt``)."""
RUN_METADATA = "usar.run"
"""MCAP metadata: software and library versions, renderer: facts about the machine."""
STATUS_METADATA = "usar.status"
"""MCAP metadata written on close: the file's state and the mission's outcome."""
START_TIME_NS = 1_000_000_000
"""The sim clock starts at 1 s, so a zero stamp (tf2's "latest") is never a real time."""


# --- the robot body (TurtleBot3 waffle) -----------------------------------------------------------


@dataclass(frozen=True, slots=True)
class RobotBody:
    """The waffle's dimensions, shared by the simulator, the costmap and the viewer.

    Metres, in ``base_footprint`` (x forward, y left, z up).
    """

    footprint: tuple[tuple[float, float], ...] = (
        (-0.205, -0.155),
        (-0.205, 0.155),
        (0.077, 0.155),
        (0.077, -0.155),
    )
    """The costmap footprint polygon."""
    radius: float = 0.26
    """The footprint rotating about base_footprint reaches 0.257 m: the costmap's robot radius."""
    body_offset: float = -0.064
    """The body centre is this far along x from base_footprint (behind the axle)."""
    body_radius: float = 0.21
    """The footprint's circumscribed radius about the body centre."""
    body_height: float = 0.094
    """Height of the body box drawn by the viewer (its centre at half this above the floor)."""
    camera_mount: tuple[float, float, float] = (0.069, -0.047, 0.117)
    """The optical centre from base_footprint (``course-world.md``)."""
    max_linear: float = 0.26
    """m/s, the waffle's top speed."""
    max_angular: float = 1.82
    """rad/s, the waffle's top turn rate."""
    max_linear_accel: float = 2.5
    """m/s^2, TurtleBot3's DWA default."""
    max_angular_accel: float = 3.2
    """rad/s^2, TurtleBot3's DWA default."""


WAFFLE = RobotBody()
"""The body both robots of the course have."""
