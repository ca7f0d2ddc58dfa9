"""ros1/debian: the Debian 12 packages a ROS 1 run needs, and the one line that names them."""

from __future__ import annotations

import pytest

from usar_replay.ros1.building import debian


def test_missing_packages_are_named_in_one_apt_line() -> None:
    line = debian.install_line(["catkin", "python3-rospy"])
    assert line == "apt-get install -y --no-install-recommends catkin python3-rospy"
    assert set(debian.APT_PACKAGES) >= {"catkin", "python3-rosmaster", "libtf2-ros-dev"}


def test_every_package_has_a_reason_and_a_file_to_look_for() -> None:
    assert set(debian._PROBES) == set(debian.APT_PACKAGES)
    assert all(debian.APT_PACKAGES.values())
    assert all(probe.startswith("/usr/") for probe in debian._PROBES.values())
    assert debian.install_line([]) == "apt-get install -y --no-install-recommends "
    assert debian.install_line().split()[4:] == list(debian.APT_PACKAGES)


def test_check_names_exactly_what_is_missing() -> None:
    gone = debian.missing()
    assert set(gone) <= set(debian.APT_PACKAGES)
    if not gone:
        debian.check()  # all installed: no error
        return
    with pytest.raises(debian.MissingRos1) as caught:
        debian.check()
    assert str(caught.value).endswith(f"apt-get update && {debian.install_line(gone)}")


def test_the_documented_apt_lines_install_every_package() -> None:
    """README.md (twice), .ci/run and docs/ros1.md carry the apt-get line verbatim: each
    installs exactly :data:`debian.APT_PACKAGES` (python3-venv, bubblewrap, libseccomp2 and
    chromium besides, where the tests run: the venv, the sandbox, its filter, and the class page's
    screenshot)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[3]
    want = debian.install_line()
    found = 0
    for name in ("README.md", ".ci/run", "docs/ros1.md"):
        for line in (root / name).read_text(encoding="utf-8").splitlines():
            if "apt-get install" in line and "catkin" in line:
                found += 1
                words = line.split("&&")[1].split()
                extra = ("python3-venv", "bubblewrap", "libseccomp2", "chromium")
                kept = (w for w in words if w not in extra)
                assert " ".join(kept) == want, name
    assert found == 4


def test_the_course_templates_packages_are_in_the_line() -> None:
    """What the course template's find_package lists and teams add (issue 31)."""
    for name in ("libtf-dev", "libtf2-geometry-msgs-dev", "libstd-srvs-dev",
                 "libimage-transport-dev", "libcv-bridge-dev", "libvisualization-msgs-dev",
                 "libangles-dev"):
        assert name in debian.APT_PACKAGES


def test_the_code_grades_tools_are_in_the_line_but_never_stop_a_ros1_run() -> None:
    """``usar code`` needs doxygen, cppcheck, clang-format, poppler and hunspell: the one apt
    line brings them, and :func:`debian.check` (``--ros1``) never asks for them."""
    line = debian.install_line()
    for name in ("doxygen", "cppcheck", "clang-format", "poppler-utils", "hunspell",
                 "hunspell-en-us"):
        assert name in debian.CODE_TOOLS and f" {name}" in line
    assert not set(debian.missing()) & debian.CODE_TOOLS
    assert set(debian.missing(code=True)) <= debian.CODE_TOOLS
