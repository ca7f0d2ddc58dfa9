"""log/run: a recording opened once, its attachments read as untrusted; real logs written by
usar's writer."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.core import contract, msgs
from usar_replay.core.errors import IncompleteLog, LogError, MissingTopic, NotAnMcapFile, UsageError
from usar_replay.core.settings import MissionSettings, RunSettings, to_toml
from usar_replay.log import bag
from usar_replay.log.run import MissionInfo, open_run
from usar_replay.world.scenario_toml import to_toml as scenario_toml

S = 1_000_000_000
ODOM = contract.odom("explorer")


def _log(path: Path, attachments: dict[str, bytes], *, n: int = 50) -> Path:
    with bag.BagWriter(path, chunk_size=512) as w:
        for name, data in attachments.items():
            w.add_attachment(name, "application/toml", data, S)
        for i in range(n):
            w.write(ODOM, msgs.Odometry(), S + i * S // 10)
    return path


def test_mission_info_round_trips_awkward_paths() -> None:
    info = MissionInfo(target='C:\\team "a"\\m.py:main', module="m", sha256="ab", usar_version="1")
    assert MissionInfo.from_toml(info.to_toml()) == info


def test_a_whole_log_with_its_attachments(tmp_path: Path) -> None:
    settings = RunSettings(mission=MissionSettings(settle_frames=3))
    mission = MissionInfo(target="m.py", module="m", sha256="cd")
    path = _log(
        tmp_path / "a.mcap",
        {
            contract.SCENARIO_ATTACHMENT: scenario_toml(one_room()).encode(),
            contract.SETTINGS_ATTACHMENT: to_toml(settings).encode(),
            contract.MISSION_ATTACHMENT: mission.to_toml().encode(),
        },
    )
    run = open_run(path)
    assert run.scenario == one_room() and run.require_scenario() == one_room()
    assert run.settings == settings and run.settings_recorded
    assert run.mission == mission and run.problems == []
    assert run.file_state == "complete" and run.outcome == "" and run.problem() == ""
    assert (run.start_ns, run.end_ns, run.duration_s) == (S, S + 49 * S // 10, 4.9)
    run.require_topics([ODOM])
    with pytest.raises(MissingTopic, match=r"topic /a is missing; .* \(also missing: /b\)"):
        run.require_topics(["/a", ODOM, "/b"])
    assert [m.log_time_ns for m in run.messages([ODOM], 2 * S, 2 * S + 1)] == [2 * S]


def test_bad_attachments_are_problems_not_crashes(tmp_path: Path) -> None:
    path = _log(
        tmp_path / "a.mcap",
        {
            contract.SCENARIO_ATTACHMENT: b"\xff\xfe",
            contract.SETTINGS_ATTACHMENT: b"[mission]\nsettle_frames = -1\n",
            contract.MISSION_ATTACHMENT: b"target = [\n",
        },
    )
    run = open_run(path)
    assert run.problems == [
        "the attached scenario.toml is not text",
        "the attached settings.toml is invalid: settings.toml: mission.settle_frames: -1 is out "
        "of range [1, 1000] frames",
        "the attached mission.toml is invalid",
    ]
    assert run.scenario is None and run.settings == RunSettings() and not run.settings_recorded
    with pytest.raises(LogError, match=r"the attached scenario\.toml is not text"):
        run.require_scenario()


def test_a_log_without_a_scenario_or_cut_before_it(tmp_path: Path) -> None:
    bare = open_run(_log(tmp_path / "bare.mcap", {}))
    with pytest.raises(MissingTopic, match=r"no scenario\.toml attached; record it with"):
        bare.require_scenario()
    data = (tmp_path / "bare.mcap").read_bytes()
    (tmp_path / "cut.mcap").write_bytes(data[: len(data) // 2])
    cut = open_run(tmp_path / "cut.mcap")
    assert cut.damage is not None and cut.problem() == cut.damage.describe()
    assert cut.outcome == "unknown"  # the status record is written at close
    cut.require_topics(["/anything"])  # may lie past the damage
    with pytest.raises(IncompleteLog, match="is not in the readable part"):
        cut.require_scenario()


def test_what_is_not_a_log(tmp_path: Path) -> None:
    (tmp_path / "notes.mcap").write_text("hello", encoding="utf-8")
    with pytest.raises(NotAnMcapFile):
        open_run(tmp_path / "notes.mcap")
    with pytest.raises(UsageError):
        open_run(tmp_path / "missing.mcap")
