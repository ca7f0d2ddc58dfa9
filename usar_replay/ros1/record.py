"""``usar record --ros1 PKG``: record a run whose mission is a ROS 1 catkin package.

The same recording as any other (:func:`usar_replay.pipeline.record.record`: simulator, log,
ground truth, outcomes), with the bridge in the mission process's place. What is checked
before anything runs, each a one-line usage error: ROS 1 is installed (else the ``apt-get``
line), the folder is one catkin package, the launch file or executable exists in it.

The package is built before the recording starts (so the run's wall time and real-time factor
are the run's alone, and the build's time is reported apart: :attr:`RecordResult.build`); a
build that fails is still a log, whose outcome is ``build_failed``. catkin_make's output comes
back with the result (:attr:`RecordResult.build_log`), for ``usar batch --code``.
"""

from __future__ import annotations

import dataclasses
import functools
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from usar_replay.core import team_parse
from usar_replay.core.errors import UnclearStart
from usar_replay.core.settings import RunSettings
from usar_replay.pipeline.record import BuildLog, Progress, RecordResult, record, with_latency
from usar_replay.process.mission_process import MissionEnded, MissionLimits, uses_kernel_sandbox
from usar_replay.process.mission_target import MissionTarget
from usar_replay.ros1 import start
from usar_replay.ros1.building import debian
from usar_replay.ros1.building.workspace import (
    BuildFailed,
    Built,
    Package,
    cached_build,
    find_package,
    private_build,
    remove_tree,
)
from usar_replay.ros1.process import Ros1Options, Ros1Process, build_limits_for, ros1_target
from usar_replay.ros1.starts_file import InstructorStart
from usar_replay.world.scenario import Scenario

__all__ = ["choose_entry", "record_ros1"]


def choose_entry(
    pkg: Package,
    options: Ros1Options,
    team_dir: Path | None = None,
    instructor: InstructorStart | None = None,
) -> Ros1Options:
    """The start of the package (:func:`usar_replay.ros1.start.decide`: ``--launch``/``--node``,
    else the instructor's starts file's table for the team, the team's ``usar.toml``,
    instructions, README, the package's shape), with where it was read;
    :class:`~usar_replay.core.errors.UnclearStart` (a usage error, one line) when nothing
    decides it. ``team_dir``: the folder handed in (a repository around the package)."""
    # every file catkin, roslaunch or usar parses, bounded before any reads it (one line)
    team_parse.check_package(team_dir or pkg.path)
    chosen = start.decide(
        pkg.path,
        pkg.name,
        launch=options.launch,
        node=options.node,
        team_dir=team_dir,
        after_launch=tuple(options.after_launch),
        instructor=instructor,
    )
    return dataclasses.replace(
        options,
        launch=chosen.launch,
        node=chosen.node,
        after_launch=chosen.after_launch,
        start_source=chosen.source,
    )


def _as_built(
    pkg: Package, opts: Ros1Options, built: Built, target: MissionTarget
) -> tuple[Ros1Options, MissionTarget]:
    """``opts`` and the log's target with the executable the build made
    (:func:`usar_replay.ros1.start.as_built`)."""
    chosen = start.as_built(
        opts.node, opts.start_source, pkg.path, built.workspace / "devel", pkg.name
    )
    if chosen.node == opts.node:
        return opts, target
    opts = dataclasses.replace(opts, node=chosen.node, start_source=chosen.source)
    return opts, dataclasses.replace(ros1_target(pkg, opts, hashed=False), sha256=target.sha256)


def record_ros1(
    scenario: Scenario,
    out: str | os.PathLike[str],
    package: str | os.PathLike[str],
    settings: RunSettings | None = None,
    progress: Callable[[Progress], None] | None = None,
    *,
    options: Ros1Options | None = None,
    limits: MissionLimits | None = None,
    instructor: InstructorStart | None = None,
) -> RecordResult:
    """Build ``package`` and record it on ``scenario`` into ``out`` (see the module doc);
    ``instructor``: the team's table of the instructor's starts file (``usar batch
    --starts``)."""
    debian.check()
    pkg = find_package(package)
    given = Path(package)
    team_dir = given if given.is_dir() else None
    opts = choose_entry(pkg, options or Ros1Options(), team_dir, instructor)
    build_limits = build_limits_for(limits or MissionLimits())
    fixed = uses_kernel_sandbox(limits or MissionLimits())  # built where the run will see it
    holder: Path | None = None
    process: Callable[..., Any]
    made: list[Ros1Process] = []  # the run's process, for its pacing counts
    target = ros1_target(pkg, opts, hashed=False)
    try:
        target = ros1_target(pkg, opts)  # hashes the package: a folder it refuses is the verdict
        built: Built
        if opts.cache:
            built = cached_build(pkg, limits=build_limits, fixed=fixed)
        else:  # a folder of its own, never inside the run's (which the run may write)
            built, holder = private_build(pkg, limits=build_limits, fixed=fixed)

        try:  # the start's executable as built (issue 51): a fallback said so, or one line
            opts, target = _as_built(pkg, opts, built, target)
        except UnclearStart:
            if holder is not None:
                remove_tree(holder)
            raise

        def process(*args: Any, **kwargs: Any) -> Ros1Process:
            made.append(Ros1Process(*args, package=pkg, options=opts, built=built, **kwargs))
            return made[-1]

        note = "cached" if built.cached else f"catkin_make {built.seconds:.1f} s"
        log = BuildLog(built.output, built.source_root, False, built.flags)
    except MissionEnded as failed:
        process = functools.partial(_failed_build, failed)
        note = "failed"
        log = None
        if isinstance(failed, BuildFailed):
            log = BuildLog(failed.output, failed.root, True, failed.flags)
    try:
        result = record(
            scenario,
            out,
            with_latency(settings or RunSettings(), 1),  # the graph thinks while the world moves
            progress,
            limits=limits,
            target=target,
            process=process,
        )
    finally:
        if holder is not None and not opts.keep_workspace:
            remove_tree(holder)
    pacing = f"{made[0].holds} shutdown holds, {made[0].capped} capped ticks" if made else ""
    if made and made[0].capped:
        # a capped tick ended at its wall cap, not when the graph was done: where the graph's
        # reaction landed is this machine's pace, so another machine may log it a tick apart
        rtf = (limits or MissionLimits()).rtf
        pacing += f" (this machine's pace may show in the log: a lower --rtf than {rtf:g} widens"
        pacing += " the cap)"
    return dataclasses.replace(result, build=note, pacing=pacing, build_log=log)


def _failed_build(failed: MissionEnded, *_args: Any, **_kwargs: Any) -> Any:
    """The mission process of a package that did not build: the run ends as its verdict."""
    raise failed
