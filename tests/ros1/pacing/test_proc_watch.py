"""ros1/proc_watch: a package's end seen in the process table, with its exit code."""

from __future__ import annotations

from proctools import child as start_child
from proctools import wait_for

from usar_replay.ros1.pacing.proc_watch import ProcWatch


def test_the_end_is_seen_in_the_process_table_with_the_exit_code() -> None:
    # a launcher that does not collect its node (as roslaunch, until its next poll)
    launcher = start_child(
        "import subprocess, sys, time\n"
        "subprocess.Popen([sys.executable, '-c', 'import sys; sys.exit(3)'])\n"
        "time.sleep(60)"
    )
    try:
        watch = ProcWatch(launcher.pid)
        wait_for(watch.ended, "the node's exit")
        assert len(watch.seen) == 1
        (failure,) = watch.failures()
        assert failure.endswith("exit code 3")
    finally:
        launcher.kill()
        launcher.wait()


