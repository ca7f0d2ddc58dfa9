"""The node API itself: parameters, and how a mission that crashes, hangs or blows its memory
ends a run (the executor's callback order and what a mission may publish:
tests/node/test_executor.py).
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from conftest import one_room

from usar_replay.api import Node, ParameterNotDeclared
from usar_replay.cli.main import main
from usar_replay.log.run import open_run
from usar_replay.node.executor import Executor
from usar_replay.world.scenario_toml import save


def test_parameters_dotted_and_slashed_names() -> None:
    ex = Executor(
        {
            "aruco_lookup_locations.target_2": [3.0, 4.0],
            "aruco_lookup_locations.target_1": [1.0, 2.0],
            "explorer.home": [-4.0, 2.5, 0.0],
        }
    )
    with ex.activate():
        node = Node("n", parameter_overrides={"explorer.home": [0.0, 0.0, 0.0]})
    # ROS 1 names (the course's rosparam paths) read as ROS 2's dotted ones
    assert node.get_parameter("aruco_lookup_locations/target_1").value == [1.0, 2.0]
    assert node.get_parameter("/aruco_lookup_locations/target_2").value == [3.0, 4.0]
    by_prefix = node.get_parameters_by_prefix("aruco_lookup_locations")
    assert list(by_prefix) == ["target_1", "target_2"]  # sorted by name
    assert by_prefix["target_2"].double_array_value == [3.0, 4.0]
    assert node.get_parameter("explorer.home").value == [0.0, 0.0, 0.0]  # node override wins
    # a declared default gives way to the run's value; an unknown name is refused
    assert node.declare_parameter("aruco_lookup_locations.target_1", [9.0, 9.0]).value == [1, 2]
    assert node.declare_parameter("mission.spin_speed", 0.1).double_value == 0.1
    assert node.has_parameter("mission.spin_speed")
    with pytest.raises(ParameterNotDeclared, match="no_such"):
        node.get_parameter("no_such/parameter")


# --- a mission that fails, end to end (`usar record`) -------------------------------------------

CRASHING = """
from usar_replay.api import Node


class Broken(Node):
    def __init__(self):
        super().__init__("broken")
        self.create_timer(0.5, self.on_timer)

    def on_timer(self):
        targets = {}
        return targets["target_1"]  # the user's own bug


def main():
    Broken()
"""

SLEEPING = """
import time
from usar_replay.api import Node


def main():
    node = Node("sleeper")
    node.create_timer(0.2, lambda: time.sleep(5))
"""

GREEDY = """
from usar_replay.api import Node

hoard = []


def main():
    node = Node("greedy")
    node.create_timer(0.2, lambda: hoard.append(bytearray(1 << 30)))
"""


def _record(tmp_path: Path, source: str, *options: str) -> tuple[int, Path]:
    mission = tmp_path / "mission.py"
    mission.write_text(textwrap.dedent(source))
    world = tmp_path / "room.toml"
    save(one_room(), world)
    out = tmp_path / "run.mcap"
    code = main(
        [
            "record",
            "--scenario",
            str(world),
            "--mission",
            str(mission),
            "--max-sim-time",
            "5",
            "--out",
            str(out),
            "--quiet",
            *options,
        ]
    )
    return code, out


def test_a_crash_ends_the_run_with_the_users_traceback_and_exit_4(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out = _record(tmp_path, CRASHING)
    assert code == 4
    run = open_run(out)
    assert run.file_state == "complete" and run.outcome == "crashed"
    reason = run.outcome_reason
    assert str(tmp_path / "mission.py") in reason and "line 12, in on_timer" in reason
    assert 'return targets["target_1"]' in reason and reason.rstrip().endswith(
        "KeyError: 'target_1'"
    )
    assert "executor.py" not in reason  # usar's plumbing is left out: the traceback is theirs
    assert run.duration_s < 1.0  # the first timer, 0.5 s in
    shown = capsys.readouterr().out
    assert "The mission crashed:" in shown and "KeyError: 'target_1'" in shown


def test_a_callback_past_the_tick_timeout_is_hung(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out = _record(tmp_path, SLEEPING, "--tick-timeout", "1")
    assert code == 4
    run = open_run(out)
    assert run.file_state == "complete" and run.outcome == "hung"
    assert "--tick-timeout" in run.outcome_reason
    assert "The mission hung:" in capsys.readouterr().out


def test_a_memory_blow_up_is_out_of_memory(tmp_path: Path) -> None:
    code, out = _record(tmp_path, GREEDY, "--mission-memory", "300")
    assert code == 4
    run = open_run(out)
    assert run.file_state == "complete"
    assert run.outcome == "out_of_memory" or (
        run.outcome == "crashed" and "MemoryError" in run.outcome_reason
    )
    if run.outcome == "out_of_memory" and "Traceback" in run.outcome_reason:
        assert "MemoryError" in run.outcome_reason
