"""Has the package ended? Seen from the process table, not from roslaunch's polling.

Why: roslaunch notices that a node exited by polling every 0.1 s of wall time, so a run that
ended when roslaunch said so ended up to a few ticks later on one recording than on another
(the issue measured 9). The bridge asks the process table instead, right after the graph went
idle in a tick: a package process gone or a zombie (its parent, roslaunch, has not collected it
yet) has exited. Which tick the end counts in is decided by :mod:`.shutdown_watch` (the tick
the shutdown began, held until the processes are gone); the package has ended once every
process seen here has exited. A zombie's exit status is in its ``/proc/<pid>/stat`` (field
52), so a node that died with an error is seen as such without waiting for roslaunch's report.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Collection
from dataclasses import dataclass, field

from usar_replay.ros1.pacing.quiescence import descendants

__all__ = ["ProcWatch"]


def _stat(pid: int, fd: int | None = None) -> tuple[str, int | None] | None:
    """(state, exit status where shown) of a process, None once it is gone; read from ``fd``
    (its ``stat`` file, kept open) when given."""
    try:
        if fd is None:
            with open(f"/proc/{pid}/stat", "rb") as f:
                raw = f.read()
        else:
            raw = os.pread(fd, 4096, 0)
    except OSError:
        return None
    if not raw:
        return None
    fields = raw[raw.rfind(b")") + 2 :].split()
    state = fields[0].decode()
    code = int(fields[49]) if len(fields) > 49 else None  # field 52 of the whole line
    return state, code


@dataclass
class ProcWatch:
    """The processes started under ``launcher`` (the ``roslaunch``/``rosrun`` process);
    ``roslaunch`` itself is not one of the package's (it outlives its nodes)."""

    launcher: int
    launcher_is_package: bool = False
    """True for ``rosrun``: the launcher process is the node."""
    seen: dict[int, str] = field(default_factory=dict)
    """pid -> its command name, every package process seen so far."""
    codes: dict[int, int] = field(default_factory=dict)
    """pid -> exit status (waitpid's encoding) of the ones seen as zombies."""
    exited: set[int] = field(default_factory=set)
    """The ones seen exited (zombies or gone) by :meth:`ended`."""
    _fds: dict[int, int] = field(default_factory=dict, repr=False)
    """pid -> its ``stat`` file, opened when first seen and read again each tick (it keeps
    naming that process: once it is collected the read fails, even if its pid is reused)."""

    def package(self, children: dict[int, list[int]] | None = None) -> list[int]:
        """The package's processes now (the launcher's descendants; with roslaunch, not
        roslaunch itself); from ``children`` (a walk of a tree holding the launcher) when
        given."""
        pids = descendants(self.launcher, children)
        return pids if self.launcher_is_package else pids[1:]

    def update(self, children: dict[int, list[int]] | None = None) -> None:
        """Note the package's processes running now (call once per tick); from ``children``
        (a walk just made) when given."""
        for pid in self.package(children):
            if pid not in self.seen:
                with contextlib.suppress(OSError), open(f"/proc/{pid}/comm") as f:
                    self.seen[pid] = f.read().strip()
                    self._fds[pid] = os.open(f"/proc/{pid}/stat", os.O_RDONLY)

    def ended(self, children: dict[int, list[int]] | None = None) -> bool:
        """True once every package process seen has exited (at least one was seen); the
        processes running now from ``children`` (a walk just made) when given."""
        self.update(children)
        if not self.seen:
            return False
        done = True
        for pid in self.seen:
            if pid in self.exited:
                continue  # once exited, for good
            st = _stat(pid, self._fds.get(pid))
            if st is None:
                self.exited.add(pid)
                self._close(pid)
                continue
            state, code = st
            if state in ("Z", "X"):
                if code is not None:
                    self.codes.setdefault(pid, code)
                self.exited.add(pid)
                self._close(pid)
                continue
            done = False
        return done

    def _close(self, pid: int) -> None:
        fd = self._fds.pop(pid, None)
        if fd is not None:
            with contextlib.suppress(OSError):
                os.close(fd)

    def close(self) -> None:
        """Close the files kept open."""
        for pid in list(self._fds):
            self._close(pid)

    def all_clean(self, besides: Collection[int] = ()) -> bool:
        """Every process seen, ``besides`` those, has exited and was seen as a zombie with
        status 0 (at least one was)."""
        rest = [pid for pid in self.seen if pid not in besides]
        return bool(rest) and all(self.codes.get(pid) == 0 for pid in rest)

    def failures(self) -> list[str]:
        """``name exit N`` (or ``killed by signal N``) for the processes that ended badly."""
        out = []
        for pid, status in sorted(self.codes.items()):
            name = self.seen.get(pid, str(pid))
            if status & 0x7F:
                out.append(f"{name} [pid {pid}] killed by signal {status & 0x7F}")
            elif status >> 8:
                out.append(f"{name} [pid {pid}] exit code {status >> 8}")
        return out
