"""``usar record --ros1 PKG``: record a run whose mission is a ROS 1 catkin package.

The same recording as any other (:func:`usar_replay.pipeline.record.record`: simulator, log,
ground truth, outcomes), with the bridge in the mission process's place. What is checked
before anything runs, each a one-line usage error: ROS 1 is installed (else the ``apt-get``
line), the folder is one catkin package, the launch file or executable exists in it.
"""

from __future__ import annotations

import dataclasses
import functools
import os
from collections.abc import Callable
from pathlib import Path

from usar_replay.core.errors import UsageError
from usar_replay.core.settings import RunSettings
from usar_replay.node.worker import MissionLimits
from usar_replay.pipeline.record import Progress, RecordResult, record
from usar_replay.ros1 import debian
from usar_replay.ros1.build import Package, find_package
from usar_replay.ros1.process import Ros1Options, Ros1Process, ros1_target
from usar_replay.world.scenario import Scenario

__all__ = ["choose_entry", "record_ros1"]


def choose_entry(pkg: Package, options: Ros1Options) -> Ros1Options:
    """Check ``--launch``/``--node`` against the package; with neither, its launch file named
    after the package, or its only launch file."""
    if options.launch and options.node:
        raise UsageError("--launch and --node: give one of them")
    if options.launch:
        name = Path(options.launch).name
        if not any(p.name == name for p in pkg.path.rglob("*.launch")):
            raise UsageError(f"--launch {options.launch}: no such launch file in {pkg.name}")
        return options
    if options.node:
        return options  # an executable exists only once built: a missing one is a crash
    found = sorted(pkg.path.rglob("*.launch"))
    named = [p for p in found if p.stem == pkg.name]
    found = named or found
    if len(found) != 1:
        raise UsageError(
            f"--ros1 {pkg.path}: {len(found)} launch files; say which with --launch FILE "
            "or --node EXECUTABLE"
        )
    return dataclasses.replace(options, launch=found[0].name)


def record_ros1(
    scenario: Scenario,
    out: str | os.PathLike[str],
    package: str | os.PathLike[str],
    settings: RunSettings | None = None,
    progress: Callable[[Progress], None] | None = None,
    *,
    options: Ros1Options | None = None,
    limits: MissionLimits | None = None,
) -> RecordResult:
    """Build ``package`` and record it on ``scenario`` into ``out`` (see the module doc)."""
    debian.check()
    pkg = find_package(package)
    opts = choose_entry(pkg, options or Ros1Options())
    return record(
        scenario,
        out,
        settings,
        progress,
        limits=limits,
        target=ros1_target(pkg, opts),
        process=functools.partial(Ros1Process, package=pkg, options=opts),
    )
