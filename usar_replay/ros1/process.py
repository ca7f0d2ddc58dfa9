"""The recorder's side of a ROS 1 run: the bridge process takes the mission process's place.

:class:`Ros1Process` is a :class:`~usar_replay.process.mission_process.MissionProcess` whose
process is the bridge (:mod:`usar_replay.ros1.bridge`) instead of a Python mission: the same
socket, the same tick protocol, the same checks on what comes back (a student's ``/tf`` that moves
a simulator frame is ``refused``, a non-finite ``cmd_vel`` too), the same verdicts (a graph that
dies is ``crashed`` with its output, one that stops answering is ``hung``). The package was built
before (:mod:`usar_replay.ros1.record`); the run mounts the built workspace and usar's underlay
read-only, in the kernel sandbox at the fixed paths they were built at
(:mod:`usar_replay.ros1.building.layout`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import signal
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from usar_replay.core import contract, msgs
from usar_replay.core.limits import RunLimits
from usar_replay.log.ros1_run import (
    GoalTolerance,
    ParameterRead,
    Ros1Node,
    Ros1Run,
    TargetReplaced,
)
from usar_replay.process.mission_process import MissionLimits, MissionProcess, uses_kernel_sandbox
from usar_replay.process.mission_target import MissionTarget
from usar_replay.process.protocol import Wire
from usar_replay.ros1 import run_files, start
from usar_replay.ros1.boundary import Ros1BoundaryCheck
from usar_replay.ros1.building.workspace import BuildLimits, Built, Package, package_sha256
from usar_replay.ros1.launch_output import file_label
from usar_replay.ros1.netns import isolated_command
from usar_replay.ros1.pacing import watcher
from usar_replay.ros1.pacing.scheduling import OneCpu
from usar_replay.sandbox.run_folder import RunFolder

__all__ = ["Ros1Options", "Ros1Process", "build_limits_for", "ros1_target"]


@dataclass(frozen=True, slots=True)
class Ros1Options:
    """How the student's graph is started and paced."""

    launch: str = ""
    """A launch file of the package (name or path inside it): ``roslaunch PKG FILE``."""
    node: str = ""
    """An executable of the package: ``rosrun PKG NODE``; with a launch file too, both run
    (one roslaunch of a launch file of usar's that includes the one and starts the other, as
    a TA's two terminals do: :mod:`.start`)."""
    after_launch: tuple[str, ...] = ()
    """Commands run in the graph's sandbox once it is up, as a TA types them in a third
    terminal (``rosservice call /start "data: true"``)."""
    start_source: str = ""
    """Where the start was read (``doc/instructions.txt line 7``; :func:`.start.decide`)."""
    settle_ms: float = 3.0
    """A tick's wall cap (``dt / rtf``, the run's limits) is at least this many milliseconds."""
    isolate: bool = True
    """Run the master and the graph in their own network namespace when possible."""
    keep_workspace: bool = False
    """Leave the run's folder (bridge, master and graph output, ROS logs) on disk."""
    cache: bool = True
    """Reuse a workspace built before from the same files (:func:`cached_build`)."""
    one_cpu: bool = True
    """Run the graph's threads on one CPU under SCHED_RR (:mod:`.scheduling`; needs root)."""
    given_settings: tuple[str, ...] = ()
    """The settings the user gave explicitly (``mission.xy_tolerance``: ``--set`` or
    ``--settings``): such a move_base tolerance wins over the package's (:mod:`.nav_params`)."""


_ROS_ETC = ("/etc/catkin", "/etc/ros", "/etc/debian_version", "/etc/hosts", "/etc/nsswitch.conf")


def _ros_etc() -> tuple[str, ...]:
    """What of ``/etc`` the graph reads, bound read-only into the sandbox like ``/usr``:
    Debian's ROS 1 configuration (catkin's environment hooks set ``ROS_PACKAGE_PATH``) and
    name resolution (roslaunch resolves ``localhost``)."""
    return tuple(p for p in _ROS_ETC if Path(p).exists())


def build_limits_for(limits: RunLimits) -> BuildLimits:
    """The build's limits from the run's: the same memory per process (and the same process
    count and file size as every sandboxed run), the run's CPU seconds per process when it has
    some, and the build's own wall time and folder (:attr:`RunLimits.build_wall_s`,
    :attr:`RunLimits.build_folder_mb`: ``--build-timeout``, ``--build-folder``; the folder is a
    tmpfs of that many MiB and :data:`~usar_replay.ros1.building.build_folder.BUILD_FOLDER_INODES`
    files, 0: a plain folder)."""
    base = BuildLimits()
    return dataclasses.replace(
        base,
        wall_s=limits.build_wall_s,
        memory_mb=limits.memory_mb,
        cpu_s=limits.cpu_s or base.cpu_s,
        run_memory_mb=limits.run_memory_mb,
        cpus=limits.cpus,
        folder_mb=limits.build_folder_mb,
    )


def ros1_target(pkg: Package, options: Ros1Options, *, hashed: bool = True) -> MissionTarget:
    """What the log's ``mission.toml`` says: how the package was started and its sha256
    ('' unless ``hashed``: a package whose folder could not be hashed is still logged)."""
    how = " ".join(
        f"--{k} {v}" for k, v in (("launch", options.launch), ("node", options.node)) if v
    )
    return MissionTarget(
        spec=f"ros1:{pkg.path} {how}".strip(),
        module=f"ros1:{pkg.name}",
        attribute=options.launch or options.node,
        path=str(pkg.path.resolve()),
        sha256=package_sha256(pkg) if hashed else "",
    )


def _text(value: Any) -> str:
    """A parameter's value as ``usar info`` shows it (``[1.0, 2.0]``, ``0.1``, ``true``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(list(value)) if isinstance(value, tuple) else str(value)


def _ready_facts(info: str) -> dict[str, Any]:
    """The bridge's ready frame's JSON (:attr:`usar_replay.ros1.bridge.Bridge.ready_info`)."""
    try:
        got = json.loads(info) if info else {}
    except (ValueError, RecursionError):
        return {}
    return got if isinstance(got, dict) else {}


def _applied_tolerances(
    facts: dict[str, Any], robots: Sequence[str]
) -> list[tuple[str, float, float, str]]:
    """(robot, xy, yaw, source) as the bridge applied them, of ``robots`` only, each checked."""
    out = []
    for row in facts.get("goal_tolerances", [])[: len(robots)]:
        if not (isinstance(row, list) and len(row) == 4 and row[0] in robots):
            continue
        robot, xy, yaw, source = row
        if all(isinstance(v, int | float) and math.isfinite(v) and v >= 0 for v in (xy, yaw)):
            out.append((str(robot), float(xy), float(yaw), str(source)[:300]))
    return out


def _targets(facts: dict[str, Any] | None) -> tuple[TargetReplaced, ...]:
    """The replaced targets the bridge reported (from the team's launch files: each field
    checked and bounded)."""
    rows = (facts or {}).get("targets", [])
    out = []
    for row in rows[:256] if isinstance(rows, list) else []:
        if not isinstance(row, dict):
            continue
        param, target = row.get("param"), row.get("target")
        if not isinstance(param, str) or not isinstance(target, int) or isinstance(target, bool):
            continue
        how = "value" if row.get("how") == "value" else "name"
        out.append(TargetReplaced(param[:200], target, str(row.get("source", ""))[:300], how))
    return tuple(out)


class Ros1Process(MissionProcess):
    """Run the bridge as the mission process on ``built`` (see the module doc)."""

    def __init__(
        self,
        target: MissionTarget,
        parameters: dict[str, Any],
        *,
        sim_topics: Sequence[str],
        sim_frames: Sequence[str],
        limits: MissionLimits | None = None,
        package: Package,
        options: Ros1Options,
        built: Built,
    ) -> None:
        self.options = options
        self.package = package
        self.parameters = dict(parameters)
        self._robots = [r for r in contract.ROBOTS if contract.odom(r) in sim_topics]
        self._kept: list[tuple[str, str, bytes]] = []
        self._one_cpu: OneCpu | None = None
        limits = limits or MissionLimits()
        # the run's folder: a size-limited tmpfs (kept on disk, unlimited, with keep_workspace)
        size = 0 if options.keep_workspace else limits.run_folder_mb
        self._bridge_folder = RunFolder("usar-ros1-", size)
        self.run_dir = Path(self._bridge_folder.path)
        self.built = built
        try:
            if built.at and not uses_kernel_sandbox(limits):
                raise ValueError(f"{built.workspace} was built for the kernel sandbox's {built.at}")
            # the paths the bridge sees: the sandbox's fixed ones (.layout) or the host's
            config: dict[str, Any] = {
                "package": package.name,
                "workspace": built.run_workspace,
                "underlays": list(built.run_underlays),
                "run_dir": str(self.run_dir),
            }
            config.update({k: v for k, v in asdict(options).items()})
            # wall seconds the graph has to register its nodes (--connect-timeout)
            config["connect_timeout_s"] = limits.connect_s
            # the slowest pace (--rtf): a tick waits at most dt / rtf of wall time for the graph
            # to go idle (docs/ros1.md, "Pacing"; 0: no cap); the graph sets the pace below it
            config["rtf"] = limits.rtf
            # where the launch file lies in the package, for usar's start file (.graph)
            config["launch_rel"] = start.launch_path(package.path, options.launch)
            self._config_path = self.run_dir / "bridge.json"
            self._config_path.write_text(json.dumps(config), encoding="utf-8")
            # the graph needs time to start: the master, roslaunch, the node's waitForServer
            startup = max(limits.startup_timeout_s, limits.connect_s + 30.0)
            # the bridge and the whole graph it starts run in the kernel sandbox (bubblewrap) as
            # a Python mission does: reading the built workspace, writing only the run's folder,
            # in a network namespace of their own whose loopback carries the ROS traffic
            limits = dataclasses.replace(
                limits,
                startup_timeout_s=startup,
                read_roots=(
                    *(() if built.mounts else (str(built.workspace), *map(str, built.underlays))),
                    *_ros_etc(),
                ),
                read_mounts=built.mounts,
                work_dir=str(self.run_dir),
            )
            super().__init__(
                target, parameters, sim_topics=sim_topics, sim_frames=sim_frames, limits=limits
            )
            # the package's own topics come back too (PoseArrays, types of its own)
            self.boundary = Ros1BoundaryCheck(self.policy)
        except BaseException:
            self._remove_run_dir()
            raise

    def command(self, fd: int) -> list[str]:
        """The bridge (it writes its output to the run's folder and leads its own session, so
        the graph it starts is one process group). In the kernel sandbox it already has a
        network namespace of its own; without one it gets just that
        (:func:`usar_replay.ros1.netns.isolated_command`)."""
        # -P: the working directory (the run's folder, which the team's processes write) is not
        # put on sys.path: a module planted there is never imported by the bridge
        bridge = ["-P", "-m", "usar_replay.ros1.bridge"]
        cmd = [sys.executable, *bridge, str(fd), str(self._config_path)]
        if self.kernel_sandbox is not None:
            return cmd
        return isolated_command(cmd, isolate=self.options.isolate)

    def send(self, t_ns: int, inputs: Sequence[Wire]) -> None:
        """Before each tick, the run's new threads go onto the graph's CPU (:mod:`.scheduling`)."""
        if self.options.one_cpu:
            if self._one_cpu is None:
                box = self.kernel_sandbox
                cpus = box.cpus if box else None
                self._one_cpu = OneCpu(
                    self.pid,
                    box.cgroup if box else None,
                    cpu=cpus.graph_cpu if cpus else None,
                    realtime=cpus is not None,
                    passes_on=b"usar_replay.ros1.bridge",
                    spares=watcher.MODULE.encode(),
                )
            self._one_cpu.apply()
        super().send(t_ns, inputs)

    def receive(self) -> list[tuple[str, str, bytes, msgs.Message]]:
        """:meth:`MissionProcess.receive`, then the threads the graph made in that tick go onto
        its CPU at once: the next tick may have been sent ahead and be running already
        (:func:`usar_replay.pipeline.record._send_ahead`)."""
        out = super().receive()
        if self._one_cpu is not None:
            self._one_cpu.apply()
        return out

    def close(self) -> None:
        try:
            super().close()
        finally:
            if self._one_cpu is not None:
                self._one_cpu.close()
            # the bridge leads its own process group: whatever of the graph outlived it goes too
            with contextlib.suppress(OSError):
                os.killpg(self.pid, signal.SIGKILL)
            try:
                self._kept = self._collect()
            finally:
                self._remove_run_dir()

    def attachments(self) -> list[tuple[str, str, bytes]]:
        """``ros1.toml`` (the package, how it was started, its nodes, the build time, the
        parameters its nodes read, the settings that applied) and each node's stdout and
        stderr, taken from the run's folder on close (:mod:`.run_files`)."""
        return list(self._kept)

    def _collect(self) -> list[tuple[str, str, bytes]]:
        outputs = run_files.node_outputs(self.run_dir)
        nodes = run_files.launch_nodes(self.run_dir)
        if self.options.node and not self.options.launch:  # rosrun: as registered
            names = run_files.registered_nodes(self.run_dir)
            nodes = [(name, self.package.name, self.options.node) for name in names]
            if len(names) == 1:  # the executable's output is that node's
                outputs = [(file_label(names[0]), data) for _, data in outputs[:1]]
        given = {"/" + key.replace(".", "/"): value for key, value in self.parameters.items()}
        read = [
            ParameterRead(name, _text(given[name]) if name in given else "", tuple(by))
            for name, by in run_files.parameters_read(self.run_dir).items()
        ]
        # what the bridge applied, as its ready frame said it (a file in the run folder is the
        # graph's to rewrite: a forged tolerance would widen the rubric's radii)
        applied = _ready_facts(self.ready_info)
        tolerances = _applied_tolerances(applied, self._robots)
        info = Ros1Run(
            package=self.package.name,
            path=self.target.path,
            sha256=self.target.sha256,
            launch=self.options.launch,
            node=self.options.node,
            after_launch=tuple(self.options.after_launch),
            start_source=self.options.start_source,
            # no build time, nor whether the build was cached: wall facts of this machine's
            # cache, which would make the same run's log differ between its first run and the
            # next (the recorder's summary and a batch's run.json say them)
            nodes=tuple(Ros1Node(*row) for row in nodes),
            replaced=tuple(Ros1Node(*row) for row in run_files.replaced_nodes(self.run_dir)),
            parameters=tuple(read),
            applied_settings=run_files.APPLIED_SETTINGS,
            holds=self.holds,
            # no capped ticks either: which tick ran out of its wall cap is the machine's load
            # (the recorder's summary says them)
        )
        info = dataclasses.replace(
            info,
            # a move_base tolerance setting applied only where the user gave it (nav_params)
            applied_settings=tuple(
                s
                for s in info.applied_settings
                if not s.startswith("mission.") or s in self.options.given_settings
            ),
            goal_tolerances=tuple(GoalTolerance(*row) for row in tolerances),
            targets_replaced=_targets(applied),
            detections_read=self.detections_read,
        )
        kept = [(contract.ROS1_ATTACHMENT, "application/toml", info.to_toml().encode())]
        prefix = contract.NODE_OUTPUT_ATTACHMENT_PREFIX
        kept += [(f"{prefix}{label}.txt", "text/plain", data) for label, data in outputs]
        return kept

    def run_folder(self) -> RunFolder | None:
        """The bridge's run folder (the graph's files, ROS logs included) is the run's."""
        return self._bridge_folder

    def _remove_run_dir(self) -> None:
        self._bridge_folder.close(keep=self.options.keep_workspace)
