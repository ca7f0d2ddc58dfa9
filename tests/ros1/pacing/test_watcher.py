"""ros1/pacing/watcher: the idle check in a process of its own, asked over a socket.

Real processes: the watcher is started on this test's process tree (as the bridge starts it
on its own), a busy child keeps the tree from going idle until the cap, and once it is gone
the tree is idle; the watcher leaves itself out of what it watches."""

from __future__ import annotations

import os
import signal
import threading
from pathlib import Path

from proctools import child as start_child
from proctools import wait_for

from usar_replay.ros1.pacing.watcher import Watcher


def test_the_watcher_answers_for_the_tree_and_leaves_itself_out() -> None:
    watcher = Watcher(os.getpid())
    # it writes: a loop with no call at all would count as waiting (test_spinners.py)
    busy = start_child(
        "import os\nfd = os.open(os.devnull, os.O_WRONLY)\nwhile True: os.write(fd, b'x')"
    )
    try:
        io = Path(f"/proc/{busy.pid}/io")
        wait_for(lambda: int(io.read_text().split("syscw:")[1].split()[0]) > 1000, "its loop")
        assert watcher.wait(0.2, launcher=busy.pid, launcher_is_package=True) is False
        assert watcher.kids is not None and busy.pid in watcher.kids[os.getpid()]
        assert watcher.proc.pid in watcher.kids[os.getpid()]  # walked, but not sampled
        assert watcher.samples > 0
        busy.kill()
        busy.wait()
        # this process's threads are blocked on the socket; the watcher itself keeps running
        wait_for(lambda: watcher.wait(1.0), "the tree idle without the busy child")
        assert watcher.long_waits() == []
    finally:
        if busy.poll() is None:
            busy.kill()
            busy.wait()
        watcher.close()
    assert watcher.proc.returncode == 0


def test_a_watcher_that_ended_is_a_clear_error() -> None:
    watcher = Watcher(os.getpid())
    watcher.proc.kill()
    watcher.proc.wait()
    try:
        watcher.wait(0.1)
    except RuntimeError as err:
        assert "idle check" in str(err)
    else:
        raise AssertionError("no error")
    finally:
        watcher.close()


def test_a_starving_watcher_is_moved_back_to_its_cpus() -> None:
    # beside a graph thread spinning at real-time priority on the CPU they share, the watcher
    # would run only in the kernel's throttling window: stopped here, it answers late, and the
    # bridge's side moves it back to the CPUs it started with, then gets its answer
    watcher = Watcher(os.getpid())
    cpus = os.sched_getaffinity(0)
    answers: list[bool] = []
    try:
        watcher.wait(0.5)  # started and answering
        os.sched_setaffinity(watcher.proc.pid, {min(cpus)})  # as OneCpu pins it
        os.kill(watcher.proc.pid, signal.SIGSTOP)
        asking = threading.Thread(target=lambda: answers.append(watcher.wait(0.1)))
        asking.start()
        if len(cpus) > 1:
            wait_for(lambda: watcher.freed, "the late answer noticed")
            assert os.sched_getaffinity(watcher.proc.pid) == cpus
        os.kill(watcher.proc.pid, signal.SIGCONT)
        asking.join(timeout=30)
        assert not asking.is_alive() and len(answers) == 1
        assert watcher.freed == (len(cpus) > 1)
    finally:
        os.kill(watcher.proc.pid, signal.SIGCONT)
        watcher.close()
