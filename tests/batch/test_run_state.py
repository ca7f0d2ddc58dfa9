"""batch.run_state: a run's process takes a state of its own, whatever its parent's (issue 42).

A child started as a Ray worker starts one (SIGINT blocked, a signal ignored, nice raised) shows
none of it after :func:`canonical`, and neither does a process it starts.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

from usar_replay.batch.run_state import clean_environment

CHILD = textwrap.dedent(
    """
    import os, signal, subprocess, sys
    from usar_replay.batch.run_state import canonical
    problems = canonical()
    grandchild = subprocess.run(
        [sys.executable, "-c",
         "import signal, os; "
         "print(sorted(signal.pthread_sigmask(signal.SIG_BLOCK, [])), "
         "signal.getsignal(signal.SIGUSR1) == signal.SIG_IGN, os.nice(0))"],
        capture_output=True, text=True, check=True,
    ).stdout.strip()
    print(problems, grandchild)
    """
)


def _as_a_ray_worker_starts_it() -> None:
    import signal

    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    signal.signal(signal.SIGUSR1, signal.SIG_IGN)
    os.nice(5)


def test_blocked_ignored_and_nice_are_undone_for_the_whole_run() -> None:
    before = subprocess.run(
        [sys.executable, "-c", "import signal; print(sorted(signal.pthread_sigmask(0, [])))"],
        preexec_fn=_as_a_ray_worker_starts_it,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "2" in before  # SIGINT blocked, as a Ray worker has it: the state to undo
    got = subprocess.run(
        [sys.executable, "-c", CHILD],
        preexec_fn=_as_a_ray_worker_starts_it,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    if os.geteuid() == 0:
        assert got == "[] [] False 0", got
    else:  # nice cannot be lowered: said, the signals still undone
        assert got.startswith("['runs at nice 5") and got.endswith("[] False 5"), got


def test_an_engines_variables_are_left_out() -> None:
    env = {"PATH": "/usr/bin", "RAY_JOB_ID": "01", "RAY_RAYLET_PID": "7", "HOME": "/root"}
    assert clean_environment(env) == {"PATH": "/usr/bin", "HOME": "/root"}
