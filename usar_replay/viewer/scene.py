"""The scene of `usar view`: a log's messages turned into columns per viewer entity (pure).

What the viewer draws, and where, is decided here; :mod:`usar_replay.viewer.view` only hands these
columns to rerun. Why the split: what a log *means* in the viewer (which entity a tf frame is,
where a detection's outline lands in the image, which marker a broadcast is nearest to) is
testable on hand-made messages without rerun, a viewer process or a file, and the rerun part is
left with one job (sending, the layout, the viewer process and its ports).

The scene, on one time axis (the log's sim time in nanoseconds):

* the tf tree as an entity tree (:func:`frame_entity_paths`): static transforms once, dynamic
  ones as a column per child frame; each robot's body under its ``base_footprint``, the camera
  under the optical frame;
* each robot's true pose, its true path so far (one row per sim second), its goals and plans;
* the true markers, the markers the mission stored (wherever it put them:
  :mod:`usar_replay.grading.stored_markers`), and every broadcast ``marker_frame`` looked up in
  ``map`` at its own stamp with :class:`usar_replay.core.tf_tree.BufferCore`, labelled with the
  nearest true marker and the distance to it;
* the camera images (the recorded bytes, never decoded here) with each detection's outline
  (``aruco_detect``'s ``/fiducial_transforms`` or ``ros2_aruco``'s ``/aruco_markers``);
* ``cmd_vel`` as scalars, ``/rosout``, goal outcomes, notes and rubric lines as text rows.

The robots, their frames, the camera and the robots' colours come from the scenario's assignment
(:func:`usar_replay.world.assignment.of`; US&R when the log has no scenario): a ROS 2 final
project run draws ``robot1`` as a US&R run draws the explorer and the follower. A robot's colour is
:data:`ROBOT_PALETTE` at its index in the assignment.

Everything is collected as plain lists while the log streams by (each entity then goes to the
viewer in one columnar call); only images are taken out early (:meth:`Scene.take_images`) so
memory stays bounded. No rerun, mcap or pybullet import here.
"""

from __future__ import annotations

import math
import string
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from usar_replay.core import contract, msgs, rotations
from usar_replay.core.tf_tree import BufferCore, TransformException
from usar_replay.grading.stored_markers import StoredMarkers, is_marker_topic
from usar_replay.world.assignment import USAR, Assignment
from usar_replay.world.assignment import of as assignment_of
from usar_replay.world.scenario import Scenario

if TYPE_CHECKING:
    from usar_replay.grading.grade import GradeReport

__all__ = [
    "ImageBatch",
    "Poses",
    "Scene",
    "Strips",
    "Texts",
    "TruePath",
    "escape_path_part",
    "frame_entity_path",
    "frame_entity_paths",
    "marker_corners",
    "media_type",
    "project",
    "robot_body",
    "robot_color",
]

FloatArray = npt.NDArray[np.float64]
XYZ = tuple[float, float, float]

PATH_ROW_PERIOD_NS = 1_000_000_000
"""The growing true path gets a new row once per sim second (a row per pose would be O(n^2))."""
PATH_MIN_STEP_M = 0.05
"""Points of the true path closer than this to the previous kept point are dropped."""
MARKER_FRAME_HISTORY = 2000
"""At most this many past ``marker_frame`` lookups are kept in the cumulative map layer."""

# --- entities that are not tf frames -------------------------------------------------------------

MAP_ENTITY = "/" + contract.MAP
WORLD_ENTITY = MAP_ENTITY + "/world"
TARGETS_ENTITY = MAP_ENTITY + "/targets"
HOMES_ENTITY = MAP_ENTITY + "/homes"
TRUTH_ENTITY = MAP_ENTITY + "/ground_truth"
TRUE_MARKERS_ENTITY = TRUTH_ENTITY + "/markers"
STORED_MARKERS_ENTITY = MAP_ENTITY + "/explorer/stored_markers"
MARKER_FRAME_ENTITY = MAP_ENTITY + "/marker_frame_in_map"
PLOTS_ENTITY = "/plots"
LOGS_ENTITY = "/logs"
ROSOUT_ENTITY = LOGS_ENTITY + "/rosout"
GOALS_LOG_ENTITY = LOGS_ENTITY + "/goals"
TF_LOG_ENTITY = LOGS_ENTITY + "/tf"
GRADE_ENTITY = LOGS_ENTITY + "/grade"
NOTES_ENTITY = LOGS_ENTITY + "/view"

# --- colours -------------------------------------------------------------------------------------

ROBOT_PALETTE: tuple[tuple[int, int, int], ...] = (
    (255, 140, 0),
    (30, 144, 255),
    (60, 200, 200),
    (220, 120, 220),
)
"""Robot colours by the robot's index in its assignment (US&R: explorer orange, follower blue;
ROS 2: robot1 orange)."""
OTHER_ROBOT_COLOR = (160, 160, 160)
WALL_COLOR = (219, 217, 204)
FLOOR_COLOR = (92, 86, 78)
OBSTACLE_COLOR = (140, 153, 178)
TARGET_COLOR = (250, 210, 40)
TRUE_MARKER_COLOR = (40, 200, 80)
STORED_MARKER_COLOR = (255, 150, 40)
MARKER_FRAME_COLOR = (230, 40, 40)
DETECTION_COLOR = (40, 255, 80)
ANGULAR_COLOR = (200, 60, 200)

_ROS_LEVELS = {10: "DEBUG", 20: "INFO", 30: "WARN", 40: "ERROR", 50: "CRITICAL"}
_GOAL_LEVELS = {0: "INFO", 1: "WARN"}


def robot_color(robot: str, robots: Sequence[str]) -> tuple[int, int, int]:
    """The colour of ``robot`` among its assignment's ``robots`` (grey for one it does not
    name)."""
    if robot not in robots:
        return OTHER_ROBOT_COLOR
    return ROBOT_PALETTE[list(robots).index(robot) % len(ROBOT_PALETTE)]


def robot_body() -> tuple[XYZ, XYZ]:
    """The drawn body box (centre, half sizes) in ``base_footprint``: the waffle's footprint
    (:data:`usar_replay.core.contract.WAFFLE`), as tall as its body, standing on the floor."""
    body = contract.WAFFLE
    xs = [x for x, _ in body.footprint]
    ys = [y for _, y in body.footprint]
    half = ((max(xs) - min(xs)) / 2, (max(ys) - min(ys)) / 2, body.body_height / 2)
    centre = ((max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2, body.body_height / 2)
    return centre, half


# --- entity paths --------------------------------------------------------------------------------

_KEPT = frozenset("-_.")
_NAMED = {"\t": "\\t", "\n": "\\n", "\r": "\\r"}
_PUNCTUATION = frozenset(string.punctuation + " ")


def escape_path_part(part: str) -> str:
    """One entity path part escaped as rerun escapes it (``escape_entity_path_part``).

    Letters, digits, ``-``, ``_`` and ``.`` stay; ASCII punctuation and space get a backslash;
    tab, newline and return their C escapes; any other character ``\\u{XXXX}`` (the rerun tests
    compare this with rerun's own function).
    """
    out: list[str] = []
    for c in part:
        if c in _KEPT or c.isalnum():
            out.append(c)
        elif c in _NAMED:
            out.append(_NAMED[c])
        elif c in _PUNCTUATION:
            out.append("\\" + c)
        else:
            out.append(f"\\u{{{ord(c):04X}}}")
    return "".join(out)


def _frame_parts(frame: str) -> list[str]:
    """A tf frame id as entity path parts: split at '/', each part escaped."""
    parts = [escape_path_part(p) for p in frame.split("/") if p]
    return parts or ["_unnamed"]


def frame_entity_paths(parents: Mapping[str, str]) -> dict[str, str]:
    """Every frame's entity path, so that the viewer's entity tree has the shape of the tf tree.

    ``parents`` is ``{child: parent}`` (what :meth:`usar_replay.core.tf_tree.BufferCore.frames`
    returns). A frame's path is its parent's path followed by the frame id; a root frame (``map``)
    is at the top: ``/map/explorer_tf/odom/explorer_tf/base_footprint/...``.

    Sanitising: a tf frame id may hold '/' (the robot prefix in ``explorer_tf/odom``); it is kept
    as a path separator, so the prefix becomes an intermediate entity without a transform
    (identity), which rerun composes correctly and which reads like tf's own namespaces. Every
    part is escaped (:func:`escape_path_part`: spaces, ':', '$' and the like), empty parts (a
    leading '/') are dropped. A cycle in the tree (a broken log) is cut where it closes. The
    viewer's own entities under a frame (``robot_body``, ``pinhole``) would only collide with a
    tf frame of that very name, which no usar log has.
    """
    out: dict[str, str] = {}

    def path_of(frame: str, seen: frozenset[str]) -> str:
        known = out.get(frame)
        if known is not None:
            return known
        parent = parents.get(frame)
        if parent is None or parent in seen or parent == frame:
            path = "/" + "/".join(_frame_parts(frame))
        else:
            path = path_of(parent, seen | {frame}) + "/" + "/".join(_frame_parts(frame))
        out[frame] = path
        return path

    for child, parent in parents.items():
        path_of(child, frozenset())
        path_of(parent, frozenset())
    return out


def frame_entity_path(parents: Mapping[str, str], frame: str) -> str:
    """The entity path of one frame (a frame unknown to the tree is a root of its own)."""
    return frame_entity_paths({**parents, frame: parents.get(frame, frame)}).get(
        frame, "/" + "/".join(_frame_parts(frame))
    )


# --- small geometry ------------------------------------------------------------------------------


def marker_corners(size: float) -> FloatArray:
    """A marker's corners in its own frame, in ArUco's order (as ``detect`` solves the pose)."""
    h = size / 2.0
    return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]], dtype=np.float64)


def project(points: FloatArray, info: msgs.CameraInfo) -> FloatArray | None:
    """Pixels of optical-frame points through ``K`` and plumb-bob distortion; None if behind."""
    if np.any(points[:, 2] <= 1e-6):
        return None
    k = info.k
    x = points[:, 0] / points[:, 2]
    y = points[:, 1] / points[:, 2]
    d = [*info.d, 0.0, 0.0, 0.0, 0.0, 0.0][:5]
    if any(d):
        k1, k2, p1, p2, k3 = d
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2
        x, y = (
            x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
            y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y,
        )
    u = k[0] * x + k[1] * y + k[2]
    v = k[4] * y + k[5]
    return np.stack([u, v], axis=1)


def media_type(image: msgs.CompressedImage) -> str:
    """The image's MIME type from its magic bytes (the ``format`` field only as a fallback)."""
    head = image.data[:4]
    if head.startswith(b"\x89PNG"):
        return "image/png"
    if head.startswith(b"\xff\xd8"):
        return "image/jpeg"
    return "image/jpeg" if "jp" in image.format.lower() else "image/png"


# --- columns -------------------------------------------------------------------------------------


@dataclass(slots=True)
class Poses:
    """A transform per row (translation, quaternion x y z w)."""

    times: list[int] = field(default_factory=list)
    translations: list[XYZ] = field(default_factory=list)
    quaternions: list[tuple[float, float, float, float]] = field(default_factory=list)


@dataclass(slots=True)
class Texts:
    """Text log rows with their level (``DEBUG`` .. ``CRITICAL``)."""

    times: list[int] = field(default_factory=list)
    texts: list[str] = field(default_factory=list)
    levels: list[str] = field(default_factory=list)


@dataclass(slots=True)
class Strips:
    """Rows of zero or more strips (or points) each: ``lengths[i]`` items belong to row ``i``.

    ``labels`` is either empty or one per item.
    """

    times: list[int] = field(default_factory=list)
    items: list[Any] = field(default_factory=list)
    labels: list[str] = field(default_factory=list)
    lengths: list[int] = field(default_factory=list)


@dataclass(slots=True)
class TruePath:
    """A robot's true path: kept points, and the rows of the growing strip."""

    kept: list[XYZ] = field(default_factory=list)
    last_row_ns: int | None = None
    last: tuple[int, XYZ] | None = None
    rows: Strips = field(default_factory=Strips)

    def add_row(self, t_ns: int, here: XYZ) -> None:
        pts = self.kept if self.kept and self.kept[-1] == here else [*self.kept, here]
        self.rows.times.append(t_ns)
        self.rows.items.append(np.asarray(pts, dtype=np.float64))
        self.rows.lengths.append(1)
        self.last_row_ns = t_ns


@dataclass(slots=True)
class ImageBatch:
    """Encoded camera images, as recorded, with their MIME types."""

    times: list[int] = field(default_factory=list)
    blobs: list[bytes] = field(default_factory=list)
    media_types: list[str] = field(default_factory=list)


# --- detections ----------------------------------------------------------------------------------

_Found = tuple[int, msgs.Vector3 | msgs.Point, msgs.Quaternion]
"""One detected marker: its ID and its pose in the camera's optical frame."""


def _fiducial_poses(msg: msgs.FiducialTransformArray) -> list[_Found]:
    """US&R's ``aruco_detect`` output as (ID, translation, rotation) per marker."""
    return [(f.fiducial_id, f.transform.translation, f.transform.rotation) for f in msg.transforms]


FRAME_LAG_NS = 1_000_000_000
"""How long before its message a detection's frame may be and still be the one it is drawn
on (the course's detector answers one tick, 50 ms, after its frame by default for a ROS 1
package: ``record.detection_latency_ticks``)."""


def _frame_time(stamp_ns: int, t_ns: int) -> int:
    """Where on the timeline a detection's outline goes: at its frame (the header stamp, the
    image's), so it is drawn over the image it was found in, not the next one; at the
    message's own time where the stamp is not a time up to :data:`FRAME_LAG_NS` before it (a
    missing or forged stamp of an old log's mission detector)."""
    return stamp_ns if 0 < t_ns - stamp_ns <= FRAME_LAG_NS and stamp_ns > 0 else t_ns


def _aruco_poses(msg: msgs.ArucoMarkers) -> list[_Found]:
    """The ROS 2 project's ``ros2_aruco`` output, the same way (IDs and poses in one order)."""
    return [
        (mid, p.position, p.orientation) for mid, p in zip(msg.marker_ids, msg.poses, strict=False)
    ]


# --- the scene -----------------------------------------------------------------------------------


class Scene:
    """A streaming consumer of a log's messages (:meth:`feed`, in log order) that collects what
    the viewer shows, as columns per entity. Call :meth:`close` once the log has been read."""

    def __init__(self, scenario: Scenario | None, *, marker_size: float = 0.15) -> None:
        self.scenario = scenario
        self.marker_size = marker_size
        self.buffer = BufferCore(cache_time=30.0)
        self.tf_parents: dict[str, str] = {}
        self.tf_static: dict[str, tuple[XYZ, tuple[float, float, float, float]]] = {}
        self.tf_dynamic: dict[str, Poses] = {}
        self.camera_info: msgs.CameraInfo | None = None
        # names come from the scenario's assignment (US&R's explorer, or ROS 2's robot1)
        asg = USAR if scenario is None else assignment_of(scenario)
        self.assignment: Assignment = asg
        self.camera_topic, self.camera_info_topic = asg.image_topic, asg.camera_info_topic
        self.camera_frame = asg.frames_of(asg.camera_robot).optical
        self._pinhole_entity: str | None = None
        self._images = ImageBatch()
        self.pending_image_bytes = 0
        self.images_taken = 0
        self.detections = Strips()
        self.scalars: dict[str, tuple[list[int], list[float]]] = {}
        self.texts: dict[str, Texts] = {}
        self.truth: dict[str, Poses] = {}
        self.paths: dict[str, TruePath] = {}
        self.goals: dict[str, Strips] = {}
        self.plans: dict[str, Strips] = {}
        self.true_markers = Strips()
        self.true_marker_xyz: dict[int, XYZ] = {}
        self.stored_markers = Strips()
        self._stored: StoredMarkers | None = None
        self._marker_frame_points: list[XYZ] = []
        self._marker_frame_labels: list[str] = []
        self.marker_frame_rows = Strips()
        self.robots: list[str] = []
        self.messages = 0
        self.end_ns = 0
        if scenario is not None:
            self.true_marker_xyz = {m.id: (m.x, m.y, m.z) for m in scenario.markers}
            for name in asg.robot_names:
                self._robot(name)

    def _robot(self, name: str) -> str:
        if name not in self.robots:
            self.robots.append(name)
        return name

    # -- feeding ----------------------------------------------------------------------------------

    def feed(self, topic: str, msg: msgs.Message | None, t_ns: int) -> None:
        """One message of the log, in log order (``msg`` None for types the viewer ignores)."""
        self.messages += 1
        self.end_ns = max(self.end_ns, t_ns)
        if msg is None:
            return
        if isinstance(msg, msgs.TFMessage) and topic in (contract.TF, contract.TF_STATIC):
            self._on_tf(msg, t_ns, static=topic == contract.TF_STATIC)
        elif isinstance(msg, msgs.CompressedImage) and topic == self.camera_topic:
            self._on_image(msg, t_ns)
        elif isinstance(msg, msgs.CameraInfo) and topic == self.camera_info_topic:
            if self.camera_info is None:
                self.camera_frame = msg.header.frame_id or self.camera_frame
            self.camera_info = msg
        elif isinstance(msg, msgs.FiducialTransformArray) and topic == contract.FIDUCIALS:
            self._on_detections(_fiducial_poses(msg), _frame_time(msg.header.stamp.ns, t_ns))
        elif isinstance(msg, msgs.ArucoMarkers) and topic == contract.ARUCO_MARKERS:
            self._on_detections(_aruco_poses(msg), _frame_time(msg.header.stamp.ns, t_ns))
        elif isinstance(msg, msgs.FiducialTransformArray) and topic == contract.TRUTH_MARKERS:
            self._on_true_markers(msg, t_ns)
        elif is_marker_topic(topic, type(msg).__msgtype__):
            self._on_stored_markers(topic, msg, t_ns)
        elif isinstance(msg, msgs.Log) and topic == contract.ROSOUT:
            text = f"[{msg.name}] {msg.msg}" if msg.name else msg.msg
            self._text(ROSOUT_ENTITY, t_ns, text, _ROS_LEVELS.get(msg.level, "INFO"))
        elif (robot := contract.robot_of_topic(topic)) is not None:
            self._on_robot_topic(self._robot(robot), topic, msg, t_ns)

    def _on_robot_topic(self, robot: str, topic: str, msg: msgs.Message, t_ns: int) -> None:
        if topic == contract.cmd_vel(robot) and isinstance(msg, msgs.Twist):
            self._scalar(f"{PLOTS_ENTITY}/{robot}/cmd_vel/linear_x", t_ns, msg.linear.x)
            self._scalar(f"{PLOTS_ENTITY}/{robot}/cmd_vel/angular_z", t_ns, msg.angular.z)
        elif topic == contract.truth_pose(robot) and isinstance(msg, msgs.PoseStamped):
            self._on_truth(robot, msg, t_ns)
        elif topic == contract.goal(robot) and isinstance(msg, msgs.PoseStamped):
            p = msg.pose.position
            yaw = rotations.yaw_from_quat(msg.pose.orientation)
            rows = self.goals.setdefault(robot, Strips())
            rows.times.append(t_ns)
            rows.items.append(
                ((p.x, p.y, p.z + 0.02), (0.3 * math.cos(yaw), 0.3 * math.sin(yaw), 0.0))
            )
            rows.labels.append(f"{robot} goal")
            rows.lengths.append(1)
        elif topic == contract.plan(robot) and isinstance(msg, msgs.Path):
            rows = self.plans.setdefault(robot, Strips())
            rows.times.append(t_ns)
            pts = [(q.pose.position.x, q.pose.position.y, 0.01) for q in msg.poses]
            rows.items.append(np.asarray(pts, dtype=np.float64).reshape(-1, 3))
            rows.lengths.append(1)
        elif topic == contract.goal_status(robot) and isinstance(msg, msgs.DiagnosticStatus):
            who = msg.hardware_id or robot
            text = f"{who}: goal {msg.name} {msg.message}"
            self._text(GOALS_LOG_ENTITY, t_ns, text, _GOAL_LEVELS.get(msg.level, "ERROR"))

    def _on_tf(self, msg: msgs.TFMessage, t_ns: int, *, static: bool) -> None:
        for tf in msg.transforms:
            child, parent = tf.child_frame_id, tf.header.frame_id
            if not child or not parent:
                continue
            self.tf_parents[child] = parent
            tr, q = tf.transform.translation, tf.transform.rotation
            xyz, quat = (tr.x, tr.y, tr.z), (q.x, q.y, q.z, q.w)
            if static:
                self.buffer.set_transform_static(tf, "view")
                self.tf_static[child] = (xyz, quat)
                continue
            self.buffer.set_transform(tf, "view")
            stamp = tf.header.stamp.ns or t_ns
            col = self.tf_dynamic.setdefault(child, Poses())
            col.times.append(stamp)
            col.translations.append(xyz)
            col.quaternions.append(quat)
            if child == contract.MARKER_FRAME:
                self._on_marker_frame(tf, stamp)

    def _on_marker_frame(self, tf: msgs.TransformStamped, stamp: int) -> None:
        """Look the broadcast up in ``map`` at its own stamp, as the mission's listener does."""
        try:
            in_map = self.buffer.lookup_transform(
                contract.MAP, contract.MARKER_FRAME, tf.header.stamp
            )
        except TransformException as err:
            text = f"{contract.MARKER_FRAME} not in {contract.MAP}: {err}"
            self._text(TF_LOG_ENTITY, stamp, text, "WARN")
            return
        p = in_map.transform.translation
        xyz = (p.x, p.y, p.z)
        label = contract.MARKER_FRAME
        if self.true_marker_xyz:
            mid, dist = min(
                ((k, math.dist(xyz, v)) for k, v in sorted(self.true_marker_xyz.items())),
                key=lambda kv: kv[1],
            )
            label = f"{contract.MARKER_FRAME} ~{mid}: {dist * 100:.1f} cm off"
        self._marker_frame_points.append(xyz)
        self._marker_frame_labels.append(label)
        pts = self._marker_frame_points[-MARKER_FRAME_HISTORY:]
        labels = self._marker_frame_labels[-MARKER_FRAME_HISTORY:]
        rows = self.marker_frame_rows
        rows.times.append(stamp)
        rows.items.extend(pts)
        rows.labels.extend(labels)
        rows.lengths.append(len(pts))

    def _on_image(self, img: msgs.CompressedImage, t_ns: int) -> None:
        im = self._images
        im.times.append(t_ns)
        im.blobs.append(img.data)
        im.media_types.append(media_type(img))
        self.pending_image_bytes += len(img.data)

    def _on_detections(self, found: list[_Found], t_ns: int) -> None:
        """Outline each detection by projecting its recorded pose through the camera's K.

        Why project rather than re-run ``detect.detect_with_corners``: it needs no image decode
        (PNG decode plus ArUco measured 6.4 ms a 640x480 frame: 30 s for a course log, six times
        the whole view), and it draws what the recorded detector *published* (its pose,
        reprojected), which is what the rest of the mission used, not what a re-detection with
        today's code would find. With the detector's own marker size and corner order the outline
        lands on the detected corners (within the published ``image_error``; the tests check it
        against a re-detection to 1.5 px). A detection with a zero quaternion (a broken log) or
        behind the camera is left out.
        """
        rows = self.detections
        rows.times.append(t_ns)
        n = 0
        if self.camera_info is not None and found:
            corners = marker_corners(self.marker_size)
            for mid, tr, q in found:
                quat = np.array([q.x, q.y, q.z, q.w], dtype=np.float64)
                if not np.all(np.isfinite(quat)) or not np.linalg.norm(quat) > 0.0:
                    continue
                rot = Rotation.from_quat(quat).as_matrix()
                pts = corners @ rot.T + np.array([tr.x, tr.y, tr.z])
                px = project(pts, self.camera_info)
                if px is None:
                    continue
                rows.items.append(np.vstack([px, px[:1]]))
                rows.labels.append(f"id {mid}")
                n += 1
        rows.lengths.append(n)

    def _on_true_markers(self, msg: msgs.FiducialTransformArray, t_ns: int) -> None:
        rows = self.true_markers
        rows.times.append(t_ns)
        for f in msg.transforms:
            tr = f.transform.translation
            self.true_marker_xyz[f.fiducial_id] = (tr.x, tr.y, tr.z)
            rows.items.append((tr.x, tr.y, tr.z))
            rows.labels.append(f"true {f.fiducial_id}")
        rows.lengths.append(len(msg.transforms))

    def _on_stored_markers(self, topic: str, msg: msgs.Message, t_ns: int) -> None:
        """The markers the mission stored, wherever it put them (a ``FiducialTransformArray``
        on ``/explorer/marker_poses``, a ``PoseArray``, a ``*marker*`` pose topic: see
        :mod:`usar_replay.grading.stored_markers`), all of them as one row each time."""
        if self._stored is None:  # the true markers are known by now (scenario or log, at t0)
            self._stored = StoredMarkers(sorted(self.true_marker_xyz.items()))
        self._stored.note(topic, msg)
        rows = self.stored_markers
        rows.times.append(t_ns)
        for mid, xyz in self._stored.by_id.items():
            rows.items.append(xyz)
            rows.labels.append(f"stored {mid}")
        rows.lengths.append(len(self._stored.by_id))

    def _on_truth(self, robot: str, msg: msgs.PoseStamped, t_ns: int) -> None:
        p, q = msg.pose.position, msg.pose.orientation
        poses = self.truth.setdefault(robot, Poses())
        poses.times.append(t_ns)
        poses.translations.append((p.x, p.y, p.z))
        poses.quaternions.append((q.x, q.y, q.z, q.w))
        path = self.paths.setdefault(robot, TruePath())
        here = (p.x, p.y, p.z + 0.01)
        if not path.kept or math.dist(path.kept[-1], here) >= PATH_MIN_STEP_M:
            path.kept.append(here)
        path.last = (t_ns, here)
        if path.last_row_ns is None or t_ns - path.last_row_ns >= PATH_ROW_PERIOD_NS:
            path.add_row(t_ns, here)

    def _scalar(self, entity: str, t_ns: int, value: float) -> None:
        times, values = self.scalars.setdefault(entity, ([], []))
        times.append(t_ns)
        values.append(value)

    def _text(self, entity: str, t_ns: int, text: str, level: str) -> None:
        col = self.texts.setdefault(entity, Texts())
        col.times.append(t_ns)
        col.texts.append(text)
        col.levels.append(level)

    def add_grade(self, report: GradeReport) -> None:
        """Each rubric line at the sim time of its evidence (the log's end when there is none)."""
        end = max(self.end_ns, report.start_ns)
        for c in report.checks:
            t = c.evidence_ns if c.evidence_ns is not None else end
            verdict = "PASS" if c.passed else "FAIL"
            self._text(
                GRADE_ENTITY,
                t,
                f"{verdict} {c.id}: {c.description} - measured {c.measured}, threshold "
                f"{c.threshold} ({c.points:g}/{c.max_points:g} points)",
                "INFO" if c.passed else "ERROR",
            )
        self._text(
            GRADE_ENTITY,
            end,
            f"grade: {report.points:g}/{report.max_points:g} points, "
            + ("every line passed" if report.passed else "some lines failed"),
            "INFO" if report.passed else "ERROR",
        )

    def add_note(self, text: str, level: str = "WARN") -> None:
        """A line of the viewer's own (e.g. the log is truncated) at the end of the log."""
        self._text(NOTES_ENTITY, self.end_ns, text, level)

    def take_images(self) -> ImageBatch:
        """The images fed since the last call (the caller sends them; memory stays bounded)."""
        batch, self._images = self._images, ImageBatch()
        self.pending_image_bytes = 0
        self.images_taken += len(batch.times)
        return batch

    def close(self) -> None:
        """The log is read: each true path gets its last row (where the robot ended)."""
        for path in self.paths.values():
            if path.last is not None and path.last[0] != path.last_row_ns:
                path.add_row(*path.last)

    # -- where things are -------------------------------------------------------------------------

    @property
    def frame_paths(self) -> dict[str, str]:
        """Entity path per tf frame, from the buffer's tree (and any frame it did not keep)."""
        return frame_entity_paths({**self.tf_parents, **self.buffer.frames()})

    def frame_path(self, frame: str) -> str:
        return self.frame_paths.get(frame) or frame_entity_path(self.tf_parents, frame)

    @property
    def pinhole_entity(self) -> str:
        """The camera's entity, fixed at first use (image batches may go out before the end)."""
        if self._pinhole_entity is None:
            self._pinhole_entity = self.frame_path(self.camera_frame) + "/pinhole"
        return self._pinhole_entity

    @property
    def image_entity(self) -> str:
        return self.pinhole_entity + "/image"

    @property
    def detections_entity(self) -> str:
        return self.pinhole_entity + "/detections"

    def robot_color(self, robot: str) -> tuple[int, int, int]:
        """The robot's colour in this run's assignment."""
        return robot_color(robot, self.assignment.robot_names)

    def base_frame(self, robot: str) -> str:
        """The robot's ``base_footprint`` frame: its assignment's name for it (``robot1/...``),
        the US&R naming for a robot the assignment does not name."""
        if robot in self.assignment.robot_names:
            return self.assignment.frames_of(robot).base
        return contract.base_frame(robot)

    def body_entities(self) -> dict[str, str]:
        """``{robot: entity}`` of each robot's body, under its ``base_footprint`` frame (every
        robot of the log or the assignment whose base frame is on tf)."""
        paths = self.frame_paths
        out: dict[str, str] = {}
        names = self.assignment.robot_names
        for robot in [*self.robots, *(r for r in names if r not in self.robots)]:
            base = paths.get(self.base_frame(robot))
            if base is not None:
                out[robot] = base + "/robot_body"
        return out

    def plotted_robots(self) -> list[str]:
        """Robots with a ``cmd_vel`` plot, in the order the robots became known."""
        return [r for r in self.robots if f"{PLOTS_ENTITY}/{r}/cmd_vel/linear_x" in self.scalars]
