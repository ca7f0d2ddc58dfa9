"""core/ros1defs: a ROS 1 definition's shape checked in one pass, parsed once, within budgets.

The pathological definitions here are the red team's shapes (#33 point 5): each must be refused
before rosbags sees it, in milliseconds, where parsing it took seconds of the recorder's CPU.
"""

from __future__ import annotations

import struct
import time

import pytest

from usar_replay.core import ros1msg
from usar_replay.core.ros1defs import DefinitionLimits, DefinitionRefused, Definitions, shape

SEP = "=" * 80
ODOMETRY = f"""# This represents an estimate of a position and velocity in free space.
Header header
string child_frame_id
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
{SEP}
MSG: std_msgs/Header
uint32 seq
time stamp
string frame_id
{SEP}
MSG: geometry_msgs/PoseWithCovariance
Pose pose
float64[36] covariance
{SEP}
MSG: geometry_msgs/Pose
Point position
Quaternion orientation
{SEP}
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
{SEP}
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
{SEP}
MSG: geometry_msgs/TwistWithCovariance
Twist twist
float64[36] covariance
{SEP}
MSG: geometry_msgs/Twist
Vector3  linear
Vector3  angular
{SEP}
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""
"""A course type's full text, as a node's connection header carries it (written here by hand)."""


def _odometry_bytes() -> bytes:
    header = struct.pack("<III", 7, 1, 0) + struct.pack("<I", 3) + b"map"
    child = struct.pack("<I", 4) + b"base"
    pose = struct.pack("<7d", 1, 2, 0, 0, 0, 0, 1) + struct.pack("<36d", *[0.0] * 36)
    twist = struct.pack("<6d", 0.5, 0, 0, 0, 0, 0.1) + struct.pack("<36d", *[0.0] * 36)
    return header + child + pose + twist


def _fields(n: int) -> str:
    return "".join(f"int32 f{i}\n" for i in range(n))


def _chain(n: int) -> str:
    """T0 contains T1 contains ... T{n}."""
    body = "p/T1 a\n" + "".join(f"{SEP}\nMSG: p/T{i}\np/T{i + 1} a\nint32 b\n" for i in range(1, n))
    return body + f"{SEP}\nMSG: p/T{n}\nint32 z\n"


def test_a_course_type_passes_and_decodes() -> None:
    got = shape("nav_msgs/Odometry", ODOMETRY)
    assert (got.types, got.fields, got.depth) == (9, 25, 3)
    value = Definitions().decode("nav_msgs/Odometry", ODOMETRY, _odometry_bytes())
    assert value.header.frame_id == "map" and value.child_frame_id == "base"
    assert value.pose.pose.orientation.w == 1.0 and value.twist.twist.angular.z == 0.1


@pytest.mark.parametrize(
    ("definition", "why"),
    [
        # the red team's 259 KB definition: 16.7 s of parsing before; past the byte cap now
        (_fields(20_000), "is 248,890 bytes; a definition is at most 65,536"),
        # under the byte cap, over the fields (one type of 5,000 fields took ~3 s)
        (_fields(5_000), "holds more than 256 fields"),
        (_chain(200), "holds more than 64 types"),
        (_chain(40), "nests types more than 32 deep"),
        ("p/T1 a\n" + f"{SEP}\nMSG: p/T1\nT2 b\n{SEP}\nMSG: p/T2\np/T1 c\n", "contains itself"),
        ("p/T0[] again\n", "contains itself"),
    ],
)
def test_pathological_definitions_are_refused_before_parsing(definition: str, why: str) -> None:
    defs = Definitions()
    start = time.process_time()
    with pytest.raises(DefinitionRefused, match=why):
        defs.decode("p/T0", definition, b"")
    assert time.process_time() - start < 0.5  # a pass over 64 KiB at most: milliseconds
    assert defs.fields == 0  # nothing counted, nothing parsed


def test_each_definition_is_parsed_once() -> None:
    defs = Definitions()
    first = defs.store("nav_msgs/Odometry", ODOMETRY)
    again = defs.store("nav_msgs/Odometry", ODOMETRY.encode().decode())  # equal, not the same
    assert first is again and defs.fields == 25
    assert ros1msg.decode("nav_msgs/Odometry", ODOMETRY, _odometry_bytes(), defs).header.seq == 7


def test_a_runs_definitions_together_stay_within_its_budget() -> None:
    defs = Definitions(DefinitionLimits(run_fields=100))
    for i in range(2):
        defs.store(f"p/T{i}", _fields(40))
    with pytest.raises(DefinitionRefused, match="one too many: a run's ROS 1 definitions"):
        defs.store("p/T2", _fields(40))
    assert defs.fields == 80
    defs.store("p/T0", _fields(40))  # one already parsed costs nothing more


def test_a_definition_that_does_not_parse_still_counts() -> None:
    """A definition rosbags refuses was parsed all the same: it counts against the budget (a
    package cannot make the recorder parse broken text for free)."""
    defs = Definitions()
    with pytest.raises(Exception, match=r"."):
        defs.store("p/T0", "int32 a b c d\n???\n")
    assert defs.fields == 2
