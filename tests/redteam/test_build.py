"""Red team: catkin packages that attack usar through their BUILD (issue 26, points 1-4).

A package's ``CMakeLists.txt`` runs code at configure time (``execute_process``), as the team's
own code, before any node runs. Each attack here is a tiny package whose CMakeLists.txt does the
attack while catkin configures it (no C++ to compile, so each build takes seconds), against the
sandboxed build of :mod:`usar_replay.ros1.building.workspace`: links planted for usar to write
through
(``build.log`` to a ``.pth``, to another team's grade), writes into another package's cached
build, a fork bomb, a 5 GiB allocation, a big file, a build that never ends. Every test asserts
the verdict, that the files targeted outside are untouched and, for a class, that the other
teams' grades are unchanged.

Needs bubblewrap and Debian's ROS 1 (CI installs both): not skipped.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import stat
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from catkintools import package
from conftest import one_room

from usar_replay.cli import main as cli
from usar_replay.core.settings import RunSettings
from usar_replay.log.run import open_run
from usar_replay.process.mission_process import MissionEnded, MissionLimits
from usar_replay.ros1.building import tree
from usar_replay.ros1.building.workspace import BuildLimits, cached_build, find_package
from usar_replay.ros1.process import Ros1Options
from usar_replay.ros1.record import record_ros1
from usar_replay.sandbox.kernel_sandbox import bwrap_available
from usar_replay.world.scenario_toml import to_toml

ROOT = Path(__file__).resolve().parents[2]
SHORT = RunSettings(record=dataclasses.replace(RunSettings().record, max_sim_time_s=0.5))
HONEST = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")


@pytest.fixture(autouse=True, scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """One private build cache for this module (usar's underlay is built once in it)."""
    assert bwrap_available()[0], "these tests need bubblewrap (apt-get install bubblewrap)"
    before = os.environ.get("XDG_CACHE_HOME")
    base = tmp_path_factory.mktemp("cache")
    os.environ["XDG_CACHE_HOME"] = str(base)
    yield base / "usar" / "ros1"
    if before is None:
        del os.environ["XDG_CACHE_HOME"]
    else:
        os.environ["XDG_CACHE_HOME"] = before


def record_verdict(tmp_path: Path, pkg: Path, **kwargs: Any) -> tuple[str, str]:
    """Record ``pkg`` on the one-room world (0.5 sim-s at most): the log's outcome and reason."""
    out = tmp_path / "run.mcap"
    record_ros1(one_room(), out, pkg, SHORT, None, **kwargs)
    run = open_run(out)
    return run.outcome, run.outcome_reason


def _entries(cache: Path, name: str) -> list[Path]:
    return sorted(p for p in cache.glob(f"{name}-*") if p.is_dir())


# -- 1. links planted by the build are never followed; the run mounts the build read-only --------


def test_links_planted_by_the_build_are_never_followed(tmp_path: Path, cache: Path) -> None:
    """The build replaces ``build.log`` (and usar's old marker) with links to a ``.pth`` and to
    a file of the machine, and tries to write outside: usar writes nothing through them, the
    build is refused (a link leaves the workspace), and nothing of it is kept."""
    outside = tmp_path / "site-packages"
    outside.mkdir()
    (outside / "kept.txt").write_text("original\n", encoding="utf-8")
    pkg = package(
        tmp_path / "linker",
        "linker",
        f"""
        set(WS "${{CMAKE_BINARY_DIR}}/..")
        execute_process(COMMAND ln -sf {outside}/x.pth ${{WS}}/build.log)
        execute_process(COMMAND ln -sf {outside}/kept.txt ${{WS}}/.usar-built)
        execute_process(COMMAND ln -sf {outside}/kept.txt ${{WS}}/../built.json)
        execute_process(COMMAND sh -c "echo pwned > {outside}/direct.pth")
        """,
    )
    outcome, reason = record_verdict(tmp_path, pkg)
    assert outcome == "build_failed", reason
    assert "link that leaves its workspace" in reason, reason
    assert sorted(p.name for p in outside.iterdir()) == ["kept.txt"]
    assert (outside / "kept.txt").read_text(encoding="utf-8") == "original\n"
    assert _entries(cache, "linker") == []  # a refused build is not kept


def test_the_run_mounts_the_built_workspace_read_only(tmp_path: Path, cache: Path) -> None:
    """A node that writes into its built workspace (its ``setup.bash``, a new file) and
    usar's underlay, seen at the sandbox's fixed paths: refused by the file system (mounted
    read-only: even the owner's chmod fails); the workspace is as its manifest says."""
    script = """
    import os, pathlib, sys
    ws = pathlib.Path(os.environ["ROS_PACKAGE_PATH"].split(":")[0]).parents[0]
    under = pathlib.Path(os.environ["ROS_PACKAGE_PATH"].split(":")[1]).parents[0]
    print("AT", ws, under)
    for name, do in [
        ("chmod", lambda: os.chmod(ws / "devel" / "setup.bash", 0o666)),
        ("new", lambda: open(ws / "devel" / "x", "w")),
        ("underlay", lambda: os.chmod(under / "devel" / "setup.bash", 0o666)),
    ]:
        try:
            do()
            print("WRITE", name, "ALLOWED")
        except OSError as err:
            print("WRITE", name, "failed", err.strerror)
    sys.exit(3)
    """
    pkg = package(tmp_path / "writer", "writer", script=script)
    outcome, reason = record_verdict(tmp_path, pkg)
    assert outcome == "crashed", reason
    assert "ALLOWED" not in reason
    assert reason.count("failed Read-only file system") == 3, reason
    assert "AT /ros1/ws /ros1/underlay" in reason, reason  # the sandbox's fixed paths
    [entry] = _entries(cache, "writer")
    record = json.loads((entry / "built.json").read_text(encoding="utf-8"))
    assert tree.verify(entry / "ws", record["files"]) == ""


# -- 2. a class: no build forges another team's grade or the class's summary ---------------------


def test_a_build_cannot_forge_the_class_grades(tmp_path: Path) -> None:
    """A team's build links its workspace's files to the next team's grade and to the class's
    summary, and writes at them directly: its own verdict is ``build_failed``, the two honest
    teams' grades are the same line for line, and a resumed batch keeps them."""
    subs, out = tmp_path / "subs", tmp_path / "out"
    subs.mkdir()
    room = tmp_path / "room.toml"
    room.write_text(to_toml(one_room()), encoding="utf-8")
    (subs / "honest_a.py").write_text(HONEST, encoding="utf-8")
    (subs / "honest_z.py").write_text(HONEST, encoding="utf-8")
    targets = [out / "honest_z" / "room.grade.json", out / "summary.csv",
               out / "honest_z" / "results.json"]  # fmt: skip
    attack = "\n".join(
        f'execute_process(COMMAND ln -sf {t} "${{CMAKE_BINARY_DIR}}/../link{i}")\n'
        f'execute_process(COMMAND sh -c "echo 60 > {t}")'
        for i, t in enumerate(targets)
    )
    attack += f'\nexecute_process(COMMAND ln -sf {targets[0]} "${{CMAKE_BINARY_DIR}}/../build.log")'
    package(subs / "forger", "forger", attack)

    def batch() -> tuple[int, str]:
        buf, old = io.StringIO(), sys.stdout
        sys.stdout = buf
        try:
            code = cli.main(
                ["batch", str(subs), "--scenario", str(room), "-o", str(out), "--max-sim-time",
                 "2", "--jobs", "1", "--quiet", "--gradescope"]
            )  # fmt: skip
        finally:
            sys.stdout = old
        return code, buf.getvalue()

    code, text = batch()
    assert code == 0, text
    grades = {t: json.loads((out / t / "room.grade.json").read_text()) for t in os.listdir(out)
              if (out / t / "room.grade.json").is_file()}  # fmt: skip
    assert grades["forger"]["outcome"] == "build_failed"
    assert grades["forger"]["points"] == 0
    mine = ("team", "log_sha256")
    a = {k: v for k, v in grades["honest_a"].items() if k not in mine}
    z = {k: v for k, v in grades["honest_z"].items() if k not in mine}
    assert a == z and a["outcome"] == "max_sim_time"
    for t in targets:
        assert not t.is_symlink() and t.read_text(encoding="utf-8") != "60\n"
    summary = (out / "summary.csv").read_text(encoding="utf-8")
    again, text = batch()  # a resume keeps every grade and the summary
    assert again == 0, text
    assert (out / "summary.csv").read_text(encoding="utf-8") == summary
    assert json.loads((out / "honest_z" / "room.grade.json").read_text())["points"] == a["points"]


# -- 3. no cache poisoning: builds are usar's, frozen, verified before reuse ---------------------


def test_a_build_cannot_poison_another_teams_cached_build(tmp_path: Path, cache: Path) -> None:
    """Team V's build is in the cache; team A's build (its key computed offline) writes at V's
    ``setup.bash`` and links to it: refused, V's build unchanged. A build changed behind usar's
    back is rebuilt, not reused; cache folders are usar's and read-only."""
    victim = find_package(package(tmp_path / "victim", "victim"))
    first = cached_build(victim)
    setup = first.workspace / "devel" / "setup.bash"
    clean = setup.read_bytes()
    attack = f"""
    execute_process(COMMAND sh -c "echo 'exit 1' >> {setup}")
    execute_process(COMMAND ln -sf {setup} "${{CMAKE_BINARY_DIR}}/../build.log")
    """
    attacker = find_package(package(tmp_path / "attacker", "attacker", attack))
    with pytest.raises(MissionEnded) as refused:
        cached_build(attacker)
    assert refused.value.verdict == "build_failed"
    assert "link that leaves its workspace" in refused.value.detail
    assert setup.read_bytes() == clean
    again = cached_build(victim)
    assert again.cached and again.workspace == first.workspace
    # frozen: no write bit anywhere in the built workspace, entry and cache private to usar
    for dirpath, dirnames, filenames in os.walk(first.workspace):
        for name in [*dirnames, *filenames]:
            st = os.lstat(os.path.join(dirpath, name))
            assert stat.S_ISLNK(st.st_mode) or not st.st_mode & 0o222, (dirpath, name)
    for folder in (cache, first.workspace.parent):
        st = os.lstat(folder)
        assert st.st_uid == os.geteuid() and stat.S_IMODE(st.st_mode) == 0o700
    # poisoned behind usar's back (as by an older usar's bug): verified, found out, rebuilt
    os.chmod(setup, 0o644)
    with open(setup, "ab") as f:
        f.write(b"exit 1\n")
    rebuilt = cached_build(victim)
    assert not rebuilt.cached and setup.read_bytes() == clean


def test_a_cache_others_may_write_is_refused(tmp_path: Path) -> None:
    shared = tmp_path / "shared"
    (shared / "usar" / "ros1").mkdir(parents=True)
    os.chmod(shared / "usar" / "ros1", 0o777)
    victim = find_package(package(tmp_path / "victim", "victim"))
    from usar_replay.core.errors import UsageError

    with pytest.raises(UsageError, match="no one else may write"):
        cached_build(victim, shared / "usar" / "ros1")


# -- 4. the build runs under the run's limits ----------------------------------------------------


def _fails(tmp_path: Path, name: str, cmake: str, limits: BuildLimits | None = None) -> str:
    pkg = find_package(package(tmp_path / name, name, cmake))
    with pytest.raises(MissionEnded) as ended:
        cached_build(pkg, limits=limits)
    assert ended.value.verdict == "build_failed"
    return ended.value.detail.strip().splitlines()[-1]


def test_a_fork_bomb_at_build_time_is_stopped(tmp_path: Path) -> None:
    """400 processes at configure time: the build's pids cgroup (or, where none can be made,
    RLIMIT_NPROC) refuses the 257th, and the build says which limit it hit."""
    cmake = """
    execute_process(COMMAND sh -c "for i in $(seq 400); do sleep 5 & done; wait"
                    ERROR_VARIABLE e)
    if(e)
      message(FATAL_ERROR "fork bomb: ${e}")
    endif()
    """
    said = _fails(tmp_path, "forker", cmake)
    assert said == "the build of forker exceeded its process limit (256 processes)", said


def test_a_big_allocation_at_build_time_is_refused(tmp_path: Path) -> None:
    cmake = """
    execute_process(COMMAND /usr/bin/python3 -c "bytearray(5 << 30)" RESULT_VARIABLE r
                    ERROR_VARIABLE e)
    if(r)
      message(FATAL_ERROR "allocation: ${e}")
    endif()
    """
    said = _fails(tmp_path, "hog", cmake)
    assert said == "the build of hog exceeded its memory limit (4096 MiB per process)", said


def test_the_build_runs_in_the_runs_memory_and_cpu_set(tmp_path: Path) -> None:
    """Three configure-time children of 200 MiB each under a 256 MiB run (issue 44: 3 x 900
    MiB under --run-memory 512 exited 0): the run's memory cgroup ends the build. And the build
    runs on the CPUs of a set of its own, not on every CPU of the machine."""
    if not os.path.isdir("/sys/fs/cgroup/memory") or os.geteuid() != 0:
        pytest.skip("needs root and a cgroup v1 memory hierarchy")
    cmake = """
    set(HOG "import time; b = bytearray(200 << 20); b[::4096] = bytes(51200); time.sleep(3)")
    execute_process(COMMAND sh -c "for i in 1 2 3; do /usr/bin/python3 -c '${HOG}' & done; wait"
                    RESULT_VARIABLE r)
    message(FATAL_ERROR "three children: ${r}")
    """
    said = _fails(tmp_path, "spread", cmake, BuildLimits(run_memory_mb=256))
    assert said == (
        "the build of spread exceeded its memory limit for all its processes "
        "(256 MiB: --run-memory)"
    ), said
    from usar_replay.sandbox import cpu_sets

    if len(cpu_sets.usable_cpus()) < 2:
        return
    cmake = """
    execute_process(COMMAND /usr/bin/python3 -c "import os; print(len(os.sched_getaffinity(0)))"
                    OUTPUT_VARIABLE n)
    message(FATAL_ERROR "cpus ${n}")
    """
    pkg = find_package(package(tmp_path / "affinity", "affinity", cmake))
    with pytest.raises(MissionEnded) as ended:
        cached_build(pkg, limits=BuildLimits(cpus=1))
    assert "cpus 1" in ended.value.detail, ended.value.detail


def test_a_big_file_at_build_time_is_cut(tmp_path: Path, cache: Path) -> None:
    cmake = """
    execute_process(COMMAND sh -c "head -c 67108864 /dev/zero > big" RESULT_VARIABLE r)
    if(r)
      message(FATAL_ERROR "big file: ${r}")
    endif()
    """
    said = _fails(tmp_path, "filler", cmake, BuildLimits(file_mb=8))
    assert said == "the build of filler exceeded its file size limit (8 MiB)", said
    assert _entries(cache, "filler") == []


def test_a_build_that_fills_its_folder_is_failed_and_not_kept(tmp_path: Path, cache: Path) -> None:
    """Issue 44: a build wrote 2 x 1000 MiB and 150,000 files into its workspace, was called a
    success and stayed in the cache. Within a 16 MiB, 100,000-file build folder: 3 x 8 MiB
    (each under the per-file limit) exits 0 and still fails, so does a flood of small files;
    neither is kept. A build within the caps is."""
    if os.geteuid() != 0:
        pytest.skip("a tmpfs build folder needs root")
    cmake = """
    execute_process(COMMAND sh -c "for i in 1 2 3; do head -c 8388608 /dev/zero > f$i; done")
    """
    said = _fails(tmp_path, "bigtotal", cmake, BuildLimits(folder_mb=16))
    assert said == (
        "the build of bigtotal exceeded its build folder (16 MiB and 100,000 files: "
        "--build-folder)"
    ), said
    assert _entries(cache, "bigtotal") == []
    cmake = """
    execute_process(COMMAND /usr/bin/python3 -c "
    import os
    os.makedirs('many', exist_ok=True)
    for i in range(120000):
        try:
            open(f'many/{i}', 'w').close()
        except OSError:
            break
    ")
    """
    said = _fails(tmp_path, "manyfiles", cmake, BuildLimits(folder_mb=64))
    assert said.startswith("the build of manyfiles exceeded its build folder"), said
    assert _entries(cache, "manyfiles") == []
    pkg = find_package(package(tmp_path / "small", "small", "# nothing to build"))
    built = cached_build(pkg, limits=BuildLimits(folder_mb=16))
    assert (built.workspace / "devel" / "setup.bash").is_file()  # copied out, on disk
    assert not os.path.ismount(built.workspace)


def test_a_spinning_build_process_is_stopped_by_its_cpu_limit(tmp_path: Path) -> None:
    cmake = """
    execute_process(COMMAND sh -c "while :; do :; done" RESULT_VARIABLE r)
    message(FATAL_ERROR "spin: ${r}")
    """
    said = _fails(tmp_path, "spinner", cmake, BuildLimits(cpu_s=1))
    assert said == "the build of spinner exceeded its CPU time limit (1 s per process)", said


def test_a_build_past_its_wall_limit_is_build_failed(tmp_path: Path) -> None:
    pkg = package(tmp_path / "sleeper", "sleeper", "execute_process(COMMAND sleep 600)")
    outcome, reason = record_verdict(
        tmp_path, pkg, options=Ros1Options(), limits=MissionLimits(build_wall_s=2.0)
    )
    assert outcome == "build_failed", reason
    assert reason.strip().splitlines()[-1] == "the build of sleeper exceeded its 2 s wall limit"


def test_batch_files_are_never_written_or_read_through_links(tmp_path: Path) -> None:
    """What a batch writes (grades, summaries) replaces a link at its final or temporary name
    instead of writing through it, and a grade that is a link is not read on resume."""
    from usar_replay.batch.plan import read_json
    from usar_replay.core.outfiles import write_text

    victim = tmp_path / "forged.json"  # a forged grade, or a .pth in site-packages
    victim.write_text('{"points": 60}\n', encoding="utf-8")
    grade = tmp_path / "room.grade.json"
    grade.symlink_to(victim)
    assert read_json(grade) is None
    (tmp_path / f".room.grade.json.{os.getpid()}.tmp").symlink_to(victim)
    write_text(grade, '{"points": 1}\n', overwrite=True)
    assert victim.read_text(encoding="utf-8") == '{"points": 60}\n'
    assert not grade.is_symlink() and read_json(grade) == {"points": 1}


PLANTED = """import os as _os, sys as _sys
if any("usar_replay" in str(a) for a in _sys.argv):  # in a process of usar's: say so, end it
    _os.write(2, b"PLANTED %s RAN IN USAR'S PROCESS\\n" % __name__.encode())
    _os._exit(66)
__path__ = ["/usr/lib/python3/dist-packages/" + __name__]  # else: Debian's, as the red team's
__file__ = __path__[0] + "/__init__.py"
exec(compile(open(__file__).read(), __file__, "exec"))
"""
BUSY_ON_CLOCK = """
import os
import time
import rospy
from rosgraph_msgs.msg import Clock

rospy.init_node("n")
null = os.open(os.devnull, os.O_WRONLY)


def busy(_msg):
    end = time.monotonic() + 0.5
    while time.monotonic() < end:
        os.write(null, b"x")  # it writes: a loop with no call at all would count as waiting


rospy.Subscriber("/clock", Clock, busy)
rospy.spin()
"""
PLANT = """
foreach(m rospy genpy roslib rosgraph std_msgs)
  file(WRITE "${CATKIN_DEVEL_PREFIX}/lib/python3/dist-packages/${m}/__init__.py" [=[%s]=])
endforeach()
"""


def test_a_teams_python_never_runs_in_usars_processes(tmp_path: Path) -> None:
    """The team's CMake plants rospy, genpy, roslib, rosgraph and std_msgs in its devel space
    (issue 44): a planted module that runs in a process of usar's (the bridge, usar's roslaunch
    wrapper) ends it with its mark. None runs there; the team's own graph never idles, and the
    capped-tick budget still ends the run."""
    pkg = package(
        tmp_path / "planter",
        "planter",
        configure=PLANT % PLANTED,
        # a node (through the planted rospy: the team's own process) busy half a second of
        # wall time on every /clock: every tick reaches its wall cap
        script=BUSY_ON_CLOCK,
    )
    out = tmp_path / "planted.mcap"
    limits = MissionLimits(kernel_sandbox="required", max_capped=3, tick_timeout_s=20.0)
    settings = RunSettings(record=dataclasses.replace(RunSettings().record, max_sim_time_s=3.0))
    result = record_ros1(one_room(), out, pkg, settings, options=Ros1Options(), limits=limits)
    assert "PLANTED" not in result.outcome_reason, result.outcome_reason
    assert result.outcome == "hung", result.outcome_reason
    assert "--max-capped" in result.outcome_reason
    # the summary says what a capped tick costs and what widens the cap
    assert "4 capped ticks (this machine's pace may show in the log: a lower --rtf than 0.5" in (
        result.pacing
    ), result.pacing
