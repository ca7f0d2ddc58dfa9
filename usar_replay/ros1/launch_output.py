"""Each node's stdout and stderr in a file of its own: ``roslaunch`` as it is, one prefix added.

Why: with ``output="screen"`` every node writes to roslaunch's own terminal, one shared stream;
roslaunch's ``--log`` puts a node's stdout in a file but its stderr still in the shared stream.
usar keeps each node's output in the log (an attachment per node), so every node gets a
``launch-prefix`` of usar's (before the student's own, if any) that sends its stdout and stderr,
in the order written, to ``OUTPUT_DIR/<node>.out`` and makes its stdout line-buffered (``stdbuf
-oL``: what is printed before a crash is not lost in a buffer). The launch file is not changed:
this module, run as a script by Debian's ``/usr/bin/python3`` (it imports only the standard
library and roslaunch), wraps roslaunch's config loading and then runs ``roslaunch.main()``.
It also writes the launch file's nodes (name, package, type) to a list, for ``usar info``.

``rosrun PKG EXE`` (``--node``) gets the same redirection around ``rosrun`` itself.

The files are written by the student's processes (in the run's folder inside the sandbox); the
recorder reads them as untrusted (:mod:`usar_replay.ros1.run_files`).
"""

from __future__ import annotations

import os
import re
import shlex
import sys
from pathlib import Path
from typing import Any

__all__ = ["OUTPUT_SUFFIX", "file_label", "launch_command", "rosrun_command", "without_prefix"]

OUTPUT_SUFFIX = ".out"
STDBUF = "/usr/bin/stdbuf"
_REDIRECT = 'exec "$@" >>"$0" 2>&1'
"""``sh -c`` body: ``$0`` is the output file, the rest the node's command (exec: same pid, so
roslaunch sees the node's own exit code)."""


_SHOWN_PREFIX = re.compile(
    r"(?:" + re.escape(STDBUF) + r" -oL )?/bin/sh -c " + re.escape(_REDIRECT) + r" \S+ "
)


def without_prefix(text: str) -> str:
    """roslaunch's lines (``process has died [..., cmd ...]``) without usar's prefix: the
    node's command as the student wrote it."""
    return _SHOWN_PREFIX.sub("", text)


def file_label(node_name: str) -> str:
    """``/ns/explorer`` -> ``ns+explorer`` (``+`` is never part of a ROS name)."""
    return node_name.strip("/").replace("/", "+") or "node"


def _prefix(output: str) -> list[str]:
    head = [STDBUF, "-oL"] if os.path.exists(STDBUF) else []
    return [*head, "/bin/sh", "-c", _REDIRECT, output]


def launch_command(output_dir: Path, nodes_file: Path, package: str, launch: str) -> str:
    """The shell words that run ``roslaunch PACKAGE LAUNCH`` through this module."""
    # -P: this file's folder (usar's ros1 modules: build.py, process.py, ...) is not put on
    # sys.path, where it could shadow a module roslaunch imports
    words = ["python3", "-P", str(Path(__file__).resolve()), str(output_dir), str(nodes_file)]
    return shlex.join([*words, package, launch])


def rosrun_command(output_dir: Path, package: str, node: str) -> str:
    """The shell words that run ``rosrun PACKAGE NODE`` with its output in its own file."""
    output = output_dir / (file_label(Path(node).name) + OUTPUT_SUFFIX)
    return shlex.join([*_prefix(str(output)), "rosrun", package, node])


def _prefixed(config: Any, output_dir: str, nodes_file: str) -> Any:
    """Every node of a loaded roslaunch config with usar's prefix; the node list written."""
    rows = []
    for node in config.nodes:
        name = (node.namespace or "/").rstrip("/") + "/" + str(node.name)
        output = os.path.join(output_dir, file_label(name) + OUTPUT_SUFFIX)
        own = f" {node.launch_prefix}" if node.launch_prefix else ""
        node.launch_prefix = shlex.join(_prefix(output)) + own
        rows.append(f"{name}\t{node.package}\t{node.type}\n")
    with open(nodes_file, "w", encoding="utf-8") as f:
        f.writelines(rows)
    return config


def main(argv: list[str]) -> None:
    """``python3 launch_output.py OUTPUT_DIR NODES_FILE ROSLAUNCH_ARGS...``."""
    import roslaunch
    import roslaunch.config

    output_dir, nodes_file, rest = argv[1], argv[2], argv[3:]
    load = roslaunch.config.load_config_default

    def load_prefixed(*args: Any, **kwargs: Any) -> Any:
        return _prefixed(load(*args, **kwargs), output_dir, nodes_file)

    roslaunch.config.load_config_default = load_prefixed
    roslaunch.main(["roslaunch", *rest])


if __name__ == "__main__":
    main(sys.argv)
