"""usar's pacing shim in the package's processes: nodes that poll without sleeping wait a tick.

Why: the bridge starts the next tick when the graph is idle (:mod:`.quiescence`). A node that
polls without sleeping (``while (ros::ok()) { pub.publish(m); ros::spinOnce(); }``, or
``while (ac.getState() != SUCCEEDED) ROS_INFO("Moving");`` while its action client's own
thread spins) never looks idle, though it has nothing new to do until sim time moves on: the
start-up gate gave up ("the graph did not go idle") or every tick waited for the wall cap
(0.33x real time, and not repeatable). On Gazebo such code burns a CPU and works.

usar's underlay builds ``usar_pacing`` (``catkin/usar_pacing/src/pacing.cpp``) beside
``fiducial_msgs``: a small library that the package's processes get through ``LD_PRELOAD``.
It wraps roscpp's poll points (``ros::spinOnce()``, ``CallbackQueue::callAvailable()`` with
no timeout, ``ros::console::print()``, ROS_INFO's entry, outside callbacks and not on
roscpp's own threads): a thread that reaches them again and again at the same sim time,
having run no callback, waits until ``ros::Time::now()`` changes: on the process's clock, a
futex the shim wakes when roscpp sets the time (``ros::Time::setNow``, its ``/clock``
callback). roscpp's own sim-time sleeps (``ros::Duration::sleep``, which ``ros::Rate::sleep``
calls, and ``ros::Time::sleepUntil``) wait on it too, where roscpp naps 1 ms at a time: a
sleeping node is then blocked, not a poller the idle check must wait out every tick. So a
busy loop runs its body a fixed number of times per tick
(a few spins or log lines of grace per tick, so a node that logs several lines in one go is
not delayed) and the idle check sees it as it sees a node paced by ``ros::Rate``. Nothing
there reads the wall clock to decide, so two recordings stay the same. With wall time (no
``/use_sim_time``) it never waits.

The library links nothing of ROS (it finds the real functions with ``dlsym``), so in a
process without roscpp (the ``bash`` and ``roslaunch`` that start the nodes, a rospy node)
nothing of it runs. rospy nodes are not paced (a busy rospy loop still waits for the cap).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

__all__ = ["LIBRARY", "library", "preloaded"]

LIBRARY = "devel/lib/libusar_pacing.so"
"""Where the shim is, in usar's underlay workspace."""


def library(underlays: Iterable[str | Path]) -> Path | None:
    """The shim in the first underlay (as the run sees it) that has it; None if none has (a
    workspace built by an older usar: the run goes on unpaced, as before)."""
    for space in underlays:
        lib = Path(space) / LIBRARY
        if lib.is_file():
            return lib
    return None


def preloaded(env: Mapping[str, str], underlays: Iterable[str | Path]) -> dict[str, str]:
    """``env`` with the shim first in ``LD_PRELOAD`` (what was there kept after it): the
    environment the package's processes start in (roslaunch hands it to every node)."""
    out = dict(env)
    lib = library(underlays)
    if lib is not None:
        out["LD_PRELOAD"] = ":".join(filter(None, (str(lib), env.get("LD_PRELOAD", ""))))
    return out
