"""Red team: missions that attack the recorder, the batch and other teams, against the sandbox.

Each attack of issue #21 that the kernel sandbox (sandbox/kernel_sandbox.py) and the guard
(usar_replay/sandbox/audit_guard.py) answer is a tiny mission here. The ``record`` tests run the
mission with the kernel sandbox alone (``usar record`` has no guard), so they show what bwrap
contains even when Python-level checks are bypassed; the batch test grades a class of attackers
between two identical honest teams with both layers on, and shows that every attacker gets a verdict
and neither honest grade moves. Every attack prints ``ATTACK name: result`` lines that the tests
read.

Needs bubblewrap (``apt-get install bubblewrap``; CI installs it): skipped only where it is
missing or cannot create namespaces. About a minute of wall time on 2 cores.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import socket
import sys
import textwrap
from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.cli import main as cli
from usar_replay.core.settings import RunSettings
from usar_replay.pipeline.record import RecordResult, record
from usar_replay.process.mission_process import MissionLimits
from usar_replay.sandbox.kernel_sandbox import bwrap_available
from usar_replay.world.scenario_toml import to_toml

ROOT = Path(__file__).resolve().parents[2]
_OK, _WHY = bwrap_available()
pytestmark = pytest.mark.skipif(not _OK, reason=f"no kernel sandbox here: {_WHY}")

SHORT = RunSettings(record=dataclasses.replace(RunSettings().record, max_sim_time_s=0.5))

NODE = """

from usar_replay.api import Node


def main() -> None:
    Node("attacker")
"""


def attack_source(body: str) -> str:
    """A mission whose module body runs ``body`` (at import, before the first tick); every
    attempt is wrapped so that the mission goes on and the run ends with a verdict."""
    prelude = textwrap.dedent(
        """
        import os, sys

        def say(name, result):
            print(f"ATTACK {name}: {result}", flush=True)

        def attempt(name, fn):
            try:
                say(name, f"ALLOWED {fn()!r}"[:300])
            except BaseException as err:
                say(name, f"failed {type(err).__name__}: {err}"[:300])
        """
    )
    return prelude + textwrap.dedent(body) + NODE


def run_attack(
    tmp_path: Path, capfd: pytest.CaptureFixture[str], body: str
) -> tuple[RecordResult, dict[str, str]]:
    """Record a one-room run of the attack (kernel sandbox only), its log next to the mission
    file as a careless student would; return the result and each attack's printed outcome."""
    team = tmp_path / "team"
    team.mkdir()
    mission = team / "attack.py"
    mission.write_text(attack_source(body), encoding="utf-8")
    capfd.readouterr()
    result = record(
        one_room(),
        team / "run.mcap",
        SHORT,
        mission=str(mission),
        limits=MissionLimits(kernel_sandbox="required", tick_timeout_s=20.0),
    )
    out = capfd.readouterr().out
    said = {}
    for line in out.splitlines():
        if line.startswith("ATTACK "):
            name, _, what = line[len("ATTACK ") :].partition(": ")
            said[name] = what
    return result, said


def _host_processes_with(marker: str) -> list[int]:
    """PIDs on this machine whose command line contains ``marker``."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            cmdline = Path("/proc", entry, "cmdline").read_bytes()
        except OSError:
            continue
        if marker.encode() in cmdline:
            found.append(int(entry))
    return found


# -- the kernel sandbox alone (usar record) ------------------------------------------------------


def test_scenario_file_via_dir_fd_and_the_log_being_written(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    scenario = tmp_path / "room.toml"
    scenario.write_text(to_toml(one_room()), encoding="utf-8")
    result, said = run_attack(
        tmp_path,
        capfd,
        f"""
        import pathlib
        here = os.path.dirname(os.path.abspath(__file__))
        attempt("dir_fd", lambda: os.read(os.open("room.toml", os.O_RDONLY,
                dir_fd=os.open({str(tmp_path)!r}, os.O_RDONLY)), 100))
        attempt("absolute", lambda: open({str(scenario)!r}).read(100))
        attempt("part", lambda: len(pathlib.Path(here, "run.mcap.part").read_bytes()))
        """,
    )
    assert result.outcome == "max_sim_time", result.outcome_reason
    assert said["dir_fd"].startswith("failed FileNotFoundError"), said
    assert said["absolute"].startswith("failed FileNotFoundError"), said
    # the log being written (with the true marker poses) lies next to the mission: masked
    assert said["part"].startswith("failed PermissionError"), said


def test_recorder_memory_and_processes_are_out_of_sight(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    result, said = run_attack(
        tmp_path,
        capfd,
        f"""
        pids = sorted(int(p) for p in os.listdir("/proc") if p.isdigit())
        say("pids", pids)
        attempt("recorder_mem", lambda: open("/proc/{os.getpid()}/mem", "rb").read(1))
        attempt("ppid", lambda: os.getppid())
        attempt("ppid_cmdline", lambda: open(f"/proc/{{os.getppid()}}/cmdline", "rb").read())
        attempt("ppid_environ", lambda: open(f"/proc/{{os.getppid()}}/environ", "rb").read())
        """,
    )
    assert result.outcome == "max_sim_time", result.outcome_reason
    # its own PID namespace: bwrap's init (1) and the mission; no usar process
    assert said["pids"] == "[1, 2]", said
    assert said["recorder_mem"].startswith("failed FileNotFoundError"), said
    assert said["ppid"] == "ALLOWED 1", said
    assert "bwrap" in said["ppid_cmdline"], said
    # bwrap itself was started with the mission's environment, not the recorder's
    assert "PYTEST" not in said["ppid_environ"] and "USAR_" not in said["ppid_environ"], said


def test_signals_reach_no_usar_process(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    recorder = os.getpid()
    result, said = run_attack(
        tmp_path,
        capfd,
        f"""
        import signal
        attempt("kill_ppid", lambda: os.kill(os.getppid(), signal.SIGKILL))
        attempt("kill_recorder", lambda: os.kill({recorder}, signal.SIGKILL))
        attempt("pidfd", lambda: signal.pidfd_send_signal(os.pidfd_open({recorder}),
                signal.SIGKILL))
        attempt("ptrace", lambda: open("/proc/{recorder}/mem", "r+b"))
        """,
    )
    # this process (the recorder) is alive to read the verdict, and the run ended normally
    assert result.outcome == "max_sim_time", result.outcome_reason
    assert said["kill_ppid"] == "ALLOWED None", said  # bwrap's init ignores it
    assert said["kill_recorder"].startswith("failed ProcessLookupError"), said
    assert said["pidfd"].startswith("failed ProcessLookupError"), said
    assert said["ptrace"].startswith("failed FileNotFoundError"), said


def test_a_setsid_daemon_dies_with_the_run(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    marker = f"4242.{os.getpid()}"
    result, said = run_attack(
        tmp_path,
        capfd,
        f"""
        import _posixsubprocess, subprocess
        def daemon():
            # a double fork with a new session, then a long sleep under a name we can find
            if os.fork() == 0:
                os.setsid()
                if os.fork() == 0:
                    os.execv("/bin/sleep", ["sleep", {marker!r}])
                os._exit(0)
            return "started"
        attempt("double_fork", daemon)
        attempt("popen", lambda: subprocess.Popen(["sleep", {marker!r}],
                start_new_session=True).pid > 0)
        """,
    )
    assert result.outcome == "max_sim_time", result.outcome_reason
    assert said["double_fork"] == "ALLOWED 'started'", said
    assert said["popen"] == "ALLOWED True", said
    # the run is over: its PID namespace ended, and every process in it with it
    assert _host_processes_with(marker) == []


def test_process_count_is_limited_and_children_end(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    result, said = run_attack(
        tmp_path,
        capfd,
        """
        import multiprocessing, time
        def bomb():
            n = 0
            try:
                while n < 2000:
                    if os.fork() == 0:
                        time.sleep(1000)
                        os._exit(0)
                    n += 1
            except OSError as err:
                return f"stopped at {n}: {type(err).__name__}"
            return n
        attempt("fork_bomb", bomb)
        ctx = multiprocessing.get_context("fork")
        attempt("multiprocessing", lambda: ctx.Process(target=time.sleep, args=(1000,)).start())
        """,
    )
    # the run's process limit was reached: that is the run's verdict (issue #33)
    assert result.outcome == "refused", result.outcome_reason
    assert "limit of 256 processes" in result.outcome_reason
    assert said["fork_bomb"].startswith("ALLOWED 'stopped at"), said
    assert int(said["fork_bomb"].split("stopped at ")[1].split(":")[0]) < 260
    # after the bomb, nothing is left to start another process with
    assert said["multiprocessing"].startswith("failed"), said


def test_no_network_to_the_host(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    udp.bind(("127.0.0.1", 0))
    udp.setblocking(False)
    tcp = socket.socket()
    tcp.bind(("127.0.0.1", 0))
    tcp.listen(1)
    tcp.setblocking(False)
    with udp, tcp:
        result, said = run_attack(
            tmp_path,
            capfd,
            f"""
            import socket
            def udp():
                s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                return s.sendto(b"truth", ("127.0.0.1", {udp.getsockname()[1]}))
            def tcp():
                s = socket.create_connection(("127.0.0.1", {tcp.getsockname()[1]}), timeout=2)
                return s.send(b"truth")
            def fastopen():
                s = socket.socket()
                return s.sendto(b"truth", socket.MSG_FASTOPEN,
                                ("127.0.0.1", {tcp.getsockname()[1]}))
            attempt("udp", udp)
            attempt("tcp", tcp)
            attempt("fastopen", fastopen)
            attempt("outside", lambda: socket.create_connection(("1.1.1.1", 53), timeout=2))
            """,
        )
        assert result.outcome == "max_sim_time", result.outcome_reason
        # the datagram went to the sandbox's own loopback: nothing reached this one
        with pytest.raises(BlockingIOError):
            udp.recv(100)
        with pytest.raises(BlockingIOError):
            tcp.accept()
    assert said["tcp"].startswith("failed ConnectionRefusedError"), said
    assert said["fastopen"].startswith("failed"), said
    assert said["outside"].startswith("failed OSError"), said


def test_writing_outside_from_c_fails(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    victim = tmp_path / "victim"
    victim.mkdir()
    grade = victim / "room.grade.json"
    grade.write_text('{"points": 0}\n', encoding="utf-8")
    result, said = run_attack(
        tmp_path,
        capfd,
        f"""
        import cv2, numpy, sqlite3
        here = os.path.dirname(os.path.abspath(__file__))
        attempt("imwrite", lambda: cv2.imwrite({str(grade)!r} + ".png",
                numpy.zeros((2, 2), numpy.uint8)))
        attempt("sqlite", lambda: sqlite3.connect({str(grade)!r}).execute("create table t(x)"))
        attempt("own_folder", lambda: open(os.path.join(here, "x.txt"), "w"))
        attempt("cwd", lambda: open("scratch.txt", "w").write("ok"))
        """,
    )
    assert result.outcome == "max_sim_time", result.outcome_reason
    assert said["imwrite"].startswith("failed") or said["imwrite"] == "ALLOWED False", said
    assert said["sqlite"].startswith("failed OperationalError"), said
    assert said["own_folder"].startswith("failed OSError"), said  # read-only: EROFS
    assert said["cwd"] == "ALLOWED 2", said  # its private work dir
    assert grade.read_text(encoding="utf-8") == '{"points": 0}\n'
    assert sorted(p.name for p in victim.iterdir()) == ["room.grade.json"]
    assert sorted(p.name for p in (tmp_path / "team").iterdir()) == ["attack.py", "run.mcap"]


def test_the_environment_is_the_missions_own(
    tmp_path: Path, capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("USAR_TEST_SECRET", "the world key")
    result, said = run_attack(tmp_path, capfd, 'say("env", sorted(os.environ))\n')
    assert result.outcome == "max_sim_time", result.outcome_reason
    names = set(json.loads(said["env"].replace("'", '"')))
    names.discard("PYTHONHASHSEED")  # passed on when set: it decides the mission's set order
    assert names == {
        "HOME",
        "LANG",
        "OMP_NUM_THREADS",
        "OPENCV_FOR_THREADS_NUM",
        "PATH",
        "PWD",
        "PYTHONDONTWRITEBYTECODE",
        "PYTHONPATH",
        "TMPDIR",
    }


# -- a class of attackers (usar batch: kernel sandbox and guard) ---------------------------------

HONEST = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")


def _batch_attacks(out: Path, subs: Path, room: Path) -> dict[str, str]:
    honest_grade = out / "honest_a" / "room.grade.json"
    return {
        "forger": f"""
        import cv2, numpy, sqlite3, subprocess
        attempt("imwrite", lambda: cv2.imwrite({str(honest_grade)!r} + ".png",
                numpy.zeros((2, 2), numpy.uint8)))
        attempt("sqlite", lambda: sqlite3.connect({str(honest_grade)!r}))
        attempt("open", lambda: open({str(honest_grade)!r}, "w"))
        """,
        "killer": """
        import signal
        attempt("kill_ppid", lambda: os.kill(os.getppid(), signal.SIGKILL))
        attempt("pidfd", lambda: signal.pidfd_send_signal(os.pidfd_open(1), signal.SIGKILL))
        attempt("fork_exec", lambda: __import__("_posixsubprocess").fork_exec)
        os.abort()  # and then it dies: a verdict for its own run, not a batch error
        """,
        "snooper": f"""
        attempt("dir_fd", lambda: os.open("room.toml", os.O_RDONLY,
                dir_fd=os.open({str(room.parent)!r}, os.O_RDONLY)))
        attempt("subs", lambda: os.listdir({str(subs)!r}))
        attempt("proc", lambda: open("/proc/1/environ", "rb").read())
        attempt("tamper", lambda: setattr(sys.modules["usar_replay.sandbox.audit_guard"],
                "_PROCESS_EVENTS", frozenset()) or os.fork())
        """,
    }


@pytest.fixture(scope="module")
def attacked_class(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, int, str]:
    root = tmp_path_factory.mktemp("redteam")
    subs, out = root / "subs", root / "out"
    subs.mkdir()
    room = root / "room.toml"
    room.write_text(to_toml(one_room()), encoding="utf-8")
    (subs / "honest_a.py").write_text(HONEST, encoding="utf-8")
    (subs / "honest_z.py").write_text(HONEST, encoding="utf-8")
    for team, body in _batch_attacks(out, subs, room).items():
        (subs / f"{team}.py").write_text(attack_source(body), encoding="utf-8")
    buf, old = io.StringIO(), sys.stdout
    sys.stdout = buf
    try:
        code = cli.main(
            ["batch", str(subs), "--scenario", str(room), "-o", str(out), "--max-sim-time", "3",
             "--tick-timeout", "10", "--jobs", "2", "--quiet", "--gradescope"]
        )  # fmt: skip
    finally:
        sys.stdout = old
    return out, code, buf.getvalue()


def _said(out: Path, team: str) -> dict[str, str]:
    text = (out / team / "room.output.txt").read_text(encoding="utf-8")
    return {
        line[7:].partition(": ")[0]: line[7:].partition(": ")[2]
        for line in text.splitlines()
        if line.startswith("ATTACK ")
    }


def _grade(out: Path, team: str) -> dict[str, object]:
    data: dict[str, object] = json.loads((out / team / "room.grade.json").read_text())
    return data


def test_attackers_get_verdicts_and_honest_grades_do_not_move(
    attacked_class: tuple[Path, int, str],
) -> None:
    out, code, text = attacked_class
    assert code == 0, text  # every run graded: no attacker made the batch fail
    a, z = _grade(out, "honest_a"), _grade(out, "honest_z")
    assert a["outcome"] == z["outcome"] == "max_sim_time"
    # the same code on the same world: the same grade, line by line, whoever ran next to them
    # (the logs differ only in the mission's file name they record)
    mine = ("team", "log_sha256")
    assert {k: v for k, v in a.items() if k not in mine} == {
        k: v for k, v in z.items() if k not in mine
    }
    for team in ("honest_a", "honest_z"):
        results = json.loads((out / team / "results.json").read_text())
        assert results["score"] == _grade(out, team)["points"]
    assert _grade(out, "killer")["outcome"] == "crashed"  # SIGABRT: its own verdict
    assert _grade(out, "forger")["outcome"] == "max_sim_time"
    assert _grade(out, "snooper")["outcome"] == "max_sim_time"
    summary = (out / "summary.csv").read_text(encoding="utf-8")
    assert all(team in summary for team in ("honest_a", "honest_z", "forger", "killer"))


def test_forging_another_grade_is_refused(attacked_class: tuple[Path, int, str]) -> None:
    out, _, _ = attacked_class
    said = _said(out, "forger")
    assert all(said[k].startswith("failed") for k in ("sqlite", "open")), said
    assert said["imwrite"].startswith("failed") or said["imwrite"] == "ALLOWED False", said
    assert not (out / "honest_a" / "room.grade.json.png").exists()


def test_signalling_the_batch_is_refused(attacked_class: tuple[Path, int, str]) -> None:
    out, _, _ = attacked_class
    said = _said(out, "killer")
    assert said["kill_ppid"].startswith("failed GuardViolation"), said  # the guard first
    assert said["pidfd"].startswith("failed GuardViolation"), said
    assert said["fork_exec"].startswith("ALLOWED <function"), said  # the guard's refusal


def test_snooping_is_refused(attacked_class: tuple[Path, int, str]) -> None:
    out, _, _ = attacked_class
    said = _said(out, "snooper")
    for name in ("dir_fd", "subs", "proc", "tamper"):
        assert said[name].startswith("failed GuardViolation"), said


# -- the sandbox changes nothing an honest mission does ------------------------------------------


def test_the_sandbox_changes_no_message_byte(tmp_path: Path) -> None:
    from logtools import digest

    from usar_replay.pipeline.replay import replay

    settings = RunSettings(record=dataclasses.replace(RunSettings().record, max_sim_time_s=4.0))
    bare, sandboxed = tmp_path / "bare.mcap", tmp_path / "sandboxed.mcap"
    a = record(one_room(), bare, settings, limits=MissionLimits(kernel_sandbox="off"))
    b = record(one_room(), sandboxed, settings, limits=MissionLimits(kernel_sandbox="required"))
    assert a.outcome == b.outcome == "max_sim_time"
    assert a.messages == b.messages > 50
    assert digest(bare) == digest(sandboxed)
    # and the sandboxed replay of the bare recording reproduces it bit for bit
    report = replay(bare, limits=MissionLimits(kernel_sandbox="required"))
    assert report.identical, report
