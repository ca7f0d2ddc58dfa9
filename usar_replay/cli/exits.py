"""The exit codes of every ``usar`` command (README: *Exit codes*).

* 0 - done; for grading: every required rubric line passed.
* 1 - a rubric line, the replay comparison or a ``scenario --check`` failed.
* 2 - usage error: bad option, bad scenario file, a missing input, an output that exists.
* 3 - the log is incomplete or corrupt (what could be read was still used, and said so).
* 4 - the mission's code crashed, hung, ran out of memory or published what it may not (the
  log is closed and records the verdict; the user's traceback is shown).
* 130, 143, 129 - interrupted by SIGINT (Ctrl-C), SIGTERM, SIGHUP (128 + the signal); a
  recording is still closed, indexed and marked interrupted.
"""

from __future__ import annotations

__all__ = [
    "EXIT_FAIL",
    "EXIT_INCOMPLETE",
    "EXIT_INTERRUPTED",
    "EXIT_MISSION",
    "EXIT_OK",
    "EXIT_USAGE",
]

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INCOMPLETE = 3
EXIT_MISSION = 4
EXIT_INTERRUPTED = 130
