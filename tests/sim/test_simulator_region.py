"""Simulator.render_region: the course camera's pixels of one window, as a full render has them."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from usar_replay.sim.course_view import CourseCamera, Region
from usar_replay.sim.simulator import Simulator
from usar_replay.world.scenario import course_world


def _look(sim: Simulator) -> None:
    scn = sim.scenario
    tx, ty = scn.targets[0]
    m = scn.marker_by_id(0)
    sim.teleport("explorer", tx, ty, math.atan2(m.y - ty, m.x - tx) + 0.2)


def test_a_region_is_that_window_of_a_full_render_pixel_for_pixel() -> None:
    """TinyRenderer samples the off-axis frustum where the full frustum samples: the same
    bytes (EGL's rasteriser differs in a few edge pixels: bench/bench_course_detect.py)."""
    scn = course_world()
    cam = CourseCamera.of(scn.camera)
    assert cam is not None
    full_cam = dataclasses.replace(scn.camera, width=cam.width, height=cam.height)
    with Simulator(dataclasses.replace(scn, camera=full_cam), renderer="tiny") as sim:
        _look(sim)
        where = sim.course_region(cam)
        assert where is not None
        frames = sim.frame_seq
        crop = sim.render_region(cam, where)
        assert sim.frame_seq == frames and sim.regions_rendered == 1  # the clock did not move
        full = sim.render_camera()
    window = full[where.y : where.y + where.height, where.x : where.x + where.width]
    assert crop.shape == (where.height, where.width, 3)
    assert np.array_equal(crop, window)
    assert crop.min() < 50 < 120 < crop.max()  # the marker's black and its white are in it


def test_a_region_is_rendered_the_same_twice() -> None:
    scn = course_world()
    cam = CourseCamera.of(scn.camera)
    assert cam is not None
    with Simulator(scn, renderer="tiny") as sim:
        _look(sim)
        where = Region(900, 300, 200, 150)
        assert np.array_equal(sim.render_region(cam, where), sim.render_region(cam, where))


def test_no_region_when_the_camera_faces_a_bare_wall() -> None:
    scn = course_world()
    cam = CourseCamera.of(scn.camera)
    assert cam is not None
    with Simulator(scn, renderer="tiny") as sim:
        sim.teleport("explorer", -4.0, 2.5, math.pi)  # the start, facing the west wall
        assert sim.course_region(cam) is None


def test_a_marker_behind_a_wall_gets_no_region_once_the_frame_shows_it_hidden() -> None:
    """Marker 1 faces south from the start strip; from (-2.44, -1.5) looking north it is in
    front of the camera and faces it, but the west divider wall stands between: the frame's
    depth buffer shows it hidden, so no region is rendered for it."""
    scn = course_world()
    cam = CourseCamera.of(scn.camera)
    assert cam is not None
    with Simulator(scn, renderer="tiny") as sim:
        sim.teleport("explorer", -2.44, -1.5, math.pi / 2)
        assert sim.course_region(cam) is not None  # geometry alone: a candidate
        sim.render_camera()
        assert sim.course_region(cam) is None  # the frame shows the wall in front of it
        sim.teleport("explorer", -2.44, 1.0, math.pi / 2)  # the same marker, in plain sight
        sim.render_camera()
        assert sim.course_region(cam) is not None
