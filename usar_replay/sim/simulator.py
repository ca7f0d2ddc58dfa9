"""The simulator: the scenario built in pybullet, two robots driven by ``cmd_vel``, one camera.

The only module that imports pybullet. Why it is built this way (measured on the 2-core machines
this runs on):

* **Kinematic robots.** Driving wheel motors through pybullet tracked ``cmd_vel`` poorly (a robot
  spinning in place drifted 9-13 cm). Each physics step here integrates the unicycle model
  exactly (with the waffle's velocity and acceleration limits) and places the base; pybullet's
  collision detection then checks the robot's footprint box against the walls, obstacles and the
  other robot, and a motion that would overlap anything is refused (the robot stays, its velocity
  drops to zero). Robots cannot pass through walls, and the result is bit-deterministic.
* **A fixed step and a sim clock in integer nanoseconds**, starting at ``start_time_ns`` (> 0:
  some tools mishandle a log time of 0). Nothing reads the wall clock.
* **Rendering is the first performance problem**: the camera renders only when a frame is due
  on the sim clock, the scene has few triangles, shadows are off, and every lighting argument is
  passed on every call (TinyRenderer otherwise keeps the previous call's, so images would depend
  on call history). The EGL plugin ignores ``shadow=0``; :mod:`usar_replay.sim.eglshadow` switches
  its shadow-map pass off, which cuts its CPU per 640x480 frame from about 105 ms to 34 ms. It
  then renders about 4x cheaper than TinyRenderer. ``renderer="auto"`` uses EGL when it loads
  and falls back to TinyRenderer; :attr:`Simulator.renderer_name` is recorded with every run
  because the two renderers' pixels differ.
* **Markers are textured OBJ quads** (a texture on a box renders as two halves and is never
  detected) wound counter-clockwise as seen from the front, with UVs chosen so the rendered marker
  is neither mirrored nor rotated; a test decodes every rendered marker to its own ID.
* **Camera model**: pybullet's FOV argument is vertical, so ``fov_v = 2 atan(tan(hfov/2) H/W)``;
  ``fx = fy = (H/2) / tan(fov_v/2)``; TinyRenderer's optical axis falls on OpenCV pixel
  ``(W/2, H/2 - 1)``. :meth:`Simulator.camera_info` publishes exactly that K.

Frames (REP-105): ``map -> <robot>_tf/odom`` (identity, static, on ``/tf_static``) ``->
<robot>_tf/base_footprint`` (odometry, on ``/tf``) ``-> <robot>_tf/camera_rgb_frame`` (static,
forward-looking, x forward) ``-> <robot>_tf/camera_rgb_optical_frame`` (static, rpy
(-pi/2, 0, -pi/2): z forward, x right, y down).

**Odometry is world-source, as the course's Gazebo publishes it.** The TurtleBot3 waffle's
``turtlebot3_waffle.gazebo.xacro`` loads ``libgazebo_ros_diff_drive.so`` without an
``<odometrySource>``, and gazebo_ros_diff_drive's default is ``world``: its ``/odom`` and its
``odom -> base_footprint`` are the model's Gazebo world pose. The course spawns the robots at
their starts, so ``/explorer/odom`` begins at (-4, 2.5), not (0, 0), and packages that compare
odometry positions with map targets work. amcl (started at the same pose) then publishes
``map -> odom`` as the identity, up to its estimation error; this world has no drift to correct,
so usar's ``map -> odom`` is exactly the identity and static. docs/ros1.md names the sources.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import math
import os
import pkgutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np


@contextlib.contextmanager
def _quiet_stdout() -> Iterator[None]:
    """Silence C-level prints (pybullet's build banner, the EGL plugin's GL report) on fd 1-2.

    They would otherwise interleave with the CLI's own output, which users may pipe.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    _libc_fflush()
    saved = (os.dup(1), os.dup(2))
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            yield
            _libc_fflush()  # C stdio buffers when stdout is a pipe: drop it while muted
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])


def _libc_fflush() -> None:
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).fflush(None)


with _quiet_stdout():
    import pybullet as p

from usar_replay.core import contract, msgs  # noqa: E402
from usar_replay.sim import course_view, eglshadow  # noqa: E402
from usar_replay.sim.course_view import CourseCamera, Region  # noqa: E402
from usar_replay.world.scenario import Scenario  # noqa: E402

__all__ = [
    "EGL_PROBE_ENV",
    "CAMERA_MOUNT",
    "FOOTPRINT",
    "LIMITS",
    "RobotLimits",
    "SimRobot",
    "Simulator",
    "camera_intrinsics",
    "egl_loads_safely",
    "pybullet_api_version",
]

FOOTPRINT = ((-0.205, -0.155), (-0.205, 0.155), (0.077, 0.155), (0.077, -0.155))
"""The waffle's costmap footprint in base_footprint (x forward), metres."""
CAMERA_MOUNT = (0.069, -0.047, 0.117)
"""Optical centre from base_footprint (course-world.md)."""
OPTICAL_RPY = (-math.pi / 2, 0.0, -math.pi / 2)
WALL_RGBA = (0.86, 0.85, 0.80, 1.0)
OBSTACLE_RGBA = (0.55, 0.60, 0.70, 1.0)
FLOOR_RGBA = (0.45, 0.42, 0.38, 1.0)
ROBOT_RGBA = (0.20, 0.22, 0.25, 1.0)
LIGHT_DIRECTION = (0.4, 0.3, 1.0)
ROBOT_VISUAL_HALF = (0.133, 0.133, 0.047)
"""Half extents of a robot's visual box, in base_footprint (x forward)."""
ROBOT_VISUAL_OFFSET = (-0.064, 0.0, 0.057)
"""Centre of a robot's visual box, in base_footprint."""
NEAR_PLANE = 0.02
"""m, the camera's near clipping distance."""
FAR_PLANE = 30.0
"""m, the camera's far clipping distance."""
CULL_MARGIN_PX = 8.0
"""Pixels of slack around the image, or around a robot's projected box, when deciding that the
robot cannot be in view."""
OCCLUSION_MARGIN_M = 0.05
"""m: a robot counts as hidden only when the static scene is this much nearer than all of it
(the depth buffer's resolution at 10 m is about 0.3 mm)."""


def _depth_buffer_value(z: float) -> float:
    """The depth-buffer value of a point ``z`` metres along the optical axis: pybullet's
    documented ``z = far * near / (far - (far - near) * d)``, solved for ``d``."""
    return FAR_PLANE * (z - NEAR_PLANE) / (z * (FAR_PLANE - NEAR_PLANE))


@dataclass(frozen=True, slots=True)
class RobotLimits:
    """The waffle's limits; accelerations are TurtleBot3's DWA defaults."""

    max_linear: float = 0.26
    max_angular: float = 1.82
    max_linear_accel: float = 2.5
    max_angular_accel: float = 3.2


LIMITS = RobotLimits()


def camera_intrinsics(width: int, height: int, hfov: float) -> tuple[float, float, float, float]:
    """(fx, fy, cx, cy) of the rendered image, in OpenCV's pixel convention."""
    fov_v = 2.0 * math.atan(math.tan(hfov / 2.0) * height / width)
    f = (height / 2.0) / math.tan(fov_v / 2.0)
    return f, f, width / 2.0, height / 2.0 - 1.0


def _quat_yaw(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


def _msg_quat(q: tuple[float, float, float, float]) -> msgs.Quaternion:
    return msgs.Quaternion(x=q[0], y=q[1], z=q[2], w=q[3])


def _tf(
    parent: str, child: str, t_ns: int, xyz: tuple[float, float, float], q: Any
) -> msgs.TransformStamped:
    return msgs.TransformStamped(
        header=msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id=parent),
        child_frame_id=child,
        transform=msgs.Transform(
            translation=msgs.Vector3(x=xyz[0], y=xyz[1], z=xyz[2]), rotation=_msg_quat(q)
        ),
    )


@dataclass(frozen=True, slots=True)
class SimRobot:
    """A robot to simulate: its names (frames) and its start pose in ``map``.

    Why: the US&R world has two robots named ``<robot>_tf/...``; the ROS 2 final project has
    one, ``robot1``, named ``robot1/...``. The simulator takes the names from here and spells none.
    """

    frames: contract.RobotFrames
    x: float
    y: float
    yaw: float = 0.0


@dataclass(slots=True)
class _RobotState:
    name: str
    frames: contract.RobotFrames
    body: int
    x: float
    y: float
    yaw: float
    v: float = 0.0
    w: float = 0.0
    cmd_v: float = 0.0
    cmd_w: float = 0.0
    refused: int = 0


EGL_PROBE_ENV = "USAR_EGL_PROBE"
"""Where a probe's answer is handed to child processes (``ok:PATH`` or ``no:PATH``), so a batch
or a test run probes once, not once per recording."""

_PROBE = (
    "import sys, pybullet as p\n"
    "p.connect(p.DIRECT)\n"
    "sys.exit(0 if p.loadPlugin(sys.argv[1], '_eglRendererPlugin') >= 0 else 3)\n"
)


@functools.cache
def egl_loads_safely(path: str) -> bool:
    """Whether pybullet's EGL plugin at ``path`` loads without taking the process with it.

    Why a probe in a child process: on some machines the plugin does not fail, it kills its
    process (Mesa's llvmpipe JIT under qemu's emulated CPUs dies with SIGSEGV on load; softpipe
    without a context makes the plugin call ``exit``), and ``--renderer auto`` would then end the
    recorder, not fall back to the tiny renderer. The answer is kept for the process and handed
    to its children through :data:`EGL_PROBE_ENV`."""
    told = os.environ.get(EGL_PROBE_ENV, "")
    verdict, _, probed = told.partition(":")
    if probed == path and verdict in ("ok", "no"):
        return verdict == "ok"
    try:
        done = subprocess.run(
            [sys.executable, "-c", _PROBE, path],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            timeout=120,
            check=False,
        )
        ok = done.returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        ok = False
    os.environ[EGL_PROBE_ENV] = f"{'ok' if ok else 'no'}:{path}"
    return ok


class Simulator:
    """The scenario in pybullet (DIRECT mode, a private client), stepped on a sim clock."""

    def __init__(
        self,
        scenario: Scenario,
        *,
        physics_hz: int = 100,
        start_time_ns: int = 1_000_000_000,
        renderer: str = "auto",
        limits: RobotLimits = LIMITS,
        robots: tuple[SimRobot, ...] | None = None,
        camera_robot: str = "explorer",
        base_tf: bool = True,
        static_frames: tuple[tuple[str, str, float, float, float], ...] = (),
    ) -> None:
        """``robots``: default the scenario's explorer and follower (US&R names). The camera
        is on ``camera_robot``. ``base_tf=False``: no ``odom -> base_footprint`` on ``/tf``
        (the ROS 2 final project's broken tree). ``static_frames``: extra ``(parent, child, x,
        y, yaw)`` links for ``/tf_static`` (the project's ``map -> originN``)."""
        if start_time_ns <= 0:
            raise ValueError("start_time_ns must be positive")
        if renderer not in ("auto", "tiny", "egl"):
            raise ValueError(f"renderer must be auto, tiny or egl, not {renderer!r}")
        self.scenario = scenario
        self.limits = limits
        self.physics_hz = physics_hz
        self.dt_ns = 1_000_000_000 // physics_hz
        self.now_ns = start_time_ns
        self._client = p.connect(p.DIRECT)
        self._tmp = tempfile.TemporaryDirectory(prefix="usar-sim-")
        self._static_bodies: list[int] = []
        cam = scenario.camera
        self.camera_period_ns = round(1e9 / cam.rate_hz)
        self.next_frame_ns = start_time_ns
        self.frame_seq = 0
        self.frames_rendered = 0
        """How many frames pybullet actually rendered (the rest were reused: nothing moved)."""
        self.regions_rendered = 0
        """How many course-camera regions :meth:`render_region` rendered (the rest were
        reused: nothing moved)."""
        self._frame_depth: tuple[tuple[object, ...], np.ndarray] | None = None
        """The view key and depth buffer of the camera's last render (:meth:`course_region`)."""
        self._last_region: tuple[object, np.ndarray] | None = None
        self._last_frame: tuple[tuple[object, ...], np.ndarray] | None = None
        self._static_depth: tuple[object, np.ndarray] | None = None
        """The depth buffer of the last render with no robot in view, and the camera pose it
        was rendered from: what may hide the other robot (:meth:`_maybe_in_view`)."""
        self.renderer_name = "tiny"
        self._renderer_flag = p.ER_TINY_RENDERER
        self.egl_shadow_map = False
        """True when the EGL plugin still runs its shadow-map pass (:mod:`eglshadow` could not
        switch it off on this build): its frames differ from shadow-free EGL frames."""
        if renderer in ("auto", "egl"):
            self._try_egl(required=renderer == "egl")
        self._build_world()
        if robots is None:
            robots = tuple(
                SimRobot(contract.RobotFrames.usar(r.name), r.x, r.y, r.yaw)
                for r in (scenario.explorer, scenario.follower)
            )
        self.robots = {r.frames.robot: self._add_robot(r.frames, r.x, r.y, r.yaw) for r in robots}
        self.camera_robot = camera_robot
        self.base_tf = base_tf
        self.static_frames = static_frames
        fx, fy, cx, cy = camera_intrinsics(cam.width, cam.height, cam.hfov)
        self._intrinsics = (fx, fy, cx, cy)
        fov_v = 2.0 * math.degrees(math.atan((cam.height / 2.0) / fy))
        self._projection = p.computeProjectionMatrixFOV(
            fov=fov_v,
            aspect=cam.width / cam.height,
            nearVal=NEAR_PLANE,
            farVal=FAR_PLANE,
            physicsClientId=self._client,
        )

    # -- lifecycle ---------------------------------------------------------------------------

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Disconnect this simulator's pybullet client and remove its generated assets."""
        if self._client >= 0:
            with _quiet_stdout():
                p.disconnect(physicsClientId=self._client)
            self._client = -1
            self._tmp.cleanup()

    def _try_egl(self, *, required: bool) -> None:
        loader = pkgutil.get_loader("eglRenderer")
        plugin = -1
        path = ""
        if loader is not None:
            path = loader.get_filename()  # type: ignore[attr-defined]
        if path and egl_loads_safely(path):
            with _quiet_stdout():
                plugin = p.loadPlugin(path, "_eglRendererPlugin", physicsClientId=self._client)
        if plugin < 0:
            if required:
                raise RuntimeError("the EGL renderer plugin does not load on this machine")
            return
        self.renderer_name = "egl"
        self._renderer_flag = p.ER_BULLET_HARDWARE_OPENGL
        self.egl_shadow_map = not eglshadow.disable_shadow_map(path)

    # -- building ----------------------------------------------------------------------------

    def _box(
        self,
        half: tuple[float, float, float],
        pos: tuple[float, float, float],
        yaw: float,
        rgba: tuple[float, float, float, float],
        mass: float = 0.0,
    ) -> int:
        c = self._client
        col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=c)
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=c)
        return int(
            p.createMultiBody(
                baseMass=mass,
                baseCollisionShapeIndex=col,
                baseVisualShapeIndex=vis,
                basePosition=pos,
                baseOrientation=_quat_yaw(yaw),
                physicsClientId=c,
            )
        )

    def _build_world(self) -> None:
        c = self._client
        scn = self.scenario
        xs = [w.x for w in scn.walls] or [0.0]
        ys = [w.y for w in scn.walls] or [0.0]
        cx, cy = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
        span = max(max(xs) - min(xs), max(ys) - min(ys)) / 2 + 2.0
        floor_vis = p.createVisualShape(
            p.GEOM_BOX, halfExtents=(span, span, 0.005), rgbaColor=FLOOR_RGBA, physicsClientId=c
        )
        p.createMultiBody(
            baseMass=0,
            baseVisualShapeIndex=floor_vis,
            basePosition=(cx, cy, -0.005),
            physicsClientId=c,
        )
        for b in (*scn.walls, *scn.boxes):
            rgba = WALL_RGBA if b in scn.walls else OBSTACLE_RGBA
            self._static_bodies.append(
                self._box((b.size_x / 2, b.size_y / 2, b.size_z / 2), (b.x, b.y, b.z), b.yaw, rgba)
            )
        for cyl in scn.cylinders:
            col = p.createCollisionShape(
                p.GEOM_CYLINDER, radius=cyl.radius, height=cyl.height, physicsClientId=c
            )
            vis = p.createVisualShape(
                p.GEOM_CYLINDER,
                radius=cyl.radius,
                length=cyl.height,
                rgbaColor=OBSTACLE_RGBA,
                physicsClientId=c,
            )
            self._static_bodies.append(
                p.createMultiBody(
                    baseMass=0,
                    baseCollisionShapeIndex=col,
                    baseVisualShapeIndex=vis,
                    basePosition=(cyl.x, cyl.y, cyl.height / 2),
                    physicsClientId=c,
                )
            )
        for s in scn.spheres:
            col = p.createCollisionShape(p.GEOM_SPHERE, radius=s.radius, physicsClientId=c)
            vis = p.createVisualShape(
                p.GEOM_SPHERE, radius=s.radius, rgbaColor=OBSTACLE_RGBA, physicsClientId=c
            )
            self._static_bodies.append(
                p.createMultiBody(
                    baseMass=0,
                    baseCollisionShapeIndex=col,
                    baseVisualShapeIndex=vis,
                    basePosition=(s.x, s.y, s.radius),
                    physicsClientId=c,
                )
            )
        for m in scn.markers:
            self._add_marker(m.id, m.x, m.y, m.z, m.yaw, m.size, m.dictionary)

    def _add_marker(
        self, mid: int, x: float, y: float, z: float, yaw: float, size: float, dictionary: str
    ) -> None:
        """A quad in the marker's y-z plane facing +x, textured with the marker's image.

        Seen from the front (looking along -x), +y is to the viewer's right and +z up, so the
        image's left-to-right runs along +y and its top-to-bottom along -z.
        """
        c = self._client
        aruco = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
        bits = aruco.markerSize + 2
        img = cv2.aruco.generateImageMarker(aruco, mid, bits * 20)
        tex_path = Path(self._tmp.name) / f"marker_{mid}.png"
        cv2.imwrite(str(tex_path), cv2.cvtColor(img, cv2.COLOR_GRAY2RGB))
        h = size / 2
        obj = Path(self._tmp.name) / f"marker_{mid}.obj"
        obj.write_text(
            f"v 0 -{h} -{h}\nv 0 {h} -{h}\nv 0 {h} {h}\nv 0 -{h} {h}\n"
            + "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 1 0 0\n"
            + "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
        )
        vis = p.createVisualShape(
            p.GEOM_MESH,
            fileName=str(obj),
            meshScale=(1, 1, 1),
            rgbaColor=(1, 1, 1, 1),
            physicsClientId=c,
        )
        body = p.createMultiBody(
            baseMass=0,
            baseVisualShapeIndex=vis,
            basePosition=(x, y, z),
            baseOrientation=_quat_yaw(yaw),
            physicsClientId=c,
        )
        tex = p.loadTexture(str(tex_path), physicsClientId=c)
        p.changeVisualShape(
            body, -1, textureUniqueId=tex, rgbaColor=(1, 1, 1, 1), physicsClientId=c
        )

    def _add_robot(
        self, frames: contract.RobotFrames, x: float, y: float, yaw: float
    ) -> _RobotState:
        c = self._client
        xs = [q[0] for q in FOOTPRINT]
        ys = [q[1] for q in FOOTPRINT]
        half = ((max(xs) - min(xs)) / 2, (max(ys) - min(ys)) / 2, 0.05)
        off = ((max(xs) + min(xs)) / 2, 0.0, 0.065)
        col = p.createCollisionShape(
            p.GEOM_BOX, halfExtents=half, collisionFramePosition=off, physicsClientId=c
        )
        vis = p.createVisualShape(
            p.GEOM_BOX,
            halfExtents=ROBOT_VISUAL_HALF,
            visualFramePosition=ROBOT_VISUAL_OFFSET,
            rgbaColor=ROBOT_RGBA,
            physicsClientId=c,
        )
        body = p.createMultiBody(
            baseMass=1.8,
            baseCollisionShapeIndex=col,
            baseVisualShapeIndex=vis,
            basePosition=(x, y, 0.0),
            baseOrientation=_quat_yaw(yaw),
            physicsClientId=c,
        )
        return _RobotState(name=frames.robot, frames=frames, body=body, x=x, y=y, yaw=yaw)

    # -- driving -----------------------------------------------------------------------------

    def set_cmd_vel(self, robot: str, twist: msgs.Twist) -> None:
        """The robot's velocity command; clamped to the limits when applied."""
        r = self.robots[robot]
        lim = self.limits
        r.cmd_v = float(np.clip(twist.linear.x, -lim.max_linear, lim.max_linear))
        r.cmd_w = float(np.clip(twist.angular.z, -lim.max_angular, lim.max_angular))

    def teleport(self, robot: str, x: float, y: float, yaw: float) -> None:
        """Place a robot (tests and tools only; the mission never calls this)."""
        r = self.robots[robot]
        r.x, r.y, r.yaw, r.v, r.w = x, y, yaw, 0.0, 0.0
        self._place(r)

    def _place(self, r: _RobotState) -> None:
        p.resetBasePositionAndOrientation(
            r.body, (r.x, r.y, 0.0), _quat_yaw(r.yaw), physicsClientId=self._client
        )

    def _blocked(self, r: _RobotState) -> bool:
        c = self._client
        p.performCollisionDetection(physicsClientId=c)
        contacts = p.getContactPoints(bodyA=r.body, physicsClientId=c)
        return any(cp[8] < -1e-6 for cp in contacts)  # cp[8]: signed distance, < 0 overlaps

    def step(self, n: int = 1) -> None:
        """Advance ``n`` fixed physics steps."""
        dt = self.dt_ns / 1e9
        lim = self.limits
        for _ in range(n):
            for r in self.robots.values():
                dv = np.clip(r.cmd_v - r.v, -lim.max_linear_accel * dt, lim.max_linear_accel * dt)
                dw = np.clip(r.cmd_w - r.w, -lim.max_angular_accel * dt, lim.max_angular_accel * dt)
                v, w = r.v + float(dv), r.w + float(dw)
                if v == 0.0 and w == 0.0:
                    r.v, r.w = 0.0, 0.0
                    continue
                old = (r.x, r.y, r.yaw)
                yaw_mid = r.yaw + w * dt / 2.0
                r.x += v * dt * math.cos(yaw_mid)
                r.y += v * dt * math.sin(yaw_mid)
                r.yaw = math.atan2(math.sin(r.yaw + w * dt), math.cos(r.yaw + w * dt))
                self._place(r)
                if self._blocked(r):
                    r.x, r.y, r.yaw = old
                    self._place(r)
                    r.v, r.w = 0.0, 0.0
                    r.refused += 1
                else:
                    r.v, r.w = v, w
            self.now_ns += self.dt_ns

    def refused_motions(self, robot: str) -> int:
        """How many steps of this robot's motion were refused because they would collide."""
        return self.robots[robot].refused

    # -- what the robots report --------------------------------------------------------------

    def true_pose(self, robot: str) -> msgs.Pose:
        """The robot's base_footprint in map (ground truth)."""
        r = self.robots[robot]
        return msgs.Pose(position=msgs.Point(x=r.x, y=r.y), orientation=_msg_quat(_quat_yaw(r.yaw)))

    def _odom_pose(self, r: _RobotState) -> tuple[float, float, float]:
        """The pose odometry reports: the true world pose (gazebo_ros_diff_drive's ``world``
        source; the module's docstring says why)."""
        return (r.x, r.y, r.yaw)

    def odometry(self, robot: str) -> msgs.Odometry:
        """Odometry in the robot's odom frame, which is ``map`` (world-source odometry; exact:
        the kinematic model has no slip)."""
        r = self.robots[robot]
        x, y, yaw = self._odom_pose(r)
        return msgs.Odometry(
            header=msgs.Header(stamp=msgs.Time.from_ns(self.now_ns), frame_id=r.frames.odom),
            child_frame_id=r.frames.base,
            pose=msgs.PoseWithCovariance(
                pose=msgs.Pose(position=msgs.Point(x=x, y=y), orientation=_msg_quat(_quat_yaw(yaw)))
            ),
            twist=msgs.TwistWithCovariance(
                twist=msgs.Twist(linear=msgs.Vector3(x=r.v), angular=msgs.Vector3(z=r.w))
            ),
        )

    def tf_static(self) -> msgs.TFMessage:
        """``map -> <odom>`` (the identity: odometry is world-source), the camera mounts and
        the extra static frames, for ``/tf_static``."""
        t = self.now_ns
        out = []
        for r in self.robots.values():
            f = r.frames
            out.append(_tf(contract.MAP, f.odom, t, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)))
            out.append(_tf(f.base, f.camera, t, CAMERA_MOUNT, (0.0, 0.0, 0.0, 1.0)))
            out.append(
                _tf(
                    f.camera,
                    f.optical,
                    t,
                    (0.0, 0.0, 0.0),
                    p.getQuaternionFromEuler(OPTICAL_RPY),
                )
            )
        for parent, child, x, y, yaw in self.static_frames:
            out.append(_tf(parent, child, t, (x, y, 0.0), _quat_yaw(yaw)))
        return msgs.TFMessage(transforms=tuple(out))

    def tf(self) -> msgs.TFMessage:
        """``<odom> -> <base_footprint>`` for every robot, at now (none when ``base_tf`` is
        off: that link is then the mission's to broadcast)."""
        out = []
        for r in self.robots.values() if self.base_tf else ():
            x, y, yaw = self._odom_pose(r)
            out.append(_tf(r.frames.odom, r.frames.base, self.now_ns, (x, y, 0.0), _quat_yaw(yaw)))
        return msgs.TFMessage(transforms=tuple(out))

    # -- camera ------------------------------------------------------------------------------

    def camera_due(self) -> bool:
        """True when the explorer's camera should take a frame at the current sim time."""
        return self.now_ns >= self.next_frame_ns

    def camera_info(self) -> msgs.CameraInfo:
        """CameraInfo matching the rendering exactly (plumb_bob, zero distortion)."""
        cam = self.scenario.camera
        fx, fy, cx, cy = self._intrinsics
        return msgs.CameraInfo(
            header=msgs.Header(
                stamp=msgs.Time.from_ns(self.now_ns),
                frame_id=self.robots[self.camera_robot].frames.optical,
            ),
            height=cam.height,
            width=cam.width,
            distortion_model="plumb_bob",
            d=(0.0, 0.0, 0.0, 0.0, 0.0),
            k=(fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0),
            r=(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            p=(fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0),
        )

    def camera_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """(optical centre, 3x3 rotation of the optical frame) in map, for the camera robot."""
        r = self.robots[self.camera_robot]
        c, s = math.cos(r.yaw), math.sin(r.yaw)
        mx, my, mz = CAMERA_MOUNT
        eye = np.array([r.x + c * mx - s * my, r.y + s * mx + c * my, mz])
        fwd = np.array([c, s, 0.0])
        left = np.array([-s, c, 0.0])
        up = np.array([0.0, 0.0, 1.0])
        rot = np.column_stack([-left, -up, fwd])  # optical x right, y down, z forward
        return eye, rot

    def render_camera(self) -> np.ndarray:
        """Render the explorer's camera now (H, W, 3) uint8 **BGR**, and schedule the next frame.

        The image depends only on the camera's pose and on what is in view: the world is static
        but for the two robots, every lighting argument is passed on each call, and there are no
        shadows. So when the explorer has not moved (its pose bit-identical) and the other robot
        has either not moved or stayed where it cannot add a pixel (wholly outside the view, or
        wholly behind the static scene: :meth:`_hidden`), the previous image *is* the image a
        fresh render gives, and it is returned again (read-only) instead of rendering: the
        parked explorer of the follower phase costs nothing while the follower is out of sight.
        :attr:`frames_rendered` counts the renders that happened.
        """
        key = self._view_key()
        if self._last_frame is not None and self._last_frame[0] == key:
            img = self._last_frame[1]
        else:
            img, depth = self._render()
            self._frame_depth = (key, depth)
            img.setflags(write=False)
            self._last_frame = (key, img)
            self.frames_rendered += 1
            if all(k is None for k in key[1:]):  # nothing but the static world was in view
                self._static_depth = (key[0], depth)
        self.frame_seq += 1
        while self.next_frame_ns <= self.now_ns:
            self.next_frame_ns += self.camera_period_ns
        return img

    def _view_key(self) -> tuple[object, ...]:
        """What the explorer's image depends on: its pose and every robot that may be in view
        (None for one that cannot add a pixel)."""
        me = self.robots[self.camera_robot]
        pose = (me.x, me.y, me.yaw)
        key: list[object] = [pose]
        static = self._static_depth
        depth = static[1] if static is not None and static[0] == pose else None
        for name, r in self.robots.items():
            if name != self.camera_robot:
                seen = self._maybe_in_view(r, depth)
                key.append((name, (r.x, r.y, r.yaw)) if seen else None)
        return tuple(key)

    def _maybe_in_view(self, r: _RobotState, static_depth: np.ndarray | None = None) -> bool:
        """False only when the robot's visual box cannot add a pixel to the explorer's image.

        Conservative on both counts. Outside the view: the usual frustum test (all eight corners
        outside one plane through the optical centre, or all nearer than the near plane); OpenGL
        and TinyRenderer both clip to the frustum. Behind the scene: with ``static_depth``, the
        depth image of this same camera pose rendered with no robot in it, the box is hidden when
        every pixel of its projected bounding rectangle (widened by :data:`CULL_MARGIN_PX`)
        already holds a surface nearer than the box's nearest corner (less
        :data:`OCCLUSION_MARGIN_M`): every fragment of the box then fails the depth test.
        """
        cam = self.scenario.camera
        fx, fy, cx, cy = self._intrinsics
        eye, rot = self.camera_pose()
        c, s = math.cos(r.yaw), math.sin(r.yaw)
        hx, hy, hz = ROBOT_VISUAL_HALF
        ox, oy, oz = ROBOT_VISUAL_OFFSET
        corners = []
        for dx in (-hx, hx):
            for dy in (-hy, hy):
                for dz in (-hz, hz):
                    bx, by = ox + dx, oy + dy
                    corners.append((r.x + c * bx - s * by, r.y + s * bx + c * by, oz + dz))
        pts = (np.array(corners) - eye) @ rot  # rows: corners in the optical frame
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        m = CULL_MARGIN_PX
        outside = (
            z < NEAR_PLANE,
            x * fx + (cx + m) * z < 0.0,  # left of the image
            x * fx - (cam.width - cx + m) * z > 0.0,  # right of it
            y * fy + (cy + m) * z < 0.0,  # above it
            y * fy - (cam.height - cy + m) * z > 0.0,  # below it
        )
        if any(bool(np.all(o)) for o in outside):
            return False
        if static_depth is None or bool(np.any(z < NEAR_PLANE)):
            return True
        u, v = x * fx / z + cx, y * fy / z + cy
        u0 = max(0, math.floor(float(u.min()) - m))
        u1 = min(cam.width, math.ceil(float(u.max()) + m) + 1)
        v0 = max(0, math.floor(float(v.min()) - m))
        v1 = min(cam.height, math.ceil(float(v.max()) + m) + 1)
        if u0 >= u1 or v0 >= v1:
            return False
        nearest = float(z.min()) - OCCLUSION_MARGIN_M
        if nearest <= NEAR_PLANE:
            return True
        # compare in the depth buffer's own units (monotonic in distance): no per-pixel maths
        return float(static_depth[v0:v1, u0:u1].max()) >= _depth_buffer_value(nearest)

    def _render(self) -> tuple[np.ndarray, np.ndarray]:
        """(BGR image, OpenGL depth buffer in [0, 1]: :func:`_depth_buffer_value`) from
        pybullet."""
        cam = self.scenario.camera
        return self._render_with(cam.width, cam.height, self._projection)

    def course_region(self, cam: CourseCamera) -> Region | None:
        """The part of ``cam``'s image where a marker may be detected now (None: nowhere),
        from the camera robot's true pose and the markers (:func:`course_view.region`).

        After :meth:`render_camera`, a marker the frame's depth buffer shows wholly behind
        something nearer (a wall, the other robot; less :data:`OCCLUSION_MARGIN_M`) is not a
        candidate: the course camera sees the scene from the same pose, so it is hidden there
        too. The test is conservative as :meth:`_maybe_in_view`'s: the deepest value in the
        marker's projected box decides."""
        eye, rot = self.camera_pose()
        me = self.robots[self.camera_robot]
        frame, last = self._frame_depth, self._last_frame
        hidden = None
        if (  # only with the depth of a frame of this very pose (render_camera just before)
            frame is not None
            and last is not None
            and frame[0] == last[0]
            and last[0][0] == (me.x, me.y, me.yaw)
        ):
            hidden = functools.partial(self._hidden_marker, frame[1])
        return course_view.region(eye, rot, self.scenario.markers, cam, hidden)

    def _hidden_marker(self, depth: np.ndarray, pts: np.ndarray) -> bool:
        """Whether a marker whose corners are ``pts`` (rows, in the optical frame, all in front)
        is wholly hidden in the frame whose depth buffer is ``depth``."""
        cam = self.scenario.camera
        fx, fy, cx, cy = self._intrinsics
        u = fx * pts[:, 0] / pts[:, 2] + cx
        v = fy * pts[:, 1] / pts[:, 2] + cy
        m = CULL_MARGIN_PX
        u0 = max(0, math.floor(float(u.min()) - m))
        u1 = min(cam.width, math.ceil(float(u.max()) + m) + 1)
        v0 = max(0, math.floor(float(v.min()) - m))
        v1 = min(cam.height, math.ceil(float(v.max()) + m) + 1)
        if u0 >= u1 or v0 >= v1:
            return False  # outside this frame: the region test decides
        nearest = float(pts[:, 2].min()) - OCCLUSION_MARGIN_M
        if nearest <= NEAR_PLANE:
            return False
        return float(depth[v0:v1, u0:u1].max()) < _depth_buffer_value(nearest)

    def render_region(self, cam: CourseCamera, where: Region) -> np.ndarray:
        """The camera robot's view as ``cam`` would see it, only the pixels of ``where``:
        (height, width, 3) uint8 BGR, the same pixels as that window of a full render at
        ``cam``'s size, at a fraction of the cost.

        How: an off-axis frustum (pybullet's ``computeProjectionMatrix``, OpenGL's
        ``glFrustum``) whose sides pass through the window's edges on the near plane, where
        the full image's symmetric frustum has its pixel grid; so each rendered pixel samples
        the scene where the full render's pixel does. Does not advance the camera's clock (the
        frame it goes with is :meth:`render_camera`'s)."""
        key = (self._view_key(), cam, where)
        if self._last_region is not None and self._last_region[0] == key:
            return self._last_region[1]  # nothing moved: the very pixels a render gives
        fx, fy, _, _ = cam.intrinsics()
        right_full = NEAR_PLANE * (cam.width / 2.0) / fx
        top_full = NEAR_PLANE * (cam.height / 2.0) / fy
        left = -right_full + 2.0 * right_full * where.x / cam.width
        right = -right_full + 2.0 * right_full * (where.x + where.width) / cam.width
        top = top_full - 2.0 * top_full * where.y / cam.height
        bottom = top_full - 2.0 * top_full * (where.y + where.height) / cam.height
        projection = p.computeProjectionMatrix(
            left, right, bottom, top, NEAR_PLANE, FAR_PLANE, physicsClientId=self._client
        )
        img = self._render_with(where.width, where.height, projection)[0]
        img.setflags(write=False)
        self._last_region = (key, img)
        self.regions_rendered += 1
        return img

    def _render_with(
        self, width: int, height: int, projection: Any
    ) -> tuple[np.ndarray, np.ndarray]:
        """(BGR image, depth buffer) of the camera robot's view through ``projection``."""
        eye, rot = self.camera_pose()
        target = eye + rot[:, 2]
        up = -rot[:, 1]
        view = p.computeViewMatrix(
            eye.tolist(), target.tolist(), up.tolist(), physicsClientId=self._client
        )
        quiet = _quiet_stdout() if self.renderer_name == "egl" else contextlib.nullcontext()
        with quiet:  # the EGL plugin prints its GL vendor on stdout on some frames
            _, _, rgba, buf, _ = p.getCameraImage(
                width,
                height,
                viewMatrix=view,
                projectionMatrix=projection,
                shadow=0,
                lightDirection=LIGHT_DIRECTION,
                lightColor=(1, 1, 1),
                lightDistance=1000.0,
                lightAmbientCoeff=0.6,
                lightDiffuseCoeff=0.4,
                lightSpecularCoeff=0.0,
                renderer=self._renderer_flag,
                flags=p.ER_NO_SEGMENTATION_MASK,
                physicsClientId=self._client,
            )
        img = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)
        bgr = cv2.cvtColor(img, cv2.COLOR_RGBA2BGR)
        depth = np.asarray(buf, dtype=np.float32).reshape(height, width)
        return bgr, depth

    def marker_poses(self) -> dict[int, msgs.Pose]:
        """Ground-truth marker poses in map (face along +x of each pose)."""
        return {
            m.id: msgs.Pose(
                position=msgs.Point(x=m.x, y=m.y, z=m.z), orientation=_msg_quat(_quat_yaw(m.yaw))
            )
            for m in sorted(self.scenario.markers, key=lambda m: m.id)
        }


def pybullet_api_version() -> int:
    """pybullet's API version, for the run's metadata (this module is its only importer)."""
    return int(p.getAPIVersion())
