"""When ``/clock`` may start: every node up, every subscription connected, the graph idle.

Why: a node that is still connecting when the first ``/clock`` arrives misses the first ticks'
messages, and how many it misses depends on the machine (the issue measured 4 to 8 ticks of
difference between two recordings). So the bridge holds ``/clock`` until

1. every node of the launch file (``roslaunch --nodes``, usar's stand-ins dropped:
   :mod:`.launch_filter`; with ``rosrun``, at least one node) has registered with the master;
2. every subscriber of every topic (the bridge's own subscriptions and the action clients'
   status, feedback and result included) is connected to every publisher of it, asked of each
   node through its slave API (``getBusInfo``: inbound connections per topic);
3. the graph has gone idle (:class:`.quiescence.Quiescence`).
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import signal
import subprocess
import time
import xmlrpc.client
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from usar_replay.ros1.launch_output import FACTS_PREFIX, nodes_command

__all__ = [
    "FACTS_PREFIX",
    "launch_listing",
    "missing_connections",
    "registered_nodes",
    "wait_until_ready",
]


FACTS_CAP = 256 * 1024
"""The most bytes of facts read (the team's launch files decide how many)."""

LISTING_CAP = 8 * 1024 * 1024
"""The most bytes of the listing's output read: the team's launch files decide what it prints
(``$(eval)``, ``<param command>``), and a listing past this says nothing (a launch file's node
list and facts are some kilobytes; the bridge's memory is not the team's to fill)."""

LISTING_WALL_S = 60.0
"""Wall seconds the listing may take (roslaunch parses the launch files and ends)."""


def launch_listing(
    script_prefix: str, package: str, launch: str, env: dict[str, str], plan: Path | None = None
) -> tuple[list[str], dict[str, Any] | None]:
    """The node names a launch file starts (``roslaunch --nodes``, ``plan`` followed; []
    where it cannot say) and what it configures for usar's stand-ins (the plan's ``facts``:
    the line the listing prints on its stdout, a pipe no other process of the run writes;
    None without one, or past :data:`FACTS_CAP`, or not a JSON object). A listing that fails,
    prints more than :data:`LISTING_CAP` or runs past :data:`LISTING_WALL_S` says neither."""
    out = _bounded_output(
        ["bash", "-c", f"{script_prefix} && exec {nodes_command(package, launch, plan)}"], env
    )
    if out is None:
        return [], None
    lines = out.decode("utf-8", "replace").splitlines()
    names = sorted(n.strip() for n in lines if n.strip().startswith("/"))
    facts: dict[str, Any] | None = None
    for line in lines:
        if line.startswith(FACTS_PREFIX) and len(line) <= FACTS_CAP:
            try:
                got = json.loads(line[len(FACTS_PREFIX) :])
            except (ValueError, RecursionError):
                got = None
            facts = got if isinstance(got, dict) else None
    return names, facts


def _bounded_output(argv: Sequence[str], env: dict[str, str]) -> bytes | None:
    """``argv``'s stdout, read as it comes and never past :data:`LISTING_CAP` bytes or
    :data:`LISTING_WALL_S` (then its process group is killed); None past either, or on a
    failed start or a non-zero exit."""
    try:
        proc = subprocess.Popen(
            argv,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
    except OSError:
        return None
    assert proc.stdout is not None
    data = bytearray()
    deadline = time.monotonic() + LISTING_WALL_S
    fd = proc.stdout.fileno()
    ok = True
    try:
        while True:
            ready, _, _ = select.select([fd], [], [], max(0.0, deadline - time.monotonic()))
            block = os.read(fd, 65536) if ready else None
            if block is None or len(data) + len(block) > LISTING_CAP:
                ok = False
                break
            if not block:
                break
            data += block
    finally:
        if not ok:
            with contextlib.suppress(OSError):
                os.killpg(proc.pid, signal.SIGKILL)
        proc.stdout.close()
        code = proc.wait()
    return bytes(data) if ok and code == 0 else None


def registered_nodes(master: Any, caller: str) -> set[str]:
    """The nodes with a publication, subscription or service at the master, but ``caller``
    and ``/rosout``."""
    _code, _msg, state = master.getSystemState(caller)
    nodes = {str(n) for group in state for _topic, names in group for n in names}
    return nodes - {caller, "/rosout"}


class _TimedTransport(xmlrpc.client.Transport):
    """An XML-RPC transport that gives up after :data:`NODE_ANSWER_S` (a node's slave API is
    the package's code: one that never answers must not hold the bridge)."""

    def make_connection(self, host: Any) -> Any:
        conn = super().make_connection(host)
        conn.timeout = NODE_ANSWER_S
        return conn


NODE_ANSWER_S = 2.0
"""Wall seconds a node's ``getBusInfo`` may take (then it counts as not connected)."""


def _inbound(uri: str, caller: str) -> dict[str, set[str]]:
    """topic -> the publishers a node's subscriptions are connected to (its ``getBusInfo``)."""
    proxy: Any = xmlrpc.client.ServerProxy(uri, transport=_TimedTransport())
    code, _msg, info = proxy.getBusInfo(caller)
    out: dict[str, set[str]] = {}
    if code != 1:
        return out
    for conn in info:
        if len(conn) >= 5 and conn[2] == "i" and (len(conn) < 6 or conn[5]):
            out.setdefault(str(conn[4]), set()).add(str(conn[1]))
    return out


def missing_connections(master: Any, caller: str) -> list[str]:
    """``node topic: n of m publishers`` for each subscription not yet connected to every
    publisher of its topic (empty: all connected)."""
    _code, _msg, (pubs, subs, _srvs) = master.getSystemState(caller)
    publishers = {topic: set(names) for topic, names in pubs}
    missing: list[str] = []
    inbound: dict[str, dict[str, set[str]]] = {}
    for topic, names in sorted(subs):
        for node in sorted(names):
            want = len(publishers.get(topic, set()) - {node})
            if want == 0:
                continue
            if node not in inbound:
                code, _m, uri = master.lookupNode(caller, node)
                try:
                    inbound[node] = _inbound(uri, caller) if code == 1 else {}
                except OSError:
                    inbound[node] = {}
            have = len(inbound[node].get(topic, set()))
            if have < want:
                missing.append(f"{node} {topic}: {have} of {want} publishers")
    return missing


def wait_until_ready(
    master: Any,
    caller: str,
    expected: Sequence[str],
    idle: Callable[[float], bool],
    alive: Callable[[], None],
    timeout_s: float,
) -> None:
    """Return once the graph is ready for the first ``/clock`` (see the module docstring);
    ``alive`` raises when the graph ended, ``idle(cap)`` waits for quiescence. Raises
    RuntimeError naming what is missing after ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    why = "registered no node with the master"
    while time.monotonic() < deadline:
        alive()
        nodes = registered_nodes(master, caller)
        absent = sorted(set(expected) - nodes)
        if not nodes or absent:
            why = "registered no node with the master"
            if absent and nodes:
                why = f"not registered: {', '.join(absent)}"
            time.sleep(0.05)
            continue
        missing = missing_connections(master, caller)
        if missing:
            why = "not connected: " + "; ".join(missing[:4])
            time.sleep(0.02)
            continue
        if not idle(2.0):
            why = "the graph did not go idle"
            continue
        if not missing_connections(master, caller):  # nothing connected or left meanwhile
            return
    raise RuntimeError(f"the ROS graph was not ready within {timeout_s:g} s ({why})")
