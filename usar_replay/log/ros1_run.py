"""What a log says about the ROS 1 package that made it: ``ros1.toml`` and each node's output.

Why: a ROS 1 run's mission is a catkin package, not a Python file, and what a reader of the log
wants to know about it is different: which package (path and sha256), how it was started (the
launch file or the node), which nodes it ran, how long it took to build (or that the build was
cached), which of usar's settings applied and which ``/mission/*``-style parameters its nodes
read. The recorder writes this once, at the end of the run (:mod:`usar_replay.ros1.process`),
as :data:`usar_replay.core.contract.ROS1_ATTACHMENT`; each node's stdout and stderr is an
attachment of its own under :data:`usar_replay.core.contract.NODE_OUTPUT_ATTACHMENT_PREFIX`.
``usar info`` and ``usar log --output`` read them here.
"""

from __future__ import annotations

import re
import textwrap
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from usar_replay.core import contract
from usar_replay.core.errors import UsageError
from usar_replay.core.msg_text import WIDTH
from usar_replay.core.safe_text import safe, safe_line
from usar_replay.log.run import Run

__all__ = [
    "GoalTolerance",
    "ParameterRead",
    "Ros1Node",
    "Ros1Run",
    "TargetReplaced",
    "node_output_lines",
    "node_outputs",
    "of",
]


@dataclass(frozen=True, slots=True)
class Ros1Node:
    """A node of the package: its resolved name, package and executable (type)."""

    name: str
    package: str = ""
    type: str = ""


@dataclass(frozen=True, slots=True)
class ParameterRead:
    """A parameter the package's nodes asked the master for."""

    name: str
    value: str
    """What usar set it to, as text; empty when usar did not set it (the node's default)."""
    read_by: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class GoalTolerance:
    """The goal tolerances usar's move_base used for one robot, and where they were read
    (``param/dwa_local_planner_params.yaml (launch/move_base.launch)``, ``the course
    template's default``, ``usar's setting mission.xy_tolerance``)."""

    robot: str
    xy: float
    yaw: float
    source: str = ""


@dataclass(frozen=True, slots=True)
class TargetReplaced:
    """A parameter of the launch file that held one of the course's lookup targets, which the
    graded world's target replaced (or dropped: the world has no such target)."""

    param: str
    target: int
    source: str = ""
    """Where the launch file set it (``param/aruco_lookup.yaml (launch/team.launch)``)."""
    how: str = "name"
    """How it was known: ``name`` (``.../aruco_lookup_locations/target_N``) or ``value``."""


@dataclass(frozen=True, slots=True)
class Ros1Run:
    """The contents of ``ros1.toml`` (see the module doc)."""

    package: str
    path: str = ""
    sha256: str = ""
    launch: str = ""
    node: str = ""
    after_launch: tuple[str, ...] = ()
    """Commands run once the graph was up (the TA's third terminal)."""
    start_source: str = ""
    """Where the start was read (``doc/instructions.txt line 7``, ``usar.toml [ros1]``)."""
    build_seconds: float = 0.0
    build_cached: bool = False
    nodes: tuple[Ros1Node, ...] = ()
    replaced: tuple[Ros1Node, ...] = ()
    """The launch file's nodes usar did not start: its stand-ins did their job (Gazebo,
    amcl, move_base, map_server, aruco_detect, rviz, ...)."""
    parameters: tuple[ParameterRead, ...] = ()
    applied_settings: tuple[str, ...] = ()
    """Prefixes of the settings that applied (``record``, ``mission.xy_tolerance``, ...)."""
    goal_tolerances: tuple[GoalTolerance, ...] = ()
    """Per robot, usar's move_base goal tolerances and their source (empty: a log before)."""
    targets_replaced: tuple[TargetReplaced, ...] = ()
    """The launch file's parameters that held the course's targets (empty: none, or a log
    before usar said)."""
    detections_read: bool | None = None
    """Whether a node of the package subscribed to ``/fiducial_transforms`` during the run
    (the master said so, tick by tick); None: a log before usar said. The rubric counts a
    detection only for a package that could use it (rubric usar v3)."""
    holds: int = 0
    """Ticks the bridge held for a node's shutdown (wall time the graph took, not sim time)."""
    capped: int = 0
    """Ticks whose wall cap ran out before the graph went idle (a repeatability warning), as
    logs before issue 46 recorded it; a newer log leaves it out (0): which tick runs out of its
    wall cap is the machine's load, and the same run must give the same bytes. The recorder's
    summary and a batch's ``run.json`` say it."""

    @property
    def pacing(self) -> str:
        """The holds (and an older log's capped ticks) as ``usar info`` says them."""
        if self.capped:
            return f"{self.holds} shutdown holds, {self.capped} capped ticks"
        return f"{self.holds} shutdown holds"

    @property
    def started_with(self) -> str:
        """The start as a TA types it: ``roslaunch P F; rosrun P N; rosservice call ...``."""
        words = []
        if self.launch:
            words.append(f"roslaunch {self.package} {self.launch}")
        if self.node or not self.launch:
            words.append(f"rosrun {self.package} {self.node}")
        return "; ".join([*words, *self.after_launch])

    @property
    def build(self) -> str:
        """The build as logs before issue 42 recorded it ('' for a newer log, which leaves
        the build's wall time out: the same run, the same bytes, cached or not)."""
        if not (self.build_cached or self.build_seconds):
            return ""
        if self.build_cached:
            return "cached (built before; catkin_make did not run)"
        return f"{self.build_seconds:.1f} s (catkin_make, wall time)"

    def applies(self, setting: str) -> bool:
        """Whether ``setting`` (``mission.spin_speed``) applied to this run."""
        return any(setting == p or setting.startswith(p + ".") for p in self.applied_settings)

    def xy_goal_tolerance(self, robot: str) -> float | None:
        """The xy goal tolerance usar's move_base used for ``robot`` (None: not recorded)."""
        for tol in self.goal_tolerances:
            if tol.robot == robot:
                return tol.xy
        return None

    def to_toml(self) -> str:
        import tomli_w  # deferred: reading a log never writes TOML

        data: dict[str, Any] = {
            "package": self.package,
            "path": self.path,
            "sha256": self.sha256,
            "launch": self.launch,
            "node": self.node,
            "after_launch": list(self.after_launch),
            "start_source": self.start_source,
            **({"build_seconds": round(self.build_seconds, 3)} if self.build_seconds else {}),
            **({"build_cached": True} if self.build_cached else {}),
            "applied_settings": list(self.applied_settings),
            "holds": self.holds,
            **({"capped": self.capped} if self.capped else {}),
            "nodes": [{"name": n.name, "package": n.package, "type": n.type} for n in self.nodes],
            "replaced": [
                {"name": n.name, "package": n.package, "type": n.type} for n in self.replaced
            ],
            "parameters": [
                {"name": p.name, "value": p.value, "read_by": list(p.read_by)}
                for p in self.parameters
            ],
            "goal_tolerances": [
                {"robot": g.robot, "xy": g.xy, "yaw": g.yaw, "source": g.source}
                for g in self.goal_tolerances
            ],
            "targets_replaced": [
                {"param": t.param, "target": t.target, "source": t.source, "how": t.how}
                for t in self.targets_replaced
            ],
            **({} if self.detections_read is None else {"detections_read": self.detections_read}),
        }
        return tomli_w.dumps(data)

    @classmethod
    def from_toml(cls, text: str) -> Ros1Run:
        data = tomllib.loads(text)
        return cls(
            package=str(data.get("package", "")),
            path=str(data.get("path", "")),
            sha256=str(data.get("sha256", "")),
            launch=str(data.get("launch", "")),
            node=str(data.get("node", "")),
            after_launch=tuple(str(c) for c in data.get("after_launch", [])),
            start_source=str(data.get("start_source", "")),
            build_seconds=float(data.get("build_seconds", 0.0)),
            build_cached=bool(data.get("build_cached", False)),
            applied_settings=tuple(str(s) for s in data.get("applied_settings", [])),
            holds=int(data.get("holds", 0)),
            capped=int(data.get("capped", 0)),
            detections_read=(
                None if "detections_read" not in data else bool(data["detections_read"])
            ),
            nodes=_nodes(data.get("nodes", [])),
            replaced=_nodes(data.get("replaced", [])),
            parameters=tuple(
                ParameterRead(
                    str(p.get("name", "")),
                    str(p.get("value", "")),
                    tuple(str(r) for r in p.get("read_by", [])),
                )
                for p in data.get("parameters", [])
            ),
            goal_tolerances=tuple(
                GoalTolerance(
                    str(g.get("robot", "")),
                    float(g.get("xy", 0.0)),
                    float(g.get("yaw", 0.0)),
                    str(g.get("source", "")),
                )
                for g in data.get("goal_tolerances", [])
            ),
            targets_replaced=tuple(
                TargetReplaced(
                    str(t.get("param", "")),
                    int(t.get("target", 0)),
                    str(t.get("source", "")),
                    str(t.get("how", "name")),
                )
                for t in data.get("targets_replaced", [])
            ),
        )


def _nodes(rows: Any) -> tuple[Ros1Node, ...]:
    return tuple(
        Ros1Node(str(n.get("name", "")), str(n.get("package", "")), str(n.get("type", "")))
        for n in rows
    )


_ANSI = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]|\x1b\][^\x07\x1b]*(\x07|\x1b\\)?")
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")


def _shown(text: str) -> str:
    """A node's output as it may go to a terminal: colours (rosconsole's) and the C0 control
    characters removed, any other (C1's CSI, the right-to-left overrides) escaped (the output
    is the student's: it must not drive the terminal)."""
    return safe(_CONTROL.sub("", _ANSI.sub("", text.expandtabs(4))))


def of(run: Run) -> Ros1Run | None:
    """The log's ``ros1.toml``; None for a log of a Python mission (or one that has none). An
    invalid one is said once among the run's problems, however often it is asked for (grading
    asks for the tolerances, the detections and the start)."""
    text = run.reader.attachments.get(contract.ROS1_ATTACHMENT)
    if text is None:
        return None
    try:
        return Ros1Run.from_toml(text.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError, ValueError, AttributeError, TypeError,
            RecursionError):  # fmt: skip
        said = f"the attached {contract.ROS1_ATTACHMENT} is invalid"
        if said not in run.problems:
            run.problems.append(said)
        return None


def node_outputs(run: Run) -> dict[str, str]:
    """Each node's stdout and stderr, by node name (``/explorer``), as text."""
    prefix = contract.NODE_OUTPUT_ATTACHMENT_PREFIX
    out: dict[str, str] = {}
    for name, data in sorted(run.reader.attachments.items()):
        if name.startswith(prefix) and name.endswith(".txt"):
            label = name.removeprefix(prefix).removesuffix(".txt")
            out["/" + label.replace("+", "/")] = data.decode("utf-8", errors="replace")
    return out


def node_output_lines(run: Run, nodes: tuple[str, ...] = ()) -> Iterator[str]:
    """``usar log --output``: each node's output under a ``--- /node: stdout and stderr ---``
    line (``nodes``: only these, ``explorer`` or ``/explorer``). A node with no output kept is a
    :class:`UsageError` naming those with one."""
    outputs = node_outputs(run)
    wanted = ["/" + n.strip("/") for n in nodes] or list(outputs)
    missing = [n for n in wanted if n not in outputs]
    if missing:
        kept = ", ".join(outputs) or "none (not a ROS 1 log, or one recorded before usar kept it)"
        raise UsageError(f"{run.path}: no output of node {missing[0]} kept; the nodes': {kept}")
    for name in wanted:
        yield f"--- {safe_line(name)}: stdout and stderr ---"  # a name from the file
        for line in _shown(outputs[name]).splitlines():
            yield from textwrap.wrap(
                line, WIDTH, subsequent_indent="    ", break_on_hyphens=False
            ) or [""]
