"""Red team, issue 26's leaks and lies: what a mission may see, print and be called.

- 9: a mission kept next to the grader's files (world, world key, settings, the output, and a
  hard link and a symlink to a world kept elsewhere) reads none of them, and still imports its
  own helper module.
- 10: a mission's crash text and log lines full of terminal escape sequences reach the
  terminal with every control character escaped (``usar record``, ``usar log``, ``usar info``).
- 11: a process killed by SIGKILL is ``crashed (signal 9)``, not ``out_of_memory`` (a Python
  mission here; the ROS 1 bridge killed by its own node in :mod:`test_ros1`'s way below).
- 12: in the ROS 2 final project a mission that forges ``/aruco_markers`` (the true ID at a
  true-looking pose, the other IDs anywhere) gains nothing: its messages are renamed
  ``/mission/aruco_markers`` and never graded; sent past the node API under the trusted name
  they are refused. An honest older mission that starts its own ``aruco_node`` still runs and
  gets the built-in mission's grade, line for line.

Needs bubblewrap (CI installs it): skipped only where it is missing or cannot make namespaces.
"""

from __future__ import annotations

import dataclasses
import os
import re
import shutil
import textwrap
from pathlib import Path

import pytest
from clitools import usar
from conftest import one_room

from usar_replay.cli.main import main
from usar_replay.core import contract, msgs
from usar_replay.core.settings import RunSettings
from usar_replay.grading.grade import GradeReport, grade_file
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult, record
from usar_replay.pipeline.replay import replay
from usar_replay.ros1.building import debian
from usar_replay.sandbox.kernel_sandbox import bwrap_available
from usar_replay.world.ros2_world import ros2_final_world
from usar_replay.world.scenario import Scenario
from usar_replay.world.scenario_toml import save

_OK, _WHY = bwrap_available()
pytestmark = pytest.mark.skipif(not _OK, reason=f"no kernel sandbox here: {_WHY}")

SECRET = "SECRET-7f3a"


def _world(path: Path) -> Path:
    save(one_room(), path)
    path.write_text(path.read_text() + f"\n# {SECRET} world {path.name}\n")
    return path


def _record(folder: Path, source: str, *options: str, out: Path | None = None) -> tuple[int, Path]:
    mission = folder / "mission.py"
    mission.write_text(textwrap.dedent(source))
    out = out or folder / "run.mcap"
    args = ["record", "--mission", str(mission), "--max-sim-time", "1", "--out", str(out)]
    return main([*args, "--quiet", *options]), out


READER = """
    import os
    import helper  # its own module, next to it: still importable

    def main():
        said = [helper.NAME]
        for name in {names!r}:
            try:
                with open(name, "rb") as f:
                    data = f.read()
                seen = "secret" if b"{secret}" in data else "plain"
                said.append(f"{{os.path.basename(name)}}=read:{{seen}}")
            except OSError as err:
                said.append(f"{{os.path.basename(name)}}=refused:{{type(err).__name__}}")
        raise RuntimeError("READ " + " | ".join(said))
"""


def test_grader_files_beside_the_mission_stay_unread(tmp_path: Path) -> None:
    """Point 9: the world, world key, settings and output next to the mission, a hard link and
    a symlink to a world kept elsewhere, and the log being written: none is readable (an empty
    file or no file); the mission's own module is."""
    team = tmp_path / "team"
    team.mkdir()
    (team / "helper.py").write_text("NAME = 'helper-ok'\n")
    world = _world(team / "world.toml")
    key = team / "world.key"
    key.write_text(f"{SECRET}-key-0123456789abcdef0123456789abcdef\n")
    settings = team / "settings.toml"
    settings.write_text(f"# {SECRET} settings\n[mission]\n")
    elsewhere = _world(tmp_path / "elsewhere.toml")  # --scenario of the second run
    os.link(elsewhere, team / "hardlink.toml")
    (team / "symlink.toml").symlink_to(elsewhere)
    old = team / "old.mcap"  # a previous output, overwritten by this run
    old.write_text(f"{SECRET} previous log\n")
    names = [str(p) for p in (world, key, settings, old, team / "old.mcap.part")]
    names += [str(team / "hardlink.toml"), str(team / "symlink.toml")]
    for scenario in (world, elsewhere):
        code, out = _record(
            team,
            READER.format(names=names, secret=SECRET),
            "--scenario", str(scenario), "--world-key", str(key), "--settings", str(settings),
            "--overwrite",
            out=old,
        )  # fmt: skip
        assert code == 4
        run = open_run(out)
        assert run.outcome == "crashed", run.outcome_reason
        said = run.outcome_reason
        assert "READ helper-ok" in said, said
        # /dev/null over each: a sandbox may not open it (a PermissionError, not a read)
        for name in ("world.key", "settings.toml", "old.mcap", "old.mcap.part"):
            assert f"{name}=refused:PermissionError" in said, said
        if scenario == world:
            assert "world.toml=refused:PermissionError" in said, said
            assert "hardlink.toml=read:secret" in said  # not the grader's in this run
        else:  # the world passed in, by another name: hidden too; its symlink leads nowhere
            assert "hardlink.toml=refused:PermissionError" in said, said
            assert "symlink.toml=refused:FileNotFoundError" in said, said
    # the grader's files are untouched
    assert SECRET in world.read_text() and SECRET in key.read_text()
    assert (team / "hardlink.toml").read_text() == elsewhere.read_text()


ESCAPES = "\x1b[2J\x1b[H\x1b]0;pwned\x07\r4/4 markers ... done\x1b[?25l\u202e"

SHOUTER = f"""
    from usar_replay.api import Node

    class Shout(Node):
        def __init__(self):
            super().__init__("shout\\x1b[31m")
            self.create_timer(0.1, self.tick)
            self.n = 0

        def tick(self):
            self.n += 1
            self.get_logger().info({ESCAPES!r} + "\\nsecond line\\tend")
            if self.n == 3:
                raise RuntimeError({ESCAPES!r})

    def main():
        Shout()
"""


def _no_controls(text: str) -> None:
    bad = [ch for ch in text if ch not in "\n\t" and (ord(ch) < 0x20 or 0x7F <= ord(ch) < 0xA0)]
    assert not bad and "\u202e" not in text, repr(text[:400])


def test_mission_text_is_printed_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Point 10: the crash text and log lines reach the terminal escaped, readable."""
    code, out = _record(tmp_path, SHOUTER, "--scenario", str(_world(tmp_path / "w.toml")))
    assert code == 4
    shown = capsys.readouterr()
    _no_controls(shown.out + shown.err)
    assert "\\x1b[2J\\x1b[H" in shown.out and "4/4 markers ... done" in shown.out, shown.out
    assert "\\u202e" in shown.out
    assert "Traceback (most recent call last):\n" in shown.out  # lines stay lines
    assert open_run(out).outcome_reason.count("\x1b") >= 4  # the log keeps the bytes as sent
    info = usar("info", str(out))
    _no_controls(info.stdout + info.stderr)
    logged = usar("log", str(out))
    _no_controls(logged.stdout + logged.stderr)
    assert "[shout\\x1b[31m]: \\x1b[2J\\x1b[H" in logged.stdout, logged.stdout
    assert "second line" in logged.stdout and "\\t" not in logged.stdout  # tabs, lines kept


KILLER = """
    import os
    import signal
    from usar_replay.api import Node

    class Killer(Node):
        def __init__(self):
            super().__init__("killer")
            self.create_timer(0.1, lambda: os.kill(os.getpid(), signal.SIGKILL))

    def main():
        Killer()
"""


def test_a_killed_mission_is_crashed_by_signal_not_out_of_memory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Point 11: SIGKILL with no out-of-memory record is ``crashed (signal 9)``."""
    code, out = _record(tmp_path, KILLER, "--scenario", str(_world(tmp_path / "w.toml")))
    assert code == 4
    run = open_run(out)
    assert run.outcome == "crashed", run.outcome
    assert "crashed (signal 9)" in run.outcome_reason and "SIGKILL" in run.outcome_reason
    assert "memory" not in run.outcome_reason
    assert "crashed (signal 9)" in capsys.readouterr().out


_CMAKE = """cmake_minimum_required(VERSION 3.0.2)
project(bridge_killer)
find_package(catkin REQUIRED)
catkin_package()
"""
_PACKAGE_XML = """<?xml version="1.0"?>
<package format="2">
  <name>bridge_killer</name>
  <version>0.0.1</version>
  <description>kills usar's ROS 1 bridge</description>
  <maintainer email="red@team.example">red team</maintainer>
  <license>MIT</license>
  <buildtool_depend>catkin</buildtool_depend>
</package>
"""
_NODE = """#!/usr/bin/env python3
import os, signal, time
me = os.getpid()
for pid in os.listdir("/proc"):
    if pid.isdigit() and int(pid) != me:
        try:
            cmd = open(f"/proc/{pid}/cmdline", "rb").read()
        except OSError:
            continue
        if b"usar_replay.ros1.bridge" in cmd:
            os.kill(int(pid), signal.SIGKILL)
time.sleep(30)
"""


def _python_node_package(tmp_path: Path, script: str) -> Path:
    """A catkin package whose one node (launch/kill.launch) is the Python ``script``."""
    pkg = tmp_path / "bridge_killer"
    (pkg / "scripts").mkdir(parents=True)
    (pkg / "CMakeLists.txt").write_text(_CMAKE)
    (pkg / "package.xml").write_text(_PACKAGE_XML)
    node = pkg / "scripts" / "kill_bridge.py"
    node.write_text(script)
    node.chmod(0o755)
    (pkg / "launch").mkdir()
    (pkg / "launch" / "kill.launch").write_text(
        '<launch><node pkg="bridge_killer" type="kill_bridge.py" name="killer"/></launch>\n'
    )
    return pkg


def _record_node(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, script: str
) -> tuple[list[str], Path]:
    """``usar record`` arguments (no ``--out``) that run ``script`` as the package's one node on
    a small world, with a build cache of the test's own; and the package."""
    assert debian.missing() == [], debian.install_line(debian.missing())
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    pkg = _python_node_package(tmp_path, script)
    world = _world(tmp_path / "w.toml")
    return ["record", "--ros1", str(pkg), "--launch", "kill.launch", "--scenario", str(world)], pkg


def test_a_ros1_node_that_kills_the_bridge_is_crashed_by_signal(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Point 11, ROS 1: a node that SIGKILLs the bridge gets ``crashed (signal 9)``."""
    args, pkg = _record_node(tmp_path, monkeypatch, _NODE)
    out = tmp_path / "killed.mcap"
    code = main([*args, "--out", str(out), "--quiet", "--max-sim-time", "2"])
    assert code == 4
    run = open_run(out)
    assert run.outcome == "crashed", (run.outcome, run.outcome_reason)
    assert "signal 9" in run.outcome_reason, run.outcome_reason
    shutil.rmtree(pkg)


_THIEF = """#!/usr/bin/env python3
# issue #26 point 5, ROS 1: take the bridge's socket to the recorder (pidfd_getfd), stop the
# bridge, then write well-formed frames to the recorder and never read what it sends
import ctypes, os, signal, struct, sys, time
import rospy
from rosgraph_msgs.msg import Clock
rospy.init_node("killer")
rospy.wait_for_message("/clock", Clock)  # the run has started: the recorder writes ticks now
rospy.sleep(1.0)
me = os.getpid()
for pid in os.listdir("/proc"):
    if not pid.isdigit() or int(pid) == me:
        continue
    try:
        argv = open(f"/proc/{pid}/cmdline", "rb").read().split(b"\\0")
    except OSError:
        continue
    at = argv.index(b"usar_replay.ros1.bridge") if b"usar_replay.ros1.bridge" in argv else 0
    if at >= 2 and argv[at - 1] == b"-m" and b"bwrap" not in argv[0]:  # the bridge, not bwrap
        fd_number = int(argv[at + 1])
        pidfd = os.pidfd_open(int(pid))
        libc = ctypes.CDLL(None, use_errno=True)
        sock = libc.syscall(438, pidfd, fd_number, 0)  # pidfd_getfd
        if sock < 0:
            sys.exit(f"pidfd_getfd: errno {ctypes.get_errno()}")
        os.kill(int(pid), signal.SIGSTOP)
        frame = b"O" + struct.pack("<qI", 0, 0) + b"\\x00"
        for _ in range(100_000):
            os.write(sock, struct.pack("!i", len(frame)) + frame)
time.sleep(60)
"""


def test_a_ros1_node_that_steals_the_bridges_socket_is_a_verdict_in_a_closed_log(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Point 5, ROS 1: a node takes the bridge's socket to the recorder with ``pidfd_getfd``,
    stops the bridge and floods the recorder with frames, never reading. Every write the
    recorder makes has a deadline, so the run ends with a verdict (no hang) in a closed log."""
    args, pkg = _record_node(tmp_path, monkeypatch, _THIEF)
    out = tmp_path / "stolen.mcap"
    done = usar(*args, "--out", str(out), "--quiet", "--max-sim-time", "30", "--tick-timeout", "3",
                timeout=240)  # fmt: skip
    assert done.returncode == 4, done.stdout + done.stderr
    run = open_run(out)
    assert run.file_state == "complete"
    # the recorder's write of the next tick to the stopped bridge ran into its deadline: the
    # tick timeout for each tick in flight (two where a tick without a frame was sent ahead)
    assert run.outcome == "hung", (run.outcome, run.outcome_reason)
    assert re.search(r"did not read its input within [36] s", run.outcome_reason)
    shutil.rmtree(pkg)


# --- point 12: the ROS 2 final project's markers come from the course's detector -------------

_ROS2_HEAD = """
    from usar_replay.api import contract
    from usar_replay.core import msgs
    from usar_replay.missions.ros2_final import OdomUpdater, TargetReacher
    from usar_replay.node.node import current_executor
"""

FORGER = (
    _ROS2_HEAD
    + """
    def forged():
        # the world's marker (ID 1 in the built-in world) 1.1 m straight ahead, as the camera
        # would see it, and the other IDs at made-up places
        ahead = msgs.Pose(position=msgs.Point(z=1.1), orientation=msgs.Quaternion(w=1.0))
        far = msgs.Pose(position=msgs.Point(x=3.0, z=-2.0), orientation=msgs.Quaternion(w=1.0))
        return msgs.ArucoMarkers(
            header=msgs.Header(frame_id="robot1/camera_rgb_optical_frame"),
            marker_ids=(1, 0, 2, 3),
            poses=(ahead, far, far, far),
        )

    class Forger(TargetReacher):
        # never turns to look: claims marker 1 at aruco_target and drives on to its destination
        def __init__(self):
            super().__init__()
            self.fake = self.create_publisher(msgs.ArucoMarkers, contract.ARUCO_MARKERS)
            self.create_timer(0.1, lambda: self.fake.publish(forged()))

        def _at_target(self, result):
            self.fake.publish(forged())
            self.destination = self.destination_for(1)
            self.phase = "lookup"
            self._broadcast()

    def main():
        OdomUpdater()
        Forger()
"""
)

OLD_DETECTOR = (
    _ROS2_HEAD
    + """
    from usar_replay.world.detect import aruco_markers, detect

    class OwnArucoNode:
        # a mission written before the course's detector: its own aruco_node on /aruco_markers
        def __init__(self, node):
            from usar_replay.core.settings import DetectorParams, from_mapping

            group = {k: p.value for k, p in node.get_parameters_by_prefix("detector").items()}
            self.params = from_mapping(DetectorParams, group, "detector.")
            self.info, self.seq = None, 0
            self.pub = node.create_publisher(msgs.ArucoMarkers, "/aruco_markers")
            node.create_subscription(msgs.CameraInfo, contract.ROS2_CAMERA_INFO, self.on_info)
            node.create_subscription(msgs.CompressedImage, contract.ROS2_IMAGE, self.on_image)

        def on_info(self, msg):
            self.info = msg

        def on_image(self, msg):
            if self.info is None:
                return
            found = detect(msg, self.info, self.params, self.seq)
            self.seq += 1
            if found.transforms:
                self.pub.publish(aruco_markers(found))

    def main():
        from usar_replay.api import Node

        OdomUpdater()
        OwnArucoNode(Node("aruco_node"))
        TargetReacher()
"""
)

SMUGGLER = (
    _ROS2_HEAD
    + """
    class Smuggler(TargetReacher):
        # past the node API: the trusted name put straight into the tick's outputs
        def _on_timer(self):
            ex = current_executor()
            ex._outputs.append((contract.ARUCO_MARKERS, msgs.ArucoMarkers(marker_ids=(1,))))
            super()._on_timer()

    def main():
        OdomUpdater()
        Smuggler()
"""
)


def _ros2_world() -> Scenario:
    """The built-in world with a 320x240 camera, as tests/missions/test_ros2_final.py records it."""
    world = ros2_final_world()
    return dataclasses.replace(
        world, camera=dataclasses.replace(world.camera, width=320, height=240)
    )


def _ros2_record(folder: Path, name: str, source: str) -> tuple[Path, RecordResult]:
    mission = folder / f"{name}.py"
    mission.write_text(textwrap.dedent(source))
    out = folder / f"{name}.mcap"
    return out, record(_ros2_world(), out, RunSettings(), mission=str(mission))


@pytest.fixture(scope="module")
def ros2_builtin(tmp_path_factory: pytest.TempPathFactory) -> GradeReport:
    out = tmp_path_factory.mktemp("ros2") / "builtin.mcap"
    assert record(_ros2_world(), out, RunSettings()).outcome == "done"
    return grade_file(out)


def test_forged_aruco_markers_gain_nothing(tmp_path: Path, ros2_builtin: GradeReport) -> None:
    """Point 12: forged detections (the true ID at a true-looking pose, the others anywhere)
    are recorded as the mission's own, never graded: the robot never looked, so no detection
    and nothing that needs one."""
    out, result = _ros2_record(tmp_path, "forger", FORGER)
    assert result.outcome == "done", result.outcome_reason  # it ran: renamed, not refused
    run = open_run(out)
    assert run.reader.publishers(contract.ARUCO_MARKERS) <= {"sim"}
    forged = [m for m in run.messages([contract.MISSION_ARUCO_MARKERS])]
    assert forged and {m.publisher for m in forged} == {"mission"}
    report = grade_file(out)
    assert {"marker.detected", "destination.reached", "time_limit"} <= set(report.failed_ids())
    # without point 12 these forgeries scored the built-in mission's 60: now 20 points less
    assert report.points <= ros2_builtin.points - 20
    # the forger drove where marker 1 leads, so nothing else differs: what it lost is exactly
    # what it could only have had by detecting the marker
    assert report.check("destination.chosen").passed
    assert not result.found  # `usar record`'s summary counts no marker either


def test_aruco_markers_sent_past_the_node_api_are_refused(tmp_path: Path) -> None:
    """Point 12: the trusted name straight into the outputs is refused at the boundary."""
    out, result = _ros2_record(tmp_path, "smuggler", SMUGGLER)
    assert result.outcome == "refused", (result.outcome, result.outcome_reason)
    assert "course's detector" in result.outcome_reason
    run = open_run(out)
    assert run.reader.publishers(contract.ARUCO_MARKERS) <= {"sim"}
    assert not grade_file(out).check("marker.detected").passed


def test_an_old_mission_with_its_own_aruco_node_grades_as_before(
    tmp_path: Path, ros2_builtin: GradeReport
) -> None:
    """Point 12: a mission that still starts its own detector on /aruco_markers runs, its
    detections are recorded as /mission/aruco_markers, and it grades as the built-in mission
    does (which is what it graded before: tests/missions/test_ros2_final.py), line for line."""
    out, result = _ros2_record(tmp_path, "old", OLD_DETECTOR)
    assert result.outcome == "done", result.outcome_reason
    run = open_run(out)
    own = [
        mid
        for m in run.messages([contract.MISSION_ARUCO_MARKERS])
        if isinstance(m.msg, msgs.ArucoMarkers)
        for mid in m.msg.marker_ids
    ]
    assert set(own) == {1}
    report = grade_file(out)
    assert report.points == ros2_builtin.points == 60
    assert [(c.id, c.passed, c.measured, c.evidence_ns) for c in report.checks] == [
        (c.id, c.passed, c.measured, c.evidence_ns) for c in ros2_builtin.checks
    ]
    # and it replays bit for bit: the course's detections from the recorded frames
    replayed = replay(run)
    assert replayed.identical, replayed.lines()
