"""ros1/scheduling: the graph's threads on one CPU under SCHED_RR."""

from __future__ import annotations

import os

from proctools import child as start_child
from proctools import wait_for

from usar_replay.ros1.scheduling import OneCpu


def test_the_graph_runs_on_one_cpu_under_sched_rr() -> None:
    child = start_child("import time\ntime.sleep(60)")
    try:
        pin = OneCpu(child.pid)
        wait_for(lambda: pin.apply() > 0 or child.pid in pin.done, "the child's threads")
        assert os.sched_getaffinity(child.pid) == {pin.cpu}
        if os.geteuid() == 0:
            policy = os.sched_getscheduler(child.pid)
            assert policy == os.SCHED_RR | os.SCHED_RESET_ON_FORK  # never inherited
        else:
            assert pin.refused
    finally:
        child.kill()
        child.wait()


def test_without_a_cpu_set_of_its_own_the_graph_is_only_pinned() -> None:
    """No SCHED_RR outside a run's own CPU set: it could starve a CPU someone else needs."""
    child = start_child("import time\ntime.sleep(60)")
    try:
        pin = OneCpu(child.pid, realtime=False)
        wait_for(lambda: pin.apply() > 0 or child.pid in pin.done, "the child's threads")
        assert os.sched_getaffinity(child.pid) == {pin.cpu}
        assert os.sched_getscheduler(child.pid) == os.SCHED_OTHER and pin.refused
    finally:
        child.kill()
        child.wait()


def test_the_watching_thread_leaves_the_graphs_cpu_and_comes_back() -> None:
    from usar_replay.ros1.scheduling import watching_elsewhere

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
