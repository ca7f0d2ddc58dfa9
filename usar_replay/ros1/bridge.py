"""The ROS 1 bridge: the mission process's place, held by a ROS 1 graph.

``python -m usar_replay.ros1.bridge FD CONFIG.json``, started by
:class:`usar_replay.ros1.process.Ros1Process` (in its own network namespace where possible).
To the recorder it speaks the mission process's tick protocol (:mod:`usar_replay.process.protocol`)
on socket FD; to the student's graph it is what the course's ``multiple_robots.launch`` starts:

* a private ROS master on a port of its own, the parameters as the course's launch sets them
  (``/aruco_lookup_locations/target_k`` as ``[x, y]``, ``/use_sim_time`` true, and usar's
  ``/explorer/home``, ``/follower/home``, ``/mission/*``, ``/detector/*``);
* Gazebo's and the robots' topics, from the simulator's tick: ``/clock``, ``/tf``,
  ``/tf_static`` and ``/map`` (latched), ``/explorer/odom``, ``/follower/odom``, the camera as
  ``sensor_msgs/Image`` on ``/explorer/camera/rgb/image_raw`` (and its ``compressed`` and
  ``camera_info``);
* aruco_detect: ``/fiducial_transforms`` as the tick brings it, from the course's detector that
  the recorder runs on every camera frame (trusted: :mod:`usar_replay.pipeline.course_detector`);
* move_base: ``/explorer/move_base`` and ``/follower/move_base`` (:mod:`.move_base`), with the
  goal tolerances the package's move_base launch sets (:mod:`.nav_params`);
* amcl: ``/explorer/amcl_pose`` and ``/follower/amcl_pose`` (:mod:`.amcl`), on motion as the
  package's amcl launch sets ``update_min_d``/``update_min_a``.

What the graph publishes on ``/tf``, ``/tf_static``, ``/explorer/cmd_vel``, ``/follower/cmd_vel``
and ``/rosout`` goes back to the recorder as the mission's outputs of the tick it reacted to.

Pacing: the graph paces the clock. One tick is: publish its messages, wait until the graph
has taken them in (actionlib's publishers write from rospy's queue threads), then ``/clock`` (so
a node woken by the clock finds the tick's data already there), then wait until the graph is
idle (:mod:`.quiescence`; at most ``dt / rtf`` of wall time, a safety net), then hand back what
arrived, sorted by (topic, node). ``/clock`` never runs ahead: the next tick starts only after
the recorder has the outputs. It starts only once the graph is connected and idle
(:mod:`.graph_start`). A node's shutdown lands in the tick it began: roscpp's
``ros::shutdown`` plays out on wall time (a join of a thread that looks every 100 ms, then the
unregistrations), so once a tick shows a sign of one (a main thread entering a wait without a
timeout, a process exited, a connection closed and its node unregistered) that tick holds
until the processes shutting down have exited and roslaunch collected them
(:mod:`.shutdown_watch`); the run ends in that tick when the package as a whole ended, once the
process table shows it gone (:mod:`.proc_watch`). The recorder runs the graph on one CPU under
SCHED_RR (:mod:`.scheduling`). With these, two recordings of a package that does not read the
wall clock are identical, its end and the nodes' screen output included (docs/ros1.md,
"Pacing").

This module is the start-up and the tick loop; the rest is one job a module: the student's
processes (:mod:`.graph`), what the simulator publishes and ``/clock`` (:mod:`.publishing`),
what the graph publishes (:mod:`.receiving`), the graph's own topics (:mod:`.topic_recorder`),
move_base (:mod:`.move_base`) and when ``/clock`` may move (:mod:`.pacing`).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import importlib
import json
import multiprocessing.connection
import os
import pickle
import signal
import socket
import subprocess
import sys
import time
import traceback
import xmlrpc.client
from pathlib import Path
from typing import TYPE_CHECKING, Any

from usar_replay.core import contract, msgs
from usar_replay.process.protocol import (
    FLAG_CAPPED,
    FLAG_DETECTIONS_READ,
    FLAG_HELD,
    FrameKind,
    outputs_frame,
    ready_frame,
    text_frame,
    unpack,
)
from usar_replay.process.wire_io import send_within
from usar_replay.ros1 import launch_filter, nav_params, run_files
from usar_replay.ros1.amcl import AmclPose
from usar_replay.ros1.building import standins
from usar_replay.ros1.building.debian import DIST_PACKAGES
from usar_replay.ros1.building.workspace import catkin_env
from usar_replay.ros1.graph import Graph, launch_target, tail
from usar_replay.ros1.pacing.graph_start import (
    launch_listing,
    missing_connections,
    registered_nodes,
    wait_until_ready,
)
from usar_replay.ros1.pacing.shutdown_watch import ShutdownWatch, node_pids
from usar_replay.ros1.pacing.watcher import Watcher
from usar_replay.ros1.receiving import Inbox
from usar_replay.ros1.topic_recorder import TopicRecorder, wire_item
from usar_replay.sandbox import kernel_sandbox
from usar_replay.world.nav import GoalLimits

if TYPE_CHECKING:
    from usar_replay.ros1.publishing import Publishing

__all__ = ["main"]

NODE = "/usar_sim"
"""The bridge's node name (what the graph sees as Gazebo, map_server, aruco_detect, move_base)."""
CONSOLE_FORMAT = "[${severity}] [${node}]: ${message}"
"""rosconsole's and rospy's screen format in the graph (``ROSCONSOLE_FORMAT``): no time."""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _ros_param(key: str) -> str:
    """``aruco_lookup_locations.target_1`` -> ``/aruco_lookup_locations/target_1``."""
    return "/" + key.replace(".", "/")


def _xmlrpc_value(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_xmlrpc_value(v) for v in value]
    return value


class Bridge:
    """One run's ROS 1 side (see the module docstring)."""

    def __init__(
        self,
        conn: multiprocessing.connection.Connection,
        setup: dict[str, Any],
        config: dict[str, Any],
    ) -> None:
        self.conn = conn
        # every write to the recorder ends by this deadline: a socket nobody reads (a node that
        # took it) must not block the bridge for good (usar_replay.process.wire_io)
        self.write_timeout_s = float(setup.get("tick_timeout_s", 10.0))
        self.config = config
        self.parameters: dict[str, Any] = setup["parameters"]
        self.rtf = float(config["rtf"])  # the run's limits (--rtf)
        self.settle_s = float(config.get("settle_ms", 3.0)) / 1000.0
        run = Path(config["run_dir"])
        self.port = _free_port()
        self.uri = f"http://127.0.0.1:{self.port}/"
        self.env = catkin_env()
        self.env.update(
            ROS_MASTER_URI=self.uri,
            ROS_IP="127.0.0.1",
            ROS_HOME=str(run / "ros_home"),
            ROS_LOG_DIR=str(run / "ros_log"),
            PYTHONUNBUFFERED="1",
            # the nodes' screen lines without rosconsole's ${time} (wall time, then sim time):
            # their output, kept in the log, is the same on every recording (rospy reads it too)
            ROSCONSOLE_FORMAT=CONSOLE_FORMAT,
            **standins.COURSE_ENV,  # as a course machine's shell has it
        )
        os.environ.update(
            {k: self.env[k] for k in ("ROS_MASTER_URI", "ROS_IP", "ROS_HOME", "ROS_LOG_DIR")}
        )
        # usar's underlays only (its fiducial_msgs): never the team's workspace, whose devel
        # space its CMake writes (a planted rospy/__init__.py there ran inside this process and
        # rewrote what it reports: issue 44); the team's processes get it from its setup.bash
        for space in map(Path, config.get("underlays", ())):
            sys.path.insert(0, str(space / "devel" / "lib" / "python3" / "dist-packages"))
        if str(DIST_PACKAGES) not in sys.path:
            sys.path.append(str(DIST_PACKAGES))  # after usar's own numpy and OpenCV
        self.master: subprocess.Popen[bytes] | None = None
        self.graph: Graph | None = None
        self.move_base: dict[str, Any] = {}
        self.amcl: dict[str, AmclPose] = {}
        self.out: Publishing
        """The simulator's side of the graph (:mod:`.publishing`; made in :meth:`start`)."""
        self.inbox = Inbox(NODE)
        """What the graph publishes (:mod:`.receiving`)."""
        self.last_t: int | None = None
        self.robots = [r for r in contract.ROBOTS if contract.odom(r) in setup["sim_topics"]]
        # the graph's own topics, recorded; asked of the master when its call log grew
        self.topics = TopicRecorder(NODE, self.uri, run / run_files.MASTER_LOG)
        self.sim_topics: list[str] = list(setup["sim_topics"])
        self.quiet: Watcher | None = None
        self.capped = 0
        """Ticks whose wall cap ran out before the graph went idle (a repeatability warning)."""
        self.holds = 0
        """Ticks held for a shutdown; both counts go to the recorder with each tick's outputs
        (:data:`usar_replay.process.protocol.FLAG_HELD`, ``FLAG_CAPPED``), which budgets them."""
        self.waited_s = 0.0
        """Wall seconds spent waiting for the graph to go idle (the bridge's log says)."""
        self._master: Any = None
        self._package_nodes: set[str] = set()
        """The package's nodes registered when /clock started (to see their ros::shutdown)."""
        self._node_pids: dict[str, int] = {}
        self._left: set[str] = set()
        """Package nodes seen unregistered."""
        self._exited: set[int] = set()
        """Package processes seen exited by the end of the last tick."""
        self._before_clock: frozenset[int] = frozenset()
        """Package processes that had exited when ``/clock`` started (roslaunch's helpers)."""
        self._connected: frozenset[int] = frozenset()
        self._cap: float | None = None
        self.shutdown = ShutdownWatch(collected_by_launcher=bool(config.get("launch")))
        self.ready_info = ""
        """What the ready frame tells the recorder: the goal tolerances applied and the
        targets replaced (JSON; :meth:`_configure_stand_ins`)."""

    # -- start-up -------------------------------------------------------------------------------

    def start(self) -> None:
        """The master, the parameters, the student's graph, then the bridge's node; returns
        once the graph is ready for the first ``/clock`` (or raises with its output).

        What overlaps, on the run's two CPUs: the master starts while this process imports
        what its node needs (rospy, the navigator's SciPy: half a second), and roslaunch starts
        the package's nodes while the bridge's node comes up (its ``/clock``, topics and
        move_base servers). A node up before them is connected to them by the master's
        ``publisherUpdate``, and the start-up gate (:meth:`_wait_for_graph`) holds ``/clock``
        until every subscription is connected and the graph idle, whichever came first. The
        parameters are set before the graph starts (a ``rosrun`` node reads them at once)."""
        ws = Path(self.config["run_dir"])
        # the launch file's node names (roslaunch --nodes, half a second of parsing) are only
        # needed by the start-up gate: asked while the master and the bridge's node start
        names = concurrent.futures.ThreadPoolExecutor(max_workers=1)
        expected: concurrent.futures.Future[tuple[list[str], dict[str, Any] | None]] | None = None
        if self.config.get("launch"):
            plan = self._write_launch_plan(ws)
            setup = f'source "{self.config["workspace"]}/devel/setup.bash"'
            pkg, launch = launch_target(self.config)
            expected = names.submit(launch_listing, setup, pkg, launch, self.env, plan)
        names.shutdown(wait=False)
        # every call logged (getParam included): ``usar info`` lists the parameters the
        # package's nodes read (:func:`.run_files.parameters_read`)
        logged = ["--master-logger-level", "debug", f"__log:={ws / run_files.MASTER_LOG}"]
        with (ws / "master.log").open("wb") as log:
            self.master = subprocess.Popen(
                ["rosmaster", "--core", "-p", str(self.port), *logged],
                env=self.env,
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
            )
        from usar_replay.ros1.publishing import Publishing  # the navigator's SciPy

        importlib.import_module("rospy")
        self.out = Publishing(self.move_base)
        master = xmlrpc.client.ServerProxy(self.uri)
        deadline = time.monotonic() + 20.0
        while True:
            try:
                master.getPid(NODE)
                break
            except OSError as err:
                if time.monotonic() > deadline or self.master.poll() is not None:
                    text = tail(ws / "master.log")
                    raise RuntimeError(f"the ROS master did not start: {text}") from err
                time.sleep(0.01)
        master.setParam(NODE, "/use_sim_time", True)
        for key, value in sorted(self.parameters.items()):
            if value is not None and key != "use_sim_time":
                master.setParam(NODE, _ros_param(key), _xmlrpc_value(value))
        self.graph = Graph(self.config, self.env)
        self._start_node()
        self.out.advertise(self.sim_topics, self.robots)
        self.quiet = Watcher(os.getpid())
        wanted, facts = ([], None) if expected is None else expected.result()
        self._configure_stand_ins(facts)
        self._wait_for_graph(master, wanted, float(self.config["connect_timeout_s"]))

    def _write_launch_plan(self, run: Path) -> Path:
        """The plan roslaunch follows (:mod:`.launch_filter`): usar's stand-ins' nodes dropped,
        the parameters usar set above winning over the launch file's."""
        params = {
            _ros_param(k): _xmlrpc_value(v) for k, v in self.parameters.items() if v is not None
        }
        params["/use_sim_time"] = True
        plan = launch_filter.plan(
            standins.REPLACED,
            standins.WORLD_NAMESPACES,
            params,
            str(run / run_files.REPLACED_FILE),
            course_targets=standins.COURSE_TARGETS,
            facts=True,
            package=str(self.config["package"]),
            robots=self.robots,
        )
        path = run / run_files.LAUNCH_PLAN
        path.write_text(json.dumps(plan, sort_keys=True), encoding="utf-8")
        return path

    def _start_node(self) -> None:
        """The bridge's node: ``/clock``, the subscribers, each robot's move_base."""
        import rospy

        from usar_replay.ros1.latched import one_connection_per_publisher

        one_connection_per_publisher()  # rospy's racing connects: one run's bytes (:mod:`.latched`)
        rospy.init_node(NODE.lstrip("/"), disable_signals=True)
        self.out.advertise_clock()
        self.inbox.subscribe(self.robots)
        from usar_replay.ros1.move_base import MoveBase

        # the template's tolerances until the launch file's are known (_configure_stand_ins)
        for robot in self.robots:
            self.move_base[robot] = MoveBase(
                robot, xy_tolerance=nav_params.TEMPLATE_XY, yaw_tolerance=nav_params.TEMPLATE_YAW
            )
            self.amcl[robot] = AmclPose(robot)

    def _configure_stand_ins(self, facts: dict[str, Any] | None) -> None:
        """move_base's goal tolerances and amcl's thresholds as the package's launch files set
        them (the node listing printed them on its stdout: :mod:`.nav_params`), before the
        first goal can arrive; the recorder's ``ros1.toml`` says what was applied, as the ready
        frame tells it (:attr:`ready_info`), never from a file the graph could rewrite."""
        given = nav_params.given_tolerances(self.parameters, self.config.get("given_settings", ()))
        applied = nav_params.goal_tolerances(facts, self.robots, given)
        for robot, xy, yaw, source in applied:
            mb = self.move_base[robot]
            mb.xy_tolerance, mb.yaw_tolerance = xy, yaw
            inscribed, inflation, tolerance, why = nav_params.goal_limits(facts, robot)
            mb.goal_limits = GoalLimits(
                inscribed_m=inscribed,
                inflation_m=inflation,
                default_tolerance_m=tolerance,
                source=why,
            )
            print(f"usar move_base {robot}: xy {xy:g} m, yaw {yaw:g} rad ({source})", flush=True)
        self.ready_info = json.dumps(
            {
                "goal_tolerances": [list(row) for row in applied],
                "targets": (facts or {}).get("targets", []),
            },
            sort_keys=True,
        )
        for robot in self.robots:
            d, a = nav_params.amcl_thresholds(facts, robot)
            self.amcl[robot].update_min_d, self.amcl[robot].update_min_a = d, a

    def _wait_for_graph(self, master: Any, expected: list[str], timeout_s: float) -> None:
        """Hold ``/clock`` until the graph is ready (:func:`.graph_start.wait_until_ready`)."""
        graph, quiet = self.graph, self.quiet
        assert graph is not None and quiet is not None

        def alive() -> None:
            ended = graph.exit_status()
            if ended is not None:
                raise RuntimeError(
                    f"{graph.what} ended (exit {ended[0]}) before it connected:\n" + graph.tail()
                )
            graph.watch.update()

        def idle(cap_s: float) -> bool:
            return self._wait_idle(cap_s)

        try:
            wait_until_ready(master, NODE, expected, idle, alive, timeout_s)
            # the graph's own topics, subscribed and connected while /clock holds (recorded)
            if self.topics.discover():
                self.topics.wait_connected(5.0)
            # the start time on /clock before the first tick: a node that waits for a valid
            # sim time before it builds its clients (ros::Time::waitForValid) builds them now,
            # and their subscriptions connect here, while /clock holds, not during the run
            # (roscpp negotiates a new subscription on its XML-RPC thread's 100 ms wall-clock
            # poll, so a connection made in a tick lands in a tick the machine decides)
            self.out.publish_clock(contract.START_TIME_NS)
            wait_until_ready(master, NODE, expected, idle, alive, timeout_s)
            # and each move_base's status (rospy's status timer runs on sim time, first at
            # 0.2 s): an action client's waitForServer, which re-checks on a 500 ms wall-clock
            # timeout when a status finds it not yet connected, is done before tick 1
            for mb in self.move_base.values():
                mb.server.publish_status()
            wait_until_ready(master, NODE, expected, idle, alive, timeout_s)
            # a client still re-checking on a wall-clock timeout gets up to 2 s to be done
            deadline = time.monotonic() + 2.0
            while quiet.long_waits() and time.monotonic() < deadline:
                for mb in self.move_base.values():
                    mb.server.publish_status()
                wait_until_ready(master, NODE, expected, idle, alive, timeout_s)
            after = [str(c) for c in self.config.get("after_launch", ())]
            if after:  # the TA's third terminal, once the graph is up; held until it acted
                graph.run_after_launch(after)
                wait_until_ready(master, NODE, expected, idle, alive, timeout_s)
                if self.topics.discover():
                    self.topics.wait_connected(5.0)
                wait_until_ready(master, NODE, expected, idle, alive, timeout_s)
            self._master = master
            self._package_nodes = registered_nodes(master, NODE)
            self._node_pids = node_pids(master, NODE, self._package_nodes)
            self._connected = quiet.connected
            self.shutdown.starting(quiet.untimed)
            graph.watch.ended()  # processes that came and went before tick 1 are no sign
            self._exited = set(graph.watch.exited)
            self._before_clock = frozenset(self._exited)
        except RuntimeError as err:
            if "ended (exit" in str(err):
                raise
            raise RuntimeError(f"{graph.what}: {err}:\n" + graph.tail()) from None

    def tick(self, t_ns: int, items: list[tuple[str, str, bytes]]) -> list[tuple[str, Any]]:
        """Publish one tick, wait for the graph, return the outputs (usar values)."""
        if self.topics.discover():
            # a topic the graph just advertised: connected before this tick's /clock, so what
            # it latched arrives in this tick whatever the machine's speed
            self.topics.wait_connected(self.settle_s + 2.0)
        if self.topics.registered:
            self._wait_connections()
        self.out.publish_inputs(items)
        poses = {r: self.out.pose(r, t_ns) for r in self.robots}
        # amcl's estimate, with the tick's simulator topics (before /clock)
        located: list[tuple[str, msgs.Message]] = []
        for robot in self.robots:
            estimate = self.amcl[robot].tick(t_ns, poses[robot])
            if estimate is not None:
                self.out.publish_own(self.amcl[robot].topic, estimate)
                located.append((self.amcl[robot].topic, estimate))
        settled: list[tuple[str, msgs.Message]] = []
        driven: list[tuple[str, msgs.Message]] = []
        for robot in self.robots:
            before, after = self.move_base[robot].tick(t_ns, poses, self.out.in_map)
            settled += before
            driven += after
        dt = 0.0 if self.last_t is None else (t_ns - self.last_t) / 1e9
        self.last_t = t_ns
        # the graph paces the clock: the tick ends when the graph is idle (:mod:`.quiescence`);
        # the wall cap (dt / rtf) is a safety net for a graph that never goes idle
        cap = self._cap = max(self.settle_s, dt / self.rtf) if self.rtf > 0 else None
        # the tick's messages delivered and taken in before /clock: actionlib's publishers
        # (move_base's result, status, feedback) write from rospy's queue threads, so without
        # this wait a result could reach a node after it saw the new time, or before, as the
        # machine's timing decides (its reaction then lands a tick later on one run)
        idle = self._wait_idle(cap, soon=True)
        self.out.publish_clock(t_ns)
        if not (self._wait_idle(cap) and idle):
            self.capped += 1
        # what arrived within the tick in a fixed order: by topic, then publishing node
        got = self.inbox.take(self.topics.take())
        # a goal's end first: real move_base publishes its zero velocity before the result
        # (resetState(), then setSucceeded), so a command the package sends when it learns
        # of the result (a one-shot spin on SUCCEEDED) is the robot's last one (issue #32).
        # The active goal's command last: when the package also commands a robot move_base
        # drives, move_base's command is the one the robot follows (what team 002 saw) and the
        # rubric's cmd_vel_one_publisher line reports the fight
        return located + settled + got + driven

    def _wait_connections(self, cap_s: float = 5.0) -> None:
        """Hold this tick's ``/clock`` until every subscription of the graph is connected to
        every publisher of its topic (:func:`.graph_start.missing_connections`), at most
        ``cap_s`` wall seconds. Why: a node registered a topic in the last tick (an action
        client built mid-run), and roscpp makes the connection on its XML-RPC thread's 100 ms
        wall-clock poll, so without this the machine decided the tick it landed in (and with
        it, the tick an action client first saw its server's status: 0.2 s apart from run to
        run)."""
        deadline = time.monotonic() + cap_s  # pacing only: never reaches a message
        while True:
            try:
                if not missing_connections(self._master, NODE):
                    break
            except (OSError, xmlrpc.client.Error):
                break  # the master is going: the tick's end says what happened
            if time.monotonic() > deadline:
                self.capped += 1  # counted against --max-capped, as a tick past its cap
                break
            time.sleep(0.002)
        self._wait_idle(self._cap if self._cap is not None else 2.0)  # what connecting set off

    def _wait_idle(self, cap: float | None, *, soon: bool = False) -> bool:
        """Until the graph is idle (:mod:`.quiescence`, asked of :mod:`.watcher`; True), at
        most ``cap`` wall seconds; ``soon``: another wait follows at once."""
        assert self.quiet is not None and self.graph is not None
        watch = self.graph.watch
        waited = time.perf_counter()  # pacing only: never reaches a message
        idle = self.quiet.wait(cap, watch.launcher, watch.launcher_is_package, soon=soon)
        self.waited_s += time.perf_counter() - waited
        return idle

    # -- the loop -------------------------------------------------------------------------------

    def serve(self) -> None:
        if not send_within(self.conn, ready_frame(self.ready_info), self.write_timeout_s):
            return
        while True:
            try:
                frame = self.conn.recv_bytes()
            except (EOFError, OSError):
                return
            if frame[:1] == FrameKind.STOP:
                return
            _, t_ns, items, _ = unpack(frame)
            capped, holds = self.capped, self.holds
            outputs = self.tick(t_ns, items)
            assert self.graph is not None
            ended = self._ended()
            done = 0
            if ended is not None:
                code, problem = ended
                if code != 0 or problem:
                    self._crash(
                        f"{self.graph.what} ended (exit {code}): {problem or 'see its output'}\n"
                        + self.graph.tail()
                        + f"\nthe ROS graph ended: {problem or f'exit code {code}'}"
                    )
                    return
                done = 1
            wire = [wire_item(topic, m) for topic, m in outputs]
            done |= FLAG_HELD if self.holds > holds else 0
            done |= FLAG_CAPPED if self.capped > capped else 0
            done |= FLAG_DETECTIONS_READ if self.topics.subscribed(contract.FIDUCIALS) else 0
            if not send_within(self.conn, outputs_frame(t_ns, wire, done), self.write_timeout_s):
                return

    def _ended(self) -> tuple[int, str] | None:
        """None while the package runs; (exit code, problem) in the tick its shutdown began
        (:mod:`.shutdown_watch`), held until the process table shows its processes gone
        (:mod:`.proc_watch`), not when roslaunch's polling notices."""
        graph, quiet = self.graph, self.quiet
        assert graph is not None and quiet is not None
        ended = graph.exit_status()
        if ended is not None:
            return ended
        watch = graph.watch
        gone = watch.ended(quiet.kids)  # the walk of this tick's last wait
        # signs of a shutdown in this tick, none of which costs a system call: a main thread
        # that entered a wait without a timeout (roscpp's join at ros::shutdown), a package
        # process that exited, a connection that closed (then the master is asked which nodes
        # unregistered: some ms, only in such a tick)
        shutting = self.shutdown.starting(quiet.untimed)
        exits = watch.exited - self._exited
        closed = self._connected - quiet.connected
        if closed and self._package_nodes:
            left = self._package_nodes - registered_nodes(self._master, NODE)
            shutting |= {self._node_pids[n] for n in left - self._left if n in self._node_pids}
            self._left |= left
        if not (shutting or exits):
            self._connected = quiet.connected
            return None if not gone else self._exit_code()
        # hold /clock until the shutdown has played out: the processes exited and roslaunch
        # collected them (and acted: a required node's death stops the launch)
        held = self.shutdown.hold(shutting | exits, poll=watch.ended)
        self.holds += 1
        print(
            f"usar shutdown hold at {self.last_t or 0} ns: pids {list(held.pids)}, exited "
            f"{list(held.exited)}, {held.wall_s * 1000:.0f} ms{' (capped)' if held.capped else ''}",
            flush=True,
        )
        self._wait_idle(self._cap)
        self.shutdown.starting(quiet.untimed)  # what the hold changed is this tick's
        self._connected = quiet.connected
        gone = watch.ended()
        self._exited = set(watch.exited)
        if not gone:
            stopping = graph.launcher_stopping()
            if not stopping and registered_nodes(self._master, NODE) & self._package_nodes:
                return None  # a node ended, the package goes on
            # the package as a whole ends (its nodes unregistered, or roslaunch stops it): the
            # rest of its processes (rosout, the nodes roslaunch stops) exit on wall time
            deadline = time.monotonic() + 10.0
            while not watch.ended() and time.monotonic() < deadline:
                if graph.exit_status() is not None:
                    break
                time.sleep(0.002)
        return self._exit_code()

    def _exit_code(self) -> tuple[int, str]:
        """The ended package's (exit code, problem)."""
        assert self.graph is not None
        failures = self.graph.watch.failures()
        if failures:
            return 1, failures[0]
        # every process that ran at /clock seen exiting with status 0, and roslaunch has
        # reported no death (of a process gone before /clock: roslaunch's helpers, a node):
        # nothing its exit can add, a third of a second later
        if self.graph.watch.all_clean(self._before_clock) and not self.graph.death_reported():
            return 0, ""
        # all exited cleanly as far as the table showed (a zombie collected before it was
        # seen shows no status): roslaunch's report of a death, once it has seen it, decides
        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline and self.graph.exit_status() is None:
            time.sleep(0.02)
        return self.graph.exit_status() or (0, "")

    def _crash(self, text: str) -> None:
        with contextlib.suppress(OSError, ValueError):
            send_within(self.conn, text_frame(FrameKind.CRASHED, text), 1.0)

    def stop(self) -> None:
        if self.quiet is not None:
            print(
                f"usar pacing: {self.quiet.samples} samples ({self.quiet.snapshots} waits on "
                f"one, {self.quiet.spun} with {self.quiet.spinners} spinning threads counted "
                f"as waiting), {self.capped} ticks capped, "
                f"{self.waited_s:.1f} s waiting for the graph, {self.shutdown.summary()}",
                flush=True,
            )
            self.quiet.close()
        if self.graph is not None:
            self.graph.stop()
        # no rospy.signal_shutdown(): it unregisters every topic with the master, call by
        # call, for a second or two; the master goes, and main() ends the process
        if self.master is not None and self.master.poll() is None:
            self.master.kill()  # it keeps nothing: the run's folder goes with it
            self.master.wait()


def main(argv: list[str]) -> None:
    """``python -m usar_replay.ros1.bridge FD CONFIG``: set up, serve ticks, clean up."""
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, signal.SIG_IGN)  # the recorder ends this process, not a Ctrl-C
    with contextlib.suppress(OSError):
        os.setsid()  # one process group with the graph: the recorder kills it as one
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    conn = multiprocessing.connection.Connection(int(argv[1]))
    setup = pickle.loads(conn.recv_bytes())  # from the recorder, which is trusted
    # the run's limits (memory, CPU, file size, open files) before the graph starts: every
    # process of it inherits them (in the kernel sandbox; empty without one)
    kernel_sandbox.apply_rlimits(setup.get("rlimits", {}))
    config = json.loads(Path(argv[2]).read_text(encoding="utf-8"))
    # rospy's and the master's chatter go to the run's folder, not the user's terminal
    log = os.open(Path(config["run_dir"]) / "bridge.log", os.O_WRONLY | os.O_CREAT | os.O_APPEND)
    os.dup2(log, 1)
    os.dup2(log, 2)
    os.close(log)
    bridge = Bridge(conn, setup, config)
    try:
        bridge.start()
        bridge.serve()
    except BaseException as err:  # noqa: BLE001 - reported to the recorder as the verdict
        text = str(err) if isinstance(err, RuntimeError) else traceback.format_exc()
        with contextlib.suppress(OSError, ValueError):
            send_within(conn, text_frame(FrameKind.CRASHED, text), 1.0)
    finally:
        bridge.stop()
        # rospy's and actionlib's threads would keep the interpreter up until the recorder's
        # kill, 2 s later: the run is over, so end now
        sys.stdout.flush()
        os._exit(0)


if __name__ == "__main__":
    main(sys.argv)
