"""The student's processes in the bridge: ``roslaunch PKG FILE`` or ``rosrun PKG NODE`` started
in the built workspace's environment (the pacing shim preloaded, :mod:`.pacing.shim`), and what
the bridge asks of them: whether they ended and why, roslaunch's own word that it stops, and
their last output lines for a crash report.

One job, kept apart from the bridge's tick loop (:mod:`.bridge`): a crash report and the end's
exit status read the same files whatever the loop does.
"""

from __future__ import annotations

import contextlib
import re
import shlex
import signal
import subprocess
from pathlib import Path
from typing import Any

from usar_replay.core.safe_text import safe_line, team_lines
from usar_replay.ros1 import run_files
from usar_replay.ros1.launch_output import (
    OUTPUT_SUFFIX,
    launch_command,
    rosrun_command,
    start_file,
    without_prefix,
)
from usar_replay.ros1.pacing import shim
from usar_replay.ros1.pacing.proc_watch import ProcWatch
from usar_replay.ros1.start_prose import THIRD_COMMANDS

__all__ = ["START_FILE", "Graph", "launch_target", "tail"]

START_FILE = "usar_start.launch"
"""usar's launch file that starts a package's launch file and executable together."""

_DIED = re.compile(r"has died \[pid \d+, exit code (-?\d+)")
"""roslaunch's report of a node's death (exit code 0 is a clean end)."""
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]|\x1b\][^\x07]*\x07")


class Graph:
    """The student's processes: ``roslaunch PKG FILE`` or ``rosrun PKG NODE``, in the built
    workspace's environment; roslaunch's own output to a file, each node's stdout and stderr to
    a file of its own (:mod:`.launch_output`); their last lines are shown when it crashes."""

    def __init__(self, config: dict[str, Any], env: dict[str, str]) -> None:
        ws = Path(config["workspace"])
        run = Path(config["run_dir"])
        self.output_dir = run / run_files.OUTPUT_DIR
        self.output_dir.mkdir(exist_ok=True)
        if config.get("launch"):
            what = f"roslaunch {config['package']} {config['launch']}"
            if config.get("node"):
                what += f" with rosrun {config['package']} {config['node']}"
            nodes = run / run_files.NODES_FILE
            plan = run / run_files.LAUNCH_PLAN
            cmd = launch_command(self.output_dir, nodes, *launch_target(config), plan)
        else:
            what = f"rosrun {config['package']} {config['node']}"
            cmd = rosrun_command(self.output_dir, config["package"], config["node"])
        self.what = what
        self.log_path = run / "graph.log"
        self.setup = f'source "{ws}/devel/setup.bash"'
        script = f"{self.setup} && exec {cmd}"
        # the pacing shim in the package's processes only (:mod:`.shim`), the third commands'
        self._env = shim.preloaded(env, config.get("underlays", ()))
        with self.log_path.open("wb") as log:
            self.proc = subprocess.Popen(
                ["bash", "-c", script],
                cwd=run,
                env=self._env,
                stdin=subprocess.DEVNULL,
                stdout=log,
                stderr=subprocess.STDOUT,
            )
        self.watch = ProcWatch(self.proc.pid, launcher_is_package=not config.get("launch"))
        self._run = run
        self.after: list[subprocess.Popen[bytes]] = []
        """The TA's third commands (``rosservice call /start ...``), once started."""

    def run_after_launch(self, commands: list[str]) -> None:
        """Start each command as a TA types it in a third terminal, in the workspace's
        environment (the pacing shim preloaded), beside the graph, its output in a file of its
        own (``after_launch_N``); they run on (a service call whose callback is the mission
        returns when the mission does) and are stopped with the graph.

        Never through a shell (issue 50): each command is split into its words as the shell
        would (:func:`shlex.split`) and run as that argv, and only a ``rosservice call`` or a
        ``rostopic pub`` runs; any other is refused, its line in its output file (kept with
        the log). :mod:`.start` reads only such commands; this is the last check."""
        env: dict[str, str] | None = None
        for number, command in enumerate(commands, start=1):
            label = f"after_launch_{number}"
            out = self.output_dir / (label + OUTPUT_SUFFIX)
            argv = _third_argv(command)
            if argv is None:
                out.write_text(
                    f"usar: refused: not a rosservice call or rostopic pub: {safe_line(command)}\n",
                    encoding="utf-8",
                )
                continue
            env = env if env is not None else self._workspace_env()
            with out.open("wb") as f:
                self.after.append(
                    subprocess.Popen(
                        argv,
                        cwd=self._run,
                        env=env,
                        stdin=subprocess.DEVNULL,
                        stdout=f,
                        stderr=subprocess.STDOUT,
                    )
                )

    def _workspace_env(self) -> dict[str, str]:
        """The environment the workspace's ``setup.bash`` makes (what a TA's terminal has
        after sourcing it), read once from ``env -0``: the third commands start in it without
        a shell of their own."""
        done = subprocess.run(
            ["bash", "-c", f"{self.setup} && exec env -0"],
            cwd=self._run,
            env=self._env,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            timeout=60,
            check=False,
        )
        env = dict(self._env)
        if done.returncode == 0:
            pairs = (
                item.partition("=") for item in done.stdout.decode(errors="replace").split("\0")
            )
            env.update({k: v for k, sep, v in pairs if sep and k})
        return env

    def exit_status(self) -> tuple[int, str] | None:
        """None while running; (exit code, problem) once it ended: roslaunch exits 0 even when
        a node died, so its report of a death is the problem then."""
        code = self.proc.poll()
        if code is None:
            return None
        return code, self.death_reported()

    def death_reported(self) -> str:
        """roslaunch's report so far of a node that died with an error (empty: none)."""
        for line in tail(self.log_path, 400).splitlines():  # roslaunch's own lines
            died = _DIED.search(line)
            if died and int(died.group(1)) != 0:
                return without_prefix(line.strip())
        return ""

    def launcher_stopping(self) -> bool:
        """roslaunch said it stops the launch (a required node died, or all of them did)."""
        text = tail(self.log_path, 40)
        return "Initiating shutdown!" in text or "roslaunch will exit" in text

    def tail(self, lines: int = 40) -> str:
        """The nodes' last output lines (``[node] line``), then roslaunch's (terminal colours
        removed)."""
        text = run_files.node_tails(self.output_dir, lines) + tail(self.log_path, lines)
        return without_prefix(_ANSI.sub("", text))

    def stop(self) -> None:
        for proc in self.after:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        for proc in self.after:
            try:
                proc.wait(timeout=2.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if self.proc.poll() is None and self.watch.seen and self.watch.ended():
            self.proc.kill()  # the package is gone: roslaunch has nothing left to stop
            self.proc.wait()
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)  # roslaunch stops its nodes on SIGINT
            try:
                self.proc.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.watch.close()


def launch_target(config: dict[str, Any]) -> tuple[str, str]:
    """(package, launch file) for roslaunch: the package's own, or, where an executable is to
    run beside it, usar's launch file in the run's folder that starts both
    (:func:`.launch_output.start_file`; package '')."""
    if not config.get("node"):
        return str(config["package"]), str(config["launch"])
    path = Path(config["run_dir"]) / START_FILE
    if not path.exists():
        rel = str(config.get("launch_rel") or config["launch"])
        path.write_text(start_file(config["package"], rel, config["node"]), encoding="utf-8")
    return "", str(path)


def _third_argv(command: str) -> list[str] | None:
    """The words of a ``rosservice call`` / ``rostopic pub`` command, or None for any other
    (or one that does not split: an open quote)."""
    try:
        argv = shlex.split(command)
    except ValueError:
        return None
    return argv if tuple(argv[:2]) in THIRD_COMMANDS else None


def tail(path: Path, lines: int = 20) -> str:
    """The last ``lines`` lines of a log file (empty when it cannot be read)."""
    with contextlib.suppress(OSError):
        return "\n".join(team_lines(path.read_text(errors="replace").rstrip("\n"))[-lines:])
    return ""
