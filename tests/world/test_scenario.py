"""Scenarios: the course world, TOML round trips, and errors that name the field."""

from __future__ import annotations

import math

import pytest

from usar_replay.world import scenario as scn


def test_course_world_facts() -> None:
    c = scn.course_world()
    assert len(c.walls) == 11 and len(c.markers) == 4
    assert c.targets[0] == (-1.752882, 3.246192)
    assert c.parameters()["aruco_lookup_locations/target_4"] == [7.710214, -1.716889]
    assert c.marker_by_id(2).yaw == math.pi
    assert all(w.size_y == 0.15 and w.size_z == 1.0 for w in c.walls)
    x0, _y0, x1, _y1 = scn.building_extent(c)
    assert x0 == pytest.approx(-5.108, abs=1e-3) and x1 == pytest.approx(8.642, abs=1e-3)
