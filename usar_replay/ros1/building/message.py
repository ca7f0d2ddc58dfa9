"""What a failed build says to the student: the compiler's lines, in their folder, and a hint.

Why: usar builds a private copy of the package, so the compiler's and CMake's paths point into
a workspace the student never made. Those paths are mapped back to the folder they gave
(``--ros1 DIR``), and the mistakes a course package commonly makes (a ``find_package``
component missing, a dependency that is not installed, a message header not generated yet) get
one line saying what to change. A ROS package that is not installed is named with the Debian
package that provides it and the ``apt-get install`` to run (:mod:`.ros_debian`); only a name
no Debian package provides gets "check its name". Gazebo's API (``#include <gazebo/...>``, a
Gazebo plugin) cannot build here at all: usar has no Gazebo, and the hint says so.
"""

from __future__ import annotations

import re
from pathlib import Path

import usar_replay.ros1.building.ros_debian as ros_debian
import usar_replay.ros1.building.standins as standins
from usar_replay.core.safe_text import team_lines

__all__ = ["errors", "hint", "student_paths"]

# the namespace of an undefined C++ symbol -> the catkin package that defines it
_NAMESPACES = {
    "ros": "roscpp",
    "tf2_ros": "tf2_ros",
    "tf2": "tf2",
    "actionlib": "actionlib",
    "tf": "tf",
    "image_transport": "image_transport",
    "cv_bridge": "cv_bridge",
}


def student_paths(output: str, src: Path, user: Path) -> str:
    """``output`` with the private copy's folder ``src`` written as the student's ``user``."""
    mine = str(user.resolve())
    out = output.replace(str(src) + "/", mine + "/").replace(str(src), mine)
    # CMake names a package's files relative to the workspace's src/: "CMake Error at PKG/..."
    return re.sub(
        rf"(CMake (?:Error|Warning)[^\n]*? at ){re.escape(src.name)}/", rf"\1{mine}/", out
    )


def errors(output: str, limit: int = 60) -> str:
    """The compiler's and CMake's errors from catkin_make's output (the lines that say what is
    wrong and the two after), or its last lines when none is marked."""
    lines = team_lines(output.rstrip("\n"))  # a team's CR or control character starts no line
    keep: list[str] = []
    for i, line in enumerate(lines):
        if re.search(r"error|Error|ERROR|undefined reference", line):
            keep += lines[i : i + 3]
    picked = list(dict.fromkeys(keep)) or lines[-limit:]
    return "\n".join(picked[:limit])


_MISSING = re.compile(
    r"Could not find the required component '([A-Za-z0-9_]+)'"
    r'|Could not find a package configuration file provided by\s+"([A-Za-z0-9_]+)"'
)
_GAZEBO_HEADER = re.compile(
    r"fatal error: ((?:gazebo|gazebo_ros|gazebo_plugins|gazebo_msgs|sdf|ignition)/[^:\s]+): "
    r"No such file"
)


def missing_package(name: str) -> str:
    """The hint for a ROS package ``find_package`` did not find: the Debian package and the
    ``apt-get install`` that provides it, why usar has none, or "check its name"."""
    deb = ros_debian.debian_package(name)
    if deb is not None:
        return f"hint: install {name}: apt-get install -y --no-install-recommends {deb}"
    why = ros_debian.not_in_debian(name)
    if why == ros_debian.GAZEBO:
        return f"hint: {name}: {gazebo()}"
    if why:
        return f"hint: {name}: {why}; remove it from find_package(...) and package.xml"
    return f"hint: no Debian 12 package provides {name!r}: check its name in find_package(...)"


def gazebo() -> str:
    """What a package that uses Gazebo's API is told (after ``hint: ``)."""
    return f"{ros_debian.GAZEBO}: use cmd_vel, /odom and /tf, not Gazebo's API"


def hint(output: str, package: str) -> str:
    """One line (within 100 columns for usual names) saying what to change, or ''."""
    m = _GAZEBO_HEADER.search(output)
    if m:
        return f"hint: {m.group(1)}: {gazebo()}"
    m = _MISSING.search(output)
    if m:
        return missing_package(m.group(1) or m.group(2))
    m = re.search(r"fatal error: ([A-Za-z0-9_]+)/[A-Za-z0-9_]+\.h: No such file", output)
    if m and m.group(1) in standins.PACKAGES:
        return f"hint: usar's {m.group(1)} is a name only, for {standins.PACKAGES[m.group(1)]}"
    if m and m.group(1) == package:
        return (
            "hint: generate the messages first: add_dependencies(TARGET "
            "${${PROJECT_NAME}_EXPORTED_TARGETS})"
        )
    if m:
        dep = m.group(1)
        return f"hint: add {dep} to find_package(catkin REQUIRED COMPONENTS ...) and package.xml"
    m = re.search(r"undefined reference to `(?:[a-z]+ )?([A-Za-z0-9_]+)::", output)
    if m:
        dep = _NAMESPACES.get(m.group(1), m.group(1))
        return f"hint: link {dep}: add it to find_package(catkin REQUIRED COMPONENTS ...)"
    return ""
