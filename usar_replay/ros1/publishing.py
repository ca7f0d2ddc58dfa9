"""The bridge's publishing side: what the simulator (Gazebo, map_server, aruco_detect) publishes
into the ROS 1 graph, tick by tick, and ``/clock``.

The tick's inputs arrive as CDR from the recorder; each is decoded, told to the bridge's tf
buffer (``/tf``, ``/tf_static``: move_base's poses read it), given to move_base (``/map``), and
published in the order the tick brings them, the camera's raw ``sensor_msgs/Image`` right before
its compressed frame. ``/tf_static`` is republished whole (latched): a subscriber that connects
later gets every static frame, as from tf2's static broadcaster. ``/clock`` is published by the
tick loop (:mod:`.bridge`) when the pacing allows, never here on its own.

One job, apart from the tick loop: the pacing (:mod:`.pacing`) decides *when*, this *what*.
"""

from __future__ import annotations

from typing import Any

from usar_replay.core import cdr, contract, msgs
from usar_replay.core.rotations import yaw_from_quat
from usar_replay.core.tf_tree import BufferCore, TransformException
from usar_replay.world.nav import grid_from_msg

__all__ = ["LATCHED", "Publishing", "genpy_time"]

LATCHED = (contract.TF_STATIC, contract.MAP_TOPIC, *map(contract.amcl_pose, contract.ROBOTS))
"""Latched as Gazebo's, map_server's and amcl's ``amcl_pose`` are: a late subscriber still
gets the last one."""


def genpy_time(t_ns: int) -> Any:
    """``t_ns`` as rospy's time (``/clock``'s value)."""
    from usar_replay.ros1.convert import ros1_time

    return ros1_time(t_ns // 1_000_000_000, t_ns % 1_000_000_000)


class Publishing:
    """The simulator's publishers in the graph (rospy's, created once per topic) and the tf the
    simulator has told so far. rospy must be initialised (``rospy.init_node``) before
    :meth:`advertise_clock` and :meth:`advertise`."""

    def __init__(self, move_base: dict[str, Any]) -> None:
        self._pubs: dict[str, Any] = {}
        self._static: dict[str, msgs.TransformStamped] = {}
        self.buffer = BufferCore(cache_time=30.0)
        self.info: msgs.CameraInfo | None = None
        self.move_base = move_base
        """Each robot's move_base (:mod:`.move_base`), the bridge's: ``/map`` is its grid."""
        self.clock: Any = None

    # -- advertising ----------------------------------------------------------------------------

    def advertise_clock(self) -> None:
        """``/clock``'s publisher (without Nagle's delay: a node waits on it every tick)."""
        import rospy
        from rosgraph_msgs.msg import Clock

        self.clock = rospy.Publisher(contract.CLOCK, Clock, queue_size=None, tcp_nodelay=True)

    def advertise(self, sim_topics: list[str], robots: list[str]) -> None:
        """Every topic the simulator will publish, before the graph starts: its subscribers
        connect before the first ``/clock`` (:mod:`.pacing.graph_start`), not during the run."""
        kinds: dict[str, type[msgs.Message]] = {
            contract.TF: msgs.TFMessage,
            contract.TF_STATIC: msgs.TFMessage,
            contract.MAP_TOPIC: msgs.OccupancyGrid,
            contract.CAMERA_INFO: msgs.CameraInfo,
            contract.IMAGE: msgs.CompressedImage,
            contract.FIDUCIALS: msgs.FiducialTransformArray,
            **{contract.odom(r): msgs.Odometry for r in robots},
        }
        for topic in sim_topics:
            if topic in kinds:
                self._publisher(topic, kinds[topic].__msgtype__)
        if contract.IMAGE in sim_topics:
            self._raw_publisher()
        for robot in robots:  # amcl's, usar's stand-in's (:mod:`.amcl`)
            self._publisher(contract.amcl_pose(robot), msgs.PoseWithCovarianceStamped.__msgtype__)

    def _publisher(self, topic: str, msgtype: str) -> Any:
        pub = self._pubs.get(topic)
        if pub is None:
            import rospy

            from usar_replay.ros1.convert import ros1_class

            pub = rospy.Publisher(
                topic, ros1_class(msgtype), queue_size=None, latch=topic in LATCHED
            )
            self._pubs[topic] = pub
        return pub

    def _raw_publisher(self) -> Any:
        topic = contract.IMAGE.removesuffix("/compressed")
        pub = self._pubs.get(topic)
        if pub is None:
            import rospy
            from sensor_msgs.msg import Image

            pub = self._pubs[topic] = rospy.Publisher(topic, Image, queue_size=None)
        return pub

    # -- one tick -------------------------------------------------------------------------------

    def publish_inputs(self, items: list[tuple[str, str, bytes]]) -> None:
        """The tick's inputs (topic, type, CDR), in their order: told to the tf buffer and
        move_base, then published."""
        for topic, msgtype, data in items:
            if not self._needed(topic, msgtype):
                continue
            value = cdr.decode(data, msgtype)
            if topic == contract.TF_STATIC and isinstance(value, msgs.TFMessage):
                for tf in value.transforms:
                    self.buffer.set_transform_static(tf, "sim")
                    self._static[tf.child_frame_id] = tf
                value = msgs.TFMessage(transforms=tuple(self._static.values()))
            elif topic == contract.TF and isinstance(value, msgs.TFMessage):
                for tf in value.transforms:
                    self.buffer.set_transform(tf, "sim")
            elif topic == contract.MAP_TOPIC and isinstance(value, msgs.OccupancyGrid):
                grid = grid_from_msg(value)
                for mb in self.move_base.values():
                    mb.grid = grid
            elif isinstance(value, msgs.CameraInfo):
                self.info = value
            elif isinstance(value, msgs.CompressedImage) and self.info is not None:
                self._raw_image(value)
            # the course's /fiducial_transforms comes in the tick, right after its frame
            self._publish(topic, value)

    def _needed(self, topic: str, msgtype: str) -> bool:
        """Whether an input is worth decoding: the bridge's tf, move_base's map and the camera's
        calibration always are; anything else only while someone subscribes to it (or its raw
        twin) or it is latched. Decoding the rest every tick was a tenth of the bridge's own
        work; its publisher is still made, so the master knows it from the first tick."""
        if topic in (contract.TF, contract.TF_STATIC, contract.MAP_TOPIC):
            return True
        if msgtype == msgs.CameraInfo.__msgtype__:
            return True
        if topic in LATCHED or self._publisher(topic, msgtype).get_num_connections() > 0:
            return True
        return msgtype == msgs.CompressedImage.__msgtype__ and (
            self._raw_publisher().get_num_connections() > 0
        )

    def publish_own(self, topic: str, value: msgs.Message) -> None:
        """A message of usar's stand-ins (amcl's ``amcl_pose``), published as the simulator's."""
        self._publish(topic, value)

    def publish_clock(self, t_ns: int) -> None:
        """``/clock`` at ``t_ns`` (the tick loop's call: when the pacing allows)."""
        from rosgraph_msgs.msg import Clock

        self.clock.publish(Clock(clock=genpy_time(t_ns)))

    def _publish(self, topic: str, value: msgs.Message) -> None:
        pub = self._publisher(topic, type(value).__msgtype__)
        if pub.get_num_connections() == 0 and topic not in LATCHED:
            return
        from usar_replay.ros1.convert import to_ros1

        pub.publish(to_ros1(value))

    def _raw_image(self, image: msgs.CompressedImage) -> None:
        """The frame as Gazebo's camera plugin publishes it: ``sensor_msgs/Image`` rgb8."""
        pub = self._raw_publisher()
        if pub.get_num_connections() == 0:
            return
        import cv2
        import numpy as np
        from sensor_msgs.msg import Image

        from usar_replay.ros1.convert import to_ros1

        bgr = cv2.imdecode(np.frombuffer(image.data, np.uint8), cv2.IMREAD_COLOR)
        if bgr is None:
            return
        out = Image()
        out.header = to_ros1(image.header)
        out.height, out.width = int(bgr.shape[0]), int(bgr.shape[1])
        out.encoding, out.is_bigendian, out.step = "rgb8", 0, int(bgr.shape[1]) * 3
        out.data = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB).tobytes()
        pub.publish(out)

    # -- where the robots are, as the simulator's tf says -----------------------------------------

    def pose(self, robot: str, t_ns: int) -> tuple[float, float, float] | None:
        """``robot``'s (x, y, yaw) in the map at ``t_ns`` (None before its tf arrived)."""
        return self.in_map(contract.base_frame(robot), t_ns)

    def in_map(self, frame: str, t_ns: int = 0) -> tuple[float, float, float] | None:
        """``frame``'s (x, y, yaw) in the map (None while tf cannot say)."""
        try:
            tf = self.buffer.lookup_transform(contract.MAP, frame, t_ns)
        except TransformException:
            return None
        tr = tf.transform.translation
        return (tr.x, tr.y, yaw_from_quat(tf.transform.rotation))
