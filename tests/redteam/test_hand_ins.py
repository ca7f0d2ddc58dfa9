"""Red team: hand-ins and logs that attack usar through names, hidden files, build leftovers
and replay (issue 33, points 2, 3, 8 and 10).

- 2: a file whose name is not UTF-8 (an old zip's ``caf\\xe9.txt``) must not end a class's
  batch: the name is hashed as bytes, the team graded; a FIFO of such a name is that team's
  ``bad_submission``, quoted escaped; the other teams are graded.
- 3: a hidden 2 GiB sparse file is never read, hashed or copied; a visible one is refused by
  the same caps for ``usar batch`` and ``usar record --ros1`` (a closed log, ``build_failed``).
- 8: a build that leaves links to folders (in and out of its workspace) or a FIFO with a
  non-UTF-8 name ends as ``build_failed`` in a closed log, its reason escaped, the cache clean,
  and the next run builds.
- 10: replay never builds a folder a log names unless its files hash to the recorded sha256,
  and an unreadable ``mission.toml`` is an error, not the built-in mission.

Bounded (0.5 sim-s runs; builds that only configure) and cleaned up (tmp folders, a private
build cache per test).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterator
from pathlib import Path

import catkintools
import pytest
from clitools import run_batch, usar
from conftest import one_room

from usar_replay.core import contract
from usar_replay.core.settings import RunSettings
from usar_replay.core.settings import to_toml as settings_toml
from usar_replay.grading.grade import grade_file
from usar_replay.log import bag
from usar_replay.log.run import MissionInfo, open_run
from usar_replay.pipeline.record import record
from usar_replay.ros1.building.workspace import find_package, package_sha256, remove_tree
from usar_replay.ros1.process import Ros1Options
from usar_replay.ros1.record import record_ros1
from usar_replay.world.scenario_toml import to_toml

ROOT = Path(__file__).resolve().parents[2]
SHORT = RunSettings(record=dataclasses.replace(RunSettings().record, max_sim_time_s=0.5))
HONEST = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")
ROS1 = Path("/usr/bin/roslaunch").exists()


@pytest.fixture(autouse=True)
def cache(tmp_path: Path) -> Iterator[Path]:
    """A private build cache per test."""
    before = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    yield tmp_path / "cache" / "usar" / "ros1"
    if before is None:
        del os.environ["XDG_CACHE_HOME"]
    else:
        os.environ["XDG_CACHE_HOME"] = before


def _touch(folder: Path, name: bytes) -> None:
    os.close(os.open(os.fsencode(folder) + b"/" + name, os.O_CREAT | os.O_WRONLY, 0o644))


def package(folder: Path, name: str, configure: str = "") -> Path:
    """A catkin package with no C++ (its build only configures), a Python node that exits,
    and ``configure`` (CMake code run at configure time: the team's code)."""
    return catkintools.package(folder, name, configure, script=catkintools.EXITS)


# -- 2 and 3: team folders ------------------------------------------------------------------


def test_a_name_that_is_not_utf8_does_not_stop_the_class(tmp_path: Path) -> None:
    """The digest hashes names as bytes: the team with ``caf\\xe9.txt`` is graded, the team
    with a FIFO of such a name is ``bad_submission`` (its name quoted escaped), the honest
    team graded; the batch exits 0 without a traceback."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    for team in ("honest", "cafe", "fifo"):
        (subs / team).mkdir(parents=True)
        (subs / team / "mission.py").write_text(HONEST, encoding="utf-8")
    _touch(subs / "cafe", b"caf\xe9.txt")
    os.mkfifo(os.fsencode(subs / "fifo") + b"/pipe\xe9")
    room = tmp_path / "room.toml"
    room.write_text(to_toml(one_room()), encoding="utf-8")
    code, text = run_batch(subs, room, out, "--max-sim-time", "0.5", "--jobs", "1", "--quiet")
    assert code == 0, text
    assert "Traceback" not in text
    summary = (out / "summary.csv").read_text(encoding="utf-8").splitlines()
    rows = {line.split(",", 1)[0]: line for line in summary[1:]}
    assert set(rows) == {"honest", "cafe", "fifo"}
    assert rows["cafe"] == rows["honest"].replace("honest", "cafe")  # graded as the honest
    assert "unusable submission: pipe\\xe9: not a regular file" in rows["fifo"]  # escaped


def test_a_package_name_that_is_not_utf8_is_hashed_as_bytes(tmp_path: Path) -> None:
    pkg = package(tmp_path / "cafe", "cafe")
    before = package_sha256(find_package(pkg))
    _touch(pkg, b"notes-caf\xe9.txt")
    assert package_sha256(find_package(pkg)) != before


@pytest.mark.skipif(not ROS1, reason="ROS 1 (Debian's ros-base) is not installed")
def test_a_big_file_in_a_package_is_a_closed_build_failed_log(tmp_path: Path) -> None:
    """The same caps for ``--ros1`` as for a batch: a 2 GiB sparse file (unread) ends the run
    as ``build_failed`` before any build, in a closed, gradable log; hidden, it is ignored."""
    pkg = package(tmp_path / "big", "big")
    (pkg / ".cache").mkdir()
    with open(pkg / ".cache" / "blob.bin", "wb") as f:
        f.truncate(2 * 1024**3)
    before = package_sha256(find_package(pkg))
    (pkg / ".cache" / "blob.bin").rename(pkg / "blob.bin")
    out = tmp_path / "big.mcap"
    result = record_ros1(one_room(), out, pkg, SHORT)
    assert result.outcome == "build_failed", result.outcome_reason
    assert "blob.bin: 2147483648 bytes; a file is at most" in result.outcome_reason
    run = open_run(out)
    assert run.file_state == "complete" and run.outcome == "build_failed"
    assert not any(c.passed for c in grade_file(out).checks)
    (pkg / "blob.bin").unlink()
    assert package_sha256(find_package(pkg)) == before


# -- 8: what a build leaves -----------------------------------------------------------------


def test_remove_tree_never_follows_or_chmods_a_link(tmp_path: Path) -> None:
    outside = tmp_path / "outside"
    (outside / "keep").mkdir(parents=True)
    (outside / "keep" / "file").write_text("x", encoding="utf-8")
    (outside / "keep").chmod(0o555)
    tree = tmp_path / "entry"
    (tree / "ws" / "devel").mkdir(parents=True)
    (tree / "ws" / "devel" / "f").write_text("y", encoding="utf-8")
    (tree / "ws" / "in_link").symlink_to("devel")
    (tree / "ws" / "out_link").symlink_to(outside / "keep")
    for folder in (tree / "ws" / "devel", tree / "ws", tree):
        folder.chmod(0o555)  # frozen, as a built workspace is
    remove_tree(tree)
    assert not os.path.lexists(tree)
    assert (outside / "keep" / "file").read_text(encoding="utf-8") == "x"
    assert (outside / "keep").stat().st_mode & 0o777 == 0o555
    (outside / "keep").chmod(0o755)


@pytest.mark.skipif(not ROS1, reason="ROS 1 (Debian's ros-base) is not installed")
@pytest.mark.parametrize("cached", [True, False])
def test_a_build_leaving_links_to_folders_is_a_closed_log_and_the_cache_stays_usable(
    tmp_path: Path, cache: Path, cached: bool
) -> None:
    outside = tmp_path / "outside"
    outside.mkdir()
    pkg = package(
        tmp_path / "linker",
        "linker",
        f"""
        set(WS "${{CMAKE_BINARY_DIR}}/..")
        execute_process(COMMAND ln -s src "${{WS}}/src_again")
        execute_process(COMMAND ln -s {outside} "${{WS}}/out_dir")
        """,
    )
    opts = Ros1Options(cache=cached)
    out = tmp_path / "run.mcap"
    result = record_ros1(one_room(), out, pkg, SHORT, options=opts)
    assert result.outcome == "build_failed", result.outcome_reason
    assert "link that leaves its workspace: out_dir" in result.outcome_reason
    assert open_run(out).file_state == "complete"
    assert outside.is_dir() and list(outside.iterdir()) == []
    assert [p for p in cache.glob("linker-*") if p.is_dir()] == []
    # the same package without the link out builds and runs (nothing half-removed is left)
    text = (pkg / "CMakeLists.txt").read_text(encoding="utf-8")
    (pkg / "CMakeLists.txt").write_text(
        "\n".join(line for line in text.splitlines() if "out_dir" not in line) + "\n",
        encoding="utf-8",
    )
    again = record_ros1(one_room(), tmp_path / "again.mcap", pkg, SHORT, options=opts)
    assert again.outcome != "build_failed", again.outcome_reason


@pytest.mark.skipif(not ROS1, reason="ROS 1 (Debian's ros-base) is not installed")
def test_a_fifo_with_a_name_that_is_not_utf8_is_an_escaped_reason(tmp_path: Path) -> None:
    pkg = package(
        tmp_path / "piper",
        "piper",
        """
        execute_process(COMMAND sh -c "mkfifo \\"${CMAKE_BINARY_DIR}/../$(printf 'p\\\\351')\\"")
        """,
    )
    out = tmp_path / "run.mcap"
    result = record_ros1(one_room(), out, pkg, SHORT)
    assert result.outcome == "build_failed", result.outcome_reason
    assert "the build left a FIFO in its workspace: p\\xe9" in result.outcome_reason
    run = open_run(out)
    assert run.file_state == "complete" and run.outcome == "build_failed"


# -- 10: replay runs only what was recorded -------------------------------------------------


def _rewritten(log: Path, out: Path, mission_toml: bytes) -> Path:
    """``log`` written again with ``mission_toml`` as its mission.toml (what a forger does)."""
    run = open_run(log)
    assert run.scenario is not None
    with bag.BagWriter(out) as w:
        t0 = run.start_ns
        toml = "application/toml"
        w.add_attachment(contract.SCENARIO_ATTACHMENT, toml, to_toml(run.scenario).encode(), t0)
        w.add_attachment(
            contract.SETTINGS_ATTACHMENT, toml, settings_toml(run.settings).encode(), t0
        )
        w.add_attachment(contract.MISSION_ATTACHMENT, toml, mission_toml, t0)
        for m in run.messages(decode=False):
            w.write_raw(m.topic, m.msgtype, m.data, m.log_time_ns, publisher=m.publisher)
        w.outcome, w.outcome_reason = run.outcome, run.outcome_reason
    return out


@pytest.fixture
def short_log(tmp_path: Path) -> Path:
    out = tmp_path / "short.mcap"
    record(one_room(), out, SHORT)
    return out


def test_an_unreadable_mission_toml_is_an_error_not_the_builtin_mission(
    tmp_path: Path, short_log: Path
) -> None:
    for text in (b"target = [\n", b"\xff\xfe", b""):
        forged = _rewritten(short_log, tmp_path / "forged.mcap", text)
        done = usar("replay", str(forged))
        assert done.returncode == 3, done.stdout + done.stderr
        assert "Traceback" not in done.stderr and done.stdout == ""
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("usar: error:"), lines
        assert "--mission" in lines[0]
        forged.unlink()
    # the user may still name the code to run
    forged = _rewritten(short_log, tmp_path / "forged.mcap", b"target = [\n")
    assert usar("replay", str(forged), "--mission", "builtin").returncode in (0, 1)


@pytest.mark.skipif(not ROS1, reason="ROS 1 (Debian's ros-base) is not installed")
def test_a_log_naming_another_folder_never_builds_it(tmp_path: Path, short_log: Path) -> None:
    """The log says ``ros1:OTHER`` with a sha256 that is not OTHER's: replay refuses in one
    line that asks for ``--ros1``; OTHER's configure-time code never runs."""
    planted = tmp_path / "planted"
    other = package(tmp_path / "other", "other", f'execute_process(COMMAND touch "{planted}")\n')
    forged_info = MissionInfo(
        target=f"ros1:{other} --launch other.launch",
        module="ros1:other",
        sha256="0" * 64,
        usar_version="x",
    )
    forged = _rewritten(short_log, tmp_path / "forged.mcap", forged_info.to_toml().encode())
    done = usar("replay", str(forged))
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "whose files are not the recorded ones" in lines[0], lines
    assert "--ros1 PKG" in lines[0]
    assert not planted.exists()
    gone = MissionInfo(target=f"ros1:{tmp_path / 'nowhere'} --launch x.launch", module="m")
    forged = _rewritten(short_log, tmp_path / "gone.mcap", gone.to_toml().encode())
    done = usar("replay", str(forged))
    assert done.returncode == 2 and "which is not here" in done.stderr, done.stderr
