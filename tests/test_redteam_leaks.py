"""Red team, issue 26's leaks and lies: what a mission may see, print and be called.

- 9: a mission kept next to the grader's files (world, world key, settings, the output, and a
  hard link and a symlink to a world kept elsewhere) reads none of them, and still imports its
  own helper module.
- 10: a mission's crash text and log lines full of terminal escape sequences reach the
  terminal with every control character escaped (``usar record``, ``usar log``, ``usar info``).
- 11: a process killed by SIGKILL is ``crashed (signal 9)``, not ``out_of_memory`` (a Python
  mission here; the ROS 1 bridge killed by its own node in :mod:`test_ros1`'s way below).

Needs bubblewrap (CI installs it): skipped only where it is missing or cannot make namespaces.
"""

from __future__ import annotations

import os
import shutil
import textwrap
from pathlib import Path

import pytest
from clitools import usar
from conftest import one_room

from usar_replay.cli.main import main
from usar_replay.log.run import open_run
from usar_replay.node.jail import bwrap_available
from usar_replay.ros1 import debian
from usar_replay.world.scenario_toml import save

_OK, _WHY = bwrap_available()
pytestmark = pytest.mark.skipif(not _OK, reason=f"no kernel sandbox here: {_WHY}")

SECRET = "SECRET-7f3a"


def _world(path: Path) -> Path:
    save(one_room(), path)
    path.write_text(path.read_text() + f"\n# {SECRET} world {path.name}\n")
    return path


def _record(folder: Path, source: str, *options: str, out: Path | None = None) -> tuple[int, Path]:
    mission = folder / "mission.py"
    mission.write_text(textwrap.dedent(source))
    out = out or folder / "run.mcap"
    args = ["record", "--mission", str(mission), "--max-sim-time", "1", "--out", str(out)]
    return main([*args, "--quiet", *options]), out


READER = """
    import os
    import helper  # its own module, next to it: still importable

    def main():
        said = [helper.NAME]
        for name in {names!r}:
            try:
                with open(name, "rb") as f:
                    data = f.read()
                seen = "secret" if b"{secret}" in data else "plain"
                said.append(f"{{os.path.basename(name)}}=read:{{seen}}")
            except OSError as err:
                said.append(f"{{os.path.basename(name)}}=refused:{{type(err).__name__}}")
        raise RuntimeError("READ " + " | ".join(said))
"""


def test_grader_files_beside_the_mission_stay_unread(tmp_path: Path) -> None:
    """Point 9: the world, world key, settings and output next to the mission, a hard link and
    a symlink to a world kept elsewhere, and the log being written: none is readable (an empty
    file or no file); the mission's own module is."""
    team = tmp_path / "team"
    team.mkdir()
    (team / "helper.py").write_text("NAME = 'helper-ok'\n")
    world = _world(team / "world.toml")
    key = team / "world.key"
    key.write_text(f"{SECRET}-key-0123456789abcdef0123456789abcdef\n")
    settings = team / "settings.toml"
    settings.write_text(f"# {SECRET} settings\n[mission]\n")
    elsewhere = _world(tmp_path / "elsewhere.toml")  # --scenario of the second run
    os.link(elsewhere, team / "hardlink.toml")
    (team / "symlink.toml").symlink_to(elsewhere)
    old = team / "old.mcap"  # a previous output, overwritten by this run
    old.write_text(f"{SECRET} previous log\n")
    names = [str(p) for p in (world, key, settings, old, team / "old.mcap.part")]
    names += [str(team / "hardlink.toml"), str(team / "symlink.toml")]
    for scenario in (world, elsewhere):
        code, out = _record(
            team,
            READER.format(names=names, secret=SECRET),
            "--scenario", str(scenario), "--world-key", str(key), "--settings", str(settings),
            "--overwrite",
            out=old,
        )  # fmt: skip
        assert code == 4
        run = open_run(out)
        assert run.outcome == "crashed", run.outcome_reason
        said = run.outcome_reason
        assert "READ helper-ok" in said, said
        # /dev/null over each: a sandbox may not open it (a PermissionError, not a read)
        for name in ("world.key", "settings.toml", "old.mcap", "old.mcap.part"):
            assert f"{name}=refused:PermissionError" in said, said
        if scenario == world:
            assert "world.toml=refused:PermissionError" in said, said
            assert "hardlink.toml=read:secret" in said  # not the grader's in this run
        else:  # the world passed in, by another name: hidden too; its symlink leads nowhere
            assert "hardlink.toml=refused:PermissionError" in said, said
            assert "symlink.toml=refused:FileNotFoundError" in said, said
    # the grader's files are untouched
    assert SECRET in world.read_text() and SECRET in key.read_text()
    assert (team / "hardlink.toml").read_text() == elsewhere.read_text()


ESCAPES = "\x1b[2J\x1b[H\x1b]0;pwned\x07\r4/4 markers ... done\x1b[?25l\u202e"

SHOUTER = f"""
    from usar_replay.api import Node

    class Shout(Node):
        def __init__(self):
            super().__init__("shout\\x1b[31m")
            self.create_timer(0.1, self.tick)
            self.n = 0

        def tick(self):
            self.n += 1
            self.get_logger().info({ESCAPES!r} + "\\nsecond line\\tend")
            if self.n == 3:
                raise RuntimeError({ESCAPES!r})

    def main():
        Shout()
"""


def _no_controls(text: str) -> None:
    bad = [ch for ch in text if ch not in "\n\t" and (ord(ch) < 0x20 or 0x7F <= ord(ch) < 0xA0)]
    assert not bad and "\u202e" not in text, repr(text[:400])


def test_mission_text_is_printed_escaped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Point 10: the crash text and log lines reach the terminal escaped, readable."""
    code, out = _record(tmp_path, SHOUTER, "--scenario", str(_world(tmp_path / "w.toml")))
    assert code == 4
    shown = capsys.readouterr()
    _no_controls(shown.out + shown.err)
    assert "\\x1b[2J\\x1b[H" in shown.out and "4/4 markers ... done" in shown.out, shown.out
    assert "\\u202e" in shown.out
    assert "Traceback (most recent call last):\n" in shown.out  # lines stay lines
    assert open_run(out).outcome_reason.count("\x1b") >= 4  # the log keeps the bytes as sent
    info = usar("info", str(out))
    _no_controls(info.stdout + info.stderr)
    logged = usar("log", str(out))
    _no_controls(logged.stdout + logged.stderr)
    assert "[shout\\x1b[31m]: \\x1b[2J\\x1b[H" in logged.stdout, logged.stdout
    assert "second line" in logged.stdout and "\\t" not in logged.stdout  # tabs, lines kept


KILLER = """
    import os
    import signal
    from usar_replay.api import Node

    class Killer(Node):
        def __init__(self):
            super().__init__("killer")
            self.create_timer(0.1, lambda: os.kill(os.getpid(), signal.SIGKILL))

    def main():
        Killer()
"""


def test_a_killed_mission_is_crashed_by_signal_not_out_of_memory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Point 11: SIGKILL with no out-of-memory record is ``crashed (signal 9)``."""
    code, out = _record(tmp_path, KILLER, "--scenario", str(_world(tmp_path / "w.toml")))
    assert code == 4
    run = open_run(out)
    assert run.outcome == "crashed", run.outcome
    assert "crashed (signal 9)" in run.outcome_reason and "SIGKILL" in run.outcome_reason
    assert "memory" not in run.outcome_reason
    assert "crashed (signal 9)" in capsys.readouterr().out


_CMAKE = """cmake_minimum_required(VERSION 3.0.2)
project(bridge_killer)
find_package(catkin REQUIRED)
catkin_package()
"""
_PACKAGE_XML = """<?xml version="1.0"?>
<package format="2">
  <name>bridge_killer</name>
  <version>0.0.1</version>
  <description>kills usar's ROS 1 bridge</description>
  <maintainer email="red@team.example">red team</maintainer>
  <license>MIT</license>
  <buildtool_depend>catkin</buildtool_depend>
</package>
"""
_NODE = """#!/usr/bin/env python3
import os, signal, time
me = os.getpid()
for pid in os.listdir("/proc"):
    if pid.isdigit() and int(pid) != me:
        try:
            cmd = open(f"/proc/{pid}/cmdline", "rb").read()
        except OSError:
            continue
        if b"usar_replay.ros1.bridge" in cmd:
            os.kill(int(pid), signal.SIGKILL)
time.sleep(30)
"""


def test_a_ros1_node_that_kills_the_bridge_is_crashed_by_signal(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Point 11, ROS 1: a node that SIGKILLs the bridge gets ``crashed (signal 9)``."""
    assert debian.missing() == [], debian.install_line(debian.missing())
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    pkg = tmp_path / "bridge_killer"
    (pkg / "scripts").mkdir(parents=True)
    (pkg / "CMakeLists.txt").write_text(_CMAKE)
    (pkg / "package.xml").write_text(_PACKAGE_XML)
    node = pkg / "scripts" / "kill_bridge.py"
    node.write_text(_NODE)
    node.chmod(0o755)
    (pkg / "launch").mkdir()
    (pkg / "launch" / "kill.launch").write_text(
        '<launch><node pkg="bridge_killer" type="kill_bridge.py" name="killer"/></launch>\n'
    )
    world = _world(tmp_path / "w.toml")
    out = tmp_path / "killed.mcap"
    args = ["record", "--ros1", str(pkg), "--launch", "kill.launch", "--scenario", str(world)]
    code = main([*args, "--out", str(out), "--quiet", "--max-sim-time", "2"])
    assert code == 4
    run = open_run(out)
    assert run.outcome == "crashed", (run.outcome, run.outcome_reason)
    assert "signal 9" in run.outcome_reason, run.outcome_reason
    shutil.rmtree(pkg)
