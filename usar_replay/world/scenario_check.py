"""`usar scenario --check`: can this world be completed? Geometry first, then the variant rules.

Why: a hand-edited world can parse and still be impossible: a marker buried in a wall, both robots
on one spot, a marker at z = 100 m or 1 nm wide, a camera at 1e-9 Hz. Recording such a world
costs minutes before it fails. These checks simulate what the mission will meet, with the same
numbers it uses (the camera model of :mod:`sim`, the robot of :mod:`contract`, the mission's
default settings), in milliseconds:

* **starts**: each robot stands in free space (it can rotate there) and the two are apart;
* **markers**: each hangs in front of a free face (the space before its face is not inside a
  wall), above the floor;
* **detection**: from each target, its own marker (the nearest) is in line of sight, within the
  mission's ``max_detection_range``, facing the camera, inside the camera's vertical view (the
  camera is 0.117 m above the floor) and at least :data:`MIN_MARKER_PX` pixels tall; while the
  explorer spins, the marker stays in view for enough frames to settle;
* then the variant rules of :func:`usar_replay.world.variants.check_variant` (every goal reachable,
  the routes fit the time limit).

The verdict is printed to stdout as plain lines; the CLI exits 1 when a check fails.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field

from usar_replay.core.contract import WAFFLE
from usar_replay.core.settings import MissionSettings
from usar_replay.world.nav import PlanningGrid
from usar_replay.world.scenario import Marker, Scenario

__all__ = ["MAX_OBLIQUE", "MIN_MARKER_PX", "Verdict", "check"]

MIN_MARKER_PX = 20.0
"""The smallest marker (edge, in pixels) the ArUco detector reads reliably: 6 cells of 3 px and
some margin."""
MAX_OBLIQUE = math.radians(60)
"""The most a marker may be turned away from the camera and still be read."""
WIDTH = 100


@dataclass(slots=True)
class Verdict:
    """The checks' results: (passed, text) in order."""

    name: str
    results: list[tuple[bool, str]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return all(ok for ok, _ in self.results)

    def add(self, ok: bool, text: str) -> None:
        self.results.append((ok, text))

    def lines(self) -> list[str]:
        """The plain verdict, each line within 100 columns."""
        failed = [t for ok, t in self.results if not ok]
        n = len(failed) or len(self.results)
        plural = "" if n == 1 else "s"
        if failed:
            head = f"scenario {self.name}: CANNOT be completed ({n} check{plural} failed)"
        else:
            head = f"scenario {self.name}: can be completed ({n} check{plural} passed)"
        body: list[str] = []
        for ok, text in self.results:
            body += textwrap.wrap(
                text,
                WIDTH,
                initial_indent=f"  {'ok  ' if ok else 'FAIL'}  ",
                subsequent_indent=" " * 10,
            )
        return [head, *body]


def _camera(scn: Scenario) -> tuple[float, float]:
    """(vertical field of view in rad, focal length in px) as the simulator renders them."""
    cam = scn.camera
    fov_v = 2.0 * math.atan(math.tan(cam.hfov / 2.0) * cam.height / cam.width)
    fy = (cam.height / 2.0) / math.tan(fov_v / 2.0)
    return fov_v, fy


def _starts(scn: Scenario, grid: PlanningGrid, v: Verdict) -> None:
    for r in (scn.explorer, scn.follower):
        free = grid.is_free(r.x, r.y)
        v.add(
            free,
            f"{r.name} starts at ({r.x:.2f}, {r.y:.2f})"
            + (" in free space" if free else ": not free space (too close to a wall or obstacle)"),
        )
    apart = math.dist((scn.explorer.x, scn.explorer.y), (scn.follower.x, scn.follower.y))
    need = 2 * WAFFLE.radius
    v.add(
        apart >= need,
        f"the robots start {apart:.2f} m apart" + ("" if apart >= need else f" (need {need} m)"),
    )


def _marker_face(m: Marker, grid: PlanningGrid, v: Verdict) -> None:
    nx, ny = math.cos(m.yaw), math.sin(m.yaw)
    front = [grid.distance_to_obstacle(m.x + nx * d, m.y + ny * d) for d in (0.06, 0.15, 0.3)]
    free = all(d > 0.0 for d in front)
    above = m.z - m.size / 2 >= 0.0
    if not free:
        v.add(False, f"marker {m.id}: its face is inside a wall or obstacle (buried)")
    elif not above:
        v.add(False, f"marker {m.id}: reaches below the floor (z {m.z} m, size {m.size} m)")
    else:
        v.add(True, f"marker {m.id}: in front of a free face, {m.z:.2f} m above the floor")


def _detection(
    scn: Scenario, k: int, target: tuple[float, float], grid: PlanningGrid, v: Verdict
) -> None:
    settings = MissionSettings()
    name = f"target_{k + 1}"
    if not scn.markers:
        v.add(False, f"{name}: there is no marker to look for")
        return
    m = min(scn.markers, key=lambda mk: (math.dist(target, (mk.x, mk.y)), mk.id))
    d = math.dist(target, (m.x, m.y))
    to_target = math.atan2(target[1] - m.y, target[0] - m.x)
    oblique = abs(math.atan2(math.sin(to_target - m.yaw), math.cos(to_target - m.yaw)))
    fov_v, fy = _camera(scn)
    cam_z = WAFFLE.camera_mount[2]
    problems: list[str] = []
    if not grid.is_free(*target):
        problems.append("the target is not free space")
    if d > settings.max_detection_range:
        problems.append(f"{d:.2f} m away, beyond {settings.max_detection_range:g} m")
    if oblique >= MAX_OBLIQUE:
        problems.append(f"it faces {math.degrees(oblique):.0f} deg away from the target")
    if not grid.line_clear(target, (m.x, m.y), skip_end=0.08):
        problems.append("a wall or obstacle is in the way")
    top = math.atan2(m.z + m.size / 2 - cam_z, max(d, 1e-9))
    bottom = math.atan2(m.z - m.size / 2 - cam_z, max(d, 1e-9))
    if top > fov_v / 2 or bottom < -fov_v / 2:
        problems.append(
            f"at z {m.z:g} m it is outside the camera's vertical view from there "
            f"({math.degrees(fov_v):.0f} deg)"
        )
    px = m.size * fy / max(d, 1e-9) * max(math.cos(oblique), 0.0)
    if px < MIN_MARKER_PX:
        problems.append(f"it is {px:.1f} px wide in the image (needs {MIN_MARKER_PX:g})")
    in_view_s = scn.camera.hfov / settings.spin_speed
    frames = in_view_s * scn.camera.rate_hz
    if frames < settings.settle_frames + 2:
        problems.append(
            f"spinning, it is in view for {frames:.1f} frames at {scn.camera.rate_hz:g} Hz "
            f"(needs {settings.settle_frames + 2})"
        )
    if problems:
        v.add(False, f"{name} cannot detect marker {m.id}: " + "; ".join(problems))
    else:
        v.add(
            True,
            f"{name} sees marker {m.id} at {d:.2f} m, {math.degrees(oblique):.0f} deg off its "
            f"normal, {px:.0f} px wide",
        )


def check(scn: Scenario) -> Verdict:
    """Every check on ``scn`` (see the module docstring); the variant rules run only when the
    geometry passes (they plan routes, which needs reachable free space)."""
    from usar_replay.world.variants import MAX_DRIVE_FRACTION, check_variant, drive_time_s

    v = Verdict(scn.name)
    grid = PlanningGrid.from_scenario(scn)
    _starts(scn, grid, v)
    for m in sorted(scn.markers, key=lambda mk: mk.id):
        _marker_face(m, grid, v)
    for k, target in enumerate(scn.targets):
        _detection(scn, k, target, grid, v)
    if not v.ok:
        return v
    problem = check_variant(scn, grid)
    if problem is not None:
        v.add(False, f"variant rules: {problem}")
        return v
    need = drive_time_s(scn, grid)
    allowed = MAX_DRIVE_FRACTION * scn.time_limit_s
    v.add(
        True,
        f"every goal is reachable; driving takes {need:.0f} s of the {allowed:.0f} s allowed "
        f"({MAX_DRIVE_FRACTION:.0%} of {scn.time_limit_s:g} s)",
    )
    return v
