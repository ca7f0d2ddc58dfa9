"""usar's handle on a mission process: ticks in, checked outputs back, and a verdict for every
way the process can fail it, including a process that speaks another protocol version or sends
what is not a frame. Programs other than the worker take its place through the public
:meth:`MissionProcess.command` hook, as the ROS 1 bridge does."""

from __future__ import annotations

import contextlib
import pickle
import socket
import subprocess
import sys
import textwrap
from collections.abc import Sequence
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import pytest

from usar_replay.core import cdr, contract, msgs
from usar_replay.core.errors import MissionEnded, ProtocolMismatch
from usar_replay.process import protocol
from usar_replay.process.mission_process import MissionLimits, MissionProcess, hide_from_mission
from usar_replay.process.mission_target import MissionTarget, resolve_target
from usar_replay.sandbox.kernel_sandbox import KernelSandbox, bwrap_available

_OK, _WHY = bwrap_available()

ECHO = """
from usar_replay.api import Node, Odometry, String


def main():
    node = Node("echo")
    pub = node.create_publisher(String, "/echo", 10)
    node.create_subscription(
        Odometry, "/explorer/odom", lambda m: pub.publish(String(data=m.child_frame_id)), 10
    )
"""

CRASH_IN_MAIN = """
def helper():
    return {}["target_1"]  # the user's own bug


def main():
    helper()
"""


def _mission(tmp_path: Path, source: str) -> MissionTarget:
    path = tmp_path / "mission.py"
    path.write_text(textwrap.dedent(source), encoding="utf-8")
    return resolve_target(str(path))


def _start(target: MissionTarget, cls: type[MissionProcess] = MissionProcess, **limits: Any) -> Any:
    limits.setdefault("kernel_sandbox", "off")
    limits.setdefault("startup_timeout_s", 60.0)
    return cls(
        target,
        {},
        sim_topics=contract.SIM_TOPICS,
        sim_frames=contract.sim_frames(),
        limits=MissionLimits(**limits),
    )


def _odom(child: str) -> protocol.Wire:
    m = msgs.Odometry(child_frame_id=child)
    return (contract.odom("explorer"), m.__msgtype__, cdr.encode(m))


@pytest.mark.parametrize(
    "mode",
    [
        "off",
        pytest.param(
            "required", marks=pytest.mark.skipif(not _OK, reason=f"no kernel sandbox: {_WHY}")
        ),
    ],
)
def test_a_tick_goes_in_and_the_missions_outputs_come_back_checked(
    tmp_path: Path, mode: str
) -> None:
    with _start(_mission(tmp_path, ECHO), kernel_sandbox=mode) as proc:
        assert proc.pid > 0
        assert (proc.kernel_sandbox is not None) == (mode == "required")
        if proc.kernel_sandbox is not None:
            assert isinstance(proc.kernel_sandbox, KernelSandbox)
        out = proc.tick(1_000_000_000, [_odom("explorer_tf/base_footprint")])
        assert [(t, ty, m) for t, ty, _, m in out] == [
            ("/echo", "std_msgs/msg/String", msgs.String(data="explorer_tf/base_footprint"))
        ]
        # several ticks in flight (replay), answered in order
        for i in range(3):
            proc.send(2_000_000_000 + i, [_odom(f"f{i}")])
        assert [proc.receive()[0][3] for _ in range(3)] == [
            msgs.String(data=f"f{i}") for i in range(3)
        ]
        assert not proc.shutdown_requested


def test_a_crash_in_main_is_the_users_traceback(tmp_path: Path) -> None:
    with pytest.raises(MissionEnded) as err:
        _start(_mission(tmp_path, CRASH_IN_MAIN))
    assert err.value.verdict == "crashed"
    detail = err.value.detail
    assert "KeyError: 'target_1'" in detail
    assert 'return {}["target_1"]' in detail and "in helper" in detail
    # usar's own frames (the worker, the loader) are left out
    assert "worker.py" not in detail and "mission_target.py" not in detail


def test_hide_from_mission_adds_paths_and_keeps_the_rest() -> None:
    base = MissionLimits(tick_timeout_s=3.0, hidden=("/a",))
    assert hide_from_mission(base, "/b", "/c") == MissionLimits(
        tick_timeout_s=3.0, hidden=("/a", "/b", "/c")
    )
    assert hide_from_mission(None, "/x").hidden == ("/x",)


# --- another program in the mission's place (what the ROS 1 bridge does) -------------------------

# a stand-in for a mission process: reads the setup, then does what BEHAVIOUR says
FAKE = """
import pickle, struct, sys
from multiprocessing.connection import Connection

conn = Connection(int(sys.argv[1]))
setup = pickle.loads(conn.recv_bytes())
{behaviour}
"""


class Fake(MissionProcess):
    """A MissionProcess whose process is a script of the test's."""

    script = ""

    def command(self, fd: int) -> list[str]:
        return [sys.executable, self.script, str(fd)]


def _fake(tmp_path: Path, behaviour: str) -> type[Fake]:
    script = tmp_path / "fake.py"
    script.write_text(FAKE.format(behaviour=textwrap.dedent(behaviour)), encoding="utf-8")
    return type("ThisFake", (Fake,), {"script": str(script)})


_TARGET = MissionTarget("fake", "fake", "main", "", "")
_READY_V1 = "conn.send_bytes(b'R' + struct.pack('<H', 1))\n"


def test_the_setup_names_the_protocol_version_and_a_ready_of_it_starts_the_run(
    tmp_path: Path,
) -> None:
    cls = _fake(
        tmp_path,
        "assert setup['protocol_version'] == 1, setup\n"
        + _READY_V1
        + "while conn.recv_bytes()[:1] != b'S':\n    pass\n",
    )
    with _start(_TARGET, cls) as proc:
        assert proc.pid > 0
    assert proc.kernel_sandbox is None


@pytest.mark.parametrize(
    ("ready", "says"),
    [
        ("b'R'", "speaks no protocol version usar knows, this usar speaks version 1"),
        ("b'R' + struct.pack('<H', 7)", "speaks protocol version 7, this usar speaks version 1"),
    ],
)
def test_a_process_of_another_protocol_version_is_a_clear_error(
    tmp_path: Path, ready: str, says: str
) -> None:
    cls = _fake(tmp_path, f"conn.send_bytes({ready})\nconn.recv_bytes()\n")
    with pytest.raises(ProtocolMismatch) as err:
        _start(_TARGET, cls)
    assert err.value.verdict == "refused"
    assert says in err.value.detail
    assert "reinstall" in err.value.detail and "\n" not in err.value.detail


@pytest.mark.parametrize(
    ("behaviour", "verdict", "says"),
    [
        (
            "conn.send_bytes(b'O' + bytes(13))\n",
            "refused",
            "sent a frame of kind b'O' before it was ready",
        ),
        (
            _READY_V1 + "conn.recv_bytes()\nconn.send_bytes(b'O\\x00\\x01')\n",
            "refused",
            "sent a malformed frame (a frame of 3 bytes is cut short",
        ),
        (
            _READY_V1
            + "conn.recv_bytes()\n"
            + "conn.send_bytes(b'O' + struct.pack('<qI', 0, 0) + b'\\x00' + b'extra')\n",
            "refused",
            "malformed frame (5 bytes after the last item of the frame)",
        ),
        (
            _READY_V1 + "conn.recv_bytes()\nconn.send_bytes(b'Zzz')\n",
            "refused",
            "sent a frame of unknown kind b'Z'",
        ),
        (_READY_V1 + "conn.recv_bytes()\nsys.exit(3)\n", "crashed", "exited (code 3)"),
        (
            _READY_V1 + "conn.recv_bytes()\nconn.send_bytes(b'Cboom')\n",
            "crashed",
            "boom",
        ),
        (
            _READY_V1 + "conn.recv_bytes()\nconn.send_bytes(b'Mno room')\n",
            "out_of_memory",
            "no room",
        ),
    ],
)
def test_every_wrong_answer_to_a_tick_is_a_verdict(
    tmp_path: Path, behaviour: str, verdict: str, says: str
) -> None:
    cls = _fake(tmp_path, behaviour)
    with pytest.raises(MissionEnded) as err, _start(_TARGET, cls, tick_timeout_s=20.0) as proc:
        proc.tick(1, [])
    assert err.value.verdict == verdict
    assert says in err.value.detail


# --- the worker's side of the handshake ---------------------------------------------------------


def _worker(setup: dict[str, Any]) -> tuple[bytes, int]:
    """Run ``python -m usar_replay.process.worker`` on a socket: (first frame, exit code)."""
    parent, child = socket.socketpair()
    with child:
        proc = subprocess.Popen(
            [sys.executable, "-m", "usar_replay.process.worker", str(child.fileno())],
            pass_fds=(child.fileno(),),
            stdin=subprocess.DEVNULL,
        )
    conn = Connection(parent.detach())
    try:
        conn.send_bytes(pickle.dumps(setup))
        assert conn.poll(60)
        first = conn.recv_bytes()
        with contextlib.suppress(OSError):  # it may be gone already
            conn.send_bytes(protocol.FrameKind.STOP)
        return first, proc.wait(timeout=30)
    finally:
        conn.close()
        if proc.poll() is None:
            proc.kill()


def _setup(target: MissionTarget, **extra: Any) -> dict[str, Any]:
    return {
        "protocol_version": protocol.PROTOCOL_VERSION,
        "target": target,
        "parameters": {},
        "sim_topics": tuple(contract.SIM_TOPICS),
        "sim_frames": tuple(contract.sim_frames()),
        "memory_mb": 0,
        "rlimits": {},
        "guard": None,
        **extra,
    }


def test_the_worker_answers_a_setup_of_another_version_with_its_own_and_runs_nothing(
    tmp_path: Path,
) -> None:
    marker = tmp_path / "ran"
    target = _mission(tmp_path, f"open({str(marker)!r}, 'w').close()\n\ndef main():\n    pass\n")
    first, code = _worker(_setup(target, protocol_version=0))
    assert first == protocol.ready_frame()  # the parent compares and says what is wrong
    assert code == 0
    assert not marker.exists()  # the mission's code never loaded
    # of this version, the same mission loads (and then says it created no Node)
    first, _ = _worker(_setup(target))
    assert first[:1] == protocol.FrameKind.CRASHED and b"created no Node" in first
    assert marker.exists()


def test_command_is_the_worker_by_default(tmp_path: Path) -> None:
    with _start(_mission(tmp_path, ECHO)) as proc:
        argv: Sequence[str] = proc.command(5)
    assert list(argv) == [sys.executable, "-m", "usar_replay.process.worker", "5"]
