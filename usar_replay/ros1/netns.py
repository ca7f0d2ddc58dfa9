"""The one place a ROS 1 graph is started: in its own network namespace where the machine
allows one.

Why: a ROS master and its nodes talk over TCP ports on every interface they find. In their own
network namespace (``unshare -rn``: a user namespace, so no root is needed, and a network one
with only loopback, brought up) two runs cannot see each other's master or topics, every run
may use the same port, and the student's code cannot reach the network. Where namespaces are
refused (some containers), the graph runs in the host's network on a free port of its own.

Everything the bridge starts (the master, roslaunch, the student's nodes) is its child, so
wrapping the bridge wraps them all. A stronger sandbox (bubblewrap) replaces
:func:`isolated_command` and nothing else.
"""

from __future__ import annotations

import functools
import shutil
from collections.abc import Sequence

from usar_replay.sandbox.kernel_sandbox import succeeds

__all__ = ["isolated_command", "netns_available"]

_LOOPBACK_UP = 'ip link set lo up && exec "$@"'


@functools.cache
def netns_available() -> bool:
    """True when ``unshare -rn`` with loopback up works here (tried once per process)."""
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return False
    return succeeds(["unshare", "-rn", "sh", "-c", _LOOPBACK_UP, "sh", "true"])


def isolated_command(argv: Sequence[str], *, isolate: bool = True) -> list[str]:
    """``argv`` as a command line that runs it in a fresh network namespace with loopback up
    (when ``isolate`` and the machine allows it), else ``argv`` itself."""
    if isolate and netns_available():
        return ["unshare", "-rn", "sh", "-c", _LOOPBACK_UP, "sh", *argv]
    return list(argv)
