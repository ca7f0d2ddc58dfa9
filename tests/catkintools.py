"""A small catkin package written for a test: the red-team builds and hand-ins share it."""

from __future__ import annotations

import textwrap
from pathlib import Path

EXITS = "import sys\nsys.exit(0)\n"
"""A node script that exits at once (a package that only needs to build and start)."""


def package_xml(folder: Path, name: str) -> None:
    """``folder`` (made) with the ``package.xml`` of a catkin package ``name``."""
    folder.mkdir(parents=True)
    (folder / "package.xml").write_text(
        f'<?xml version="1.0"?>\n<package format="2"><name>{name}</name><version>0.0.1</version>'
        "<description>a test's</description><maintainer email='r@t.invalid'>r</maintainer>"
        "<license>MIT</license><buildtool_depend>catkin</buildtool_depend></package>\n",
        encoding="utf-8",
    )


def package(folder: Path, name: str, configure: str = "", script: str = "") -> Path:
    """A catkin package ``name`` in ``folder`` with no C++ (its build only configures), whose
    CMakeLists.txt runs ``configure`` (CMake code: the team's code) at configure time, with a
    launch file starting ``scripts/node.py``, which holds ``script`` when one is given."""
    package_xml(folder, name)
    (folder / "CMakeLists.txt").write_text(
        f"cmake_minimum_required(VERSION 3.0.2)\nproject({name})\nfind_package(catkin REQUIRED)\n"
        f"catkin_package()\n{textwrap.dedent(configure)}\n",
        encoding="utf-8",
    )
    (folder / "launch").mkdir()
    (folder / "launch" / f"{name}.launch").write_text(
        f'<launch><node pkg="{name}" type="node.py" name="n" output="screen"/></launch>\n',
        encoding="utf-8",
    )
    if script:
        (folder / "scripts").mkdir()
        node = folder / "scripts" / "node.py"
        node.write_text("#!/usr/bin/python3\n" + textwrap.dedent(script), encoding="utf-8")
        node.chmod(0o755)
    return folder


NODE_CPP = """#include <ros/ros.h>

int main(int argc, char** argv) {{
  ros::init(argc, argv, "{name}");
  ros::NodeHandle nh;{body}
  return 0;
}}
"""
"""A C++ node that starts and exits (``body``: lines of the team's, a warning or an error)."""


def cxx_package(folder: Path, name: str, body: str = "", cmake: str = "") -> Path:
    """A catkin package ``name`` in ``folder`` with one C++ node, ``src/main.cpp`` (the node
    of :data:`NODE_CPP` with ``body`` in it), its ``CMakeLists.txt`` with ``cmake`` (CMake
    code) before the node's target, and a launch file starting it."""
    package_xml(folder, name)
    xml = folder / "package.xml"
    xml.write_text(xml.read_text().replace("</package>", "<depend>roscpp</depend></package>"))
    (folder / "CMakeLists.txt").write_text(
        f"cmake_minimum_required(VERSION 3.0.2)\nproject({name})\n"
        "find_package(catkin REQUIRED COMPONENTS roscpp)\ncatkin_package()\n"
        f"{textwrap.dedent(cmake)}\ninclude_directories(${{catkin_INCLUDE_DIRS}})\n"
        f"add_executable({name}_node src/main.cpp)\n"
        f"target_link_libraries({name}_node ${{catkin_LIBRARIES}})\n",
        encoding="utf-8",
    )
    (folder / "src").mkdir()
    (folder / "src" / "main.cpp").write_text(NODE_CPP.format(name=name, body=body))
    (folder / "launch").mkdir()
    (folder / "launch" / f"{name}.launch").write_text(
        f'<launch><node pkg="{name}" type="{name}_node" name="n" output="screen"/></launch>\n',
        encoding="utf-8",
    )
    return folder
