"""The idle check in a process of its own: the bridge waits for its answer, blocked.

Why: the bridge is one Python process, and its own threads are part of the graph (rospy's
queue threads write move_base's result and status, its receiving threads take in what the
nodes publish). Sampled from the bridge's main thread, every sample held the interpreter's
lock (the GIL) that those threads need: the samples had to pause (0.2 ms) between them to let
them run, or a result waiting for the lock looked delivered and the package's reaction moved a
tick from run to run. Here the samples run in a process of their own, with no lock to share
and no pause, while the bridge's main thread is blocked on this socket like any idle thread.

The recorder gives the watcher no real-time priority (:class:`.scheduling.OneCpu`): beside the
graph's ``SCHED_RR`` threads, on their CPU, it runs only when the graph does not (so its first
sample is usually the graph at rest), and without real-time priority it stays off the graph's
CPU where it can.

Protocol: one JSON object per line each way on the socket (both ends are usar's own code, in
the same sandbox; nothing is unpickled). Each wait first finds the tree's processes and threads
again if the run created one since the last wait (:meth:`.Quiescence.created`), then waits.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import socket
import subprocess
import sys
import time
from collections.abc import Collection
from typing import Any

from usar_replay.ros1.pacing.proc_watch import ProcWatch
from usar_replay.ros1.pacing.quiescence import NAP_S, Quiescence

__all__ = ["MODULE", "Watcher", "main"]

MODULE = "usar_replay.ros1.pacing.watcher"
"""What the watcher's command line runs (``python -m``): how :class:`.OneCpu` knows it."""
SPIN_S = 0.002
"""How long the watcher looks for a request it was told comes soon without sleeping."""
LATE_S = 0.2
"""How much later than its cap an answer may come before the watcher counts as starving."""


class Watcher:
    """The bridge's side: starts the watcher on the tree under ``root`` (the bridge's pid)
    and asks it; the answers' details stay as attributes, as on :class:`.Quiescence`."""

    def __init__(self, root: int) -> None:
        mine, theirs = socket.socketpair()
        # blocking, whatever default timeout the caller's process set (rospy sets one, and a
        # socket with a timeout is non-blocking underneath: the watcher read "end of file")
        mine.setblocking(True)
        theirs.setblocking(True)
        mine_inode = os.fstat(mine.fileno()).st_ino
        with theirs:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", MODULE, str(theirs.fileno()), str(root), str(mine_inode)],
                pass_fds=(theirs.fileno(),),
                stdin=subprocess.DEVNULL,
            )
        self._sock = mine
        self._lines = mine.makefile("rb")
        self._cpus = os.sched_getaffinity(0)
        """The CPUs the watcher started with (the run's set): where it goes if it starves."""
        self.freed = False
        """The watcher was moved off the graph's CPU (:meth:`_ask`)."""
        self.untimed: frozenset[int] = frozenset()
        """As :attr:`.Quiescence.untimed`, at the last wait's end."""
        self.connected: frozenset[int] = frozenset()
        """As :attr:`.Quiescence.connected`, at the last wait's end."""
        self.samples = 0
        self.snapshots = 0
        """Waits that ended on one sample (:meth:`.Quiescence.confined`)."""
        self.spun = 0
        """Waits that ended with a spinner counted as waiting (:mod:`.spinners`)."""
        self.spinners = 0
        """Threads moved to ``SCHED_IDLE`` as spinners so far."""
        self.kids: dict[int, list[int]] | None = None
        """The tree's last walk (processes -> their children)."""

    def _ask(self, request: dict[str, Any]) -> dict[str, Any]:
        """One request and its answer. Where the answer is later than the request's cap (and
        :data:`LATE_S`), the watcher is starving: beside a graph thread that spins at real-time
        priority on the CPU they share (a loop no pacing point sees), it runs only when the
        kernel's real-time throttling lets it, 50 ms a second. It is then moved back to the
        CPUs it started with, for good, and the tick ends at its wall cap as it did before the
        watcher shared the graph's CPU."""
        try:
            self._sock.sendall(json.dumps(request).encode() + b"\n")
            cap = request.get("cap")
            if not self.freed and cap is not None and len(self._cpus) > 1:
                ready, _, _ = select.select([self._sock], [], [], float(cap) + LATE_S)
                if not ready:
                    self.free()
            line = self._lines.readline()
        except OSError:
            line = b""
        if not line:
            code = self.proc.poll()
            raise RuntimeError(f"usar's idle check (its watcher process) ended (exit {code})")
        answer: dict[str, Any] = json.loads(line)
        return answer

    def free(self) -> None:
        """Move the watcher back to the CPUs it started with (see :meth:`_ask`)."""
        self.freed = True
        with contextlib.suppress(OSError):
            os.sched_setaffinity(self.proc.pid, self._cpus)

    def wait(
        self,
        cap_s: float | None,
        launcher: int | None = None,
        launcher_is_package: bool = False,
        *,
        soon: bool = False,
    ) -> bool:
        """The tree found again where it changed (the package: ``launcher``'s descendants,
        ``launcher`` itself only when ``launcher_is_package``), then
        :meth:`.Quiescence.wait`. ``soon``: the next wait follows within a fraction of a
        millisecond (the ``/clock`` after the inputs), and the watcher looks for it without
        sleeping (see :func:`serve`)."""
        request = {"op": "wait", "cap": cap_s, "launcher": launcher, "own": launcher_is_package}
        got = self._ask({**request, "soon": soon})
        # what did not change since the last answer is left out of it
        if "untimed" in got:
            self.untimed = frozenset(got["untimed"])
        if "connected" in got:
            self.connected = frozenset(got["connected"])
        self.samples = int(got["samples"])
        self.snapshots = int(got.get("snapshots", 0))
        self.spun = int(got.get("spun", 0))
        self.spinners = int(got.get("spinners", 0))
        if "kids" in got:
            self.kids = {int(k): v for k, v in got["kids"].items()}
        return bool(got["idle"])

    def long_waits(self) -> list[int]:
        """:meth:`.Quiescence.long_waits`."""
        return list(self._ask({"op": "long_waits"})["long"])

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self._sock.sendall(b'{"op": "stop"}\n')
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=2.0)
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        self._lines.close()
        self._sock.close()


def _package(kids: dict[int, list[int]], launcher: int | None, own: bool) -> Collection[int]:
    """The package's processes in the walk (:meth:`.ProcWatch.package`; none before the
    package is launched)."""
    return () if launcher is None else ProcWatch(launcher, own).package(kids)


def serve(sock: socket.socket, root: int, ignore: Collection[int] = ()) -> None:
    """Answer the bridge until it says stop or goes; ``ignore``: the sockets of the pair it
    asks on (they hold nothing while the tree is sampled).

    No pause between samples where another CPU may take them; on the graph's only CPU the
    pause lets the graph run (where it has no real-time priority to come first). Where it has
    another CPU, after a wait asked with ``soon`` the watcher looks for the next request
    without sleeping, for at most :data:`SPIN_S`: a process that sleeps between two requests
    0.1 ms apart is woken from an idle CPU each time (30-50 microseconds on a virtual
    machine, twice a tick)."""
    quiet = Quiescence(root=root, own_pid=os.getpid())
    quiet.ignore = frozenset(ignore)
    own_cpu = len(os.sched_getaffinity(0)) > 1
    nap_s = 0.0 if own_cpu else NAP_S
    lines = sock.makefile("rb")
    told: dict[str, Any] = {}  # what the bridge was last told, by key
    poller = select.poll()
    poller.register(sock.fileno(), select.POLLIN)
    try:
        while True:
            line = lines.readline()
            if not line:
                return
            request = json.loads(line)
            op = request.get("op")
            if op == "wait":
                answer: dict[str, Any] = {}
                if quiet.created():
                    answer["kids"] = quiet.children.walk(root)
                    quiet.refresh(
                        _package(answer["kids"], request["launcher"], request["own"]),
                        answer["kids"],
                    )
                answer["idle"] = quiet.wait(request["cap"], nap_s=nap_s)
                answer["samples"] = quiet.samples
                answer["snapshots"] = quiet.snapshots
                if quiet.spun:
                    answer["spun"] = quiet.spun
                    answer["spinners"] = quiet.spinners.moved
                for key, value in (("untimed", quiet.untimed), ("connected", quiet.connected)):
                    if told.get(key) != value:
                        answer[key] = sorted(value)
                        told[key] = value
            elif op == "long_waits":
                answer = {"long": quiet.long_waits()}
            else:
                return
            sock.sendall(json.dumps(answer).encode() + b"\n")
            if own_cpu and request.get("soon"):
                deadline = time.perf_counter() + SPIN_S  # pacing only: never in a message
                while not poller.poll(0) and time.perf_counter() < deadline:
                    pass
    finally:
        quiet.close()


def main(argv: list[str]) -> None:
    """``python -m usar_replay.ros1.pacing.watcher FD ROOT [PEER_INODE]``."""
    # no real-time priority of its own, whatever it was started with (module docstring)
    with contextlib.suppress(OSError, AttributeError):
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    with socket.socket(fileno=int(argv[0])) as sock, contextlib.suppress(OSError):
        sock.setblocking(True)
        serve(sock, int(argv[1]), {os.fstat(sock.fileno()).st_ino, *map(int, argv[2:3])})


if __name__ == "__main__":
    main(sys.argv[1:])
