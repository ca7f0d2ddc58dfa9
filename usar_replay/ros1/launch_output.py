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
Before that, the loaded config goes through usar's plan (:mod:`.launch_filter`): the nodes usar
stands in for are dropped (and listed in a file of their own), usar's parameters win.
``--nodes`` (the bridge's list of nodes to wait for) goes through the same plan.

``rosrun PKG EXE`` (``--node``) gets the same redirection around ``rosrun`` itself.

The files are written by the student's processes (in the run's folder inside the sandbox); the
recorder reads them as untrusted (:mod:`usar_replay.ros1.run_files`).
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = [
    "OUTPUT_SUFFIX",
    "file_label",
    "launch_command",
    "nodes_command",
    "rosrun_command",
    "start_file",
    "without_prefix",
]

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


def launch_command(
    output_dir: Path, nodes_file: Path, package: str, launch: str, plan: Path | None = None
) -> str:
    """The shell words that run ``roslaunch PACKAGE LAUNCH`` through this module, following
    ``plan`` (:mod:`.launch_filter`) when given."""
    # -P: this file's folder (usar's ros1 modules: build.py, process.py, ...) is not put on
    # sys.path, where it could shadow a module roslaunch imports
    words = ["python3", "-P", str(Path(__file__).resolve()), str(output_dir), str(nodes_file)]
    return shlex.join([*words, str(plan or "-"), *([package] if package else []), launch])


def nodes_command(package: str, launch: str, plan: Path | None = None) -> str:
    """The shell words that print the nodes ``roslaunch PACKAGE LAUNCH`` starts (``roslaunch
    --nodes``), ``plan`` followed."""
    words = ["python3", "-P", str(Path(__file__).resolve()), "-", "-", str(plan or "-")]
    return shlex.join([*words, "--nodes", *([package] if package else []), launch])


def start_file(package: str, launch_rel: str, node: str) -> str:
    """A launch file of usar's that starts a package's launch file and one of its executables
    together, as a TA's two terminals do (``roslaunch PKG FILE``, then ``rosrun PKG EXE``):
    the launch file included as it is, the executable as a node named after it (``.py`` left
    out; roslaunch
    gives every node a name: ``__name:=EXE``, where ``rosrun`` leaves the name ``ros::init``
    chose)."""
    from xml.sax.saxutils import quoteattr

    name = re.sub(r"[^A-Za-z0-9_]", "_", node.removesuffix(".py"))
    name = name if name[:1].isalpha() else "n_" + name
    include = f"$(find {package})/{launch_rel}"
    return (
        "<launch>\n"
        f"  <include file={quoteattr(include)}/>\n"
        f"  <node pkg={quoteattr(package)} type={quoteattr(node)} name={quoteattr(name)}"
        ' output="screen"/>\n'
        "</launch>\n"
    )


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


def _sibling(name: str) -> ModuleType:
    """usar's module ``name`` beside this file, loaded by path (this script runs in Debian's
    Python, which has no usar, with ``-P``: its folder is not on ``sys.path``)."""
    spec = importlib.util.spec_from_file_location(
        f"usar_{name}", Path(__file__).resolve().parent / f"{name}.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _write_facts(
    plan: dict[str, Any],
    params: dict[str, Any],
    dropped: list[Any],
    sources: dict[str, tuple[str, str]],
    targets: list[tuple[str, int, str]],
) -> None:
    """What the launch file configures for usar's stand-ins (:mod:`.nav_params`) and where the
    course's targets were replaced (:mod:`.launch_filter`), as one JSON line on stdout (the
    bridge reads it, bounded: :func:`usar_replay.ros1.pacing.graph_start.launch_listing`)."""
    import json

    param_sources = _sibling("param_sources")
    package_dir = ""
    if plan.get("package"):
        try:
            import rospkg

            package_dir = str(rospkg.RosPack().get_path(str(plan["package"])))
        except Exception:  # noqa: BLE001 - a label only: the path itself then
            package_dir = ""

    def label(path: str) -> str:
        return str(param_sources.label(path, package_dir))

    nav = _sibling("nav_params").facts(params, dropped, sources, plan.get("robots", ()), label)
    rows = []
    for key, k, how in targets[:256]:
        yaml_file, launch = sources.get(key, ("", ""))
        where = label(yaml_file) + (f" ({label(launch)})" if launch else "") if yaml_file else (
            f"a <param> in {label(launch)}" if launch else "the launch file"
        )
        rows.append({"param": key, "target": k, "how": how, "source": where})
    nav["targets"] = rows
    # on the listing's stdout, a pipe to the bridge: a file in the run folder was the team's
    # to rewrite before the bridge or the recorder read it (a forged goal tolerance widens the
    # rubric's radii)
    print(FACTS_PREFIX + json.dumps(nav, sort_keys=True), flush=True)


FACTS_PREFIX = "usar-facts "
"""The listing's stdout line that carries the facts (node names start with ``/``)."""


def main(argv: list[str]) -> None:
    """``python3 launch_output.py OUTPUT_DIR NODES_FILE PLAN ROSLAUNCH_ARGS...`` (``-`` for
    OUTPUT_DIR and NODES_FILE with ``--nodes``, for PLAN when there is none)."""
    # roslaunch is Debian's and this module usar's: neither imports a module of a workspace's
    # devel space (the team's CMake writes it: a planted roslib or rosgraph would run here);
    # the nodes still get the team's PYTHONPATH, which roslaunch passes on in their environment
    sys.path[:] = [p for p in sys.path if "/devel/lib/python3/dist-packages" not in p]
    import roslaunch
    import roslaunch.config
    import roslaunch.node_args

    output_dir, nodes_file, plan_file, rest = argv[1], argv[2], argv[3], argv[4:]
    launch_filter = _sibling("launch_filter")
    plan = launch_filter.load_plan(plan_file) if plan_file != "-" else {}
    load = roslaunch.config.load_config_default
    sources = _sibling("param_sources").install()

    def load_planned(*args: Any, **kwargs: Any) -> Any:
        config = load(*args, **kwargs)
        facts = {k: p.value for k, p in config.params.items()}  # before the plan changes them
        targets: list[tuple[str, int, str]] = []
        dropped = launch_filter.apply(config, plan, targets)
        if output_dir == "-" and plan.get("facts"):
            try:
                _write_facts(plan, facts, dropped, dict(sources), targets)
            except Exception as err:  # noqa: BLE001 - the listing goes on: the template's then
                print(f"usar: the launch file's facts not written: {err!r}", file=sys.stderr)
        if output_dir != "-":
            if dropped and not config.nodes:  # roslaunch would wait for nothing, for good
                kinds = sorted({str(n.package) for n in dropped})
                raise SystemExit(
                    f"usar: the launch file starts only nodes usar stands in for "
                    f"({', '.join(kinds)}): start the team's own nodes in it"
                )
            if plan.get("replaced_file"):
                with open(plan["replaced_file"], "w", encoding="utf-8") as f:
                    f.writelines(launch_filter.rows(dropped))
            _prefixed(config, output_dir, nodes_file)
        return config

    roslaunch.config.load_config_default = load_planned
    roslaunch.node_args.load_config_default = load_planned  # ``--nodes`` took it by name
    roslaunch.main(["roslaunch", *rest])


if __name__ == "__main__":
    main(sys.argv)
