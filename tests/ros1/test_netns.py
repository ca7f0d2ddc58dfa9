"""ros1/netns: a command in a network namespace of its own, loopback only, run for real."""

from __future__ import annotations

import subprocess
import sys

import pytest

from usar_replay.ros1.netns import isolated_command, netns_available

INTERFACES = [
    sys.executable,
    "-c",
    "import socket; print(sorted(n for _, n in socket.if_nameindex()))",
]


def test_without_isolation_the_command_is_itself() -> None:
    assert isolated_command(["rosmaster", "--core"], isolate=False) == ["rosmaster", "--core"]


def test_an_isolated_command_sees_only_loopback() -> None:
    if not netns_available():
        assert isolated_command(INTERFACES) == INTERFACES  # the host's network, as it is
        pytest.skip("this machine refuses network namespaces (unshare -rn)")
    cmd = isolated_command(INTERFACES)
    assert cmd[:2] == ["unshare", "-rn"] and cmd[-len(INTERFACES) :] == INTERFACES
    done = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=30)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "['lo']"
    host = subprocess.run(INTERFACES, capture_output=True, text=True, check=True).stdout
    assert "'lo'" in host
