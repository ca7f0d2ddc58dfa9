"""The process state a batch run starts from, the same whichever engine started it.

Why: a process inherits more than its environment. A Ray worker (2.60, measured) blocks SIGINT
in its signal mask, runs at nice 15 and sets ``RAY_*`` variables; the mask and ignored signals
survive ``exec``, so every process of the run (the recorder, the ROS 1 bridge, roslaunch, the
team's nodes) got them. roslaunch stops a launch's nodes with SIGINT: with SIGINT blocked, a
two-node team whose required node ended held its tick until roslaunch's SIGTERM fifteen
seconds later, and the run ended ``hung`` under Ray and ``done`` on the local engine (issue
42). So the run's own process, first thing, takes a state of its own instead of its parent's:
no blocked signal, no ignored signal but those Python itself ignores (SIGPIPE, SIGXFSZ: its
children get them back as default), nice 0 (where the process may raise its priority: root; a
run cannot undo a nice it may not lower, and says so), and no engine's variables in what its
children see (:func:`clean_environment`).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
from collections.abc import Mapping

__all__ = ["ENGINE_PREFIXES", "canonical", "clean_environment"]

ENGINE_PREFIXES = ("RAY_",)
"""Variables an engine sets for its own workers: none of a run's business."""
_PYTHON_IGNORES = frozenset({signal.SIGPIPE, signal.SIGXFSZ})
"""Ignored by CPython itself at start (``subprocess`` restores them in children)."""


def clean_environment(env: Mapping[str, str]) -> dict[str, str]:
    """``env`` without an engine's own variables (:data:`ENGINE_PREFIXES`)."""
    return {k: v for k, v in env.items() if not k.startswith(ENGINE_PREFIXES)}


def canonical() -> list[str]:
    """Put this process in the run's state (see the module doc); what could not be done, for
    the run's output (empty: nothing)."""
    problems: list[str] = []
    signal.pthread_sigmask(signal.SIG_SETMASK, set())
    for sig in signal.valid_signals():
        if sig in (signal.SIGKILL, signal.SIGSTOP) or sig in _PYTHON_IGNORES:
            continue
        with contextlib.suppress(OSError, ValueError):
            if signal.getsignal(sig) == signal.SIG_IGN:
                signal.signal(sig, signal.SIG_DFL)
    niceness = os.getpriority(os.PRIO_PROCESS, 0)
    if niceness != 0:
        try:
            os.setpriority(os.PRIO_PROCESS, 0, 0)
        except PermissionError:
            problems.append(f"runs at nice {niceness} (its parent's), not 0: only root lowers it")
    return problems


def main_prelude() -> None:
    """:func:`canonical`, its problems said on stderr (the run's output file)."""
    for problem in canonical():
        print(f"usar: this run {problem}", file=sys.stderr)
