"""ros1/quiescence: when the graph has finished reacting to a tick, on real processes."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
from proctools import child as start_child
from proctools import wait_for

from usar_replay.ros1.pacing.quiescence import Quiescence


def test_a_thread_polling_the_clock_must_wake_before_the_graph_is_idle() -> None:
    # 10 ms naps, as roscpp's ros::Time::waitForValid: idle only once it woke and slept again
    child = start_child("import time\nwhile True: time.sleep(0.01)")
    try:
        quiet = Quiescence(own_tid=threading.get_native_id())
        wait_for(lambda: len(quiet.refresh()) > 1, "the child")
        quiet.refresh(package=[child.pid])
        wait_for(lambda: quiet.threads()[child.pid].polling, "the child's nap")
        before = quiet.threads()[child.pid].runs
        assert quiet.wait(5.0)
        assert quiet.threads()[child.pid].runs > before
    finally:
        child.kill()
        child.wait()


def test_a_busy_graph_is_not_idle_and_the_cap_ends_the_wait() -> None:
    # it writes: no spinner (a loop with no call at all counts as waiting: test_spinners.py)
    child = start_child(
        "import os\nfd = os.open(os.devnull, os.O_WRONLY)\nwhile True: os.write(fd, b'x')"
    )
    try:
        quiet = Quiescence(own_tid=threading.get_native_id())
        wait_for(lambda: len(quiet.refresh()) > 1, "the child")
        quiet.refresh(package=[child.pid])
        io = Path(f"/proc/{child.pid}/io")
        wait_for(lambda: int(io.read_text().split("syscw:")[1].split()[0]) > 1000, "its loop")
        assert not quiet.wait(0.05)
    finally:
        child.kill()
        child.wait()


def test_bytes_in_a_socket_of_the_graph_keep_it_busy() -> None:
    import socket

    a, b = socket.socketpair()
    with a, b:
        quiet = Quiescence(own_tid=threading.get_native_id())
        quiet.refresh()
        a.sendall(b"x")  # an unknown socket with bytes: the tree's sockets are looked up
        assert quiet.sockets_waiting() >= 1
        b.recv(1)
        already = quiet.sockets_waiting()  # what this test process has waiting elsewhere
        a.sendall(b"unread")
        assert quiet.sockets_waiting() == already + 6
        assert not quiet.wait(0.02)
        b.recv(16)
        assert quiet.sockets_waiting() == already


def test_a_main_thread_joining_a_thread_is_noted_as_in_an_untimed_wait() -> None:
    # ros::shutdown joins roscpp's threads so
    # (:mod:`usar_replay.ros1.pacing.shutdown_watch`); a main
    # thread in timed naps is not
    joining = start_child(
        "import threading\nt = threading.Thread(target=threading.Event().wait)\nt.start()\nt.join()"
    )
    napping = start_child("import time\nwhile True: time.sleep(0.01)")
    try:
        quiet = Quiescence(own_tid=threading.get_native_id())
        wait_for(lambda: len(quiet.refresh()) > 2, "the children")
        package = [joining.pid, napping.pid]
        quiet.refresh(package)

        def noted() -> bool:
            quiet.refresh(package)
            quiet.threads()
            return joining.pid in quiet.untimed

        wait_for(noted, "the join")
        assert napping.pid not in quiet.untimed
        quiet.refresh([napping.pid])  # only the package's processes are looked at
        quiet.threads()
        assert joining.pid not in quiet.untimed
    finally:
        for c in (joining, napping):
            c.kill()
            c.wait()


def test_one_walk_of_the_tree_answers_for_any_process_in_it() -> None:
    import os
    import signal

    from usar_replay.ros1.pacing.quiescence import children_map, descendants

    parent = start_child(
        "import subprocess, sys, time\n"
        "subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)'])\n"
        "time.sleep(60)"
    )
    try:
        wait_for(lambda: len(descendants(parent.pid)) == 2, "the grandchild")
        me = os.getpid()
        kids = children_map(me)
        assert descendants(me, kids) == descendants(me)
        below = descendants(parent.pid, kids)  # a process inside the walk, no /proc read
        assert below == descendants(parent.pid) and below[0] == parent.pid and len(below) == 2
        os.kill(below[1], signal.SIGKILL)
    finally:
        parent.kill()
        parent.wait()


def test_the_walk_with_files_kept_open_sees_children_come_and_go() -> None:
    import os

    from usar_replay.ros1.pacing.quiescence import ChildrenFiles, children_map

    me = os.getpid()
    with ChildrenFiles() as files:
        before = files.walk(me)
        assert before == children_map(me)
        kid = start_child("import time; time.sleep(60)")
        try:
            now = files.walk(me)  # the same open files, read again
            assert kid.pid in now[me] and now == children_map(me)
        finally:
            kid.kill()
            kid.wait()
        assert kid.pid not in files.walk(me)[me]


def test_a_runnable_thread_anywhere_ends_the_quiet_readings() -> None:
    """With a thread runnable anywhere, every thread is read in full (``syscall``): a thread
    that has not run since the last sample might be one woken and waiting for a CPU."""
    busy = start_child("while True: pass")
    try:
        quiet = Quiescence(own_tid=threading.get_native_id())
        wait_for(lambda: len(quiet.refresh()) > 1, "the child")
        wait_for(lambda: not quiet._nothing_runnable(), "a runnable thread in the load average")
        quiet.refresh([busy.pid])
        wait_for(lambda: quiet.threads()[busy.pid].running, "the busy child seen running")
    finally:
        busy.kill()
        busy.wait()


def test_one_sample_is_enough_only_for_a_real_time_tree_on_the_askers_only_cpu() -> None:
    """The watcher's case (:meth:`Quiescence.confined`): the tree real-time on the CPU the
    asking thread alone may use; a wait then ends on one sample. A tree thread allowed
    elsewhere could run while the asker reads: two samples again."""
    import os

    import pytest

    child = start_child("import time; time.sleep(600)")
    mine = os.sched_getaffinity(0)
    cpu = max(mine)
    try:
        quiet = Quiescence(root=child.pid)
        wait_for(lambda: quiet.refresh() == [child.pid], "the child")
        tids = [int(t) for t in os.listdir(f"/proc/{child.pid}/task")]
        assert not quiet.confined()  # an ordinary process on any CPU
        try:
            for tid in tids:
                os.sched_setaffinity(tid, {cpu})
                os.sched_setscheduler(tid, os.SCHED_RR, os.sched_param(1))
        except PermissionError:
            pytest.skip("real-time priority needs root (CAP_SYS_NICE)")
        os.sched_setaffinity(0, {cpu})
        quiet.created()  # the tree as found now (as the watcher asks before each wait)
        quiet.refresh()
        assert quiet.confined()
        assert quiet.wait(5.0) and quiet.snapshots == 1
        os.sched_setaffinity(tids[0], mine)  # the child may run beside the asker now
        quiet.refresh()
        assert not quiet.confined()
        samples = quiet.samples
        assert quiet.wait(5.0) and quiet.snapshots == 1 and quiet.samples >= samples + 2
    finally:
        os.sched_setaffinity(0, mine)
        child.kill()
        child.wait()


def test_a_confined_tree_is_read_quietly_while_the_machine_is_busy_elsewhere(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The recorder renders the next tick on the run's other CPU while the watcher samples
    (``record.actuation_latency_ticks``): the machine is never quiet then. A tree real-time on
    the asker's only CPU still has no thread waiting for a CPU while the asker runs, so a
    thread that has not run since its last reading keeps it (one ``schedstat`` read, no
    ``syscall``); without that confinement the same busy machine gets full readings."""
    import os

    mine = os.sched_getaffinity(0)
    if len(mine) < 2:
        pytest.skip("needs a second CPU for the busy process")
    cpu = max(mine)
    child = start_child("import time; time.sleep(600)")
    busy = start_child("while True: pass")
    real_pread = os.pread
    try:
        quiet = Quiescence(root=child.pid)
        wait_for(lambda: quiet.refresh() == [child.pid], "the child")
        try:
            for tid in (int(t) for t in os.listdir(f"/proc/{child.pid}/task")):
                os.sched_setaffinity(tid, {cpu})
                os.sched_setscheduler(tid, os.SCHED_RR, os.sched_param(1))
        except PermissionError:
            pytest.skip("real-time priority needs root (CAP_SYS_NICE)")
        os.sched_setaffinity(busy.pid, mine - {cpu})
        os.sched_setaffinity(0, {cpu})
        quiet.created()
        quiet.refresh()
        assert quiet.confined()
        wait_for(lambda: not quiet._nothing_runnable(), "the busy process in the load average")
        first = quiet.threads(confined=True)  # full readings: none before
        syscall = {t.syscall for t in quiet._threads.values()}
        reads: list[int] = []

        def counted(fd: int, n: int, offset: int) -> bytes:
            reads.append(fd)
            return real_pread(fd, n, offset)

        monkeypatch.setattr(os, "pread", counted)
        assert quiet.threads(confined=True) == first
        assert reads and not syscall & set(reads)  # schedstat only
        reads.clear()
        quiet.threads()  # the machine is busy, and nothing says the tree is confined
        assert syscall & set(reads)
    finally:
        monkeypatch.undo()
        os.sched_setaffinity(0, mine)
        for proc in (child, busy):
            proc.kill()
            proc.wait()
