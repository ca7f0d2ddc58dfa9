"""ros1/ros_debian: the ROS name -> Debian 12 package table the build hint reads."""

from __future__ import annotations

import glob
import shutil
import subprocess

import pytest

from usar_replay.ros1.building import debian, ros_debian, standins


def _owners() -> dict[str, str]:
    """ROS name -> the installed Debian package that holds its ``<name>Config.cmake`` (one
    ``dpkg -S`` for all of them)."""
    files: dict[str, str] = {}
    for ros in ros_debian.DEBIAN:
        found = glob.glob(f"/usr/share/{ros}/cmake/{ros}Config.cmake") + glob.glob(
            f"/usr/lib/*/cmake/{ros}/{ros}Config.cmake"
        )
        if found:
            files[found[0]] = ros
    if not files or shutil.which("dpkg") is None:
        return {}
    done = subprocess.run(["dpkg", "-S", *files], capture_output=True, text=True, check=False)
    out: dict[str, str] = {}
    for line in done.stdout.splitlines():
        deb, _, path = line.partition(": ")
        if path in files:
            out[files[path]] = deb.split(":")[0]
    return out


def test_every_installed_row_is_the_package_that_holds_the_cmake_config() -> None:
    """The table is not a guess: where the package is installed (the README's line installs
    the course's), dpkg says who owns ``<name>Config.cmake``, and it is the row's package."""
    owners = _owners()
    if not owners:
        pytest.skip("no Debian ROS 1 installed here")
    for ros, owner in owners.items():
        assert owner == ros_debian.DEBIAN[ros], ros
    assert len(owners) >= 20


def test_the_apt_lines_packages_are_rows_of_the_table() -> None:
    rows = set(ros_debian.DEBIAN.values())
    for deb in (
        "libtf-dev",
        "libstd-srvs-dev",
        "libcv-bridge-dev",
        "libimage-transport-dev",
        "libtf2-geometry-msgs-dev",
        "libvisualization-msgs-dev",
        "libangles-dev",
    ):
        assert deb in rows and deb in debian.APT_PACKAGES


def test_lookup_and_what_debian_lacks() -> None:
    assert ros_debian.debian_package("tf") == "libtf-dev"
    assert ros_debian.debian_package("laser_geometry") == "liblaser-geometry-dev"
    assert ros_debian.debian_package("gazebo_ros") is None  # usar's stand-in, not Debian's
    assert ros_debian.debian_package("no_such_pkg") is None
    assert ros_debian.not_in_debian("gazebo") == ros_debian.GAZEBO
    assert "move_base" in ros_debian.not_in_debian("costmap_2d")
    assert ros_debian.not_in_debian("tf") == ""
    # a name is Debian's, usar's stand-in, or lacking: never two of them
    stand_ins = set(standins.PACKAGES) | {"fiducial_msgs"}
    assert not stand_ins & set(ros_debian.DEBIAN)
    assert not stand_ins & set(ros_debian.NOT_IN_DEBIAN)
    assert not set(ros_debian.DEBIAN) & set(ros_debian.NOT_IN_DEBIAN)
