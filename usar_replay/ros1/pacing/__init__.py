"""ros1.pacing: when the bridge may publish the next ``/clock``, and how the graph is scheduled.

One concern, the pacing side, in one folder: ``graph_start`` (when ``/clock`` may start: every
node up, every subscription connected, the graph idle), ``quiescence`` (the graph has finished
reacting to a tick: threads blocked, sockets drained, clock pollers cycled), ``watcher`` (that
check in a process of its own, which the bridge waits on), ``sock_diag``
(bytes waiting in the graph's sockets, asked of the kernel), ``shutdown_watch`` (a node's
``ros::shutdown()`` held in the tick it began), ``proc_watch`` (the package's processes and
their exit statuses), ``scheduling`` (the graph's CPU set and real-time policy) and ``shim``
(the preloaded roscpp shim that makes busy-polling threads wait for the next ``/clock``).

The bridge (``ros1.bridge``) sits above this and the build side; nothing here imports it.
"""

from usar_replay.ros1.pacing.graph_start import (
    launch_listing,
    registered_nodes,
    wait_until_ready,
)
from usar_replay.ros1.pacing.proc_watch import ProcWatch
from usar_replay.ros1.pacing.quiescence import Quiescence, descendants
from usar_replay.ros1.pacing.scheduling import OneCpu
from usar_replay.ros1.pacing.shutdown_watch import ShutdownWatch
from usar_replay.ros1.pacing.sock_diag import SockDiag

__all__ = [
    "OneCpu",
    "ProcWatch",
    "Quiescence",
    "ShutdownWatch",
    "SockDiag",
    "descendants",
    "launch_listing",
    "registered_nodes",
    "wait_until_ready",
]
