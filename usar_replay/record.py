"""`usar record`: run the mission live in pybullet and write everything to one MCAP file.

The loop is the design's data flow, sim -> messages -> mission -> messages -> sim, on the sim
clock only. At each control tick (``control_hz``) the simulator's outputs (``/tf``, odometry, a
camera frame when one is due, ground truth) are written to the log **and** handed to the mission
in the same order; whatever the mission publishes is written at the same sim time, and its
``cmd_vel``s go back to the simulator. Because the mission sees exactly the logged messages (the
camera frame is encoded first and the mission detects on those bytes), a replay from the log
reproduces its outputs bit for bit.
"""

from __future__ import annotations

import dataclasses
import math
import os
import platform
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from usar_replay import __version__, bag, msgs
from usar_replay.detect import encode_image
from usar_replay.info import SCENARIO_ATTACHMENT
from usar_replay.mission import CAMERA_INFO_TOPIC, IMAGE_TOPIC, Mission, MissionSettings, Phase
from usar_replay.nav import OccupancyGrid
from usar_replay.scenario import Scenario, to_toml
from usar_replay.sim import Simulator

__all__ = [
    "GROUND_TRUTH_MARKERS",
    "Progress",
    "RecordResult",
    "RecordSettings",
    "default_output",
    "record",
]

GROUND_TRUTH_MARKERS = "/ground_truth/markers"
START_TIME_NS = 1_000_000_000


@dataclass(frozen=True, slots=True, kw_only=True)
class RecordSettings:
    """How a run is recorded (the scenario says what world; this says how it is simulated)."""

    physics_hz: int = 100
    control_hz: int = 20
    max_sim_time_s: float | None = None
    """Hard stop; default 1.5 x the scenario's time limit (a run past the limit fails grading)."""
    renderer: str = "auto"
    mission: MissionSettings = dataclasses.field(default_factory=MissionSettings)


@dataclass(frozen=True, slots=True)
class Progress:
    """What the progress display shows after each control tick."""

    sim_time_s: float
    phase: Phase
    markers_found: int
    markers_total: int
    frames: int


@dataclass(frozen=True, slots=True)
class RecordResult:
    """What a recording produced, for the end-of-run summary."""

    path: Path
    status: str
    sim_duration_s: float
    wall_time_s: float
    frames: int
    messages: int
    markers_found: dict[int, tuple[float, float, float]]
    marker_errors_m: dict[int, float]
    mission_done: bool
    renderer: str

    @property
    def real_time_factor(self) -> float:
        return self.sim_duration_s / self.wall_time_s if self.wall_time_s > 0 else math.inf

    @property
    def size_bytes(self) -> int:
        return self.path.stat().st_size if self.path.exists() else 0


def default_output(scenario: Scenario, directory: str | os.PathLike[str] = "recordings") -> Path:
    """``recordings/<scenario>[-seed<N>].mcap``: a name that says what was run, not when."""
    stem = scenario.name + (f"-seed{scenario.seed}" if scenario.seed is not None else "")
    return Path(directory) / f"{stem}.mcap"


def _run_metadata(scenario: Scenario, settings: RecordSettings, renderer: str) -> dict[str, str]:
    import cv2
    import pybullet

    return {
        "software": f"usar-replay {__version__}",
        "python": platform.python_version(),
        "opencv": cv2.__version__,
        "pybullet_api": str(pybullet.getAPIVersion()),
        "renderer": renderer,
        "scenario": scenario.name,
        "seed": "" if scenario.seed is None else str(scenario.seed),
        "camera": f"{scenario.camera.width}x{scenario.camera.height}@{scenario.camera.rate_hz:g}",
        "camera_encoding": scenario.camera.encoding,
        "physics_hz": str(settings.physics_hz),
        "control_hz": str(settings.control_hz),
        "start_time_ns": str(START_TIME_NS),
        "mission_settings": repr(settings.mission),
    }


def _truth_markers(scenario: Scenario, t_ns: int) -> msgs.FiducialTransformArray:
    items = []
    for m in sorted(scenario.markers, key=lambda m: m.id):
        items.append(
            msgs.FiducialTransform(
                fiducial_id=m.id,
                transform=msgs.Transform(
                    translation=msgs.Vector3(x=m.x, y=m.y, z=m.z),
                    rotation=msgs.Quaternion(z=math.sin(m.yaw / 2), w=math.cos(m.yaw / 2)),
                ),
            )
        )
    return msgs.FiducialTransformArray(
        header=msgs.Header(stamp=msgs.Time.from_ns(t_ns), frame_id="map"), transforms=tuple(items)
    )


def record(
    scenario: Scenario,
    out: str | os.PathLike[str],
    settings: RecordSettings | None = None,
    progress: Callable[[Progress], None] | None = None,
) -> RecordResult:
    """Run the mission on ``scenario`` and write the log to ``out``.

    Ctrl-C (KeyboardInterrupt) stops the run: the file is closed, indexed and marked
    ``interrupted``, and the interrupt propagates to the caller after the file is safe.
    """
    settings = settings or RecordSettings()
    wall_start = time.perf_counter()  # only for the real-time factor shown to people
    limit_s = settings.max_sim_time_s or scenario.time_limit_s * 1.5
    grid = OccupancyGrid.from_scenario(scenario)
    mission = Mission(scenario, grid, settings.mission)
    frames = 0
    with (
        Simulator(
            scenario,
            physics_hz=settings.physics_hz,
            start_time_ns=START_TIME_NS,
            renderer=settings.renderer,
        ) as sim,
        bag.BagWriter(out) as writer,
    ):
        renderer = sim.renderer_name
        t0 = sim.now_ns
        writer.add_attachment(
            SCENARIO_ATTACHMENT, "application/toml", to_toml(scenario).encode(), t0
        )
        writer.add_metadata(bag.RUN_METADATA, _run_metadata(scenario, settings, renderer))

        def publish(topic: str, msg: msgs.Message, t_ns: int) -> None:
            writer.write(topic, msg, t_ns)
            for out_topic, out_msg in mission.on_message(topic, msg, t_ns):
                writer.write(out_topic, out_msg, t_ns)
                if out_topic.endswith("/cmd_vel") and isinstance(out_msg, msgs.Twist):
                    sim.set_cmd_vel(out_topic.split("/")[1], out_msg)

        publish("/tf_static", sim.tf_static(), t0)
        writer.write(GROUND_TRUTH_MARKERS, _truth_markers(scenario, t0), t0)
        steps_per_tick = max(1, settings.physics_hz // settings.control_hz)
        end_ns = t0 + int(limit_s * 1e9)
        while not mission.done and sim.now_ns <= end_ns:
            t = sim.now_ns
            publish("/tf", sim.tf(), t)
            if sim.camera_due():
                frame = sim.render_camera()
                info = sim.camera_info()
                data = encode_image(frame, scenario.camera.encoding)
                image = msgs.CompressedImage(
                    header=info.header, format=scenario.camera.encoding, data=data
                )
                publish(CAMERA_INFO_TOPIC, info, t)
                publish(IMAGE_TOPIC, image, t)
                frames += 1
            for robot in ("explorer", "follower"):
                publish(f"/{robot}/odom", sim.odometry(robot), t)
                truth = msgs.PoseStamped(
                    header=msgs.Header(stamp=msgs.Time.from_ns(t), frame_id="map"),
                    pose=sim.true_pose(robot),
                )
                writer.write(f"/ground_truth/{robot}/pose", truth, t)
            if progress is not None:
                progress(
                    Progress(
                        (t - t0) / 1e9,
                        mission.phase,
                        len(mission.markers),
                        len(scenario.markers),
                        frames,
                    )
                )
            sim.step(steps_per_tick)
        status = "complete"
        if not mission.done:
            writer.write(
                "/rosout",
                msgs.Log(
                    stamp=msgs.Time.from_ns(sim.now_ns),
                    level=msgs.Log.ERROR,
                    name="record",
                    msg=f"stopped at the hard limit of {limit_s:.0f} s sim time; mission not done",
                ),
                sim.now_ns,
            )
        sim_duration = (sim.now_ns - t0) / 1e9
        message_count = writer.message_count
    errors = {}
    truth = {m.id: m for m in scenario.markers}
    for mid, (x, y, z, _) in mission.markers.items():
        if mid in truth:
            m = truth[mid]
            errors[mid] = math.dist((x, y, z), (m.x, m.y, m.z))
    return RecordResult(
        path=Path(out),
        status=status,
        sim_duration_s=sim_duration,
        wall_time_s=time.perf_counter() - wall_start,
        frames=frames,
        messages=message_count,
        markers_found={k: v[:3] for k, v in sorted(mission.markers.items())},
        marker_errors_m=errors,
        mission_done=mission.done,
        renderer=renderer,
    )


def print_summary(result: RecordResult, file: TextIO | None = None) -> None:
    """The end-of-run summary for people."""
    lines = [
        f"Recorded {result.path} ({result.size_bytes / 1e6:.1f} MB, {result.messages} messages,"
        f" {result.frames} camera frames, renderer {result.renderer})",
        f"Sim duration {result.sim_duration_s:.1f} s in {result.wall_time_s:.1f} s wall:"
        f" real-time factor {result.real_time_factor:.2f}",
        "Mission " + ("complete" if result.mission_done else "NOT complete"),
        f"Markers found: {len(result.markers_found)}",
    ]
    for mid, pos in result.markers_found.items():
        err = result.marker_errors_m.get(mid)
        err_s = f", error {err * 100:.1f} cm" if err is not None else ""
        lines.append(f"  marker {mid}: ({pos[0]:.3f}, {pos[1]:.3f}, {pos[2]:.3f}){err_s}")
    print("\n".join(lines), file=file or sys.stdout)
