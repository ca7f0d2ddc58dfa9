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


def test_the_bridge_gives_move_base_the_packages_limits(capsys: pytest.CaptureFixture[str]) -> None:
    """The launch file's facts reach each robot's move_base: the follower's footprint and
    planner tolerance as its costmap YAML sets them, the explorer's the template's."""
    from types import SimpleNamespace

    from usar_replay.ros1.bridge import Bridge

    square = [[-0.2, -0.2], [-0.2, 0.2], [0.2, 0.2], [0.2, -0.2]]
    src = "param/costmap.yaml (launch/mb.launch)"
    facts = {
        "move_base": {
            "follower": {
                "footprint": {"key": "k", "value": square, "source": src},
                "default_tolerance": {"key": "k", "value": 0.3, "source": src},
            }
        }
    }
    robots = ("explorer", "follower")
    bridge = SimpleNamespace(
        parameters={},
        config={},
        robots=robots,
        move_base={r: SimpleNamespace(xy_tolerance=0.0, yaw_tolerance=0.0) for r in robots},
        amcl={r: SimpleNamespace(update_min_d=0.0, update_min_a=0.0) for r in robots},
        ready_info="",
    )
    Bridge._configure_stand_ins(bridge, facts)  # type: ignore[arg-type]
    follower = bridge.move_base["follower"].goal_limits
    assert (follower.inscribed_m, follower.default_tolerance_m) == pytest.approx((0.21, 0.3))
    assert src in follower.source
    assert bridge.move_base["explorer"].goal_limits == GoalLimits()
    assert "usar move_base follower" in capsys.readouterr().out
