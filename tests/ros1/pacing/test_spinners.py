"""ros1/pacing/spinners: a thread spinning with no pausing point counts as waiting after its
allowance of CPU time, reacts within the wait its cause arrived in, and is moved aside.

On real processes: a small C program whose main thread spins on a counter that its second
thread bumps for each byte it reads from stdin, and writes a line when it sees it move (as a
student's ``while (client.getState() != SUCCEEDED) {}`` sees the result that the action
client's thread set). The recordings of a real package: tests/ros1/pacing/test_busy_wait.py.
"""

from __future__ import annotations

import os
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from proctools import child as start_child
from proctools import wait_for

from usar_replay.ros1.pacing.quiescence import Quiescence, ThreadState, _still
from usar_replay.ros1.pacing.spinners import Spinners, spin_key

SPINNER_C = r"""
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <unistd.h>

static atomic_int bumped;

static void* reader(void* arg) {
  (void)arg;
  char c;
  while (read(0, &c, 1) == 1) atomic_fetch_add(&bumped, 1);
  _exit(0);
}

int main(void) {
  pthread_t t;
  pthread_create(&t, 0, reader, 0);
  int seen = 0;
  for (;;) {  // no call while nothing moves: a busy wait the pacing shim never sees
    int now = atomic_load_explicit(&bumped, memory_order_relaxed);
    if (now != seen) {
      seen = now;
      char line[32];
      int n = snprintf(line, sizeof line, "saw %d\n", now);
      write(1, line, n);
    }
  }
}
"""


@pytest.fixture
def spinner(tmp_path: Path) -> Iterator[subprocess.Popen[bytes]]:
    """:data:`SPINNER_C` built and started, its output in ``tmp_path / "out"``."""
    (tmp_path / "spin.c").write_text(SPINNER_C, encoding="utf-8")
    subprocess.run(["gcc", "-O1", "-o", "spin", "spin.c", "-lpthread"], cwd=tmp_path, check=True)
    with (tmp_path / "out").open("wb") as out:
        proc = subprocess.Popen([str(tmp_path / "spin")], stdin=subprocess.PIPE, stdout=out)
    try:
        yield proc
    finally:
        proc.kill()
        proc.wait()
        if proc.stdin is not None:
            proc.stdin.close()


def _quiet(pid: int) -> Quiescence:
    quiet = Quiescence(own_tid=threading.get_native_id())
    wait_for(lambda: pid in quiet.refresh() and len(os.listdir(f"/proc/{pid}/task")) == 2, "it")
    quiet.refresh(package=[pid])
    return quiet


def test_the_key_is_voluntary_switches_reads_writes_and_page_faults() -> None:
    status = b"Name:\tx\nvoluntary_ctxt_switches:\t7\nnonvoluntary_ctxt_switches:\t90\n"
    io = b"rchar: 1\nwchar: 2\nsyscr: 3\nsyscw: 4\nread_bytes: 0\n"
    stat = b"12 (a (b) c) R 1 12 12 0 -1 4194304 50 0 2 0 9 1 0 0 20 0 1 0 100 0 0"
    assert spin_key(status, io, stat) == (7, 3, 4, 52)  # minflt 50 + majflt 2
    assert spin_key(b"", io, stat) is None


def test_a_silent_spinner_counts_as_waiting_and_reacts_in_the_wait_its_cause_came_in(
    spinner: subprocess.Popen[bytes], tmp_path: Path
) -> None:
    quiet = _quiet(spinner.pid)
    try:
        assert quiet.wait(5.0)  # not the cap: idle, the spinner counted as waiting
        assert quiet.spun >= 1
        # moved aside once it spun its allowance: at real-time priority on the graph's one
        # CPU it would hold that CPU from the thread that sets what it waits for
        policy = os.sched_getscheduler(spinner.pid) & ~os.SCHED_RESET_ON_FORK
        assert policy == os.SCHED_IDLE
        assert spinner.stdin is not None
        for n in range(1, 6):
            spinner.stdin.write(b"x")
            spinner.stdin.flush()
            assert quiet.wait(5.0)
            # what it waited for came in this wait: it has seen it and said so, every time
            assert (tmp_path / "out").read_text().splitlines()[-1] == f"saw {n}"
    finally:
        quiet.close()


def test_a_busy_loop_that_writes_is_no_spinner_and_the_cap_ends_the_wait() -> None:
    child = start_child(
        "import os\nfd = os.open(os.devnull, os.O_WRONLY)\nwhile True: os.write(fd, b'x')"
    )
    try:
        quiet = _quiet_one(child.pid)
        wait_for(lambda: _writes(child.pid) > 1000, "its loop")  # past its start-up
        assert not quiet.wait(0.1)
        assert quiet.spun == 0 and not quiet.spinners.demoted
    finally:
        child.kill()
        child.wait()


def _writes(pid: int) -> int:
    """The write calls ``pid`` made so far."""
    return int(Path(f"/proc/{pid}/io").read_text().split("syscw:")[1].split()[0])


def _quiet_one(pid: int) -> Quiescence:
    quiet = Quiescence(own_tid=threading.get_native_id())
    wait_for(lambda: pid in quiet.refresh(), "the child")
    quiet.refresh(package=[pid])
    return quiet


def test_the_allowance_is_counted_from_the_first_reading_that_moved() -> None:
    """A thread's ``schedstat`` on another CPU lags by up to a scheduler tick: CPU time counts
    from a reading that moved, which was exact when taken."""
    spin = Spinners(allowance_s=0.001)
    key = (1, 2, 3, 0)
    got, _ = spin.update({7: (1_000_000, key)})
    assert got == frozenset()  # a run seen once: not yet a candidate
    got, _ = spin.update({7: (1_000_000, key)})
    assert got == {7}
    spin.based({7: 1_000_000})
    spin.update({7: (1_500_000, key)})  # the anchor: 1.5 ms
    assert spin.short_s({7}, {7: 1_500_000}) == pytest.approx(0.001, abs=1e-9)
    spin.update({7: (2_600_000, key)})
    assert spin.short_s({7}, {7: 2_600_000}) <= 0
    got, _ = spin.update({7: (2_700_000, (2, 2, 3, 0))})  # it blocked once: a new run
    assert got == frozenset()
    spin.update({})  # blocked now
    got, _ = spin.update({7: (2_800_000, (2, 2, 3, 0))})
    assert got == frozenset()


TICKER_C = SPINNER_C.replace(
    "int main(void) {\n  pthread_t t;\n  pthread_create(&t, 0, reader, 0);",
    """static void* ticker(void* arg) {  // a tf2 listener's thread: a 10 ms wait, for nothing
  (void)arg;
  pthread_mutex_t m = PTHREAD_MUTEX_INITIALIZER;
  pthread_cond_t c = PTHREAD_COND_INITIALIZER;
  pthread_mutex_lock(&m);
  for (;;) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    ts.tv_nsec += 10000000;
    if (ts.tv_nsec >= 1000000000) { ts.tv_sec += 1; ts.tv_nsec -= 1000000000; }
    pthread_cond_timedwait(&c, &m, &ts);
  }
}

int main(void) {
  pthread_t t, u;
  pthread_create(&t, 0, reader, 0);
  pthread_create(&u, 0, ticker, 0);""",
).replace("#include <unistd.h>", "#include <time.h>\n#include <unistd.h>")


@pytest.mark.slow
def test_a_thread_waking_on_its_own_timeout_leaves_the_spinners_allowance_running(
    tmp_path: Path,
) -> None:
    """Issue 51: a spinner beside a thread that wakes every 10 ms of wall time for nothing (a
    tf2 listener's) counts as waiting once it spun its allowance (50 ms of CPU, five of its
    wakes) and still reacts in the wait its cause came in; the thread's wait is noted as a
    timer (:func:`test_a_wake_for_nothing_keeps_the_base_and_a_wake_that_read_does_not`, in the
    fast suite, holds the rule itself).

    Slow (``-m slow``, on CPUs nothing else wants): the spinner, once moved aside, is
    ``SCHED_IDLE`` and runs only where its CPUs have nothing else to run, as in a run's own CPU
    set. Beside the fast suite's other worker it got no CPU and every wait reached its cap
    (failed in 2 of 2 suite runs and in 3 of 3 runs beside three busy loops on 2 CPUs; passed
    3 of 3 alone)."""
    (tmp_path / "tick.c").write_text(TICKER_C, encoding="utf-8")
    subprocess.run(["gcc", "-O1", "-o", "tick", "tick.c", "-lpthread"], cwd=tmp_path, check=True)
    with (tmp_path / "out").open("wb") as out:
        proc = subprocess.Popen([str(tmp_path / "tick")], stdin=subprocess.PIPE, stdout=out)
    quiet = Quiescence(own_tid=threading.get_native_id())
    try:
        wait_for(
            lambda: proc.pid in quiet.refresh() and len(os.listdir(f"/proc/{proc.pid}/task")) == 3,
            "it",
        )
        quiet.refresh(package=[proc.pid])
        quiet.spinners = Spinners(allowance_s=0.05)
        assert quiet.wait(10.0)  # not the cap
        assert quiet.spun >= 1 and quiet.spinners.demoted
        quiet.wait(10.0)
        timers = [t.last.timer for t in quiet._threads.values() if t.last is not None]
        assert sum(timer is not None for timer in timers) == 1  # the ticker's, not the reader's
        assert proc.stdin is not None
        for n in range(1, 4):
            proc.stdin.write(b"x")
            proc.stdin.flush()
            assert quiet.wait(10.0)
            assert (tmp_path / "out").read_text().splitlines()[-1] == f"saw {n}"
    finally:
        quiet.close()
        proc.kill()
        proc.wait()
        if proc.stdin is not None:
            proc.stdin.close()


def test_a_wake_for_nothing_keeps_the_base_and_a_wake_that_read_does_not() -> None:
    """:func:`_still` beside a spinner: a thread back in the same timed wait, having read,
    written and faulted nothing, woke on its timeout; one that read (a message came) or waits
    on another futex reacted; without a spinner any run counts, as before."""
    spinner = ThreadState(True, 10, False, True, 5_000_000, (1, 2, 3, 4))
    timer = (0x7F00, 8, 4, 57)
    base = {1: spinner, 2: ThreadState(False, 5, False, True, 100, timer=timer)}
    woke = {1: spinner, 2: ThreadState(False, 6, False, True, 120, timer=timer)}
    assert _still(base, woke, {1}, woke_ok=True)
    assert not _still(base, woke, {1})
    read = {1: spinner, 2: ThreadState(False, 6, False, True, 120, timer=(0x7F00, 9, 4, 57))}
    assert not _still(base, read, {1}, woke_ok=True)
    other = {1: spinner, 2: ThreadState(False, 6, False, True, 120, timer=(0x7F08, 8, 4, 57))}
    assert not _still(base, other, {1}, woke_ok=True)
    untimed = {1: spinner, 2: ThreadState(False, 6, False, True, 120)}
    assert not _still(base, untimed, {1}, woke_ok=True)
