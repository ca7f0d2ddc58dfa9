"""A faulty mission: the listener looks marker_frame up at time zero ("latest"), and the
broadcast is stamped "now" in the timer loop instead of with the image's stamp.

The bug: the assignment's own snippets stamp the broadcast with ``ros::Time::now()`` and look it
up at ``ros::Time(0)``. The detection comes from an older camera frame than "now": while the
robot rotates, the camera has turned since that frame, so the stored pose lags (by the angle
turned in one loop period times the marker's distance: about 1 cm at 0.1 rad/s, 10 Hz, 1 m).
The correct listener looks up at the image's stamp (``Time.from_msg(msg.header.stamp)``), with
the broadcast stamped with that same stamp.

Derived from examples/minimal_mission.py; the bug is marked ``# BUG:``.
"""

import math

from usar_replay.api import (
    Buffer,
    DiagnosticStatus,
    FiducialTransform,
    FiducialTransformArray,
    Header,
    NavigateClient,
    Node,
    Point,
    Pose,
    PoseStamped,
    Time,
    Transform,
    TransformBroadcaster,
    TransformException,
    TransformListener,
    TransformStamped,
    Twist,
    Vector3,
    quat_from_yaw,
    shutdown,
)


def goal(x: float, y: float, yaw: float = 0.0) -> PoseStamped:
    pose = Pose(position=Point(x=x, y=y), orientation=quat_from_yaw(yaw))
    return PoseStamped(header=Header(frame_id="map"), pose=pose)


class Explorer(Node):
    def __init__(self) -> None:
        super().__init__("explorer")
        targets = self.get_parameters_by_prefix("aruco_lookup_locations")
        self.targets = [p.value for _, p in sorted(targets.items())]
        self.buffer = Buffer()
        TransformListener(self.buffer, self)
        self.tf = TransformBroadcaster(self)
        self.nav = NavigateClient(self, "explorer", buffer=self.buffer)
        self.cmd = self.create_publisher(Twist, "/explorer/cmd_vel")
        self.out = self.create_publisher(FiducialTransformArray, "/explorer/marker_poses")
        self.create_subscription(FiducialTransformArray, "/fiducial_transforms", self.on_markers)
        self.create_timer(0.1, self.on_timer)
        self.k, self.spinning, self.seen, self.found = -1, False, None, {}

    def next_target(self, _result: object = None) -> None:
        self.k += 1
        if self.k < len(self.targets):
            self.nav.send_goal(goal(*self.targets[self.k]), self.arrived, ignore_yaw=True)
        else:
            self.nav.send_goal(goal(*self.get_parameter("explorer.home").value), name="home")

    def arrived(self, _result: object) -> None:
        self.spinning = True

    def on_markers(self, msg: FiducialTransformArray) -> None:
        for f in msg.transforms:
            t = f.transform.translation
            if self.spinning and f.fiducial_id not in self.found and math.hypot(t.x, t.z) < 2.5:
                self.seen = (f.fiducial_id, f.transform)  # broadcast later, in the loop

    def on_timer(self) -> None:
        if self.k < 0:
            return self.next_target()
        if self.seen is not None:
            marker_id, transform = self.seen
            # BUG: stamped "now" (this loop's time), not with the image's stamp: the detection
            # is from an earlier frame, when the camera was turned less far
            now = self.get_clock().now().to_msg()
            header = Header(stamp=now, frame_id="explorer_tf/camera_rgb_optical_frame")
            child = TransformStamped(
                header=header, child_frame_id="marker_frame", transform=transform
            )
            self.tf.sendTransform(child)
            try:
                # BUG: Time() is "latest", not the image's stamp
                p = self.buffer.lookup_transform("map", "marker_frame", Time())
            except TransformException as err:
                return self.get_logger().warning(f"lookup failed: {err}")
            self.store(marker_id, p.transform)
            return self.next_target()
        if self.spinning:
            self.cmd.publish(Twist(angular=Vector3(z=0.1)))

    def store(self, marker_id: int, pose: Transform) -> None:
        self.found[marker_id] = pose
        self.spinning, self.seen = False, None
        self.cmd.publish(Twist())
        now = self.get_clock().now().to_msg()
        stored = sorted(self.found.items())
        markers = tuple(FiducialTransform(fiducial_id=i, transform=t) for i, t in stored)
        header = Header(stamp=now, frame_id="map")
        self.out.publish(FiducialTransformArray(header=header, transforms=markers))


class Follower(Node):
    def __init__(self) -> None:
        super().__init__("follower")
        targets = self.get_parameters_by_prefix("aruco_lookup_locations")
        self.targets = [p.value for p in targets.values()]
        self.nav = NavigateClient(self, "follower")
        self.markers, self.queue = {}, None
        self.create_subscription(FiducialTransformArray, "/explorer/marker_poses", self.on_markers)
        self.create_subscription(DiagnosticStatus, "/explorer/goal_status", self.on_explorer)

    def on_markers(self, msg: FiducialTransformArray) -> None:
        self.markers = {f.fiducial_id: f.transform.translation for f in msg.transforms}

    def on_explorer(self, status: DiagnosticStatus) -> None:
        if status.name == "home" and self.queue is None:
            self.queue = sorted(self.markers)  # visit the markers in ID order
            self.visit()

    def visit(self, _result: object = None) -> None:
        if not self.queue:
            home = self.get_parameter("follower.home").value
            return self.nav.send_goal(goal(*home), lambda _r: shutdown(), name="home")
        m = self.markers[self.queue.pop(0)]  # stop 0.3 m from it, toward its nearest target
        tx, ty = min(self.targets, key=lambda t: math.hypot(t[0] - m.x, t[1] - m.y))
        d = math.hypot(tx - m.x, ty - m.y)
        x, y = m.x + 0.3 * (tx - m.x) / d, m.y + 0.3 * (ty - m.y) / d
        self.nav.send_goal(goal(x, y, math.atan2(m.y - y, m.x - x)), self.visit)


def main() -> None:
    from usar_replay.missions.usar import ArucoDetect  # the course's detector node, kept as is

    ArucoDetect()
    Explorer()
    Follower()
