"""Navigation: the costmap from geometry, the planner, the controller, failure with a reason."""

from __future__ import annotations

import itertools
import math

import pytest

from usar_replay.core import msgs
from usar_replay.world.nav import (
    DriveLimits,
    GoalLimits,
    Navigator,
    NavStatus,
    PlanningGrid,
    course_goal,
    plan,
    robot_disc,
)
from usar_replay.world.scenario import course_world

COURSE = course_world()
HOME = (-4.0, 2.5)


@pytest.fixture(scope="module")
def grid() -> PlanningGrid:
    return PlanningGrid.from_scenario(COURSE)


def test_grid_has_the_walls_and_the_free_space(grid: PlanningGrid) -> None:
    for w in COURSE.walls:
        r, c = grid.world_to_cell(w.x, w.y)
        assert grid.occupied[r, c], w.name
    for x, y in (*COURSE.targets, HOME, (-4.0, 3.5)):
        assert grid.is_free(x, y)
        assert grid.distance_to_obstacle(x, y) > 0.4
    # the doorway in the divider is open, the divider beside it is not
    assert grid.is_free(1.4, 0.05)
    assert not grid.is_free(-2.0, 0.037)
    assert grid.resolution == 0.05


def test_course_route_plans_keep_off_the_walls(grid: PlanningGrid) -> None:
    route = [HOME, *COURSE.targets, HOME]
    for a, b in itertools.pairwise(route):
        result = plan(grid, a, b)
        assert result.ok, result.reason
        assert result.path[0] == a and result.path[-1] == b
        assert min(grid.distance_to_obstacle(*p) for p in result.path) >= grid.robot_radius
        assert result.length_m >= math.dist(a, b)


def test_unreachable_goals_fail_with_a_reason(grid: PlanningGrid) -> None:
    inside_wall = (COURSE.walls[6].x, COURSE.walls[6].y)
    result = plan(grid, HOME, inside_wall)
    assert not result.ok and "in collision" in result.reason
    nav = Navigator(grid)
    assert (
        nav.set_goal(
            *inside_wall, None, xy_tolerance=0.05, yaw_tolerance=0.17, t_ns=1, start=(*HOME, 0.0)
        )
        == []
    )
    assert nav.status is NavStatus.FAILED and "collision" in nav.reason


def _drive(
    grid: PlanningGrid, goals: list[tuple[float, float, float | None]], blocked: bool = False
) -> tuple[list[msgs.Twist], list[Navigator], tuple[float, float, float]]:
    x, y, yaw = HOME[0], HOME[1], 0.0
    t = 1_000_000_000
    twists: list[msgs.Twist] = []
    navs = []
    for gx, gy, gyaw in goals:
        nav = Navigator(grid)
        nav.set_goal(gx, gy, gyaw, xy_tolerance=0.05, yaw_tolerance=0.17, t_ns=t, start=(x, y, yaw))
        for _ in range(4000):
            if nav.status is not NavStatus.ACTIVE:
                break
            tw = nav.update(t, x, y, yaw)
            twists.append(tw)
            v, w = tw.linear.x, tw.angular.z
            if not blocked:
                x += v * 0.05 * math.cos(yaw + w * 0.025)
                y += v * 0.05 * math.sin(yaw + w * 0.025)
                yaw = math.atan2(math.sin(yaw + w * 0.05), math.cos(yaw + w * 0.05))
                assert grid.distance_to_obstacle(x, y) >= 0.16, (x, y)
            t += 50_000_000
        navs.append(nav)
    return twists, navs, (x, y, yaw)


def test_controller_reaches_every_course_target_within_limits(grid: PlanningGrid) -> None:
    goals = [(tx, ty, None) for tx, ty in COURSE.targets] + [(*HOME, 0.0)]
    twists, navs, (x, y, yaw) = _drive(grid, goals)
    assert [n.status for n in navs] == [NavStatus.SUCCEEDED] * len(goals)
    assert math.dist((x, y), HOME) <= 0.05 and abs(yaw) <= 0.17
    lim = DriveLimits()
    assert max(abs(t.linear.x) for t in twists) <= lim.max_linear + 1e-12
    assert max(abs(t.angular.z) for t in twists) <= lim.max_angular + 1e-12
    for a, b in itertools.pairwise(twists):
        assert abs(b.linear.x - a.linear.x) <= lim.max_linear_accel * 0.05 + 1e-9


def test_a_long_detour_is_progress_not_a_stuck_robot(grid: PlanningGrid) -> None:
    """Either side of the start-strip wall: the path runs ~3 m east, away from the goal, and
    back. Progress is measured along the path, so no recovery fires and both goals succeed."""
    goals = [(-3.5, 1.2, None), (-3.5, 2.6, None)]
    assert plan(grid, HOME, goals[0][:2]).length_m > 2.5 * math.dist(HOME, goals[0][:2])
    _, navs, (x, y, _) = _drive(grid, goals)
    assert [n.status for n in navs] == [NavStatus.SUCCEEDED] * 2, [n.reason for n in navs]
    assert all(n._recoveries == 0 for n in navs)
    assert math.dist((x, y), goals[1][:2]) <= 0.05


def test_a_blocked_robot_fails_after_recovery(grid: PlanningGrid) -> None:
    _, navs, _ = _drive(grid, [(COURSE.targets[0][0], COURSE.targets[0][1], None)], blocked=True)
    assert navs[0].status is NavStatus.FAILED
    assert "stuck" in navs[0].reason and "2 recoveries" in navs[0].reason


def test_navigation_is_deterministic(grid: PlanningGrid) -> None:
    goals = [(COURSE.targets[1][0], COURSE.targets[1][1], 1.0)]
    assert _drive(grid, goals)[0] == _drive(PlanningGrid.from_scenario(COURSE), goals)[0]


def test_a_parked_robot_is_an_obstacle_in_another_robots_map(grid: PlanningGrid) -> None:
    x, y, yaw = HOME[0], HOME[1], 0.0
    cx, cy, r = robot_disc(x, y, yaw)
    assert (cx, cy) == pytest.approx((x - 0.064, y)) and r == pytest.approx(0.21)
    with_robot = grid.with_discs([(cx, cy, r)])
    assert grid.is_free(x, y) and not with_robot.is_free(x, y)
    assert not with_robot.is_free(x + 0.4, y)  # the other robot cannot come this close
    assert with_robot.is_free(x + 0.6, y)
    assert not grid.occupied[grid.world_to_cell(cx, cy)]  # the original map is unchanged
    # the follower's start is still connected to the rest of the building around it
    assert plan(with_robot, (-4.0, 3.5), COURSE.targets[0]).ok


# --- which goals the course's global planner has a plan to (issue 51) ---------------------------

CYLINDER = (1.914, 3.688)
"""A cylinder of the course world (r 0.2821): marker 2 of the second known layout hangs on it."""


def test_a_goal_within_the_inscribed_radius_of_a_cylinder_has_no_plan(grid: PlanningGrid) -> None:
    """Issue 51's follower goal, marker 2 of the second layout minus (0.4, 0.4): 0.10 m from the
    cylinder's surface, its costmap cell within the template footprint's inscribed radius
    (0.087 m, padded) of an obstacle cell: refused, never moved. 0.17 m out along x it is
    plannable (it stays where it is; usar's move_base then keeps its own clearance)."""
    refused, why = course_goal(grid, 2.208 - 0.4, 3.717 - 0.4)
    assert refused is None
    assert why.startswith("goal (1.808, 3.317) is within the footprint's inscribed radius")
    assert "default_tolerance 0 m" in why
    beside = (CYLINDER[0] - 0.45, CYLINDER[1])
    assert course_goal(grid, *beside) == (beside, "")
    assert not grid.is_free(*beside)  # inside usar's clearance all the same
    wall, why = course_goal(grid, 0.0, 0.0)  # inside the divider: an obstacle cell
    assert wall is None and "is in an obstacle" in why


def test_the_packages_limits_decide(grid: PlanningGrid) -> None:
    """A wider footprint refuses the goal beside the cylinder; a ``default_tolerance`` reaches a
    plannable cell near a refused goal; an inflation radius below the inscribed radius paints no
    inscribed cost (only the obstacle's own cells refuse)."""
    beside = (CYLINDER[0] - 0.45, CYLINDER[1])
    wide = GoalLimits(inscribed_m=0.2)
    assert course_goal(grid, *beside, wide)[0] is None
    near, why = course_goal(grid, 1.808, 3.317, GoalLimits(default_tolerance_m=0.2))
    assert near is not None and why == "" and math.dist(near, (1.808, 3.317)) <= 0.2
    assert grid.distance_to_obstacle(*near) > 0.087
    thin = GoalLimits(inscribed_m=0.3, inflation_m=0.01)
    assert course_goal(grid, 1.808, 3.317, thin) == ((1.808, 3.317), "")
    assert course_goal(grid, 0.0, 0.0, thin)[0] is None


def test_every_course_target_and_home_has_a_plan(grid: PlanningGrid) -> None:
    for x, y in (*COURSE.targets, HOME, (COURSE.follower.x, COURSE.follower.y)):
        assert course_goal(grid, x, y) == ((x, y), ""), (x, y)
