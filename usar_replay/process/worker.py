"""The mission process's own side: what runs in the kernel sandbox, loading the user's code and
serving ticks until told to stop.

``python -m usar_replay.process.worker FD``, started by
:class:`usar_replay.process.mission_process.MissionProcess`: read the setup (a pickle from the
parent, which is trusted) from socket FD, set the limits on itself, preload what usar needs
before the audit guard goes on, load the target (:mod:`usar_replay.process.mission_target`), run
its ``main()``, say it is ready, then answer each tick frame with the outputs frame of the
mission's callbacks (:mod:`usar_replay.process.protocol`). Every failure is reported as a frame
with the user's traceback (``crashed``, ``out_of_memory``, ``refused``), never raised.

A crash's traceback is the user's own: the frames of their code are shown, usar's plumbing in
between is left out.
"""

from __future__ import annotations

import contextlib
import importlib
import multiprocessing.connection
import os
import pickle
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from usar_replay.core import cdr
from usar_replay.core.finite import NonFiniteValue
from usar_replay.node.boundary_check import MAX_MESSAGE_BYTES, OutputRefused, PublishRefused
from usar_replay.node.executor import Executor, PublishPolicy
from usar_replay.process import protocol
from usar_replay.process.mission_target import MissionTarget, load
from usar_replay.process.protocol import FrameKind
from usar_replay.sandbox import kernel_sandbox

__all__ = ["main"]

# usar's plumbing a mission's call passes through: the node API, this process, the sandbox
_PACKAGE = Path(__file__).resolve().parents[1]
_USAR_DIRS = tuple(f"{_PACKAGE / layer}/" for layer in ("node", "process", "sandbox"))


def _user_traceback(exc: BaseException) -> str:
    """The traceback with usar's own frames left out (the last frame is kept: it says where
    the error was raised, e.g. the publish that was refused)."""
    tb = traceback.extract_tb(exc.__traceback__)
    last = len(tb) - 1
    keep = [f for i, f in enumerate(tb) if not f.filename.startswith(_USAR_DIRS) or i == last]
    lines = ["Traceback (most recent call last):\n", *traceback.format_list(keep)]
    lines += traceback.format_exception_only(type(exc), exc)
    return "".join(lines)


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
    if setup.get("protocol_version") != protocol.PROTOCOL_VERSION:
        conn.send_bytes(protocol.ready_frame())  # no mission code: the parent says what is wrong
        return
    # one thread per library: the mission process shares the machine with usar's own process
    # (replay reads and grades while the mission runs), and OpenCV's thread pool in the ArUco
    # detector costs a third more CPU time than it saves wall time there (2 cores); these are
    # read when the libraries load, so they are set before the user's imports
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("OPENCV_FOR_THREADS_NUM", "1")
    _limit_memory(int(setup["memory_mb"]))
    _limit_cpu(int(setup.get("cpu_s", 0)))
    kernel_sandbox.apply_rlimits(setup.get("rlimits", {}))  # in the sandbox: all of its limits
    target: MissionTarget = setup["target"]
    policy = PublishPolicy(sim_topics=setup["sim_topics"], sim_frames=setup["sim_frames"])
    executor = Executor(setup["parameters"], policy)
    if setup.get("guard") is not None:
        _preload()
        setup["guard"].install()  # the audit guard: after usar's imports, before the user's
    try:
        with executor.activate():
            module = load(target)
            entry = getattr(module, target.attribute, None)
            if not callable(entry):
                raise AttributeError(
                    f"{target.spec}: no function {target.attribute!r} that creates the nodes"
                )
            entry()
            if not executor.nodes:
                raise RuntimeError(f"{target.spec}: {target.attribute}() created no Node")
            conn.send_bytes(protocol.ready_frame())
            _serve(conn, executor)
    except MemoryError as err:
        _report(conn, FrameKind.OUT_OF_MEMORY, _user_traceback(err))
    except (NonFiniteValue, OutputRefused, PublishRefused) as err:  # refused at the call
        _report(conn, FrameKind.REFUSED, _user_traceback(err))
    except BaseException as err:  # noqa: BLE001 - the user's error is the verdict, not ours
        _report(conn, FrameKind.CRASHED, _user_traceback(err))


def _report(conn: multiprocessing.connection.Connection, kind: FrameKind, text: str) -> None:
    with contextlib.suppress(OSError, ValueError):
        conn.send_bytes(protocol.text_frame(kind, text))


def _serve(conn: multiprocessing.connection.Connection, executor: Executor) -> None:
    with executor.activate():
        while True:
            try:
                frame = conn.recv_bytes()
            except EOFError:
                return
            if frame[:1] == FrameKind.STOP:
                return
            _, t_ns, items, _ = protocol.unpack(frame)
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
            conn.send_bytes(protocol.outputs_frame(t_ns, wire, executor.shutdown_requested))


def main(argv: Sequence[str]) -> None:
    """``python -m usar_replay.process.worker FD``: read the setup from socket FD, then serve."""
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
    main(sys.argv)
