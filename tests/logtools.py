"""Test helpers that build and edit logs: digests, edited copies, synthetic runs."""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path

from usar_replay.core import msgs
from usar_replay.core.contract import SCENARIO_ATTACHMENT
from usar_replay.log import bag
from usar_replay.world.scenario import Scenario
from usar_replay.world.scenario_toml import to_toml


def digest(path: Path) -> str:
    """sha256 over every message's topic, log time and CDR bytes, in log order."""
    h = hashlib.sha256()
    for m in bag.BagReader(path).messages(decode_messages=False):
        h.update(m.topic.encode() + m.log_time_ns.to_bytes(8, "little") + m.data)
    return h.hexdigest()


Edit = Callable[[bag.BagMessage], msgs.Message | bool | None]


def rewrite(
    src: Path,
    dst: Path,
    edit: Edit | None = None,
    *,
    scenario: Scenario | None = None,
    keep_scenario: bool = True,
    retime: Callable[[int], int] | None = None,
) -> None:
    """Copy a log; ``edit`` returns a replacement message, False to drop it, None to keep it.

    ``scenario`` replaces the attached scenario (``keep_scenario=False`` drops it); ``retime``
    maps each log time to a new one (it must keep them in order).
    """
    reader = bag.BagReader(src)
    with bag.BagWriter(dst) as w:
        for name, data in reader.attachments.items():
            if name == SCENARIO_ATTACHMENT:
                if not keep_scenario:
                    continue
                if scenario is not None:
                    data = to_toml(scenario).encode()
            w.add_attachment(name, "application/toml", data, reader.start_ns)
        w.add_metadata(bag.RUN_METADATA, reader.metadata.get(bag.RUN_METADATA, {}))
        for m in reader.messages(decode_messages=edit is not None):
            out = None if edit is None else edit(m)
            if out is False:
                continue
            t = m.log_time_ns if retime is None else retime(m.log_time_ns)
            who = m.publisher or "sim"
            if isinstance(out, msgs.Message):
                w.write(m.topic, out, t, publisher=who)
            else:
                w.write_raw(m.topic, m.msgtype, m.data, t, publisher=who)


def truncate_at(src: Path, dst: Path, min_time_ns: int) -> int:
    """Cut ``src``'s bytes (a killed recorder) at the first length, in steps of 1/64 of the file,
    whose readable part reaches ``min_time_ns``; returns the last log time still readable."""
    data = src.read_bytes()
    for k in range(1, 64):
        dst.write_bytes(data[: len(data) * k // 64])
        reader = bag.BagReader(dst)
        if reader.damage is not None and reader.damage.last_time_ns >= min_time_ns:
            return reader.damage.last_time_ns
    raise AssertionError("no cut of the file reaches that time")


class Synthetic:
    """A hand-made log of ground truth and mission outputs, for grader tests."""

    def __init__(self, path: Path, scenario: Scenario) -> None:
        self.w = bag.BagWriter(path)
        self.w.add_attachment(
            SCENARIO_ATTACHMENT, "application/toml", to_toml(scenario).encode(), 1
        )
        self.t = 1_000_000_000

    def pose(self, robot: str, x: float, y: float) -> None:
        self.w.write(
            f"/ground_truth/{robot}/pose",
            msgs.PoseStamped(
                header=msgs.Header(stamp=msgs.Time.from_ns(self.t), frame_id="map"),
                pose=msgs.Pose(position=msgs.Point(x=x, y=y)),
            ),
            self.t,
            publisher="recorder",
        )

    def write(self, topic: str, msg: msgs.Message, publisher: str = "mission") -> None:
        self.w.write(topic, msg, self.t, publisher=publisher)

    def advance(self, seconds: float) -> None:
        self.t += int(seconds * 1e9)

    def close(self) -> None:
        self.w.close()


OPTICAL_FRAME = "explorer_tf/camera_rgb_optical_frame"
Waypoint = int | tuple[float, float]
"""A stop (target number k = 1..N for the explorer, a marker ID for the follower) or a point
driven through without stopping."""


def _nearest(p: tuple[float, float], options: dict[int, tuple[float, float]]) -> int:
    return min(options, key=lambda k: (p[0] - options[k][0]) ** 2 + (p[1] - options[k][1]) ** 2)


def visit_point(scenario: Scenario, marker_id: int, distance: float = 0.3) -> tuple[float, float]:
    """Where a follower stands to visit a marker: ``distance`` in front of it, toward the target
    it is seen from."""
    m = scenario.marker_by_id(marker_id)
    targets = {i: (float(t[0]), float(t[1])) for i, t in enumerate(scenario.targets)}
    tx, ty = targets[_nearest((m.x, m.y), targets)]
    dx, dy = tx - m.x, ty - m.y
    n = (dx * dx + dy * dy) ** 0.5
    return (m.x + dx / n * distance, m.y + dy / n * distance)


class SyntheticRun(Synthetic):
    """A whole mission made of straight drives, for grader tests that need several markers.

    The explorer's camera frame is ``map`` itself (a static identity transform), so a detection's
    transform is the marker's map position and a ``marker_frame`` broadcast of it lands exactly on
    the true marker. Both robots' ground truth is written every ``dt``; the simulator's ``/tf``
    carries the explorer's base.
    """

    def __init__(
        self, path: Path, scenario: Scenario, *, speed: float = 2.0, dt: float = 0.1
    ) -> None:
        super().__init__(path, scenario)
        self.scenario = scenario
        self.speed, self.dt = speed, dt
        self.xy = {
            "explorer": (scenario.explorer.x, scenario.explorer.y),
            "follower": (scenario.follower.x, scenario.follower.y),
        }
        self.write(
            "/tf_static",
            msgs.TFMessage(
                transforms=(
                    msgs.TransformStamped(
                        header=msgs.Header(stamp=msgs.Time.from_ns(self.t), frame_id="map"),
                        child_frame_id=OPTICAL_FRAME,
                        transform=msgs.Transform(),
                    ),
                )
            ),
        )
        self.tick()

    def tick(self) -> None:
        """Ground truth of both robots and the simulator's /tf at the current time."""
        for robot, (x, y) in self.xy.items():
            self.pose(robot, x, y)
        x, y = self.xy["explorer"]
        self.write(
            "/tf",
            msgs.TFMessage(
                transforms=(
                    msgs.TransformStamped(
                        header=msgs.Header(stamp=msgs.Time.from_ns(self.t), frame_id="map"),
                        child_frame_id="explorer_tf/base_footprint",
                        transform=msgs.Transform(translation=msgs.Vector3(x=x, y=y)),
                    ),
                )
            ),
        )

    def step(self) -> None:
        self.advance(self.dt)
        self.tick()

    def drive(self, robot: str, to: tuple[float, float]) -> None:
        """Straight to ``to`` at ``speed``, landing exactly on it."""
        x0, y0 = self.xy[robot]
        dist = ((to[0] - x0) ** 2 + (to[1] - y0) ** 2) ** 0.5
        n = max(1, int(dist / (self.speed * self.dt) + 0.999))
        for i in range(1, n + 1):
            self.xy[robot] = (x0 + (to[0] - x0) * i / n, y0 + (to[1] - y0) * i / n)
            self.step()

    def wait(self, seconds: float) -> None:
        for _ in range(max(1, round(seconds / self.dt))):
            self.step()

    def detect(self, marker_ids: list[int], *, broadcast: bool = True) -> None:
        """One camera frame seeing these markers, each broadcast as marker_frame."""
        stamp = msgs.Time.from_ns(self.t)
        found = tuple(
            msgs.FiducialTransform(
                fiducial_id=mid,
                transform=msgs.Transform(
                    translation=msgs.Vector3(
                        x=self.scenario.marker_by_id(mid).x,
                        y=self.scenario.marker_by_id(mid).y,
                        z=self.scenario.marker_by_id(mid).z,
                    )
                ),
            )
            for mid in sorted(marker_ids)
        )
        self.write(  # the course's detector, run by the recorder: the world's ("sim")
            "/fiducial_transforms",
            msgs.FiducialTransformArray(
                header=msgs.Header(stamp=stamp, frame_id=OPTICAL_FRAME), transforms=found
            ),
            publisher="sim",
        )
        if broadcast:
            for f in found:
                self.write(
                    "/tf",
                    msgs.TFMessage(
                        transforms=(
                            msgs.TransformStamped(
                                header=msgs.Header(stamp=stamp, frame_id=OPTICAL_FRAME),
                                child_frame_id="marker_frame",
                                transform=f.transform,
                            ),
                        )
                    ),
                )


FOLLOWER_HOME_VIA = (-1.0, 2.5)
"""In the course world, a straight line from marker 3 home passes marker 1: go round it."""


def synthetic_mission(
    path: Path,
    scenario: Scenario,
    *,
    explorer_route: list[Waypoint] | None = None,
    explorer_returns: bool = True,
    follower_route: list[Waypoint] | None = None,
    follower_wiggle_after_stop: int | None = None,
    broadcast: bool = True,
) -> None:
    """A mission that passes every rubric line by default; the arguments make it faulty.

    The explorer stops at each target number in ``explorer_route`` and detects the marker
    nearest that target (markers of targets it never stops at are seen from its last stop, so a
    skipped target does not also lose a detection); then it drives home unless told not to.
    Then the follower visits the marker IDs in ``follower_route`` and drives home.
    ``follower_wiggle_after_stop``: the follower moves 0.3 m and back after that explorer stop.
    """
    n_targets = len(scenario.targets)
    route = explorer_route if explorer_route is not None else list(range(1, n_targets + 1))
    markers_xy = {m.id: (m.x, m.y) for m in scenario.markers}
    seen_from = {k: _nearest(t, markers_xy) for k, t in enumerate(scenario.targets, start=1)}
    stops = [w for w in route if isinstance(w, int)]
    unseen = [seen_from[k] for k in sorted(seen_from) if k not in stops]
    last_stop = max(i for i, w in enumerate(route) if isinstance(w, int))
    stop_number = 0
    run = SyntheticRun(path, scenario)
    for i, w in enumerate(route):
        if isinstance(w, tuple):
            run.drive("explorer", w)
            continue
        t = scenario.targets[w - 1]
        run.drive("explorer", (float(t[0]), float(t[1])))
        stop_number += 1
        ids = [seen_from[w]] + (unseen if i == last_stop else [])
        for mid in sorted(set(ids)):  # one marker per frame, as the mission broadcasts
            run.wait(0.5)
            run.detect([mid], broadcast=broadcast)
        run.wait(0.5)
        if follower_wiggle_after_stop == stop_number:
            x, y = run.xy["follower"]
            run.drive("follower", (x + 0.3, y))
            run.drive("follower", (x, y))
    if explorer_returns:
        run.drive("explorer", (scenario.explorer.x, scenario.explorer.y))
    run.wait(1.0)
    froute = follower_route
    if froute is None:
        froute = [*sorted(markers_xy), FOLLOWER_HOME_VIA]
    for w in froute:
        run.drive("follower", visit_point(scenario, w) if isinstance(w, int) else w)
        if isinstance(w, int):
            run.wait(0.5)
    run.drive("follower", (scenario.follower.x, scenario.follower.y))
    run.wait(1.0)
    run.close()
