"""Red team (issue #21, points 2-4): a student who wants the points without doing the work.

Each attack is a tiny mission (inline below), recorded with ``usar record`` for a sim-second or
two in the one-room world with the explorer facing away from the marker (the course's detector
never sees it). Every test asserts the verdict (the log's outcome and the exit code), that the
recorder did not crash (no traceback of usar's, a closed log that grades), and that the attack
earned nothing. The world-key attack (deriving a seeded world from installed code) is pure.
"""

from __future__ import annotations

import dataclasses
import math
import textwrap
from pathlib import Path

import pytest
from clitools import usar
from conftest import one_room

from usar_replay.core import contract, msgs
from usar_replay.grading.grade import grade_file
from usar_replay.grading.usar import Grader, judge
from usar_replay.log.run import open_run
from usar_replay.world.scenario import RobotStart, course_world
from usar_replay.world.scenario_toml import to_toml
from usar_replay.world.variants import make_variant
from usar_replay.world.world_key import ENV_VAR, WorldKey, key_from_env

EXIT_MISSION = 4
HEADER = """
import gc, math, multiprocessing.connection, os, struct
from usar_replay.api import *

class Attack(Node):
    def __init__(self):
        super().__init__("attack")
        self.tf = TransformBroadcaster(self)
        self.ticks = 0
        self.create_subscription(Odometry, "/explorer/odom", self.on_odom)

    def on_odom(self, msg):
        self.ticks += 1
        if self.ticks == 3:
            self.attack(msg)

def main():
    Attack()
"""
"""Every attack mission: a node whose ``attack`` runs once, at the third tick."""


def _away_room_toml(tmp_path: Path) -> Path:
    room = dataclasses.replace(
        one_room(), explorer=RobotStart(name="explorer", x=-1.2, y=0.6, yaw=math.pi)
    )
    path = tmp_path / "room.toml"
    path.write_text(to_toml(room))
    return path


def _attack(tmp_path: Path, body: str, *, sim_s: float = 1.0) -> tuple[int, str, Path]:
    """Record the mission whose ``Attack.attack(self, msg)`` is ``body``: (exit code, the
    mission's verdict as usar printed it, the log)."""
    mission = tmp_path / "attack.py"
    method = textwrap.indent(textwrap.dedent(body), "    ")
    mission.write_text(f"{HEADER}\n\ndef attack(self, msg):\n{method}\n\nAttack.attack = attack\n")
    out = tmp_path / "attack.mcap"
    done = usar(
        "record",
        "--scenario",
        str(_away_room_toml(tmp_path)),
        "--mission",
        str(mission),
        "--max-sim-time",
        str(sim_s),
        "--quiet",
        "--out",
        str(out),
    )
    # the recorder itself never crashed: no traceback from usar's own code
    assert "usar_replay/pipeline" not in done.stderr and "usar_replay/log" not in done.stderr
    assert out.exists(), done.stderr
    return done.returncode, done.stdout + done.stderr, out


def _refused(code: int, shown: str, log: Path, *needles: str) -> None:
    """The run ended ``refused`` (exit 4), the reason names ``needles``, the log is closed and
    grades, and the attack earned no detection or broadcast line."""
    run = open_run(log)
    assert code == EXIT_MISSION, shown
    assert run.file_state == "complete" and run.outcome == "refused", (run.outcome, shown)
    for needle in needles:
        assert needle in run.outcome_reason, run.outcome_reason
    _earned_nothing(log)


def _earned_nothing(log: Path) -> None:
    lines = {c.id: c for c in grade_file(log).checks}
    for line in ("marker_0.detected", "marker_0.broadcast"):
        assert not lines[line].passed and lines[line].points == 0.0, lines[line]


# --- forging the evidence -----------------------------------------------------------------------


def test_forged_detections_are_refused_and_never_graded(tmp_path: Path) -> None:
    code, shown, log = _attack(
        tmp_path,
        """
        fake = FiducialTransform(fiducial_id=0, transform=Transform(
            translation=Vector3(x=0.0, y=0.0, z=1.0), rotation=Quaternion(w=1.0)))
        pub = self.create_publisher(FiducialTransformArray, "/fiducial_transforms")
        pub.publish(FiducialTransformArray(header=msg.header, transforms=(fake,)))
        """,
    )
    _refused(code, shown, log, "/fiducial_transforms", "course's detector")


def test_marker_frame_without_a_detection_earns_no_marker_line(tmp_path: Path) -> None:
    """The issue's 60/60 attack: the mission knows where the marker is (it read the scenario,
    or another process's memory), turns the course's detector off and broadcasts a perfect
    ``marker_frame`` on every tick. Nothing is refused; nothing is earned."""
    marker = one_room().markers[0]
    code, shown, log = _attack(
        tmp_path,
        f"""
        self.create_publisher(Bool, "/aruco_detect/enable_detections").publish(Bool(data=False))
        self.create_timer(0.05, lambda: self.tf.sendTransform(TransformStamped(
            header=Header(stamp=self.get_clock().now().to_msg(), frame_id="map"),
            child_frame_id="marker_frame",
            transform=Transform(translation=Vector3(x={marker.x}, y={marker.y}, z={marker.z}),
                                rotation=Quaternion(w=1.0)))))
        """,
        sim_s=2.0,
    )
    run = open_run(log)
    assert code == 1 and run.outcome == "max_sim_time", shown
    broadcasts = [
        t
        for m in run.messages([contract.TF])
        if m.publisher == "mission" and isinstance(m.msg, msgs.TFMessage)
        for t in m.msg.transforms
    ]
    assert len(broadcasts) >= 10  # the forged frames are in the log ...
    lines = {c.id: c for c in grade_file(log).checks}
    for line in ("marker_0.detected", "marker_0.broadcast", "marker_frame.only_on_detection"):
        assert not lines[line].passed and lines[line].points == 0.0, lines[line]  # ... unpaid
    measured = lines["marker_0.broadcast"].measured
    assert measured == "no broadcast within 2 s after a detection of marker 0"


# --- non-finite values ----------------------------------------------------------------------------


def test_an_infinite_marker_frame_is_refused_at_the_call(tmp_path: Path) -> None:
    code, shown, log = _attack(
        tmp_path,
        """
        self.tf.sendTransform(TransformStamped(
            header=Header(stamp=msg.header.stamp, frame_id="explorer_tf/camera_rgb_optical_frame"),
            child_frame_id="marker_frame",
            transform=Transform(translation=Vector3(x=math.inf), rotation=Quaternion(w=1.0))))
        """,
    )
    _refused(code, shown, log, "translation.x = inf")
    assert "sendTransform" in shown or "attack" in shown  # the user's own line is shown


def test_a_nan_cmd_vel_is_refused_and_never_reaches_the_physics(tmp_path: Path) -> None:
    code, shown, log = _attack(
        tmp_path,
        """
        pub = self.create_publisher(Twist, "/explorer/cmd_vel")
        pub.publish(Twist(linear=Vector3(x=math.nan)))
        """,
    )
    _refused(code, shown, log, "/explorer/cmd_vel", "linear.x = nan")
    truth = [
        m.msg.pose.position
        for m in open_run(log).messages([contract.truth_pose("explorer")])
        if isinstance(m.msg, msgs.PoseStamped)
    ]
    assert truth and all(math.isfinite(p.x) and math.isfinite(p.y) for p in truth)


def _observed_marker_run() -> Grader:
    """A grader that saw the explorer's camera at the origin of ``map`` (identity chain)."""
    g = Grader(one_room())
    chain = [
        msgs.TransformStamped(
            header=msgs.Header(frame_id=parent),
            child_frame_id=child,
            transform=msgs.Transform(rotation=msgs.Quaternion(w=1.0)),
        )
        for parent, child in (
            (contract.MAP, contract.odom_frame("explorer")),
            (contract.odom_frame("explorer"), contract.base_frame("explorer")),
            (contract.base_frame("explorer"), contract.OPTICAL_FRAME),
        )
    ]
    g.feed(contract.TF_STATIC, msgs.TFMessage(transforms=tuple(chain)), 10**9)
    return g


@pytest.mark.parametrize("bad", [math.inf, -math.inf, math.nan])
def test_non_finite_detection_and_marker_frame_fail_the_rubric(bad: float) -> None:
    """Whatever reaches a log (a modified recorder, an edited file), a non-finite measurement
    fails: the issue's "worst error -100.0 cm" passed 40/60."""
    g = _observed_marker_run()
    stamp = msgs.Time.from_ns(2 * 10**9)
    weird = msgs.Transform(translation=msgs.Vector3(x=bad, y=0.4, z=0.3))
    detection = msgs.FiducialTransform(fiducial_id=0, transform=weird)
    g.feed(
        contract.FIDUCIALS,
        msgs.FiducialTransformArray(
            header=msgs.Header(stamp=stamp, frame_id=contract.OPTICAL_FRAME),
            transforms=(detection,),
        ),
        2 * 10**9,
    )
    frame = msgs.TransformStamped(
        header=msgs.Header(stamp=stamp, frame_id=contract.OPTICAL_FRAME),
        child_frame_id=contract.MARKER_FRAME,
        transform=weird,
    )
    g.feed(contract.TF, msgs.TFMessage(transforms=(frame,)), 2 * 10**9)
    lines = {c.id: c for c in judge(g)}
    assert not lines["marker_0.detected"].passed
    assert not lines["marker_0.broadcast"].passed
    assert "-100.0" not in lines["marker_0.broadcast"].measured
    assert sum(c.points for c in lines.values() if c.id.startswith("marker")) == 0.0


# --- floods, sizes, types, garbage -------------------------------------------------------------


def test_a_150_mb_message_is_refused(tmp_path: Path) -> None:
    code, shown, log = _attack(
        tmp_path,
        """
        self.create_publisher(String, "/big").publish(String(data="x" * 150_000_000))
        """,
    )
    _refused(code, shown, log, "/big", "8 MiB")


def test_500k_rosout_lines_in_one_tick_are_refused(tmp_path: Path) -> None:
    code, shown, log = _attack(
        tmp_path,
        """
        for i in range(500_000):
            self.get_logger().info(f"line {i}")
        """,
    )
    _refused(code, shown, log, "/rosout", "10000 messages")
    lines = [m for m in open_run(log).messages([contract.ROSOUT]) if m.publisher == "mission"]
    assert len(lines) < 100  # nothing of the flood was written


def test_one_topic_with_two_types_is_refused_not_a_crash(tmp_path: Path) -> None:
    code, shown, log = _attack(
        tmp_path,
        """
        self.create_publisher(String, "/shared").publish(String(data="a"))
        self.create_publisher(Bool, "/shared").publish(Bool(data=True))
        """,
    )
    _refused(code, shown, log, "/shared", "one topic, one type")


# a modified mission process: usar's node API bypassed, bytes written to the socket itself
_CONN = (
    "conn = next(o for o in gc.get_objects() if type(o) is multiprocessing.connection.Connection)\n"
)


@pytest.mark.parametrize(
    ("write", "reason"),
    [
        ('conn.send_bytes(b"O" + b"\\xff" * 21)', "malformed frame"),
        ('conn.send_bytes(b"Z")', "unknown kind"),
        ('os.write(conn.fileno(), struct.pack("!i", 150_000_000) + b"x" * 64)', "bytes in one"),
        (
            't, m = b"/cmd_vel", b"geometry_msgs/msg/Twist"\n'
            'conn.send_bytes(b"O" + struct.pack("<qI", 0, 1) + b"\\0"'
            ' + struct.pack("<HHI", len(t), len(m), 3) + t + m + b"abc")',
            "do not decode",
        ),
    ],
    ids=["garbage", "unknown-kind", "150MB-header", "undecodable"],
)
def test_garbage_across_the_boundary_is_refused(tmp_path: Path, write: str, reason: str) -> None:
    code, shown, log = _attack(tmp_path, _CONN + write + "\n")
    _refused(code, shown, log, reason)


# --- hidden worlds --------------------------------------------------------------------------------


def test_a_keyed_world_cannot_be_derived_from_installed_code(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The attack: the mission's lookup targets are its parameters; try every seed of the
    installed variant generator until they match. With a key, no seed matches."""
    base = course_world()
    key = WorldKey(b"0123456789abcdef-instructor-only")
    graded = make_variant(base, 3, key)
    assert graded == make_variant(base, 3, key)  # the instructor gets it again, exactly
    for seed in range(4):
        assert make_variant(base, seed).targets != graded.targets
    # the log records the key's digest, never the key; no key: the world and its file as before
    toml = to_toml(graded)
    assert key.digest in toml and "instructor-only" not in toml and key.digest not in repr(key)
    assert graded.world_key == key.digest and make_variant(base, 3).world_key == ""
    assert "world_key" not in to_toml(make_variant(base, 3))
    monkeypatch.setenv(ENV_VAR, "0123456789abcdef-instructor-only")
    found = key_from_env()
    assert found is not None and found.digest == key.digest
    monkeypatch.setenv(ENV_VAR, "")
    assert key_from_env() is None
