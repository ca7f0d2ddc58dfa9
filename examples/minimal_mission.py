"""A minimal US&R mission on usar's node API: `usar record --mission examples/minimal_mission.py`."""

import math

from usar_replay.api import (
    Buffer, DiagnosticStatus, FiducialTransform, FiducialTransformArray, Header, NavigateClient, Node, Point, Pose, PoseStamped, Time,
    TransformBroadcaster, TransformException, TransformListener, TransformStamped, Twist, Vector3,
    quat_from_yaw, shutdown,
)


def goal(x: float, y: float, yaw: float = 0.0) -> PoseStamped:
    position, orientation = Point(x=x, y=y), quat_from_yaw(yaw)
    return PoseStamped(header=Header(frame_id="map"), pose=Pose(position=position, orientation=orientation))


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
                child = TransformStamped(header=msg.header, child_frame_id="marker_frame", transform=f.transform)
                self.tf.sendTransform(child)  # the listener gets it after this callback
                self.seen = (f.fiducial_id, msg.header.stamp)

    def on_timer(self) -> None:
        if self.k < 0:
            return self.next_target()
        if self.seen is not None:
            marker_id, stamp = self.seen
            try:
                p = self.buffer.lookup_transform("map", "marker_frame", Time.from_msg(stamp)).transform
            except TransformException as err:
                return self.get_logger().warning(f"lookup failed: {err}")
            self.found[marker_id] = p
            self.spinning, self.seen = False, None
            self.cmd.publish(Twist())
            stamp_now = self.get_clock().now().to_msg()
            self.out.publish(FiducialTransformArray(header=Header(stamp=stamp_now, frame_id="map"), transforms=tuple(
                FiducialTransform(fiducial_id=i, transform=t) for i, t in sorted(self.found.items()))))
            return self.next_target()
        if self.spinning:
            self.cmd.publish(Twist(angular=Vector3(z=0.1)))


class Follower(Node):
    def __init__(self) -> None:
        super().__init__("follower")
        self.targets = [p.value for p in self.get_parameters_by_prefix("aruco_lookup_locations").values()]
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
