"""core/team_parse: every parser of a team's file (TOML, package.xml and launch XML, YAML) meets
a nesting bomb, a 100 MB file and bad bytes as one line of refusal, in bounded time and memory;
the course's own shapes pass.

The 100 MB files are sparse (``truncate``): their size is what the caps read, and a test that
wrote 100 MB per case would cost the suite more than the attack costs usar. Memory is measured
with ``tracemalloc``: a parser that read such a file would hold 100 MB."""

from __future__ import annotations

import os
import tracemalloc
from collections.abc import Callable
from pathlib import Path

import pytest

from usar_replay.core import team_parse as tp
from usar_replay.core.errors import TeamFileRefused, UnusableSubmission, UsarError

BOMB_DEPTH = 5000

BOMBS: dict[str, bytes] = {
    "usar.toml": b"a = " + b"[" * BOMB_DEPTH + b"]" * BOMB_DEPTH + b"\n",  # tomllib recurses
    "inline.toml": b"a = " + b"{b = " * 3000 + b"1" + b"}" * 3000 + b"\n",
    "dotted.toml": b"[" + b".".join([b"a"] * BOMB_DEPTH) + b"]\nb = 1\n",  # no recursion, deep
    "package.xml": b"<package>" + b"<a>" * BOMB_DEPTH + b"</a>" * BOMB_DEPTH + b"</package>",
    "go.launch": b"<launch>" + b"<group>" * BOMB_DEPTH + b"</group>" * BOMB_DEPTH + b"</launch>",
    "laughs.launch": (
        b'<?xml version="1.0"?><!DOCTYPE l [<!ENTITY a "aaaaaaaaaa">'
        + b"".join(f'<!ENTITY a{k} "{"&a;" * 10}">'.encode() for k in range(9))
        + b"]><launch>&a8;</launch>"
    ),
    "flow.yaml": b"a: " + b"[" * BOMB_DEPTH + b"]" * BOMB_DEPTH + b"\n",
    "block.yaml": b"".join(b" " * k + b"k:\n" for k in range(1000)),  # 500 KB
    "dashes.yml": b"- " * BOMB_DEPTH + b"x\n",
}

HONEST: dict[str, bytes] = {
    "usar.toml": b'[ros1]\nlaunch = "go.launch"\nafter_launch = ["rosservice call /go \'{}\'"]\n',
    "package.xml": (
        b'<?xml version="1.0"?>\n<package format="2">\n  <name>final_project</name>\n'
        b"  <version>0.0.1</version>\n  <depend>rospy</depend>\n</package>\n"
    ),
    "go.launch": (
        b'<?xml version="1.0" encoding="ISO-8859-1"?>\n<launch>\n  <!-- caf\xe9 -->\n'
        b'  <arg name="x" default="0"/>\n  <group ns="tb3_0">\n'
        b'    <node pkg="final_project" type="explorer.py" name="explorer" output="screen">\n'
        b'      <rosparam command="load" file="$(find final_project)/param/p.yaml"/>\n'
        b"    </node>\n  </group>\n</launch>\n"
    ),
    "broken.launch": b"<launch><node></launch>\n",  # syntax: roslaunch's to say
    "dwa.yaml": (
        b"DWAPlannerROS:\n  xy_goal_tolerance: 0.05  # [m] [[[\n  yaw_goal_tolerance: 0.17\n"
        b"  footprint: [[-0.1, -0.1], [0.1, 0.1]]\n  note: '[[[[[[[[[[' \n"
        b"aruco_lookup_locations:\n  target_1: [1.0, 2.0]\n  list:\n    - - a\n      - b\n"
        b"literal: |\n  [[[[\n  text\n"
    ),
}


def _write(folder: Path, name: str, data: bytes) -> Path:
    path = folder / name
    path.write_bytes(data)
    return path


def _bounded(call: Callable[[], object]) -> tuple[object, int]:
    """``call()`` (its result or the refusal it raised) and the peak bytes it allocated."""
    tracemalloc.start()
    try:
        try:
            got: object = call()
        except TeamFileRefused as err:
            got = err
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return got, peak


@pytest.mark.parametrize("name", sorted(BOMBS))
def test_a_nesting_bomb_is_one_line_of_refusal(tmp_path: Path, name: str) -> None:
    path = _write(tmp_path, name, BOMBS[name])
    got, peak = _bounded(lambda: tp.check_file(path))
    assert isinstance(got, TeamFileRefused), f"{name} was parsed: {got!r}"
    said = str(got)
    assert said.startswith(f"{name}: ") and "\n" not in said, said
    assert "nested deeper than 64" in said or "<!ENTITY>" in said, said
    assert peak < 8 * 1024 * 1024, f"{name}: {peak} bytes to refuse it"


@pytest.mark.parametrize("name", ["usar.toml", "package.xml", "go.launch", "p.yaml"])
def test_a_100_mb_file_is_refused_before_it_is_read(tmp_path: Path, name: str) -> None:
    path = tmp_path / name
    with path.open("wb") as f:
        f.truncate(100 * 1024 * 1024)
    got, peak = _bounded(lambda: tp.check_file(path))
    assert isinstance(got, TeamFileRefused)
    assert (
        str(got)
        == f"{name}: 104857600 bytes; usar reads at most "
        + (f"{tp.MAX_CONFIG_BYTES}" if name.endswith(".toml") else f"{tp.MAX_XML_BYTES}")
        + " of this file"
    )
    assert peak < 1024 * 1024  # not a byte of it read


@pytest.mark.parametrize("name", ["usar.toml", "package.xml", "go.launch", "p.yaml"])
def test_bytes_that_are_not_utf8_are_refused(tmp_path: Path, name: str) -> None:
    path = _write(tmp_path, name, b"<a>x = 1\xff\xfe</a>\n")
    with pytest.raises(TeamFileRefused, match=r"not UTF-8 text \(byte 0xff at offset 8\)"):
        tp.check_file(path)


def test_xml_in_a_declared_encoding_is_read_in_it(tmp_path: Path) -> None:
    ok = _write(tmp_path, "a.launch", '<?xml version="1.0" encoding="latin-1"?><l>\xe9</l>'.encode(
        "latin-1"))  # fmt: skip
    tp.check_file(ok)
    odd = _write(tmp_path, "b.launch", b'<?xml version="1.0" encoding="klingon"?><l/>')
    with pytest.raises(TeamFileRefused, match="unknown encoding 'klingon'"):
        tp.check_file(odd)


@pytest.mark.parametrize("name", sorted(HONEST))
def test_the_courses_shapes_pass(tmp_path: Path, name: str) -> None:
    tp.check_file(_write(tmp_path, name, HONEST[name]))


def test_toml_text_parses_as_tomllib_does() -> None:
    assert tp.toml('[ros1]\nnode = "a.py"\n', "usar.toml") == {"ros1": {"node": "a.py"}}
    with pytest.raises(TeamFileRefused, match=r"^usar.toml: not valid TOML: .*line 1"):
        tp.toml("[ros1\n", "usar.toml")


def test_a_link_or_a_fifo_is_refused_without_blocking(tmp_path: Path) -> None:
    real = _write(tmp_path, "real.toml", b"a = 1\n")
    (tmp_path / "usar.toml").symlink_to(real)
    with pytest.raises(TeamFileRefused, match="cannot be read"):
        tp.toml_file(tmp_path / "usar.toml")
    os.mkfifo(tmp_path / "p.yaml")
    with pytest.raises(TeamFileRefused, match="not a regular file"):
        tp.check_file(tmp_path / "p.yaml")


def test_a_package_is_checked_file_by_file_and_its_outputs_left_out(tmp_path: Path) -> None:
    pkg = tmp_path / "team"
    for name, data in HONEST.items():
        folder = pkg / ("launch" if name.endswith(".launch") else "")
        folder.mkdir(parents=True, exist_ok=True)
        _write(folder, name, data)
    _write(pkg, "cascade.xml", b"<a>" * 100 + b"</a>" * 100)  # not a parsed file: never read
    _write(pkg, "pyproject.toml", b"not = [toml")
    (pkg / "build").mkdir()
    _write(pkg / "build", "deep.yaml", BOMBS["flow.yaml"])  # catkin's output, not the team's
    tp.check_package(pkg)
    (pkg / "param").mkdir()
    _write(pkg / "param", "p.yaml", BOMBS["flow.yaml"])
    with pytest.raises(TeamFileRefused) as err:
        tp.check_package(pkg)
    assert str(err.value) == "param/p.yaml: nested deeper than 64 levels"
    assert isinstance(err.value, UnusableSubmission) and isinstance(err.value, UsarError)


def test_a_name_with_controls_is_shown_escaped(tmp_path: Path) -> None:
    path = _write(tmp_path, "x\x1b[2J.yaml", BOMBS["flow.yaml"])
    with pytest.raises(TeamFileRefused) as err:
        tp.check_file(path)
    assert "\x1b" not in str(err.value) and "x\\x1b[2J.yaml" in str(err.value)


def test_head_reads_the_start_of_any_file_and_never_refuses(tmp_path: Path) -> None:
    cmake = tmp_path / "CMakeLists.txt"
    cmake.write_bytes(b"project(x)\nadd_executable(a a.cpp)\n\xff" + b"#" * (3 << 20))
    text = tp.head(cmake)
    assert text.startswith("project(x)\nadd_executable(a a.cpp)\n\ufffd")
    assert len(text) == tp.MAX_HEAD_BYTES
    (tmp_path / "link.txt").symlink_to(cmake)
    os.mkfifo(tmp_path / "fifo")
    assert tp.head(tmp_path / "link.txt") == tp.head(tmp_path / "fifo") == ""
    assert tp.head(tmp_path / "missing") == ""
