"""Shared fixtures: a one-room world with one marker, recorded once per test session.

Tests mirror the package (``tests/<layer>/test_<module>.py``; ``e2e/``, ``redteam/``, ``meta/``
beside them) and are imported by pytest's ``importlib`` mode (pyproject.toml), so two folders may
each hold a ``test_grade.py``. That mode puts nothing on ``sys.path``; this folder goes there
here, so the shared helpers (``clitools``, ``catkintools``, ``logtools``, ``example_worlds``,
``msg_strategies`` and this module's ``one_room``) import the same way from every folder.
"""

from __future__ import annotations

import math
import os
import pkgutil
import sys
from collections.abc import Iterator
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import pytest

from usar_replay.core.settings import RunSettings
from usar_replay.pipeline.record import RecordResult, record
from usar_replay.sandbox import cpu_sets
from usar_replay.sim import simulator
from usar_replay.world.scenario import Box, CameraSettings, Marker, RobotStart, Scenario


def pytest_configure(config: pytest.Config) -> None:
    """Under xdist, one CPU per run (:data:`usar_replay.sandbox.cpu_sets.WANT_ENV`); and
    pybullet's EGL renderer probed once per test process and handed to every ``usar``
    subprocess through the environment, as a batch hands it to its runs
    (:func:`usar_replay.sim.simulator.egl_loads_safely`): each of the suite's hundreds of
    records would otherwise start a probe of ~1 s for the same answer. The probe's own tests
    clear it (tests/sim/test_simulator.py)."""
    del config
    if int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")) > 1:
        # each run a CPU of its own, so the workers' runs go side by side: a run that took both
        # CPUs of a 2-CPU machine made the other worker's next run wait for its end
        os.environ.setdefault(cpu_sets.WANT_ENV, "1")
    loader = pkgutil.get_loader("eglRenderer")
    if loader is not None:
        simulator.egl_loads_safely(loader.get_filename())  # type: ignore[attr-defined]


def one_room() -> Scenario:
    """A 4 m x 3 m room, one marker on the east wall, one lookup target in front of it."""
    t, h = 0.15, 1.0

    def wall(name: str, x: float, y: float, yaw: float, length: float) -> Box:
        return Box(name=name, x=x, y=y, z=h / 2, size_x=length, size_y=t, size_z=h, yaw=yaw)

    return Scenario(
        name="one-room",
        walls=(
            wall("south", 0.0, -1.575, 0.0, 4.3),
            wall("north", 0.0, 1.575, math.pi, 4.3),
            wall("west", -2.075, 0.0, -math.pi / 2, 3.0),
            wall("east", 2.075, 0.0, math.pi / 2, 3.0),
        ),
        markers=(Marker(id=0, x=1.99, y=0.4, yaw=math.pi),),
        targets=((1.1, 0.3),),
        explorer=RobotStart(name="explorer", x=-1.2, y=0.6),
        follower=RobotStart(name="follower", x=-1.2, y=-0.9),
        camera=CameraSettings(width=320, height=240, rate_hz=10.0),
        time_limit_s=120.0,
    )


@pytest.fixture(scope="session")
def room_log(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, RecordResult]:
    """The one-room mission, recorded once (about 10-20 s of wall time)."""
    path = tmp_path_factory.mktemp("room") / "room.mcap"
    result = record(one_room(), path, RunSettings())
    return path, result


@pytest.fixture(scope="session")
def _shared_build_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(scope="module")
def module_build_cache(_shared_build_cache: Path) -> Iterator[Path]:
    """The test process's ROS 1 build cache (``XDG_CACHE_HOME``) for the module: usar's underlay
    and each package are built once per test process and reused by every module that asks
    (the cache is keyed by content, so a variant is a build of its own), and no user's cache is
    touched. Tests of the cache itself make one of their own."""
    yield from _cache_home(_shared_build_cache)


@pytest.fixture(scope="module")
def own_build_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A ROS 1 build cache of the module's own (``XDG_CACHE_HOME``), empty at its start: for
    the tests of building and caching, which ask whether a build was made or reused."""
    yield from _cache_home(tmp_path_factory.mktemp("own_cache"))


def _cache_home(home: Path) -> Iterator[Path]:
    """``XDG_CACHE_HOME`` set to ``home`` for a module's tests, put back after them."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("XDG_CACHE_HOME", str(home))
        yield home
