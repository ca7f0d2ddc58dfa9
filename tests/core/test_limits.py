"""A run's limits as one value: one default, one range and one flag per field, and its
JSON/TOML form read back exactly; bad values are one line naming the flag or the key."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from usar_replay.core.errors import UsageError
from usar_replay.core.limits import (
    BATCH_LIMITS,
    FLAGS,
    GRADESCOPE_LIMITS,
    LIMITS_FORMAT,
    RunLimits,
    check_value,
    limits_from_json,
    limits_from_toml,
    load_limits,
)


def test_the_forms_read_back_what_was_written() -> None:
    lim = RunLimits(tick_timeout_s=2.5, run_memory_mb=700, cpus=3, build_folder_mb=0)
    assert lim.to_dict()["format"] == LIMITS_FORMAT
    assert limits_from_json(lim.to_json()) == lim
    assert limits_from_toml(lim.to_toml()) == lim
    # every field is in the form, none twice
    names = [f.name for f in dataclasses.fields(RunLimits)]
    assert list(lim.to_dict())[1:] == names


def test_a_hand_written_table_changes_only_what_it_names(tmp_path: Path) -> None:
    f = tmp_path / "limits.toml"
    f.write_text("[limits]\nrun_memory_mb = 512\nwall_s = 90\n", encoding="utf-8")
    got = load_limits(str(f), BATCH_LIMITS)
    assert (got.run_memory_mb, got.wall_s, got.cpu_s) == (512, 90.0, BATCH_LIMITS.cpu_s)
    assert isinstance(got.wall_s, int | float) and got.processes == RunLimits().processes


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("[limits]\nrun_memory = 5\n", "run_memory: not a limit"),
        ("[limits]\nprocesses = 0\n", "processes 0: expected 1 or more"),
        ('[limits]\nwall_s = "1h"\n', "wall_s '1h': expected seconds >= 0"),
        ("[limits]\nmax_holds = 2.5\n", "max_holds 2.5: expected a whole number"),
        ("[limits]\nprocesses = true\n", "processes True: expected a whole number"),
        ('[limits]\nformat = "usar-limits/9"\n', "format 'usar-limits/9' is not"),
        ("[limits\n", "invalid TOML"),
    ],
)
def test_a_bad_file_is_one_line_naming_the_key(tmp_path: Path, text: str, why: str) -> None:
    f = tmp_path / "limits.toml"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(UsageError, match=f"^--limits {f}: .*") as err:
        load_limits(str(f))
    assert why in str(err.value) and "\n" not in str(err.value)


def test_a_missing_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="no such file"):
        load_limits(str(tmp_path / "none.toml"))


def test_a_value_that_exists_is_valid() -> None:
    with pytest.raises(UsageError, match=r"--tick-timeout 0.0: expected a positive number"):
        RunLimits(tick_timeout_s=0.0)
    with pytest.raises(UsageError, match=r"--hold-wall nan"):
        RunLimits(hold_wall_s=float("nan"))
    with pytest.raises(UsageError, match=r"cpus -1: expected 0 \(two when free, else one\)"):
        dataclasses.replace(RunLimits(), cpus=-1)
    with pytest.raises(UsageError, match=r"limits of x: run_folder_mb -2"):
        RunLimits.from_mapping({"run_folder_mb": -2}, "limits of x")
    check_value("wall_s", 0)  # 0: none


def test_one_row_per_flag_and_the_commands_that_take_it() -> None:
    flags = {row.flag: row for row in FLAGS}
    assert len(flags) == len(FLAGS)
    for old in ("--tick-timeout", "--mission-memory", "--max-log-mib", "--wall-limit",
                "--run-memory", "--processes", "--run-folder", "--max-holds", "--hold-wall",
                "--max-capped", "--cpu-limit", "--build-folder", "--build-timeout",
                "--connect-timeout", "--rtf"):  # fmt: skip
        assert {"record", "replay", "batch", "gradescope"} <= set(flags[old].commands), old
    assert flags["--grade-limit"].commands == ("batch", "gradescope")
    assert {row.dest for row in FLAGS} >= {"tick_timeout", "run_memory", "build_folder"}
    assert all(row.help and row.kind in (int, float) for row in FLAGS)


def test_the_defaults_of_each_command() -> None:
    assert RunLimits().cpu_s == 0 and BATCH_LIMITS.cpu_s == 1800
    assert BATCH_LIMITS.values() == {**RunLimits().values(), "cpu_s": 1800}
    # Gradescope's default container has 768 MB: the run must fit inside it
    assert GRADESCOPE_LIMITS.run_memory_mb < 768 and GRADESCOPE_LIMITS.cpu_s == 1800


def test_the_json_form_is_plain_json() -> None:
    data = json.loads(BATCH_LIMITS.to_json())
    assert data["format"] == LIMITS_FORMAT and data["cpu_s"] == 1800
    with pytest.raises(UsageError, match="expected a JSON object"):
        limits_from_json("[1]")


def test_the_documented_table_is_the_batch_defaults() -> None:
    """docs/batch.md's ``[limits]`` example reads back as ``usar batch``'s defaults: the doc
    names every field, with its value."""
    import re

    doc = (Path(__file__).resolve().parents[2] / "docs" / "batch.md").read_text(encoding="utf-8")
    block = re.search(r"```toml\n(\[limits\]\n.*?)```", doc, re.S)
    assert block is not None
    assert limits_from_toml(block.group(1)) == BATCH_LIMITS
    assert set(re.findall(r"^(\w+) =", block.group(1), re.M)) == {"format", *RunLimits().values()}
