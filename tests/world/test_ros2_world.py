"""world/ros2_world: the ROS 2 final project's world, its task, its variants and its check
(no simulation)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from usar_replay.core import contract
from usar_replay.core.errors import InvalidScenario
from usar_replay.world import scenario_toml
from usar_replay.world.ros2_world import check_ros2, make_ros2_variant, ros2_final_world, task_of
from usar_replay.world.scenario import Scenario
from usar_replay.world.world_key import WorldKey


def test_world_round_trips_through_toml_and_is_playable() -> None:
    world = ros2_final_world()
    assert world.assignment == "ros2-final"
    assert scenario_toml.from_toml(scenario_toml.to_toml(world)) == world
    assert check_ros2(world) is None
    task = task_of(world)
    assert task.frame_id == "origin1" and task.marker_id == 1
    assert task.destinations == {0: (1.0, 1.0), 1: (1.0, -1.0), 2: (-1.0, -1.0), 3: (-1.0, 1.0)}
    # origin1 at (1.5, -0.5), yaw 0: aruco_1 (1, -1) is (2.5, -1.5) in map
    assert task.destination == pytest.approx((2.5, -1.5))
    # read in the wrong frame it is far from the truth (the faulty example relies on it)
    assert math.dist(task.in_map(1, contract.MAP), task.destination) > 1.0


def test_unknown_assignment_and_missing_task_fields_are_named() -> None:
    text = scenario_toml.to_toml(ros2_final_world())
    with pytest.raises(InvalidScenario, match=r"ros2-finale.*did you mean 'ros2-final'"):
        scenario_toml.from_toml(text.replace('"ros2-final"', '"ros2-finale"'))
    broken = dataclasses.replace(
        ros2_final_world(), task=tuple(kv for kv in ros2_final_world().task if kv[0] != "origin3.x")
    )
    with pytest.raises(InvalidScenario, match=r"task\.origin3\.x: missing"):
        task_of(broken)


def test_variants_are_seeded_checked_and_vary_what_the_project_varies() -> None:
    base = ros2_final_world()
    variants = [make_ros2_variant(base, seed) for seed in range(6)]
    assert make_ros2_variant(base, 3) == variants[3]
    for v in variants:
        assert check_ros2(v) is None
        assert v.walls == base.walls and v.targets == base.targets
    tasks = [task_of(v) for v in variants]
    assert len({t.marker_id for t in tasks}) > 1
    assert len({t.frame_id for t in tasks}) > 1
    assert len({t.destination for t in tasks}) == len(tasks)


def _moved(key: str, value: float | str) -> Scenario:
    world = ros2_final_world()
    task = tuple((k, value if k == key else v) for k, v in world.task)
    assert task != world.task, key
    return dataclasses.replace(world, task=task)


def test_the_check_names_the_first_problem() -> None:
    far = dataclasses.replace(ros2_final_world(), targets=((-1.0, 0.0),))  # aruco_target
    problem = check_ros2(far)
    assert problem is not None and problem.startswith("the marker is ")
    assert problem.endswith("deg off aruco_target")
    lost = _moved("final_destination.aruco_1.x", 40.0)  # origin1 is at (1.5, -0.5)
    assert check_ros2(lost) == (
        "final_destination.aruco_1 in origin1 is (41.50, -1.50) in map: not reachable"
    )


def test_a_keyed_variant_differs_from_the_plain_one() -> None:
    base = ros2_final_world()
    key = WorldKey(b"0123456789abcdef0123456789abcdef")
    assert make_ros2_variant(base, 2, key) == make_ros2_variant(base, 2, key)
    assert [task_of(make_ros2_variant(base, s, key)) for s in range(4)] != [
        task_of(make_ros2_variant(base, s)) for s in range(4)
    ]


def test_the_task_names_a_bad_field() -> None:
    with pytest.raises(InvalidScenario, match=r"frame_id: must be one of origin1, .*got 'map'"):
        task_of(_moved("final_destination.frame_id", "map"))
    two = dataclasses.replace(ros2_final_world(), targets=((0.0, 0.0), (1.0, 1.0)))
    with pytest.raises(InvalidScenario, match="has one target"):
        task_of(two)
