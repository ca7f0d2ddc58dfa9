"""The mission process: user code runs in its own process and talks to usar only in messages.

Why a process: a mission is untrusted code (a student's, a team's). In its own process it sees
what a ROS node sees, the messages it subscribes to and its parameters, and never the
simulator, the scenario's marker list or ground truth; its crash, hang or memory blow-up ends
*its* process, and usar records a verdict (``crashed``, ``hung``, ``out_of_memory``) in the log
instead of crashing itself. Live (``usar record``) and in replay the same code path runs: the
parent hands the process one tick at a time (see :mod:`usar_replay.node.executor`) and gets back
what the mission published.

The wire: ``multiprocessing`` pipes carrying bytes the parent parses itself. Inputs go down as
CDR (the log's bytes); outputs come back as (topic, type, CDR) triples that the parent decodes
with usar's own schemas and checks against the :class:`PublishPolicy` again: nothing from the
mission process is ever unpickled. Parent -> child setup data (parameters, the target) is
pickled, which is safe in that direction.

Where: in the kernel sandbox of :mod:`usar_replay.node.jail` (bubblewrap) by default, with the
mission's file's folder read-only, a private work dir as its working directory, no network, no
view of any usar process and a handful of environment variables; the socket to the parent is the
one thing it shares with usar. See :attr:`MissionLimits.jail`.

A crash's traceback is the user's own: the frames of their code are shown, usar's plumbing in
between is left out.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import importlib.util
import multiprocessing.connection
import os
import pickle
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import traceback
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from types import ModuleType
from typing import Any

from usar_replay import __version__
from usar_replay.core import cdr, msgs
from usar_replay.core.errors import MissionEnded, UsageError
from usar_replay.core.finite import NonFiniteValue
from usar_replay.node import hide
from usar_replay.node import kernel_sandbox as jail  # the worker split renames its uses
from usar_replay.node.audit_guard import GuardPolicy as SandboxPolicy
from usar_replay.node.boundary_check import (
    MAX_FRAME_BYTES,
    MAX_MESSAGE_BYTES,
    BoundaryCheck,
    OutputRefused,
    PublishRefused,
)
from usar_replay.node.executor import Executor, PublishPolicy
from usar_replay.node.log_budget import DEFAULT_MAX_LOG_MIB, LogBudget
from usar_replay.node.wire_io import send_within

__all__ = [
    "BUILTIN",
    "MissionEnded",
    "MissionLimits",
    "MissionProcess",
    "MissionTarget",
    "hide_from_mission",
    "resolve_target",
]

BUILTIN = "builtin"
"""``--mission builtin`` (the default): the course's reference mission."""

_TICK, _OUT, _CRASH, _READY, _STOP, _REFUSED = b"T", b"O", b"C", b"R", b"S", b"F"
_USAR_DIR = str(Path(__file__).resolve().parent)

Wire = tuple[str, str, bytes]
"""(topic, ROS 2 type name, CDR bytes)."""


@dataclass(frozen=True, slots=True)
class MissionTarget:
    """What ``--mission`` named: a built-in name, a ``.py`` file, or ``module:attribute``."""

    spec: str
    """As the user gave it (``builtin``, ``team7/mission.py``, ``my_pkg.mission:main``)."""
    module: str
    """The module to import (a file's is loaded under the name ``usar_user_mission``)."""
    attribute: str
    """The callable that creates the nodes (default ``main``)."""
    path: str
    """The source file ('' when the module is not a file)."""
    sha256: str
    """sha256 of the source file: the log says exactly which code ran."""


def resolve_target(spec: str | None) -> MissionTarget:
    """Check ``--mission`` and find its source (a :class:`UsageError` says what is wrong)."""
    spec = (spec or BUILTIN).strip()
    if spec.startswith("ros1:"):
        raise UsageError(
            f"mission {spec!r} is a ROS 1 package: only Python missions are re-run here; "
            "grade its recorded outputs with usar grade, or record it again with --ros1"
        )
    # a reference mission's name (builtin, an assignment's): the assignment's module:function
    from usar_replay.world.assignment import mission_path

    text = mission_path(spec) or spec
    attr = "main"
    if text.endswith(".py") or "/" in text or os.sep in text:
        file_part = text
        if ":" in text and not text.endswith(".py"):
            file_part, attr = text.rsplit(":", 1)
        path = Path(file_part)
        if not path.is_file():
            raise UsageError(f"--mission {spec}: no such file; give a .py file or module:function")
        source = path.read_bytes()
        return MissionTarget(
            spec, "usar_user_mission", attr, str(path.resolve()), hashlib.sha256(source).hexdigest()
        )
    module, _, attr_part = text.partition(":")
    attr = attr_part or "main"
    try:
        found = importlib.util.find_spec(module)
    except (ImportError, ValueError):
        found = None
    if found is None or found.origin is None:
        raise UsageError(
            f"--mission {spec}: cannot find module {module!r}; give a .py file or module:function"
        )
    origin = found.origin
    digest = hashlib.sha256(Path(origin).read_bytes()).hexdigest() if Path(origin).is_file() else ""
    return MissionTarget(spec, module, attr, origin, digest)


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
    sandbox: SandboxPolicy | None = None
    """Files, processes and network the mission may not touch (usar_replay.node.sandbox)."""
    jail: str = "auto"
    """The kernel sandbox (usar_replay.node.jail): ``auto`` uses it when bwrap works here (else
    one warning on stderr, and the environment variable ``USAR_SANDBOX=off`` turns it off),
    ``required`` refuses to start without it (a batch), ``off`` never uses it."""
    read_roots: tuple[str, ...] = ()
    """What the jailed mission may read besides Python (default: its file's folder, or the
    folder its module was found in); a batch gives the team's submission."""
    hidden: tuple[str, ...] = ()
    """Files and folders the jailed mission may not read even when they lie in a readable
    folder (the log being written or replayed, and every file the grader passed in: the
    world, the world key, the settings, the thresholds, the output; :mod:`~usar_replay.node.hide`
    also finds their other hard-linked names)."""
    work_dir: str = ""
    """The jailed mission's writable folder and working directory: default a fresh one,
    removed at close; a given one (the ROS 1 bridge's run folder) is the caller's to remove."""
    max_log_mib: int = DEFAULT_MAX_LOG_MIB
    """The run's byte budget for its log, in MiB (0: none); past it the run is ``refused``
    (:mod:`usar_replay.node.log_budget`)."""


# --- the wire ---------------------------------------------------------------------------------

_HDR = struct.Struct("<qI")
_ITEM = struct.Struct("<HHI")


def _pack(kind: bytes, t_ns: int, items: Sequence[Wire], flag: int = 0) -> bytes:
    parts = [kind, _HDR.pack(t_ns, len(items)), bytes([flag])]
    for topic, msgtype, data in items:
        tb, mb = topic.encode(), msgtype.encode()
        parts += [_ITEM.pack(len(tb), len(mb), len(data)), tb, mb, data]
    return b"".join(parts)


def _unpack(frame: bytes) -> tuple[bytes, int, list[Wire], int]:
    kind = frame[:1]
    t_ns, n = _HDR.unpack_from(frame, 1)
    pos = 1 + _HDR.size
    flag = frame[pos]
    pos += 1
    items: list[Wire] = []
    for _ in range(n):
        lt, lm, ld = _ITEM.unpack_from(frame, pos)
        pos += _ITEM.size
        topic = frame[pos : pos + lt].decode()
        pos += lt
        msgtype = frame[pos : pos + lm].decode()
        pos += lm
        items.append((topic, msgtype, frame[pos : pos + ld]))
        pos += ld
    if pos != len(frame):
        raise ValueError("malformed frame from the mission process")
    return kind, t_ns, items, flag


# --- the child ----------------------------------------------------------------------------------


def _user_traceback(exc: BaseException) -> str:
    """The traceback with usar's own frames left out (the last frame is kept: it says where
    the error was raised, e.g. the publish that was refused)."""
    tb = traceback.extract_tb(exc.__traceback__)
    keep = [f for i, f in enumerate(tb) if not f.filename.startswith(_USAR_DIR) or i == len(tb) - 1]
    lines = ["Traceback (most recent call last):\n", *traceback.format_list(keep)]
    lines += traceback.format_exception_only(type(exc), exc)
    return "".join(lines)


def _load(target: MissionTarget) -> ModuleType:
    if target.module == "usar_user_mission":
        spec = importlib.util.spec_from_file_location(target.module, target.path)
        if spec is None or spec.loader is None:
            raise ImportError(f"cannot load {target.path}")
        module = importlib.util.module_from_spec(spec)
        sys.modules[target.module] = module
        sys.path.insert(0, str(Path(target.path).parent))
        spec.loader.exec_module(module)
        return module
    return importlib.import_module(target.module)


def _limit_memory(mb: int) -> None:
    if mb <= 0:
        return
    with contextlib.suppress(ImportError, ValueError, OSError):
        import resource

        limit = mb * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _limit_cpu(seconds: int) -> None:
    """RLIMIT_CPU: past the soft limit the kernel sends SIGXCPU (the parent's verdict: hung)."""
    if seconds <= 0:
        return
    with contextlib.suppress(ImportError, ValueError, OSError):
        import resource

        resource.setrlimit(resource.RLIMIT_CPU, (seconds, seconds + 5))


def _preload() -> None:
    """Import what the node API and usar's own decoding load lazily, before the sandbox is on:
    numpy's import calls ``ctypes.dlopen``, which the sandbox refuses to a mission, and the
    rosbags typestore (the CDR fallback) reads its definitions from files."""
    import cv2  # noqa: F401 - loaded for the mission's detector
    import numpy  # noqa: F401

    importlib.import_module("usar_replay.api")
    cdr.typestore()


def _child_main(conn: multiprocessing.connection.Connection, setup: dict[str, Any]) -> None:
    """The mission process: load the target, run ``main()``, then serve ticks until told to
    stop. Every failure is reported as text, never raised into the parent."""
    # one thread per library: the mission process shares the machine with usar's own process
    # (replay reads and grades while the mission runs), and OpenCV's thread pool in the ArUco
    # detector costs a third more CPU time than it saves wall time there (2 cores); these are
    # read when the libraries load, so they are set before the user's imports
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("OPENCV_FOR_THREADS_NUM", "1")
    _limit_memory(int(setup["memory_mb"]))
    _limit_cpu(int(setup.get("cpu_s", 0)))
    jail.apply_rlimits(setup.get("rlimits", {}))  # in the sandbox: all of its limits
    target: MissionTarget = setup["target"]
    policy = PublishPolicy(sim_topics=setup["sim_topics"], sim_frames=setup["sim_frames"])
    executor = Executor(setup["parameters"], policy)
    if setup.get("sandbox") is not None:
        _preload()
        setup["sandbox"].install()  # after usar's own imports, before the user's code
    try:
        with executor.activate():
            module = _load(target)
            entry = getattr(module, target.attribute, None)
            if not callable(entry):
                raise AttributeError(
                    f"{target.spec}: no function {target.attribute!r} that creates the nodes"
                )
            entry()
            if not executor.nodes:
                raise RuntimeError(f"{target.spec}: {target.attribute}() created no Node")
            conn.send_bytes(_READY)
            _serve(conn, executor)
    except MemoryError as err:
        _report(conn, b"M", _user_traceback(err))
    except (NonFiniteValue, OutputRefused, PublishRefused) as err:  # refused at the call
        _report(conn, _REFUSED, _user_traceback(err))
    except BaseException as err:  # noqa: BLE001 - the user's error is the verdict, not ours
        _report(conn, _CRASH, _user_traceback(err))


def _report(conn: multiprocessing.connection.Connection, kind: bytes, text: str) -> None:
    with contextlib.suppress(OSError, ValueError):
        conn.send_bytes(kind + text.encode("utf-8", errors="replace"))


def _serve(conn: multiprocessing.connection.Connection, executor: Executor) -> None:
    with executor.activate():
        while True:
            try:
                frame = conn.recv_bytes()
            except EOFError:
                return
            if frame[:1] == _STOP:
                return
            _, t_ns, items, _ = _unpack(frame)
            # decoded one by one as the executor delivers them, and only where a node subscribes
            # (checked at that moment: a callback may subscribe to a topic later in the tick):
            # a message nobody receives costs no decoding, exactly as if it were delivered
            inputs = (
                (topic, cdr.decode(data, msgtype))
                for topic, msgtype, data in items
                if executor.subscription_count(topic)
            )
            # a mission that said it is done runs no more callbacks (live, the run ends there)
            outputs = [] if executor.shutdown_requested else executor.tick(t_ns, inputs)
            wire = [(topic, type(m).__msgtype__, cdr.encode(m)) for topic, m in outputs]
            for topic, msgtype, data in wire:
                if len(data) > MAX_MESSAGE_BYTES:
                    raise OutputRefused(
                        f"a {msgtype} of {len(data)} bytes on {topic}: a message is at most "
                        f"{MAX_MESSAGE_BYTES} bytes (8 MiB)"
                    )
            conn.send_bytes(_pack(_OUT, t_ns, wire, int(executor.shutdown_requested)))


# --- the parent ---------------------------------------------------------------------------------


_warned = False


def _use_jail(limits: MissionLimits) -> bool:
    """Run this mission in the kernel sandbox? (see :attr:`MissionLimits.jail`)"""
    global _warned
    mode = limits.jail
    if mode == "auto" and os.environ.get("USAR_SANDBOX", "").strip().lower() == "off":
        mode = "off"
    if mode == "off":
        return False
    ok, why = jail.bwrap_available()
    if ok:
        return True
    if mode == "required":
        raise UsageError(
            f"{why}: usar will not run untrusted mission code without a kernel sandbox; "
            f"install it ({jail.INSTALL_HINT}) or pass --no-sandbox"
        )
    if not _warned:
        _warned = True
        print(
            f"usar: warning: {why}; the mission runs without a kernel sandbox "
            f"({jail.INSTALL_HINT} to get one; USAR_SANDBOX=off silences this)",
            file=sys.stderr,
        )
    return False


def _module_root(target: MissionTarget) -> str:
    """The folder a module target was found under (its top package's parent)."""
    if not target.path:
        return ""
    path = Path(target.path)
    depth = target.module.count(".") + (2 if path.name == "__init__.py" else 1)
    return str(path.parents[depth - 1]) if len(path.parents) >= depth else ""


def _submission_roots(target: MissionTarget) -> list[str]:
    """What the jailed mission reads by default: its file's folder (helpers next to it), or
    the folder its module was found in; nothing for usar's own missions."""
    if target.module == "usar_user_mission":
        return [str(Path(target.path).parent)]
    if target.module.startswith("usar_replay."):
        return []  # bound with usar's package (its parent may be a whole checkout)
    root = _module_root(target)
    return [root] if root else []


def _mission_env(target: MissionTarget) -> dict[str, str]:
    """The mission's whole environment in the jail: nothing of the caller's but the thread
    settings (and PYTHONHASHSEED, which decides set order in the mission's own code)."""
    path = [str(Path(jail.package_dir()).parent)]
    if target.module != "usar_user_mission" and not target.module.startswith("usar_replay."):
        root = _module_root(target)
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


def hide_from_mission(limits: MissionLimits | None, *paths: str) -> MissionLimits:
    """``limits`` with ``paths`` (the log being written) hidden from the jailed mission."""
    base = limits or MissionLimits()
    return replace(base, hidden=(*base.hidden, *paths))


class MissionProcess:
    """The parent's handle on a mission process. Use as a context manager::

    with MissionProcess(target, parameters, ...) as proc:
        outputs = proc.tick(t_ns, inputs)   # raises MissionEnded on crash / hang / refusal
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
        self._work: str | None = None
        self._own_work = False
        self._jail: jail.Jail | None = None
        policy = self.limits.sandbox
        jailed = _use_jail(self.limits)
        if jailed:
            # the mission's own writable folder (its working directory), removed at close
            self._own_work = not self.limits.work_dir
            self._work = self.limits.work_dir or tempfile.mkdtemp(prefix="usar-mission-")
            if policy is not None:
                policy = replace(
                    policy,
                    write_roots=(*policy.write_roots, self._work),
                    own_roots=(*policy.own_roots, self._work),
                )
            self._jail = jail.Jail(
                jail.JailLimits(memory_mb=self.limits.memory_mb, cpu_s=self.limits.cpu_s)
            )
        self._setup = {
            "target": target,
            "parameters": parameters,
            "sim_topics": tuple(sim_topics),
            "sim_frames": tuple(sim_frames),
            "memory_mb": self.limits.memory_mb,
            "cpu_s": self.limits.cpu_s,
            "rlimits": self._jail.rlimits() if self._jail else {},
            "sandbox": policy,
            "usar_version": __version__,
            "tick_timeout_s": self.limits.tick_timeout_s,
        }
        hidden: list[str] = []
        if self._jail is not None:
            try:  # the grader's files, by any of their names under the mission's folders
                roots = self.limits.read_roots or _submission_roots(target)
                hidden = [*sum(hide.grader_files(self.limits.hidden, roots), ())]
            except BaseException:
                self._cleanup()
                raise
        parent_sock, child_sock = socket.socketpair()
        with child_sock:
            # a fresh interpreter running this module: no fork of usar's state (pybullet, an
            # open log), no re-import of the caller's __main__ (multiprocessing's spawn does);
            # the socket keeps its number through bwrap, which passes inherited descriptors on
            argv = self._argv(child_sock.fileno())
            env: dict[str, str] | None = None
            if self._jail is not None and self._work is not None:
                roots = self.limits.read_roots or _submission_roots(target)
                # bwrap gets the mission's environment too: its init process stays in the
                # sandbox, where /proc/1/environ would show the caller's variables
                env = _mission_env(target)
                argv = jail.jail_argv(
                    argv,
                    ro_binds=[*jail.python_binds(), *roots],
                    work_dir=self._work,
                    env=env,
                    limits=self._jail.limits,
                    hidden=hidden,
                    info_fd=self._jail.info_fd,
                )
            try:
                fds = (child_sock.fileno(), *((self._jail.info_fd,) if self._jail else ()))
                self._proc = subprocess.Popen(
                    self._jail.launch(argv) if self._jail else argv,
                    pass_fds=fds,
                    stdin=subprocess.DEVNULL,
                    env=env,
                )
            except BaseException:
                self._cleanup()
                raise
            if self._jail is not None:
                self._jail.started()
        self._conn = multiprocessing.connection.Connection(parent_sock.detach())
        self._in_flight = 0
        try:
            self._send_frame(pickle.dumps(self._setup), self.limits.startup_timeout_s, "starting")
            self._wait(self.limits.startup_timeout_s, "starting (import and main())")
        except BaseException:
            self.close()
            raise

    def _argv(self, fd: int) -> list[str]:
        """The command that serves the tick protocol on socket ``fd``: here a fresh interpreter
        running this module. Another front end (the ROS 1 bridge,
        :mod:`usar_replay.ros1.process`) starts its own process here."""
        return [sys.executable, "-m", "usar_replay.node.worker", str(fd)]

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
            send_within(self._conn, _STOP, 1.0)  # a peer that reads no more is killed below
        try:
            self._proc.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait(timeout=5.0)
        self._conn.close()
        self._cleanup()

    def _cleanup(self) -> None:
        """Remove the jail's cgroup (killing what is left in it) and the private work dir."""
        if self._jail is not None:
            self._jail.close()
        if self._work is not None:
            if self._own_work:
                shutil.rmtree(self._work, ignore_errors=True)
            self._work = None

    def _died(self, doing: str) -> MissionEnded:
        try:
            code: int | None = self._proc.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            code = None
        signum = jail.signal_of_exit(code) if self._jail else (-code if code and code < 0 else None)
        if signum is not None:
            import signal

            name = (
                signal.Signals(signum).name
                if signum in signal.Signals._value2member_map_
                else signum
            )
            if signum == signal.SIGXCPU:
                return MissionEnded(
                    "hung", f"the mission process used up its CPU-time limit while {doing}"
                )
            if signum == signal.SIGKILL and self._jail is not None and self._jail.oom_killed():
                return MissionEnded(
                    "out_of_memory",
                    f"the kernel's out-of-memory killer ended the mission process ({name}) "
                    f"while {doing}",
                )
            # what happened, and no more: a SIGKILL is not called out of memory unless the
            # kernel's record says so (a ROS 1 node may kill its bridge)
            return MissionEnded(
                "crashed",
                f"crashed (signal {signum}): the mission process was killed by {name} "
                f"while {doing}",
            )
        return MissionEnded("crashed", f"the mission process exited (code {code}) while {doing}")

    def _wait(self, timeout_s: float, doing: str) -> bytes:
        if not self._conn.poll(timeout_s):
            self._proc.kill()
            self._proc.wait()
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
        kind = frame[:1]
        if kind == _CRASH:
            raise MissionEnded("crashed", frame[1:].decode("utf-8", errors="replace"))
        if kind == b"M":
            raise MissionEnded("out_of_memory", frame[1:].decode("utf-8", errors="replace"))
        if kind == _REFUSED:
            raise MissionEnded("refused", frame[1:].decode("utf-8", errors="replace"))
        return frame

    def _refuse(self, reason: str) -> MissionEnded:
        """End the process now (what it sends is not read any more) and say why."""
        self._proc.kill()
        return MissionEnded("refused", reason)

    def send(self, t_ns: int, inputs: Sequence[Wire]) -> None:
        """Hand one tick to the mission without waiting (replay keeps several in flight)."""
        # each tick already in flight may take its own tick timeout before the process reads on
        timeout_s = self.limits.tick_timeout_s * (self._in_flight + 1)
        try:
            self._send_frame(_pack(_TICK, t_ns, inputs), timeout_s, "handling a tick")
        except (BrokenPipeError, ConnectionResetError):
            # the process is gone (a crash while ticks were in flight): its report, if it sent
            # one, is waiting to be read; else say how it died
            if self._conn.poll(0):
                self._wait(0, "handling a tick")
            raise self._died("handling a tick") from None
        self._in_flight += 1
        self.budget.inputs(inputs)

    def _send_frame(self, frame: bytes, timeout_s: float, doing: str) -> None:
        """Write one frame to the process within ``timeout_s`` wall seconds, or end it as
        ``hung``: a process that stops reading its socket must not block the recorder in a
        write (:mod:`usar_replay.node.wire_io`)."""
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
        if frame[:1] != _OUT:
            raise self._refuse(f"the mission process sent a frame of unknown kind {frame[:1]!r}")
        try:
            _kind, _t, items, flag = _unpack(frame)
        except (ValueError, IndexError, struct.error) as err:  # UnicodeDecodeError included
            raise self._refuse(f"the mission process sent a malformed frame ({err})") from None
        try:
            out = self.boundary.check(items)
        except OutputRefused as err:
            raise self._refuse(str(err)) from None
        over = self.budget.outputs(items)
        if over:
            raise self._refuse(over)
        self.shutdown_requested = self.shutdown_requested or bool(flag)
        return out

    def tick(self, t_ns: int, inputs: Sequence[Wire]) -> list[tuple[str, str, bytes, msgs.Message]]:
        """One tick, closed loop (live recording): send and wait for the outputs."""
        self.send(t_ns, inputs)
        return self.receive()


def _child_entry(argv: Sequence[str]) -> None:
    """``python -m usar_replay.node.worker FD``: read the setup from the socket FD, then serve."""
    import signal

    # Ctrl-C, a closed terminal or `kill` of the group reach this process too: the recorder
    # handles them (closing the log, then this process); the mission must not turn one into a
    # "crash" of its own. If the recorder dies, the socket closes and this process ends.
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, signal.SIG_IGN)
    conn = multiprocessing.connection.Connection(int(argv[1]))
    setup = pickle.loads(conn.recv_bytes())  # from the parent, which is trusted
    _child_main(conn, setup)


if __name__ == "__main__":
    _child_entry(sys.argv)
