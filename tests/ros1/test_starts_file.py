"""ros1.starts_file: the instructor's starts file (``usar batch --starts``, issue 50): a table
per team, its third commands only service calls and publishes, every mistake one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.core.errors import UsageError
from usar_replay.ros1.starts_file import InstructorStart, read_starts


def test_a_table_per_team(tmp_path: Path) -> None:
    file = tmp_path / "starts.toml"
    file.write_text(
        '[group7]\nnode = "final_project_node"\nlaunch = "launch/go.launch"\n'
        'after_launch = [\'rosservice call /start "data: true"\']\nnote = "office hours"\n'
        '[group9]\nafter_launch = "rostopic pub -1 /go std_msgs/Bool true"\n'
    )
    starts = read_starts(file)
    g7 = starts["group7"]
    assert (g7.launch, g7.node, g7.after_launch) == (
        "go.launch",
        "final_project_node",
        ("rosservice call /start 'data: true'",),
    )
    assert g7.source == "the instructor's starts.toml [group7]: office hours"
    assert starts["group9"].after_launch == ("rostopic pub -1 /go std_msgs/Bool true",)
    assert starts["group9"].launch == starts["group9"].node == ""
    assert InstructorStart.from_json(g7.to_json()) == g7


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("[g]\nafter_launch = ['echo $(id -u); sleep 1000']\n", "is not a rosservice call"),
        ('[g]\nexec = "x"\n', "unknown key 'exec'"),
        ('g = "x"\n', "expected a table per team"),
        ("[g]\nnode = 3\n", "are strings"),
        ("[g]\nafter_launch = 3\n", "a list of commands"),
        ("[g\n", "not valid TOML"),
        ("x = " + "[" * 5000 + "]" * 5000 + "\n", "not valid TOML"),
    ],
)
def test_a_mistake_is_one_line(tmp_path: Path, text: str, says: str) -> None:
    file = tmp_path / "starts.toml"
    file.write_text(text)
    with pytest.raises(UsageError) as err:
        read_starts(file)
    assert says in str(err.value) and "\n" not in str(err.value)
    assert str(err.value).startswith(f"--starts {file}")


def test_a_missing_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="No such file"):
        read_starts(tmp_path / "absent.toml")
