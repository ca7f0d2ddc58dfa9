"""sandbox/kernel_sandbox: the bubblewrap command line, run for real on a shell script: who it
runs as, what it sees, where it may write, what is hidden, and the run's limits. (The attacks
on it, from a mission: tests/redteam/test_kernel_sandbox.py.)"""

from __future__ import annotations

import signal
import subprocess
from pathlib import Path

import pytest

from usar_replay.sandbox.kernel_sandbox import (
    SANDBOX_UID,
    KernelSandbox,
    SandboxLimits,
    bwrap_available,
    sandbox_argv,
    signal_of_exit,
)

SCRIPT = """
id -u
hostname
cat {ro}/visible.txt
cat {ro}/secret.txt; echo "secret:$?"
ls {ro}/grader | wc -l
echo x > {ro}/new.txt 2>/dev/null; echo "ro-write:$?"
echo x > {outside}/new.txt 2>/dev/null; echo "outside-write:$?"
echo kept > {work}/out.txt; echo "work-write:$?"
echo "env:$MINE:${{HOME:-unset}}"
"""


def test_signal_of_exit() -> None:
    assert signal_of_exit(None) is None
    assert signal_of_exit(-int(signal.SIGKILL)) == signal.SIGKILL  # bwrap itself killed
    assert signal_of_exit(128 + int(signal.SIGXCPU)) == signal.SIGXCPU  # the process inside
    assert signal_of_exit(0) is None and signal_of_exit(1) is None and signal_of_exit(200) is None


def test_limits_become_rlimits() -> None:
    limits = SandboxLimits(memory_mb=100, cpu_s=7, file_mb=2, open_files=64, processes=0)
    with KernelSandbox(limits) as jail:
        assert jail.cgroup is None
        assert jail.rlimits() == {
            "AS": 100 * 1024 * 1024,
            "CPU": 7,
            "FSIZE": 2 * 1024 * 1024,
            "NOFILE": 64,
            "NPROC": 0,  # 0: leave it: with no pids cgroup and processes=0 there is no limit
            "CORE": 0,
            "MSGQUEUE": 0,  # applied as 0: no POSIX message queue for a run
        }


@pytest.fixture
def folders(tmp_path: Path) -> dict[str, Path]:
    ro, work, outside = tmp_path / "ro", tmp_path / "work", tmp_path / "outside"
    for folder in (ro, ro / "grader", work, outside):
        folder.mkdir()
    (ro / "visible.txt").write_text("the mission's file\n", encoding="utf-8")
    (ro / "secret.txt").write_text("the grader's world\n", encoding="utf-8")
    (ro / "grader" / "key").write_text("k", encoding="utf-8")
    return {"ro": ro, "work": work, "outside": outside}


def test_a_jailed_script_sees_and_writes_only_what_it_is_given(folders: dict[str, Path]) -> None:
    ok, why = bwrap_available()
    if not ok:
        pytest.skip(why)
    ro, work = folders["ro"], folders["work"]
    script = SCRIPT.format(ro=ro, work=work, outside=folders["outside"])
    argv = sandbox_argv(
        ["/bin/sh", "-c", script],
        ro_binds=[str(ro)],
        work_dir=str(work),
        env={"MINE": "yes", "PATH": "/usr/bin:/bin"},
        hidden=[str(ro / "secret.txt"), str(ro / "grader"), str(folders["outside"])],
    )
    assert argv[-3:] == ["/bin/sh", "-c", script] and argv[-4] == "--"
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == str(SANDBOX_UID) and lines[1] == "mission"
    assert lines[2] == "the mission's file"
    assert lines[3] in ("secret:0", "secret:1")  # /dev/null over it: empty, or refused
    assert "the grader's world" not in done.stdout
    assert lines[4].strip() == "0"  # an empty folder over the grader's
    assert lines[5] != "ro-write:0" and lines[6] != "outside-write:0"
    assert lines[7] == "work-write:0" and (work / "out.txt").read_text() == "kept\n"
    assert lines[8] == "env:yes:unset"  # only the environment given
    assert not (ro / "new.txt").exists() and not (folders["outside"] / "new.txt").exists()


def test_a_bad_network_is_refused(folders: dict[str, Path]) -> None:
    if not bwrap_available()[0]:
        pytest.skip("no bwrap here")
    with pytest.raises(ValueError, match="network='host'"):
        sandbox_argv(["true"], ro_binds=[], work_dir=str(folders["work"]), env={}, network="host")  # type: ignore[arg-type]


MOVED = """
pwd
cat /fixed/ro/visible.txt
cat /fixed/ro/secret.txt; echo "secret:$?"
ls {ro} 2>/dev/null; echo "host-path:$?"
echo x > /fixed/ro/new.txt 2>/dev/null; echo "ro-write:$?"
echo kept > /fixed/work/out.txt; echo "work-write:$?"
"""


def test_a_folder_mounted_at_another_path_is_read_only_and_hides_as_at_home(
    folders: dict[str, Path],
) -> None:
    """``ro_mounts`` and ``work_at`` (a ROS 1 workspace at /ros1/ws): the host folders appear
    at the given paths only, the mount read-only, a hidden file under it hidden there too."""
    ok, why = bwrap_available()
    if not ok:
        pytest.skip(why)
    ro, work = folders["ro"], folders["work"]
    script = MOVED.format(ro=ro)
    argv = sandbox_argv(
        ["/bin/sh", "-c", script],
        ro_binds=[],
        work_dir=str(work),
        env={"PATH": "/usr/bin:/bin"},
        hidden=[str(ro / "secret.txt")],
        ro_mounts=[(str(ro), "/fixed/ro")],
        work_at="/fixed/work",
    )
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "/fixed/work" and lines[1] == "the mission's file"
    assert lines[2] in ("secret:0", "secret:1") and "the grader's world" not in done.stdout
    assert lines[3] != "host-path:0"  # not at its host path as well
    assert lines[4] != "ro-write:0" and not (ro / "new.txt").exists()
    assert lines[5] == "work-write:0" and (work / "out.txt").read_text() == "kept\n"


@pytest.mark.parametrize("dest", ["relative", "/usr/lib/x", "/proc", "/", "/a/../b", "/lib"])
def test_a_mount_over_the_sandboxs_own_paths_is_refused(
    folders: dict[str, Path], dest: str
) -> None:
    if not bwrap_available()[0]:
        pytest.skip("no bwrap here")
    with pytest.raises(ValueError, match="mount"):
        sandbox_argv(
            ["true"], ro_binds=[], work_dir=str(folders["work"]), env={},
            ro_mounts=[(str(folders["ro"]), dest)],
        )  # fmt: skip


def _limit_memory(cgroup: str, limit: int) -> bool:
    """Give the run's memory cgroup a limit (v1 or v2), as a grader could; False where the
    kernel does not let this test set one."""
    for name in ("memory.max", "memory.limit_in_bytes"):
        path = Path(cgroup, name)
        if path.exists():
            try:
                path.write_text(str(limit))
                return True
            except OSError:
                return False
    return False


@pytest.mark.parametrize("oom", [True, False])
def test_a_kill_is_called_out_of_memory_only_on_the_kernels_record(oom: bool) -> None:
    """The OOM killer really fires in the run's memory cgroup (its limit set here, 64 MiB,
    then 256 MiB touched), and :meth:`KernelSandbox.oom_killed` reads its record; a plain
    SIGKILL of the same process leaves no record (issue #26 point 11)."""
    import sys

    with KernelSandbox(SandboxLimits(memory_mb=0)) as box:
        if box.memory_cgroup is None or not _limit_memory(box.memory_cgroup, 64 << 20):
            pytest.skip("no memory cgroup of usar's own on this machine")
        hog = "x = bytearray(256 << 20)\nimport time\ntime.sleep(60)"
        wait = "import time\ntime.sleep(60)"
        proc = subprocess.Popen(box.launch([sys.executable, "-c", hog if oom else wait]))
        if not oom:
            proc.send_signal(signal.SIGKILL)
        assert proc.wait(timeout=60) == -signal.SIGKILL
        assert box.oom_killed() is oom


def test_the_sandboxs_network_namespace_has_connection_tables_of_its_own(
    folders: dict[str, Path],
) -> None:
    """Where the machine allows (root, Linux 6.1+), bwrap starts from an empty namespace whose
    children get TCP and UDP hash tables of their own (1024 and 256 buckets), so a socket dump
    in the sandbox walks its own few connections, not the host's table; the host's setting is
    left as it was. Elsewhere the command is bwrap's own."""
    from usar_replay.sandbox.kernel_sandbox import own_tables_argv, own_tables_available

    if not bwrap_available()[0]:
        pytest.skip("no bwrap here")
    host = Path("/proc/sys/net/ipv4/tcp_child_ehash_entries")
    before = host.read_text() if host.exists() else None
    script = "cat /proc/sys/net/ipv4/tcp_ehash_entries /proc/sys/net/ipv4/udp_hash_entries"
    argv = sandbox_argv(
        ["/bin/sh", "-c", script],
        ro_binds=[],
        work_dir=str(folders["work"]),
        env={"PATH": "/usr/bin:/bin"},
        network="loopback",
    )
    if not own_tables_available():
        assert own_tables_argv(argv) == argv
        return
    with KernelSandbox(SandboxLimits(processes=0)) as box:
        done = subprocess.run(box.launch(argv), capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["1024", "256"]  # negative: the host's table, shared
    assert (host.read_text() if host.exists() else None) == before
