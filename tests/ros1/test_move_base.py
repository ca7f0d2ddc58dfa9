"""ros1/move_base: which goals usar's move_base drives to, as the package's global planner
decides (issue 51); the action server itself is covered end to end by tests/e2e/test_ros1.py."""

from __future__ import annotations

import math

import pytest

from usar_replay.ros1.move_base import GOAL_TOLERANCE_M, planned_goal
from usar_replay.world.nav import GoalLimits, PlanningGrid, plan
from usar_replay.world.scenario import course_world

FOLLOWER_HOME = (-4.0, 3.5)


@pytest.fixture(scope="module")
def grid() -> PlanningGrid:
    return PlanningGrid.from_scenario(course_world())


def test_a_goal_the_course_has_no_plan_to_is_refused_never_moved(grid: PlanningGrid) -> None:
    """The follower's goal behind marker 2 of the second layout (0.10 m from the cylinder's
    surface): no goal, the reason says why (move_base aborts it; usar moved it 0.22 m before)."""
    goal, why = planned_goal(grid, 1.808, 3.317)
    assert goal is None and "inscribed radius" in why
    assert planned_goal(grid, 0.0, 0.0)[0] is None  # inside the divider wall


def test_a_goal_beside_the_cylinder_the_course_plans_to_is_driven_to(grid: PlanningGrid) -> None:
    """0.17 m from the surface: plannable on the course; usar's navigator keeps its own wider
    clearance, so it drives to the nearest free cell within GOAL_TOLERANCE_M, and has a path."""
    beside = (1.914 - 0.45, 3.688)
    goal, why = planned_goal(grid, *beside)
    assert goal is not None and why == ""
    assert grid.is_free(*goal) and math.dist(goal, beside) <= GOAL_TOLERANCE_M
    assert plan(grid, FOLLOWER_HOME, goal).ok
    # with the package's wider footprint, the course's planner refuses it too
    assert planned_goal(grid, *beside, GoalLimits(inscribed_m=0.2))[0] is None


def test_a_free_goal_is_the_goal(grid: PlanningGrid) -> None:
    assert planned_goal(grid, -4.0, 2.5) == ((-4.0, 2.5), "")
