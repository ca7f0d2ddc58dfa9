"""Small worlds for the example missions' tests (each recording a minute of sim time or less)."""

from __future__ import annotations

import dataclasses
import math

from conftest import one_room

from usar_replay.core.settings import DetectorParams, RunSettings
from usar_replay.world.scenario import Box, CameraSettings, Marker, RobotStart, Scenario

MARKER_SIZE = 0.3
"""The corridor's markers: twice the course's, so that 320x240 frames read them 3 m away."""
CORRIDOR_SETTINGS = RunSettings(detector=DetectorParams(marker_size=MARKER_SIZE))
"""The detector must know the markers' size (it gives their distance)."""


def quick_room() -> Scenario:
    """The one-room world with the explorer starting 0.6 m from the lookup target, facing the
    marker: it is found at once, so a run is mostly the follower's part."""
    return dataclasses.replace(
        one_room(),
        name="quick-room",
        explorer=RobotStart(name="explorer", x=0.5, y=0.3),
        time_limit_s=60.0,
    )


def corridor() -> Scenario:
    """A 4 m x 1.6 m corridor with two markers; record it with :data:`CORRIDOR_SETTINGS`.

    Marker 1 is on the north wall by target_1, behind the explorer as it arrives there; marker 0
    is on the east wall by target_2, in view from target_1 2.9 m away (beyond the 2.5 m range
    gate of the minimal mission): the course's far-marker trap in small. The explorer finds
    marker 1 first, so the finding order (1, 0) is not the ID order (0, 1).
    """
    t, h = 0.15, 1.0

    def wall(name: str, x: float, y: float, yaw: float, length: float) -> Box:
        return Box(name=name, x=x, y=y, z=h / 2, size_x=length, size_y=t, size_z=h, yaw=yaw)

    return Scenario(
        name="corridor",
        walls=(
            wall("south", 0.0, -0.875, 0.0, 4.3),
            wall("north", 0.0, 0.875, math.pi, 4.3),
            wall("west", -2.075, 0.0, -math.pi / 2, 1.9),
            wall("east", 2.075, 0.0, math.pi / 2, 1.9),
        ),
        markers=(
            Marker(id=0, x=1.99, y=0.0, z=0.3, yaw=math.pi, size=MARKER_SIZE),
            Marker(id=1, x=-1.3, y=0.79, z=0.3, yaw=-math.pi / 2, size=MARKER_SIZE),
        ),
        targets=((-0.9, 0.0), (1.3, 0.0)),
        explorer=RobotStart(name="explorer", x=-1.65, y=0.15),
        follower=RobotStart(name="follower", x=-1.65, y=-0.5),
        camera=CameraSettings(width=320, height=240, rate_hz=10.0),
        time_limit_s=150.0,
    )
