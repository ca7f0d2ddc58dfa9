"""ros1/param_sources: each parameter's YAML file and launch file, as Debian's roslaunch
loaded them (a ``<rosparam>`` in a node, one with ``ns=``, a ``<param>``, an ``<include>``; the
last writer wins), and how ``usar info`` names a file."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from usar_replay.ros1 import param_sources
from usar_replay.ros1.building import debian

_LOAD = """
import json, sys
sys.path.insert(0, sys.argv[1])
import param_sources, roslaunch.config
sources = param_sources.install()
roslaunch.config.load_config_default([sys.argv[2]], None, verbose=False)
print(json.dumps(sources))
"""


@pytest.mark.skipif(
    not (debian.DIST_PACKAGES / "roslaunch" / "__init__.py").exists(),
    reason="Debian's roslaunch is not installed",
)
def test_each_parameter_names_its_yaml_and_its_launch_file(tmp_path: Path) -> None:
    (tmp_path / "a.yaml").write_text("P:\n  tol: 0.4\n  other: 1\n", encoding="utf-8")
    (tmp_path / "b.yaml").write_text("P:\n  tol: 0.3\n", encoding="utf-8")
    inner = tmp_path / "inner.launch"
    inner.write_text(
        "<launch>\n"
        '  <node pkg="p" type="t" name="mb">\n'
        f'    <rosparam file="{tmp_path / "a.yaml"}" command="load"/>\n'
        f'    <rosparam file="{tmp_path / "b.yaml"}" command="load"/>\n'
        '    <param name="P/rate" value="5"/>\n'
        "  </node>\n"
        "</launch>\n",
        encoding="utf-8",
    )
    outer = tmp_path / "outer.launch"
    outer.write_text(
        "<launch>\n"
        f'  <include file="{inner}"/>\n'
        f'  <rosparam file="{tmp_path / "a.yaml"}" command="load" ns="g"/>\n'
        '  <param name="/top" value="1"/>\n'
        "</launch>\n",
        encoding="utf-8",
    )
    here = str(Path(param_sources.__file__).parent)
    done = subprocess.run(
        ["/usr/bin/python3", "-P", "-c", _LOAD, here, str(outer)],
        capture_output=True,
        text=True,
        check=False,
        env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "ROS_HOME": str(tmp_path)},
    )
    assert done.returncode == 0, done.stderr
    got = {k: tuple(v) for k, v in json.loads(done.stdout.splitlines()[-1]).items()}
    a, b = str(tmp_path / "a.yaml"), str(tmp_path / "b.yaml")
    assert got["/mb/P/tol"] == (b, str(inner))  # the last file loaded wins, as in roslaunch
    assert got["/mb/P/other"] == (a, str(inner))
    assert got["/mb/P/rate"] == ("", str(inner))  # a node's private <param>
    assert got["/g/P/tol"] == (a, str(outer))
    assert got["/top"] == ("", str(outer))


def test_a_file_is_named_by_its_place_in_a_package(tmp_path: Path) -> None:
    team = tmp_path / "src" / "team"
    (team / "param").mkdir(parents=True)
    other = tmp_path / "src" / "turtlebot3_navigation"
    (other / "param").mkdir(parents=True)
    (other / "package.xml").write_text("<package/>", encoding="utf-8")
    label = param_sources.label
    assert label(str(team / "param" / "x.yaml"), str(team)) == "param/x.yaml"
    assert label(str(other / "param" / "y.yaml"), str(team)) == "turtlebot3_navigation/param/y.yaml"
    assert label("/nowhere/z.yaml", "") == "/nowhere/z.yaml"
    assert label("an inline <rosparam>", str(team)) == "an inline <rosparam>"
    assert label("", str(team)) == ""
