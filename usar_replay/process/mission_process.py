"""usar's handle on a mission process: start it, hand it ticks, check what comes back, judge it.

Why a process: a mission is untrusted code (a student's, a team's). In its own process it sees
what a ROS node sees, the messages it subscribes to and its parameters, and never the
simulator, the scenario's marker list or ground truth; its crash, hang or memory blow-up ends
*its* process, and usar records a verdict (``crashed``, ``hung``, ``out_of_memory``,
``refused``) in the log instead of crashing itself. Live (``usar record``) and in replay the
same code path runs: :class:`MissionProcess` hands the process one tick at a time and gets back
what the mission published, as frames of :mod:`usar_replay.process.protocol`. Outputs come back
as (topic, type, CDR) triples that are decoded with usar's own schemas and checked against the
:class:`PublishPolicy` again (:mod:`~usar_replay.node.boundary_check`): nothing from the mission
process is ever unpickled.

Where: in the kernel sandbox (bubblewrap, :mod:`usar_replay.sandbox.kernel_sandbox`) by default,
with the mission's file's folder read-only, a private work dir as its working directory, no
network, no view of any usar process and a handful of environment variables; the socket to the
parent is the one thing it shares with usar (see :attr:`MissionLimits.kernel_sandbox`). Inside
it, the audit guard (:mod:`usar_replay.sandbox.audit_guard`, :attr:`MissionLimits.guard`) watches
what the mission's Python code opens. What runs there is :mod:`usar_replay.process.worker`, or
another program that speaks the protocol (:meth:`MissionProcess.command`: the ROS 1 bridge).

Wall-clock limits only decide verdicts; they never reach a message.
"""

from __future__ import annotations

import collections
import contextlib
import multiprocessing.connection
import os
import pickle
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

from usar_replay import __version__
from usar_replay.core import msgs
from usar_replay.core.errors import MissionEnded, ProtocolMismatch, UsageError
from usar_replay.node.boundary_check import MAX_FRAME_BYTES, BoundaryCheck, OutputRefused
from usar_replay.node.executor import PublishPolicy
from usar_replay.process import protocol
from usar_replay.process.log_budget import DEFAULT_MAX_LOG_MIB, LogBudget
from usar_replay.process.mission_target import MissionTarget
from usar_replay.process.protocol import FrameKind, Wire
from usar_replay.process.wire_io import send_within
from usar_replay.sandbox import confinement, cpu_sets, hide, kernel_sandbox
from usar_replay.sandbox.audit_guard import GuardPolicy
from usar_replay.sandbox.kernel_sandbox import KernelSandbox, SandboxLimits
from usar_replay.sandbox.run_folder import DEFAULT_RUN_FOLDER_MB, RunFolder

__all__ = [
    "DEFAULT_HOLD_WALL_S",
    "DEFAULT_MAX_CAPPED",
    "DEFAULT_MAX_HOLDS",
    "DEFAULT_PROCESSES",
    "DEFAULT_RUN_MEMORY_MB",
    "MissionEnded",
    "MissionLimits",
    "MissionProcess",
    "hide_from_mission",
    "uses_kernel_sandbox",
]


DEFAULT_RUN_MEMORY_MB = 3072
"""The whole run's memory in MiB (``--run-memory-mb``): a ROS 1 graph (master, roslaunch, rosout,
the bridge, the team's nodes) uses well under 1 GiB."""
DEFAULT_PROCESSES = 256
"""Processes and threads of one run (``--processes``)."""
DEFAULT_MAX_HOLDS = 20
"""Shutdown holds of one ROS 1 run (``--max-holds``): an honest package holds once or twice."""
DEFAULT_HOLD_WALL_S = 30.0
"""Wall seconds all of one ROS 1 run's shutdown holds may take together (``--hold-wall``): an
honest package's hold or two take well under a second each."""
DEFAULT_MAX_CAPPED = 600
"""Capped ticks of one ROS 1 run (``--max-capped``): 2 min of wall time at the default pace."""


@dataclass(frozen=True, slots=True)
class MissionLimits:
    """What a mission process may use. Wall-clock limits only decide *verdicts*; they never
    reach a message (a slow machine gives the same log, or a ``hung`` verdict)."""

    tick_timeout_s: float = 10.0
    """Wall seconds one tick's callbacks may take before the mission is declared hung."""
    startup_timeout_s: float = 60.0
    """Wall seconds for importing the mission and running its ``main()``."""
    memory_mb: int = 4096
    """Address-space limit of the mission process (RLIMIT_AS), in MiB; 0 for none."""
    cpu_s: int = 0
    """CPU-time limit of the mission process (RLIMIT_CPU), in seconds; 0 for none. Past it the
    process is killed and the run is ``hung`` (a batch sets it: see usar_replay.batch.plan)."""
    guard: GuardPolicy | None = None
    """The audit guard's policy: files, processes and network the mission's Python code may not
    touch (usar_replay.sandbox.audit_guard); None: no guard."""
    kernel_sandbox: str = "auto"
    """The kernel sandbox (usar_replay.sandbox.kernel_sandbox): ``auto`` uses it when bwrap works
    here (else one warning on stderr, and the environment variable ``USAR_SANDBOX=off`` turns
    it off), ``required`` refuses to start without it (a batch), ``off`` never uses it."""
    read_roots: tuple[str, ...] = ()
    """What the sandboxed mission may read besides Python (default: its file's folder, or the
    folder its module was found in); a batch gives the team's submission."""
    read_mounts: tuple[tuple[str, str], ...] = ()
    """(host folder, path in the sandbox) pairs the sandboxed mission reads at another path
    than the host's (a built ROS 1 workspace: :mod:`usar_replay.ros1.building.layout`);
    read-only."""
    hidden: tuple[str, ...] = ()
    """Files and folders the sandboxed mission may not read even when they lie in a readable
    folder (the log being written or replayed, and every file the grader passed in: the
    world, the world key, the settings, the thresholds, the output; :mod:`~usar_replay.sandbox.hide`
    also finds their other hard-linked names)."""
    work_dir: str = ""
    """The sandboxed mission's writable folder and working directory: default a fresh one,
    removed at close; a given one (the ROS 1 bridge's run folder) is the caller's to remove."""
    max_log_mib: int = DEFAULT_MAX_LOG_MIB
    """The run's byte budget for its log, in MiB (0: none); past it the run is ``refused``
    (:mod:`usar_replay.process.log_budget`)."""
    run_memory_mb: int = DEFAULT_RUN_MEMORY_MB
    """Memory of the whole run in the kernel sandbox, MiB (0: none): every process of it and
    the files it writes to its tmpfs mounts (its memory cgroup); past it: ``out_of_memory``."""
    processes: int = DEFAULT_PROCESSES
    """Processes and threads of the run together (its pids cgroup); reaching it: ``refused``."""
    run_folder_mb: int = DEFAULT_RUN_FOLDER_MB
    """Size of the run's writable folder, MiB (a tmpfs; 0: a plain folder); filling it:
    ``refused`` (:mod:`usar_replay.sandbox.run_folder`)."""
    max_holds: int = DEFAULT_MAX_HOLDS
    """Ticks the ROS 1 bridge may hold for a node's shutdown (each up to 6 s of wall time);
    past it the run is ``hung`` (0: no budget)."""
    max_capped: int = DEFAULT_MAX_CAPPED
    """Ticks whose wall cap may run out before the ROS 1 graph goes idle; past it: ``hung``
    (0: no budget)."""
    hold_wall_s: float = DEFAULT_HOLD_WALL_S
    """Wall seconds the ROS 1 bridge's shutdown holds may take together; past it: ``hung``
    (0: no budget). With :attr:`max_holds`, one hostile team costs at most this much more than
    its sim time."""
    wall_s: float = 0.0
    """Wall seconds for the whole run, start-up included (0: none); past it: ``wall_limit``."""
    cpus: int = 0
    """CPUs of the run's own CPU set (:mod:`usar_replay.sandbox.cpu_sets`; 0: two when free, else
    one). A batch gives each run its share."""


def hide_from_mission(limits: MissionLimits | None, *paths: str) -> MissionLimits:
    """``limits`` with ``paths`` (the log being written) hidden from the sandboxed mission."""
    base = limits or MissionLimits()
    return replace(base, hidden=(*base.hidden, *paths))


def uses_kernel_sandbox(limits: MissionLimits) -> bool:
    """Will a mission under ``limits`` run in the kernel sandbox? (what a ROS 1 build asks
    before it builds: a workspace built for the sandbox's fixed paths runs only there)"""
    return _use_kernel_sandbox(limits)


def _use_kernel_sandbox(limits: MissionLimits) -> bool:
    """Run this mission in the kernel sandbox? (see :attr:`MissionLimits.kernel_sandbox`; the
    one policy: :func:`usar_replay.sandbox.confinement.confined`)"""
    return confinement.confined(limits.kernel_sandbox, warn=True)


def _mission_env(target: MissionTarget) -> dict[str, str]:
    """The mission's whole environment in the kernel sandbox: nothing of the caller's but the
    thread settings (and PYTHONHASHSEED, which decides set order in the mission's own code)."""
    path = [os.path.dirname(kernel_sandbox.package_dir())]
    if not target.is_file and not target.is_usar_module:
        root = target.module_root()
        if root:
            path.append(root)
    env = {
        "PATH": "/usr/local/bin:/usr/bin:/bin",
        "PYTHONPATH": os.pathsep.join(path),
        "LANG": "C.UTF-8",
        "HOME": "/tmp",
        "TMPDIR": "/tmp",
        "PYTHONDONTWRITEBYTECODE": "1",
    }
    for name in ("OMP_NUM_THREADS", "OPENCV_FOR_THREADS_NUM"):
        env[name] = os.environ.get(name, "1")
    if "PYTHONHASHSEED" in os.environ:
        env["PYTHONHASHSEED"] = os.environ["PYTHONHASHSEED"]
    return env


class MissionProcess:
    """The parent's handle on a mission process. Use as a context manager::

    with MissionProcess(target, parameters, ...) as proc:
        outputs = proc.tick(t_ns, inputs)   # raises MissionEnded on crash / hang / refusal

    A front end that runs another program in the mission's place (the ROS 1 bridge,
    :class:`usar_replay.ros1.process.Ros1Process`) overrides :meth:`command`.
    """

    def __init__(
        self,
        target: MissionTarget,
        parameters: dict[str, Any],
        *,
        sim_topics: Sequence[str],
        sim_frames: Sequence[str],
        limits: MissionLimits | None = None,
    ) -> None:
        self.target = target
        self.limits = limits or MissionLimits()
        self.policy = PublishPolicy(sim_topics=sim_topics, sim_frames=sim_frames)
        self.boundary = BoundaryCheck(self.policy)
        self.budget = LogBudget(self.limits.max_log_mib)
        self.shutdown_requested = False
        self.holds = 0
        """Ticks the ROS 1 bridge held for a shutdown (:data:`protocol.FLAG_HELD`)."""
        self.hold_wall_s = 0.0
        """Wall seconds those held ticks took (verdicts only: never reaches a message)."""
        self._sent: collections.deque[float] = collections.deque()
        self._last_read = 0.0
        self.capped = 0
        self.detections_read = False
        """A ROS 1 graph's node subscribed to ``/fiducial_transforms`` in some tick
        (:data:`.protocol.FLAG_DETECTIONS_READ`)."""
        self.ready_info = ""
        """What the process said with its ready frame (:func:`.protocol.ready_frame`)."""
        """Ticks whose wall cap ran out (:data:`protocol.FLAG_CAPPED`)."""
        self._started = time.monotonic()  # verdicts only: never reaches a message
        self._work: str | None = None
        self._own_work = False
        self._folder: RunFolder | None = None
        self._sandbox: KernelSandbox | None = None
        guard = self._prepare_sandbox()
        setup = {
            "protocol_version": protocol.PROTOCOL_VERSION,
            "target": target,
            "parameters": parameters,
            "sim_topics": tuple(sim_topics),
            "sim_frames": tuple(sim_frames),
            "memory_mb": self.limits.memory_mb,
            "cpu_s": self.limits.cpu_s,
            "rlimits": self._sandbox.rlimits() if self._sandbox else {},
            "guard": guard,
            "usar_version": __version__,
            "tick_timeout_s": self.limits.tick_timeout_s,
        }
        self._proc, self._conn = self._start()
        self._in_flight = 0
        try:
            self._send_frame(pickle.dumps(setup), self.limits.startup_timeout_s, "starting")
            self._wait_ready()
        except BaseException:
            self.close()
            raise

    # -- starting ------------------------------------------------------------------------------

    def _prepare_sandbox(self) -> GuardPolicy | None:
        """Make the kernel sandbox's run (cgroups, limits) and the mission's work dir when the
        mission runs sandboxed; the audit guard's policy, which may write the work dir too."""
        guard = self.limits.guard
        if not _use_kernel_sandbox(self.limits):
            return guard
        # the mission's own writable folder (its working directory, a size-limited tmpfs),
        # removed at close
        self._own_work = not self.limits.work_dir
        if self._own_work:
            self._folder = RunFolder("usar-mission-", self.limits.run_folder_mb)
        self._work = self._folder.path if self._folder else self.limits.work_dir
        if guard is not None:
            guard = replace(
                guard,
                write_roots=(*guard.write_roots, self._work),
                own_roots=(*guard.own_roots, self._work),
            )
        # the run's own CPUs, and the recorder's with them (:mod:`.cpu_sets`)
        try:
            cpus = cpu_sets.claim(self.limits.cpus)
        except TimeoutError as err:
            self._cleanup()
            raise UsageError(f"{err}: other usar runs hold every CPU") from None
        if cpus is not None:
            cpus.pin_caller()
        self._sandbox = KernelSandbox(
            SandboxLimits(
                memory_mb=self.limits.memory_mb,
                cpu_s=self.limits.cpu_s,
                processes=self.limits.processes,
                run_memory_mb=self.limits.run_memory_mb,
            ),
            cpus=cpus,
        )
        return guard

    def run_folder(self) -> RunFolder | None:
        """The run's size-limited folder, if it has one (a front end that makes its own, the
        ROS 1 bridge's, returns that)."""
        return self._folder

    def _start(self) -> tuple[subprocess.Popen[bytes], multiprocessing.connection.Connection]:
        """Start :meth:`command` (in the kernel sandbox when there is one) with one end of a
        socket pair: a fresh interpreter, no fork of usar's state (pybullet, an open log), no
        re-import of the caller's ``__main__`` (multiprocessing's spawn does); the socket keeps
        its number through bwrap, which passes inherited descriptors on."""
        try:
            roots = self.limits.read_roots or self.target.submission_roots()
            hidden: list[str] = []
            if self._sandbox is not None:  # the grader's files, by any of their names
                mounted = [src for src, _ in self.limits.read_mounts]
                hidden = [*sum(hide.grader_files(self.limits.hidden, [*roots, *mounted]), ())]
            parent_sock, child_sock = socket.socketpair()
        except BaseException:
            self._cleanup()
            raise
        with child_sock:
            argv = self.command(child_sock.fileno())
            env: dict[str, str] | None = None
            fds: tuple[int, ...] = (child_sock.fileno(),)
            if self._sandbox is not None and self._work is not None:
                # bwrap gets the mission's environment too: its init process stays in the
                # sandbox, where /proc/1/environ would show the caller's variables
                env = _mission_env(self.target)
                argv = self._sandbox.launch(
                    kernel_sandbox.sandbox_argv(
                        argv,
                        ro_binds=[*kernel_sandbox.python_binds(), *roots],
                        work_dir=self._work,
                        env=env,
                        limits=self._sandbox.limits,
                        hidden=hidden,
                        info_fd=self._sandbox.info_fd,
                        ro_mounts=self.limits.read_mounts,
                        seccomp_fd=self._sandbox.seccomp_fd,
                    )
                )
                fds += self._sandbox.fds
            try:
                proc = subprocess.Popen(argv, pass_fds=fds, stdin=subprocess.DEVNULL, env=env)
            except BaseException:
                parent_sock.close()
                self._cleanup()
                raise
            if self._sandbox is not None:
                self._sandbox.started()
        return proc, multiprocessing.connection.Connection(parent_sock.detach())

    def command(self, fd: int) -> list[str]:
        """The command that serves the tick protocol on socket ``fd``: here a fresh interpreter
        running :mod:`usar_replay.process.worker`. Another front end (the ROS 1 bridge,
        :mod:`usar_replay.ros1.process`) starts its own program here; :attr:`kernel_sandbox` is
        already decided when this is asked."""
        return [sys.executable, "-m", "usar_replay.process.worker", str(fd)]

    def _wait_ready(self) -> None:
        """The process's first frame: ready, of this protocol version (else it ends here)."""
        frame = self._wait(self.limits.startup_timeout_s, "starting (import and main())")
        if frame[:1] != FrameKind.READY:
            raise self._refuse(
                f"the mission process sent a frame of kind {frame[:1]!r} before it was ready"
            )
        try:
            self.ready_info = protocol.check_ready(frame)
        except ProtocolMismatch:
            self._proc.kill()  # what it sends is not read any more
            raise

    # -- what others may ask -------------------------------------------------------------------

    @property
    def kernel_sandbox(self) -> KernelSandbox | None:
        """The kernel sandbox's run the process is in (None: it runs without one)."""
        return self._sandbox

    @property
    def pid(self) -> int:
        """The process usar started (bwrap's, in the kernel sandbox)."""
        return self._proc.pid

    def __enter__(self) -> MissionProcess:
        return self

    def attachments(self) -> list[tuple[str, str, bytes]]:
        """Files the process leaves for the log, as (name, media type, bytes), asked once it
        is closed (none for a Python mission; the ROS 1 bridge's: its nodes' output)."""
        return []

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop the process (politely, then for good)."""
        with contextlib.suppress(OSError, ValueError):
            send_within(self._conn, FrameKind.STOP, 1.0)  # one that reads no more is killed
        try:
            self._proc.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait(timeout=5.0)
        self._conn.close()
        self._cleanup()

    def _cleanup(self) -> None:
        """Remove the kernel sandbox's cgroup (killing what is left in it) and the private work
        dir."""
        if self._sandbox is not None:
            self._sandbox.close()
        if self._work is not None:
            if self._folder is not None:
                self._folder.close()
            elif self._own_work:
                shutil.rmtree(self._work, ignore_errors=True)
            self._work = None

    # -- verdicts ------------------------------------------------------------------------------

    def _died(self, doing: str) -> MissionEnded:
        try:
            code: int | None = self._proc.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            code = None
        if self._sandbox is not None:
            signum = kernel_sandbox.signal_of_exit(code)
        else:
            signum = -code if code and code < 0 else None
        if signum is None:
            return MissionEnded(
                "crashed", f"the mission process exited (code {code}) while {doing}"
            )
        name = _signal_name(signum)
        if signum == signal.SIGXCPU:
            return MissionEnded(
                "hung", f"the mission process used up its CPU-time limit while {doing}"
            )
        if signum == signal.SIGKILL and self._sandbox is not None and self._sandbox.oom_killed():
            return MissionEnded(
                "out_of_memory",
                f"the kernel's out-of-memory killer ended the mission process ({name}) "
                f"while {doing}",
            )
        limit = self._limit_reached()
        if limit is not None:
            return limit
        # what happened, and no more: a SIGKILL is not called out of memory unless the
        # kernel's record says so (a ROS 1 node may kill its bridge)
        return MissionEnded(
            "crashed",
            f"crashed (signal {signum}): the mission process was killed by {name} while {doing}",
        )

    def _wait(self, timeout_s: float, doing: str) -> bytes:
        if not self._conn.poll(timeout_s):
            self._proc.kill()
            self._proc.wait()
            # a run-wide limit that killed or refused one of its processes is why the rest
            # waits (a parent blocked on a child the OOM killer ended): that is the verdict
            limit = self._limit_reached()
            if limit is not None:
                raise limit
            raise MissionEnded(
                "hung",
                f"no answer within {timeout_s:g} s of wall time while {doing}: a callback does "
                "not return (an endless loop, a sleep, a wait for a message that cannot come "
                "within the same tick); raise the limit with --tick-timeout",
            )
        try:
            frame = self._conn.recv_bytes(MAX_FRAME_BYTES)
        except (EOFError, OSError):
            if self._conn.closed or not self._conn.readable:  # a frame over the length
                raise self._refuse(
                    f"the mission process sent more than {MAX_FRAME_BYTES} bytes in one frame"
                ) from None
            raise self._died(doing) from None
        verdict = _TEXT_VERDICTS.get(frame[:1])
        if verdict is not None:
            # a node that died of a run-wide limit (a child OOM-killed, a failed fork) crashes
            # the graph: the limit is the verdict
            raise self._limit_reached() or MissionEnded(verdict, protocol.text_of(frame))
        return frame

    def _limit_reached(self) -> MissionEnded | None:
        """The run-wide limit the run reached, as its verdict (None: none). Each is a counter
        the kernel keeps for the run's cgroups or its folder: a few reads per tick."""
        box, lim = self._sandbox, self.limits
        if box is None:
            return None
        if box.oom_killed():
            return MissionEnded(
                "out_of_memory",
                f"the run used up its memory ({lim.run_memory_mb} MiB for all its processes "
                "and the files they write to /tmp, /dev/shm and its folder): the kernel's "
                "out-of-memory killer ended one of its processes",
            )
        if box.tcp_refused():
            return MissionEnded(
                "out_of_memory",
                f"the run's TCP socket buffers reached their limit "
                f"({kernel_sandbox.tcp_limit_mb(lim.run_memory_mb)} MiB, a quarter of its "
                "--run-memory: cgroup v1 counts them apart from the run's memory)",
            )
        if box.processes_refused():
            return MissionEnded(
                "refused",
                f"the run reached its limit of {lim.processes} processes and threads "
                "(the kernel refused a fork)",
            )
        folder = self.run_folder()
        if folder is not None and folder.full():
            return MissionEnded(
                "refused", f"the run filled its folder (its limit is {folder.size_mb} MiB)"
            )
        return None

    def _refuse(self, reason: str) -> MissionEnded:
        """End the process now (what it sends is not read any more) and say why."""
        self._proc.kill()
        return MissionEnded("refused", reason)

    # -- ticks ---------------------------------------------------------------------------------

    def send(self, t_ns: int, inputs: Sequence[Wire]) -> None:
        """Hand one tick to the mission without waiting (replay keeps several in flight)."""
        # each tick already in flight may take its own tick timeout before the process reads on
        timeout_s = self.limits.tick_timeout_s * (self._in_flight + 1)
        frame = protocol.tick_frame(t_ns, inputs)
        try:
            self._send_frame(frame, timeout_s, "handling a tick")
        except (BrokenPipeError, ConnectionResetError):
            # the process is gone (a crash while ticks were in flight): its report, if it sent
            # one, is waiting to be read; else say how it died
            if self._conn.poll(0):
                self._wait(0, "handling a tick")
            raise self._died("handling a tick") from None
        self._in_flight += 1
        self._sent.append(time.monotonic())  # a held tick's wall time (verdicts only)
        self.budget.inputs(inputs)

    def _send_frame(self, frame: bytes, timeout_s: float, doing: str) -> None:
        """Write one frame to the process within ``timeout_s`` wall seconds, or end it as
        ``hung``: a process that stops reading its socket must not block the recorder in a
        write (:mod:`usar_replay.process.wire_io`)."""
        if not send_within(self._conn, frame, timeout_s):
            self._proc.kill()
            self._proc.wait()
            raise MissionEnded(
                "hung",
                f"the mission process did not read its input within {timeout_s:g} s of wall "
                f"time while {doing}: it stopped reading its socket (or a callback does not "
                "return); raise the limit with --tick-timeout",
            )

    def receive(self) -> list[tuple[str, str, bytes, msgs.Message]]:
        """The outputs of the oldest tick in flight: (topic, type, CDR, decoded), checked."""
        frame = self._wait(self.limits.tick_timeout_s, "handling a tick")
        self._in_flight -= 1
        now = time.monotonic()
        sent = self._sent.popleft() if self._sent else now
        took, self._last_read = now - max(sent, self._last_read), now
        if frame[:1] != FrameKind.OUTPUTS:
            raise self._refuse(f"the mission process sent a frame of unknown kind {frame[:1]!r}")
        try:
            _kind, _t, items, flag = protocol.unpack(frame)
        except ValueError as err:
            raise self._refuse(f"the mission process sent a malformed frame ({err})") from None
        try:
            out = self.boundary.check(items)
        except OutputRefused as err:
            raise self._refuse(str(err)) from None
        over = self.budget.outputs(items)
        if over:
            raise self._refuse(over)
        limit = self._limit_reached()
        if limit is not None:
            self._proc.kill()
            raise limit
        self.shutdown_requested = self.shutdown_requested or bool(flag & protocol.FLAG_DONE)
        self.holds += bool(flag & protocol.FLAG_HELD)
        if flag & protocol.FLAG_HELD:
            self.hold_wall_s += took
        self.capped += bool(flag & protocol.FLAG_CAPPED)
        self.detections_read = self.detections_read or bool(flag & protocol.FLAG_DETECTIONS_READ)
        over_time = self._time_budget()
        if over_time is not None:
            self._proc.kill()
            raise over_time
        return out

    def _time_budget(self) -> MissionEnded | None:
        """The run's time budgets (holds, capped ticks, wall time) as a verdict once one is
        used up (None: none is)."""
        lim = self.limits
        if lim.max_holds and self.holds > lim.max_holds:
            return MissionEnded(
                "hung",
                f"the ROS graph held {self.holds} ticks for a shutdown (its budget is "
                f"{lim.max_holds}: --max-holds); a node that forks or waits like ros::shutdown() "
                "every tick never ends",
            )
        if lim.hold_wall_s and self.hold_wall_s > lim.hold_wall_s:
            return MissionEnded(
                "hung",
                f"the ROS graph's shutdown holds took {self.hold_wall_s:.1f} s of wall time in "
                f"{self.holds} ticks (its budget is {lim.hold_wall_s:g} s: --hold-wall); a node "
                "that fakes a shutdown every tick never ends",
            )
        if lim.max_capped and self.capped > lim.max_capped:
            return MissionEnded(
                "hung",
                f"the ROS graph never went idle within its wall cap in {self.capped} ticks "
                f"(its budget is {lim.max_capped}: --max-capped)",
            )
        wall = time.monotonic() - self._started
        if lim.wall_s and wall > lim.wall_s:
            return MissionEnded(
                "wall_limit",
                f"the run took more than {lim.wall_s:g} s of wall time (--wall-limit)",
            )
        return None

    def tick(self, t_ns: int, inputs: Sequence[Wire]) -> list[tuple[str, str, bytes, msgs.Message]]:
        """One tick, closed loop (live recording): send and wait for the outputs."""
        self.send(t_ns, inputs)
        return self.receive()


def _signal_name(signum: int) -> str:
    """``SIGKILL`` for 9; the number itself for one Python has no name for."""
    try:
        return signal.Signals(signum).name
    except ValueError:
        return str(signum)


_TEXT_VERDICTS: dict[bytes, str] = {
    FrameKind.CRASHED: "crashed",
    FrameKind.OUT_OF_MEMORY: "out_of_memory",
    FrameKind.REFUSED: "refused",
}
"""The frames a mission process ends with, and the verdict each one is."""
