"""``usar replay`` of a ROS 1 log: the recorded package, re-run against the recorded inputs.

Why it can: the bridge's pacing makes a package's run repeatable (docs/ros1.md, "Pacing"), so
feeding the log's ticks to the same package again gives the same outputs, bit for bit, and
the replay compares them as a Python mission's replay does (:mod:`usar_replay.pipeline.replay`:
the first differing message, the rubric delta with ``--grade``). Where a package is not
repeatable (it reads the wall clock, an unseeded ``rand()``), the comparison names the topic
that diverged first and its sim time.

Which package: ``--ros1 PKG`` (``--launch``/``--node`` as for ``usar record``; its sha256
against the recorded one says whether the code changed: a regression run then); without it,
the folder the log names (``mission.toml``: ``ros1:PATH --launch FILE``) only when it is here
and its files hash to the recorded sha256, said on stderr before anything is built. Why so
strict (issue 33): a log is input from anyone, and building a package runs its code, so a log
must not choose which folder of this machine is built and run.
"""

from __future__ import annotations

import dataclasses
import functools
import sys
from collections.abc import Callable
from typing import Any

from usar_replay.core.errors import MissionEnded, UsageError
from usar_replay.core.safe_text import safe_line
from usar_replay.log import ros1_run
from usar_replay.log.run import Run
from usar_replay.process.mission_process import MissionLimits, MissionProcess, uses_kernel_sandbox
from usar_replay.process.mission_target import MissionTarget
from usar_replay.ros1 import nav_params
from usar_replay.ros1.building import debian
from usar_replay.ros1.building.workspace import Package, cached_build, find_package, package_sha256
from usar_replay.ros1.process import Ros1Options, Ros1Process, build_limits_for, ros1_target
from usar_replay.ros1.record import choose_entry

__all__ = ["recorded_entry", "recorded_package", "ros1_process"]


def recorded_entry(target: str) -> tuple[str, str, str]:
    """(package path, launch file, executable) from a log's ``ros1:PATH --launch FILE``
    (``--launch FILE --node EXE`` where both ran)."""
    rest = target.removeprefix("ros1:")
    launch = node = ""
    for flag in (" --node ", " --launch "):  # written launch first: read from the end
        before, found, entry = rest.rpartition(flag)
        if found and " --" not in entry:
            rest = before
            if flag == " --node ":
                node = entry
            else:
                launch = entry
    return rest.strip(), launch, node


def ros1_process(
    run: Run,
    package: str | None = None,
    launch: str | None = None,
    node: str | None = None,
    limits: MissionLimits | None = None,
) -> tuple[MissionTarget, Callable[..., MissionProcess]]:
    """The package to replay (the recorded one, or ``package``), built (from the verified
    cache, under the build's limits, as ``usar record --ros1`` builds it), and a process factory
    for :func:`usar_replay.pipeline.replay.replay`. Usage errors (one line) when it is not
    here; a package that does not build is :class:`MissionEnded` (``build_failed``, exit 4)."""
    debian.check()
    path, rec_launch, rec_node = recorded_entry(run.mission.target)
    pkg = find_package(package) if package is not None else recorded_package(run, path)
    recorded = ros1_run.of(run)
    # the move_base tolerances the user set when recording win again (:mod:`.nav_params`)
    tolerances = recorded.goal_tolerances if recorded is not None else ()
    given = nav_params.given_in(t.source for t in tolerances)
    if launch or node:
        options = Ros1Options(launch=launch or "", node=node or "", given_settings=given)
    else:  # as recorded: the same start, the same third command
        after = recorded.after_launch if recorded is not None else ()
        options = Ros1Options(
            launch=rec_launch, node=rec_node, after_launch=after, given_settings=given
        )
    options = choose_entry(pkg, options)
    target = ros1_target(pkg, options)
    run_limits = limits or MissionLimits()
    built = cached_build(
        pkg,
        limits=build_limits_for(run_limits),
        fixed=uses_kernel_sandbox(run_limits),
    )
    factory: Any = functools.partial(Ros1Process, package=pkg, options=options, built=built)
    return dataclasses.replace(target), factory


def recorded_package(run: Run, path: str) -> Package:
    """The package folder the log names, when it is here and hashes to the recorded sha256
    (said on stderr: the folder that will be built); else a one-line usage error that asks
    for ``--ros1 PKG``."""
    shown = safe_line(path)
    ask = "give the package to replay with --ros1 PKG"
    try:
        pkg = find_package(path)
    except UsageError:
        raise UsageError(
            f"{run.path} was recorded from the ROS 1 package {shown}, which is not here; {ask}"
        ) from None
    try:
        digest = package_sha256(pkg)
    except MissionEnded as err:
        raise UsageError(f"{shown}: {safe_line(err.detail)}; {ask}") from None
    if not run.mission.sha256 or digest != run.mission.sha256:
        raise UsageError(
            f"{run.path} was recorded from {shown}, whose files are not the recorded ones "
            f"(sha256 {digest[:12]}, recorded {safe_line(run.mission.sha256[:12]) or 'none'}); "
            f"{ask}"
        )
    print(
        f"usar: replaying the recorded package {safe_line(str(pkg.path))}: "
        f"its sha256 {digest[:12]} is the recorded one",
        file=sys.stderr,
    )
    return pkg
