"""The built-in ROS 2 final project mission, as nodes on the public node API (no back door).

The project (the course's ROS 2 edition, one Turtlebot3 ``robot1``), in the course's split:

* :class:`OdomUpdater` (the students' ``odom_updater`` package, node
  ``dynamic_tf2_frame_publisher``): the tf tree is broken at start; on every ``/robot1/odom`` it
  broadcasts ``robot1/odom -> robot1/base_footprint`` with the odometry's pose and stamp;
* :class:`ArucoNode` (ros2_aruco's ``aruco_node``): each camera frame with a marker in it ->
  ``/aruco_markers`` (``ros2_aruco_interfaces/msg/ArucoMarkers``, poses in the optical frame).
  In the project's world the course's detector runs on usar's side (trusted) and delivers
  ``/aruco_markers`` as an input: this node is then idle, so missions that start it keep
  working unchanged;
* :class:`TargetReacher`: drives to ``aruco_target`` (given in ``robot1/odom``, as the course's
  ``bot_controller`` took it), then rotates in place (``angular.z = 0.2``) until
  ``/aruco_markers`` has a marker; takes ``final_destination.aruco_<ID>`` in
  ``final_destination.frame_id``, broadcasts it as the frame ``final_destination``, looks it
  up in ``robot1/odom`` and drives there; then ``shutdown()``.

Driving uses the move_base-like :class:`~usar_replay.node.navigation.NavigateClient` (given
``robot1/base_footprint`` as the base frame) rather than a hand-written controller: it plans
around the room's obstacles, and it finds the robot through tf (``map -> robot1/odom ->
robot1/base_footprint``), so, as in the course, nothing moves until the tree is connected.

The three faulty variants in ``examples/ros2_final/`` subclass these nodes and override one
method each (:meth:`TargetReacher.destination_frame`, :meth:`TargetReacher.destination_for`).
"""

from __future__ import annotations

from usar_replay.core import contract, msgs
from usar_replay.core.rotations import quat_from_yaw
from usar_replay.core.settings import DetectorParams, from_mapping
from usar_replay.node.executor import shutdown
from usar_replay.node.navigation import NavigateClient, NavResult
from usar_replay.node.node import Node, Time, current_executor
from usar_replay.node.tf2 import Buffer, TransformBroadcaster, TransformException, TransformListener
from usar_replay.world.detect import aruco_markers, detect

__all__ = ["SEARCH_SPEED", "ArucoNode", "OdomUpdater", "TargetReacher", "main"]

ROBOT = contract.ROS2_ROBOT
SEARCH_SPEED = 0.2
"""rad/s: the project's ``angular.z`` while looking for the marker."""


class OdomUpdater(Node):
    """Connects the tf tree: ``robot1/odom -> robot1/base_footprint`` from ``/robot1/odom``."""

    def __init__(self) -> None:
        super().__init__("dynamic_tf2_frame_publisher")
        self.broadcaster = TransformBroadcaster(self)
        self.create_subscription(msgs.Odometry, contract.odom(ROBOT), self._on_odom)

    def _on_odom(self, msg: msgs.Odometry) -> None:
        p = msg.pose.pose
        self.broadcaster.sendTransform(
            msgs.TransformStamped(
                header=msgs.Header(stamp=msg.header.stamp, frame_id=contract.ROS2_ODOM_FRAME),
                child_frame_id=contract.ROS2_BASE_FRAME,
                transform=msgs.Transform(
                    translation=msgs.Vector3(x=p.position.x, y=p.position.y, z=p.position.z),
                    rotation=p.orientation,
                ),
            )
        )


class ArucoNode(Node):
    """ros2_aruco's ``aruco_node``: the markers in each camera frame, when there are any.

    ``topic``: where to publish. In the project's world the course's detector runs on usar's
    side (trusted: :mod:`usar_replay.pipeline.course_detector`) and delivers ``/aruco_markers``
    as an input: the node is then idle (it subscribes to nothing and publishes nothing), so a
    mission that starts it receives the course's detections, the same messages at the same
    place in each tick. To run a changed detector, publish on a topic of your own,
    ``ArucoNode(topic="/my_detector/aruco_markers")``: replay compares it, the rubric never
    counts it."""

    def __init__(self, topic: str = contract.ARUCO_MARKERS) -> None:
        super().__init__("aruco_node")
        group = {k: p.value for k, p in self.get_parameters_by_prefix("detector").items()}
        self.params = from_mapping(DetectorParams, group, "detector.")
        self.info: msgs.CameraInfo | None = None
        self.seq = 0
        self.idle = current_executor().provided_by_world(topic)
        if self.idle:
            return
        self.pub = self.create_publisher(msgs.ArucoMarkers, topic)
        self.create_subscription(msgs.CameraInfo, contract.ROS2_CAMERA_INFO, self._on_info)
        self.create_subscription(msgs.CompressedImage, contract.ROS2_IMAGE, self._on_image)

    def _on_info(self, msg: msgs.CameraInfo) -> None:
        self.info = msg

    def _on_image(self, msg: msgs.CompressedImage) -> None:
        if self.info is None:
            return
        found = detect(msg, self.info, self.params, self.seq)
        self.seq += 1
        if found.transforms:
            self.pub.publish(aruco_markers(found))


class TargetReacher(Node):
    """Goal 1 (``aruco_target``), the marker search, ``final_destination``, goal 2."""

    def __init__(self) -> None:
        super().__init__("target_reacher")
        self.aruco_target = (
            float(self.get_parameter("aruco_target.x").value),
            float(self.get_parameter("aruco_target.y").value),
        )
        self.frame_id = str(self.get_parameter("final_destination.frame_id").value)
        self.buffer = Buffer(cache_time=30.0)
        self.listener = TransformListener(self.buffer, self)
        self.broadcaster = TransformBroadcaster(self)
        self.cmd = self.create_publisher(msgs.Twist, contract.cmd_vel(ROBOT))
        self.nav = NavigateClient(
            self, ROBOT, buffer=self.buffer, base_frame=contract.ROS2_BASE_FRAME
        )
        self.create_subscription(msgs.ArucoMarkers, contract.ARUCO_MARKERS, self._on_markers)
        self.create_timer(0.1, self._on_timer)
        self.phase = "start"
        self.destination: tuple[float, float] | None = None

    # -- what the faulty examples change -------------------------------------------------------

    def destination_for(self, marker_id: int) -> tuple[float, float]:
        """``final_destination.aruco_<ID>`` (x, y)."""
        prefix = f"final_destination.aruco_{marker_id}"
        return (
            float(self.get_parameter(f"{prefix}.x").value),
            float(self.get_parameter(f"{prefix}.y").value),
        )

    def destination_frame(self) -> str:
        """The frame the destinations are given in: ``final_destination.frame_id``."""
        return self.frame_id

    # -- the phases ----------------------------------------------------------------------------

    def _goal(self, x: float, y: float) -> msgs.PoseStamped:
        return msgs.PoseStamped(
            header=msgs.Header(frame_id=contract.ROS2_ODOM_FRAME),
            pose=msgs.Pose(position=msgs.Point(x=x, y=y), orientation=quat_from_yaw(0.0)),
        )

    def _on_timer(self) -> None:
        if self.phase == "start":
            self.phase = "goal_1"
            self.nav.send_goal(
                self._goal(*self.aruco_target),
                self._at_target,
                name="aruco_target",
                ignore_yaw=True,
            )
        elif self.phase == "search":
            self.cmd.publish(msgs.Twist(angular=msgs.Vector3(z=SEARCH_SPEED)))
        elif self.phase in ("lookup", "goal_2"):
            self._broadcast()
            if self.phase == "lookup":
                self._lookup()

    def _at_target(self, result: NavResult) -> None:
        if not result.succeeded:
            self.get_logger().error(f"aruco_target not reached: {result.reason}")
            shutdown("aruco_target not reached")
            return
        self.get_logger().info("aruco_target reached: searching for the marker")
        self.phase = "search"

    def _on_markers(self, msg: msgs.ArucoMarkers) -> None:
        if self.phase != "search" or not msg.marker_ids:
            return
        self.cmd.publish(msgs.Twist())
        marker_id = int(msg.marker_ids[0])
        self.destination = self.destination_for(marker_id)
        self.get_logger().info(
            f"marker {marker_id}: final destination ({self.destination[0]:g}, "
            f"{self.destination[1]:g}) in {self.destination_frame()}"
        )
        self.phase = "lookup"
        self._broadcast()

    def _broadcast(self) -> None:
        assert self.destination is not None
        x, y = self.destination
        self.broadcaster.sendTransform(
            msgs.TransformStamped(
                header=msgs.Header(
                    stamp=self.get_clock().now().to_msg(), frame_id=self.destination_frame()
                ),
                child_frame_id=contract.FINAL_DESTINATION_FRAME,
                transform=msgs.Transform(translation=msgs.Vector3(x=x, y=y)),
            )
        )

    def _lookup(self) -> None:
        try:
            tf = self.buffer.lookup_transform(
                contract.ROS2_ODOM_FRAME, contract.FINAL_DESTINATION_FRAME, Time()
            )
        except TransformException as err:
            self.get_logger().warning(f"final_destination not yet in robot1/odom: {err}")
            return
        t = tf.transform.translation
        self.get_logger().info(f"final_destination in robot1/odom: ({t.x:.3f}, {t.y:.3f})")
        self.phase = "goal_2"
        self.nav.send_goal(
            self._goal(t.x, t.y), self._at_destination, name="final_destination", ignore_yaw=True
        )

    def _at_destination(self, result: NavResult) -> None:
        self.phase = "done"
        if result.succeeded:
            self.get_logger().info("final destination reached")
            shutdown("final destination reached")
        else:
            self.get_logger().error(f"final destination not reached: {result.reason}")
            shutdown("final destination not reached")


def main() -> None:
    """Create the project's nodes (``usar record --assignment ros2-final`` runs this)."""
    OdomUpdater()
    ArucoNode()
    TargetReacher()
