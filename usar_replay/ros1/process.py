"""The recorder's side of a ROS 1 run: the bridge process takes the mission process's place.

:class:`Ros1Process` is a :class:`usar_replay.node.worker.MissionProcess` whose process is the
bridge (:mod:`usar_replay.ros1.bridge`) instead of a Python mission: the same socket, the same
tick protocol, the same checks on what comes back (a student's ``/tf`` that moves a simulator
frame is ``refused``, a non-finite ``cmd_vel`` too), the same verdicts (a graph that dies is
``crashed`` with its output, one that stops answering is ``hung``). Before the bridge starts,
the package is built in a private workspace; a build that fails is ``build_failed``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import shutil
import signal
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from usar_replay.node.worker import MissionLimits, MissionProcess, MissionTarget, Wire
from usar_replay.ros1.build import Package, build, cached_build, package_sha256
from usar_replay.ros1.isolation import isolated_command
from usar_replay.ros1.scheduling import OneCpu

__all__ = ["Ros1Options", "Ros1Process", "ros1_target"]


@dataclass(frozen=True, slots=True)
class Ros1Options:
    """How the student's graph is started and paced."""

    launch: str = ""
    """A launch file of the package (name or path inside it): ``roslaunch PKG FILE``."""
    node: str = ""
    """An executable of the package: ``rosrun PKG NODE`` (when no launch file is given)."""
    rtf: float = 0.5
    """The slowest pace, a safety net: a tick waits at most ``dt / rtf`` of wall time for the
    graph to go idle (docs/ros1.md, "Pacing"; 0: no cap). The graph sets the pace: a tick ends
    as soon as it is idle."""
    settle_ms: float = 3.0
    """The wall cap is at least this many milliseconds, whatever ``rtf``."""
    connect_timeout_s: float = 60.0
    """Wall seconds the student's graph has to register a node with the master."""
    isolate: bool = True
    """Run the master and the graph in their own network namespace when possible."""
    keep_workspace: bool = False
    """Leave the run's folder (bridge, master and graph output, ROS logs) on disk."""
    cache: bool = True
    """Reuse a workspace built before from the same files (:func:`cached_build`)."""
    one_cpu: bool = True
    """Run the graph's threads on one CPU under SCHED_RR (:mod:`.scheduling`; needs root)."""


_ROS_ETC = ("/etc/catkin", "/etc/ros", "/etc/debian_version", "/etc/hosts", "/etc/nsswitch.conf")


def _ros_etc() -> tuple[str, ...]:
    """What of ``/etc`` the graph reads, bound read-only into the sandbox like ``/usr``:
    Debian's ROS 1 configuration (catkin's environment hooks set ``ROS_PACKAGE_PATH``) and
    name resolution (roslaunch resolves ``localhost``)."""
    return tuple(p for p in _ROS_ETC if Path(p).exists())


def ros1_target(pkg: Package, options: Ros1Options) -> MissionTarget:
    """What the log's ``mission.toml`` says: how the package was started and its sha256."""
    how = f"--launch {options.launch}" if options.launch else f"--node {options.node}"
    return MissionTarget(
        spec=f"ros1:{pkg.path} {how}".strip(),
        module=f"ros1:{pkg.name}",
        attribute=options.launch or options.node,
        path=str(pkg.path.resolve()),
        sha256=package_sha256(pkg),
    )


class Ros1Process(MissionProcess):
    """Build ``package``, then run the bridge as the mission process (see the module doc)."""

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
    ) -> None:
        self.options = options
        self._one_cpu: OneCpu | None = None
        self.run_dir = Path(tempfile.mkdtemp(prefix="usar-ros1-"))
        try:
            if options.cache:
                self.built = cached_build(package)
            else:
                self.built = build(package, self.run_dir / "ws")
            config = {
                "package": package.name,
                "workspace": str(self.built.workspace),
                "run_dir": str(self.run_dir),
            }
            config.update({k: v for k, v in asdict(options).items()})
            self._config_path = self.run_dir / "bridge.json"
            self._config_path.write_text(json.dumps(config), encoding="utf-8")
            # the graph needs time to start: the master, roslaunch, the node's waitForServer
            limits = limits or MissionLimits()
            startup = max(limits.startup_timeout_s, options.connect_timeout_s + 30.0)
            # the bridge and the whole graph it starts run in the kernel sandbox (bubblewrap) as
            # a Python mission does: reading the built workspace, writing only the run's folder,
            # in a network namespace of their own whose loopback carries the ROS traffic
            limits = dataclasses.replace(
                limits,
                startup_timeout_s=startup,
                read_roots=(str(self.built.workspace), *_ros_etc()),
                work_dir=str(self.run_dir),
            )
            super().__init__(
                target, parameters, sim_topics=sim_topics, sim_frames=sim_frames, limits=limits
            )
        except BaseException:
            self._remove_run_dir()
            raise

    def _argv(self, fd: int) -> list[str]:
        """The bridge (it writes its output to the run's folder and leads its own session, so
        the graph it starts is one process group). In the kernel sandbox it already has a
        network namespace of its own; without one it gets just that
        (:func:`usar_replay.ros1.isolation.isolated_command`)."""
        cmd = [sys.executable, "-m", "usar_replay.ros1.bridge", str(fd), str(self._config_path)]
        if self._jail is not None:
            return cmd
        return isolated_command(cmd, isolate=self.options.isolate)

    def send(self, t_ns: int, inputs: Sequence[Wire]) -> None:
        """Before each tick, the run's new threads go onto the graph's CPU (:mod:`.scheduling`)."""
        if self.options.one_cpu:
            if self._one_cpu is None:
                self._one_cpu = OneCpu(self._proc.pid, self._jail.cgroup if self._jail else None)
            self._one_cpu.apply()
        super().send(t_ns, inputs)

    def close(self) -> None:
        try:
            super().close()
        finally:
            # the bridge leads its own process group: whatever of the graph outlived it goes too
            with contextlib.suppress(OSError):
                os.killpg(self._proc.pid, signal.SIGKILL)
            self._remove_run_dir()

    def _remove_run_dir(self) -> None:
        if not self.options.keep_workspace:
            shutil.rmtree(self.run_dir, ignore_errors=True)
