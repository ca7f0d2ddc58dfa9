"""ros1/publishing: the simulator's side of the graph. The tick's inputs decoded from CDR and
told to the bridge's tf buffer (move_base's poses) and camera state, the publishers made once
per topic; with nobody subscribed nothing is sent (rospy's publishers of Debian's ROS 1
packages, no master needed). What subscribers receive, and when: tests/ros1/test_record.py and
tests/ros1/test_bridge.py (recordings through a real graph)."""

from __future__ import annotations

import math
import sys

import pytest

from usar_replay.core import cdr, contract, msgs
from usar_replay.ros1.building import debian
from usar_replay.ros1.publishing import LATCHED, Publishing, genpy_time

# queue_size=None is the bridge's choice (synchronous publishing: the pacing needs it)
pytestmark = pytest.mark.filterwarnings("ignore:The publisher should be created")


@pytest.fixture(scope="module", autouse=True)
def _ros1() -> None:
    if str(debian.DIST_PACKAGES) not in sys.path:
        sys.path.append(str(debian.DIST_PACKAGES))
    pytest.importorskip("rospy")


def _odom_tf(x: float, sec: int) -> msgs.TFMessage:
    half = math.pi / 4  # a quarter turn
    return msgs.TFMessage(
        transforms=(
            msgs.TransformStamped(
                header=msgs.Header(stamp=msgs.Time(sec=sec), frame_id=contract.MAP),
                child_frame_id=contract.base_frame("explorer"),
                transform=msgs.Transform(
                    translation=msgs.Vector3(x=x, y=2.0),
                    rotation=msgs.Quaternion(z=math.sin(half), w=math.cos(half)),
                ),
            ),
        )
    )


def _item(topic: str, value: msgs.Message) -> tuple[str, str, bytes]:
    return topic, type(value).__msgtype__, cdr.encode(value)


def test_the_ticks_tf_is_where_move_base_finds_the_robot() -> None:
    out = Publishing({})
    assert out.pose("explorer", 0) is None  # before any tf
    out.publish_inputs([_item(contract.TF, _odom_tf(1.5, 1))])
    pose = out.pose("explorer", 1_000_000_000)
    assert pose is not None
    x, y, yaw = pose
    assert (x, y) == (1.5, 2.0)
    assert yaw == pytest.approx(math.pi / 2)
    assert out.in_map("no_such_frame") is None


def test_camera_info_is_kept_and_each_topic_has_one_publisher() -> None:
    out = Publishing({})
    info = msgs.CameraInfo(header=msgs.Header(frame_id="cam"), height=240, width=320)
    out.advertise([contract.CAMERA_INFO, contract.IMAGE, "/not_the_simulators"], ["explorer"])
    made = dict(out._pubs)
    assert set(made) == {
        contract.CAMERA_INFO,
        contract.IMAGE,
        contract.IMAGE.removesuffix("/compressed"),  # the raw frame, as Gazebo's plugin
        contract.amcl_pose("explorer"),  # amcl's stand-in's, latched as amcl's
    }
    out.publish_inputs([_item(contract.CAMERA_INFO, info)])  # nobody subscribed: not sent
    assert out.info == info
    assert out._pubs == made  # the same publishers, not new ones
    assert [topic for topic in made if topic in LATCHED] == [contract.amcl_pose("explorer")]


def test_clock_time_splits_into_seconds_and_nanoseconds() -> None:
    t = genpy_time(12_500_000_001)
    assert (t.secs, t.nsecs) == (12, 500_000_001)
