"""ros1/scheduling: the graph's threads on one CPU under SCHED_RR."""

from __future__ import annotations

import os

from proctools import child as start_child
from proctools import wait_for

from usar_replay.ros1.pacing.scheduling import OneCpu


def test_the_graph_runs_on_one_cpu_under_sched_rr() -> None:
    child = start_child("import time\ntime.sleep(60)")
    try:
        pin = OneCpu(child.pid)
        wait_for(lambda: pin.apply() > 0 or child.pid in pin.done, "the child's threads")
        assert os.sched_getaffinity(child.pid) == {pin.cpu}
        if os.geteuid() == 0:
            assert os.sched_getscheduler(child.pid) == os.SCHED_RR
        else:
            assert pin.refused
    finally:
        child.kill()
        child.wait()




def test_the_watching_thread_leaves_the_graphs_cpu_and_comes_back() -> None:
    from usar_replay.ros1.pacing.scheduling import watching_elsewhere

    before = os.sched_getaffinity(0)
    cpus = sorted(before)
    try:
        os.sched_setaffinity(0, {cpus[-1]})  # as the recorder pins the bridge
        with watching_elsewhere():
            inside = os.sched_getaffinity(0)
        assert os.sched_getaffinity(0) == {cpus[-1]}
        if len(cpus) > 1:
            assert cpus[-1] not in inside and inside
        else:
            assert inside == {cpus[-1]}  # no other CPU: it stays
        os.sched_setaffinity(0, before)  # not pinned: it stays where it is
        with watching_elsewhere():
            assert os.sched_getaffinity(0) == before
    finally:
        os.sched_setaffinity(0, before)
