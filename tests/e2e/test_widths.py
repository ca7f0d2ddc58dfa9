"""Every line a person reads fits 100 columns: each command is run on a real log (the session's
one-room recording, a copy cut in half, a ``.part``) and every line of its stdout and stderr is
measured.

Why: the README promises 100 columns; lines that ran past it (replay's digest, 101; recover's
136 and 184; grade's warning about an incomplete log, 112-118) were found by a person reading
them, not by a test. A path longer than a line is wrapped where it must be; the commands here
run on the relative paths a student types.
"""

from __future__ import annotations

import io
import shutil
from pathlib import Path

import pytest
from clitools import usar
from conftest import one_room

from usar_replay.batch.classreport import collect, to_table
from usar_replay.batch.driver import BatchSummary
from usar_replay.batch.plan import Plan, RunResult, Submission, World
from usar_replay.pipeline.record import RecordResult, print_summary
from usar_replay.world.scenario_toml import to_toml

WIDTH = 100


@pytest.fixture(scope="module")
def logs(room_log: tuple[Path, RecordResult], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A student's project folder: ``runs/`` with the one-room log, a copy cut in half
    (incomplete) and the same as a killed ``.part``, and the world as TOML. Commands run in
    the folder on relative paths, as a student types them."""
    d = tmp_path_factory.mktemp("project")
    (d / "runs").mkdir()
    shutil.copy(room_log[0], d / "runs" / "room.mcap")
    data = room_log[0].read_bytes()
    (d / "runs" / "half.mcap").write_bytes(data[: len(data) // 2])
    (d / "runs" / "killed.mcap.part").write_bytes(data[: len(data) // 2])
    (d / "room.toml").write_text(to_toml(one_room()), encoding="utf-8")
    return d


def _too_wide(text: str) -> list[str]:
    return [f"{len(line)}: {line}" for line in text.splitlines() if len(line) > WIDTH]


COMMANDS = [
    (["info", "runs/room.mcap"], 0),
    (["info", "runs/half.mcap"], 3),
    (["recover", "runs/killed.mcap.part"], 0),
    (["replay", "runs/room.mcap"], 0),
    (["replay", "--set", "detector.dictionary=DICT_5X5_50", "runs/room.mcap"], 1),
    (["replay", "runs/half.mcap"], 3),
    (["grade", "runs/room.mcap"], 0),
    (["grade", "runs/half.mcap"], 3),
    (["grade", "runs/room.mcap", "runs/half.mcap"], 3),
    (["report", "runs/room.mcap", "-o", "pages"], 0),
    (["scenario", "--check"], 0),
    (["scenario", "--scenario", "room.toml", "--check"], 0),
]


@pytest.mark.parametrize(("args", "code"), COMMANDS, ids=[" ".join(a) for a, _ in COMMANDS])
def test_every_line_fits(logs: Path, args: list[str], code: int) -> None:
    out = usar(*args, cwd=logs)
    assert out.returncode == code, out.stderr[-2000:]
    assert "Traceback" not in out.stderr
    assert out.stdout.strip() or out.stderr.strip()
    assert not _too_wide(out.stdout), _too_wide(out.stdout)
    assert not _too_wide(out.stderr), _too_wide(out.stderr)


def test_the_record_summary_fits(room_log: tuple[Path, RecordResult], logs: Path) -> None:
    """The summary of the session's recording, as if written under a long name."""
    import dataclasses

    result = dataclasses.replace(room_log[1], path=logs / ("a-rather-long-run-name-" * 4 + ".mcap"))
    buf = io.StringIO()
    print_summary(result, buf)
    assert str(result.path)[:20] in buf.getvalue()
    assert not _too_wide(buf.getvalue()), _too_wide(buf.getvalue())


def test_the_batch_lines_fit(tmp_path: Path) -> None:
    teams = [f"team_with_a_rather_long_name_{i}" for i in range(3)]
    plan = Plan(
        tmp_path,
        [Submission(t, tmp_path, "", "", "") for t in teams],
        [World("course-variant-seed12", "", "course-variant-seed12")],
    )
    results = [
        RunResult(teams[0], "course-variant-seed12", "graded", "max_sim_time", 30.0, 60.0),
        RunResult(teams[1], "course-variant-seed12", "graded", "out_of_memory", 0.0, 60.0),
        RunResult(teams[2], "course-variant-seed12", "error", error="x" * 150),
    ]
    text = "\n".join(BatchSummary(plan, results).lines())
    assert "out of memory 1" in text
    assert not _too_wide(text), _too_wide(text)
    table = to_table(collect(plan, {"course-variant-seed12": 60.0}))
    assert table.splitlines()[0].startswith("team") and not _too_wide(table), _too_wide(table)
