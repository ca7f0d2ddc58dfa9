"""Red team: run-wide limits and time budgets (issue #33, points 1, 6 and 7).

Each attack is a tiny mission run through the real recorder in the kernel sandbox: a node that
asks for every CPU and looks for the cgroup files (its CPU set holds), a memory hog spread over
three children, ``/dev/shm`` and ``/tmp`` (the run's memory cgroup ends it ``out_of_memory``),
a fork bomb (the pids cgroup: ``refused``), a disk filler (the run folder's tmpfs: ``refused``),
a process that flags every tick a shutdown hold or a capped tick (the budget: ``hung``), and a
run past its wall limit (``wall_limit``). Each ends in a closed log. The SCHED_RR test starts a
real process in a claimed CPU set, gives it real-time priority as the recorder does, and shows
its children and new threads do not inherit it.

Needs bubblewrap and root (cgroups, tmpfs): skipped where either is missing. Each run is a few
seconds of sim time; the limits are small so that each attack ends within a few ticks.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import one_room
from proctools import wait_for

from usar_replay.core import msgs
from usar_replay.core.settings import RunSettings
from usar_replay.log.run import open_run
from usar_replay.pipeline.record import RecordResult, record
from usar_replay.process.mission_process import MissionLimits
from usar_replay.ros1.pacing.scheduling import OneCpu
from usar_replay.sandbox import cpu_sets
from usar_replay.sandbox.kernel_sandbox import (
    KernelSandbox,
    SandboxLimits,
    bwrap_available,
    python_binds,
    sandbox_argv,
)

_OK, _WHY = bwrap_available()
pytestmark = pytest.mark.skipif(
    not _OK or os.geteuid() != 0, reason=f"needs bubblewrap and root: {_WHY or 'not root'}"
)
RUN = RunSettings(record=dataclasses.replace(RunSettings().record, max_sim_time_s=3.0))


def _record(tmp_path: Path, source: str, **limits: object) -> tuple[Path, RecordResult]:
    mission = tmp_path / "attack.py"
    mission.write_text(source, encoding="utf-8")
    out = tmp_path / "attack.mcap"
    lim = MissionLimits(kernel_sandbox="required", **limits)  # type: ignore[arg-type]
    result = record(one_room(), out, RUN, mission=str(mission), limits=lim)
    run = open_run(out)
    assert run.file_state == "complete" and run.outcome == result.outcome
    return out, result


def _said(log: Path) -> list[str]:
    """The mission's log lines (/rosout)."""
    return [m.msg.msg for m in open_run(log).messages(["/rosout"]) if isinstance(m.msg, msgs.Log)]


ESCAPE = """
import os

from usar_replay.api import Node


def main() -> None:
    node = Node("escape")
    try:
        os.sched_setaffinity(0, range(os.cpu_count() or 1))
        said = "asked"
    except OSError as err:
        said = type(err).__name__
    cpus = sorted(os.sched_getaffinity(0))
    node.get_logger().info(f"ATTACK affinity {said}: {len(cpus)}")
    seen = os.path.exists("/sys/fs/cgroup/cpuset") or os.path.exists("/sys/fs/cgroup/unified")
    node.get_logger().info(f"ATTACK cgroup files {'SEEN' if seen else 'hidden'}")
"""


def test_a_mission_cannot_leave_its_cpu_set_or_see_its_cgroup(tmp_path: Path) -> None:
    if not cpu_sets.usable_cpus():  # the run waits for a CPU another run (or worker) holds
        pytest.skip("no writable cgroup v1 cpuset hierarchy here (not root?)")
    out, _ = _record(tmp_path, ESCAPE, cpus=1)
    lines = _said(out)
    assert any(line.startswith("ATTACK affinity") and line.endswith(": 1") for line in lines), lines
    assert "ATTACK cgroup files hidden" in lines


HOG = """
import os, time

from usar_replay.api import Node

with open("/tmp/fill", "wb") as f:
    f.write(b"t" * (100 << 20))
with open("/dev/shm/fill", "wb") as f:
    f.write(b"s" * (100 << 20))
ready = []
for _ in range(3):  # each child's memory held before the run's first tick, not raced with it
    r, w = os.pipe()
    if os.fork() == 0:
        data = b"c" * (150 << 20)
        os.write(w, b"1")
        time.sleep(600)
        os._exit(0)
    os.close(w)  # only the child holds it: a child the OOM killer ends reads as EOF
    ready.append(r)
for r in ready:
    os.read(r, 1)


def main() -> None:
    Node("hog")
"""


def test_a_memory_hog_over_children_and_tmpfs_is_out_of_memory(tmp_path: Path) -> None:
    _out, result = _record(tmp_path, HOG, run_memory_mb=384)
    assert result.outcome == "out_of_memory", result.outcome_reason
    assert "384 MiB" in result.outcome_reason or "out-of-memory killer" in result.outcome_reason


FORK_BOMB = """
import os, time

from usar_replay.api import Node

for _ in range(200):
    try:
        if os.fork() == 0:
            time.sleep(600)
            os._exit(0)
    except OSError:
        break


def main() -> None:
    Node("bomb")
"""


def test_a_fork_bomb_is_refused_at_the_process_limit(tmp_path: Path) -> None:
    _out, result = _record(tmp_path, FORK_BOMB, processes=32)
    assert result.outcome == "refused", result.outcome_reason
    assert "limit of 32 processes" in result.outcome_reason


FILLER = """
from usar_replay.api import Node

try:
    for i in range(1000):
        with open(f"fill{i}", "wb") as f:
            f.write(b"d" * (1 << 20))
except OSError:
    pass


def main() -> None:
    Node("filler")
"""


def test_a_disk_filler_is_refused_at_the_run_folders_size(tmp_path: Path) -> None:
    _out, result = _record(tmp_path, FILLER, run_folder_mb=8)
    assert result.outcome == "refused", result.outcome_reason
    assert "filled its folder (its limit is 8 MiB)" in result.outcome_reason


FLAGGER = """
import sys
from multiprocessing.connection import Connection

from usar_replay.api import Node
from usar_replay.process.protocol import FrameKind, outputs_frame, ready_frame, unpack


def main() -> None:
    Node("flagger")
    conn = Connection(int(sys.argv[1]))
    conn.send_bytes(ready_frame())  # then every tick answered with the flag a bridge sets
    while True:
        frame = conn.recv_bytes()
        if frame[:1] == FrameKind.STOP:
            return
        conn.send_bytes(outputs_frame(unpack(frame).t_ns, [], FLAG))
"""


@pytest.mark.parametrize(
    ("flag", "budget", "said"), [(2, "max_holds", "held 4 ticks"), (4, "max_capped", "in 4 ticks")]
)
def test_every_tick_a_hold_or_capped_ends_at_its_budget(
    tmp_path: Path, flag: int, budget: str, said: str
) -> None:
    source = FLAGGER.replace("FLAG))", f"{flag}))")
    _out, result = _record(tmp_path, source, **{budget: 3})
    assert result.outcome == "hung", result.outcome_reason
    assert said in result.outcome_reason


def test_slow_holds_end_at_their_wall_budget(tmp_path: Path) -> None:
    """A node that fakes a shutdown every tick, each hold slow (issue 44): past --hold-wall's
    wall seconds the run is hung, long before --max-holds' count (20 holds of 6 s were 129 s
    of wall time for 1 sim-s)."""
    answer = "        conn.send_bytes(outputs_frame("
    source = FLAGGER.replace("FLAG))", "2))").replace(answer, "        time.sleep(0.2)\n" + answer)
    source = source.replace("def main() -> None:", "import time\n\n\ndef main() -> None:")
    _out, result = _record(tmp_path, source, max_holds=1000, hold_wall_s=0.5)
    assert result.outcome == "hung", result.outcome_reason
    assert "--hold-wall" in result.outcome_reason and "budget is 0.5 s" in result.outcome_reason
    assert int(result.outcome_reason.split(" ticks (")[0].rsplit(" ", 1)[1]) <= 6


TCP_FLOOD = """
import socket

from usar_replay.api import Node

held = []


def main() -> None:
    node = Node("flood")
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(128)

    def flood() -> None:  # loopback connections nobody reads: their buffers stay in the kernel
        for _ in range(16):
            client = socket.create_connection(server.getsockname())
            peer, _ = server.accept()
            client.setblocking(False)
            held.extend([client, peer])
            try:
                while True:
                    client.send(b"x" * 65536)
            except OSError:
                pass
        node.get_logger().info(f"ATTACK {len(held)} sockets")

    node.create_timer(0.1, flood)
"""


def test_tcp_buffers_are_charged_to_the_run(tmp_path: Path) -> None:
    """Loopback TCP buffers nobody reads (issue 44: 1.2 GiB under --run-memory 700, charged to
    no one in cgroup v1): past the run's TCP limit the run is out_of_memory."""
    _out, result = _record(tmp_path, TCP_FLOOD, run_memory_mb=256)
    assert result.outcome == "out_of_memory", result.outcome_reason
    assert "TCP socket buffers" in result.outcome_reason and "64 MiB" in result.outcome_reason


MQUEUE = """
import ctypes, os, resource

from usar_replay.api import Node


def main() -> None:
    node = Node("mq")
    rt = ctypes.CDLL("librt.so.1", use_errno=True)
    rt.mq_open.restype = ctypes.c_int
    fd = rt.mq_open(b"/usar_attack", os.O_CREAT | os.O_RDWR, 0o600, None)
    soft, hard = resource.getrlimit(resource.RLIMIT_MSGQUEUE)
    node.get_logger().info(f"ATTACK mq_open {fd} errno {ctypes.get_errno()} limit {soft} {hard}")
"""


def test_no_message_queue_for_a_run(tmp_path: Path) -> None:
    """POSIX message queues are charged to the host user every run shares (issue 44): a run
    may create none."""
    out, _ = _record(tmp_path, MQUEUE)
    said = [line for line in _said(out) if line.startswith("ATTACK")]
    assert said and said[0].startswith("ATTACK mq_open -1") and said[0].endswith("limit 0 0"), said


POOLS = """
import ctypes

from usar_replay.api import Node

KEYCTL, ADD_KEY = {keyctl}, {add_key}


def main() -> None:
    node = Node("pools")
    libc = ctypes.CDLL("libc.so.6", use_errno=True)
    made = 0
    while made < 200 and libc.inotify_init() >= 0:  # held: never closed
        made += 1
    why = ctypes.get_errno()
    ctypes.set_errno(0)
    joined = libc.syscall(KEYCTL, 1, None)  # KEYCTL_JOIN_SESSION_KEYRING: a new keyring
    key_errno = ctypes.get_errno()
    added = libc.syscall(ADD_KEY, b"user", b"usar", b"x" * 32, 32, -3)  # the session keyring
    said = f"inotify {{made}} {{why}} keyctl {{joined}} {{key_errno}} add {{added}}"
    node.get_logger().info("ATTACK " + said)
"""


def _syscall(name: str) -> int:
    import ctypes
    import ctypes.util

    lib = ctypes.CDLL(ctypes.util.find_library("seccomp") or "libseccomp.so.2")
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    return int(lib.seccomp_syscall_resolve_name(name.encode()))


def test_inotify_and_keys_are_bounded_per_run(tmp_path: Path) -> None:
    """inotify instances and keys are charged to the host user every run shares (issue 44: one
    run took all 128 of its inotify instances): a run gets its own share of inotify (16) and no
    key at all, and goes on to its own verdict in a closed log; the host keeps the rest."""
    import errno

    source = POOLS.format(keyctl=_syscall("keyctl"), add_key=_syscall("add_key"))
    out, result = _record(tmp_path, source)
    said = [line for line in _said(out) if line.startswith("ATTACK")]
    assert said == [f"ATTACK inotify 16 {errno.EMFILE} keyctl -1 {errno.EPERM} add -1"], said
    assert result.outcome == "max_sim_time", result.outcome_reason  # its own: it never ends


def test_a_run_past_its_wall_limit_ends_as_wall_limit(tmp_path: Path) -> None:
    slow = ESCAPE.replace('Node("escape")', 'Node("slow")\n    node.create_timer(0.1, burn)')
    slow += "\n\ndef burn() -> None:\n    sum(range(3_000_000))\n"
    _out, result = _record(tmp_path, slow, wall_s=0.5)
    assert result.outcome == "wall_limit", result.outcome_reason
    assert "more than 0.5 s of wall time" in result.outcome_reason


RR_CHILD = """
import os, sys, threading, time
while os.sched_getscheduler(0) & ~os.SCHED_RESET_ON_FORK != os.SCHED_RR:
    time.sleep(0.01)  # until the recorder's OneCpu gave this process SCHED_RR
open("rr", "w").close()
while not os.path.exists("go"):
    time.sleep(0.01)  # the recorder has stopped applying: what follows is inherited only
pid = os.fork()
if pid == 0:
    before = os.sched_getscheduler(0)
    try:
        os.sched_setscheduler(0, os.SCHED_RR, os.sched_param(1))
        again = "ALLOWED"
    except OSError:
        again = "refused"
    print("child", before, again, flush=True)
    os._exit(0)
os.waitpid(pid, 0)
seen = []
t = threading.Thread(target=lambda: seen.append(os.sched_getscheduler(0)))
t.start()
t.join()
print("thread", seen[0], flush=True)
"""


def test_real_time_priority_is_not_inherited_by_children_or_threads(tmp_path: Path) -> None:
    """A sandboxed process given SCHED_RR as the recorder gives it: its child starts as an
    ordinary process and may not raise itself, its new thread starts ordinary too."""
    got = cpu_sets.claim(1, wait_s=60)
    if got is None:
        pytest.skip("no CPU sets here")
    argv = sandbox_argv(
        [sys.executable, "-c", RR_CHILD],
        ro_binds=python_binds(),
        work_dir=str(tmp_path),
        env={"PATH": "/usr/bin:/bin"},
    )
    with KernelSandbox(SandboxLimits(processes=16), cpus=got) as box:
        proc = subprocess.Popen(box.launch(argv), stdout=subprocess.PIPE, text=True)
        pin = OneCpu(proc.pid, box.cgroup, cpu=got.graph_cpu)
        # as before each tick: its threads found and given SCHED_RR
        wait_for(lambda: pin.apply() < 0 or (tmp_path / "rr").exists(), "SCHED_RR", 60)
        (tmp_path / "go").touch()
        out, _ = proc.communicate(timeout=60)
    assert not pin.refused, pin.refused
    other = str(os.SCHED_OTHER)
    assert out.split() == ["child", other, "refused", "thread", other], out
