"""The simulator: determinism, the camera model, markers the right way round, walls that stop."""

from __future__ import annotations

import hashlib
import math
import os
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

from usar_replay.core import msgs
from usar_replay.sim.simulator import FOOTPRINT, Simulator
from usar_replay.world.nav import Navigator, NavStatus, PlanningGrid
from usar_replay.world.scenario import course_world

# the marker each course target sees, in target order (course-world.md)
TARGET_MARKER = {0: 0, 1: 1, 2: 3, 3: 2}


@pytest.fixture(scope="module")
def sim() -> Simulator:
    s = Simulator(course_world(), renderer="tiny")
    yield s
    s.close()


def _face(sim: Simulator, k: int) -> tuple[np.ndarray, msgs.CameraInfo]:
    scn = sim.scenario
    tx, ty = scn.targets[k]
    m = scn.marker_by_id(TARGET_MARKER[k])
    sim.teleport("explorer", tx, ty, math.atan2(m.y - ty, m.x - tx))
    return sim.render_camera(), sim.camera_info()


@pytest.mark.parametrize("k", range(4))
def test_each_course_marker_decodes_to_its_id_from_its_target(sim: Simulator, k: int) -> None:
    img, info = _face(sim, k)
    det = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50))
    corners, ids, _ = det.detectMarkers(img)
    assert ids is not None and ids.ravel().tolist() == [TARGET_MARKER[k]]
    # K matches the rendering: the marker's true corners project onto the detected ones
    m = sim.scenario.marker_by_id(TARGET_MARKER[k])
    eye, rot = sim.camera_pose()
    kmat = np.array(info.k).reshape(3, 3)
    h, c, s = m.size / 2, math.cos(m.yaw), math.sin(m.yaw)
    # seen from the front: top-left is at -y (local), top; OpenCV order TL, TR, BR, BL
    local = [(-h, h), (h, h), (h, -h), (-h, -h)]
    for (ly, lz), found in zip(local, corners[0][0], strict=True):
        world = np.array([m.x - s * ly, m.y + c * ly, m.z + lz])
        cam = rot.T @ (world - eye)
        uv = (kmat @ cam)[:2] / cam[2]
        assert np.hypot(*(uv - found)) < 1.5, (uv, found)


def test_camera_info_and_optical_frame(sim: Simulator) -> None:
    info = sim.camera_info()
    assert (info.width, info.height) == (640, 480)
    assert info.header.frame_id == "explorer_tf/camera_rgb_optical_frame"
    fx = info.k[0]
    # horizontal FOV 1.3439 rad: the image's half-width subtends hfov/2
    assert math.isclose(2 * math.atan(320 / fx), 1.3439, rel_tol=1e-9)
    sim.teleport("explorer", -4.0, 2.5, 0.3)
    eye, rot = sim.camera_pose()
    ahead = np.array([-4.0 + math.cos(0.3) * 2, 2.5 + math.sin(0.3) * 2, eye[2]])
    cam = rot.T @ (ahead - eye)
    assert cam[2] > 1.9 and abs(cam[0]) < 0.1 and abs(cam[1]) < 1e-9  # z forward
    below = rot.T @ (eye - np.array([0, 0, 1.0]) - eye)
    assert below[1] > 0.99  # y down


def test_tf_chain_names() -> None:
    with Simulator(course_world(), renderer="tiny") as sim:
        static = {(t.header.frame_id, t.child_frame_id) for t in sim.tf_static().transforms}
        dynamic = {(t.header.frame_id, t.child_frame_id) for t in sim.tf().transforms}
    for r in ("explorer", "follower"):
        assert ("map", f"{r}_tf/odom") in static
        assert (f"{r}_tf/odom", f"{r}_tf/base_footprint") in dynamic
        assert (f"{r}_tf/base_footprint", f"{r}_tf/camera_rgb_frame") in static
        assert (f"{r}_tf/camera_rgb_frame", f"{r}_tf/camera_rgb_optical_frame") in static


def _drive(renderer: str) -> tuple[list[tuple[float, float, float]], str]:
    poses = []
    digest = hashlib.sha256()
    with Simulator(course_world(), renderer=renderer) as sim:
        for i in range(40):
            sim.set_cmd_vel(
                "explorer",
                msgs.Twist(linear=msgs.Vector3(x=0.26), angular=msgs.Vector3(z=0.3 * math.sin(i))),
            )
            sim.set_cmd_vel("follower", msgs.Twist(angular=msgs.Vector3(z=1.0)))
            sim.step(5)
            for r in ("explorer", "follower"):
                p = sim.true_pose(r)
                poses.append((p.position.x, p.position.y, p.orientation.z))
            if sim.camera_due():
                digest.update(sim.render_camera().tobytes())
    return poses, digest.hexdigest()


def test_same_commands_give_bit_identical_poses_and_images() -> None:
    a, b = _drive("tiny"), _drive("tiny")
    assert a == b


def test_limits_and_odometry() -> None:
    with Simulator(course_world(), renderer="tiny") as sim:
        sim.set_cmd_vel(
            "explorer", msgs.Twist(linear=msgs.Vector3(x=5.0), angular=msgs.Vector3(z=9.0))
        )
        sim.step(100)  # 1 s
        odom = sim.odometry("explorer")
        assert odom.twist.twist.linear.x == pytest.approx(0.26)
        assert odom.twist.twist.angular.z == pytest.approx(1.82)
        true = sim.true_pose("explorer")
        # world-source odometry (gazebo_ros_diff_drive's default): the pose is the world pose
        assert odom.pose.pose == true
        assert odom.header.frame_id == "explorer_tf/odom"


def test_odometry_starts_at_the_start_pose_and_map_to_odom_is_the_identity() -> None:
    """As the course's Gazebo publishes it: ``/explorer/odom`` begins at (-4, 2.5), not (0, 0),
    ``odom -> base_footprint`` equals it, and ``map -> odom`` is the identity (what amcl,
    started at the same pose, publishes), so ``map -> base_footprint`` is the true pose."""
    with Simulator(course_world(), renderer="tiny") as sim:
        sim.set_cmd_vel(
            "follower", msgs.Twist(linear=msgs.Vector3(x=0.2), angular=msgs.Vector3(z=0.5))
        )
        first = sim.odometry("explorer").pose.pose.position
        assert (first.x, first.y) == (sim.scenario.explorer.x, sim.scenario.explorer.y)
        sim.step(150)
        static = {t.child_frame_id: t.transform for t in sim.tf_static().transforms}
        dynamic = {t.child_frame_id: t.transform for t in sim.tf().transforms}
        for r in ("explorer", "follower"):
            assert static[f"{r}_tf/odom"] == msgs.Transform()
            link = dynamic[f"{r}_tf/base_footprint"]
            pose = sim.odometry(r).pose.pose
            assert (link.translation.x, link.translation.y) == (pose.position.x, pose.position.y)
            assert link.rotation == pose.orientation
            assert pose == sim.true_pose(r)
        moved = sim.odometry("follower").pose.pose.position
        assert (
            math.hypot(moved.x - sim.scenario.follower.x, moved.y - sim.scenario.follower.y) > 0.2
        )


def test_acceleration_is_limited() -> None:
    with Simulator(course_world(), renderer="tiny") as sim:
        sim.set_cmd_vel("explorer", msgs.Twist(linear=msgs.Vector3(x=0.26)))
        sim.step(1)
        v = sim.odometry("explorer").twist.twist.linear.x
        assert 0 < v <= 2.5 * 0.01 + 1e-12


def test_a_wall_stops_the_robot() -> None:
    with Simulator(course_world(), renderer="tiny") as sim:
        # face the east outer wall (inner face at x = 8.4925) from 1 m away and drive on
        sim.teleport("explorer", 7.5, -1.0, 0.0)
        sim.set_cmd_vel("explorer", msgs.Twist(linear=msgs.Vector3(x=0.26)))
        sim.step(1500)  # 15 s: far enough to cross the wall if nothing stopped it
        x = sim.true_pose("explorer").position.x
        front = max(q[0] for q in FOOTPRINT)
        assert x + front <= 8.4925 + 1e-6
        assert x > 8.3  # it did drive up to the wall
        assert sim.refused_motions("explorer") > 0
        assert sim.odometry("explorer").twist.twist.linear.x == 0.0


def test_camera_runs_at_its_rate_on_the_sim_clock() -> None:
    with Simulator(course_world(), renderer="tiny") as sim:
        frames = 0
        t0 = sim.now_ns
        while sim.now_ns < t0 + 2_000_000_000:
            if sim.camera_due():
                sim.render_camera()
                frames += 1
            sim.step(5)
        assert frames == 20


def test_egl_renderer_is_deterministic_when_it_loads() -> None:
    with Simulator(course_world(), renderer="auto") as sim:
        if sim.renderer_name != "egl":
            pytest.skip("the EGL renderer plugin does not load on this machine")
    a, b = _drive("egl"), _drive("egl")
    assert a == b


def test_explorer_drives_to_every_course_target_in_the_simulator() -> None:
    """The navigator closes the loop through the simulator: every target, no wall touched."""
    scn = course_world()
    grid = PlanningGrid.from_scenario(scn)
    nav = Navigator(grid)
    with Simulator(scn, renderer="tiny") as sim:
        for tx, ty in scn.targets:
            pose = sim.true_pose("explorer")
            start = (pose.position.x, pose.position.y, _yaw_of(pose))
            nav.set_goal(
                tx, ty, None, xy_tolerance=0.05, yaw_tolerance=0.17, t_ns=sim.now_ns, start=start
            )
            deadline = sim.now_ns + 180_000_000_000
            while nav.status is NavStatus.ACTIVE and sim.now_ns < deadline:
                pose = sim.true_pose("explorer")
                x, y = pose.position.x, pose.position.y
                # the base keeps clear of every wall and obstacle (the footprint is 0.155 m wide
                # each side), and the simulator never had to refuse a colliding motion (below)
                assert grid.distance_to_obstacle(x, y) >= 0.15, (x, y)
                sim.set_cmd_vel("explorer", nav.update(sim.now_ns, x, y, _yaw_of(pose)))
                sim.step(5)
            assert nav.status is NavStatus.SUCCEEDED, nav.reason
            end = sim.true_pose("explorer").position
            assert math.dist((end.x, end.y), (tx, ty)) <= 0.05
        assert sim.refused_motions("explorer") == 0


def _yaw_of(pose: msgs.Pose) -> float:
    q = pose.orientation
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


# -- frames reused when nothing moved ---------------------------------------------------------


def _room_sim() -> Simulator:
    from conftest import one_room

    return Simulator(one_room(), renderer="tiny")


def test_a_parked_camera_reuses_its_frame_exactly() -> None:
    """Nothing moved: no render, and the pixels are those a fresh simulator renders."""
    with _room_sim() as a:
        a.teleport("explorer", -1.2, 0.0, 0.1)
        first = a.render_camera()
        again = a.render_camera()
        assert a.frames_rendered == 1 and again is first and not again.flags.writeable
        assert a.frame_seq == 2
        with _room_sim() as fresh:
            fresh.teleport("explorer", -1.2, 0.0, 0.1)
            assert np.array_equal(fresh.render_camera(), again)


def test_a_robot_moving_out_of_view_does_not_render_and_changes_no_pixel() -> None:
    with _room_sim() as a:
        a.teleport("explorer", -1.2, 0.0, 0.0)  # facing +x: the west half of the room is behind
        a.render_camera()
        behind = [(-1.9, -1.3), (-1.9, 1.3), (-1.85, 0.0)]
        for x, y in behind:
            a.teleport("follower", x, y, 0.7)
            img = a.render_camera()
            assert a.frames_rendered == 1
            with _room_sim() as fresh:  # the same world, rendered from scratch
                fresh.teleport("explorer", -1.2, 0.0, 0.0)
                fresh.teleport("follower", x, y, 0.7)
                assert np.array_equal(fresh.render_camera(), img)


def test_a_robot_moving_in_view_or_the_camera_moving_renders_again() -> None:
    with _room_sim() as a:
        a.teleport("explorer", -1.2, 0.0, 0.0)
        base = a.render_camera().copy()
        a.teleport("follower", 0.8, 0.2, 0.0)  # in front of the camera
        seen = a.render_camera()
        assert a.frames_rendered == 2 and not np.array_equal(seen, base)
        a.teleport("follower", 0.8, 0.25, 0.0)  # moved while in view
        a.render_camera()
        assert a.frames_rendered == 3
        a.teleport("explorer", -1.2, 0.0, 1e-12)  # the smallest turn is a new view
        a.render_camera()
        assert a.frames_rendered == 4


def _egl_sim() -> Simulator:
    sim = Simulator(course_world(), renderer="auto")
    if sim.renderer_name != "egl":
        sim.close()
        pytest.skip("the EGL renderer plugin does not load on this machine")
    return sim


def test_egl_honours_shadow_off_so_hidden_motion_changes_no_pixel() -> None:
    """The EGL plugin ignores ``shadow=0``; with its shadow-map pass switched off, a body that
    moves behind a wall changes no pixel, and a reused frame equals a fresh render."""
    with _egl_sim() as a:
        assert not a.egl_shadow_map
        a.teleport("explorer", -4.0, 2.5, 0.0)
        base = a.render_camera()
        a.teleport("follower", 5.0, -2.0, 0.3)  # in the frustum, behind the divider
        assert np.array_equal(a._render()[0], base)
    with _egl_sim() as fresh:
        fresh.teleport("explorer", -4.0, 2.5, 0.0)
        fresh.teleport("follower", 5.0, -2.0, 0.3)
        assert np.array_equal(fresh.render_camera(), base)


@pytest.mark.parametrize("renderer", ["tiny", "egl"])
def test_a_robot_hidden_behind_a_wall_does_not_render_and_changes_no_pixel(renderer: str) -> None:
    """In the frustum but behind the static scene: no render, and the pixels a fresh simulator
    renders; once it steps into plain view, the camera renders again. (One simulator at a time:
    the EGL plugin is one per process.)"""
    scn = course_world()
    hidden = [(5.0, -2.0, 0.3), (3.0, -1.0, 2.0), (-2.0, 1.4, 0.0)]
    frames = []
    with Simulator(scn, renderer=renderer) as a:
        if a.renderer_name != renderer:
            pytest.skip(f"the {renderer} renderer does not load on this machine")
        a.teleport("explorer", -4.0, 2.5, 0.0)  # facing east along the north hall
        a.teleport("follower", -4.0, 3.5, 0.0)  # beside it, out of the frustum
        base = a.render_camera()
        for x, y, yaw in hidden:
            a.teleport("follower", x, y, yaw)
            assert a._maybe_in_view(a.robots["follower"])  # the frustum alone would render
            frames.append(a.render_camera())
            assert a.frames_rendered == 1, (x, y)
        a.teleport("follower", -2.5, 2.6, 0.0)  # in plain view down the hall
        seen = a.render_camera()
        assert a.frames_rendered == 2 and not np.array_equal(seen, base)
    for (x, y, yaw), img in zip(hidden, frames, strict=True):
        with Simulator(scn, renderer=renderer) as fresh:
            fresh.teleport("explorer", -4.0, 2.5, 0.0)
            fresh.teleport("follower", x, y, yaw)
            assert np.array_equal(fresh.render_camera(), img), (x, y)


def test_an_egl_plugin_that_kills_its_process_is_probed_in_a_child(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A plugin whose load ends the process (llvmpipe under qemu's emulated CPU dies with
    SIGSEGV) is answered 'does not load' by a child process: the caller lives on, and the answer
    is handed to its children through the environment."""
    from usar_replay.sim import simulator

    src = tmp_path / "crash.c"
    src.write_text(
        "#include <signal.h>\n"
        "__attribute__((constructor)) static void die(void) { raise(SIGSEGV); }\n"
    )
    lib = tmp_path / "crash.so"
    subprocess.run(["gcc", "-shared", "-fPIC", "-o", str(lib), str(src)], check=True)
    monkeypatch.delenv(simulator.EGL_PROBE_ENV, raising=False)
    simulator.egl_loads_safely.cache_clear()
    try:
        assert simulator.egl_loads_safely(str(lib)) is False
        assert os.environ[simulator.EGL_PROBE_ENV] == f"no:{lib}"
    finally:
        simulator.egl_loads_safely.cache_clear()


def test_an_egl_probe_handed_down_is_not_run_again(monkeypatch: pytest.MonkeyPatch) -> None:
    """A child process takes its parent's answer for the same plugin path (no second probe)."""
    from usar_replay.sim import simulator

    monkeypatch.setenv(simulator.EGL_PROBE_ENV, "ok:/nowhere/eglRenderer.so")
    simulator.egl_loads_safely.cache_clear()
    try:
        assert simulator.egl_loads_safely("/nowhere/eglRenderer.so") is True  # no file: not probed
        assert simulator.egl_loads_safely("/elsewhere/eglRenderer.so") is False  # probed: fails
    finally:
        simulator.egl_loads_safely.cache_clear()
