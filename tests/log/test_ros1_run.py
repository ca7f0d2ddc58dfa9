"""log/ros1_run: a ROS 1 run's facts (``ros1.toml``) and its nodes' outputs, attached to a real
log written by usar's writer and read back."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from usar_replay.core import contract, msgs
from usar_replay.core.errors import UsageError
from usar_replay.log import bag, ros1_run
from usar_replay.log.run import open_run

RUN = ros1_run.Ros1Run(
    package="usar_course",
    path="/home/t/usar_course",
    sha256="ab" * 32,
    launch="usar_course.launch",
    build_seconds=12.3456,
    nodes=(ros1_run.Ros1Node("/explorer", "usar_course", "explorer_node"),),
    replaced=(ros1_run.Ros1Node("/gazebo", "gazebo_ros", "gzserver"),),
    parameters=(ros1_run.ParameterRead("/mission/spin_speed", "0.1", ("/explorer",)),),
    applied_settings=("record", "mission.xy_tolerance"),
    holds=2,
    capped=7,
)


def _log(path: Path, attachments: dict[str, bytes]) -> Path:
    with bag.BagWriter(path) as w:
        w.add_metadata(bag.RUN_METADATA, {})
        for name, data in attachments.items():
            w.add_attachment(name, "text/plain", data, 1)
        w.write(contract.ROSOUT, msgs.Log(name="explorer", msg="hi"), 10**9)
    return path


def test_the_facts_round_trip_through_toml() -> None:
    back = ros1_run.Ros1Run.from_toml(RUN.to_toml())
    assert back == ros1_run.Ros1Run(**{**_fields(RUN), "build_seconds": 12.346})
    assert RUN.started_with == "roslaunch usar_course usar_course.launch"
    assert RUN.build == "12.3 s (catkin_make, wall time)"
    assert RUN.pacing == "2 shutdown holds, 7 capped ticks"
    assert ros1_run.Ros1Run.from_toml('package = "p"').pacing == "0 shutdown holds"
    # a newer run leaves its capped ticks (the machine's load) out of the log
    assert "capped" not in dataclasses.replace(RUN, capped=0).to_toml()
    rosrun = ros1_run.Ros1Run(package="p", node="n", build_cached=True)
    assert rosrun.started_with == "rosrun p n"
    assert rosrun.build.startswith("cached")


def _fields(run: ros1_run.Ros1Run) -> dict[str, object]:
    return {name: getattr(run, name) for name in run.__dataclass_fields__}


def test_which_settings_applied() -> None:
    assert RUN.applies("record.control_hz") and RUN.applies("record")
    assert RUN.applies("mission.xy_tolerance")
    assert not RUN.applies("mission.spin_speed") and not RUN.applies("recorder.x")


def test_a_log_gives_its_ros1_facts_or_none(tmp_path: Path) -> None:
    with_it = open_run(
        _log(tmp_path / "a.mcap", {contract.ROS1_ATTACHMENT: RUN.to_toml().encode()})
    )
    assert ros1_run.of(with_it) == ros1_run.Ros1Run.from_toml(RUN.to_toml())
    assert ros1_run.of(open_run(_log(tmp_path / "b.mcap", {}))) is None
    bad = open_run(_log(tmp_path / "c.mcap", {contract.ROS1_ATTACHMENT: b"package = [\n"}))
    assert ros1_run.of(bad) is None
    assert "the attached ros1.toml is invalid" in bad.problems


def test_node_outputs_are_shown_without_control_sequences(tmp_path: Path) -> None:
    prefix = contract.NODE_OUTPUT_ATTACHMENT_PREFIX
    run = open_run(
        _log(
            tmp_path / "a.mcap",
            {
                prefix + "explorer.txt": b"\x1b[32m[ INFO] ok\x1b[0m\n\tindented\x07\n",
                prefix + "ns+follower.txt": b"x" * 150 + b"\n",
            },
        )
    )
    assert set(ros1_run.node_outputs(run)) == {"/explorer", "/ns/follower"}
    assert list(ros1_run.node_output_lines(run, ("explorer",))) == [
        "--- /explorer: stdout and stderr ---",
        "[ INFO] ok",
        "    indented",
    ]
    follower = list(ros1_run.node_output_lines(run, ("/ns/follower",)))
    assert [len(line) for line in follower[1:]] == [100, 54]
    with pytest.raises(UsageError, match=r"no output of node /camera kept; the nodes': /explorer"):
        list(ros1_run.node_output_lines(run, ("camera",)))


NAV = ros1_run.Ros1Run(
    package="p",
    launch="go.launch",
    goal_tolerances=(
        ros1_run.GoalTolerance("explorer", 0.05, 0.17, "the course template's default"),
        ros1_run.GoalTolerance(
            "follower", 0.4, 0.17, "param/dwa_local_planner_params.yaml (launch/move_base.launch)"
        ),
    ),
    targets_replaced=(
        ros1_run.TargetReplaced(
            "/mission/aruco_lookup_locations/target_1", 1, "param/t.yaml (launch/go.launch)"
        ),
        ros1_run.TargetReplaced("/mission/copy", 2, "a <param> in launch/go.launch", "value"),
    ),
)


def test_goal_tolerances_and_replaced_targets_round_trip() -> None:
    back = ros1_run.Ros1Run.from_toml(NAV.to_toml())
    assert back == NAV
    assert back.xy_goal_tolerance("follower") == 0.4
    assert back.xy_goal_tolerance("explorer") == 0.05
    assert back.xy_goal_tolerance("robot1") is None
    old = ros1_run.Ros1Run.from_toml('package = "p"')  # a log from before issue 43
    assert old.goal_tolerances == () and old.targets_replaced == ()
    assert old.xy_goal_tolerance("follower") is None


def test_info_shows_the_tolerances_used_and_the_targets_replaced(tmp_path: Path) -> None:
    from usar_replay.log.info import describe

    run = open_run(_log(tmp_path / "a.mcap", {contract.ROS1_ATTACHMENT: NAV.to_toml().encode()}))
    text = describe(run)
    flat = " ".join(text.split())
    assert (
        "move_base: follower: goal tolerances xy 0.4 m, yaw 0.17 rad, from "
        "param/dwa_local_planner_params.yaml (launch/move_base.launch)"
    ) in flat
    assert (
        "move_base: explorer: goal tolerances xy 0.05 m, yaw 0.17 rad, from the course "
        "template's default"
    ) in flat
    assert "Targets replaced by the world's (the launch file set the course's):" in text
    assert (
        "  /mission/aruco_lookup_locations/target_1 = target 1  (param/t.yaml (launch/go.launch))"
    ) in text
    assert "  /mission/copy = target 2, known by its value  (a <param> in launch/go.launch)" in text
    bad = open_run(
        _log(tmp_path / "b.mcap", {contract.ROS1_ATTACHMENT: b'goal_tolerances = [{xy = "a"}]'})
    )
    assert ros1_run.of(bad) is None and "the attached ros1.toml is invalid" in bad.problems
    assert ros1_run.of(bad) is None  # asked again (grading asks three times): said once
    assert bad.problems.count("the attached ros1.toml is invalid") == 1
