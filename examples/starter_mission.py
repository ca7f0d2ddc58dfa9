"""Starter mission for ENPM809Y "US&R Simplified": fill in the TODOs.

Run it:      usar record --mission examples/starter_mission.py --out runs/mine.mcap
Grade it:    usar grade runs/mine.mcap
Replay it:   usar replay --mission examples/starter_mission.py runs/mine.mcap

As it is, it runs without error and does nothing: the robots stay home, so every rubric line
fails (the run stops at the time limit; add ``--max-sim-time 20`` to stop sooner). The node
API is documented in docs/node-api.md (rclpy's and tf2_ros's calls, with the same names);
examples/minimal_mission.py is one way to fill this in, and examples/faulty/ holds the bugs
students of this course actually hit.
"""

# everything the TODOs need (some are unused until you fill them in)
from usar_replay.api import (  # noqa: F401
    Buffer,
    DiagnosticStatus,
    FiducialTransformArray,
    Header,
    NavigateClient,
    NavResult,
    Node,
    Point,
    Pose,
    PoseStamped,
    Time,
    TransformBroadcaster,
    TransformException,
    TransformListener,
    TransformStamped,
    Twist,
    Vector3,
    quat_from_yaw,
    shutdown,
)


def goal_in_map(x: float, y: float, yaw: float = 0.0) -> PoseStamped:
    """A navigation goal: goals are in the ``map`` frame (docs/node-api.md, "Navigation")."""
    pose = Pose(position=Point(x=x, y=y), orientation=quat_from_yaw(yaw))
    return PoseStamped(header=Header(frame_id="map"), pose=pose)


class Explorer(Node):
    """Visits target_1..N in order, finds and stores one marker at each, then goes home."""

    def __init__(self) -> None:
        super().__init__("explorer")
        # 5.1 Read the target locations from the parameter server (docs/node-api.md,
        # "Parameters"): aruco_lookup_locations/target_1 .. target_N, each [x, y].
        targets = self.get_parameters_by_prefix("aruco_lookup_locations")
        self.targets = [p.value for _, p in sorted(targets.items())]
        self.home = self.get_parameter("explorer.home").value  # [x, y, yaw]
        self.get_logger().info(f"{len(self.targets)} lookup targets: {self.targets}")

        # tf2 (docs/node-api.md, "tf2"): a buffer filled by a listener, and a broadcaster.
        self.buffer = Buffer()
        self.listener = TransformListener(self.buffer, self)
        self.broadcaster = TransformBroadcaster(self)
        # 5.2 move_base (docs/node-api.md, "Navigation"): send_goal(goal, done_callback).
        self.nav = NavigateClient(self, "explorer", buffer=self.buffer)
        self.cmd_vel = self.create_publisher(Twist, "/explorer/cmd_vel")
        self.marker_poses = self.create_publisher(FiducialTransformArray, "/explorer/marker_poses")
        self.create_subscription(FiducialTransformArray, "/fiducial_transforms", self.on_fiducials)
        self.create_timer(0.1, self.on_timer)  # sim time, 10 Hz (docs/node-api.md, "Timers")
        self.markers: dict[int, object] = {}  # marker ID -> pose in map

    def on_timer(self) -> None:
        # TODO 5.2: send the explorer to target_1 (then 2, 3, ...) with
        #   self.nav.send_goal(goal_in_map(x, y), self.on_target_reached, ignore_yaw=True)
        # TODO 5.3: once a target is reached, rotate slowly until a marker is detected:
        #   self.cmd_vel.publish(Twist(angular=Vector3(z=0.1)))
        #   (only while the navigator is idle: two publishers on one cmd_vel fight)
        # TODO 5.4: after the last marker, go home (self.home) and stay there.
        pass

    def on_target_reached(self, result: NavResult) -> None:
        # TODO: result.succeeded tells whether the goal was reached; start the search here.
        pass

    def on_fiducials(self, msg: FiducialTransformArray) -> None:
        # TODO 5.3.1 broadcaster: ONLY when msg.transforms is not empty, broadcast marker_frame
        #   as a child of msg.header.frame_id (explorer_tf/camera_rgb_optical_frame), stamped
        #   with msg.header.stamp (the image's stamp), transform = the detection's transform:
        #   self.broadcaster.sendTransform(TransformStamped(header=..., child_frame_id=...,
        #   transform=...)). Beware: a marker far away may belong to another target.
        # TODO 5.3.2 listener: look marker_frame up in map at that same stamp
        #   (self.buffer.lookup_transform("map", "marker_frame", Time.from_msg(stamp))), in a
        #   try/except TransformException, and store it by fiducial_id in self.markers;
        #   publish them on /explorer/marker_poses for the follower (docs/node-api.md, "tf2").
        pass


class Follower(Node):
    """After the explorer is home: visits the stored markers in ID order, then goes home."""

    def __init__(self) -> None:
        super().__init__("follower")
        self.home = self.get_parameter("follower.home").value
        self.nav = NavigateClient(self, "follower")
        self.markers: dict[int, object] = {}
        self.create_subscription(
            FiducialTransformArray, "/explorer/marker_poses", self.on_marker_poses
        )
        # the explorer's navigator reports each goal's outcome on /explorer/goal_status
        self.create_subscription(DiagnosticStatus, "/explorer/goal_status", self.on_explorer)

    def on_marker_poses(self, msg: FiducialTransformArray) -> None:
        # TODO: remember the markers' poses in map, by fiducial_id.
        pass

    def on_explorer(self, status: DiagnosticStatus) -> None:
        # TODO 6: when the explorer's "home" goal succeeded, visit the markers in ID order
        #   (0, 1, 2, ...). Markers are on walls: stop at a free point within 0.4 m of each,
        #   not at the marker itself. Then go home and end the mission with shutdown()
        #   (usar's rclpy.shutdown(): the run ends after this tick).
        pass


def main() -> None:
    """usar calls this to create the nodes, then runs them (docs/node-api.md, "Running")."""
    from usar_replay.missions.usar import ArucoDetect  # aruco_detect, as the course gives it

    ArucoDetect()
    Explorer()
    Follower()
