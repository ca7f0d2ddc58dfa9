"""`usar batch`: a small class of example missions graded on the one-room world.

The class (recorded once per module, about 1.5 min of wall time on 2 busy cores with 2 jobs):
``full`` is examples/minimal_mission.py as is (full marks); ``crash`` is a copy with a ``raise``
in a callback; ``hang`` loops for ever in a callback; ``hog`` allocates without end; ``snoop``
tries to read another team's log; ``nomission`` is a folder without a mission. Then resume,
grading-only redo, Gradescope's JSON and the class summary are checked on that output. The Ray
test runs a smaller class on both engines and compares the logs' digests.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from clitools import default_signals, run_batch
from conftest import one_room
from logtools import digest

from usar_replay.batch.classreport import ClassGrades, collect, to_table
from usar_replay.batch.plan import (
    RunResult,
    discover,
    make_plan,
    make_worlds,
)
from usar_replay.core.errors import UsageError
from usar_replay.core.limits import BATCH_LIMITS
from usar_replay.world.scenario_toml import to_toml

ROOT = Path(__file__).resolve().parents[2]
MINIMAL = (ROOT / "examples" / "minimal_mission.py").read_text(encoding="utf-8")
ARRIVED = "    def arrived(self, _result: object) -> None:\n        self.spinning = True\n"
FIRST_TIMER = "    def on_timer(self) -> None:\n"


def faulty(find: str, replace: str) -> str:
    """A copy of the minimal mission with one deliberate bug."""
    assert find in MINIMAL, "the minimal mission changed: update this test's bug"
    return MINIMAL.replace(find, replace, 1)


CRASH = faulty(ARRIVED, ARRIVED + '        raise RuntimeError("deliberate bug at the target")\n')
HANG = faulty(FIRST_TIMER, FIRST_TIMER + "        while True:\n            pass\n")
HOG = faulty(
    FIRST_TIMER,
    FIRST_TIMER
    + "        hog = []\n        while True:\n            hog.append(bytearray(32 << 20))\n",
)
CRASH_AT_START = faulty(FIRST_TIMER, FIRST_TIMER + '        raise ValueError("at once")\n')
SLOW = faulty(FIRST_TIMER, FIRST_TIMER + "        import time\n        time.sleep(0.2)\n")


def snoop(out: Path) -> str:
    target = out / "full" / "room.mcap"
    return f"def main() -> None:\n    open({str(target)!r}, 'rb').read()\n"


def make_class(root: Path, out: Path) -> Path:
    subs = root / "subs"
    (subs / "full").mkdir(parents=True)
    (subs / "full" / "mission.py").write_text(MINIMAL, encoding="utf-8")
    (subs / "crash.py").write_text(CRASH, encoding="utf-8")
    (subs / "hang.py").write_text(HANG, encoding="utf-8")
    (subs / "hog.py").write_text(HOG, encoding="utf-8")
    (subs / "snoop.py").write_text(snoop(out), encoding="utf-8")
    (subs / "nomission").mkdir()
    (subs / "nomission" / "README.txt").write_text("forgot the code\n", encoding="utf-8")
    return subs


def room_file(root: Path) -> Path:
    path = root / "room.toml"
    path.write_text(to_toml(one_room()), encoding="utf-8")
    return path


CLASS_ARGS = ["--tick-timeout", "5", "--mission-memory", "1000", "--jobs", "2", "--quiet"]


@pytest.fixture(scope="module")
def graded_class(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path, str]:
    root = tmp_path_factory.mktemp("class")
    out = root / "out"
    subs = make_class(root, out)
    room = room_file(root)
    code, text = run_batch(subs, room, out, *CLASS_ARGS, "--gradescope")
    assert code == 0, text
    return subs, room, out, text


def grade_of(out: Path, team: str) -> dict[str, object]:
    data: dict[str, object] = json.loads((out / team / "room.grade.json").read_text())
    return data


# -- the class ---------------------------------------------------------------------------------


def test_reference_mission_gets_full_marks(graded_class: tuple[Path, Path, Path, str]) -> None:
    _, _, out, _ = graded_class
    g = grade_of(out, "full")
    assert g["outcome"] == "done"
    assert g["points"] == g["max_points"] == 60
    assert all(c["passed"] for c in g["checks"])  # type: ignore[attr-defined]


def test_faulty_missions_get_their_verdicts(graded_class: tuple[Path, Path, Path, str]) -> None:
    _, _, out, _ = graded_class
    crash = grade_of(out, "crash")
    assert crash["outcome"] == "crashed"
    assert "deliberate bug at the target" in str(crash["outcome_reason"])
    assert "crash.py" in str(crash["outcome_reason"])  # the user's own traceback
    assert float(crash["points"]) < 60  # type: ignore[arg-type]
    # it reached the target before the bug: that line is kept
    checks = {c["id"]: c for c in crash["checks"]}  # type: ignore[attr-defined]
    assert checks["explorer.target_1"]["passed"]
    assert not checks["follower.home"]["passed"]
    assert grade_of(out, "hang")["outcome"] == "hung"
    hog = grade_of(out, "hog")
    assert hog["outcome"] == "out_of_memory", hog["outcome_reason"]


def test_reading_another_teams_log_is_refused(graded_class: tuple[Path, Path, Path, str]) -> None:
    _, _, out, _ = graded_class
    g = grade_of(out, "snoop")
    assert g["outcome"] == "crashed"
    assert "usar sandbox: the mission may not read" in str(g["outcome_reason"])
    assert str(out / "full" / "room.mcap") in str(g["outcome_reason"])
    assert g["points"] == 0


def test_each_team_folder_holds_its_own_files(graded_class: tuple[Path, Path, Path, str]) -> None:
    _, _, out, _ = graded_class
    for team in ("full", "crash", "hang", "hog", "snoop"):
        names = sorted(p.name for p in (out / team).iterdir())
        assert names == [
            "results.json",
            "room.grade.json",
            "room.mcap",
            "room.output.txt",
            "room.run.json",
        ], team
    assert sorted(p.name for p in (out / "nomission").iterdir()) == ["results.json"]


def test_class_summary_csv_and_table(graded_class: tuple[Path, Path, Path, str]) -> None:
    _, _, out, text = graded_class
    rows = list(csv.DictReader(io.StringIO((out / "summary.csv").read_text())))
    assert [r["team"] for r in rows] == ["crash", "full", "hang", "hog", "nomission", "snoop"]
    by_team = {r["team"]: r for r in rows}
    assert by_team["full"]["room"] == by_team["full"]["total"] == "60"
    assert by_team["full"]["problems"] == ""
    assert by_team["hang"]["problems"] == "room: hung"
    assert by_team["nomission"]["total"] == "0"
    assert "no mission.py" in by_team["nomission"]["problems"]
    table = (out / "summary.txt").read_text()
    assert table.strip() in text
    assert all(len(line) <= 100 for line in text.splitlines())
    assert re.search(r"^hang +\d+H ", table, re.M) and re.search(r"^full +60 +60/60$", table, re.M)


def test_gradescope_results_shape(graded_class: tuple[Path, Path, Path, str]) -> None:
    _, _, out, _ = graded_class
    for team in ("full", "crash", "nomission"):
        r = json.loads((out / team / "results.json").read_text())
        assert set(r) >= {"score", "max_score", "tests", "execution_time", "output"}
        assert isinstance(r["execution_time"], int)
        assert r["visibility"] in ("visible", "hidden", "after_due_date", "after_published")
        assert len(r["tests"]) == 1
        for t in r["tests"]:
            assert set(t) >= {"name", "score", "max_score", "status", "output", "visibility"}
            assert t["status"] in ("passed", "failed")
        assert r["score"] == pytest.approx(sum(t["score"] for t in r["tests"]))
        assert r["max_score"] == 60
    full = json.loads((out / "full" / "results.json").read_text())
    assert full["score"] == 60 and full["tests"][0]["status"] == "passed"
    crash = json.loads((out / "crash" / "results.json").read_text())
    assert crash["tests"][0]["status"] == "failed"
    assert "deliberate bug at the target" in crash["tests"][0]["output"]


def test_resume_does_nothing_then_redoes_a_deleted_grade(
    graded_class: tuple[Path, Path, Path, str],
) -> None:
    subs, room, out, _ = graded_class
    logs = {t: (out / t / "room.mcap").stat().st_mtime_ns for t in ("full", "crash")}
    code, text = run_batch(subs, room, out, *CLASS_ARGS)
    assert code == 0
    assert "0 graded now, 5 finished before, 0 errors" in text
    # a deleted grade is graded again, from the same log (not recorded again)
    before = grade_of(out, "crash")
    (out / "crash" / "room.grade.json").unlink()
    code, text = run_batch(subs, room, out, *CLASS_ARGS)
    assert code == 0
    assert "1 graded now, 4 finished before" in text
    assert grade_of(out, "crash") == before
    assert {t: (out / t / "room.mcap").stat().st_mtime_ns for t in logs} == logs


def test_deleted_log_is_recorded_again_to_the_same_bytes(
    graded_class: tuple[Path, Path, Path, str],
) -> None:
    subs, room, out, _ = graded_class
    log = out / "snoop" / "room.mcap"
    old = digest(log)
    log.unlink()
    code, text = run_batch(subs, room, out, *CLASS_ARGS)
    assert code == 0
    assert "1 graded now" in text
    assert digest(log) == old


def test_changed_inputs_are_run_again(graded_class: tuple[Path, Path, Path, str]) -> None:
    subs, room, out, _ = graded_class
    from usar_replay.core.settings import RunSettings
    from usar_replay.core.settings import to_toml as settings_toml

    worlds = make_worlds((), [str(room)])
    toml = settings_toml(RunSettings())
    lim = dataclasses.replace(BATCH_LIMITS, tick_timeout_s=5.0, memory_mb=1000)  # CLASS_ARGS
    plan = make_plan(
        discover(subs), worlds, out, settings_toml=toml, limits=lim, submissions_root=subs
    )
    assert plan.jobs == [] and len(plan.finished) == 5
    # another limit is another input: every run again
    plan = make_plan(
        discover(subs),
        worlds,
        out,
        settings_toml=toml,
        limits=dataclasses.replace(lim, tick_timeout_s=6.0),
        submissions_root=subs,
    )
    assert len(plan.jobs) == 5
    # other thresholds: grading only
    plan = make_plan(
        discover(subs),
        worlds,
        out,
        settings_toml=toml,
        thresholds_toml="[thresholds]\nhome_m = 0.2\n",
        limits=lim,
        submissions_root=subs,
    )
    assert len(plan.jobs) == 5 and all(j.grade_only for j in plan.jobs)


# -- engines -----------------------------------------------------------------------------------


def test_local_and_ray_engines_write_the_same_logs(tmp_path: Path) -> None:
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'usar-replay[ray]')")
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "mini.py").write_text(MINIMAL, encoding="utf-8")
    (subs / "early.py").write_text(CRASH_AT_START, encoding="utf-8")
    room = room_file(tmp_path)
    args = ["--max-sim-time", "4", "--jobs", "2", "--quiet"]
    code, _ = run_batch(subs, room, tmp_path / "local", *args)
    assert code == 0
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        code, _ = run_batch(subs, room, tmp_path / "ray", *args, "--engine", "ray")
    finally:
        ray.shutdown()
    assert code == 0
    for team in ("mini", "early"):
        a, b = tmp_path / "local" / team / "room.mcap", tmp_path / "ray" / team / "room.mcap"
        assert digest(a) == digest(b), team
        ga, gb = (
            json.loads((d / team / "room.grade.json").read_text())
            for d in (a.parent.parent, b.parent.parent)
        )
        assert ga == gb
    assert (
        json.loads((tmp_path / "ray" / "early" / "room.grade.json").read_text())["outcome"]
        == "crashed"
    )


def test_wall_limit_is_a_verdict(tmp_path: Path) -> None:
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "slow.py").write_text(SLOW, encoding="utf-8")
    room = room_file(tmp_path)
    code, text = run_batch(subs, room, tmp_path / "out", "--wall-limit", "8", "--quiet")
    assert code == 0, text
    g = grade_of(tmp_path / "out", "slow")
    assert g["outcome"] == "wall_limit"
    assert "wall time" in str(g["outcome_reason"])
    assert float(g["points"]) < 60  # type: ignore[arg-type]
    assert g["log_complete"] is False  # the cut log is graded as far as it goes
    # whatever the limit cut short, nothing of the run stays mounted in the batch's folder
    with open("/proc/self/mountinfo", encoding="utf-8", errors="replace") as f:
        assert str(tmp_path) not in f.read()


@pytest.mark.slow
def test_ctrl_c_cuts_runs_that_are_redone(tmp_path: Path) -> None:
    """Slow (about 40 s): a run cut by Ctrl-C leaves no manifest entry and is redone."""
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "slow.py").write_text(SLOW, encoding="utf-8")
    room = room_file(tmp_path)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "usar_replay.cli", "batch", str(subs), "--scenario", str(room)]
    cmd += ["-o", str(out), "--max-sim-time", "3", "--quiet"]
    proc = subprocess.Popen(
        cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=default_signals
    )
    part = out / "slow" / "room.mcap.part"
    while not part.exists():
        assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert not (out / "slow" / "room.run.json").exists()
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "1 graded now, 0 finished before" in done.stdout
    assert grade_of(out, "slow")["outcome"] == "max_sim_time"


# -- the parts ---------------------------------------------------------------------------------


def test_table_fits_100_columns_with_many_worlds(tmp_path: Path) -> None:
    from usar_replay.batch.plan import Plan, Submission, World

    teams = [f"team_with_a_rather_long_name_{i}" for i in range(3)]
    worlds = [f"seed{i}" for i in range(20)]
    plan = Plan(
        tmp_path,
        [Submission(t, tmp_path, "", "", "") for t in teams],
        [World(w, "", w) for w in worlds],
    )
    grades: ClassGrades = collect(plan, dict.fromkeys(worlds, 60.0))
    table = to_table(grades)
    assert all(len(line) <= 100 for line in table.splitlines())
    assert "more worlds in summary.csv" in table
    assert RunResult("t", "w", "graded", "hung").failed
    assert not RunResult("t", "w", "finished", "done").failed


def test_sandbox_refuses_other_files_and_processes(tmp_path: Path) -> None:
    own, other, work = tmp_path / "own", tmp_path / "other", tmp_path / "work"
    for d in (own, other, work):
        d.mkdir()
    (own / "mine.txt").write_text("mine")
    (other / "theirs.txt").write_text("theirs")
    script = f"""
from usar_replay.sandbox.audit_guard import GuardPolicy
GuardPolicy(read_roots=({str(own)!r},), write_roots=({str(work)!r},),
              deny_roots=({str(tmp_path)!r},), own_roots=({str(own)!r},)).install()
import os, subprocess
print(open({str(own / "mine.txt")!r}).read())
open({str(work / "scratch.txt")!r}, "w").write("ok")
for attempt in (lambda: open({str(other / "theirs.txt")!r}).read(),
                lambda: open({str(own / "new.txt")!r}, "w"),
                lambda: os.listdir({str(other)!r}),
                lambda: subprocess.run(["cat", {str(other / "theirs.txt")!r}]),
                lambda: open("/etc/hostname").read()):
    try:
        attempt()
        print("ALLOWED")
    except PermissionError as err:
        print("refused:", err)
"""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True
    )
    lines = done.stdout.splitlines()
    assert lines[0] == "mine"
    assert (work / "scratch.txt").read_text() == "ok"
    assert len(lines) == 6 and all(line.startswith("refused: usar sandbox") for line in lines[1:])


def test_output_inside_the_submissions_is_refused(tmp_path: Path) -> None:
    from usar_replay.batch.driver import plan_class

    (tmp_path / "a.py").write_text("def main(): pass\n")
    with pytest.raises(UsageError, match="must not contain each other"):
        plan_class(tmp_path, tmp_path / "graded", settings_toml="")


def test_a_batch_runs_no_more_runs_at_once_than_free_cpus_and_shares_them_out() -> None:
    from usar_replay.batch.engines import share_cpus

    assert share_cpus(2, 2, 2) == (2, 1)  # one CPU per run
    assert share_cpus(1, 2, 2) == (1, 2)  # the one run gets both
    assert share_cpus(4, 2, 2) == (2, 1)  # fewer at once rather than sharing
    assert share_cpus(3, 8, 8) == (3, 2)
    assert share_cpus(2, 0, 2) == (1, 1)  # all held by other runs: one at a time, waiting
    assert share_cpus(2, 0, 0) == (2, 0)  # no CPU sets here: as asked, none claimed


def test_the_instructors_starts_file_mistakes_are_usage_errors(tmp_path: Path) -> None:
    """``usar batch --starts``: a third command that is shell text, or a table naming no team,
    is exit 2 with one line before anything runs (issue 50)."""
    from clitools import usar

    (tmp_path / "subs").mkdir()
    (tmp_path / "subs" / "a.py").write_text("def main(): pass\n")
    bad = tmp_path / "starts.toml"
    bad.write_text("[a]\nafter_launch = ['echo $(id -u); sleep 1000']\n")
    done = usar("batch", "subs", "-o", "out", "--starts", str(bad), "--no-sandbox", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"usar: error: --starts {bad} [a]: after_launch 'echo $(id")
    assert len(done.stderr.splitlines()) == 1
    bad.write_text('[b]\nnode = "x"\n')
    done = usar("batch", "subs", "-o", "out", "--starts", str(bad), "--no-sandbox", cwd=tmp_path)
    assert done.returncode == 2 and "--starts: [b] is no team of" in done.stderr
    assert not (tmp_path / "out").exists()
