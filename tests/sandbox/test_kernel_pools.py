"""sandbox/kernel_pools: the run's share of the kernel's per-user pools, run for real in bwrap.
inotify instances stop at the run's bound (where bwrap alone goes past it), keys are refused,
and the filter is libseccomp's BPF. (The attack from a ROS 1 team: tests/redteam.)"""

from __future__ import annotations

import errno
import subprocess
import sys
from pathlib import Path

import pytest

from usar_replay.sandbox import kernel_pools
from usar_replay.sandbox.kernel_pools import PoolLimits
from usar_replay.sandbox.kernel_sandbox import (
    KernelSandbox,
    SandboxLimits,
    bwrap_available,
    python_binds,
    sandbox_argv,
)

# makes up to 24 inotify instances, then asks for a session keyring (KEYCTL_JOIN_SESSION_KEYRING
# through libc's keyctl wrapper name, resolved by libseccomp's own table for this machine)
PROBE = r"""
import ctypes, os, sys
libc = ctypes.CDLL(None, use_errno=True)
made = 0
while made < 24 and libc.inotify_init() >= 0:
    made += 1
print(made, ctypes.get_errno() if made < 24 else 0)
ctypes.set_errno(0)
print(libc.syscall(int(sys.argv[1]), 1, 0), ctypes.get_errno())
"""


def _keyctl_number() -> int:
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("seccomp")
    assert name, "libseccomp2 is part of Debian's base (apt depends on it)"
    lib = ctypes.CDLL(name)
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    number = int(lib.seccomp_syscall_resolve_name(b"keyctl"))
    assert number > 0
    return number


def _run(tmp_path: Path, limits: SandboxLimits, *, filtered: bool) -> list[list[int]]:
    ok, why = bwrap_available()
    if not ok:
        pytest.skip(why)
    with KernelSandbox(limits) as box:
        argv = sandbox_argv(
            [sys.executable, "-c", PROBE, str(_keyctl_number())],
            ro_binds=python_binds(),
            work_dir=str(tmp_path),
            env={"PATH": "/usr/bin:/bin"},
            info_fd=box.info_fd,
            seccomp_fd=box.seccomp_fd if filtered else None,
        )
        proc = subprocess.Popen(
            box.launch(argv), pass_fds=box.fds, stdout=subprocess.PIPE, text=True
        )
        box.started()
        out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 0, out
    return [[int(word) for word in line.split()] for line in out.splitlines()]


def test_a_run_takes_at_most_its_share_of_inotify_and_no_key(tmp_path: Path) -> None:
    assert kernel_pools.pool_limits_available(), "CI's machine gives user namespaces"
    (made, why), (key, key_errno) = _run(tmp_path, SandboxLimits(processes=0), filtered=True)
    assert (made, why) == (PoolLimits().inotify_instances, errno.EMFILE)
    assert (key, key_errno) == (-1, errno.EPERM)


def test_without_the_runs_bounds_the_same_probe_goes_past_them(tmp_path: Path) -> None:
    """The negative: no pool bound, no filter; the kernel's host-wide limit alone (128 for the
    host user) lets the probe make all 24 instances and join a keyring of its own."""
    limits = SandboxLimits(processes=0, pools=PoolLimits(0, 0, 0, 0))
    (made, _), (key, _) = _run(tmp_path, limits, filtered=False)
    assert made == 24 and key > 0


def test_the_bounds_are_set_before_the_program_and_a_failure_stops_it() -> None:
    script = kernel_pools.pool_limits_argv(["bwrap", "x"], PoolLimits(3, 5, 0, 7))
    assert script[:3] == [script[0], "--user", "--map-root-user"]
    body = script[script.index("-c") + 1]
    assert "echo 3 > /proc/sys/user/max_inotify_instances || exit 125" in body
    assert "max_fanotify_groups" not in body  # 0: left as it is
    assert body.endswith('exec "$@"') and script[-2:] == ["bwrap", "x"]
    assert kernel_pools.pool_limits_argv(["bwrap"], PoolLimits(0, 0, 0, 0)) == ["bwrap"]


def test_the_filter_is_a_bpf_program_refusing_the_key_calls() -> None:
    program = kernel_pools.keyring_filter()
    assert program is not None and len(program) % 8 == 0 and len(program) >= 8 * 6
    fd = kernel_pools.keyring_filter_fd()
    assert fd is not None
    try:
        import os

        assert os.read(fd, len(program) + 1) == program  # at offset 0, the whole program
    finally:
        os.close(fd)
