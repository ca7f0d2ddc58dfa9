"""What a ROS 1 run leaves in its private folder for the log: each node's output, the launch
file's nodes, the parameters the nodes read.

Why a module of its own: these files are written inside the kernel sandbox, by the student's
processes or next to them (the run's folder is the one place they may write), and read after
the run by the recorder, outside it. So they are read as untrusted input: the folder and each
file opened with ``O_NOFOLLOW`` relative to the run's folder (a symlink planted there is not
followed), only regular files with one link (no hard link to someone else's file), never more
than a fixed number of bytes, names checked. A node's output longer than
:data:`OUTPUT_HEAD` + :data:`OUTPUT_TAIL` keeps its beginning and its end, with a line saying
how much was left out between them.

The files:

* ``output/<node>.out``: a node's stdout and stderr, in the order written
  (:mod:`.launch_output`);
* :data:`NODES_FILE`: the launch file's nodes, one ``name TAB package TAB type`` per line;
* :data:`REPLACED_FILE`: the launch file's nodes usar did not start, its stand-ins doing their
  job (:mod:`.launch_filter`), in the same form; :data:`LAUNCH_PLAN` is the bridge's plan for
  them (written before the package runs, read by roslaunch's side only);
* :data:`MASTER_LOG`: the ROS master's log of every API call, from which the parameters each
  node read (``getParam``, ``hasParam``, ``searchParam``, ``subscribeParam``) and the nodes that
  registered (for ``rosrun``, which has no launch file to list them) are taken.
"""

from __future__ import annotations

import contextlib
import os
import re
import stat
from collections.abc import Iterator
from pathlib import Path

from usar_replay.core.safe_text import team_lines
from usar_replay.ros1.launch_output import OUTPUT_SUFFIX

__all__ = [
    "APPLIED_SETTINGS",
    "LAUNCH_PLAN",
    "MASTER_LOG",
    "NODES_FILE",
    "OUTPUT_DIR",
    "OUTPUT_HEAD",
    "OUTPUT_TAIL",
    "launch_nodes",
    "node_outputs",
    "node_tails",
    "parameters_read",
    "REPLACED_FILE",
    "registered_nodes",
    "replaced_nodes",
]

OUTPUT_DIR = "output"
NODES_FILE = "launch_nodes.tsv"
REPLACED_FILE = "launch_replaced.tsv"
LAUNCH_PLAN = "launch_plan.json"
MASTER_LOG = "master_api.log"
OUTPUT_HEAD = 16 * 1024
"""Bytes kept from the start of a node's output (its start-up lines)."""
OUTPUT_TAIL = 48 * 1024
"""Bytes kept from the end of a node's output (what it said last, before a crash)."""
MAX_NODES = 64
"""At most this many nodes' outputs (and launch file rows) are kept."""
_MASTER_LOG_CAP = 32 * 1024 * 1024

APPLIED_SETTINGS = ("record", "detector", "mission.xy_tolerance", "mission.yaw_tolerance")
"""The settings a ROS 1 run applies on usar's side (``usar info`` lists only these): the
recording's clock, rates and limits, usar's detector (aruco_detect's role) and usar's move_base
goal tolerances (those two only where the user gave them: :mod:`.nav_params`). The other
``mission.*`` settings are the Python mission's; a package is only
offered them as ``/mission/*`` parameters, and ``usar info`` lists those its nodes read."""

_LABEL = re.compile(r"[A-Za-z0-9_.+-]{1,200}")
_NODE_NAME = re.compile(r"/[A-Za-z0-9_/~]{0,200}")
_MASTER_CALL = re.compile(
    r"\b(getParam|hasParam|searchParam|subscribeParam|registerPublisher|registerSubscriber"
    r"|registerService)\('([^'\s]{1,200})', '([^'\s]{1,200})'"
)
_ROS_INTERNAL = re.compile(
    r"/(use_sim_time|enable_statistics|tcp_keepalive|rosout_disable_topics_generation"
    r"|statistics_window_\w+)|.*/actionlib_client_(pub|sub)_queue_size"
)
"""Parameters every roscpp/rospy node or actionlib client reads by itself: not the package's
choice, so not listed."""
_NOT_NODES = ("/usar_sim", "/roslaunch", "/rosout", "/rostopic", "/rosparam")
"""Callers that are not the package's nodes: usar's own node, roslaunch, ROS's tools."""


@contextlib.contextmanager
def _dir(run_dir: Path, *parts: str) -> Iterator[int | None]:
    """A descriptor of ``run_dir/parts...``, each part opened without following a symlink."""
    fd: int | None = os.open(run_dir, os.O_RDONLY | os.O_DIRECTORY)
    try:
        for part in parts:
            assert fd is not None
            try:
                sub = os.open(part, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW, dir_fd=fd)
            except OSError:
                os.close(fd)
                fd = None
                break
            os.close(fd)
            fd = sub
        yield fd
    finally:
        if fd is not None:
            os.close(fd)


def _read(dir_fd: int, name: str, head: int, tail: int) -> tuple[bytes, bytes, int] | None:
    """(first ``head`` bytes, last ``tail`` bytes or b"" when all fit, size) of a regular file
    of one link; None for anything else."""
    try:
        fd = os.open(name, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK, dir_fd=dir_fd)
    except OSError:
        return None
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode) or st.st_nlink != 1:
            return None
        size = st.st_size
        if size <= head + tail:
            return f.read(head + tail), b"", size
        first = f.read(head)
        f.seek(size - tail)
        return first, f.read(tail), size


_LATEST_RACE = re.compile(rb"^INFO: cannot create a symlink to latest log directory[^\n]*\n?", re.M)
"""rosgraph's own line (``roslogging.renew_latest_logdir``), printed by a rospy process when
another one (roslaunch, a node starting beside it) renewed ``ROS_LOG_DIR/latest`` between its
``lexists`` and its ``remove``: a race of rosgraph's, which process loses it the machine's
timing decides (one recording had it, the next did not), and the line names the host's run
folder. It says nothing of the team's code, so a node's output is kept without it."""


def _output_text(first: bytes, last: bytes, size: int) -> bytes:
    left_out = size - len(first) - len(last)
    first, last = _LATEST_RACE.sub(b"", first), _LATEST_RACE.sub(b"", last)
    if not last:
        return first
    note = (
        f"\n[usar: {left_out} bytes of this node's output left out here; the log keeps its "
        f"first {OUTPUT_HEAD // 1024} KiB and its last {OUTPUT_TAIL // 1024} KiB]\n"
    )
    return first + note.encode() + last


def _labels(dir_fd: int) -> list[str]:
    names = sorted(n for n in os.listdir(dir_fd) if n.endswith(OUTPUT_SUFFIX))
    labels = [n.removesuffix(OUTPUT_SUFFIX) for n in names]
    return [label for label in labels if _LABEL.fullmatch(label)][:MAX_NODES]


def node_outputs(run_dir: Path) -> list[tuple[str, bytes]]:
    """Each node's output as (label, bytes), bounded (see the module doc), by label."""
    out: list[tuple[str, bytes]] = []
    with _dir(run_dir, OUTPUT_DIR) as fd:
        if fd is None:
            return out
        for label in _labels(fd):
            got = _read(fd, label + OUTPUT_SUFFIX, OUTPUT_HEAD, OUTPUT_TAIL)
            if got is not None:
                out.append((label, _output_text(*got)))
    return out


def node_tails(output_dir: Path, lines: int = 40) -> str:
    """The last lines of each node's output, ``[label] line`` each (for a crash's reason; run
    inside the sandbox by the bridge, beside the nodes)."""
    per_node = max(5, lines // 4)
    text = ""
    for label, data in node_outputs(output_dir.parent) if output_dir.is_dir() else []:
        last = team_lines(data.decode("utf-8", errors="replace").rstrip("\n"))[-per_node:]
        text += "".join(f"[{label}] {line}\n" for line in last)
    return text


def launch_nodes(run_dir: Path, name: str = NODES_FILE) -> list[tuple[str, str, str]]:
    """The launch file's nodes as (name, package, type); empty for ``rosrun``."""
    with _dir(run_dir) as fd:
        got = None if fd is None else _read(fd, name, 64 * 1024, 0)
    if got is None:
        return []
    rows: list[tuple[str, str, str]] = []
    for line in got[0].decode("utf-8", errors="replace").splitlines():
        fields = line.split("\t")
        if len(fields) == 3 and _NODE_NAME.fullmatch(fields[0]):
            rows.append((fields[0], fields[1][:200], fields[2][:200]))
    return rows[:MAX_NODES]


def replaced_nodes(run_dir: Path) -> list[tuple[str, str, str]]:
    """The launch file's nodes usar did not start, as (name, package, type)."""
    return launch_nodes(run_dir, REPLACED_FILE)


def _master_calls(run_dir: Path) -> list[tuple[str, str, str]]:
    """(method, caller, first argument) of each parameter read and registration the master
    logged, by a caller that is one of the package's nodes."""
    half = _MASTER_LOG_CAP // 2
    with _dir(run_dir) as fd:
        got = None if fd is None else _read(fd, MASTER_LOG, half, half)
    if got is None:
        return []
    text = (got[0] + b"\n" + got[1]).decode("utf-8", errors="replace")
    return [
        (method, caller, key)
        for method, caller, key in _MASTER_CALL.findall(text)
        if not caller.startswith(_NOT_NODES) and _NODE_NAME.fullmatch(caller)
    ]


def parameters_read(run_dir: Path) -> dict[str, list[str]]:
    """The parameters the package's nodes asked the master for: name -> the nodes, sorted
    (not those every ROS node reads by itself, such as ``/use_sim_time``)."""
    read: dict[str, set[str]] = {}
    for method, caller, key in _master_calls(run_dir):
        if method.startswith("register") or not _NODE_NAME.fullmatch(key):
            continue
        if not _ROS_INTERNAL.fullmatch(key):
            read.setdefault(key, set()).add(caller)
    return {key: sorted(nodes) for key, nodes in sorted(read.items())}


def registered_nodes(run_dir: Path) -> list[str]:
    """The package's nodes as they registered with the master (a publisher, a subscriber or a
    service), sorted."""
    names = {caller for method, caller, _ in _master_calls(run_dir) if method.startswith("reg")}
    return sorted(names)[:MAX_NODES]
