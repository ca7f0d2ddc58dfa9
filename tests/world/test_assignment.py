"""A third assignment from a package of its own: recorded, graded and viewed by the unchanged CLI.

The package (written to a temporary folder) declares the entry point ``usar_replay.assignments``
as an installed distribution does (a ``.dist-info`` folder beside it on ``PYTHONPATH``); its
function registers the assignment (world layer) and its rubric (grading's registry). Nothing of
usar is edited: this is the public way to add an assignment (docs/assignments.md).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from clitools import usar

PLUGIN = '''
"""toy-patrol: one robot, the scout, drives forward; the rubric checks it moved."""

import math

from usar_replay.core import contract, msgs
from usar_replay.grading.rubrics import register_rubric
from usar_replay.grading.verdict import Check, GradeReport, Rubric
from usar_replay.world.assignment import Assignment, register
from usar_replay.world.scenario import Box, CameraSettings, Marker, Scenario

NAME = "toy-patrol"
SCOUT = "scout"
TRUTH = contract.truth_pose(SCOUT)


def world():
    t, h = 0.15, 1.0

    def wall(name, x, y, yaw, length):
        return Box(name=name, x=x, y=y, z=h / 2, size_x=length, size_y=t, size_z=h, yaw=yaw)

    return Scenario(
        name="toy-room",
        walls=(
            wall("south", 0.0, -1.575, 0.0, 4.3),
            wall("north", 0.0, 1.575, math.pi, 4.3),
            wall("west", -2.075, 0.0, -math.pi / 2, 3.0),
            wall("east", 2.075, 0.0, math.pi / 2, 3.0),
        ),
        markers=(Marker(id=0, x=1.99, y=0.4, yaw=math.pi),),
        targets=((1.1, 0.3),),
        camera=CameraSettings(width=160, height=120, rate_hz=5.0),
        time_limit_s=20.0,
        assignment=NAME,
    )


class MovedGrader:
    def __init__(self, scenario, thresholds=None):
        self.start_ns = None
        self.first = None
        self.best, self.when = 0.0, None

    def feed(self, topic, msg, t_ns):
        if topic == TRUTH and isinstance(msg, msgs.PoseStamped):
            p = (msg.pose.position.x, msg.pose.position.y)
            self.first = self.first or p
            if math.dist(self.first, p) > self.best:
                self.best, self.when = math.dist(self.first, p), t_ns

    def found_markers(self):
        return ()

    def report(self, source, *, log_complete=True, log_problem=""):
        ok = self.best >= 0.3
        check = Check(
            "scout.moved", "the scout drove at least 0.3 m", ok, 2.0 if ok else 0.0, 2.0,
            f"{self.best:.2f} m", ">= 0.30 m", self.when,
        )
        return GradeReport(source, (check,), self.start_ns or 0, log_complete, log_problem)


TOY = Assignment(
    name=NAME,
    title="Toy patrol (a third assignment from its own package)",
    robots=(contract.RobotFrames.usar(SCOUT),),
    camera_robot=SCOUT,
    image_topic="/scout/camera/rgb/image_raw/compressed",
    camera_info_topic="/scout/camera/rgb/camera_info",
    sim_base_tf=True,
    static_frames=(),
    static_links=lambda scenario: (),
    starts=lambda scenario: ((-1.2, 0.0, 0.0),),
    parameters=lambda scenario, settings: {"use_sim_time": True},
    builtin_mission=NAME,
    mission="toy_patrol_mission:main",
    world=world,
    variant=lambda scenario, seed, key=None: scenario,
)


def register_all():
    register(TOY)
    register_rubric(NAME, lambda: Rubric(MovedGrader, (TRUTH,), (TRUTH,)))
'''

MISSION = '''
"""The toy's reference mission: forward at 0.2 m/s for 3 s, then stop and say done."""

from usar_replay.api import Node, Twist, Vector3, shutdown


class Patrol(Node):
    def __init__(self):
        super().__init__("patrol")
        self.cmd = self.create_publisher(Twist, "/scout/cmd_vel")
        self.ticks = 0
        self.create_timer(0.1, self.on_timer)

    def on_timer(self):
        self.ticks += 1
        if self.ticks > 30:
            self.cmd.publish(Twist())
            shutdown()
        else:
            self.cmd.publish(Twist(linear=Vector3(x=0.2)))


def main():
    Patrol()
'''


@pytest.fixture(scope="module")
def plugin(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The toy package, as an installed distribution with its entry point."""
    root = tmp_path_factory.mktemp("plugin")
    (root / "toy_patrol.py").write_text(PLUGIN, encoding="utf-8")
    (root / "toy_patrol_mission.py").write_text(MISSION, encoding="utf-8")
    info = root / "toy_patrol-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: toy-patrol\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        "[usar_replay.assignments]\ntoy-patrol = toy_patrol:register_all\n"
    )
    return root


def _usar(plugin: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``usar ARGS`` in ``cwd`` with the toy assignment's package importable."""
    path = [str(plugin), os.environ.get("PYTHONPATH", "")]
    return usar(
        *args, cwd=cwd, env={**os.environ, "PYTHONPATH": os.pathsep.join(p for p in path if p)}
    )


@pytest.fixture(scope="module")
def toy_log(plugin: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    out = tmp_path_factory.mktemp("runs")
    rec = _usar(plugin, out, "record", "--assignment", "toy-patrol", "--out", "toy.mcap")
    assert rec.returncode == 0, rec.stderr + rec.stdout
    return out / "toy.mcap", rec.stdout


def test_the_toy_records_with_its_own_mission(toy_log: tuple[Path, str]) -> None:
    log, stdout = toy_log
    assert log.is_file()
    assert "Mission toy-patrol: the mission said it was done" in stdout
    assert "Markers found: 0/1 (as `usar grade` counts them)" in stdout


def test_the_toy_is_graded_by_its_own_rubric(plugin: Path, toy_log: tuple[Path, str]) -> None:
    log, _ = toy_log
    out = _usar(plugin, log.parent, "grade", log.name, "--json", "toy.json", "--overwrite")
    assert out.returncode == 0, out.stderr + out.stdout
    assert "scout.moved" in out.stdout
    report = json.loads((log.parent / "toy.json").read_text(encoding="utf-8"))
    text = json.dumps(report)
    assert '"scout.moved"' in text and '"passed": true' in text, text


def test_the_toy_is_viewed(plugin: Path, toy_log: tuple[Path, str]) -> None:
    log, _ = toy_log
    out = _usar(plugin, log.parent, "view", log.name, "--save", "toy.rrd")
    assert out.returncode == 0, out.stderr
    assert (log.parent / "toy.rrd").stat().st_size > 0


def test_without_the_package_the_world_is_unknown(toy_log: tuple[Path, str]) -> None:
    """The log names its assignment; a machine without the package says so in one line."""
    log, _ = toy_log
    out = subprocess.run(
        [sys.executable, "-m", "usar_replay.cli", "grade", str(log)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode != 0
    assert "unknown assignment 'toy-patrol'" in out.stderr
    assert "Traceback" not in out.stderr


def test_registry_refuses_a_second_assignment_under_a_taken_name() -> None:
    import dataclasses

    from usar_replay.world import assignment

    clash = dataclasses.replace(assignment.USAR, title="another US&R")
    with pytest.raises(ValueError, match="already registered"):
        assignment.register(clash)
    assert assignment.register(assignment.USAR) is assignment.USAR


def test_the_docs_show_the_entry_point() -> None:
    doc = Path(__file__).resolve().parents[2] / "docs" / "assignments.md"
    text = doc.read_text(encoding="utf-8")
    assert '[project.entry-points."usar_replay.assignments"]' in text
    assert "register_rubric" in text


def test_the_toy_replays_bit_for_bit(plugin: Path, toy_log: tuple[Path, str]) -> None:
    """The log says ``--mission toy-patrol``: replay finds it through the package's entry point."""
    log, _ = toy_log
    out = _usar(plugin, log.parent, "replay", log.name)
    assert out.returncode == 0, out.stderr + out.stdout


def test_an_assignment_and_the_rubric_registry_have_one_home_each() -> None:
    """``Assignment`` and the assignments' table are defined once (the world layer); the rubric
    registry once (grading); nothing else keeps a list of assignment names."""
    import ast

    package = Path(__file__).resolve().parents[2] / "usar_replay"
    homes: dict[str, list[str]] = {}
    for path in sorted(package.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            names = []
            if isinstance(node, ast.ClassDef):
                names = [node.name]
            elif isinstance(node, ast.Assign | ast.AnnAssign):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names = [t.id for t in targets if isinstance(t, ast.Name)]
            for name in names:
                homes.setdefault(name, []).append(str(path.relative_to(package)))
    assert homes["Assignment"] == ["world/assignment.py"]
    assert homes["ASSIGNMENTS"] == ["world/assignment.py"]
    assert homes["_RUBRICS"] == ["grading/rubrics.py"]
