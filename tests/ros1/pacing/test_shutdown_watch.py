"""ros1/shutdown_watch: a shutdown held until its processes exited and were collected."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import xmlrpc.client
import xmlrpc.server
from collections.abc import Iterator
from typing import Any

import pytest
from proctools import child as start_child

from usar_replay.ros1.pacing.shutdown_watch import ShutdownWatch, exited, node_pids, reaped

# a launcher as roslaunch: starts a node, collects it on a 0.1 s poll; the node exits when the
# launcher closes its stdin, which it does when the test writes a line to the launcher
_LAUNCHER = (
    "import subprocess, sys, time\n"
    "node = subprocess.Popen([sys.executable, '-c', 'import sys; sys.stdin.read()'],"
    " stdin=subprocess.PIPE)\n"
    "print(node.pid, flush=True)\n"
    "sys.stdin.readline()\n"
    "node.stdin.close()\n"
    "while node.poll() is None: time.sleep(0.1)\n"
    "sys.stdin.readline()\n"
)


@pytest.fixture
def launcher() -> Iterator[tuple[subprocess.Popen[str], int]]:
    proc = subprocess.Popen(
        [sys.executable, "-c", _LAUNCHER], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout is not None
    node = int(proc.stdout.readline())
    try:
        yield proc, node
    finally:
        proc.kill()
        proc.wait()


def test_a_main_thread_entering_an_untimed_wait_is_a_sign_once() -> None:
    watch = ShutdownWatch()
    assert watch.starting({10}) == {10}
    assert watch.starting({10}) == set()  # still waiting: not a new sign
    assert watch.starting({10, 11}) == {11}
    assert watch.starting(set()) == set()
    assert watch.starting({10}) == {10}  # it left the wait and entered one again


def test_the_hold_lasts_until_the_node_exited_and_its_launcher_collected_it(
    launcher: tuple[subprocess.Popen[str], int],
) -> None:
    proc, node = launcher
    assert proc.stdin is not None
    watch = ShutdownWatch()
    assert not exited(node)
    proc.stdin.write("stop\n")
    proc.stdin.flush()
    held = watch.hold({node})
    assert reaped(node)
    assert held.exited == (node,)
    assert not held.capped
    assert proc.poll() is None  # the launcher is still there: it collected its node
    assert watch.summary().startswith("1 shutdown holds (longest ")


def test_without_a_launcher_the_hold_ends_at_the_exit() -> None:
    # the bridge's own child (rosrun): a zombie until the bridge collects it
    node = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"], stdin=-1)
    assert node.stdin is not None
    try:
        node.stdin.close()
        held = ShutdownWatch(collected_by_launcher=False).hold({node.pid})
        assert exited(node.pid) and not reaped(node.pid)
        assert held.exited == (node.pid,) and not held.capped
    finally:
        node.kill()
        node.wait()


def test_a_process_that_does_not_exit_ends_the_hold_at_its_cap() -> None:
    busy = start_child("import signal; signal.pause()")
    try:
        watch = ShutdownWatch(hold_cap_s=0.05)
        held = watch.hold({busy.pid})
        assert held.capped and held.exited == ()
        assert held.wall_s >= 0.05
        longest = f"{held.wall_s * 1000:.0f} ms"
        assert watch.summary() == f"1 shutdown holds (longest {longest}, 1 capped)"
        # a false sign costs one hold: its main thread's waits are no sign any more
        assert watch.starting({busy.pid}) == set()
    finally:
        busy.kill()
        busy.wait()


def test_node_pids_asks_each_node_for_its_pid() -> None:
    # a master and a node's slave API, as XML-RPC servers (the calls the ROS master answers)
    node = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False)
    node.register_function(lambda caller: [1, "", os.getpid()], "getPid")
    uri = f"http://127.0.0.1:{node.server_address[1]}/"

    def lookup(caller: str, name: str) -> list[Any]:
        return [1, "", uri] if name == "/talker" else [-1, "unknown node", ""]

    master = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False)
    master.register_function(lookup, "lookupNode")
    servers = [node, master]
    for server in servers:
        threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        proxy = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{master.server_address[1]}/")
        assert node_pids(proxy, "/usar_sim", ["/talker", "/gone"]) == {"/talker": os.getpid()}
    finally:
        for server in servers:
            server.shutdown()
            server.server_close()
