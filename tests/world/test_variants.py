"""Seeded variants ("a different environment"): deterministic, valid, and validation can fail."""

from __future__ import annotations

import dataclasses
import math

import pytest

from usar_replay.core.errors import InvalidScenario
from usar_replay.world.nav import PlanningGrid
from usar_replay.world.scenario import course_world
from usar_replay.world.scenario_toml import from_toml, to_toml
from usar_replay.world.variants import (
    MAX_DRIVE_FRACTION,
    MAX_RANGE,
    check_variant,
    drive_time_s,
    make_variant,
)

BASE = course_world()
GRID = PlanningGrid.from_scenario(BASE)


@pytest.mark.parametrize("seed", range(10))
def test_ten_seeded_variants_validate(seed: int) -> None:
    v = make_variant(BASE, seed)
    assert check_variant(v, GRID) is None
    assert v.seed == seed and len(v.markers) == len(v.targets) == 4
    assert sorted(m.id for m in v.markers) == [0, 1, 2, 3]
    # the building and the robots' starts are the course's; only markers and targets moved
    assert (v.walls, v.boxes, v.cylinders, v.spheres) == (
        BASE.walls,
        BASE.boxes,
        BASE.cylinders,
        BASE.spheres,
    )
    assert (v.explorer, v.follower) == (BASE.explorer, BASE.follower)
    assert {(m.x, m.y) for m in v.markers}.isdisjoint({(m.x, m.y) for m in BASE.markers})
    for target in v.targets:
        nearest = min(math.dist(target, (m.x, m.y)) for m in v.markers)
        assert nearest <= MAX_RANGE
    assert drive_time_s(v, GRID) <= MAX_DRIVE_FRACTION * v.time_limit_s
    # the variant survives the trip through its TOML (it travels inside every recording)
    assert from_toml(to_toml(v)) == v


def test_same_seed_same_world_other_seed_other_world() -> None:
    assert make_variant(BASE, 3) == make_variant(BASE, 3)
    assert make_variant(BASE, 3).markers != make_variant(BASE, 4).markers


def test_the_course_world_itself_passes_the_rules() -> None:
    assert check_variant(BASE, GRID) is None


def test_validation_rejects_a_target_out_of_sight() -> None:
    v = make_variant(BASE, 0)
    far = dataclasses.replace(v, targets=((-4.0, -3.0), *v.targets[1:]))
    problem = check_variant(far, GRID)
    assert problem is not None and "target_1" in problem


def test_validation_rejects_a_target_inside_a_wall() -> None:
    wall = BASE.walls[6]  # the start-strip wall
    v = dataclasses.replace(BASE, targets=((wall.x, wall.y), *BASE.targets[1:]))
    problem = check_variant(v, GRID)
    assert problem is not None and "target_1" in problem


def test_validation_rejects_a_world_too_big_for_its_time_limit() -> None:
    need = drive_time_s(BASE, GRID)
    assert 300 < need < MAX_DRIVE_FRACTION * BASE.time_limit_s  # the course: ~350 s of driving
    tight = dataclasses.replace(BASE, time_limit_s=need / MAX_DRIVE_FRACTION - 1.0)
    problem = check_variant(tight, GRID)
    assert problem is not None and "of driving" in problem


def test_negative_seed_is_a_user_error() -> None:
    with pytest.raises(InvalidScenario, match="--seed -1"):
        make_variant(BASE, -1)
